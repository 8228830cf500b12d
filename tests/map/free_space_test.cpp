// Free space from lines of sight (map/visibility/free_space.hpp; docs/design.md, "Free space from
// lines of sight") on analytic scenes seen by a camera cast in double precision
// (tests/support/ray_scene.hpp: points only where a line of sight reaches): a box that vanishes,
// open ground with stereo noise, a ditch seen from 17.5 cm, the shadows of rocks, a rock's flank
// beside the lines of sight, refused input, the records through moves and snapshots, the run-time
// and compile-time switches. The expected answers come from the scenes' geometry, not from the
// library.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "support/ray_scene.hpp"

namespace {

using ccmap::CadreConfig;
using ccmap::CellClass;
using ccmap::FrameCounters;
using ccmap::PointXYZ;
using ccmap::QueryResult;
using ccmap::Stack;
using ccmap::StackParams;
using ccmap::Status;
using ccmap::test::AnalyticScene;
using ccmap::test::SceneBox;
using ccmap::test::SceneCamera;
using ccmap::test::SceneDitch;
using ccmap::test::SceneFrame;
// tests/map/free_space_every_ray_test.cpp runs the same scenes on the stack that casts every line
// of sight (map/visibility/sight_table.hpp): it defines these three before including this file.
#ifndef CCMAP_FREE_SPACE_CONFIG
#define CCMAP_FREE_SPACE_CONFIG CadreConfig
#define CCMAP_FREE_SPACE_RAYS 1024.0F
#define FreeSpaceScenes FreeSpace
#endif
using Map = Stack<CCMAP_FREE_SPACE_CONFIG>;

#ifndef CCMAP_FREE_SPACE_CAMERA_SCALE
#define CCMAP_FREE_SPACE_CAMERA_SCALE 1
#endif
/// The scenes' camera (120 x 90 pixels, times CCMAP_FREE_SPACE_CAMERA_SCALE each way).
SceneCamera scene_camera() {
  SceneCamera cam;
  cam.cols *= CCMAP_FREE_SPACE_CAMERA_SCALE;
  cam.rows *= CCMAP_FREE_SPACE_CAMERA_SCALE;
  return cam;
}

StackParams params(bool free_space, bool gate) {
  StackParams p = ccmap::default_stack_params(0.04F);
  p.free_space_rays = free_space ? CCMAP_FREE_SPACE_RAYS : 0.0F;
  p.outlier_gate_sigma = gate ? 3.0F : 0.0F;
  return p;
}

std::unique_ptr<Map> make_map(const StackParams& p) {
  auto m = std::make_unique<Map>();
  EXPECT_EQ(m->init(p), Status::kOk);
  return m;
}

FrameCounters fold(Map& map, const SceneFrame& f) {
  FrameCounters c{};
  EXPECT_EQ(map.move_to(f.origin.x, f.origin.y), Status::kOk);
  EXPECT_EQ(map.update_frame(f.points.data(), f.points.size(), f.origin, &c), Status::kOk);
  return c;
}

/// True if some query point of the rectangle (2 cm raster) answers `cls`.
bool any_class(const Map& map, double x0, double y0, double x1, double y1, CellClass cls) {
  for (double x = x0; x <= x1; x += 0.02) {
    for (double y = y0; y <= y1; y += 0.02) {
      if (map.query(static_cast<float>(x), static_cast<float>(y)).cell_class == cls) {
        return true;
      }
    }
  }
  return false;
}

/// Every layer's raw cells bitwise equal.
bool same_layers(const Map& a, const Map& b) {
  for (int c = 0; c < Map::kCcmLayerCount; ++c) {
    const auto& ga = a.ccm_layer(c);
    const auto& gb = b.ccm_layer(c);
    if (std::memcmp(ga.storage(), gb.storage(), ga.cell_count() * sizeof(*ga.storage())) != 0) {
      return false;
    }
  }
  const auto& fa = a.fine_layer();
  const auto& fb = b.fine_layer();
  return std::memcmp(fa.storage(), fb.storage(), fa.cell_count() * sizeof(*fa.storage())) == 0;
}

// ---- ghosts ----

TEST(FreeSpaceScenes, AVanishedBoxIsClearedWithinAFewFramesWhileThePaperUpdateKeepsIt) {
  // A 30 cm x 30 cm x 15 cm box 1.4 m ahead, seen for 4 frames, then gone. With the outlier gate
  // off (the paper's update) the ground seen where it stood only dilutes its cells; the lines of
  // sight through the empty space clear them.
  AnalyticScene with_box;
  with_box.boxes.push_back(SceneBox{1.40, -0.15, 1.70, 0.15, 0.15});
  const AnalyticScene empty;
  auto on = make_map(params(true, false));
  auto off = make_map(params(false, false));
  SceneCamera cam = scene_camera();
  for (int k = 0; k < 4; ++k) {
    cam.seed = static_cast<std::uint64_t>(k) + 1U;
    const SceneFrame f = ccmap::test::render_scene(with_box, cam);
    fold(*on, f);
    fold(*off, f);
  }
  ASSERT_TRUE(any_class(*on, 1.38, -0.17, 1.72, 0.17, CellClass::kObstacle)) << "the box is mapped as an obstacle";
  std::uint32_t cleared = 0;
  int frames_to_clear = -1;
  for (int k = 0; k < 8; ++k) {
    cam.seed = static_cast<std::uint64_t>(k) + 100U;
    const SceneFrame f = ccmap::test::render_scene(empty, cam);
    cleared += fold(*on, f).cleared_cells;
    fold(*off, f);
    if (frames_to_clear < 0 && !any_class(*on, 1.38, -0.17, 1.72, 0.17, CellClass::kObstacle)) {
      frames_to_clear = k + 1;
    }
  }
  EXPECT_GT(cleared, 0U) << "lines of sight through the empty box cleared no cell";
  EXPECT_GE(frames_to_clear, 1);
  EXPECT_LE(frames_to_clear, 5) << "the box's ghost outlived 5 frames of lines of sight through it";
  EXPECT_TRUE(any_class(*off, 1.38, -0.17, 1.72, 0.17, CellClass::kObstacle))
      << "without free space the paper's update should still show the ghost after 8 frames "
         "(else this scene does not test clearing)";
}

TEST(FreeSpaceScenes, RaysOverTheLowSideOfACellHoldingARockFlankClearNothingAndTheFlankGoneIsCleared) {
  // A rock's flank beside the lines of sight: a staircase of 2 cm treads rising 3 cm each (a 56
  // deg flank, 24 cm tall, above the camera's 17.5 cm), 60 cm deep, 1.5 m ahead, its foot y0 to
  // the left of the view's axis. The 8 cm cells at its foot hold ground and flank: their top
  // (mean + sqrt(3) sigma_zz) stands near the flank's upper treads, while lines of sight to the
  // ground behind pass over their low side, above the terrain (the camera's rays are exact, so
  // every line of sight clears the terrain by construction) but below that top by more than the
  // clear margin. The scene never changes, so every cell emptied is real terrain lost (the
  // analytic truth: none). Two feet of the flank (2 and 10 cm left of the axis), each its own map.
  // Then the flank vanishes and the camera looks at its place: the lines of sight pass through
  // where it stood, and cells of it are emptied after the evidence rule's frames
  // (free_space_clear_frames), not before.
  const StackParams p = params(true, true);
  const auto clear_frames = static_cast<int>(p.free_space_clear_frames);
  for (const double y0 : {0.02, 0.10}) {
    AnalyticScene flank;
    for (int k = 0; k < 8; ++k) {
      flank.boxes.push_back(SceneBox{1.5, y0 + 0.02 * k, 2.1, y0 + 0.5, 0.03 * (k + 1)});
    }
    auto map = make_map(p);
    SceneCamera cam = scene_camera();
    std::uint32_t cleared = 0;
    for (int k = 0; k < 12; ++k) {
      cam.seed = static_cast<std::uint64_t>(k) + 1U;
      cleared += fold(*map, ccmap::test::render_scene(flank, cam)).cleared_cells;
    }
    EXPECT_EQ(cleared, 0U) << "lines of sight over the low side of cells holding a rock flank (foot " << y0
                           << " m left) emptied real terrain";
    ASSERT_TRUE(any_class(*map, 1.5, y0, 2.1, y0 + 0.5, CellClass::kObstacle)) << "the flank is mapped as an obstacle";
    // The flank gone: nothing emptied before clear_frames frames of lines of sight through it,
    // cells of it emptied at that frame.
    const AnalyticScene empty;
    std::uint32_t ghost_cleared = 0;
    for (int k = 0; k < clear_frames; ++k) {
      cam.seed = static_cast<std::uint64_t>(k) + 100U;
      ghost_cleared += fold(*map, ccmap::test::render_scene(empty, cam)).cleared_cells;
      if (k + 1 < clear_frames) {
        EXPECT_EQ(ghost_cleared, 0U) << "the vanished flank was emptied after " << k + 1
                                     << " frames, faster than the evidence rule allows";
      }
    }
    EXPECT_GT(ghost_cleared, 0U) << "lines of sight through the vanished flank (foot " << y0 << " m left) emptied no cell of it in "
                                 << clear_frames << " frames";
  }
}

TEST(FreeSpaceScenes, RaysFromBehindTheSensorOrFromRefusedPointsClearNothing) {
  // A box behind the camera (mapped looking back), then frames whose every point would cast a
  // line of sight through it: points behind the sensor (sensor frame, view axis +x), NaN, out of
  // range, too noisy for every layer. None may clear a cell; the control (no view axis) does.
  AnalyticScene scene;
  scene.boxes.push_back(SceneBox{-1.70, -0.15, -1.40, 0.15, 0.15});
  SceneCamera back;
  back.heading_cos = -1.0;
  StackParams p = params(true, false);
  p.sensor_view_axis = {1.0F, 0.0F, 0.0F};
  auto guarded = make_map(p);
  auto control = make_map(params(true, false));
  for (int k = 0; k < 3; ++k) {
    back.seed = static_cast<std::uint64_t>(k) + 1U;
    const SceneFrame f = ccmap::test::render_scene(scene, back);
    fold(*guarded, f);
    fold(*control, f);
  }
  ASSERT_TRUE(any_class(*guarded, -1.72, -0.17, -1.38, 0.17, CellClass::kObstacle));
  // Sensor frame = map frame at the origin (identity rotation); ground points 1.9 to 2.3 m behind,
  // their lines of sight through the box's former place (two rows, 0.2 m apart across it).
  ccmap::Pose pose{};
  pose.rotation[0][0] = pose.rotation[1][1] = pose.rotation[2][2] = 1.0F;
  pose.translation = PointXYZ{0.0F, 0.0F, 0.175F};
  std::vector<PointXYZ> behind;
  for (int i = 0; i < 2000; ++i) {
    const float along = static_cast<float>(i % 1000);
    const float row = i < 1000 ? -0.1F : 0.1F;
    behind.push_back(PointXYZ{-1.9F - 0.0004F * along, row + 0.0002F * along - 0.1F, -0.175F});
  }
  std::uint32_t control_cleared = 0;
  for (int k = 0; k < 6; ++k) {
    FrameCounters c{};
    ASSERT_EQ(guarded->update_frame_sensor(behind.data(), behind.size(), pose, &c), Status::kOk);
    EXPECT_EQ(c.free_rays, 0U) << "a point behind the sensor cast a line of sight";
    EXPECT_GT(c.free_rays_refused, 0U) << "the refused lines of sight are counted";
    EXPECT_EQ(c.cleared_cells, 0U) << "a point behind the sensor cleared a cell";
    FrameCounters cc{};
    ASSERT_EQ(control->update_frame_sensor(behind.data(), behind.size(), pose, &cc), Status::kOk);
    control_cleared += cc.cleared_cells;
  }
  EXPECT_GT(control_cleared, 0U) << "the same rays without a view axis clear the box (else the test proves nothing)";
  // Refused points: NaN, beyond 1e5 m, beyond every layer's range (30 m behind the box).
  auto before = make_map(params(true, false));
  for (int k = 0; k < 3; ++k) {
    back.seed = static_cast<std::uint64_t>(k) + 1U;
    fold(*before, ccmap::test::render_scene(scene, back));
  }
  std::vector<PointXYZ> bad;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < 600; ++i) {
    bad.push_back(PointXYZ{nan, 0.0F, 0.0F});
    bad.push_back(PointXYZ{-2.0e5F, 0.0F, 0.0F});
    bad.push_back(PointXYZ{-30.0F, 0.001F * static_cast<float>(i), -25.0F});
  }
  const PointXYZ origin{0.0F, 0.0F, 0.175F};
  for (int k = 0; k < 6; ++k) {
    FrameCounters c{};
    ASSERT_EQ(before->update_frame(bad.data(), bad.size(), origin, &c), Status::kOk);
    EXPECT_EQ(c.free_rays, 0U) << "a refused point cast a line of sight";
    EXPECT_EQ(c.cleared_cells, 0U);
    EXPECT_EQ(c.drop_cells, 0U);
  }
  EXPECT_TRUE(any_class(*before, -1.72, -0.17, -1.38, 0.17, CellClass::kObstacle)) << "refused points erased the box";
  // A non-finite sensor origin refuses the frame: nothing changes, nothing is counted.
  auto reference = make_map(params(true, false));
  for (int k = 0; k < 3; ++k) {
    back.seed = static_cast<std::uint64_t>(k) + 1U;
    fold(*reference, ccmap::test::render_scene(scene, back));
  }
  SceneFrame good = ccmap::test::render_scene(AnalyticScene{}, back);
  FrameCounters c{};
  EXPECT_EQ(reference->update_frame(good.points.data(), good.points.size(), PointXYZ{nan, 0.0F, 0.175F}, &c),
            Status::kNonFiniteInput);
  EXPECT_EQ(c.free_rays + c.free_rays_refused + c.cleared_cells + c.drop_cells, 0U);
  auto twin = make_map(params(true, false));
  for (int k = 0; k < 3; ++k) {
    back.seed = static_cast<std::uint64_t>(k) + 1U;
    fold(*twin, ccmap::test::render_scene(scene, back));
  }
  EXPECT_TRUE(same_layers(*reference, *twin)) << "a refused frame changed the map";
}

