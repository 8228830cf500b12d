// CI checks of the obstacle-detection (Figs. 6/7) and drift (Fig. 10) experiments at reduced
// size (--quick configurations, in-process): the outcomes the method must show even small.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "experiments/detection.hpp"
#include "experiments/drift.hpp"
#include "experiments/registration.hpp"
#include "sim/data_dir.hpp"

namespace ex = ccmap::experiments;

namespace {

const ex::DetectionRow& row(const ex::DetectionResult& r, ex::DetectionMethod m, double ratio) {
  const ex::DetectionRow* found = r.find(m, 0.08, ratio);
  EXPECT_NE(found, nullptr) << ex::detection_method_name(m) << " at " << ratio << " x cell missing";
  static const ex::DetectionRow empty{};
  return found != nullptr ? *found : empty;
}

/// A tiny run for the shard tests: one resolution, one size, short drive, sparse rays.
ex::DetectionConfig tiny_config() {
  ex::DetectionConfig c = ex::DetectionConfig::quick();
  c.size_ratios = {1.0};
  c.pixel_stride = 5;
  c.start_margin_m = 0.0;
  return c;
}

}  // namespace

// One quick campaign (8 cm cells; obstacles of 0.5, 1 and 2 cells; DetectionConfig::quick()
// trials), several outcomes: ctest runs every TEST in its own process, so they share one run.
TEST(ExperimentsDetection, QuickCampaignShowsSubCellDetectionOfCcmAndTheRoughnessFilterLimit) {
  const ex::DetectionConfig cfg = ex::DetectionConfig::quick();
  const ex::DetectionResult r = ex::run_detection(cfg);
  const ex::DetectionRow& ccm05 = row(r, ex::DetectionMethod::kCcmObstacleFirst, 0.5);
  const ex::DetectionRow& ccm1 = row(r, ex::DetectionMethod::kCcmObstacleFirst, 1.0);
  const ex::DetectionRow& ccm2 = row(r, ex::DetectionMethod::kCcmObstacleFirst, 2.0);
  const ex::DetectionRow& omg05 = row(r, ex::DetectionMethod::kOmg, 0.5);
  const ex::DetectionRow& omg1 = row(r, ex::DetectionMethod::kOmg, 1.0);
  ASSERT_EQ(ccm1.counts.trials, cfg.trials);
  {
    SCOPED_TRACE("CCM detects an obstacle of the cell size in most trials");
    EXPECT_GE(2 * ccm1.counts.detected, ccm1.counts.trials + 1)
        << "CCM marked a 1 x cell obstacle in only " << ccm1.counts.detected << " of " << ccm1.counts.trials << " trials";
    EXPECT_GT(ccm1.counts.hit, 0U) << "no obstacle cell of a 1 x cell obstacle marked in any frame";
  }
  {
    SCOPED_TRACE("the roughness filter at the same resolution misses more");
    EXPECT_LT(ccm1.missed_share(), omg1.missed_share())
        << "1 x cell: CCM leaves " << 100 * ccm1.missed_share() << " % of the known obstacle area traversable, OMG + "
        << "roughness " << 100 * omg1.missed_share() << " %";
    EXPECT_GT(omg1.missed_share(), 0.1) << "OMG + roughness should miss part of a 1 x cell obstacle";
    // Half a cell: the constant cell's mean is diluted below the 20 deg step.
    EXPECT_GT(ccm05.counts.detected, omg05.counts.detected)
        << "0.5 x cell: CCM detected " << ccm05.counts.detected << ", OMG " << omg05.counts.detected << " trials";
    EXPECT_GT(omg05.missed_share(), 0.5) << "OMG + roughness should miss most of a half-cell obstacle";
  }
  {
    SCOPED_TRACE("CCM's misses drop as the obstacle grows past ~0.75 cell");
    EXPECT_LT(ccm05.counts.detected, ccm05.counts.trials) << "a half-cell obstacle should not always be found";
    EXPECT_LE(ccm05.counts.detected, ccm1.counts.detected);
    EXPECT_EQ(ccm2.counts.detected, ccm2.counts.trials) << "a 2 x cell obstacle was not marked in every trial";
    EXPECT_LT(ccm2.missed_share(), 0.25) << "CCM misses " << 100 * ccm2.missed_share() << " % of a 2 x cell obstacle";
  }
  {
    SCOPED_TRACE("CCM's false obstacles lie next to the obstacle; the library classes detect no more");
    for (double ratio : {0.5, 1.0, 2.0}) {
      const ex::DetectionRow& c = row(r, ex::DetectionMethod::kCcmObstacleFirst, ratio);
      EXPECT_LE(c.counts.fn_far, c.counts.correct / 1000U)
          << "CCM marked " << c.counts.fn_far << " cell-frames of open lunar terrain as obstacle at " << ratio << " x cell";
      EXPECT_LE(row(r, ex::DetectionMethod::kCcm, ratio).counts.hit, c.counts.hit);
    }
  }
}

