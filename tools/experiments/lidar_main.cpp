// ccmap_exp_lidar: CCM vs Kalman vs OMG on the real Lone Star Geyser laser scan, judged by the
// height error at held-out points (see lidar.hpp). Skipped, saying why, when the data is absent.
//   ccmap_exp_lidar [--seed N] [--out DIR] [--quick] [--paper-cell] [--data DIR]
//                   [--gate K] [--change-points M] [--change-share S]
// (the options of every experiment, common.hpp; ccmap_exp_lidar --help lists them).
#include <cstdio>
#include <string>
#include <vector>

#include "experiments/common.hpp"
#include "parse_args.hpp"
#include "experiments/lidar.hpp"

int main(int argc, char** argv) {
  using namespace ccmap::experiments;
  ExperimentArgs args;
  const auto app = make_experiment_app(
      "ccmap_exp_lidar", "Real laser scan: CCM vs Kalman vs OMG height error at held-out points (Lone Star Geyser TLS)",
      &args);
  if (const int rc = parse_experiment_args(*app, argc, argv, &args); rc >= 0) return rc;
  LidarConfig cfg = args.quick ? LidarConfig::quick() : LidarConfig{};
  cfg.seed = args.seed;
  cfg.gate = args.gate;
  cfg.paper_cell = args.paper_cell;
  std::vector<std::string> pictures;
  LidarRun crop;
  std::string why;
  if (!run_lidar(cfg, lidar_crop_path(args.data_dir), "LONE STAR 10 X 10 M CROP", args.out_dir, "lidar_crop", &crop, &why,
                 &pictures)) {
    std::printf("ccmap_exp_lidar: skipped: %s\n", why.c_str());
    return 0;
  }
  std::printf("Real laser scan, %.0f %% of the points held out (seed %llu); CCM (%s cell) predicts the sub-cell height "
              "(eq. 10), Kalman/OMG the cell height\n\n%s\n",
              100.0 * cfg.holdout_share, static_cast<unsigned long long>(cfg.seed), cfg.paper_cell ? "paper" : "full",
              lidar_table(crop).c_str());
  if (cfg.include_full_scan) {
    LidarRun full;
    if (run_lidar(cfg, lidar_full_path(args.data_dir), "LONE STAR FULL SCAN", args.out_dir, "lidar_full", &full, &why,
                  &pictures)) {
      std::printf("%s\n", lidar_table(full).c_str());
    } else {
      std::printf("full scan skipped: %s\n\n", why.c_str());
    }
  }
  for (const std::string& p : pictures) std::printf("wrote %s\n", p.c_str());
  return 0;
}
