// CI check of the real laser scan experiment (tools/experiments/lidar.cpp) on the 10 x 10 m Lone
// Star crop: with the outlier cut, CCM's sub-cell height predicts held-out points better than
// the piece-wise constant maps at the same resolution (the paper's cell: RMS and median at every
// resolution; the full cell: median and 95th percentile at every resolution, RMS at 32 cm, see
// docs/evaluation.md for why not at 8 and 16 cm); with every point (raw), the +10 m returns
// dominate the RMS and CCM is worse there, but its median error stays lower. Skipped when the
// shared data is absent (a user's clone).
#include <gtest/gtest.h>

#include <string>

#include "experiments/lidar.hpp"
#include "sim/data_dir.hpp"

namespace ex = ccmap::experiments;

namespace {

bool load(ex::LidarRun* run, std::string* why, bool paper_cell = false) {
  const std::string path = ex::lidar_crop_path(ccmap::sim::resolve_data_dir());
  ex::LidarConfig cfg = ex::LidarConfig::quick();
  cfg.paper_cell = paper_cell;
  return ex::run_lidar(cfg, path, "crop", "", "", run, why);
}

}  // namespace

TEST(ExperimentsLidar, PaperCellBeatsConstantMapsAtHeldOutPointsAfterOutlierCut) {
  ex::LidarRun run;
  std::string why;
  if (!load(&run, &why, /*paper_cell=*/true)) GTEST_SKIP() << why;
  ASSERT_EQ(run.variants.size(), 3U);
  const ex::LidarVariant& cut = run.variants[1];
  ASSERT_EQ(cut.name, "cut");
  EXPECT_GT(cut.removed_outliers, 100U) << "the crop has returns up to +10 m";
  for (double w : {0.08, 0.16, 0.32}) {
    const ex::LidarMethodStats* ccm = cut.find("CCM", w, "common");
    const ex::LidarMethodStats* omg = cut.find("OMG", w, "common");
    const ex::LidarMethodStats* kal = cut.find("Kalman", w, "common");
    ASSERT_TRUE(ccm && omg && kal);
    EXPECT_GT(ccm->evaluated, 1000U) << "too few held-out points in known cells at " << w << " m";
    EXPECT_EQ(ccm->evaluated, omg->evaluated) << "the common set differs";
    EXPECT_LT(ccm->rms_m, omg->rms_m) << "at " << w * 100 << " cm: CCM RMS " << ccm->rms_m * 1000 << " mm vs OMG "
                                      << omg->rms_m * 1000 << " mm";
    EXPECT_LE(ccm->median_abs_m, omg->median_abs_m) << "at " << w * 100 << " cm";
    EXPECT_NEAR(kal->rms_m, omg->rms_m, 1e-3 * omg->rms_m) << "Kalman and OMG heights are both the running mean";
  }
}

TEST(ExperimentsLidar, FullCellBeatsConstantMapsInMedianAndTailAfterOutlierCut) {
  ex::LidarRun run;
  std::string why;
  if (!load(&run, &why)) GTEST_SKIP() << why;
  ASSERT_EQ(run.variants.size(), 3U);
  const ex::LidarVariant& cut = run.variants[1];
  for (double w : {0.08, 0.16, 0.32}) {
    const ex::LidarMethodStats* ccm = cut.find("CCM", w, "common");
    const ex::LidarMethodStats* omg = cut.find("OMG", w, "common");
    ASSERT_TRUE(ccm && omg);
    // The smaller-eigenvalue coverage keeps fewer of the sparse 8 cm cells (2.5 points each).
    EXPECT_GT(ccm->evaluated, 500U) << "too few held-out points in known cells at " << w << " m";
    EXPECT_EQ(ccm->evaluated, omg->evaluated) << "the common set differs";
    EXPECT_LT(ccm->median_abs_m, omg->median_abs_m) << "at " << w * 100 << " cm";
    EXPECT_LT(ccm->p95_abs_m, omg->p95_abs_m) << "at " << w * 100 << " cm";
  }
  const ex::LidarMethodStats* ccm = cut.find("CCM", 0.32, "common");
  const ex::LidarMethodStats* omg = cut.find("OMG", 0.32, "common");
  EXPECT_LT(ccm->rms_m, 0.9 * omg->rms_m) << "at 32 cm: CCM RMS " << ccm->rms_m * 1000 << " mm vs OMG "
                                          << omg->rms_m * 1000 << " mm";
}

TEST(ExperimentsLidar, RawOutliersDominateTheRmsButNotTheMedian) {
  ex::LidarRun run;
  std::string why;
  if (!load(&run, &why)) GTEST_SKIP() << why;
  const ex::LidarVariant& raw = run.variants[0];
  ASSERT_EQ(raw.name, "raw");
  for (double w : {0.16, 0.32}) {
    const ex::LidarMethodStats* ccm = raw.find("CCM", w, "common");
    const ex::LidarMethodStats* omg = raw.find("OMG", w, "common");
    ASSERT_TRUE(ccm && omg);
    EXPECT_GT(omg->max_abs_m, 5.0) << "the raw held-out set keeps the +10 m returns";
    EXPECT_GT(ccm->rms_m, 0.1) << "raw RMS is dominated by outliers";
    EXPECT_LT(ccm->median_abs_m, omg->median_abs_m) << "at " << w * 100 << " cm";
  }
}

TEST(ExperimentsLidar, TheOutlierGateDoesNotWorsenTheStacksAtHeldOutGround) {
  // The library's stacks from the raw cloud, predicting the held-out ground: the gate removes
  // isolated returns (the 95th percentile of the error falls at 16 and 32 cm) but admits the
  // steam and vegetation that stand as surfaces of their own (docs/evaluation.md, "Outliers"):
  // the RMS, which those dominate, stays within 2 % of the gate-off figure.
  ex::LidarRun run;
  std::string why;
  if (!load(&run, &why)) GTEST_SKIP() << why;
  const ex::LidarVariant& stack = run.variants[2];
  ASSERT_EQ(stack.name, "stack");
  for (double w : {0.16, 0.32}) {
    const ex::LidarMethodStats* off = stack.find("CCM, gate off", w, "common");
    const ex::LidarMethodStats* on = stack.find("CCM, gate on", w, "common");
    ASSERT_TRUE(off && on);
    EXPECT_GT(on->evaluated, 1000U);
    EXPECT_LT(on->p95_abs_m, off->p95_abs_m) << "at " << w * 100 << " cm";
    EXPECT_LT(on->rms_m, 1.02 * off->rms_m) << "at " << w * 100 << " cm";
  }
}
