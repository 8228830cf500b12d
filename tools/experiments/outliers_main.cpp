// ccmap_exp_outliers: outliers on a slope and real change, outlier gate off and on (issue 12).
//   ccmap_exp_outliers [--seed N] [--quick] [--gate K] [--change-points M] [--change-share S]
// (the options of every experiment, common.hpp; ccmap_exp_outliers --help lists them).
#include <cstdio>

#include "ccmap/map/config.hpp"
#include "experiments/common.hpp"
#include "experiments/outliers.hpp"
#include "parse_args.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const auto app = make_experiment_app(
      "ccmap_exp_outliers",
      "Outliers and real change: the outlier gate off and on (--out, --data and --paper-cell are accepted\n"
      "and unused)",
      &args);
  if (const int rc = parse_experiment_args(*app, argc, argv, &args); rc >= 0) return rc;
  OutlierConfig cfg = args.quick ? OutlierConfig::quick() : OutlierConfig{};
  cfg.seed = args.seed;
  cfg.gate = args.gate;
  const OutlierResult r = run_outliers(cfg);
  std::printf("gate on: %s\n\n%s", cfg.gate.describe(ccmap::default_stack_params(0.08F)).c_str(),
              outlier_tables(cfg, r).c_str());
  return 0;
}
