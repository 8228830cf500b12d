// ccmap_exp_fig10: drift resilience of CCM on wave terrain (paper Fig. 10, Section V-D).
//   ccmap_exp_fig10 [--seed N] [--out DIR] [--quick] [--paper-cell]
#include <cstdio>
#include <string>

#include "experiments/common.hpp"
#include "experiments/drift.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const int rc = parse_experiment_args(argc, argv, "Fig. 10: CCM false obstacles vs pose drift on wave terrain", &args);
  if (rc >= 0) return rc;
  DriftConfig cfg = args.quick ? DriftConfig::quick() : DriftConfig{};
  cfg.seed = args.seed;
  cfg.paper_cell = args.paper_cell;
  cfg.progress = true;
  const DriftResult r = run_drift(cfg);
  std::printf("Fig. 10: drift resilience (single-layer CCM maps, %s CCM cell, CADRE stereo)\n%s\n",
              cfg.paper_cell ? "paper" : "full", drift_table(cfg, r).c_str());
  std::string error;
  if (!write_drift_outputs(cfg, r, args.out_dir, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  std::printf("wrote %s/fig10.svg and %s/fig10.csv\n", args.out_dir.c_str(), args.out_dir.c_str());
  return 0;
}