// ---- open ground: nothing lost, nothing invented ----

TEST(FreeSpaceScenes, OpenGroundWithUnclippedStereoNoiseLosesNoCellAndShowsNoDrop) {
  // Flat and 11-degree ground, driven over for 12 frames with the CADRE noise sigma = r^2/300
  // (Gaussian, unclipped): grazing rays end within 5 m. The map must equal, bitwise, the map of
  // the same frames without free space (no cell cleared), and no query answers a drop-off.
  for (const double slope : {0.0, 0.2}) {
    AnalyticScene scene;
    scene.slope_x = slope;
    auto on = make_map(params(true, true));
    auto off = make_map(params(false, true));
    std::uint32_t cleared = 0;
    std::uint32_t drops = 0;
    for (int k = 0; k < 12; ++k) {
      SceneCamera cam = scene_camera();
      cam.x = 0.2 * k;
      cam.noise_per_range_sq = 1.0 / 300.0;
      cam.seed = static_cast<std::uint64_t>(k) + 7U;
      const SceneFrame f = ccmap::test::render_scene(scene, cam);
      const FrameCounters c = fold(*on, f);
      fold(*off, f);
      cleared += c.cleared_cells;
      drops += c.drop_cells;
      EXPECT_GT(c.free_rays, 500U);
    }
    EXPECT_EQ(cleared, 0U) << "open ground of slope " << slope << " lost cells to clearing";
    EXPECT_EQ(drops, 0U) << "open ground of slope " << slope << " got drop-offs";
    EXPECT_TRUE(same_layers(*on, *off)) << "free space changed a cell of open ground (slope " << slope << ")";
    EXPECT_FALSE(any_class(*on, -8.0, -8.0, 10.0, 8.0, CellClass::kDropOff));
  }
}

