// The reference of issue 31 item 2 (tools/traverse/ghost_truth.hpp) against cases worked by hand:
// flat ground at z = 0, the camera 0.175 m above it, a 25 cm box (present, or gone while the map
// still holds its top), a 16 cm cell's clear margin 0.12 m (0.75 x the width).
//
// A line of sight from height h = 0.175 to the ground at horizontal distance d stands at
// h (1 - x / d) at distance x. Over a cell [1.00, 1.16] m ahead whose top is 0.25 m it passes
// clearly below (under 0.25 - 0.12 = 0.13 m at its entry, its highest point there) when
// 1 - 1 / d < 0.13 / 0.175, d < 3.889 m, and it reaches ground beyond the cell when d > 1.16 m.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sim/stereo.hpp"
#include "sim/terrain.hpp"
#include "traverse/ghost_truth.hpp"

namespace tr = ccmap::traverse;
namespace sim = ccmap::sim;

namespace {

constexpr double kCamHeight = 0.175;

/// Flat ground over [0, 10] m x [0, 10] m at 1 cm, optionally with a 25 cm box over
/// x in [3.0, 3.3], y in [4.8, 5.2].
sim::HeightRaster ground(bool box) {
  sim::HeightRaster r(0.0, 0.0, 0.01, 1001, 1001, 0.0F);
  if (box) {
    for (int j = 480; j <= 520; ++j) {
      for (int i = 300; i <= 330; ++i) r.at(i, j) = 0.25F;
    }
  }
  r.build_blocks();
  return r;
}

/// The lines of sight of one pixel column of the default camera (stride 4) at (2, 5), heading +x.
std::vector<tr::SightLine> column_lines(const sim::HeightRaster& raster, int column, bool whole_frame = false) {
  sim::StereoParams p;
  p.pixel_stride = 4;
  const sim::StereoCamera camera(p);
  const sim::Pose2 pose{2.0, 5.0, 0.0};
  sim::DepthImage depth = camera.render_depth(raster, pose);
  if (!whole_frame) {
    for (int r = 0; r < depth.rows; ++r) {
      for (int c = 0; c < depth.cols; ++c) {
        if (c != column) depth.depth_m[static_cast<std::size_t>(r * depth.cols + c)] = NAN;
      }
    }
  }
  return tr::sight_lines(camera, depth, camera.camera_position(raster, pose), pose.yaw);
}

// Column 106 of the stride-4 image: pixel centre u = 424.5, 0.5 px left of the principal point,
// so its lines stay within 3 mm of y = 5 over 3.6 m: inside the cells' 16 cm. Its rows r have
// yn = (4 r + 0.5 - 325) / 600 and meet the ground at d = 0.175 / tan(25 deg + atan(yn)):
// r = 19: 4.003 m (0.1313 m at the entry: not below 0.13), r = 20: 3.540 m, ..., r = 36: 1.206 m,
// r = 37: 1.156 m (inside the cell). Rows 20..36: 17 lines.
constexpr int kCentreColumn = 106;
constexpr int kLinesBelowByHand = 17;

const tr::TruthCell kBoxCell{3.0, 4.92, 0.16, 0.25, 0.12};     // at the box, its top
const tr::TruthCell kShadowCell{3.4, 4.92, 0.16, 0.25, 0.12};  // behind the box, a ghost top

}  // namespace

TEST(GhostTruth, ExplicitLinesOverAGoneBoxAreBelowItExactlyWhereTheHandCalculationSays) {
  // Lines to the ground at d = 0.5, 0.75, ..., 5.0 m along y = 0; the cell [1.0, 1.16] x [-0.08, 0.08].
  std::vector<tr::SightLine> lines;
  int expected = 0;
  for (int k = 0; k <= 18; ++k) {
    const double d = 0.5 + 0.25 * k;
    lines.push_back(tr::SightLine{0.0, 0.0, kCamHeight, d, 0.0, 0.0});
    expected += (d > 1.16 && d < kCamHeight / (kCamHeight - 0.13)) ? 1 : 0;  // 1.25 .. 3.75
  }
  ASSERT_EQ(expected, 11);
  const tr::TruthCell cell{1.0, -0.08, 0.16, 0.25, 0.12};
  EXPECT_EQ(tr::lines_clearly_below(cell, lines), 11);
  // The same lines never pass clearly below true ground's surface, nor a cell they do not cross.
  EXPECT_EQ(tr::lines_clearly_below(tr::TruthCell{1.0, -0.08, 0.16, 0.01, 0.12}, lines), 0);
  EXPECT_EQ(tr::lines_clearly_below(tr::TruthCell{1.0, 0.10, 0.16, 0.25, 0.12}, lines), 0);
  // A line that ends in the cell or before it reaches no ground beyond it.
  EXPECT_FALSE(tr::passes_clearly_below(cell, tr::SightLine{0.0, 0.0, kCamHeight, 1.1, 0.0, 0.0}));
  EXPECT_FALSE(tr::passes_clearly_below(cell, tr::SightLine{0.0, 0.0, kCamHeight, 0.9, 0.0, 0.0}));
}

