// ccmap_exp_fig10: drift resilience of CCM on wave terrain (paper Fig. 10, Section V-D), each map
// also with uncertain moves (Stack::move_to(x, y, sigma)).
//   ccmap_exp_fig10 [--seed N] [--out DIR] [--quick] [--paper-cell] [--data DIR] [--odometry-sigma F]
//                   [--gate K] [--change-points M] [--change-share S]
//   --odometry-sigma F   sigma of the uncertain moves = F x the distance moved, F in [0, 1]
//                        (default: each run's own drift fraction)
// (ccmap_exp_fig10 --help lists the options.)
#include <cstdio>
#include <string>

#include "experiments/common.hpp"
#include "experiments/drift.hpp"
#include "number_options.hpp"
#include "parse_args.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const auto app =
      make_experiment_app("ccmap_exp_fig10", "Fig. 10: CCM false obstacles vs pose drift on wave terrain", &args);
  double odometry_sigma = -1.0;  // < 0: each run's own drift fraction (DriftConfig::odometry_sigma_fraction)
  ccmap::tools::add_real(*app, "--odometry-sigma", &odometry_sigma, 0.0, 1.0, false, "F",
                         "sigma of the uncertain moves = F x the distance moved, F in [0, 1]\n"
                         "(default: each run's own drift fraction)")
      ->default_str("");
  if (const int rc = parse_experiment_args(*app, argc, argv, &args); rc >= 0) return rc;
  DriftConfig cfg = args.quick ? DriftConfig::quick() : DriftConfig{};
  cfg.odometry_sigma_fraction = odometry_sigma;
  cfg.seed = args.seed;
  cfg.gate = args.gate;
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
