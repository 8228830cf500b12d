// The lateral covariance experiment (issue 11, issue 9 item 4): slope errors of the paper's
// 9-float CCM cell (CcmPaperCell, eq. 9 per axis) and of the full cell (CcmCell, the 2 x 2
// least-squares solve) on the point sets where x and y are correlated in a cell, and the seen
// share a cell needs to pass each cell's coverage test.
//
// Cases (a plane z = c + a x + b y, the truth; 16 cm cells unless said otherwise; points uniform
// over the seen part of the cell, no noise, so every slope error is the cell's, not the data's):
//  - diagonal half: the triangle x + y < 0 of a 12 deg plane along y (a shadow edge seen at 45 deg);
//  - half at a random angle: the half plane n . (x, y) < 0, n uniform on the circle;
//  - full cell of 500 points: the sample correlation of x and y alone;
//  - L: three quadrants of the cell;
//  - pooled parents: 8 cm children, each a regular 12 x 12 grid on a 20 deg plane along y,
//    pooled with ccm_pool4 for every pattern of observed children;
//  - coverage: for a straight shadow edge at angle theta to the x axis, the smallest seen
//    share of the cell (the part on one side of the edge, through any offset) that passes
//    ccm_is_covered with tau = 0.8, found by bisection on a 400 x 400 grid of the cell.
// Deterministic by seed. Host only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ccmap::experiments {

struct LateralConfig {
  double cell_width_m = 0.16;
  int trials = 200;          ///< random cells per random case
  int points = 2000;         ///< points per cell (the full-cell case uses 500)
  std::uint64_t seed = 1;
  static LateralConfig quick() {
    LateralConfig c;
    c.trials = 20;
    return c;
  }
};

/// Slope error (|(a, b) - truth|, the gradient's error vector length) of one case, both cells.
struct LateralSlopeRow {
  std::string name;
  double truth_slope_x = 0.0, truth_slope_y = 0.0;
  double paper_slope_x = 0.0, full_slope_x = 0.0;  ///< of the first trial (the deterministic cases: the only one)
  double paper_rms = 0.0, paper_max = 0.0;         ///< over the trials
  double full_rms = 0.0, full_max = 0.0;
  int paper_covered = 0, full_covered = 0;         ///< trials whose cell passed ccm_is_covered (tau 0.8)
  int trials = 0;
};

struct LateralCoverageRow {
  double edge_deg = 0.0;
  double paper_share = 0.0;  ///< smallest seen share covered by the paper cell's test
  double full_share = 0.0;   ///< ... by the full cell's (smaller eigenvalue)
};

struct LateralResult {
  std::vector<LateralSlopeRow> slopes;
  std::vector<LateralCoverageRow> coverage;
};

LateralResult run_lateral(const LateralConfig& config);
std::string lateral_table(const LateralConfig& config, const LateralResult& result);

}  // namespace ccmap::experiments
