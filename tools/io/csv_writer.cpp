#include "csv_writer.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace ccmap::tools {

bool write_layer_csv(const std::string& path, const std::vector<LayerCellRow>& rows, std::string* error) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) {
    if (error != nullptr) *error = "cannot open '" + path + "' for writing: " + std::strerror(errno);
    return false;
  }
  std::fprintf(f, "%s\n", kLayerCsvHeader);
  for (const LayerCellRow& r : rows) {
    // Centres and heights with 6 decimals (micrometres, also for UTM-sized values); slopes and
    // variances with 7 significant digits (float precision of the library).
    std::fprintf(f, "%d,%lld,%lld,%.6f,%.6f,%.9g,%.7g,%.6f,%.7g,%.7g,%.7g,%.7g,%s\n", r.layer,
                 static_cast<long long>(r.ix), static_cast<long long>(r.iy), r.cx, r.cy, r.res, r.weight, r.height,
                 r.slope_x, r.slope_y, r.normal_var, r.elev_var, r.cell_class.c_str());
  }
  const bool write_error = std::ferror(f) != 0;
  if (std::fclose(f) != 0 || write_error) {
    if (error != nullptr) *error = "error writing '" + path + "'";
    return false;
  }
  return true;
}

bool read_layer_csv(const std::string& path, std::vector<LayerCellRow>* rows, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = "cannot open '" + path + "'";
    return false;
  }
  std::string line;
  if (!std::getline(in, line) || line != kLayerCsvHeader) {
    *error = path + ": unexpected header '" + line + "'";
    return false;
  }
  rows->clear();
  std::size_t line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) f.push_back(field);
    if (f.size() != 13) {
      *error = path + ": line " + std::to_string(line_no) + ": expected 13 fields";
      return false;
    }
    LayerCellRow r;
    char* end = nullptr;
    bool ok = true;
    auto num = [&](const std::string& s) {
      const double v = std::strtod(s.c_str(), &end);
      if (s.empty() || *end != '\0') ok = false;
      return v;
    };
    r.layer = static_cast<int>(num(f[0]));
    r.ix = static_cast<std::int64_t>(num(f[1]));
    r.iy = static_cast<std::int64_t>(num(f[2]));
    r.cx = num(f[3]);
    r.cy = num(f[4]);
    r.res = num(f[5]);
    r.weight = num(f[6]);
    r.height = num(f[7]);
    r.slope_x = num(f[8]);
    r.slope_y = num(f[9]);
    r.normal_var = num(f[10]);
    r.elev_var = num(f[11]);
    r.cell_class = f[12];
    if (!ok) {
      *error = path + ": line " + std::to_string(line_no) + ": bad number";
      return false;
    }
    rows->push_back(r);
  }
  return true;
}

}  // namespace ccmap::tools
