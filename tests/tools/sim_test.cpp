// Tests of the host simulator (tools/sim): terrain determinism, rock size law, stereo ray
// casting on a plane (geometry and analytic range error), occlusion, hazards, paths, DTM.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sim/cloud.hpp"
#include "sim/data_dir.hpp"
#include "sim/hazard.hpp"
#include "sim/path.hpp"
#include "sim/rng.hpp"
#include "sim/stereo.hpp"
#include "sim/terrain.hpp"

namespace sim = ccmap::sim;

namespace {

sim::HeightRaster flat_raster(double size_m, double res_m, double z = 0.0) {
  sim::HeightRaster r(-size_m / 2, -size_m / 2, res_m, static_cast<int>(size_m / res_m) + 1,
                      static_cast<int>(size_m / res_m) + 1, static_cast<float>(z));
  r.build_blocks();
  return r;
}

}  // namespace

TEST(SimRng, SameSeedSameStreamAndNormalMoments) {
  sim::Rng a(7), b(7);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.next_u64(), b.next_u64()) << "stream differs at draw " << i;
  sim::Rng n(3);
  double s = 0, s2 = 0;
  const int count = 200000;
  for (int i = 0; i < count; ++i) {
    const double v = n.normal();
    s += v;
    s2 += v * v;
  }
  EXPECT_NEAR(s / count, 0.0, 0.01) << "Box-Muller mean off";
  EXPECT_NEAR(s2 / count, 1.0, 0.02) << "Box-Muller variance off";
}

TEST(SimTerrain, DeterministicBySeed) {
  const sim::Rect area{0, 0, 20, 20};
  const sim::ProceduralTerrain a(sim::lunar_terrain_params(area, 11));
  const sim::ProceduralTerrain b(sim::lunar_terrain_params(area, 11));
  const sim::ProceduralTerrain c(sim::lunar_terrain_params(area, 12));
  ASSERT_EQ(a.rocks().size(), b.rocks().size());
  double max_diff_same = 0.0, max_diff_other = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const double x = 0.01 * k, y = 20.0 - 0.0093 * k;
    max_diff_same = std::max(max_diff_same, std::fabs(a.height(x, y) - b.height(x, y)));
    max_diff_other = std::max(max_diff_other, std::fabs(a.height(x, y) - c.height(x, y)));
  }
  EXPECT_EQ(max_diff_same, 0.0) << "same seed gave different heights";
  EXPECT_GT(max_diff_other, 0.01) << "a different seed gave (nearly) the same terrain";
}

TEST(SimTerrain, RockSizesFollowPowerLaw) {
  sim::TerrainParams p;
  p.area = sim::Rect{0, 0, 200, 200};
  p.rocks = sim::RockParams{0.5, 0.1, 2.0, 2.5, 0.5};
  p.seed = 5;
  const sim::ProceduralTerrain t(p);
  const std::vector<sim::Rock>& rocks = t.rocks();
  ASSERT_EQ(rocks.size(), 20000U);
  // Cumulative counts N(>=D) at D = 0.1 .. 0.4 m: log-log slope should be -2.5.
  const double d0 = 0.1, d1 = 0.4;
  const auto count_ge = [&](double d) {
    return static_cast<double>(std::count_if(rocks.begin(), rocks.end(), [d](const sim::Rock& r) { return r.diameter_m >= d; }));
  };
  const double n0 = count_ge(d0), n1 = count_ge(d1);
  ASSERT_GT(n1, 100.0);
  const double slope = std::log(n1 / n0) / std::log(d1 / d0);
  // Truncation at 2 m changes N(>=0.4) by < 1 %, well inside the tolerance.
  EXPECT_NEAR(slope, -2.5, 0.1) << "cumulative rock count does not follow D^-2.5";
  for (const sim::Rock& r : rocks) {
    ASSERT_GE(r.diameter_m, 0.1 - 1e-12);
    ASSERT_LE(r.diameter_m, 2.0 + 1e-12);
    ASSERT_NEAR(r.height_m, 0.5 * r.diameter_m, 1e-12);
  }
  // A dome: full height at the centre, nothing outside its footprint.
  const sim::Rock& r = rocks.front();
  EXPECT_GE(t.obstacle_height(r.x, r.y), r.height_m - 1e-12);
}

