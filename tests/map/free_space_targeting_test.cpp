// Which lines of sight the sampled walk spends its rays on (map/visibility/free_space.hpp,
// FreeSpace::choose and score_candidate; docs/design.md, "Free space from lines of sight"): the
// presets take detail::kRayCandidates candidates per walked ray and walk those whose line of sight
// crosses hidden ground or a cell with evidence against it; WithRayCandidates<CadreConfig, 1> is
// the even subsample alone, the reference here. The scenes are analytic
// (tests/support/ray_scene.hpp: a camera cast in double precision); what is expected of a map
// comes from the scenes' geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "support/ray_scene.hpp"

namespace {

using ccmap::CadreConfig;
using ccmap::CellClass;
using ccmap::FrameCounters;
using ccmap::Stack;
using ccmap::StackParams;
using ccmap::Status;
using ccmap::test::AnalyticScene;
using ccmap::test::SceneBox;
using ccmap::test::SceneCamera;
using ccmap::test::SceneDitch;
using ccmap::test::SceneFrame;
using Targeted = Stack<CadreConfig>;
using EvenSubsample = Stack<ccmap::WithRayCandidates<CadreConfig, 1>>;

static_assert(ccmap::detail::FreeSpace<CadreConfig>::kCandidates == ccmap::detail::kRayCandidates,
              "the presets take the library's candidates per ray");
static_assert(ccmap::detail::FreeSpace<ccmap::WithRayCandidates<CadreConfig, 1>>::kCandidates == 1U,
              "the reference walks the even subsample");

StackParams params(float rays, float gate_sigma = 3.0F) {
  StackParams p = ccmap::default_stack_params(0.04F);
  p.free_space_rays = rays;
  p.outlier_gate_sigma = gate_sigma;
  return p;
}

template <typename Map>
std::unique_ptr<Map> make_map(float rays, float gate_sigma = 3.0F) {
  auto m = std::make_unique<Map>();
  EXPECT_EQ(m->init(params(rays, gate_sigma)), Status::kOk);
  return m;
}

template <typename Map>
FrameCounters fold(Map& map, const SceneFrame& f) {
  FrameCounters c{};
  EXPECT_EQ(map.move_to(f.origin.x, f.origin.y), Status::kOk);
  EXPECT_EQ(map.update_frame(f.points.data(), f.points.size(), f.origin, &c), Status::kOk);
  return c;
}

/// Query points (2 cm raster) of the rectangle whose class satisfies `pred`.
template <typename Map, typename Pred>
int count_where(const Map& map, double x0, double y0, double x1, double y1, Pred pred) {
  int n = 0;
  for (double x = x0; x <= x1; x += 0.02) {
    for (double y = y0; y <= y1; y += 0.02) {
      n += pred(map.query(static_cast<float>(x), static_cast<float>(y)).cell_class) ? 1 : 0;
    }
  }
  return n;
}

/// Query points (2 cm raster) of the rectangle that answer `cls`.
template <typename Map>
int count_class(const Map& map, double x0, double y0, double x1, double y1, CellClass cls) {
  return count_where(map, x0, y0, x1, y1, [cls](CellClass c) { return c == cls; });
}

/// Two stacks' snapshots (every layer's cells, every free-space record, the stage's frame count)
/// bitwise equal.
template <typename CA, typename CB>
bool same_maps(const Stack<CA>& a, const Stack<CB>& b) {
  std::vector<std::uint8_t> sa(ccmap::snapshot_size<CA>());
  std::vector<std::uint8_t> sb(ccmap::snapshot_size<CB>());
  std::size_t na = 0;
  std::size_t nb = 0;
  EXPECT_EQ(ccmap::save_snapshot(a, sa.data(), sa.size(), &na), Status::kOk);
  EXPECT_EQ(ccmap::save_snapshot(b, sb.data(), sb.size(), &nb), Status::kOk);
  return na == nb && std::memcmp(sa.data(), sb.data(), na) == 0;
}

bool same_counters(const FrameCounters& a, const FrameCounters& b) {
  return a.free_rays == b.free_rays && a.free_rays_refused == b.free_rays_refused &&
         a.cleared_cells == b.cleared_cells && a.drop_cells == b.drop_cells;
}

/// A 30 cm deep ditch, 0.6 m wide, its near rim 0.9 m ahead of a camera 17.5 cm high.
AnalyticScene ditch_scene() {
  AnalyticScene s;
  s.ditches.push_back(SceneDitch{0.9, -1.5, 1.5, 1.5, 0.30});
  return s;
}

TEST(FreeSpaceTargeting, TheRaysOverADitchProveItsNearEdgeWhereTheEvenSubsampleDoesNot) {
  // 128 rays (half the presets' default) over the scenes' 120 x 90 camera (10,800 points): the even
  // subsample walks one point in 85, few of them beyond the rim. The lines of sight to the far
  // wall and beyond pass over the ditch's hidden inside: the targeted walk spends its rays there.
  const SceneDitch d = ditch_scene().ditches[0];
  auto targeted = make_map<Targeted>(128.0F);
  auto even = make_map<EvenSubsample>(128.0F);
  for (int k = 0; k < 3; ++k) {
    SceneCamera cam;
    cam.seed = static_cast<std::uint64_t>(k) + 1U;
    const SceneFrame f = ccmap::test::render_scene(ditch_scene(), cam);
    const FrameCounters a = fold(*targeted, f);
    const FrameCounters b = fold(*even, f);
    EXPECT_EQ(a.free_rays + a.free_rays_refused, b.free_rays + b.free_rays_refused)
        << "the targeted walk has the even subsample's slots";
    EXPECT_GE(a.free_rays, b.free_rays);
  }
  // (Measured: 60 drop-off answers on the near edge, 432 inside, against 26 and 202.)
  // Geometry: the near edge of the ditch inside the rover's swath (|y| <= 0.3 m, the 4 cm strip
  // behind the rim) and the ditch as a whole; nothing before the rim or beyond the far wall.
  const int edge_targeted = count_class(*targeted, d.x0 + 0.01, -0.3, d.x0 + 0.05, 0.3, CellClass::kDropOff);
  const int edge_even = count_class(*even, d.x0 + 0.01, -0.3, d.x0 + 0.05, 0.3, CellClass::kDropOff);
  const int inside_targeted = count_class(*targeted, d.x0 + 0.01, -0.3, d.x1 - 0.01, 0.3, CellClass::kDropOff);
  const int inside_even = count_class(*even, d.x0 + 0.01, -0.3, d.x1 - 0.01, 0.3, CellClass::kDropOff);
  EXPECT_GT(edge_targeted, edge_even) << "the targeted walk proved no more of the ditch's near rim than the even subsample";
  EXPECT_GT(inside_targeted, inside_even) << "the targeted walk proved no more of the ditch than the even subsample";
  EXPECT_EQ(count_class(*targeted, -1.0, -1.4, d.x0 - 0.02, 1.4, CellClass::kDropOff), 0)
      << "a drop-off before the rim";
  EXPECT_EQ(count_class(*targeted, d.x1 + 0.02, -1.4, 4.0, 1.4, CellClass::kDropOff), 0)
      << "a drop-off beyond the far wall";
}

TEST(FreeSpaceTargeting, AFarGhostIsClearedWhereTheEvenSubsampleLeavesIt) {
  // A 30 cm x 30 cm x 25 cm box 1.8 m ahead, seen for 4 frames, then gone (the paper's update:
  // the ground seen where it stood only dilutes its cells). At 256 rays over 10,800 points about
  // one line of sight a frame passes through its place, fewer than the evidence rule's two; once
  // one has contradicted a cell, the targeted walk aims the next frame's candidates there
  // (measured: the box's obstacle answers gone after 7 empty frames; the even subsample keeps
  // all of them after 10).
  AnalyticScene with_box;
  with_box.boxes.push_back(SceneBox{1.8, -0.15, 2.1, 0.15, 0.25});
  const AnalyticScene empty;
  auto targeted = make_map<Targeted>(256.0F, 0.0F);
  auto even = make_map<EvenSubsample>(256.0F, 0.0F);
  SceneCamera cam;
  for (int k = 0; k < 4; ++k) {
    cam.seed = static_cast<std::uint64_t>(k) + 1U;
    const SceneFrame f = ccmap::test::render_scene(with_box, cam);
    fold(*targeted, f);
    fold(*even, f);
  }
  ASSERT_GT(count_class(*targeted, 1.78, -0.17, 2.12, 0.17, CellClass::kObstacle), 0) << "the box is an obstacle";
  ASSERT_GT(count_class(*even, 1.78, -0.17, 2.12, 0.17, CellClass::kObstacle), 0);
  for (int k = 0; k < 10; ++k) {
    cam.seed = static_cast<std::uint64_t>(k) + 100U;
    const SceneFrame f = ccmap::test::render_scene(empty, cam);
    fold(*targeted, f);
    fold(*even, f);
  }
  EXPECT_EQ(count_class(*targeted, 1.78, -0.17, 2.12, 0.17, CellClass::kObstacle), 0)
      << "the box's ghost outlived 10 frames of targeted lines of sight";
  EXPECT_GT(count_class(*even, 1.78, -0.17, 2.12, 0.17, CellClass::kObstacle), 0)
      << "the even subsample cleared the far ghost too: this scene does not test the targeting";
}

/// Query points (2 cm raster) of the rectangle that answer a lethal class (ccmap::is_lethal).
template <typename Map>
int count_lethal(const Map& map, double x0, double y0, double x1, double y1) {
  return count_where(map, x0, y0, x1, y1, [](CellClass c) { return ccmap::is_lethal(c); });
}

TEST(FreeSpaceTargeting, LinesOfSightEndingJustBehindAGoneBoxAreWalkedFirstFromItsFirstEmptyFrame) {
  // A 30 cm x 30 cm x 25 cm box 1.6 m ahead of a camera 0.5 m up (the default gate), seen for 4
  // frames, then gone. In the first empty frame no record holds evidence yet, so only a
  // candidate's own cells can say that its line of sight passes below a known surface: the
  // cells one and two before its point, whose top stands above the line there by the clear
  // margin while its point lies more than that margin below the cell's mean (score_candidate).
  // The lines of sight that end on the ground the box uncovered do; walked first, they bring the
  // evidence rule's two rays a frame from the first empty frame on. Measured (2 cm query raster,
  // 324 points in the box's place, 270 a hazard while it stood): none after 5 empty frames
  // (without that level, as the targeting was before it: 72 after 5 and 6, none after 7); the
  // even subsample keeps 144 after 8.
  AnalyticScene with_box;
  with_box.boxes.push_back(SceneBox{1.6, -0.15, 1.9, 0.15, 0.25});
  const AnalyticScene empty;
  auto targeted = make_map<Targeted>(256.0F);
  auto even = make_map<EvenSubsample>(256.0F);
  SceneCamera cam;
  cam.height_m = 0.5;
  for (int k = 0; k < 4; ++k) {
    cam.seed = static_cast<std::uint64_t>(k) + 1U;
    const SceneFrame f = ccmap::test::render_scene(with_box, cam);
    fold(*targeted, f);
    fold(*even, f);
  }
  const int seen = count_lethal(*targeted, 1.58, -0.17, 1.92, 0.17);
  ASSERT_GT(seen, 200) << "the box is a hazard (of 324 query points)";
  ASSERT_EQ(count_lethal(*even, 1.58, -0.17, 1.92, 0.17), seen) << "both maps saw the box alike";
  for (int k = 0; k < 5; ++k) {
    cam.seed = static_cast<std::uint64_t>(k) + 100U;
    const SceneFrame f = ccmap::test::render_scene(empty, cam);
    fold(*targeted, f);
    fold(*even, f);
  }
  EXPECT_EQ(count_lethal(*targeted, 1.58, -0.17, 1.92, 0.17), 0)
      << "the box's ghost outlived 5 empty frames of targeted lines of sight";
  EXPECT_GE(count_lethal(*even, 1.58, -0.17, 1.92, 0.17), 100)
      << "the even subsample cleared the box too: this scene does not test the targeting";
  // Nothing else is a hazard: the ground around the box's place, the place included.
  EXPECT_EQ(count_lethal(*targeted, 1.2, -0.6, 2.3, 0.6), 0);
}

TEST(FreeSpaceTargeting, AFrameWithNothingHiddenWalksTheEvenSubsampleAndTheChoiceIsDeterministic) {
  // Flat open ground, no noise, a camera of 360 rows. The first frame, from 0.5 m back, observes
  // the ground before the second frame's nearest points; the second sees up to 2 m, densely: no candidate's line of
  // sight crosses an unobserved cell and no cell holds evidence, so every candidate scores alike
  // and the targeted walk casts exactly the even subsample's rays (the maps bitwise equal).
  const AnalyticScene flat;
  auto targeted = make_map<Targeted>(0.0F);
  auto again = make_map<Targeted>(0.0F);
  auto even = make_map<EvenSubsample>(0.0F);
  SceneCamera back;
  back.x = -0.5;
  back.rows = 360;
  back.far_m = 2.5;
  SceneCamera here;
  here.rows = 360;
  here.far_m = 2.0;
  // The first frame without free space (the stacks alike), the second with it.
  for (int k = 0; k < 2; ++k) {
    const SceneFrame f = ccmap::test::render_scene(flat, k == 0 ? back : here);
    const FrameCounters a = fold(*targeted, f);
    const FrameCounters b = fold(*even, f);
    const FrameCounters c = fold(*again, f);
    EXPECT_TRUE(same_counters(a, c)) << "the same frames chose different lines of sight";
    EXPECT_TRUE(same_counters(a, b)) << "a frame with nothing hidden did not walk the even subsample";
    if (k == 0) {
      EXPECT_EQ(a.free_rays, 0U);
      ASSERT_EQ(targeted->set_params(params(128.0F), nullptr), Status::kOk);
      ASSERT_EQ(even->set_params(params(128.0F), nullptr), Status::kOk);
      ASSERT_EQ(again->set_params(params(128.0F), nullptr), Status::kOk);
    } else {
      EXPECT_GT(a.free_rays, 100U);
    }
  }
  EXPECT_TRUE(same_maps(*targeted, *again)) << "the choice of lines of sight is not deterministic";
  EXPECT_TRUE(same_maps(*targeted, *even)) << "with nothing hidden the targeted walk differs from the even subsample";
  // The same frames over a ditch: the choice differs (else the equality above tests nothing),
  // and stays deterministic.
  auto ditch_a = make_map<Targeted>(0.0F);
  auto ditch_b = make_map<Targeted>(0.0F);
  auto ditch_even = make_map<EvenSubsample>(0.0F);
  for (int k = 0; k < 2; ++k) {
    const SceneFrame f = ccmap::test::render_scene(ditch_scene(), k == 0 ? back : here);
    fold(*ditch_a, f);
    fold(*ditch_b, f);
    fold(*ditch_even, f);
    if (k == 0) {
      ASSERT_EQ(ditch_a->set_params(params(128.0F), nullptr), Status::kOk);
      ASSERT_EQ(ditch_b->set_params(params(128.0F), nullptr), Status::kOk);
      ASSERT_EQ(ditch_even->set_params(params(128.0F), nullptr), Status::kOk);
    }
  }
  EXPECT_TRUE(same_maps(*ditch_a, *ditch_b));
  EXPECT_FALSE(same_maps(*ditch_a, *ditch_even)) << "the ditch's hidden inside drew no line of sight";
}

}  // namespace
