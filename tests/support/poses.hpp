// Sensor poses for tests (plain-float ccmap::Pose): identity and yaw rotations built from a
// (cos, sin) pair, so no trigonometric function is evaluated (bitwise portable).
#pragma once

#include "ccmap/map/types.hpp"

namespace ccmap::test {

[[nodiscard]] inline Pose yaw_pose(float c, float s, PointXYZ translation) noexcept {
  return Pose{{{c, -s, 0.0F}, {s, c, 0.0F}, {0.0F, 0.0F, 1.0F}}, translation};
}

[[nodiscard]] inline Pose identity_pose(PointXYZ translation = PointXYZ{0.0F, 0.0F, 0.0F}) noexcept {
  return yaw_pose(1.0F, 0.0F, translation);
}

}  // namespace ccmap::test
