// Small value types shared by the simulator parts.
#pragma once

namespace ccmap::sim {

/// A 3-D point (m); the frame is stated where it is used.
struct Point3 {
  double x = 0.0, y = 0.0, z = 0.0;
};

/// Planar rover pose in the map/world frame: position (m) and heading yaw (rad, from +x
/// towards +y). The rover's z is the terrain height under it (see StereoCamera).
struct Pose2 {
  double x = 0.0, y = 0.0, yaw = 0.0;
};

}  // namespace ccmap::sim
