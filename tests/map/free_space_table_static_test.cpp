// The viewshed table of every line of sight (map/visibility/sight_table.hpp) on a scene that never
// changes: the flight cycle's static frame (tests/support/flight_cycle.hpp, cycle_frame(0): a
// full 850 x 650 CADRE frame, swell and rocks of 3-20 cm) fed again and again from the same pose
// to Stack<WithEveryLineOfSight<CadreConfig>>, the table fed by one point in 8 and by every point.
// The reference is the scene itself: nothing in it moves, so every cell the first frame observed
// must still hold its points after every later frame (no cell emptied), and the layers must be
// bitwise those of the same frames folded by the stack with free space switched off (the table
// changes only its own records; a cell it empties is the only way the two can differ).
// The frame places every pixel's point on the terrain without occlusion (cadre_frames.hpp), so
// lines of sight to the ground behind a rock pass through the rock's cells: each such cell is
// contradicted by the table frame after frame, and only the frame's points that land on the
// rock's surface (its confirmation, docs/design.md 12) keep it.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "ccmap/map/visibility/sight_table.hpp"
#include "support/flight_cycle.hpp"
#include "support/map_state.hpp"

namespace {

using Table = ccmap::Stack<ccmap::WithEveryLineOfSight<ccmap::CadreConfig>>;

/// Frames fed (the evidence rule empties a cell after free_space_clear_frames = 3 of them: eight
/// give it two full rounds and more).
constexpr int kFrames = 8;

struct Observed {
  std::uint32_t cells = 0U;  ///< cells of every layer the first frame observed
  std::uint32_t lost = 0U;   ///< of them, empty after a later frame (summed over the frames)
};

/// True if cell `slot` of `layer` holds points (weight > 0).
bool holds(const Table& map, int layer, std::size_t slot) {
  if (layer == 0) {
    return map.fine_layer().storage()[slot].weight > 0.0F;
  }
  return map.ccm_layer(layer - 1).storage()[slot].weight > 0.0F;
}
std::size_t cells_of(const Table& map, int layer) {
  return layer == 0 ? map.fine_layer().cell_count() : map.ccm_layer(layer - 1).cell_count();
}

void check_static_scene(float free_space_rays, bool sensor_frame) {
  const ccmap::test::CadreFrame frame = ccmap::test::cycle_frame(0);
  const ccmap::test::CyclePose pose = ccmap::test::cycle_pose(0);
  ccmap::StackParams p = ccmap::default_stack_params(0.04F);
  p.free_space_rays = free_space_rays;
  auto table = std::make_unique<Table>();
  ASSERT_EQ(table->init(p), ccmap::Status::kOk);
  p.free_space_rays = 0.0F;
  auto off = std::make_unique<Table>();
  ASSERT_EQ(off->init(p), ccmap::Status::kOk);
  std::uint32_t cleared = 0U;
  std::uint32_t fed_frames = 0U;  // frames in which the table took lines of sight (most of the frame's 8th or all)
  Observed seen;
  std::unique_ptr<bool[]> first;
  for (int k = 0; k < kFrames; ++k) {
    ccmap::FrameCounters c{}, d{};
    for (auto* map : {table.get(), off.get()}) {
      ASSERT_EQ(map->move_to(pose.x, pose.y), ccmap::Status::kOk);
      ccmap::FrameCounters* counters = map == table.get() ? &c : &d;
      if (sensor_frame) {
        ASSERT_EQ(map->update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, counters),
                  ccmap::Status::kOk);
      } else {
        ASSERT_EQ(map->update_frame(frame.map_points.data(), frame.map_points.size(), frame.sensor_origin, counters),
                  ccmap::Status::kOk);
      }
    }
    cleared += c.cleared_cells;
    fed_frames += c.free_rays > 50000U ? 1U : 0U;
    // The first frame's observed cells, layer by layer in storage order.
    std::size_t at = 0U;
    if (k == 0) {
      std::size_t total = 0U;
      for (int layer = 0; layer < Table::kLayerCount; ++layer) {
        total += cells_of(*table, layer);
      }
      first = std::make_unique<bool[]>(total);
    }
    for (int layer = 0; layer < Table::kLayerCount; ++layer) {
      for (std::size_t s = 0; s < cells_of(*table, layer); ++s, ++at) {
        if (k == 0) {
          first[at] = holds(*table, layer, s);
          seen.cells += first[at] ? 1U : 0U;
        } else if (first[at] && !holds(*table, layer, s)) {
          ++seen.lost;
          ADD_FAILURE() << "frame " << k + 1 << ": the table emptied cell " << s << " of layer " << layer
                        << ", observed since the first frame of a scene that never changes";
        }
      }
    }
  }
  EXPECT_EQ(fed_frames, static_cast<std::uint32_t>(kFrames)) << "the table saw too few lines of sight to test anything";
  EXPECT_GT(seen.cells, 800U) << "the frame observed too few cells to test anything";
  EXPECT_EQ(cleared, 0U) << "cells emptied on a static scene (counted by the stage)";
  EXPECT_EQ(seen.lost, 0U);
  EXPECT_TRUE(ccmap::test::raw_map_state(*table) == ccmap::test::raw_map_state(*off)) << "the table changed a cell of a static scene";
}

TEST(FreeSpaceTableStatic, OneInEightLosesNoCellOfAStaticSceneSensorFrame) {
  check_static_scene(ccmap::detail::free_space_table_rays(8), true);
}

TEST(FreeSpaceTableStatic, OneInEightLosesNoCellOfAStaticSceneMapFrame) {
  check_static_scene(ccmap::detail::free_space_table_rays(8), false);
}

TEST(FreeSpaceTableStatic, EveryPointLosesNoCellOfAStaticSceneSensorFrame) {
  check_static_scene(ccmap::detail::kFreeSpaceEveryRay, true);
}

}  // namespace
