// Real laser scan experiment: CCM versus the piece-wise constant Kalman and OMG maps on the
// Lone Star Geyser terrestrial laser scan (/work/shared/data/lone_star_tls, see its README),
// judged by the height error at held-out scan points.
//
// Procedure (per cloud: the 10 x 10 m crop, optionally the full 32 x 41 m scan):
//  1. Read the cloud (double, UTM metres) and subtract a local origin in double first: the
//     floor of the minimum x and y and the rounded median z (a UTM northing of 4.9e6 m has
//     0.5 m float steps; 2324 m of elevation 0.24 mm).
//  2. Hold out holdout_share of the points (by seed); the rest builds the maps.
//  3. For each cell width: fixed grids of CcmCell, KalmanCell and OmgCell over the cloud's
//     bounding box, every training point folded into its cell (CCM: ccm_update with the
//     position relative to the cell centre, weight 1, no weight limit; Kalman and OMG: the
//     height with variance sigma_m^2, weight 1).
//  4. Each held-out point is predicted by each map: CCM by the sub-cell height of eq. (10) at
//     the point (ccm_height_at), the constant maps by the cell height. Points in unknown cells
//     are skipped and counted: a constant cell is known with >= min_points points; a CCM cell
//     additionally needs eq. (12)'s coverage (lateral spread >= tau of a full cell's): a
//     half-shadowed cell would extrapolate its plane. The main comparison uses the points all
//     three maps know (the CCM-known set); the constant maps are also reported on their own,
//     larger known set.
//  5. Outliers: the scan has returns up to +10 m (crop) or +15 m (full scan) above the ground
//     (steam, vegetation). Two variants are reported, each saying which:
//       raw  - every point, in training and in the held-out set;
//       cut  - points more than robust_cut_m above the median height of their 1 x 1 m block
//              are removed from both (the count is reported).
//  6. The library's maps (issue 12): single-layer stacks (Stack<SingleCcmConfig>,
//     <SingleKalmanConfig>, <SingleOmgConfig>, default_stack_params with a constant lidar noise
//     of sigma_m), every raw training point in one frame (as `ccmap map` maps one cloud), the
//     outlier gate off (the paper's update) and on (GateSetting); the held-out points that are
//     not outliers by the cut above (the ground) are predicted by query_layer (CCM: the sub-cell
//     plane), over the points every one of the six maps knows. Variant "stack" (widths whose
//     256-cell window holds the cloud).
// Errors are map minus held-out z (m): RMS, median |e|, 95th percentile |e|.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "experiments/common.hpp"

namespace ccmap::experiments {

struct LidarConfig {
  std::vector<double> cell_widths_m{0.08, 0.16, 0.32};
  double holdout_share = 0.10;
  double robust_cut_m = 0.30;
  double outlier_block_m = 1.0;
  double sigma_m = 0.01;        ///< measurement sigma for Kalman/OMG (TLS range noise + registration)
  double min_points = 3.0;      ///< a cell with fewer (training) points is unknown
  double coverage_tau = 0.8;    ///< eq. (12)
  bool include_full_scan = true;
  double image_step_m = 0.025;  ///< raster of the height pictures
  std::uint64_t seed = 1;
  GateSetting gate;             ///< the "gate on" stacks of variant "stack"
  bool paper_cell = false;      ///< CCM maps of CcmPaperCell (the paper's 9 floats) instead of CcmCell
  static LidarConfig quick() {
    LidarConfig c;
    c.include_full_scan = false;
    return c;
  }
};

struct LidarMethodStats {
  std::string method;           ///< "CCM", "OMG", "Kalman"
  std::string point_set;        ///< "common" (all maps know the cell) or "own" (this map's known cells)
  double cell_width_m = 0.0;
  std::size_t evaluated = 0;    ///< held-out points predicted
  std::size_t skipped = 0;      ///< held-out points in unknown cells
  double rms_m = 0.0, median_abs_m = 0.0, p95_abs_m = 0.0, max_abs_m = 0.0;
  double skipped_share() const {
    const double n = static_cast<double>(evaluated + skipped);
    return n > 0.0 ? static_cast<double>(skipped) / n : 0.0;
  }
};

struct LidarVariant {
  std::string name;             ///< "raw", "cut" or "stack"
  std::size_t train_points = 0, held_out_points = 0, removed_outliers = 0;
  std::vector<LidarMethodStats> stats;
  const LidarMethodStats* find(const std::string& method, double cell_width_m, const std::string& point_set) const;
};

struct LidarRun {
  std::string cloud_name;
  std::string path;
  std::size_t points = 0;
  double origin_x = 0.0, origin_y = 0.0, origin_z = 0.0;  ///< subtracted (double)
  double extent_x = 0.0, extent_y = 0.0;                   ///< bounding box (m)
  double z_p50 = 0.0, z_max_above_p50 = 0.0;               ///< local z
  std::vector<LidarVariant> variants;  ///< raw, cut, stack
  std::string gate;                    ///< the "gate on" stacks' gate (GateSetting::describe)
};

/// The crop's path inside a data directory.
std::string lidar_crop_path(const std::string& data_dir);
/// The full scan's path inside a data directory.
std::string lidar_full_path(const std::string& data_dir);

/// Runs the experiment on one cloud file. False with the reason in *why when the file is absent
/// or unreadable (the caller skips). With out_dir non-empty, writes <out_dir>/<prefix>_<w>cm.png
/// (cut variant: held-in points, CCM sub-cell height, constant height, per resolution).
bool run_lidar(const LidarConfig& config, const std::string& path, const std::string& name, const std::string& out_dir,
               const std::string& prefix, LidarRun* out, std::string* why, std::vector<std::string>* pictures = nullptr);

std::string lidar_table(const LidarRun& run);

}  // namespace ccmap::experiments
