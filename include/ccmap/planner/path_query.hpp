// Path query: how far along a path can the rover body go before it meets a hazard, or ground
// the map does not know?
//
//   const ccmap::PathPoint route[] = {{x0, y0}, {x1, y1}, {x2, y2}};
//   const ccmap::PathSweep sweep{0.6F, 0.4F, 0.05F, ccmap::kDefaultMaxUnknownShare};
//   const ccmap::PathResult r = ccmap::query_path(map, route, 3, sweep);
//   if (r.hazard_found && r.first_hazard_m < 1.5F) { ...stop or replan... }
//
// The body (a length x width rectangle, its length along the direction of travel) is placed at
// poses every step_m along the path, from its start (distance 0) to its end (the end is always
// a pose), and each pose is a footprint query (planner/footprint.hpp). Answer: the distance along
// the path of the first pose whose footprint is a drop-off, obstacle or steep (footprint_class), and of the
// first whose unknown share exceeds max_unknown_share (a hazardous footprint may be both), with
// the poses there and their footprint results. The walk stops once both are found. Between poses
// the body is not checked: choose step_m below the size of the smallest hazard that matters
// (a cell of the finest layer is a safe choice).
//
// Paths:
//  - query_path: a polyline of 2 .. kMaxPathVertices map-frame points. The body's heading is the
//    direction of the segment the pose lies on (at a vertex, the segment that starts there).
//    Segments shorter than 1 um are skipped; a polyline without a longer one is refused.
//  - query_arc: from a start pose, a circular arc of constant curvature (1/m, > 0 turns left,
//    0 is straight) and length length_m >= 0, turning at most one full circle
//    (|curvature| * length_m <= 2 pi). Poses follow the arc exactly (sin/cos by a deterministic
//    polynomial, error < 2e-7: bitwise the same on every target).
//
// Bounded: at most kMaxPathSamples poses (refused with kOutOfRange beyond), each a footprint
// within kMaxFootprintCells. No heap; stack use < 4 KiB.
#pragma once

#include <cstddef>
#include <cstdint>

#include "ccmap/core/sin_cos.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/map/stack.hpp"

namespace ccmap {

/// Largest number of poses a path query evaluates.
inline constexpr std::uint32_t kMaxPathSamples = 256U;
/// Largest number of polyline vertices.
inline constexpr std::size_t kMaxPathVertices = 256U;

struct PathPoint {
  float x;  ///< map frame (m)
  float y;
};

/// A pose along a path: position and unit heading (the body's length axis).
struct PathPose {
  float x;
  float y;
  float heading_x;
  float heading_y;
};

/// The body swept along the path and how it is judged.
struct PathSweep {
  float length_m;           ///< body length along the direction of travel (m), > 0
  float width_m;            ///< body width (m), > 0
  float step_m;             ///< distance between poses (m), > 0
  float max_unknown_share;  ///< a footprint with more unknown area counts as unknown, [0, 1]
};

struct PathResult {
  Status status;                 ///< kOk or the refusal (then nothing else is set)
  bool hazard_found;             ///< a pose's footprint is a drop-off, obstacle or steep
  float first_hazard_m;          ///< its distance along the path (m); 0 if none
  PathPose hazard_pose;
  FootprintResult hazard;        ///< its footprint
  bool unknown_found;            ///< a pose's footprint has more unknown area than allowed
  float first_unknown_m;         ///< its distance along the path (m); 0 if none
  PathPose unknown_pose;
  FootprintResult unknown;       ///< its footprint
  float path_length_m;           ///< length of the whole path (m)
  float checked_m;               ///< distance of the last pose evaluated (m)
  std::uint32_t samples;         ///< poses evaluated
  std::uint32_t cells_visited;   ///< map cells read over all of them
};

namespace detail {

/// Poses along a path (validated by make_*): pose(t) for 0 <= t <= length.
class PathSampler {
 public:
  /// Polyline segments shorter than this (m) are skipped.
  static constexpr float kMinSegmentM = 1.0e-6F;

  /// A polyline. kInvalidArgument: null points, fewer than 2 or more than kMaxPathVertices, no
  /// segment of 1 um or more; kNonFiniteInput; kOutOfRange: a point beyond kMaxAbsCoordinateM.
  [[nodiscard]] Status make_polyline(const PathPoint* points, std::size_t count) noexcept;
  /// An arc. kNonFiniteInput; kInvalidArgument: heading shorter than 1e-6, negative length;
  /// kOutOfRange: start beyond kMaxAbsCoordinateM, |curvature| * length > 2 pi, length > 1e4 m.
  [[nodiscard]] Status make_arc(const PathPose& start, float curvature, float length_m) noexcept;
  [[nodiscard]] float length() const noexcept { return length_; }
  [[nodiscard]] PathPose pose(float t) const noexcept;

