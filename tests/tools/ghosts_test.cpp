// CI check of the free-space experiment (tools/traverse/ghosts.cpp) at its --quick size,
// in-process: with free space, rover 1's ghosts of its team mates shrink and no real cell is lost;
// a ditch and a crater are drop-offs at their rims before the rover reaches them, where the map
// without free space shows only their far side; rock shadows are no drop-offs.
#include <gtest/gtest.h>

#include "traverse/ghosts.hpp"

namespace tr = ccmap::traverse;

TEST(GhostsExperiment, FreeSpaceClearsGhostsMarksDropOffsAtTheRimAndLosesNothing) {
  const tr::GhostResult r = tr::run_ghosts(tr::GhostConfig::quick());
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_LT(r.team.after[0].end_area_m2, 0.6 * r.team.before[0].end_area_m2)
      << "rover 1's ghosts of its team mates did not shrink";
  EXPECT_LT(r.team.after[0].area_frames_m2, r.team.before[0].area_frames_m2);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(r.team.before[k].cleared_cells, 0U) << "the map without free space cleared cells";
    EXPECT_EQ(r.team.after[k].lost_ground, 0U) << "rover " << k + 1 << " lost real ground to clearing";
    EXPECT_EQ(r.team.after[k].lost_rock, 0U) << "rover " << k + 1 << " lost a rock to clearing";
    EXPECT_EQ(r.team.after[k].cleared_ghost, r.team.after[k].cleared_cells) << "rover " << k + 1;
  }
  ASSERT_EQ(r.drops.size(), 3U);
  for (const tr::DropCase& d : r.drops) {
    EXPECT_LT(d.first_drop_range_m[0], 0.0) << d.name << ": a drop-off without free space";
    EXPECT_LT(d.rim_hazard_range_m[0], 0.0) << d.name << ": a hazard at the rim without free space";
    EXPECT_GT(d.first_drop_range_m[1], 0.0) << d.name << ": no drop-off with free space";
    EXPECT_GT(d.rim_hazard_range_m[1], 0.5) << d.name << ": the hazard at the rim came too late (or never)";
    EXPECT_EQ(d.rim_hazard_class[1], "drop") << d.name;
  }
  EXPECT_EQ(r.shadows.drop_near_rocks_m2[1], 0.0) << "a rock's shadow became a drop-off";
  EXPECT_EQ(r.shadows.drop_open_m2[1], 0.0) << "open ground became a drop-off";
}