// ---- drop-offs ----

/// The ditch scene: 1 m wide, 40 cm deep, its near rim 1.2 m ahead of a camera 17.5 cm high.
AnalyticScene ditch_scene() {
  AnalyticScene s;
  s.ditches.push_back(SceneDitch{1.2, -1.5, 2.2, 1.5, 0.40});
  return s;
}

std::unique_ptr<Map> map_of_ditch() {
  auto m = make_map(params(true, true));
  for (int k = 0; k < 3; ++k) {
    SceneCamera cam = scene_camera();
    cam.seed = static_cast<std::uint64_t>(k) + 1U;
    fold(*m, ccmap::test::render_scene(ditch_scene(), cam));
  }
  return m;
}

TEST(FreeSpaceScenes, ADitchSeenFrom17cmIsADropOffWhereTheRaysProveItAndNowhereElse) {
  const auto map = map_of_ditch();
  const SceneDitch d = ditch_scene().ditches[0];
  // Geometry: the line of sight grazing the rim at 1.2 m falls 0.175 / 1.2 m per metre, so it
  // passes more than the 8 cm layer's step (6 cm) below the rim from 1.2 + 0.06 / 0.146 = 1.61 m
  // on, and reaches the far wall (2.2 m) before the floor: the floor is never seen.
  EXPECT_TRUE(any_class(*map, 1.70, -0.3, 2.10, 0.3, CellClass::kDropOff))
      << "no drop-off where every line of sight passes more than a step below the rim";
  int wrong = 0;
  int drops = 0;
  for (double x = -1.0; x <= 4.0; x += 0.02) {
    for (double y = -2.0; y <= 2.0; y += 0.02) {
      const QueryResult q = map->query(static_cast<float>(x), static_cast<float>(y));
      if (q.cell_class != CellClass::kDropOff) {
        continue;
      }
      ++drops;
      EXPECT_EQ(q.status, Status::kOk);
      EXPECT_EQ(q.weight, 0.0F) << "a drop-off answer holds no points";
      // The answering cell must overlap the ditch (a true drop inside it).
      const double w = q.cell_width_m;
      // A query point on a cell boundary (the 2 cm raster meets every 8 cm boundary) may be
      // answered by either neighbour (float index rounding: grid::index_of_position): the
      // cell may start at either side's floor.
      bool overlaps = false;
      for (const double ex : {-1e-4, 1e-4}) {
        for (const double ey : {-1e-4, 1e-4}) {
          const double cx0 = std::floor((x + ex) / w) * w;
          const double cy0 = std::floor((y + ey) / w) * w;
          overlaps = overlaps || (cx0 < d.x1 && cx0 + w > d.x0 && cy0 < d.y1 && cy0 + w > d.y0);
        }
      }
      wrong += overlaps ? 0 : 1;
      // Its height is an upper bound of the hidden floor, above the true floor and no higher than
      // the rays that cross the rim to the far wall's top pass over the rim: 0.175 (1 - 1.2 / 2.2)
      // = 8 cm (near the rim a cell is a drop-off as part of the run of unobserved cells a ray
      // proved one in further on, so its own bound may lie within a step of the rim).
      EXPECT_LT(q.height_m, 0.175F * (1.0F - 1.2F / 2.2F) + 0.005F) << "at (" << x << ", " << y << ")";
      EXPECT_GT(q.height_m, -d.depth) << "the bound is above the true floor";
    }
  }
  EXPECT_GT(drops, 0);
  EXPECT_EQ(wrong, 0) << "drop-off answers in cells that do not overlap the ditch";
  // Before the rim nothing is a drop; right behind it, the run of unobserved cells a ray proved a
  // drop in further on is one (the planner must stop at the rim, not 40 cm inside the ditch).
  EXPECT_FALSE(any_class(*map, -1.0, -1.4, 1.18, 1.4, CellClass::kDropOff));
#ifndef CCMAP_FREE_SPACE_NO_RUN_MARKING  // every line of sight: not done (docs/design.md 12)
  EXPECT_TRUE(any_class(*map, 1.21, -0.3, 1.30, 0.3, CellClass::kDropOff)) << "the ditch's near edge is no drop-off";
#endif
}

