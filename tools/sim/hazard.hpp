// Ground-truth hazards per map cell, the reference the detection experiments compare map
// classes against.
//
// Definition (for a square cell of width w, sampled on an n x n grid of sub-cell centres with
// n = max(4, ceil(w / sample_spacing_m))):
//  1. Local ground plane: the least-squares plane g(x, y) fitted to terrain.ground_height() at
//     the samples (rocks and boxes excluded; for terrains without discrete obstacles, such as
//     a DTM or the wave terrain, the surface itself).
//  2. slope_deg = atan(|grad g|): the inclination of the local ground.
//  3. relief_m = max_s (h - g) - min_s (h - g) over the samples, with h = terrain.height():
//     the largest height step inside the cell relative to the local ground (a rock or box
//     top above it, a crater rim or bowl, a step).
//  4. raised_m = max_s (h - ground_height): the tallest discrete obstacle (rock/box) part
//     inside the cell (0 for terrains without discrete obstacles).
//  5. obstacle = relief_m > min_obstacle_height_m  or  raised_m > min_obstacle_height_m;
//     steep = slope_deg > max_slope_deg; hazard = obstacle or steep.
// A cell with any NaN sample (outside the terrain) is invalid (valid = false, no hazard).
// Precision: the samples resolve features down to ~sample_spacing_m; a rock that only grazes
// the cell corner counts with the part of its dome inside the cell.
#pragma once

#include <vector>

#include "sim/terrain.hpp"

namespace ccmap::sim {

struct HazardParams {
  double min_obstacle_height_m = 0.15;
  double max_slope_deg = 20.0;
  double sample_spacing_m = 0.01;
};

struct CellHazard {
  bool valid = false;
  bool obstacle = false;
  bool steep = false;
  double relief_m = 0.0;
  double raised_m = 0.0;
  double slope_deg = 0.0;
  double ground_height_m = 0.0;  ///< g at the cell centre
  bool hazard() const { return valid && (obstacle || steep); }
};

/// Grid of cells: cell (ix, iy) covers [x0 + ix*w, x0 + (ix+1)*w) x [y0 + iy*w, ...).
struct HazardGrid {
  double origin_x = 0.0, origin_y = 0.0, cell_width_m = 0.0;
  int nx = 0, ny = 0;
  std::vector<CellHazard> cells;  ///< row-major, index ix + nx * iy
  const CellHazard& at(int ix, int iy) const { return cells[static_cast<std::size_t>(ix + nx * iy)]; }
};

CellHazard evaluate_cell_hazard(const Terrain& terrain, const Rect& cell, const HazardParams& params);

HazardGrid compute_hazard_grid(const Terrain& terrain, double origin_x, double origin_y, double cell_width_m,
                               int nx, int ny, const HazardParams& params);

}  // namespace ccmap::sim
