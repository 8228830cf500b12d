// Where ccmap_ghosts places a drop-off answer on the true terrain (tools/traverse/ghosts.hpp,
// drop_place), held to analytic cases on flat ground. A crater of radius R, depth d and rim
// height m has the bowl h(r) = -d + (d + m) (r / R)^2 inside its rim circle (tools/sim/terrain.hpp):
// it lies max(0, -h) below the ground around it, and its wall's slope is 2 (d + m) r / R^2. A
// cell is the bowl where that depth exceeds the cell's step (0.75 w), the inner wall where it
// does not but the centre is inside the rim circle and the wall is steeper than 20 deg, and
// elsewhere otherwise: open ground, the rim's outer flank, a gentle dish, a steep slope that is no
// crater are all false drop-offs.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/terrain.hpp"
#include "traverse/ghosts.hpp"

namespace sim = ccmap::sim;
namespace tr = ccmap::traverse;

namespace {

constexpr double kW = 0.04;      // the finest layer's cell (m)
constexpr double kFraction = 0.75;  // its step: 3 cm
constexpr double kPi = 3.14159265358979323846;

// The crater of the cases: centre (5, 5), R = 1 m, d = 0.3 m, m = 0.04 m.
sim::ProceduralTerrain crater_terrain() {
  sim::ProceduralTerrain t;
  t.add_crater(sim::Crater{5.0, 5.0, 2.0, 0.3, 0.04});
  return t;
}

double bowl_depth(double r) { return std::max(0.0, 0.3 - 0.34 * r * r); }
double wall_slope_deg(double r) { return std::atan(2.0 * 0.34 * r) * 180.0 / kPi; }

}  // namespace

TEST(DropPlace, TheBowlDeeperThanTheStepIsTheBowl) {
  const sim::ProceduralTerrain t = crater_terrain();
  ASSERT_GT(bowl_depth(0.05), kFraction * kW);
  EXPECT_EQ(tr::drop_place(t, 5.01, 5.01, kW, kFraction), tr::DropPlace::kBowl);
  // A ditch deeper than the step is a drop too.
  sim::ProceduralTerrain d;
  d.add_ditch(sim::Ditch{2.0, 0.0, 2.6, 3.0, 0.15});
  EXPECT_EQ(tr::drop_place(d, 2.3, 1.5, kW, kFraction), tr::DropPlace::kBowl);
}

TEST(DropPlace, TheSteepUpperWallInsideTheRimIsTheInnerWall) {
  const sim::ProceduralTerrain t = crater_terrain();
  // The cell [5.92, 5.96) x [5.00, 5.04): r from 0.92 to 0.96, centre 0.940.
  ASSERT_LT(bowl_depth(0.92), kFraction * kW);  // 1 cm deep at its inner edge: not the bowl
  ASSERT_GT(wall_slope_deg(0.92), 20.0);        // 32 deg
  EXPECT_EQ(tr::drop_place(t, 5.93, 5.01, kW, kFraction), tr::DropPlace::kInnerWall);
  // The same on the wall's other side (the cell [4.04, 4.08) x [4.96, 5.00)).
  EXPECT_EQ(tr::drop_place(t, 4.05, 4.99, kW, kFraction), tr::DropPlace::kInnerWall);
}

TEST(DropPlace, OpenGroundTheOuterFlankAGentleDishAndASlopeAreElsewhere) {
  const sim::ProceduralTerrain t = crater_terrain();
  EXPECT_EQ(tr::drop_place(t, 1.02, 1.02, kW, kFraction), tr::DropPlace::kElsewhere);  // open ground
  // The rim's outer flank, r = 1.1 (the falloff m (r^-3 - 2.5^-3) / (1 - 2.5^-3): 5 deg).
  EXPECT_EQ(tr::drop_place(t, 6.11, 5.01, kW, kFraction), tr::DropPlace::kElsewhere);
  // A dish: R = 2, d = 0.05, m = 0.01; at r = 0.81 it is 1.1 cm deep and 2.8 deg steep.
  sim::ProceduralTerrain dish;
  dish.add_crater(sim::Crater{5.0, 5.0, 4.0, 0.05, 0.01});
  ASSERT_LT(0.05 - 0.06 * 0.80 * 0.80, kFraction * kW);
  EXPECT_EQ(tr::drop_place(dish, 6.61, 5.01, kW, kFraction), tr::DropPlace::kElsewhere);
  // A plane 35 deg steep with no crater: a hazard, but no drop.
  sim::TerrainParams p;
  p.slope_x = 0.7;
  const sim::ProceduralTerrain slope(p);
  ASSERT_TRUE(slope.craters().empty());
  EXPECT_EQ(tr::drop_place(slope, 3.01, 3.01, kW, kFraction), tr::DropPlace::kElsewhere);
}