TEST(FreeSpaceScenes, PlannerQueriesTreatADropOffAsLethal) {
  const auto map = map_of_ditch();
  // The body astride the ditch: a drop-off part.
  const ccmap::FootprintResult f = ccmap::query_footprint(*map, ccmap::Footprint{1.9F, 0.0F, 1.0F, 0.0F, 0.6F, 0.4F});
  ASSERT_EQ(f.status, Status::kOk);
  EXPECT_EQ(f.worst_class, CellClass::kDropOff);
  EXPECT_EQ(ccmap::footprint_class(f, ccmap::kDefaultMaxUnknownShare), CellClass::kDropOff);
  // A path into the ditch meets its first hazard there.
  const ccmap::PathPoint route[2] = {{0.3F, 0.0F}, {2.5F, 0.0F}};
  const ccmap::PathResult p = ccmap::query_path(*map, route, 2, ccmap::PathSweep{0.6F, 0.4F, 0.05F, 1.0F});
  ASSERT_EQ(p.status, Status::kOk);
  EXPECT_TRUE(p.hazard_found) << "a path over a drop-off found no hazard";
  EXPECT_EQ(p.hazard.worst_class, CellClass::kDropOff);
  // The cost raster: lethal pixels inside the ditch, none before the rim.
  constexpr std::uint32_t kSide = 100;
  std::vector<std::uint8_t> cost(kSide * kSide);
  ccmap::CostmapStats stats{};
  ASSERT_EQ(ccmap::fill_costmap(*map, ccmap::CostmapSpec{1.5F, 0.0F, 0.04F, kSide, 0.0F}, cost.data(), cost.size(), &stats),
            Status::kOk);
  auto pixel = [&](float x, float y) {
    const auto ix = static_cast<std::uint32_t>((x - (1.5F - 2.0F)) / 0.04F);
    const auto iy = static_cast<std::uint32_t>((y - (0.0F - 2.0F)) / 0.04F);
    return cost[iy * kSide + ix];
  };
  EXPECT_EQ(pixel(1.9F, 0.02F), ccmap::kCostLethal) << "a drop-off pixel is not lethal";
  EXPECT_NE(pixel(0.8F, 0.02F), ccmap::kCostLethal) << "flat ground before the ditch is lethal";
}

