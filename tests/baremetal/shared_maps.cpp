#include "shared_maps.hpp"

#include "support/board_scenario.hpp"
#include "support/hash_unit.hpp"

namespace ccmap::bmtest {
namespace {
CadreStack g_stacks[2];
alignas(8) std::uint8_t g_snapshot[kCadreSnapshotBytes];
PointXYZ g_map_points[kFramePoints];
PointXYZ g_sensor_points[kFramePoints];
}  // namespace

CadreStack& cadre_stack(int which) noexcept { return g_stacks[which == 0 ? 0 : 1]; }
std::uint8_t* snapshot_buffer() noexcept { return g_snapshot; }
PointXYZ* frame_map_points() noexcept { return g_map_points; }
PointXYZ* frame_sensor_points() noexcept { return g_sensor_points; }

void terrain_frame(int frame, float rx, float ry, std::size_t n) noexcept {
  const Pose pose = test::scenario::pose_from(rx, ry, 0.0F);
  for (std::size_t i = 0; i < n && i < kFramePoints; ++i) {
    const auto id = static_cast<std::uint32_t>(frame) * 1000003U + static_cast<std::uint32_t>(i);
    const float ahead = 0.2F + 3.5F * test::hash_unit(id, 5U);
    const float side = 3.0F * test::hash_unit(id, 6U) - 1.5F;
    const float noise = 0.002F * (test::hash_unit(id, 7U) - 0.5F);
    g_map_points[i] = test::scenario::terrain_point(pose, rx, ry, ahead, side, noise, false);
  }
}

}  // namespace ccmap::bmtest
