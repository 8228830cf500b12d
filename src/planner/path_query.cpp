// Non-template parts of the path queries (planner/path_query.hpp): path sampling.
#include <cmath>

#include "ccmap/core/sin_cos.hpp"
#include "ccmap/planner/path_query.hpp"

namespace ccmap::detail {

Status PathSampler::make_polyline(const PathPoint* points, std::size_t count) noexcept {
  if (points == nullptr || count < 2U || count > kMaxPathVertices) {
    return Status::kInvalidArgument;
  }
  float length = 0.0F;
  for (std::size_t i = 0; i < count; ++i) {
    if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y)) {
      return Status::kNonFiniteInput;
    }
    if (check_position(points[i].x, points[i].y) != Status::kOk) {
      return Status::kOutOfRange;
    }
    if (i > 0U) {
      const float dx = points[i].x - points[i - 1U].x;
      const float dy = points[i].y - points[i - 1U].y;
      const float segment = std::sqrt(dx * dx + dy * dy);
      length += segment >= kMinSegmentM ? segment : 0.0F;
    }
  }
  if (!(length > 0.0F)) {
    return Status::kInvalidArgument;
  }
  *this = PathSampler{};
  points_ = points;
  count_ = count;
  length_ = length;
  return Status::kOk;
}

Status PathSampler::make_arc(const PathPose& start, float curvature, float length_m) noexcept {
  const float values[] = {start.x, start.y, start.heading_x, start.heading_y, curvature, length_m};
  for (const float v : values) {
    if (!std::isfinite(v)) {
      return Status::kNonFiniteInput;
    }
  }
  if (check_position(start.x, start.y) != Status::kOk) {
    return Status::kOutOfRange;
  }
  OrientedRect unit{};  // normalises the heading (and refuses a null one)
  if (!(length_m >= 0.0F) || !make_oriented_rect(start.x, start.y, start.heading_x, start.heading_y, 1.0F, 1.0F, &unit)) {
    return Status::kInvalidArgument;
  }
  if (length_m > 1.0e4F || std::fabs(curvature) * length_m > 6.28318531F) {
    return Status::kOutOfRange;
  }
  *this = PathSampler{};
  arc_ = true;
  start_ = PathPose{start.x, start.y, unit.ux, unit.uy};
  curvature_ = curvature;
  length_ = length_m;
  return Status::kOk;
}

PathPose PathSampler::pose(float t) const noexcept {
  if (arc_) {
    // Turned angle theta = k t; position = start + u A + n B with u the start heading, n its
    // left normal, A = sin(theta) / k, B = (1 - cos(theta)) / k (t and 0 at k = 0), in the
    // forms that stay exact as k -> 0.
    const float theta = curvature_ * t;
    float s = 0.0F;
    float c = 1.0F;
    sin_cos(theta, &s, &c);
    float along = 0.0F;
    float across = 0.0F;
    if (std::fabs(theta) < 0.5F) {
      const float q = theta * theta;  // Taylor to theta^8 / theta^9: truncation < 3e-11
      along = t * (1.0F + q * (-1.0F / 6.0F + q * (1.0F / 120.0F + q * (-1.0F / 5040.0F + q * (1.0F / 362880.0F)))));
      across = t * theta * (0.5F + q * (-1.0F / 24.0F + q * (1.0F / 720.0F + q * (-1.0F / 40320.0F + q * (1.0F / 3628800.0F)))));
    } else {
      along = s / curvature_;  // |k| >= 0.5 / t > 0
      across = (1.0F - c) / curvature_;
    }
    const float ux = start_.heading_x;
    const float uy = start_.heading_y;
    return PathPose{start_.x + ux * along - uy * across, start_.y + uy * along + ux * across, c * ux - s * uy,
                    s * ux + c * uy};
  }
  // Polyline: the segment that holds t (the last one for t at or beyond the end).
  float walked = 0.0F;
  PathPose last{points_[0].x, points_[0].y, 1.0F, 0.0F};
  for (std::size_t i = 1; i < count_; ++i) {
    const float dx = points_[i].x - points_[i - 1U].x;
    const float dy = points_[i].y - points_[i - 1U].y;
    const float segment = std::sqrt(dx * dx + dy * dy);
    if (segment < kMinSegmentM) {
      continue;
    }
    const float ux = dx / segment;
    const float uy = dy / segment;
    const float along = t - walked;
    last = PathPose{points_[i].x, points_[i].y, ux, uy};
    if (along < segment) {
      const float a = along > 0.0F ? along : 0.0F;
      return PathPose{points_[i - 1U].x + ux * a, points_[i - 1U].y + uy * a, ux, uy};
    }
    walked += segment;
  }
  return last;
}

Status path_sample_count(float length, const PathSweep& sweep, std::uint32_t* count) noexcept {
  const float values[] = {length, sweep.length_m, sweep.width_m, sweep.step_m, sweep.max_unknown_share};
  for (const float v : values) {
    if (!std::isfinite(v)) {
      return Status::kNonFiniteInput;
    }
  }
  if (!(sweep.length_m > 0.0F) || !(sweep.width_m > 0.0F) || !(sweep.step_m > 0.0F) || !(length >= 0.0F) ||
      sweep.max_unknown_share < 0.0F || sweep.max_unknown_share > 1.0F) {
    return Status::kInvalidArgument;
  }
  // Poses at 0, step, 2 step, ... below the end, and the end; a pose within 0.1 % of a step of
  // the end is the end.
  const float steps = length / sweep.step_m;
  if (!(steps < static_cast<float>(kMaxPathSamples))) {
    return Status::kOutOfRange;
  }
  auto n = static_cast<std::uint32_t>(std::floor(steps));
  if (steps - static_cast<float>(n) > 1.0e-3F) {
    ++n;
  }
  n += 1U;
  if (n > kMaxPathSamples) {
    return Status::kOutOfRange;
  }
  *count = n;
  return Status::kOk;
}

}  // namespace ccmap::detail