TEST(FreeSpaceScenes, TheShadowOfARockIsUnknownNotADropOff) {
  // Rocks 15 cm (below the camera) and 30 cm (above it) on flat ground: the ground behind them
  // is hidden by something standing above the ground in front, not by a drop.
  for (const double h : {0.15, 0.30}) {
    AnalyticScene scene;
    scene.boxes.push_back(SceneBox{1.0, -0.1, 1.2, 0.1, h});
    scene.boxes.push_back(SceneBox{2.0, 0.6, 2.4, 1.0, h});
    auto map = make_map(params(true, true));
    std::uint32_t drops = 0;
    for (int k = 0; k < 4; ++k) {
      SceneCamera cam = scene_camera();
      cam.seed = static_cast<std::uint64_t>(k) + 1U;
      drops += fold(*map, ccmap::test::render_scene(scene, cam)).drop_cells;
    }
    EXPECT_EQ(drops, 0U) << "the shadow of a " << h << " m rock was marked a drop-off";
    EXPECT_FALSE(any_class(*map, -1.0, -2.0, 6.0, 2.0, CellClass::kDropOff));
    // The shadow right behind the first rock stays unobserved in the finest layer.
    EXPECT_EQ(map->query_layer(0, 1.25F, 0.0F).status, Status::kUnknown) << "the shadow of a " << h << " m rock";
  }
}

