#include "sim/hazard.hpp"

#include <algorithm>
#include <cmath>

namespace ccmap::sim {

CellHazard evaluate_cell_hazard(const Terrain& terrain, const Rect& cell, const HazardParams& params) {
  CellHazard out;
  const double w = std::max(cell.width(), cell.height());
  const int n = std::max(4, static_cast<int>(std::ceil(w / std::max(1e-4, params.sample_spacing_m))));
  const double cx = 0.5 * (cell.x0 + cell.x1), cy = 0.5 * (cell.y0 + cell.y1);
  std::vector<double> xs, ys, hs, gs;
  xs.reserve(static_cast<std::size_t>(n * n));
  ys.reserve(xs.capacity());
  hs.reserve(xs.capacity());
  gs.reserve(xs.capacity());
  for (int j = 0; j < n; ++j) {
    const double y = cell.y0 + (j + 0.5) * cell.height() / n;
    for (int i = 0; i < n; ++i) {
      const double x = cell.x0 + (i + 0.5) * cell.width() / n;
      const double h = terrain.height(x, y), g = terrain.ground_height(x, y);
      if (!std::isfinite(h) || !std::isfinite(g)) return out;  // invalid
      xs.push_back(x - cx);
      ys.push_back(y - cy);
      hs.push_back(h);
      gs.push_back(g);
    }
  }
  // Least-squares plane g = c + a x + b y on a symmetric grid: x and y are centred and
  // uncorrelated, so the normal equations decouple.
  double sg = 0.0, sxg = 0.0, syg = 0.0, sxx = 0.0, syy = 0.0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    sg += gs[k];
    sxg += xs[k] * gs[k];
    syg += ys[k] * gs[k];
    sxx += xs[k] * xs[k];
    syy += ys[k] * ys[k];
  }
  const double c = sg / static_cast<double>(xs.size());
  const double a = sxx > 0.0 ? sxg / sxx : 0.0;
  const double b = syy > 0.0 ? syg / syy : 0.0;
  double lo = 1e300, hi = -1e300, raised = 0.0;
  for (std::size_t k = 0; k < xs.size(); ++k) {
    const double d = hs[k] - (c + a * xs[k] + b * ys[k]);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
    raised = std::max(raised, hs[k] - gs[k]);
  }
  out.valid = true;
  out.relief_m = hi - lo;
  out.raised_m = raised;
  out.slope_deg = std::atan(std::sqrt(a * a + b * b)) * 180.0 / kPi;
  out.ground_height_m = c;
  out.obstacle = out.relief_m > params.min_obstacle_height_m || out.raised_m > params.min_obstacle_height_m;
  out.steep = out.slope_deg > params.max_slope_deg;
  return out;
}

HazardGrid compute_hazard_grid(const Terrain& terrain, double origin_x, double origin_y, double cell_width_m,
                               int nx, int ny, const HazardParams& params) {
  HazardGrid grid;
  grid.origin_x = origin_x;
  grid.origin_y = origin_y;
  grid.cell_width_m = cell_width_m;
  grid.nx = nx;
  grid.ny = ny;
  grid.cells.resize(static_cast<std::size_t>(std::max(0, nx) * std::max(0, ny)));
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      const Rect cell{origin_x + ix * cell_width_m, origin_y + iy * cell_width_m, origin_x + (ix + 1) * cell_width_m,
                      origin_y + (iy + 1) * cell_width_m};
      grid.cells[static_cast<std::size_t>(ix + nx * iy)] = evaluate_cell_hazard(terrain, cell, params);
    }
  }
  return grid;
}

}  // namespace ccmap::sim
