#include "experiments/common.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "ccmap/map/config.hpp"
#include "sim/data_dir.hpp"

namespace ccmap::experiments {

void GateSetting::apply(StackParams* params) const {
  if (sigma >= 0.0) params->outlier_gate_sigma = static_cast<float>(sigma);
  if (min_points >= 0.0) params->change_min_points = static_cast<float>(min_points);
  if (share >= 0.0) params->change_share = static_cast<float>(share);
}

std::string GateSetting::describe(const StackParams& defaults) const {
  StackParams p = defaults;
  apply(&p);
  if (!(p.outlier_gate_sigma > 0.0F)) return "gate off (the paper's update)";
  return format("gate %.3g sigma, change rule %.3g points / %.3g %%", static_cast<double>(p.outlier_gate_sigma),
                static_cast<double>(p.change_min_points), 100.0 * static_cast<double>(p.change_share));
}

int parse_experiment_args(int argc, char** argv, const std::string& description, ExperimentArgs* args) {
  std::string data_flag;
  const char* prog = argc > 0 ? argv[0] : "experiment";
  auto usage = [&](FILE* f) {
    std::fprintf(f,
                 "%s\n\nusage: %s [--seed N] [--out DIR] [--quick] [--data DIR] [--paper-cell] [--gate K]\n"
                 "       [--change-points M] [--change-share S]\n"
                 "  --seed N    random seed (default 1); results are deterministic by seed\n"
                 "  --out DIR   output directory for figures (default out/experiments)\n"
                 "  --quick     reduced size (what the CI test runs)\n"
                 "  --paper-cell  the paper's 9-float CCM cell (no lateral covariance) instead of the full cell\n"
                 "  --data DIR  real-data directory (default $CCMAP_DATA_DIR, else the shared data next to the "
                 "source tree)\n"
                 "  --gate K, --change-points M, --change-share S\n"
                 "              the maps' outlier gate (K sigma, 0 = off: the paper's update) and change rule\n"
                 "              (docs/design.md); default: the library's\n",
                 description.c_str(), prog);
  };
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--help" || a == "-h") {
      usage(stdout);
      return 0;
    } else if (a == "--quick") {
      args->quick = true;
    } else if (a == "--paper-cell") {
      args->paper_cell = true;
    } else if (a == "--seed" && has_value) {
      char* end = nullptr;
      args->seed = std::strtoull(argv[++i], &end, 10);
      if (end == nullptr || *end != '\0') {
        std::fprintf(stderr, "bad --seed value %s\n", argv[i]);
        return 2;
      }
    } else if (a == "--out" && has_value) {
      args->out_dir = argv[++i];
    } else if (a == "--data" && has_value) {
      data_flag = argv[++i];
    } else if ((a == "--gate" || a == "--change-points" || a == "--change-share") && has_value) {
      char* end = nullptr;
      const double v = std::strtod(argv[++i], &end);
      if (end == nullptr || *end != '\0' || !(v >= 0.0)) {
        std::fprintf(stderr, "bad %s value %s\n", a.c_str(), argv[i]);
        return 2;
      }
      (a == "--gate" ? args->gate.sigma : a == "--change-points" ? args->gate.min_points : args->gate.share) = v;
    } else {
      std::fprintf(stderr, "unknown or incomplete argument: %s\n", a.c_str());
      usage(stderr);
      return 2;
    }
  }
  args->data_dir = sim::resolve_data_dir(data_flag);
  return -1;
}

bool ensure_directory(const std::string& dir, std::string* error) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    if (error != nullptr) *error = "cannot create directory " + dir + ": " + ec.message();
    return false;
  }
  return true;
}

std::string Table::str() const {
  std::vector<std::size_t> width(header_.size(), 0);
  for (std::size_t c = 0; c < header_.size(); ++c) width[c] = header_[c].size();
  for (const auto& r : rows_)
    for (std::size_t c = 0; c < r.size() && c < width.size(); ++c) width[c] = std::max(width[c], r[c].size());
  std::ostringstream o;
  auto line = [&](const std::vector<std::string>& r) {
    for (std::size_t c = 0; c < width.size(); ++c) {
      const std::string cell = c < r.size() ? r[c] : "";
      o << (c == 0 ? "" : "  ") << cell << std::string(width[c] - cell.size(), ' ');
    }
    o << '\n';
  };
  line(header_);
  std::size_t total = 0;
  for (std::size_t w : width) total += w + 2;
  o << std::string(total > 2 ? total - 2 : 0, '-') << '\n';
  for (const auto& r : rows_) line(r);
  return o.str();
}

std::string format(const char* fmt, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(buf, sizeof buf, fmt, ap);
  va_end(ap);
  return buf;
}

}  // namespace ccmap::experiments