TEST(SimTerrain, CraterHasBowlAndRaisedRim) {
  sim::ProceduralTerrain t;
  t.add_crater(sim::Crater{0.0, 0.0, 4.0, 0.6, 0.1});
  EXPECT_NEAR(t.height(0, 0), -0.6, 1e-12) << "bowl floor";
  EXPECT_NEAR(t.height(2.0, 0), 0.1, 1e-12) << "rim crest at r = R";
  EXPECT_NEAR(t.height(6.0, 0), 0.0, 1e-12) << "no relief beyond 2.5 R";
  EXPECT_GT(t.height(2.5, 0), 0.0) << "raised outer flank";
}

TEST(SimTerrain, WaveTerrainIsSinusoidal) {
  const sim::WaveTerrain w(0.1, 2.0);
  EXPECT_NEAR(w.height(0.5, 3.0), 0.1, 1e-12);
  EXPECT_NEAR(w.height(1.5, -7.0), -0.1, 1e-12);
}

TEST(SimRaster, BilinearMatchesPlaneAndNaNOutside) {
  sim::ProceduralTerrain plane;
  sim::TerrainParams p;
  p.slope_x = 0.2;
  p.slope_y = -0.1;
  plane = sim::ProceduralTerrain(p);
  const sim::HeightRaster r = sim::rasterize(plane, sim::Rect{0, 0, 2, 1}, 0.05);
  EXPECT_EQ(r.nx(), 41);
  EXPECT_EQ(r.ny(), 21);
  EXPECT_NEAR(r.height(1.234, 0.567), 0.2 * 1.234 - 0.1 * 0.567, 1e-6) << "bilinear is exact on a plane";
  EXPECT_TRUE(std::isnan(r.height(-0.01, 0.5))) << "outside the raster must be NaN";
}

TEST(SimCloud, NoiseHasRequestedSigma) {
  const sim::ProceduralTerrain flat;
  sim::CloudParams cp;
  cp.area = sim::Rect{0, 0, 10, 10};
  cp.count = 50000;
  cp.sigma_z_m = 0.05;
  cp.seed = 9;
  const std::vector<sim::Point3> pts = sim::sample_noisy_cloud(flat, cp);
  ASSERT_EQ(pts.size(), cp.count);
  double s2 = 0;
  for (const auto& q : pts) {
    ASSERT_TRUE(cp.area.contains(q.x, q.y));
    s2 += q.z * q.z;
  }
  EXPECT_NEAR(std::sqrt(s2 / static_cast<double>(pts.size())), 0.05, 0.001) << "cloud noise sigma off";
}

TEST(SimStereo, NoiselessFlatPlanePointsLieOnPlane) {
  const sim::HeightRaster ground = flat_raster(40.0, 0.02, 0.3);
  sim::StereoParams sp;
  sp.disparity_sigma_px = 0.0;
  sp.disparity_step_px = 0.0;
  sp.pixel_stride = 5;
  const sim::StereoCamera cam(sp);
  const sim::StereoFrame f = cam.capture(ground, sim::Pose2{1.0, 2.0, 0.7}, 1);
  ASSERT_GT(f.points_map.size(), 5000U);
  EXPECT_NEAR(f.sensor_position_map.z, 0.3 + 0.175, 1e-6) << "raster heights are floats";
  double worst = 0.0;
  for (const auto& q : f.points_map) worst = std::max(worst, std::fabs(q.z - 0.3));
  EXPECT_LT(worst, 1e-3) << "noise-free points are off the plane by " << worst << " m";
  // Analytic depth for the pixel row through the image centre: Z = H / sin(pitch).
  const double z_centre = 0.175 / std::sin(25.0 * sim::kPi / 180.0);
  bool found = false;
  for (std::size_t k = 0; k < f.pixels.size(); ++k) {
    if (std::fabs(f.pixels[k].v - 325.5F) < 0.1F && std::fabs(f.pixels[k].u - 425.5F) < 0.1F) {
      // Pixel centre is 0.5 px below the optical axis: allow the matching change in depth.
      EXPECT_NEAR(f.pixels[k].depth_m, z_centre, 0.003) << "centre pixel depth off";
      found = true;
    }
  }
  EXPECT_TRUE(found);
  // Rays above the horizon see nothing: the top rows are empty.
  for (const auto& px : f.pixels) {
    const double elevation = std::atan2(325.0 - px.v, 600.0) - 25.0 * sim::kPi / 180.0;
    ASSERT_LT(elevation, 0.0) << "a point was measured above the horizon";
  }
}

