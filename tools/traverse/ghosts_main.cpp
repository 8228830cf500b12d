// ccmap_ghosts: free space from lines of sight, before and after (issue 21; docs/evaluation.md,
// "Ghosts and drop-offs"): a team of three rovers seeing each other drive off, negative obstacles
// approached, rock shadows on open ground.
//   ccmap_ghosts [--seed N] [--quick] [--out DIR] [--gate K] [--change-points M] [--change-share S]
//                [--rays N]   (AFTER's free_space_rays; default: the library's, StackParams)
//                [--stride K] (AFTER casts the lines of sight of every K-th point, K = 1, 2, 4, 8, 16:
//                              the viewshed table, free_space_rays = 65536 - K; 1 = every one)
//                [--dropoff-truth] (the drop-off cases also against tools/traverse/dropoff_truth.hpp)
//                [--ghost-truth N] (issue 31 item 2's reference on rover 1's map: a cell is seen in a
//                              frame when N true lines of sight pass clearly below it; ghost_truth.hpp)
// (the experiments' options, experiments/common.hpp; --data and --paper-cell are accepted and unused).
#include <cstdio>

#include "ccmap/map/config.hpp"
#include "ccmap/map/visibility/sight_table.hpp"

#include "experiments/common.hpp"
#include "parse_args.hpp"
#include "traverse/ghosts.hpp"

int main(int argc, char** argv) {
  using namespace ccmap;
  experiments::ExperimentArgs args;
  args.out_dir = "out/ghosts";
  const auto app = experiments::make_experiment_app(
      "ccmap_ghosts",
      "Free space from lines of sight, without and with it: ghosts of rovers that drove on, drop-offs\n"
      "approached, rock shadows (--data and --paper-cell are accepted and unused)",
      &args);
  int rays = 0;
  app->add_option("--rays", rays, "AFTER's lines of sight per frame (1..65535; default: the library's)")
      ->type_name("N")
      ->check(CLI::Range(1, 65535));
  int stride = 0;
  app->add_option("--stride", stride,
                  "AFTER casts the lines of sight of every K-th point (the viewshed table; 1 = every one)")
      ->type_name("K")
      ->check(CLI::IsMember({1, 2, 4, 8, 16}))
      ->excludes("--rays");
  bool dropoff_truth = false;
  app->add_flag("--dropoff-truth", dropoff_truth,
                "also hold AFTER's drop-offs to an independent reference of what the lines of sight prove\n"
                "(tools/traverse/dropoff_truth.hpp; a progress line per frame)");
  int truth_rays = 0;
  app->add_option("--ghost-truth", truth_rays,
                  "also judge rover 1's ghosts against true lines of sight: a cell is seen in a frame when at least N "
                  "of them pass clearly below it (issue 31 item 2)")
      ->type_name("N")
      ->check(CLI::Range(1, 1000000));
  if (const int rc = experiments::parse_experiment_args(*app, argc, argv, &args); rc >= 0) return rc;
  if (stride > 0) rays = static_cast<int>(detail::free_space_table_rays(stride));
  traverse::GhostConfig cfg = args.quick ? traverse::GhostConfig::quick() : traverse::GhostConfig{};
  cfg.seed = args.seed;
  cfg.gate = args.gate;
  cfg.free_space_rays = rays;
  cfg.dropoff_truth = dropoff_truth;
  cfg.out_dir = args.out_dir;
  cfg.ghost_truth_rays = truth_rays;
  cfg.log = stderr;
  const traverse::GhostResult r = traverse::run_ghosts(cfg);
  if (!r.ok()) {
    std::fprintf(stderr, "ccmap_ghosts: %s\n", r.error.c_str());
    return 1;
  }
  std::printf("gate: %s\n\n%s", cfg.gate.describe(default_stack_params(0.04F)).c_str(),
              traverse::ghost_report(r, cfg).c_str());
  if (truth_rays > 0) std::printf("\n%s", traverse::ghost_truth_report(r.team.truth).c_str());
  return 0;
}
