// Helpers of the ccmap CLI tests (cli_test.cpp, tiling_test.cpp): run the tool in-process, write
// clouds, read its CSV and its summary line.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "csv_writer.hpp"

namespace ccmap::test {

struct CliRun {
  int code;
  std::string out;
  std::string err;
};

/// `ccmap <args>` through run_cli (no process): exit code, standard output, standard error.
inline CliRun run_ccmap(std::vector<std::string> args) {
  args.insert(args.begin(), "ccmap");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::ostringstream out, err;
  const int code = ccmap::tools::run_cli(static_cast<int>(args.size()), argv.data(), out, err);
  return CliRun{code, out.str(), err.str()};
}

struct XyzPoint {
  double x, y, z;
};

/// A binary little-endian PLY with double coordinates: the values reach the tool exactly.
inline void write_ply(const std::filesystem::path& path, const std::vector<XyzPoint>& points) {
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << points.size()
      << "\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
  for (const XyzPoint& p : points) {
    const double v[3] = {p.x, p.y, p.z};
    out.write(reinterpret_cast<const char*>(v), sizeof v);
  }
}

/// The rows of a layer CSV (the header is checked).
inline std::vector<ccmap::tools::LayerCellRow> read_rows(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "layer,ix,iy,cx,cy,res,weight,height,slope_x,slope_y,normal_var,elev_var,class") << path;
  std::vector<ccmap::tools::LayerCellRow> rows;
  std::string error;
  EXPECT_TRUE(ccmap::tools::read_layer_csv(path.string(), &rows, &error)) << error;
  return rows;
}

/// "points: read N, used M, ..." from the summary.
inline bool summary_counts(const std::string& out, long long* read, long long* used) {
  const std::size_t at = out.find("points: read ");
  return at != std::string::npos && std::sscanf(out.c_str() + at, "points: read %lld, used %lld", read, used) == 2;
}

/// The number after `key` in the summary line ("outside map 0" -> 0 for key "outside map "),
/// -1 if absent.
inline long long summary_count(const std::string& out, const std::string& key) {
  const std::size_t line = out.find("points: read ");
  if (line == std::string::npos) return -1;
  const std::size_t at = out.find(key, line);
  return at == std::string::npos ? -1 : std::atoll(out.c_str() + at + key.size());
}

}  // namespace ccmap::test
