// Fig. 5 of the paper: reconstruction precision and variance consistency of CCM versus the
// piece-wise constant Kalman and OMG maps, on a 20 x 20 m simulated terrain with 3 m cells and
// on the real HiRISE Mars DTM.
//
// Setting: a noise-added point cloud (x, y uniform, z = h + N(0, sigma_z)) is binned into a
// fixed grid of cells (index floor((x - x0) / w)); each cell is updated with every point:
//  - CCM: ccm_update(x - C_x, y - C_y, z, weight 1, no weight limit),
//  - Kalman: kalman_update(z, sigma_z^2),
//  - OMG: omg_update(z, sigma_z^2, weight 1).
// Evaluation on a fine grid (eval_step_m) of the true surface h:
//  - error = map height - h, with the CCM sub-cell height (eq. 10, ccm_height_at) and the
//    constant cells' height;
//  - RMS error over the observed area;
//  - 3-sigma violation share: the share of that area where |error| > 3 sigma, sigma^2 being
//    each map's elevation variance (CCM: ccm_elevation_variance at the point; OMG: the mixture
//    variance; Kalman: its estimate variance).
// Half-resolution claim: CCM at 2 w against the constant maps at w, with memory
// (40 B per full CCM cell, 36 B per paper cell with paper_cell, 12 B per constant cell).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/terrain.hpp"
#include "sim/types.hpp"

namespace ccmap::experiments {

struct Fig5Config {
  double size_m = 20.0;
  double cell_width_m = 3.0;
  double points_per_m2 = 100.0;
  double sigma_z_m = 0.05;
  double eval_step_m = 0.05;
  double mars_cell_width_m = 3.0;
  double mars_points_per_m2 = 25.0;
  double mars_eval_step_m = 0.2;
  std::uint64_t seed = 1;
  bool paper_cell = false;  ///< CcmPaperCell (the paper's 9 floats) instead of CcmCell
  static Fig5Config quick() {
    Fig5Config c;
    c.points_per_m2 = 25.0;
    c.eval_step_m = 0.1;
    c.mars_points_per_m2 = 5.0;
    c.mars_eval_step_m = 0.5;
    return c;
  }
};

/// The simulated terrain of the experiment (rolling ground, slope, roughness, rocks, craters).
sim::TerrainParams fig5_terrain_params(double size_m, std::uint64_t seed);

struct Fig5MethodStats {
  std::string method;           ///< "CCM", "OMG", "Kalman"
  double cell_width_m = 0.0;
  int cells_x = 0, cells_y = 0;
  std::size_t bytes = 0;        ///< cells * bytes per cell
  double rms_m = 0.0;           ///< RMS of (map height - true height) over observed samples
  double violation_share = 0.0; ///< share of observed samples with |error| > 3 sigma
  double median_sigma_m = 0.0;  ///< median of the map's elevation standard deviation
  std::size_t samples = 0;      ///< observed evaluation samples
  /// Per evaluation sample (row-major, row 0 = south), NaN where unobserved; filled only if
  /// images were requested.
  std::vector<float> error_m, sigma_m;
};

struct Fig5Run {
  std::string terrain_name;
  sim::Rect area;
  std::size_t points = 0;
  int eval_nx = 0, eval_ny = 0;
  double eval_step_m = 0.0;
  std::vector<Fig5MethodStats> methods;  ///< CCM(w), OMG(w), Kalman(w), CCM(2w)
  const Fig5MethodStats* find(const std::string& method, double cell_width_m) const;
};

/// Builds the three maps at cell_width_m (and CCM at 2 * cell_width_m) from `cloud` and
/// evaluates them against `truth` over `area`. keep_maps fills error_m/sigma_m; paper_cell
/// builds the CCM maps of CcmPaperCell instead of CcmCell.
Fig5Run evaluate_fig5_maps(const sim::Terrain& truth, const sim::Rect& area, const std::vector<sim::Point3>& cloud,
                           double cell_width_m, double sigma_z_m, double eval_step_m, bool keep_maps,
                           bool paper_cell = false);

/// The simulated 20 x 20 m run.
Fig5Run run_fig5_synthetic(const Fig5Config& config, bool keep_maps);

/// The same comparison on the Mars DTM (heights shifted to zero mean). Returns false with the
/// reason in *why if the DTM is not available (the caller skips).
bool run_fig5_mars(const Fig5Config& config, const std::string& data_dir, bool keep_maps, Fig5Run* out,
                   std::string* why);

/// PNG maps (error and 3-sigma violations per method, as in the paper's Fig. 5) plus an SVG
/// page that lays them out with titles: <prefix>_maps.svg, <prefix>_<method>_error.png, ...
bool write_fig5_images(const Fig5Run& run, const sim::Terrain& truth, const std::string& out_dir,
                       const std::string& prefix, std::string* error);

std::string fig5_table(const Fig5Run& run, bool with_paper);

}  // namespace ccmap::experiments
