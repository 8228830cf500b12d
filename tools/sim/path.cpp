#include "sim/path.hpp"

#include <cmath>

#include "sim/rng.hpp"
#include "sim/terrain.hpp"

namespace ccmap::sim {

std::vector<PathPose> generate_path(const Pose2& start, const std::vector<PathSegment>& segments, double spacing_m) {
  std::vector<PathPose> out;
  out.push_back(PathPose{start, 0.0});
  if (!(spacing_m > 0.0)) return out;
  Pose2 p = start;
  double driven = 0.0;
  double since_last = 0.0;
  for (const PathSegment& s : segments) {
    if (!(s.length_m > 0.0)) continue;
    // Integrate in small exact sub-steps so arcs are followed exactly and samples fall every
    // spacing_m of driven distance.
    double remaining = s.length_m;
    const double curvature = s.turn_rad / s.length_m;
    while (remaining > 1e-12) {
      const double step = std::min(remaining, spacing_m - since_last);
      if (std::fabs(curvature) < 1e-12) {
        p.x += step * std::cos(p.yaw);
        p.y += step * std::sin(p.yaw);
      } else {
        const double r = 1.0 / curvature;
        const double yaw1 = p.yaw + step * curvature;
        p.x += r * (std::sin(yaw1) - std::sin(p.yaw));
        p.y += -r * (std::cos(yaw1) - std::cos(p.yaw));
        p.yaw = yaw1;
      }
      remaining -= step;
      driven += step;
      since_last += step;
      if (since_last >= spacing_m - 1e-12) {
        out.push_back(PathPose{p, driven});
        since_last = 0.0;
      }
    }
  }
  if (since_last > 1e-9) out.push_back(PathPose{p, driven});
  return out;
}

std::vector<Pose2> apply_drift(const std::vector<PathPose>& truth, const DriftParams& drift) {
  double direction = drift.direction_rad;
  if (drift.random_direction) {
    Rng rng(drift.seed);
    direction = rng.uniform(0.0, 2.0 * kPi);
  }
  const double ux = std::cos(direction), uy = std::sin(direction);
  std::vector<Pose2> out;
  out.reserve(truth.size());
  for (const PathPose& t : truth) {
    const double e = drift.fraction_of_distance * t.distance_m;
    out.push_back(Pose2{t.pose.x + e * ux, t.pose.y + e * uy, t.pose.yaw + drift.heading_rad_per_m * t.distance_m});
  }
  return out;
}

}  // namespace ccmap::sim
