// The flight cycle as a CADRE rover runs it, one frame at a time (docs/performance.md, "The
// flight cycle"): move the map to the rover's new pose, fold the stereo frame in with its pose
// (sensor frame, as the camera delivers it), and answer the planner's question about the ground
// ahead. Shared by the 80 ms timing test (tests/map/timing_test.cpp), the deterministic
// instruction budget (tests/map/cycle_icount.cpp) and the benchmarks (tools/bench), so that all
// three measure the same work.
//
// The drive: the rover advances 0.25 m per frame on a gentle left curve (heading turning by
// ~0.05 rad per frame, from an integer rotation: no trigonometry, bitwise portable). Each frame is
// a full 850 x 650 CADRE stereo frame (tests/support/cadre_frames.hpp) in which 2 % of the
// pixels have no disparity (NaN) and 6 % lie beyond every IV-G range (6..15 m): a real matcher's
// frame is not all usable ground.
//
// The planner's questions (planner/footprint.hpp, planner/path_query.hpp): the footprint query of the
// rover's 1 m x 2 m corridor ahead (0.3 .. 2.3 m in front, +-0.5 m to the sides), and the path
// query of the next 2 m straight ahead swept by the 0.6 m x 0.4 m body every 5 cm (41 poses).
// corridor_queries() keeps the per-cell form (1250 point queries over the same corridor) that
// tests/icount/icount_corridor_example.cpp compares with the footprint query.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/map/stack.hpp"
#include "support/cadre_frames.hpp"

namespace ccmap::test {

inline constexpr int kCycleWidthPx = 850;
inline constexpr int kCycleHeightPx = 650;
inline constexpr float kCycleInvalidShare = 0.02F;
inline constexpr float kCycleFarShare = 0.06F;
inline constexpr float kCycleStepM = 0.25F;

/// Rover pose of cycle k: position and heading (cos, sin), sensor 17.5 cm above the ground.
struct CyclePose {
  float x;
  float y;
  float heading_cos;
  float heading_sin;
};

inline CyclePose cycle_pose(int k) noexcept {
  CyclePose p{0.0F, 0.0F, 1.0F, 0.0F};
  for (int j = 0; j < k; ++j) {
    p.x += kCycleStepM * p.heading_cos;
    p.y += kCycleStepM * p.heading_sin;
    const float c = p.heading_cos * 0.99875026F - p.heading_sin * 0.04997917F;  // +0.05 rad
    const float s = p.heading_sin * 0.99875026F + p.heading_cos * 0.04997917F;
    const float norm = std::sqrt(c * c + s * s);
    p.heading_cos = c / norm;
    p.heading_sin = s / norm;
  }
  return p;
}

/// The stereo frame of cycle k (allocates: generate it outside any timed region).
inline CadreFrame cycle_frame(int k, int width_px = kCycleWidthPx, int height_px = kCycleHeightPx) {
  const CyclePose p = cycle_pose(k);
  CadreFrameSpec spec;
  spec.width_px = width_px;
  spec.height_px = height_px;
  spec.sensor_x = p.x;
  spec.sensor_y = p.y;
  spec.heading_cos = p.heading_cos;
  spec.heading_sin = p.heading_sin;
  spec.seed = 100U + static_cast<std::uint32_t>(k);
  spec.invalid_share = kCycleInvalidShare;
  spec.far_share = kCycleFarShare;
  return make_cadre_frame(spec);
}

/// What one cycle answered (checked by the callers, so that no work is optimised away).
struct CycleOutcome {
  Status move_status;
  Status update_status;
  FrameCounters counters;
  FootprintResult corridor;  ///< the 1 m x 2 m corridor ahead
  PathResult path;           ///< the next 2 m swept by the rover body
};

/// The corridor ahead of the rover as a footprint: 2 m long from 0.3 m in front, 1 m wide.
inline Footprint corridor_footprint(const CyclePose& pose) noexcept {
  return Footprint{pose.x + 1.3F * pose.heading_cos, pose.y + 1.3F * pose.heading_sin, pose.heading_cos,
                   pose.heading_sin, 2.0F, 1.0F};
}

/// The path question: the next 2 m straight ahead from 0.3 m in front, the 0.6 m x 0.4 m body every 5 cm.
template <typename Config>
PathResult cycle_path(const Stack<Config>& stack, const CyclePose& pose) noexcept {
  const PathPose start{pose.x + 0.3F * pose.heading_cos, pose.y + 0.3F * pose.heading_sin, pose.heading_cos,
                       pose.heading_sin};
  return query_arc(stack, start, 0.0F, 2.0F, PathSweep{0.6F, 0.4F, 0.05F, kDefaultMaxUnknownShare});
}

/// The per-cell form of the corridor question: one point query per 4 cm cell (25 x 50);
/// returns the unknown count and adds the hazardous count to *hazards.
template <typename Config>
int corridor_queries(const Stack<Config>& stack, const CyclePose& pose, int* hazards) noexcept {
  int unknown = 0;
  const float step = 0.04F;  // the CADRE finest cell
  for (int i = 0; i < 50; ++i) {
    const float ahead = 0.3F + (static_cast<float>(i) + 0.5F) * step;
    for (int j = 0; j < 25; ++j) {
      const float side = -0.5F + (static_cast<float>(j) + 0.5F) * step;
      const float x = pose.x + pose.heading_cos * ahead - pose.heading_sin * side;
      const float y = pose.y + pose.heading_sin * ahead + pose.heading_cos * side;
      const QueryResult q = stack.query(x, y);
      unknown += q.status != Status::kOk ? 1 : 0;
      *hazards += (q.cell_class == CellClass::kObstacle || q.cell_class == CellClass::kSteep) ? 1 : 0;
    }
  }
  return unknown;
}

/// One cycle: move_to, update_frame_sensor, the corridor footprint and the 2 m path. No allocation.
template <typename Config>
CycleOutcome run_cycle(Stack<Config>& stack, const CyclePose& pose, const CadreFrame& frame) noexcept {
  CycleOutcome out{};
  out.move_status = stack.move_to(pose.x, pose.y);
  out.update_status =
      stack.update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, &out.counters);
  out.corridor = query_footprint(stack, corridor_footprint(pose));
  out.path = cycle_path(stack, pose);
  return out;
}

/// True if the cycle did what a rover needs: accepted move and frame, most points used, the
/// unusable ones refused for the right reasons, the corridor (seen by the previous frames and
/// this one) answered and mostly known, the path swept to its end or to its first hazard (the
/// rover's question is the distance to it: the sweep stops there).
inline bool cycle_ok(const CycleOutcome& o, std::size_t frame_points) noexcept {
  const FrameCounters& c = o.counters;
  const auto n = static_cast<double>(frame_points);
  return o.move_status == Status::kOk && o.update_status == Status::kOk && c.received == frame_points &&
         static_cast<double>(c.rejected_non_finite) > 0.015 * n && static_cast<double>(c.too_noisy) > 0.05 * n &&
         static_cast<double>(c.used) > 0.8 * n && o.corridor.status == Status::kOk && o.corridor.unknown_share < 0.5F &&
         o.path.status == Status::kOk && (o.path.samples == 41U || o.path.hazard_found);
}

}  // namespace ccmap::test
