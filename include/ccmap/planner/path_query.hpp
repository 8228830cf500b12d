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
// first whose unknown share exceeds max_unknown_share or that has any upset part (upset_share > 0:
// a single-event upset, map/detail/integrity.hpp; a hazardous footprint may be both), with
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
// Cost: the answer is that of every pose's footprint query, but poses of one heading (a straight
// path, a polyline's segment) are judged in groups: one walk over the rectangle a group sweeps
// finds the poses that a lethal or unknown part may touch, and only those are walked as
// footprints (detail::sweep_path). A clear straight path costs about one walk of the area it
// sweeps; a turning arc, one footprint per pose.
//
// Bounded: at most kMaxPathSamples poses (refused with kOutOfRange beyond), each a footprint
// within kMaxFootprintCells (a group whose swept rectangle exceeds it is judged pose by pose).
// No heap; stack use < 4 KiB.
#pragma once

#include <cstddef>
#include <cstdint>

#include "ccmap/core/sin_cos.hpp"
#include "ccmap/grid/ring_index.hpp"
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
  std::uint32_t samples;         ///< poses judged (in order, up to the walk's end)
  std::uint32_t cells_visited;   ///< map cells read: the groups' walks and the poses walked one by one
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

/// True if two poses have bit for bit the same heading (poses of one straight run).
[[nodiscard]] inline bool same_heading(const PathPose& a, const PathPose& b) noexcept {
  return grid::detail::float_bits(a.heading_x) == grid::detail::float_bits(b.heading_x) &&
         grid::detail::float_bits(a.heading_y) == grid::detail::float_bits(b.heading_y);
}

/// Largest number of consecutive poses judged together by one walk of their swept rectangle.
inline constexpr std::uint32_t kMaxHullPoses = 32U;
/// The first group of a straight run has this many poses (one: judged alone); each next one
/// kHullGrowth times as many, up to kMaxHullPoses.
inline constexpr std::uint32_t kFirstHullPoses = 1U;
inline constexpr std::uint32_t kHullGrowth = 8U;

/// The poses of one group: which of them may hold a hazard or too much unknown area.
struct HullFlags {
  float unknown_bound[kMaxHullPoses];  ///< unknown area (m^2) of the pieces the pose may overlap
  bool maybe_hazard[kMaxHullPoses];    ///< a lethal piece may overlap the pose
};

/// Sink of the walk over a group's swept rectangle: for every unknown or lethal piece, the poses
/// whose rectangle it may touch. A pose's footprint is inside the swept rectangle and has the
/// same heading, and a map cell answers every piece of it alike (region_walk.hpp), so a pose
/// that no lethal piece may touch has no lethal part, and its unknown area is at most the sum of
/// the unknown pieces that may touch it. Pieces and poses are compared along the heading only:
/// across it the swept rectangle is the body's width (plus the margin).
class HullSink {
 public:
  /// along: each pose's centre along the heading from the rectangle's centre (m); half_length:
  /// the body's half length plus the margin (m).
  HullSink(const OrientedRect& rect, const float* along, std::uint32_t count, float half_length, HullFlags* flags) noexcept
      : rect_(rect), along_(along), count_(count), half_length_(half_length), flags_(flags) {}

