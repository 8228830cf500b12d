// CI check of the team experiment (tools/traverse/team.cpp) at its --quick size, in-process: two
// CADRE rovers on different paths exchanging deltas every 3 frames. Every delta merges, and each
// rover's final map knows more of the ground with the team than alone, without losing what it
// found itself; coarse layers only carry the same knowledge in fewer bytes.
#include <gtest/gtest.h>

#include "traverse/team.hpp"

namespace tr = ccmap::traverse;

TEST(TeamExperiment, DeltasMergeAndEveryRoverKnowsMoreWithTheTeam) {
  const tr::TeamResult all = tr::run_team(tr::TeamConfig::quick());
  ASSERT_TRUE(all.ok()) << all.error;
  ASSERT_EQ(all.rovers.size(), 2U);
  for (const tr::RoverResult& r : all.rovers) {
    EXPECT_GT(r.frames, 10) << "rover " << r.id;
    EXPECT_EQ(r.deltas_refused, 0U) << "rover " << r.id << " refused a team mate's delta";
    EXPECT_GT(r.deltas_sent, 5U);
    EXPECT_GT(r.cells_merged, 100U) << "rover " << r.id << " merged almost nothing";
    EXPECT_GT(r.team.known(), 1.2 * r.alone.known()) << "rover " << r.id;
    // Hazards it found alone it still finds (merged cells can only add evidence here).
    EXPECT_GE(r.team.truth_hazard_known - r.team.missed, 0.9 * (r.alone.truth_hazard_known - r.alone.missed))
        << "rover " << r.id;
    EXPECT_LT(r.team.false_share(), 0.05) << "rover " << r.id;
  }
  tr::TeamConfig coarse = tr::TeamConfig::quick();
  coarse.finest_layer = 2;  // 16 cm and coarser
  const tr::TeamResult some = tr::run_team(coarse);
  ASSERT_TRUE(some.ok()) << some.error;
  for (std::size_t i = 0; i < some.rovers.size(); ++i) {
    EXPECT_LT(some.rovers[i].bytes_sent, all.rovers[i].bytes_sent / 2) << "rover " << some.rovers[i].id;
    EXPECT_GT(some.rovers[i].team.known(), 0.95 * all.rovers[i].team.known()) << "rover " << some.rovers[i].id;
  }
}
