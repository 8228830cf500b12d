// Rover paths (straight lines and arcs) and a drifting pose estimate.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/types.hpp"

namespace ccmap::sim {

/// One path piece: drive length_m while the heading turns by turn_rad (0 = straight line,
/// otherwise a circular arc of radius length_m / |turn_rad|, positive = to the left).
struct PathSegment {
  double length_m = 0.0;
  double turn_rad = 0.0;
};

/// A pose sampled along a path with the distance driven to reach it.
struct PathPose {
  Pose2 pose;
  double distance_m = 0.0;
};

/// Poses every spacing_m along the segments, starting with `start` (distance 0) and ending at
/// the path's end. Segments with length <= 0 are skipped.
std::vector<PathPose> generate_path(const Pose2& start, const std::vector<PathSegment>& segments, double spacing_m);

/// Pose-estimate drift that grows with the distance driven d:
///   position error = fraction_of_distance * d * (cos(direction_rad), sin(direction_rad)),
///   heading error  = heading_rad_per_m * d.
/// If random_direction, direction_rad is drawn from seed instead (uniform in [0, 2 pi)).
/// fraction_of_distance = 0.08 is "8 % drift" (paper Section V-D).
struct DriftParams {
  double fraction_of_distance = 0.0;
  double direction_rad = 0.0;
  bool random_direction = false;
  double heading_rad_per_m = 0.0;
  std::uint64_t seed = 1;
};

/// The estimated (drifting) pose for each true path pose.
std::vector<Pose2> apply_drift(const std::vector<PathPose>& truth, const DriftParams& drift);

}  // namespace ccmap::sim