TEST(SimStereo, DepthErrorGrowsWithRangeSquared) {
  const sim::HeightRaster ground = flat_raster(60.0, 0.05, 0.0);
  sim::StereoParams sp;
  sp.disparity_sigma_px = 0.1;
  sp.disparity_step_px = 0.0;  // pure Gaussian disparity noise: sigma_Z = Z^2 sigma_d / (f b)
  sp.pixel_stride = 1;
  sp.max_depth_m = 25.0;
  const sim::StereoCamera cam(sp);
  const sim::StereoFrame f = cam.capture(ground, sim::Pose2{0, 0, 0}, 21);
  // Bins of true depth; the relative error (Z' - Z) / sigma_Z(Z) must have unit spread.
  const double bins[][2] = {{0.5, 0.7}, {1.5, 2.0}, {4.0, 5.0}, {7.0, 10.0}};
  for (const auto& b : bins) {
    double s = 0, s2 = 0;
    int n = 0;
    for (const auto& px : f.pixels) {
      if (px.true_depth_m < b[0] || px.true_depth_m >= b[1]) continue;
      const double e = (px.depth_m - px.true_depth_m) / cam.depth_sigma(px.true_depth_m);
      s += e;
      s2 += e * e;
      ++n;
    }
    ASSERT_GT(n, 2000) << "too few pixels in depth bin " << b[0];
    const double mean = s / n, sd = std::sqrt(s2 / n - mean * mean);
    EXPECT_NEAR(sd, 1.0, 0.06) << "depth noise at " << b[0] << "-" << b[1] << " m is " << sd
                               << " x the analytic Z^2 sigma_d/(f b)";
    EXPECT_NEAR(mean, 0.0, 0.1) << "depth bias at " << b[0] << " m";
  }
  // With 1/16 px quantisation the analytic sigma includes step^2/12.
  sp.disparity_step_px = 1.0 / 16.0;
  const sim::StereoCamera qcam(sp);
  EXPECT_NEAR(qcam.depth_sigma(3.0), 9.0 / 30.0 * std::sqrt(0.01 + 1.0 / 256.0 / 12.0), 1e-12);
}

TEST(SimStereo, BoxCastsAnOcclusionShadow) {
  // Flat ground, a 10 cm box from x = 1.0 to 1.2 m; camera at the origin looking +x, 17.5 cm
  // high. The far top edge shadows the ground up to x = 1.2 * 0.175 / (0.175 - 0.1) = 2.8 m.
  sim::ProceduralTerrain t;
  t.add_box(sim::Box{1.0, -0.5, 1.2, 0.5, 0.1});
  const sim::HeightRaster r = sim::rasterize(t, sim::Rect{-1, -3, 6, 3}, 0.005);
  sim::StereoParams sp;
  sp.disparity_sigma_px = 0.0;
  sp.disparity_step_px = 0.0;
  sp.pixel_stride = 2;
  sp.pitch_deg = 10.0;
  const sim::StereoCamera cam(sp);
  const sim::StereoFrame f = cam.capture(r, sim::Pose2{0, 0, 0}, 3);
  int on_top = 0, on_front = 0, in_shadow = 0, behind_shadow = 0;
  for (const auto& q : f.points_map) {
    if (q.x > 1.01 && q.x < 1.19 && std::fabs(q.y) < 0.3 && std::fabs(q.z - 0.1) < 0.003) ++on_top;
    if (std::fabs(q.x - 1.0) < 0.005 && std::fabs(q.y) < 0.3 && q.z > 0.01 && q.z < 0.09) ++on_front;
    if (q.x > 1.3 && q.x < 2.6 && std::fabs(q.y) < 0.3 && q.z < 0.02) ++in_shadow;
    if (q.x > 3.0 && q.x < 4.0 && std::fabs(q.y) < 0.3 && q.z < 0.02) ++behind_shadow;
  }
  EXPECT_GT(on_top, 50) << "box top not seen";
  EXPECT_GT(on_front, 50) << "box front face not seen";
  EXPECT_EQ(in_shadow, 0) << "ground points inside the box's occlusion shadow";
  EXPECT_GT(behind_shadow, 50) << "ground beyond the shadow not seen";
}

TEST(SimStereo, BorderStreaksSmearForegroundDepth) {
  sim::ProceduralTerrain t;
  t.add_box(sim::Box{1.0, -0.5, 1.2, 0.5, 0.1});
  const sim::HeightRaster r = sim::rasterize(t, sim::Rect{-1, -3, 6, 3}, 0.005);
  sim::StereoParams sp;
  sp.disparity_sigma_px = 0.0;
  sp.disparity_step_px = 0.0;
  sp.pixel_stride = 2;
  sp.pitch_deg = 10.0;
  sp.border_streak_probability = 0.5;
  const sim::StereoCamera cam(sp);
  const sim::StereoFrame f = cam.capture(r, sim::Pose2{0, 0, 0}, 3);
  ASSERT_GT(f.streak_pixels, 20U);
  int floating = 0;
  for (std::size_t k = 0; k < f.points_map.size(); ++k) {
    if (f.pixels[k].streak && f.points_map[k].z > 0.1 + 0.002) ++floating;
  }
  EXPECT_GT(floating, 10) << "streaks should put points above the box's top rim";
  const sim::StereoFrame again = cam.capture(r, sim::Pose2{0, 0, 0}, 3);
  EXPECT_EQ(again.streak_pixels, f.streak_pixels) << "streaks must be deterministic by seed";
}

