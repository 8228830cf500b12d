// Stack configurations of the global map's tests and host tools (include/ccmap/global/), and the
// points a rover with drifting odometry sees.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ccmap/map/config.hpp"
#include "ccmap/map/types.hpp"

namespace ccmap::test {

/// CCM layers of 4, 8 and 16 cm, 64 cells a side (+-1.28, +-2.56, +-5.12 m): the coarse search
/// has a 32 cm level (16 cm pooled) and two layers below it.
struct ThreeCcmConfig {
  static constexpr FineKind kFineKind = FineKind::kNone;
  static constexpr CcmCellKind kCcmCell = CcmCellKind::kFull;
  static constexpr std::int32_t kFineSide = 0;
  static constexpr std::array<std::int32_t, 3> kCcmSides{{64, 64, 64}};
  static constexpr float kDefaultFinestCellWidthM = 0.04F;
};

/// One CCM layer of 32 x 32 cells of 8 cm (+-1.28 m): patches of 16 x 16 cells are 1.28 m.
struct OneCcm8cmConfig {
  static constexpr FineKind kFineKind = FineKind::kNone;
  static constexpr CcmCellKind kCcmCell = CcmCellKind::kFull;
  static constexpr std::int32_t kFineSide = 0;
  static constexpr std::array<std::int32_t, 1> kCcmSides{{32}};
  static constexpr float kDefaultFinestCellWidthM = 0.08F;
};

/// One CCM layer of 64 x 64 cells of 4 cm (+-1.28 m).
struct OneCcm4cmConfig {
  static constexpr FineKind kFineKind = FineKind::kNone;
  static constexpr CcmCellKind kCcmCell = CcmCellKind::kFull;
  static constexpr std::int32_t kFineSide = 0;
  static constexpr std::array<std::int32_t, 1> kCcmSides{{64}};
  static constexpr float kDefaultFinestCellWidthM = 0.04F;
};

/// A rover pose in the plane (m, rad): the truth of a simulated drive, or what odometry believes.
struct DrivePose {
  double x, y, yaw;
};

/// The ground within `radius` (m) of the true pose, on a square lattice of `spacing` in the
/// rover's frame, as a rover that believes it stands at `believed` places it: map-frame x, y from
/// the believed pose, z = ground(true x, true y).
template <typename Ground>
std::vector<PointXYZ> ground_seen_from(const DrivePose& truth, const DrivePose& believed, double radius,
                                       double spacing, Ground&& ground) {
  std::vector<PointXYZ> out;
  const double ct = std::cos(truth.yaw), st = std::sin(truth.yaw);
  const double cb = std::cos(believed.yaw), sb = std::sin(believed.yaw);
  const int n = static_cast<int>(std::floor(radius / spacing));
  for (int j = -n; j <= n; ++j) {
    for (int i = -n; i <= n; ++i) {
      const double u = i * spacing, v = j * spacing;
      if (u * u + v * v <= radius * radius) {
        const double gx = truth.x + ct * u - st * v, gy = truth.y + st * u + ct * v;
        out.push_back(PointXYZ{static_cast<float>(believed.x + cb * u - sb * v),
                               static_cast<float>(believed.y + sb * u + cb * v), static_cast<float>(ground(gx, gy))});
      }
    }
  }
  return out;
}

}  // namespace ccmap::test
