#include "sim/cloud.hpp"

#include <cmath>

#include "sim/rng.hpp"

namespace ccmap::sim {

std::vector<Point3> sample_noisy_cloud(const Terrain& terrain, const CloudParams& params) {
  std::vector<Point3> out;
  out.reserve(params.count);
  Rng rng(params.seed);
  for (std::size_t k = 0; k < params.count; ++k) {
    const double x = rng.uniform(params.area.x0, params.area.x1);
    const double y = rng.uniform(params.area.y0, params.area.y1);
    const double noise = rng.normal(0.0, params.sigma_z_m);
    const double h = terrain.height(x, y);
    if (std::isfinite(h)) out.push_back(Point3{x, y, h + noise});
  }
  return out;
}

}  // namespace ccmap::sim
