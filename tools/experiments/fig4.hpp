// Fig. 4 of the paper: surface-normal variance of one CCM cell versus obstacle coverage.
//
// A 32 cm cell with a 24 cm step (75 % of the cell width): the step covers the far fraction c
// of the cell along x (x >= w/2 - c w). Points are fed into one CcmCell (the library's
// ccm_update) and sigma_s^2 (eq. 11) is read back for c from 0 to 1.
//  - Noiseless: an n x n grid of points at sub-cell centres; c = k/n exactly.
//    Analytic curve: with u = c (1 - c), sigma_s^2 = h^2 u (1 - 3u); at c = 0.5 it is h^2/16.
//    Thresholding at the 50 % value detects c (1 - c) >= 1/12, i.e. c in [9.18 %, 90.82 %]
//    (paper: 11 % - 91 %).
//  - Stereo-like noise: uniform random points, each displaced along the line of sight of a
//    camera camera_height_m above the ground at distance `range_m` by N(0, sigma_Z) with
//    sigma_Z = Z^2/(f b) sqrt(sigma_d^2 + q^2/12) (the simulator's stereo model), averaged
//    over trials; one curve per range.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ccmap::experiments {

struct Fig4Config {
  double cell_width_m = 0.32;
  double step_height_m = 0.24;
  int grid_n = 200;                        ///< noiseless points per axis (even; c resolution 1/n)
  int noisy_levels = 50;                   ///< coverage levels of the noisy curves (c = k / levels)
  int noisy_points = 2000;                 ///< points per noisy cell
  int noisy_trials = 20;                   ///< cells averaged per level
  std::vector<double> noisy_ranges_m{2.0, 4.0};
  double camera_height_m = 0.175;
  double focal_px = 600.0, baseline_m = 0.05, disparity_sigma_px = 0.1, disparity_step_px = 1.0 / 16.0;
  std::uint64_t seed = 1;
  bool paper_cell = false;                 ///< the paper's 9-float cell (CcmPaperCell) instead of CcmCell
  static Fig4Config quick() {
    Fig4Config c;
    c.grid_n = 100;
    c.noisy_levels = 20;
    c.noisy_points = 1000;
    c.noisy_trials = 5;
    return c;
  }
};

struct Fig4Curve {
  std::vector<double> coverage;         ///< fraction 0..1
  std::vector<double> normal_variance;  ///< m^2
};

/// Coverage interval [lo, hi] where the curve is >= threshold (linear interpolation of the
/// crossings); lo = hi = NaN if never.
struct CoverageInterval {
  double lo, hi;
};

struct Fig4NoisyCurve {
  double range_m = 0.0;
  double depth_sigma_m = 0.0;
  Fig4Curve curve;
  double threshold = 0.0;              ///< its own value at 50 % coverage
  CoverageInterval interval{0.0, 0.0}; ///< with its own threshold
  CoverageInterval interval_noiseless_threshold{0.0, 0.0};
};

struct Fig4Result {
  Fig4Curve noiseless, analytic;
  double threshold = 0.0;           ///< noiseless sigma_s^2 at c = 0.5 (m^2)
  double analytic_threshold = 0.0;  ///< h^2 / 16
  CoverageInterval interval{0.0, 0.0};           ///< measured, noiseless
  CoverageInterval analytic_interval{0.0, 0.0};  ///< c(1-c) >= 1/12
  std::vector<Fig4NoisyCurve> noisy;
};

/// sigma_s^2 = h^2 u (1 - 3u), u = c (1 - c).
double fig4_analytic_normal_variance(double coverage, double step_height_m);

CoverageInterval coverage_interval(const Fig4Curve& curve, double threshold);

Fig4Result run_fig4(const Fig4Config& config);

/// Writes fig4.svg and fig4.csv into out_dir; false with a reason.
bool write_fig4_outputs(const Fig4Config& config, const Fig4Result& result, const std::string& out_dir,
                        std::string* error);

/// The result table (with the paper's numbers beside).
std::string fig4_table(const Fig4Config& config, const Fig4Result& result);

}  // namespace ccmap::experiments
