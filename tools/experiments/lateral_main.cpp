// ccmap_exp_lateral: slope errors of the paper's 9-float CCM cell and of the full cell (with the
// lateral covariance) where x and y are correlated in a cell, and the seen share coverage needs
// (issue 11; see lateral.hpp).
//   ccmap_exp_lateral [--seed N] [--out DIR] [--quick] [--paper-cell] [--data DIR]
//                     [--gate K] [--change-points M] [--change-share S]
// (the options of every experiment, common.hpp; ccmap_exp_lateral --help lists them).
#include <cstdio>

#include "experiments/common.hpp"
#include "parse_args.hpp"
#include "experiments/lateral.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const auto app = make_experiment_app(
      "ccmap_exp_lateral",
      "Lateral covariance: slope errors and coverage of the paper cell and the full CCM cell (both cells, whatever\n"
      "--paper-cell says; --out, --data and the gate options are accepted and unused)",
      &args);
  if (const int rc = parse_experiment_args(*app, argc, argv, &args); rc >= 0) return rc;
  LateralConfig cfg = args.quick ? LateralConfig::quick() : LateralConfig{};
  cfg.seed = args.seed;
  const LateralResult r = run_lateral(cfg);
  std::printf("Lateral covariance (both cells, whatever --paper-cell says)\n%s\n", lateral_table(cfg, r).c_str());
  return 0;
}