  void operator()(const RegionPiece& piece, const RegionAnswer& a) noexcept {
    // An upset piece flags its poses as a lethal one does: each is judged on its own footprint
    // (footprint_class: unknown), never let through on the unknown-area bound.
    const bool lethal = (a.known && is_lethal(a.cell_class)) || a.upset;
    if (a.known && !lethal) {
      return;
    }
    // The piece's extent along the heading (relative to the rectangle's centre).
    float lo = 0.0F;
    float hi = 0.0F;
    if (piece.polygon != nullptr) {
      lo = piece.polygon->x[0] * rect_.ux + piece.polygon->y[0] * rect_.uy;
      hi = lo;
      for (int i = 1; i < piece.polygon->count; ++i) {
        const float s = piece.polygon->x[i] * rect_.ux + piece.polygon->y[i] * rect_.uy;
        lo = s < lo ? s : lo;
        hi = s > hi ? s : hi;
      }
    } else {
      const float centre = piece.dx * rect_.ux + piece.dy * rect_.uy;
      const float reach = piece.half * rect_.corner_reach;
      lo = centre - reach;
      hi = centre + reach;
    }
    for (std::uint32_t i = 0; i < count_; ++i) {
      if (along_[i] - half_length_ > hi || along_[i] + half_length_ < lo) {
        continue;
      }
      if (lethal) {
        flags_->maybe_hazard[i] = true;
      } else {
        flags_->unknown_bound[i] += piece.area;
      }
    }
  }

 private:
  const OrientedRect& rect_;
  const float* along_;
  std::uint32_t count_;
  float half_length_;
  HullFlags* flags_;
};

/// The body's footprint at `pose`, validated (kOk) or refused: a body larger than the
/// footprint limit, or a pose off range.
[[nodiscard]] inline Status pose_rect(const PathPose& pose, const PathSweep& sweep, float finest,
                                      OrientedRect* rect) noexcept {
  const Footprint body{pose.x, pose.y, pose.heading_x, pose.heading_y, sweep.length_m, sweep.width_m};
  return make_footprint_rect(body, finest, kMaxFootprintCells, rect);
}

/// The footprint at `pose` (validated: pose_rect) into *result (the first hazard, the first
/// unknown footprint), as the per-pose sweep judges it.
template <typename Config>
[[gnu::noinline]] void judge_pose(const QueryView<Config>& view, float finest, const PathPose& pose, float t, const PathSweep& sweep,
                PathResult* result) noexcept {
  OrientedRect rect{};
  (void)pose_rect(pose, sweep, finest, &rect);  // validated when the pose was made
  const FootprintResult f = footprint_over(view, rect);
  result->cells_visited += f.cells_visited;
  const CellClass verdict = footprint_class(f, sweep.max_unknown_share);
  if (!result->hazard_found && is_lethal(verdict)) {
    result->hazard_found = true;
    result->first_hazard_m = t;
    result->hazard_pose = pose;
    result->hazard = f;
  }
  if (!result->unknown_found && (f.worst_class == CellClass::kUnknown || f.unknown_share > sweep.max_unknown_share ||
                                 f.upset_share > 0.0F)) {
    result->unknown_found = true;
    result->first_unknown_m = t;
    result->unknown_pose = pose;
    result->unknown = f;
  }
}

/// The walk over the rectangle that the poses at distances ts[0 .. n) sweep (2 <= n <=
/// kMaxHullPoses, one heading) into *flags (HullSink); adds the cells it read to *reads. False
/// (nothing flagged) if that rectangle is refused (larger than the footprint limit). Not inlined:
/// its walk's frame is gone before a flagged pose's footprint walk starts.
template <typename Config>
[[gnu::noinline]] bool flag_group(const QueryView<Config>& view, const PathSampler& path, const float* ts,
                                  std::uint32_t n, const PathSweep& sweep, float finest, HullFlags* flags,
                                  std::uint32_t* reads) noexcept {
  const PathPose first = path.pose(ts[0]);
  const PathPose last = path.pose(ts[n - 1U]);
  OrientedRect unit{};
  (void)pose_rect(first, sweep, finest, &unit);  // validated when the group was made: its unit heading
  const float ux = unit.ux;
  const float uy = unit.uy;
  const float cx = 0.5F * (first.x + last.x);
  const float cy = 0.5F * (first.y + last.y);
  // Margin (m) for the rounding of the two walks' geometry: 1 mm, and ~7 float steps of the
  // coordinates' size (positions far from the origin round more coarsely).
  const float margin = 1.0e-3F + 4.0e-7F * (std::fabs(cx) + std::fabs(cy));
  float along[kMaxHullPoses];
  float reach_along = 0.0F;
  float reach_across = 0.0F;
  for (std::uint32_t i = 0; i < n; ++i) {
    const PathPose p = path.pose(ts[i]);
    const float dx = p.x - cx;
    const float dy = p.y - cy;
    along[i] = dx * ux + dy * uy;
    const float across = std::fabs(dy * ux - dx * uy);
    reach_along = std::fabs(along[i]) > reach_along ? std::fabs(along[i]) : reach_along;
    reach_across = across > reach_across ? across : reach_across;
  }
  const float half_length = 0.5F * sweep.length_m + margin;
  const Footprint swept{cx, cy, ux, uy, 2.0F * (reach_along + half_length),
                        2.0F * (reach_across + 0.5F * sweep.width_m + margin)};
  OrientedRect hull{};
  if (make_footprint_rect(swept, finest, kMaxFootprintCells, &hull) != Status::kOk) {
    return false;
  }
  RegionWalk<Config> walk(view);
  HullSink sink(hull, along, n, half_length, flags);
  walk.run(hull, sink);
  *reads += walk.cells_read();
  return true;
}