// ---- state: moves, snapshots, switches ----

TEST(FreeSpaceScenes, DropOffsSurviveASnapshotAndLeaveWithTheirWindow) {
  const auto map = map_of_ditch();
  ASSERT_TRUE(any_class(*map, 1.7, -0.3, 2.1, 0.3, CellClass::kDropOff));
  std::vector<std::uint8_t> buffer(ccmap::snapshot_size<CadreConfig>());
  std::size_t written = 0;
  ASSERT_EQ(ccmap::save_snapshot(*map, buffer.data(), buffer.size(), &written), Status::kOk);
  auto loaded = std::make_unique<Map>();
  ASSERT_EQ(ccmap::load_snapshot(*loaded, buffer.data(), written), Status::kOk);
  for (double x = 1.0; x <= 2.4; x += 0.04) {
    for (double y = -0.5; y <= 0.5; y += 0.04) {
      const QueryResult a = map->query(static_cast<float>(x), static_cast<float>(y));
      const QueryResult b = loaded->query(static_cast<float>(x), static_cast<float>(y));
      ASSERT_EQ(a.cell_class, b.cell_class) << "a loaded map answers another class at (" << x << ", " << y << ")";
      ASSERT_EQ(a.height_m, b.height_m);
    }
  }
  // A snapshot of a stack without free space is another shape.
  auto plain = std::make_unique<Stack<ccmap::WithFreeSpace<CadreConfig, false>>>();
  EXPECT_EQ(ccmap::load_snapshot(*plain, buffer.data(), written), Status::kVersionMismatch);
  // Away beyond every window and back: the records left with the cells.
  ASSERT_EQ(loaded->move_to(100.0F, 0.0F), Status::kOk);
  ASSERT_EQ(loaded->move_to(0.0F, 0.0F), Status::kOk);
  EXPECT_FALSE(any_class(*loaded, 1.0, -0.5, 2.4, 0.5, CellClass::kDropOff)) << "a drop-off outlived its window";
}

