// ccmap_exp_lateral: slope errors of the paper's 9-float CCM cell and of the full cell (with the
// lateral covariance) where x and y are correlated in a cell, and the seen share coverage needs
// (issue 11; see lateral.hpp).
//   ccmap_exp_lateral [--seed N] [--quick]
#include <cstdio>

#include "experiments/common.hpp"
#include "experiments/lateral.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const int rc = parse_experiment_args(
      argc, argv, "Lateral covariance: slope errors and coverage of the paper cell and the full CCM cell", &args);
  if (rc >= 0) return rc;
  LateralConfig cfg = args.quick ? LateralConfig::quick() : LateralConfig{};
  cfg.seed = args.seed;
  const LateralResult r = run_lateral(cfg);
  std::printf("Lateral covariance (both cells, whatever --paper-cell says)\n%s\n", lateral_table(cfg, r).c_str());
  return 0;
}
