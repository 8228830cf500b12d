// The drop-off reference of the ghost experiment (tools/traverse/dropoff_truth.hpp) held to the
// analytic case it must reproduce: a flat-floored ditch with vertical walls in flat ground, seen
// along its axis from a camera at height h, a metres before its near rim (the rim ground 0).
// Similar triangles: the line of sight grazing the rim falls h (x - a) / a below it at x, and
// reaches the floor (depth D) at a (1 + D / h); so a cell [x0, x1) of the floor is hidden when
// a <= x0 and x1 <= min(a (1 + D / h), far wall), its lowest line of sight lies h (x1 - a) / a below
// the rim, and it is provably a drop of step s when x1 > a (1 + s / h).
#include <gtest/gtest.h>

#include <cmath>

#include "sim/stereo.hpp"
#include "sim/terrain.hpp"
#include "traverse/dropoff_truth.hpp"

namespace tr = ccmap::traverse;
namespace sim = ccmap::sim;

namespace {

constexpr double kH = 0.175;   // camera height above the ground (m)
constexpr double kA = 1.01;    // camera to the near rim (m); the far wall at kA + kW
constexpr double kW = 0.6;     // the ditch's width (m)

/// Feeds fans of rays along +x from (0, y, kH), every 0.2 mm of ground range, each ending where it
/// meets the ditch's terrain (computed here, not by the simulator).
void feed_fans(tr::DropoffTruth& truth, double depth) {
  for (double y : {-0.06, -0.02, 0.02, 0.06}) {
    for (int n = 0; n < 13500; ++n) {
      const double xt = 0.3 + 0.0002 * n;  // where the ray would meet z = 0
      auto z_at = [&](double x) { return kH * (1.0 - x / xt); };
      double xe = xt, ze = 0.0;  // ground before the rim or beyond the far wall
      if (xt > kA && xt <= kA + kW) {
        const double floor_x = xt * (kH + depth) / kH;
        if (floor_x <= kA + kW) {
          xe = floor_x;
          ze = -depth;
        } else {
          xe = kA + kW;  // the far wall
          ze = z_at(xe);
        }
      } else if (xt > kA + kW && z_at(kA + kW) < 0.0) {
        xe = kA + kW;
        ze = z_at(xe);
      }
      truth.add_point(xe, y);
      truth.add_ray(sim::Point3{0.0, y, kH}, sim::Point3{xe, y, ze}, 0.0);
    }
  }
}

struct Counts {
  int hidden = 0, provable = 0;
};

Counts check_against_similar_triangles(const tr::DropoffTruth& truth, double depth) {
  Counts c;
  for (int k = 0; k < truth.layer_count(); ++k) {
    const tr::DropoffTruth::Layer& l = truth.layer(k);
    for (int j = 0; j < l.nj; ++j) {
      for (int i = 0; i < l.ni; ++i) {
        const double x0 = truth.centre_x(k, i) - 0.5 * l.width_m, x1 = x0 + l.width_m;
        const bool hidden = x0 >= kA && x1 <= std::min(kA * (1.0 + depth / kH), kA + kW);
        const bool provable = hidden && x1 > kA * (1.0 + l.step_m / kH);
        EXPECT_EQ(truth.hidden(k, i, j), hidden) << "layer " << k << " cell [" << x0 << ", " << x1 << ")";
        EXPECT_EQ(truth.provable(k, i, j), provable) << "layer " << k << " cell [" << x0 << ", " << x1 << ")";
        if (hidden) {
          // The lowest line of sight over a hidden cell is the one grazing the rim, at the cell's far edge.
          EXPECT_NEAR(truth.below(k, i, j), -kH * (x1 - kA) / kA, 1e-4) << "layer " << k << " cell at " << x0;
        }
        c.hidden += hidden ? 1 : 0;
        c.provable += provable ? 1 : 0;
      }
    }
  }
  return c;
}

tr::DropoffTruth make_truth() {
  // 4 cm (step 3 cm) and 8 cm (step 6 cm) cells over the ditch and 0.5 m either side.
  return tr::DropoffTruth(0.5, 2.1, -0.08, 0.08, {0.04, 0.08}, {0.03, 0.06});
}

}  // namespace

