#include "experiments/common.hpp"

#include <algorithm>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

#include "ccmap/map/classify.hpp"
#include "ccmap/map/config.hpp"
#include "number_options.hpp"
#include "parse_args.hpp"
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

std::unique_ptr<CLI::App> make_experiment_app(const std::string& program, const std::string& description,
                                              ExperimentArgs* args) {
  auto app = std::make_unique<CLI::App>(description, program);
  app->option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  tools::add_whole<std::uint64_t>(*app, "--seed", &args->seed, 0, UINT64_MAX, "N",
                                  "random seed; results are deterministic by seed");
  app->add_option("--out", args->out_dir, "output directory for figures")->type_name("DIR")->capture_default_str();
  app->add_flag("--quick", args->quick, "reduced size (what the CI test runs)");
  app->add_flag("--paper-cell", args->paper_cell,
                "the paper's 9-float CCM cell (no lateral covariance) instead of the full cell");
  app->add_option("--data", args->data_dir,
                  "real-data directory (default $CCMAP_DATA_DIR, else the shared data next to the source tree)")
      ->type_name("DIR");
  add_gate_options(*app, &args->gate);
  return app;
}

void add_gate_options(CLI::App& app, GateSetting* gate) {
  // One field of the setting, checked alone: the library's defaults are valid, so a setting is
  // valid exactly when each of its fields is valid beside them.
  auto add = [&app](const std::string& name, const std::string& type, const std::string& help,
                    double GateSetting::*field, GateSetting* target) {
    app.add_option_function<std::string>(
           name,
           [name, field, target](const std::string& v) {
             const double most = std::numeric_limits<float>::max();  // StackParams holds them as floats
             GateSetting one;
             one.*field = tools::parse_real(name, v, 0.0, most);
             StackParams p = default_stack_params(0.08F);
             one.apply(&p);
             if (validate_stack_params(p, 1) != Status::kOk) {
               throw CLI::ValidationError(name, v + " is refused by the library's validate_stack_params (docs/design.md section 9)");
             }
             target->*field = one.*field;
           },
           help)
        ->type_name(type);
  };
  add("--gate", "K", "the outlier gate at K sigma, 0 = off: the paper's update (docs/design.md\nsection 9); default: the library's",
      &GateSetting::sigma, gate);
  add("--change-points", "M", "the change rule's point count (default: the library's)", &GateSetting::min_points, gate);
  add("--change-share", "S", "the change rule's share (default: the library's)", &GateSetting::share, gate);
}

int parse_experiment_args(CLI::App& app, int argc, char** argv, ExperimentArgs* args) {
  const int code = tools::parse_args(app, argc, argv);
  if (code >= 0) return code;
  args->data_dir = sim::resolve_data_dir(args->data_dir);
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
