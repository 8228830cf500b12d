// ccmap_exp_fig10: drift resilience of CCM on wave terrain (paper Fig. 10, Section V-D), each map
// also with uncertain moves (Stack::move_to(x, y, sigma)).
//   ccmap_exp_fig10 [--seed N] [--out DIR] [--quick] [--paper-cell] [--odometry-sigma F]
//   --odometry-sigma F   sigma of the uncertain moves = F x the distance moved (default: each
//                        run's own drift fraction)
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "experiments/common.hpp"
#include "experiments/drift.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  // --odometry-sigma is this program's own; the rest goes to the common parser.
  double odometry_sigma = -1.0;
  std::vector<char*> rest;
  for (int i = 0; i < argc; ++i) {
    if (std::string(argv[i]) == "--odometry-sigma" && i + 1 < argc) {
      char* end = nullptr;
      odometry_sigma = std::strtod(argv[++i], &end);
      if (end == argv[i] || *end != '\0' || !(odometry_sigma >= 0.0) || odometry_sigma > 1.0) {
        std::fprintf(stderr, "--odometry-sigma: expected a fraction in [0, 1], got %s\n", argv[i]);
        return 2;
      }
      continue;
    }
    rest.push_back(argv[i]);
  }
  ExperimentArgs args;
  const int rc = parse_experiment_args(static_cast<int>(rest.size()), rest.data(),
                                       "Fig. 10: CCM false obstacles vs pose drift on wave terrain "
                                       "(also: --odometry-sigma F, sigma of the uncertain moves per metre moved)",
                                       &args);
  if (rc >= 0) return rc;
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