TEST(SimHazard, RockAndSlopeClassification) {
  sim::TerrainParams p;
  p.slope_x = std::tan(25.0 * sim::kPi / 180.0);
  sim::ProceduralTerrain steep(p);
  sim::HazardParams hp;
  hp.min_obstacle_height_m = 0.1;
  hp.max_slope_deg = 20.0;
  const sim::CellHazard s = sim::evaluate_cell_hazard(steep, sim::Rect{0, 0, 0.32, 0.32}, hp);
  EXPECT_TRUE(s.steep);
  EXPECT_FALSE(s.obstacle) << "a plane has no relief";
  EXPECT_NEAR(s.slope_deg, 25.0, 0.01);
  sim::ProceduralTerrain rocky;
  rocky.add_rock(sim::Rock{0.16, 0.16, 0.2, 0.12});
  const sim::CellHazard o = sim::evaluate_cell_hazard(rocky, sim::Rect{0, 0, 0.32, 0.32}, hp);
  EXPECT_TRUE(o.obstacle);
  EXPECT_NEAR(o.raised_m, 0.12, 0.005);
  EXPECT_FALSE(o.steep) << "rocks must not tilt the ground plane";
  const sim::HazardGrid g = sim::compute_hazard_grid(rocky, 0, 0, 0.32, 3, 3, hp);
  int obstacles = 0;
  for (const auto& c : g.cells) obstacles += c.obstacle ? 1 : 0;
  EXPECT_EQ(obstacles, 1) << "only the cell under the rock is an obstacle";
}

TEST(SimPath, ArcAndDrift) {
  const std::vector<sim::PathPose> path =
      sim::generate_path(sim::Pose2{0, 0, 0}, {{2.0, 0.0}, {sim::kPi, sim::kPi}}, 0.1);
  ASSERT_GE(path.size(), 2U);
  EXPECT_NEAR(path.back().distance_m, 2.0 + sim::kPi, 1e-9);
  // Straight 2 m then a half circle of radius 1 to the left: ends at (2, 2) heading -x.
  EXPECT_NEAR(path.back().pose.x, 2.0, 1e-6);
  EXPECT_NEAR(path.back().pose.y, 2.0, 1e-6);
  EXPECT_NEAR(path.back().pose.yaw, sim::kPi, 1e-9);
  sim::DriftParams d;
  d.fraction_of_distance = 0.08;
  d.direction_rad = sim::kPi / 2;
  const std::vector<sim::Pose2> est = sim::apply_drift(path, d);
  const double err = std::hypot(est.back().x - path.back().pose.x, est.back().y - path.back().pose.y);
  EXPECT_NEAR(err, 0.08 * (2.0 + sim::kPi), 1e-9) << "drift must be 8 % of the distance";
}

TEST(SimDtm, LoadsMarsDtm) {
  const std::string path = sim::mars_dtm_path(sim::resolve_data_dir());
  std::string why;
  if (!sim::data_file_available(path, &why)) GTEST_SKIP() << why;
  sim::HeightRaster dtm;
  std::string error;
  ASSERT_TRUE(sim::load_esri_ascii(path, &dtm, &error)) << error;
  EXPECT_EQ(dtm.nx(), 70);
  EXPECT_EQ(dtm.ny(), 120);
  EXPECT_NEAR(dtm.resolution(), 1.01, 1e-12);
  EXPECT_GT(dtm.min_height(), 750.0);
  EXPECT_LT(dtm.max_height(), 795.0);
  // First value of the file is the north-west vertex; bilinear sampling hits it exactly.
  EXPECT_NEAR(dtm.at(0, 119), 784.3110, 1e-3);
  EXPECT_NEAR(dtm.height(dtm.origin_x(), dtm.origin_y() + 119 * 1.01), 784.3110, 1e-3);
  EXPECT_NEAR(dtm.origin_x(), 0.505, 1e-12) << "values sit at cell centres";
}
