// Determinism scenarios shared by every target: the geometry of the CADRE traverse of
// tests/map/determinism_dump.cpp, the whole-stack hash both golden values use, and the
// board-sized scenario that the host, aarch64 Linux (ccmap_determinism_dump) and the bare-metal
// board (tests/baremetal/scenario_cases.cpp) run against one golden file,
// tests/golden/determinism.txt.
//
// No heap, no libm: the caller hands over every buffer (static storage on the board), the
// terrain and the path are polynomials and quotients (+ - * / are correctly rounded IEEE
// operations, identical on every target built with -ffp-contract=off), the sensor rotation is
// a rational (Cayley) parametrisation and the noise an integer hash.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include "ccmap/map/stack.hpp"
#include "support/hash_unit.hpp"
#include "support/map_state.hpp"
#include "support/poses.hpp"

namespace ccmap::test::scenario {

using CadreStack = Stack<CadreConfig>;

/// Terrain height (m, map frame): a rational bump field plus a 12 cm step, + - * / only.
inline float terrain(float x, float y) {
  const float a = x * 0.3F, b = y * 0.25F;
  float h = 0.2F * a / (1.0F + a * a) + 0.1F * b * b / (1.0F + b * b);
  if (x > 3.0F && x < 3.5F) h += 0.12F;
  return h;
}

/// Sensor pose at (x, y, 0.5 m), rotated about z by yaw with t = tan(yaw / 2) (Cayley):
/// cos = (1 - t^2) / (1 + t^2), sin = 2t / (1 + t^2). No trigonometric function.
inline Pose pose_from(float x, float y, float t) {
  const float d = 1.0F / (1.0F + t * t);
  const float c = (1.0F - t * t) * d, s = 2.0F * t * d;
  return yaw_pose(c, s, PointXYZ{x, y, 0.5F});
}

/// Point i of a frame seen from `pose` (sensor at (rx, ry)): `ahead` and `side` (m) in the
/// sensor's heading frame; in the sensor frame if `sensor_frame`, else in the map frame.
inline PointXYZ terrain_point(const Pose& pose, float rx, float ry, float ahead, float side, float noise,
                              bool sensor_frame) {
  if (sensor_frame) {
    // The map point through the inverse pose (R^T (p - t)).
    const float mx = rx + pose.rotation[0][0] * ahead + pose.rotation[0][1] * side;
    const float my = ry + pose.rotation[1][0] * ahead + pose.rotation[1][1] * side;
    return PointXYZ{ahead, side, terrain(mx, my) + noise - 0.5F};
  }
  const float mx = rx + ahead;
  const float my = ry + side;
  return PointXYZ{mx, my, terrain(mx, my) + noise};
}

/// FNV-1a 64 of the whole stack: every stored float and window (map_hash), the life-time
/// counters, and an export of every layer through the pooling path. `records` must hold the
/// largest layer (StackT::layer_capacity(0)). Returns false if an export fails. StackT: a
/// Stack of the CADRE shape, either CCM cell (CadreStack or Stack<PaperCell<CadreConfig>>).
template <typename StackT>
inline bool hash_stack(const StackT& stack, CellRecord* records, std::size_t capacity, Fnv1a64& h) {
  const std::uint64_t cells = map_hash(stack);
  h.u32(static_cast<std::uint32_t>(cells >> 32));
  h.u32(static_cast<std::uint32_t>(cells));
  const FrameCounters c = stack.total_counters();
  for (const std::uint32_t v : {c.received, c.used, c.rejected_non_finite, c.rejected_out_of_range, c.rejected_weight,
                                c.outside_map, c.too_noisy, c.gated_finer, c.gated_occluded, c.gated_held,
                                c.gated_pool_full, c.gated_admitted, c.gated_dropped, c.reseeded_cells, c.merged_cells,
                                c.free_rays, c.free_rays_refused, c.cleared_cells, c.drop_cells}) {
    h.u32(v);
  }
  for (int k = 0; k < StackT::kLayerCount; ++k) {
    std::size_t written = 0;
    if (stack.export_layer(k, records, capacity, &written) != Status::kOk) {
      return false;
    }
    h.u32(static_cast<std::uint32_t>(written));
    for (std::size_t i = 0; i < written; ++i) {
      const CellRecord& r = records[i];
      h.i32(r.index.x);
      h.i32(r.index.y);
      for (const float v : {r.weight, r.height_m, r.slope_x, r.slope_y, r.normal_variance, r.elevation_variance}) {
        h.f32(v);
      }
      h.byte(static_cast<std::uint8_t>(r.cell_class));
    }
  }
  return true;
}

// ---- the board-sized scenario ----------------------------------------------------------------
// Sized for a controller with 1 MiB + 192 KiB of SRAM (the image's RAM_SIZE 0x130000,
// tests/baremetal/CMakeLists.txt): the CADRE map (874,256 B on the Cortex-M7, docs/integration.md
// section 9) + one frame of 10,000 points (120 KB) + their weights (40 KB) + an export buffer for
// the largest layer (180 KB).
// 24 frames along a curved path, cycling through the three update calls (map frame, sensor
// frame, map frame with per-point weights), with hostile points, then queries on a grid.
inline constexpr std::uint32_t kBoardFramePoints = 10000U;
inline constexpr int kBoardFrames = 24;

struct BoardResult {
  std::uint64_t hash;
  FrameCounters totals;
  int failed_step;  ///< 0 if every call answered as expected, else which step did not
};

/// Runs the scenario on `stack` (initialised here with the CADRE defaults) with the caller's
/// buffers: points[kBoardFramePoints], weights[kBoardFramePoints],
/// records[CadreStack::layer_capacity(0)].
inline BoardResult run_board_scenario(CadreStack& stack, PointXYZ* points, float* weights, CellRecord* records) {
  BoardResult result{0U, FrameCounters{}, 0};
  if (stack.init(default_stack_params(0.04F)) != Status::kOk) {
    result.failed_step = 1;
    return result;
  }
  for (int f = 0; f < kBoardFrames; ++f) {
    const float fx = static_cast<float>(f);
    const float rx = 0.05F * fx;
    const float ry = 0.3F * (fx / kBoardFrames) * (fx / kBoardFrames) - 0.1F;
    const float yaw_t = 0.2F * (fx / kBoardFrames) - 0.05F;
    if (stack.move_to(rx, ry) != Status::kOk) {
      result.failed_step = 2;
      return result;
    }
    const int kind = f % 3;  // 0: map frame, 1: sensor frame, 2: map frame with weights
    const Pose pose = pose_from(rx, ry, yaw_t);
    for (std::uint32_t i = 0; i < kBoardFramePoints; ++i) {
      const std::uint32_t id = static_cast<std::uint32_t>(f) * kBoardFramePoints + i + 7000000U;
      const float ahead = 0.25F + 4.5F * hash_unit(id, 1U);
      const float side = (5.0F * hash_unit(id, 2U) - 2.5F) * (0.2F + ahead / 4.75F);
      const float noise = 0.003F * (hash_unit(id, 3U) - 0.5F);
      points[i] = terrain_point(pose, rx, ry, ahead, side, noise, kind == 1);
      weights[i] = 0.5F + 1.5F * hash_unit(id, 4U);
    }
    // Hostile input, refused and counted alike on every target.
    points[0].x = std::numeric_limits<float>::quiet_NaN();
    points[1].z = 3.0e5F;
    points[2].y = -std::numeric_limits<float>::infinity();
    if (kind != 1) {
      points[3] = PointXYZ{rx + 40.0F, ry, 0.0F};  // outside every window
    }
    weights[4] = 0.0F;
    weights[5] = std::numeric_limits<float>::quiet_NaN();
    FrameCounters frame{};
    const PointXYZ origin{rx, ry, 0.5F};
    const Status st = kind == 0   ? stack.update_frame(points, kBoardFramePoints, origin, &frame)
                      : kind == 1 ? stack.update_frame_sensor(points, kBoardFramePoints, pose, &frame)
                                  : stack.update_frame(points, weights, kBoardFramePoints, origin, &frame);
    if (st != Status::kOk || frame.received != kBoardFramePoints) {
      result.failed_step = 3;
      return result;
    }
  }
  Fnv1a64 h;
  h.byte(1);  // format version of this scenario's hash
  if (!hash_stack(stack, records, CadreStack::layer_capacity(0), h)) {
    result.failed_step = 4;
    return result;
  }
  // Point queries on a 5 cm grid around the robot: every layer answers some of them.
  for (int j = -40; j < 40; j += 3) {
    for (int i = -60; i < 100; i += 3) {
      const QueryResult q = stack.query(0.05F * static_cast<float>(i), 0.05F * static_cast<float>(j));
      h.byte(static_cast<std::uint8_t>(q.status));
      h.i32(q.layer);
      for (const float v : {q.height_m, q.slope_x, q.slope_y, q.normal_variance, q.elevation_variance, q.weight}) {
        h.f32(v);
      }
      h.byte(static_cast<std::uint8_t>(q.cell_class));
    }
  }
  result.hash = h.hash;
  result.totals = stack.total_counters();
  return result;
}

}  // namespace ccmap::test::scenario