TEST(ExperimentsDetection, ShardsMergeToTheSameTableAsOneRun) {
  ex::DetectionConfig all = tiny_config();
  all.first_seed = 7;
  all.trials = 2;
  ex::DetectionConfig first = all, second = all;
  first.trials = 1;
  second.first_seed = 8;
  second.trials = 1;
  const ex::DetectionResult whole = ex::run_detection(all);
  // Through the shard files, as --merge does.
  const std::string dir = ::testing::TempDir();
  const std::string a = dir + "/ccmap_det_shard_a.csv", b = dir + "/ccmap_det_shard_b.csv";
  std::string error;
  ASSERT_TRUE(ex::write_detection_csv(a, ex::run_detection(second), &error)) << error;
  ASSERT_TRUE(ex::write_detection_csv(b, ex::run_detection(first), &error)) << error;
  ex::DetectionResult ra, rb, merged;
  ASSERT_TRUE(ex::read_detection_csv(a, &ra, &error)) << error;
  ASSERT_TRUE(ex::read_detection_csv(b, &rb, &error)) << error;
  ASSERT_TRUE(ex::merge_detection_results({ra, rb}, &merged, &error)) << error;
  EXPECT_EQ(merged.first_seed, 7U);
  EXPECT_EQ(merged.end_seed, 9U);
  ASSERT_EQ(merged.rows.size(), whole.rows.size());
  for (std::size_t i = 0; i < whole.rows.size(); ++i) {
    EXPECT_EQ(merged.rows[i].method, whole.rows[i].method);
    EXPECT_TRUE(merged.rows[i].counts == whole.rows[i].counts) << "row " << i << " differs after merging shards";
  }
  EXPECT_EQ(ex::detection_table(merged), ex::detection_table(whole));
  EXPECT_FALSE(ex::merge_detection_results({ra, ra}, &merged, &error)) << "overlapping shards must be refused";
  std::remove(a.c_str());
  std::remove(b.c_str());
}

TEST(ExperimentsDrift, FalseObstacleShareGrowsWithDrift) {
  const ex::DriftConfig cfg = ex::DriftConfig::quick();
  const ex::DriftResult r = ex::run_drift(cfg);
  const double w = cfg.cell_widths_m.front(), wl = cfg.weight_limits.front();
  std::vector<double> shares;
  for (double d : cfg.drift_fractions) {
    const ex::DriftRow* x = r.find(w, wl, d);
    ASSERT_NE(x, nullptr);
    EXPECT_GT(x->known, 1000U) << "too little observed ground at drift " << d;
    shares.push_back(x->share());
  }
  ASSERT_EQ(shares.size(), 3U);
  EXPECT_LT(shares[0], 0.02) << "without drift CCM marks " << 100 * shares[0] << " % of a traversable wave as obstacle";
  EXPECT_LE(shares[0], shares[1]);
  EXPECT_GT(shares[2], shares[1] + 0.05) << "24 % drift should mark much more of the wave than 8 %";
  EXPECT_GT(shares[2], cfg.tolerance);
  const double crossing = ex::drift_crossing(r, w, wl, cfg.tolerance);
  EXPECT_TRUE(crossing > 0.0 && crossing < 0.24) << "crossing at " << crossing;
}

