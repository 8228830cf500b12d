// Noise-added point cloud of a terrain (the paper's Fig. 5 setting).
#pragma once

#include <cstdint>
#include <vector>

#include "sim/terrain.hpp"
#include "sim/types.hpp"

namespace ccmap::sim {

struct CloudParams {
  Rect area{0.0, 0.0, 20.0, 20.0};
  std::size_t count = 40000;  ///< points drawn (points where the terrain is NaN are dropped)
  double sigma_z_m = 0.05;    ///< standard deviation of the vertical noise
  std::uint64_t seed = 1;
};

/// (x, y) uniform over params.area, z = terrain.height(x, y) + N(0, sigma_z) (world frame).
std::vector<Point3> sample_noisy_cloud(const Terrain& terrain, const CloudParams& params);

}  // namespace ccmap::sim