TEST(FreeSpaceScenes, ExportListsDropOffCellsWithTheirBound) {
  const auto map = map_of_ditch();
  int found = 0;
  for (int layer = 0; layer < Map::kLayerCount; ++layer) {
    std::vector<ccmap::CellRecord> records(Map::layer_capacity(layer));
    std::size_t written = 0;
    ASSERT_EQ(map->export_layer(layer, records.data(), records.size(), &written), Status::kOk);
    for (std::size_t i = 0; i < written; ++i) {
      if (records[i].cell_class == CellClass::kDropOff) {
        ++found;
        EXPECT_EQ(records[i].weight, 0.0F);
        EXPECT_LT(records[i].height_m, 0.0F) << "the bound of a drop-off lies below the rim";
      }
    }
  }
  EXPECT_GT(found, 0) << "no drop-off cell exported";
}

TEST(FreeSpaceScenes, SwitchedOffAtRunTimeItIsTheStackCompiledWithoutIt) {
  AnalyticScene with_box;
  with_box.boxes.push_back(SceneBox{1.40, -0.15, 1.70, 0.15, 0.15});
  auto off = make_map(params(false, false));
  auto compiled_out = std::make_unique<Stack<ccmap::WithFreeSpace<CadreConfig, false>>>();
  ASSERT_EQ(compiled_out->init(params(true, false)), Status::kOk) << "its free_space_rays is ignored";
  for (int k = 0; k < 6; ++k) {
    SceneCamera cam = scene_camera();
    cam.seed = static_cast<std::uint64_t>(k) + 1U;
    const SceneFrame f = ccmap::test::render_scene(k < 3 ? with_box : AnalyticScene{}, cam);
    FrameCounters a{}, b{};
    ASSERT_EQ(off->move_to(f.origin.x, f.origin.y), Status::kOk);
    ASSERT_EQ(compiled_out->move_to(f.origin.x, f.origin.y), Status::kOk);
    ASSERT_EQ(off->update_frame(f.points.data(), f.points.size(), f.origin, &a), Status::kOk);
    ASSERT_EQ(compiled_out->update_frame(f.points.data(), f.points.size(), f.origin, &b), Status::kOk);
    EXPECT_EQ(a.free_rays + a.cleared_cells + a.drop_cells + a.free_rays_refused, 0U);
    EXPECT_EQ(b.free_rays + b.cleared_cells + b.drop_cells + b.free_rays_refused, 0U);
  }
  for (int c = 0; c < Map::kCcmLayerCount; ++c) {
    const auto& ga = off->ccm_layer(c);
    const auto& gb = compiled_out->ccm_layer(c);
    EXPECT_EQ(std::memcmp(ga.storage(), gb.storage(), ga.cell_count() * sizeof(*ga.storage())), 0) << "CCM layer " << c;
  }
  EXPECT_EQ(std::memcmp(off->fine_layer().storage(), compiled_out->fine_layer().storage(),
                        off->fine_layer().cell_count() * sizeof(*off->fine_layer().storage())),
            0);
  // 4 bytes per cell of every layer (14,336 for CADRE) and the ray scratch are not carried.
  EXPECT_GE(sizeof(Map) - sizeof(Stack<ccmap::WithFreeSpace<CadreConfig, false>>), 14336U * 4U);
}

}  // namespace