TEST(GhostTruth, ACameraColumnPassesBelowAGoneBoxInTheRowsCountedByHandAndNeverBelowAPresentOne) {
  const sim::HeightRaster flat = ground(false);
  const sim::HeightRaster with_box = ground(true);
  const std::vector<tr::SightLine> gone = column_lines(flat, kCentreColumn);
  const std::vector<tr::SightLine> present = column_lines(with_box, kCentreColumn);
  ASSERT_FALSE(gone.empty());
  ASSERT_FALSE(present.empty());
  EXPECT_EQ(tr::lines_clearly_below(kBoxCell, gone), kLinesBelowByHand);
  // The box there: its lines end on its face (not beyond the cell) or pass over its top.
  EXPECT_EQ(tr::lines_clearly_below(kBoxCell, present), 0);
  // Behind it: a line reaching ground past x = 3.56 crossed the box's top (0.25 m) on the way
  // from 0.175 m, so it still rises there: never below 0.13 m. Its shadow is not seen.
  EXPECT_EQ(tr::lines_clearly_below(kShadowCell, present), 0);
  // With the box gone the shadow cell is seen as well (entry 1.4 m: d < 0.175 x 1.4 / 0.045).
  EXPECT_GT(tr::lines_clearly_below(kShadowCell, gone), 0);
}

TEST(GhostTruth, EveryPixelOfTheFramePassesBelowNoCellOfTrueGround) {
  // The real side: a true line of sight lies above the true terrain, so no cell whose top is the
  // ground (plus 2 cm: less than the 4 cm cell's 3 cm margin above it) is passed clearly below.
  const sim::HeightRaster with_box = ground(true);
  const std::vector<tr::SightLine> lines = column_lines(with_box, 0, true);
  ASSERT_GT(lines.size(), 10000U);
  int below = 0;
  for (int i = 0; i < 95; ++i) {
    for (int j = 0; j < 100; ++j) {
      const double x = 2.2 + 0.04 * i, y = 3.0 + 0.04 * j;
      // The cells wholly on the box (i 20..26, j 45..54) hold its top, the others the ground.
      const bool on_box = i >= 20 && i <= 26 && j >= 45 && j <= 54;
      const double top = on_box ? 0.25 : 0.02;
      below += tr::lines_clearly_below(tr::TruthCell{x, y, 0.04, top, 0.03}, lines);
    }
  }
  EXPECT_EQ(below, 0);
}

TEST(GhostTruth, TracksAGhostFromItsFirstSeenFrameToTheFrameTheMapEmptiesIt) {
  // A team mate's box stood at frame 0 and left; the map holds its top in one 16 cm cell
  // (index (19, 31) of 0.16 m: [3.04, 3.20] x [4.96, 5.12]) for frames 1..3 and empties it after
  // frame 3's update. The column's lines pass below it every frame: first seen at frame 1,
  // hypot(1.12, 0.04) m from the camera (cell centre (3.12, 5.04), camera (2.0, 5.0)), delay 3
  // seen frames.
  const sim::HeightRaster flat = ground(false);
  const auto box_at = [](double x, double y, int f) { return f == 0 && x >= 3.0 && x <= 3.3 && y >= 4.8 && y <= 5.2; };
  tr::GhostTruth truth(flat, 0.75, 2, [](double, double, double) { return false; }, box_at, box_at);
  const std::vector<tr::SightLine> lines = column_lines(flat, kCentreColumn);
  const tr::MapCellView ghost{2, 19, 31, 0.16, 0.25};
  const tr::MapCellView ground_cell{2, 25, 31, 0.16, 0.01};
  for (int f = 1; f <= 4; ++f) {
    std::vector<tr::MapCellView> cells{ground_cell};
    if (f <= 3) cells.push_back(ghost);
    truth.before_update(f, cells, lines, 2.0, 5.0);
    if (f == 3) cells.pop_back();
    truth.after_update(f, cells);
  }
  const tr::GhostTruthResult r = truth.result();
  ASSERT_EQ(r.tracks.size(), 1U) << "the ground cell's top is not above the ground by its margin: not judged";
  const tr::TruthTrack& t = r.tracks[0];
  EXPECT_TRUE(t.ghost);
  EXPECT_EQ(t.first_frame, 1);
  EXPECT_EQ(t.first_seen, 1);
  EXPECT_NEAR(t.seen_range_m, std::hypot(1.12, 0.04), 1e-9);
  EXPECT_EQ(t.emptied, 3);
  EXPECT_EQ(t.seen_until_emptied, 3);
  EXPECT_GE(t.max_rays, 2);
}