/// The sweep (see the header comment). Consecutive poses of one heading (a straight path, a
/// polyline's segment) are judged in groups: one walk over the rectangle they sweep flags the
/// poses a lethal or unknown piece may touch (flag_group, HullSink), and only those are walked
/// one by one, in order, for what is still sought. The answer is the per-pose sweep's: a pose
/// left out has no lethal part and at most half the allowed unknown area (the margin covers the
/// float rounding of the two walks). A straight run's first pose is judged alone, then groups of
/// 8, then of 32: a hazard at the start costs one footprint, a clear 2 m path about one walk
/// of the area it sweeps instead of one per pose. Poses of a turning arc, and groups whose swept
/// rectangle exceeds the footprint limit, are judged one by one. Every pose's footprint is
/// validated, judged or not (a refused pose refuses the query, as per pose).
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
  const float unknown_allowed = 0.5F * sweep.max_unknown_share * (sweep.length_m * sweep.width_m);
  float ts[kMaxHullPoses];
  std::uint32_t group = kFirstHullPoses;
  std::uint32_t i = 0U;
  while (i < count && !(result.hazard_found && result.unknown_found)) {
    // The next poses of one heading, up to `group` of them, each validated.
    std::uint32_t n = 0U;
    PathPose head{};
    while (n < group && i + n < count) {
      const float t = path_sample_distance(i + n, count, sweep.step_m, path.length());
      const PathPose pose = path.pose(t);
      if (n > 0U && !same_heading(pose, head)) {
        break;
      }
      OrientedRect rect{};
      const Status status = pose_rect(pose, sweep, finest, &rect);
      if (status != Status::kOk) {
        return refused_path(status);  // a body larger than the footprint limit, or a pose off range
      }
      head = n == 0U ? pose : head;
      ts[n] = t;
      ++n;
    }
    HullFlags flags{};
    const bool grouped = n >= 2U && flag_group(view, path, ts, n, sweep, finest, &flags, &result.cells_visited);
    for (std::uint32_t j = 0; j < n && !(result.hazard_found && result.unknown_found); ++j) {
      ++result.samples;
      result.checked_m = ts[j];
      const bool hazard = !result.hazard_found && flags.maybe_hazard[j];
      const bool unknown = !result.unknown_found && !(flags.unknown_bound[j] <= unknown_allowed);
      if (!grouped || hazard || unknown) {
        judge_pose(view, finest, path.pose(ts[j]), ts[j], sweep, &result);
      }
    }
    i += n;
    // A full group: the next one kHullGrowth times as long; a group cut by a turn or the path's
    // end: the next straight run starts with one pose again.
    group = n == group ? (group < kMaxHullPoses / kHullGrowth ? kHullGrowth * group : kMaxHullPoses) : kFirstHullPoses;
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