 private:
  const PathPoint* points_ = nullptr;
  std::size_t count_ = 0U;
  bool arc_ = false;
  PathPose start_{};
  float curvature_ = 0.0F;
  float length_ = 0.0F;
};

/// kOk and the number of poses (step_m apart from 0, plus the end) for a path of `length`, or
/// the refusal of the sweep: kNonFiniteInput, kInvalidArgument (extents or step not > 0, share
/// outside [0, 1]), kOutOfRange (more than kMaxPathSamples poses).
[[nodiscard]] Status path_sample_count(float length, const PathSweep& sweep, std::uint32_t* count) noexcept;

/// Distance of pose i of `count` (the last one is the end of the path).
[[nodiscard]] inline float path_sample_distance(std::uint32_t i, std::uint32_t count, float step, float length) noexcept {
  const float t = static_cast<float>(i) * step;
  return (i + 1U == count || t > length) ? length : t;
}

[[nodiscard]] inline PathResult refused_path(Status status) noexcept {
  PathResult r{};
  r.status = status;
  r.hazard = empty_footprint_result(status);
  r.unknown = empty_footprint_result(status);
  return r;
}

template <typename Config>
[[nodiscard]] PathResult sweep_path(const Stack<Config>& stack, const PathSampler& path, const PathSweep& sweep) noexcept {
  std::uint32_t count = 0U;
  const Status counted = path_sample_count(path.length(), sweep, &count);
  if (counted != Status::kOk) {
    return refused_path(counted);
  }
  PathResult result = refused_path(Status::kOk);
  result.path_length_m = path.length();
  const QueryView<Config> view = PlannerAccess<Config>::view(stack);
  const float finest = stack.layer_cell_width(0);
  for (std::uint32_t i = 0; i < count && !(result.hazard_found && result.unknown_found); ++i) {
    const float t = path_sample_distance(i, count, sweep.step_m, path.length());
    const PathPose pose = path.pose(t);
    const Footprint body{pose.x, pose.y, pose.heading_x, pose.heading_y, sweep.length_m, sweep.width_m};
    OrientedRect rect{};
    const Status status = make_footprint_rect(body, finest, kMaxFootprintCells, &rect);
    if (status != Status::kOk) {
      return refused_path(status);  // a body larger than the footprint limit, or a pose off range
    }
    const FootprintResult f = footprint_over(view, rect);
    ++result.samples;
    result.cells_visited += f.cells_visited;
    result.checked_m = t;
    const CellClass verdict = footprint_class(f, sweep.max_unknown_share);
    if (!result.hazard_found && is_lethal(verdict)) {
      result.hazard_found = true;
      result.first_hazard_m = t;
      result.hazard_pose = pose;
      result.hazard = f;
    }
    if (!result.unknown_found && (f.worst_class == CellClass::kUnknown || f.unknown_share > sweep.max_unknown_share)) {
      result.unknown_found = true;
      result.first_unknown_m = t;
      result.unknown_pose = pose;
      result.unknown = f;
    }
  }
  return result;
}

}  // namespace detail

/// The path query over a polyline (see the header comment). kNotInitialised before init.
template <typename Config>
[[nodiscard]] PathResult query_path(const Stack<Config>& stack, const PathPoint* points, std::size_t count,
                                    const PathSweep& sweep) noexcept {
  const Status state = stack.state_status();  // kNotInitialised, or kCorrupt after an upset
  if (state != Status::kOk) {
    return detail::refused_path(state);
  }
  detail::PathSampler path;
  const Status status = path.make_polyline(points, count);
  return status == Status::kOk ? detail::sweep_path(stack, path, sweep) : detail::refused_path(status);
}

/// The path query over an arc from `start` (see the header comment). kNotInitialised before init.
template <typename Config>
[[nodiscard]] PathResult query_arc(const Stack<Config>& stack, const PathPose& start, float curvature, float length_m,
                                   const PathSweep& sweep) noexcept {
  const Status state = stack.state_status();  // kNotInitialised, or kCorrupt after an upset
  if (state != Status::kOk) {
    return detail::refused_path(state);
  }
  detail::PathSampler path;
  const Status status = path.make_arc(start, curvature, length_m);
  return status == Status::kOk ? detail::sweep_path(stack, path, sweep) : detail::refused_path(status);
}

}  // namespace ccmap
