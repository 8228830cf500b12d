// ccmap_exp_outliers: outliers on a slope and real change, outlier gate off and on (issue 12).
//   ccmap_exp_outliers [--seed N] [--quick] [--gate K] [--change-points M] [--change-share S]
#include <cstdio>

#include "ccmap/map/config.hpp"
#include "experiments/common.hpp"
#include "experiments/outliers.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const int rc = parse_experiment_args(argc, argv, "Outliers and real change: the outlier gate off and on", &args);
  if (rc >= 0) return rc;
  OutlierConfig cfg = args.quick ? OutlierConfig::quick() : OutlierConfig{};
  cfg.seed = args.seed;
  cfg.gate = args.gate;
  const OutlierResult r = run_outliers(cfg);
  std::printf("gate on: %s\n\n%s", cfg.gate.describe(ccmap::default_stack_params(0.08F)).c_str(),
              outlier_tables(cfg, r).c_str());
  return 0;
}