TEST(DropoffTruth, DeepDitchProvesTheCellsBeyondTheStepsSimilarTriangle) {
  tr::DropoffTruth truth = make_truth();
  feed_fans(truth, 0.30);
  const Counts c = check_against_similar_triangles(truth, 0.30);
  // By hand: the whole floor (1.01 - 1.61 m) is hidden; 4 cm cells [1.04, 1.60): 14 per row, of
  // them x1 > 1.01 (1 + 0.03 / 0.175) = 1.183 m: 11; 8 cm cells [1.04, 1.60): 7 per row, x1 > 1.356 m: 4.
  EXPECT_EQ(c.hidden, 4 * 14 + 2 * 7);
  EXPECT_EQ(c.provable, 4 * 11 + 2 * 4);
}

TEST(DropoffTruth, DitchShallowerThanTheStepProvesNothing) {
  tr::DropoffTruth truth = make_truth();
  feed_fans(truth, 0.02);
  const Counts c = check_against_similar_triangles(truth, 0.02);
  // The shadow ends at 1.01 (1 + 0.02 / 0.175) = 1.125 m: 4 cm cells [1.04, 1.12) and the 8 cm cell
  // [1.04, 1.12) hidden, none proved.
  EXPECT_EQ(c.hidden, 4 * 2 + 2 * 1);
  EXPECT_EQ(c.provable, 0);
}

TEST(DropoffTruth, SimulatedCameraFramesAgreeWithTheSimilarTriangles) {
  // The same ditch in the simulator's raster, seen by its CADRE camera from 1.01 m: the frame's
  // true points and lines of sight (add_frame: the pixel's depth, the camera's mounting) prove only
  // cells beyond a (1 + s / h) of the hidden floor, and most of them (pixels are discrete).
  sim::TerrainParams p;
  p.area = sim::Rect{-2.0, -2.0, 4.0, 2.0};
  sim::ProceduralTerrain terrain(p);
  terrain.add_ditch(sim::Ditch{kA, -2.0, kA + kW, 2.0, 0.30});
  const sim::HeightRaster raster = sim::rasterize(terrain, sim::Rect{-2.0, -2.0, 4.0, 2.0}, 0.01);
  sim::StereoParams sp;
  sp.pixel_stride = 2;
  const sim::StereoCamera camera(sp);
  ASSERT_NEAR(terrain.height(0.0, 0.0), 0.0, 1e-12);
  const sim::StereoFrame frame = camera.capture(raster, sim::Pose2{0.0, 0.0, 0.0}, 1);
  tr::DropoffTruth truth(0.5, 2.1, -0.3, 0.3, {0.04}, {0.03});
  tr::add_frame(truth, camera, frame, raster, kA, 0.0, [](double) { return 0.0; });
  const tr::DropoffTruth::Layer& l = truth.layer(0);
  int provable = 0, expected = 0;
  for (int j = 0; j < l.nj; ++j) {
    for (int i = 0; i < l.ni; ++i) {
      const double x0 = truth.centre_x(0, i) - 0.02, x1 = x0 + 0.04;
      const bool floor = x0 >= kA && x1 <= kA + kW;
      const bool beyond = x1 > kA * (1.0 + 0.03 / kH);
      if (truth.provable(0, i, j)) {
        ++provable;
        EXPECT_TRUE(floor && x1 > kA * (1.0 + 0.03 / kH) - 0.01) << "cell [" << x0 << ", " << x1 << ") proved";
      }
      if (floor && beyond) ++expected;
      if (x1 <= kA - 0.02) {
        // Before the rim the ground pixels lie less than 2 cm apart: every cell is seen.
        EXPECT_FALSE(truth.hidden(0, i, j)) << "a cell of the ground before the ditch is hidden: [" << x0 << ", " << x1 << ")";
      }
    }
  }
  EXPECT_EQ(expected, 14 * 11);  // rows [-0.28, 0.28), cells [1.16, 1.20) .. [1.56, 1.60)
  EXPECT_GE(provable, expected * 9 / 10);
}
