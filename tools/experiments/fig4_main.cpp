// ccmap_exp_fig4: CCM normal variance vs obstacle coverage (paper Fig. 4).
//   ccmap_exp_fig4 [--seed N] [--out DIR] [--quick] [--paper-cell] [--data DIR]
//                  [--gate K] [--change-points M] [--change-share S]
// (the options of every experiment, common.hpp; ccmap_exp_fig4 --help lists them).
#include <cstdio>
#include <string>

#include "experiments/common.hpp"
#include "parse_args.hpp"
#include "experiments/fig4.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const auto app = make_experiment_app("ccmap_exp_fig4",
                                       "Fig. 4: CCM surface-normal variance vs obstacle coverage (single cells: --data\n"
                                       "and the gate options are accepted and unused)",
                                       &args);
  if (const int rc = parse_experiment_args(*app, argc, argv, &args); rc >= 0) return rc;
  Fig4Config cfg = args.quick ? Fig4Config::quick() : Fig4Config{};
  cfg.seed = args.seed;
  cfg.paper_cell = args.paper_cell;
  const Fig4Result r = run_fig4(cfg);
  std::printf("Fig. 4: %.0f cm cell, %.0f cm step (75%% of the cell width), threshold = sigma_s^2 at 50%% coverage\n\n%s\n",
              cfg.cell_width_m * 100, cfg.step_height_m * 100, fig4_table(cfg, r).c_str());
  std::string error;
  if (!write_fig4_outputs(cfg, r, args.out_dir, &error)) {
    std::fprintf(stderr, "error: %s\n", error.c_str());
    return 1;
  }
  std::printf("wrote %s/fig4.svg and %s/fig4.csv\n", args.out_dir.c_str(), args.out_dir.c_str());
  return 0;
}