TEST(ExperimentsDrift, RegistrationKeepsTheWaveTraversableAndThePoseOnIt) {
  // The same runs with every frame registered before it is folded in: the wave fixes x (the
  // drift's direction), so the map keeps the no-drift share of false obstacles at every drift and
  // the pose estimate stays within millimetres of the truth (the plain estimate is off by the drift).
  const ex::DriftConfig cfg = ex::DriftConfig::quick();
  ASSERT_TRUE(cfg.compare_registration);
  const ex::DriftResult r = ex::run_drift(cfg);
  const double w = cfg.cell_widths_m.front(), wl = cfg.weight_limits.front();
  for (double d : cfg.drift_fractions) {
    const ex::DriftRow* plain = r.find(w, wl, d);
    const ex::DriftRow* registered = r.find(w, wl, d, false, true);
    ASSERT_NE(plain, nullptr);
    ASSERT_NE(registered, nullptr);
    EXPECT_LT(registered->share(), 0.02) << "registered at drift " << d << ": " << 100 * registered->share() << " %";
    EXPECT_LT(registered->final_pose_error_m, 0.01) << "registered pose off at drift " << d;
    EXPECT_NEAR(plain->final_pose_error_m, d * cfg.path_length_m, 0.01) << "the plain estimate carries the drift";
    EXPECT_GT(registered->registrations, 0U);
    EXPECT_EQ(registered->x_observable, registered->registrations) << "the wave fixes x in every frame";
  }
  EXPECT_FALSE(std::isfinite(ex::drift_crossing(r, w, wl, cfg.tolerance, false, true))) << "registered maps crossed 5 %";
}

TEST(ExperimentsRegistration, FlatGroundClaimsOnlyHeightAndTheSinusoidAliasesBeyondHalfAPeriod) {
  ex::RegistrationExpConfig cfg = ex::RegistrationExpConfig::quick();
  cfg.terrains = {ex::RegistrationTerrain::kFlat, ex::RegistrationTerrain::kSinusoid};
  const ex::RegistrationExpResult r = ex::run_registration_experiment(cfg);
  ASSERT_EQ(r.cells.size(), 2U * cfg.overlaps.size() * cfg.offsets.size());
  for (const ex::RegistrationCell& c : r.cells) {
    if (c.terrain == ex::RegistrationTerrain::kFlat) {
      EXPECT_EQ(c.claimed_x + c.claimed_y + c.claimed_yaw, 0) << "flat ground claimed x, y or yaw";
      EXPECT_EQ(c.claimed_z, c.trials) << "flat ground should fix the height in every trial";
      EXPECT_EQ(c.over_claims, 0);
    } else {
      EXPECT_EQ(c.claimed_y, 0) << "nothing varies along the sinusoid's crests";
      if (c.offset_m < 0.3) {
        EXPECT_EQ(c.claimed_x, c.trials) << "offset " << c.offset_m;
        EXPECT_EQ(c.over_claims, 0) << "offset " << c.offset_m;
      }
    }
  }
}

TEST(ExperimentsRegistration, RealTerrainWithoutOverClaims) {
  ex::RegistrationExpConfig cfg = ex::RegistrationExpConfig::quick();
  cfg.terrains = {ex::RegistrationTerrain::kLoneStar, ex::RegistrationTerrain::kMarsDtm};
  cfg.offsets = {0.02, 0.1};
  cfg.data_dir = ccmap::sim::resolve_data_dir();
  const ex::RegistrationExpResult r = ex::run_registration_experiment(cfg);
  int available = 0, claimed = 0;
  for (const ex::RegistrationTerrainInfo& t : r.terrains) available += t.available ? 1 : 0;
  if (available == 0) GTEST_SKIP() << "no real terrain data: " << r.terrains.front().why;
  for (const ex::RegistrationCell& c : r.cells) {
    EXPECT_EQ(c.over_claims, 0) << "terrain " << int(c.terrain) << " overlap " << c.overlap << " offset " << c.offset_m;
    claimed += c.claimed_x;
  }
  EXPECT_GT(claimed, 0) << "real terrain should fix x in some trials";
}
