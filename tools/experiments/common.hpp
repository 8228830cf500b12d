// Shared plumbing of the experiment programs: command-line options (CLI11), output directory, tables.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace ccmap {
struct StackParams;
}

namespace ccmap::experiments {

/// The outlier gate and change rule of a run (docs/design.md, "Outlier gate and change"):
/// negative fields keep the library's default_stack_params value; sigma 0 switches the gate off.
struct GateSetting {
  double sigma = -1.0;
  double min_points = -1.0;
  double share = -1.0;
  /// Writes the non-negative fields into *params.
  void apply(StackParams* params) const;
  /// "library default", "off", or e.g. "3 sigma, 3 points, 8 %".
  std::string describe(const StackParams& defaults) const;
};

/// Options every experiment accepts (make_experiment_app):
///   --seed N   (default 1)  --out DIR (default out/experiments)  --quick (reduced size)
///   --data DIR (real data; default $CCMAP_DATA_DIR, else <source>/../shared/data)
///   --gate K, --change-points M, --change-share S   (the outlier gate: GateSetting)
///   --paper-cell (the paper's 9-float CCM cell, CcmPaperCell, instead of the full CcmCell)
struct ExperimentArgs {
  std::uint64_t seed = 1;
  std::string out_dir = "out/experiments";
  bool quick = false;
  bool paper_cell = false;
  std::string data_dir;  ///< the --data text until parse_experiment_args resolves it (never empty after)
  GateSetting gate;
};

/// A CLI11 parser named `program` whose --help starts with `description`, holding the options
/// every experiment accepts, bound to *args (which must outlive it). The program adds its own
/// options to it, then calls parse_experiment_args. As in the hand-written parsers before it,
/// the last of a repeated option counts.
std::unique_ptr<CLI::App> make_experiment_app(const std::string& program, const std::string& description,
                                              ExperimentArgs* args);

/// Adds --gate K, --change-points M, --change-share S bound to *gate, which must outlive `app`:
/// the experiments' options (make_experiment_app) and the traverse's. A value is refused unless
/// validate_stack_params accepts it (docs/design.md section 9), so that no run starts with a
/// stack whose init would fail.
void add_gate_options(CLI::App& app, GateSetting* gate);

/// Parses argv with `app` (tools/args/parse_args.hpp), then resolves args->data_dir. Returns -1
/// to go on, otherwise the exit code to return right away (0 after --help; 2 after a refused
/// command line, said in one line on stderr).
int parse_experiment_args(CLI::App& app, int argc, char** argv, ExperimentArgs* args);

/// Creates `dir` (and parents) if needed; false with a reason in *error.
bool ensure_directory(const std::string& dir, std::string* error);

/// Plain-text table printed with aligned columns.
class Table {
 public:
  explicit Table(std::vector<std::string> header) : header_(std::move(header)) {}
  void add_row(std::vector<std::string> row) { rows_.push_back(std::move(row)); }
  std::string str() const;

 private:
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
};

/// printf-style formatting into a std::string.
std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

}  // namespace ccmap::experiments
