// Registration of a frame to the map (registration/registration.hpp): analytic terrains shifted
// by known corrections, what each terrain lets registration observe, an independent
// double-precision model of the same normal equations (reference_registration.hpp), the map left
// untouched, outliers and changed ground, and every refusal.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "ccmap/registration/registration.hpp"
#include "registration/reference_registration.hpp"
#include "support/map_state.hpp"
#include "support/poses.hpp"
#include "support/terrain_frames.hpp"

namespace ccmap {
namespace {

using Map = Stack<CadreConfig>;
using test::Terrain;
using test::TestCorrection;

constexpr float kInf = std::numeric_limits<float>::infinity();

/// A CADRE map of `terrain` from `frames` frames at the true pose (sensor at the origin).
std::unique_ptr<Map> map_of(Terrain terrain, int frames = 3) {
  auto map = std::make_unique<Map>();
  EXPECT_EQ(map->init(default_stack_params(0.04F)), Status::kOk);
  for (int k = 0; k < frames; ++k) {
    test::TerrainFrameSpec spec;
    spec.terrain = terrain;
    spec.seed = 100U + static_cast<std::uint32_t>(k);
    const test::TerrainFrame f = test::make_terrain_frame(spec);
    EXPECT_EQ(map->update_frame(f.points.data(), f.points.size(), f.origin, nullptr), Status::kOk);
  }
  return map;
}

/// A new frame of `terrain` as a rover with a pose error sees it (registration should answer c).
test::TerrainFrame displaced_frame(Terrain terrain, const TestCorrection& c, std::uint32_t seed = 7U) {
  test::TerrainFrameSpec spec;
  spec.terrain = terrain;
  spec.seed = seed;
  return test::displace(test::make_terrain_frame(spec), c);
}

RegistrationResult register_displaced(const Map& map, Terrain terrain, const TestCorrection& c,
                                      std::uint32_t seed = 7U) {
  const test::TerrainFrame f = displaced_frame(terrain, c, seed);
  return ccmap::register_frame(map, f.points.data(), f.points.size(), f.origin, default_registration_params());
}

/// Applies a result to a map-frame point about `o` (registration/types.hpp).
void apply(const RegistrationResult& r, PointXYZ o, double x, double y, double z, double* out) {
  const double cs = std::cos(double(r.dyaw)), sn = std::sin(double(r.dyaw));
  out[0] = cs * (x - o.x) - sn * (y - o.y) + o.x + r.dx;
  out[1] = sn * (x - o.x) + cs * (y - o.y) + o.y + r.dy;
  out[2] = z + r.dz;
}

/// RMS height of the corrected frame above the true terrain (m): what the correction is for.
double corrected_rms(const RegistrationResult& r, const test::TerrainFrame& f, Terrain terrain) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < f.points.size(); i += 37) {
    double q[3];
    apply(r, f.origin, f.points[i].x, f.points[i].y, f.points[i].z, q);
    const double e = q[2] - test::terrain_height(terrain, q[0], q[1]);
    sum += e * e;
    ++n;
  }
  return std::sqrt(sum / n);
}

const TestCorrection kOffset{0.03, -0.02, 0.015, 0.02};

// ---------------------------------------------------------------------------------------------
// What each terrain lets registration observe
// ---------------------------------------------------------------------------------------------

TEST(RegistrationTerrain, FlatGroundFixesTheHeightAndNothingElse) {
  auto map = map_of(Terrain::kFlat);
  for (std::uint32_t seed = 1; seed <= 4; ++seed) {
    const RegistrationResult r = register_displaced(*map, Terrain::kFlat, kOffset, seed);
    ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
    EXPECT_TRUE(r.observable[kAxisZ]) << "flat ground must fix the height";
    EXPECT_FALSE(r.observable[kAxisX] || r.observable[kAxisY] || r.observable[kAxisYaw])
        << "flat ground claimed x, y or yaw (seed " << seed << ")";
    EXPECT_EQ(r.dx, 0.0F) << "no x may be invented on flat ground";
    EXPECT_EQ(r.dy, 0.0F) << "no y may be invented on flat ground";
    EXPECT_EQ(r.dyaw, 0.0F) << "no yaw may be invented on flat ground";
    EXPECT_EQ(r.sigma_dx, kInf);
    EXPECT_EQ(r.sigma_dy, kInf);
    EXPECT_EQ(r.sigma_dyaw, kInf);
    EXPECT_EQ(r.rank, 1U);
    EXPECT_NEAR(r.dz, kOffset.dz, 3.0 * r.sigma_dz + 5e-4) << "height off by " << (r.dz - kOffset.dz) * 1e3 << " mm";
    EXPECT_LT(r.sigma_dz, 1e-3F);
  }
}

TEST(RegistrationTerrain, TiltedPlaneFixesItsTurnButNotWhereAlongItsGradient) {
  // On one plane z = a x + b y a shift along the gradient is a shift in height: dz and (dx, dy)
  // are one unknown (a dx + b dy - dz), and the shift along the contours none. A turn about the
  // vertical turns the plane's gradient: observable.
  auto map = map_of(Terrain::kPlane);
  const test::TerrainFrame f = displaced_frame(Terrain::kPlane, kOffset);
  const RegistrationResult r = ccmap::register_frame(*map, f.points.data(), f.points.size(), f.origin, default_registration_params());
  ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
  EXPECT_FALSE(r.observable[kAxisX] || r.observable[kAxisY] || r.observable[kAxisZ])
      << "a single plane cannot fix x, y or z alone";
  EXPECT_TRUE(r.observable[kAxisYaw]) << "the plane's gradient direction fixes the turn";
  EXPECT_EQ(r.rank, 2U);
  EXPECT_NEAR(r.dyaw, kOffset.yaw, 3.0 * r.sigma_dyaw + 5e-4);
  // Minimum norm: (dx, dy, dz) lies along (-a, -b, 1), the one observable translation.
  EXPECT_NEAR(r.dx / r.dz, -0.15, 0.02) << "a translation along the plane was invented";
  EXPECT_NEAR(r.dy / r.dz, -0.05, 0.02) << "a translation along the plane was invented";
  EXPECT_LT(corrected_rms(r, f, Terrain::kPlane), 3e-3) << "the corrected frame does not lie on the plane";
}

TEST(RegistrationTerrain, RampFixesAlongItAndHeightButNotAcross) {
  auto map = map_of(Terrain::kRampX);
  const RegistrationResult r = register_displaced(*map, Terrain::kRampX, kOffset);
  ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
  EXPECT_TRUE(r.observable[kAxisX] && r.observable[kAxisZ]) << "the ramp's edges fix x, the flats z";
  EXPECT_FALSE(r.observable[kAxisY]) << "nothing varies across the ramp";
  // y is absent from the evidence but for noise coupling it to the yaw: at most a millimetre or two.
  EXPECT_LT(std::fabs(r.dy), 2e-3) << "a y was invented across the ramp";
  EXPECT_EQ(r.sigma_dy, kInf);
  EXPECT_NEAR(r.dx, kOffset.dx, 3.0 * r.sigma_dx + 5e-4) << "x off by " << (r.dx - kOffset.dx) * 1e3 << " mm";
  EXPECT_NEAR(r.dz, kOffset.dz, 3.0 * r.sigma_dz + 5e-4) << "z off by " << (r.dz - kOffset.dz) * 1e3 << " mm";
}

TEST(RegistrationTerrain, BowlLeavesTheTurnAboutItsAxisOpen) {
  // z = k |p - b|^2 is unchanged by a turn about the vertical through b: a turn about the sensor
  // is that turn plus a shift, so x, y and yaw are one unknown short. Only z is claimed, and the
  // correction moves the bowl's axis where it belongs.
  auto map = map_of(Terrain::kBowl);
  const RegistrationResult r = register_displaced(*map, Terrain::kBowl, kOffset);
  ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
  EXPECT_TRUE(r.observable[kAxisZ]);
  EXPECT_FALSE(r.observable[kAxisX] || r.observable[kAxisY] || r.observable[kAxisYaw])
      << "the turn about the bowl's axis was claimed";
  EXPECT_EQ(r.rank, 3U);
  // Where the correction puts the point that the true correction puts at the bowl's axis.
  const test::TerrainFrame f = displaced_frame(Terrain::kBowl, kOffset);
  const double cs = std::cos(-kOffset.yaw), sn = std::sin(-kOffset.yaw);
  const double bx = 2.0 - f.origin.x - kOffset.dx, by = 0.5 - f.origin.y - kOffset.dy;
  const double px = f.origin.x + cs * bx - sn * by, py = f.origin.y + sn * bx + cs * by;  // C^-1(axis)
  double q[3];
  apply(r, f.origin, px, py, 0.0, q);
  EXPECT_NEAR(q[0], 2.0, 4e-3) << "the bowl's axis lands off in x";
  EXPECT_NEAR(q[1], 0.5, 4e-3) << "the bowl's axis lands off in y";
}

TEST(RegistrationTerrain, SinusoidFixesAcrossItsCrestsNotAlongThem) {
  auto map = map_of(Terrain::kSinusoidX);
  const RegistrationResult r = register_displaced(*map, Terrain::kSinusoidX, kOffset);
  ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
  EXPECT_TRUE(r.observable[kAxisX] && r.observable[kAxisZ] && r.observable[kAxisYaw]);
  EXPECT_FALSE(r.observable[kAxisY]) << "nothing varies along the crests";
  EXPECT_EQ(r.dy, 0.0F);
  EXPECT_NEAR(r.dx, kOffset.dx, 3.0 * r.sigma_dx + 5e-4);
  EXPECT_NEAR(r.dyaw, kOffset.yaw, 3.0 * r.sigma_dyaw + 5e-4);
}

TEST(RegistrationTerrain, SinusoidBeyondHalfAPeriodLandsOnTheNextCrest) {
  // Repetitive terrain: a shift by a whole period (0.8 m) fits as well as none, and the solver
  // finds the alignment nearest to the pose it was given. 0.5 m off is nearer to -0.3 m: that is
  // the answer, claimed as observable, because locally it is. This limit is the caller's to
  // respect (a pose known to better than half the terrain's period; docs/design.md).
  auto map = map_of(Terrain::kSinusoidX);
  RegistrationParams p = default_registration_params();
  p.max_translation_m = 0.6F;
  p.max_iterations = 30U;
  const TestCorrection c{0.5, 0.0, 0.0, 0.0};
  const test::TerrainFrame f = displaced_frame(Terrain::kSinusoidX, c);
  const RegistrationResult r = ccmap::register_frame(*map, f.points.data(), f.points.size(), f.origin, p);
  ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
  EXPECT_NEAR(r.dx, 0.5 - 0.8, 0.01) << "expected the alias one period away";
}

TEST(RegistrationTerrain, RollingGroundFixesAllFour) {
  auto map = map_of(Terrain::kRolling);
  const TestCorrection offsets[] = {kOffset, {-0.05, 0.04, -0.02, -0.03}, {0.0, 0.0, 0.0, 0.0}, {0.08, 0.0, 0.01, 0.0}};
  for (const TestCorrection& c : offsets) {
    const RegistrationResult r = register_displaced(*map, Terrain::kRolling, c);
    ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
    EXPECT_EQ(r.rank, 4U);
    for (int a = 0; a < 4; ++a) EXPECT_TRUE(r.observable[a]) << "axis " << a << " not observable on rolling ground";
    EXPECT_NEAR(r.dx, c.dx, 3.0 * r.sigma_dx + 5e-4);
    EXPECT_NEAR(r.dy, c.dy, 3.0 * r.sigma_dy + 5e-4);
    EXPECT_NEAR(r.dz, c.dz, 3.0 * r.sigma_dz + 5e-4);
    EXPECT_NEAR(r.dyaw, c.yaw, 3.0 * r.sigma_dyaw + 5e-4);
    EXPECT_LT(r.sigma_dx, 3e-3F);
    EXPECT_LT(r.sigma_dy, 3e-3F);
    EXPECT_LE(r.iterations, default_registration_params().max_iterations);
  }
}

TEST(RegistrationTerrain, SigmasAreHonestOverManyFrames) {
  // Over independent frames the errors divided by the claimed sigmas must scatter like unit
  // normals or less: RMS <= 1.5 and none beyond 4 (rolling ground and rocks on a swell).
  for (const Terrain t : {Terrain::kRolling, Terrain::kRocks}) {
    auto map = map_of(t);
    double sum = 0.0;
    int n = 0;
    for (std::uint32_t seed = 11; seed < 23; ++seed) {
      const RegistrationResult r = register_displaced(*map, t, kOffset, seed);
      ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
      const double err[4] = {r.dx - kOffset.dx, r.dy - kOffset.dy, r.dz - kOffset.dz, r.dyaw - kOffset.yaw};
      const float sig[4] = {r.sigma_dx, r.sigma_dy, r.sigma_dz, r.sigma_dyaw};
      for (int a = 0; a < 4; ++a) {
        if (!r.observable[a]) continue;
        const double z = err[a] / std::max(double(sig[a]), a == kAxisYaw ? 2e-4 : 2e-4);
        EXPECT_LT(std::fabs(z), 4.0) << "terrain " << int(t) << " seed " << seed << " axis " << a << ": error "
                                     << err[a] << " against sigma " << sig[a];
        sum += z * z;
        ++n;
      }
    }
    ASSERT_GT(n, 12) << "too few claims to judge the sigmas";
    EXPECT_LT(std::sqrt(sum / n), 1.5) << "terrain " << int(t) << ": sigmas over-confident";
  }
}

// ---------------------------------------------------------------------------------------------
// Against an independent double-precision model of the same normal equations
// ---------------------------------------------------------------------------------------------

TEST(RegistrationReference, SolutionIsTheStationaryPointOfTheDoubleModel) {
  for (const Terrain t : {Terrain::kRolling, Terrain::kRampX, Terrain::kFlat, Terrain::kRocks}) {
    auto map = map_of(t);
    const test::TerrainFrame f = displaced_frame(t, kOffset);
    const RegistrationParams p = default_registration_params();
    const RegistrationResult r = ccmap::register_frame(*map, f.points.data(), f.points.size(), f.origin, p);
    ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
    const test::ReferenceRegistration<CadreConfig> model(*map, f.points, f.origin, p);
    const double at[4] = {r.dx, r.dy, r.dz, r.dyaw};
    const test::ReferenceAnswer a = model.evaluate(at);
    ASSERT_TRUE(a.ok) << "the model matched " << a.matched << " samples";
    EXPECT_NEAR(a.matched, int(r.points_matched), 0.01 * r.points_matched + 2) << "terrain " << int(t);
    EXPECT_NEAR(a.lever, r.lever_m, 0.01 * a.lever);
    // The model's own Gauss-Newton step from the library's answer: within the convergence bound.
    EXPECT_LT(std::hypot(a.step[0], a.step[1]), 5e-4) << "terrain " << int(t) << ": not at the model's minimum in x-y";
    EXPECT_LT(std::fabs(a.step[2]), 2e-4) << "terrain " << int(t) << ": not at the model's minimum in z";
    EXPECT_LT(std::fabs(a.step[3]) * a.lever, 5e-4) << "terrain " << int(t) << ": not at the model's minimum in yaw";
    const float sig[4] = {r.sigma_dx, r.sigma_dy, r.sigma_dz, r.sigma_dyaw};
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(a.observable[k], r.observable[k]) << "terrain " << int(t) << " axis " << k;
      if (a.observable[k] && r.observable[k]) {
        const double expected = std::max(a.sigma_model[k], a.sigma_jack[k]);
        EXPECT_NEAR(sig[k], expected, 0.05 * expected) << "terrain " << int(t) << " axis " << k;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The frame's form, the map untouched, outliers
// ---------------------------------------------------------------------------------------------

TEST(Registration, SensorFrameAgreesWithTheMapFrame) {
  auto map = map_of(Terrain::kRolling);
  const test::TerrainFrame f = displaced_frame(Terrain::kRolling, kOffset);
  // The same points in a sensor frame turned by 0.3 rad about z.
  const float c = std::cos(0.3F), s = std::sin(0.3F);
  const Pose pose = test::yaw_pose(c, s, f.origin);
  std::vector<PointXYZ> sensor(f.points.size());
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    const float x = f.points[i].x - f.origin.x, y = f.points[i].y - f.origin.y;
    sensor[i] = PointXYZ{c * x + s * y, -s * x + c * y, f.points[i].z - f.origin.z};
  }
  const RegistrationParams p = default_registration_params();
  const RegistrationResult a = ccmap::register_frame(*map, f.points.data(), f.points.size(), f.origin, p);
  const RegistrationResult b = ccmap::register_frame_sensor(*map, sensor.data(), sensor.size(), pose, p);
  ASSERT_EQ(a.status, Status::kOk);
  ASSERT_EQ(b.status, Status::kOk);
  EXPECT_NEAR(a.dx, b.dx, 2e-4);
  EXPECT_NEAR(a.dy, b.dy, 2e-4);
  EXPECT_NEAR(a.dz, b.dz, 1e-4);
  EXPECT_NEAR(a.dyaw, b.dyaw, 2e-4);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(a.observable[k], b.observable[k]);
}

TEST(Registration, ChangesNothingInTheMap) {
  auto map = map_of(Terrain::kRolling);
  const std::vector<unsigned char> before = test::raw_map_state(*map);
  const FrameCounters totals = map->total_counters();
  const std::uint32_t frames = map->accepted_frames();
  const RegistrationResult r = register_displaced(*map, Terrain::kRolling, kOffset);
  ASSERT_EQ(r.status, Status::kOk);
  EXPECT_EQ(test::raw_map_state(*map), before) << "registration wrote to the map";
  EXPECT_EQ(map->accepted_frames(), frames);
  EXPECT_EQ(map->total_counters().received, totals.received);
  EXPECT_EQ(map->rejected_frames(), 0U);
}

TEST(Registration, OutliersAndChangedGroundFadeOut) {
  auto map = map_of(Terrain::kRolling);
  test::TerrainFrame f = displaced_frame(Terrain::kRolling, kOffset);
  // 10 % of the points 0.2 .. 1 m off (mismatches), and a 40 cm box standing on the ground
  // that the map has not seen (changed ground): every point over it 0.3 m higher.
  std::uint32_t h = 12345U;
  for (std::size_t i = 0; i < f.points.size(); ++i) {
    h = h * 1664525U + 1013904223U;
    PointXYZ& q = f.points[i];
    if ((h >> 24) < 26U) q.z += 0.2F + 0.8F * static_cast<float>((h >> 8) & 0xFFFFU) / 65535.0F;
    if (q.x > 2.0F && q.x < 2.4F && q.y > -0.2F && q.y < 0.2F) q.z += 0.3F;
  }
  const RegistrationResult r = ccmap::register_frame(*map, f.points.data(), f.points.size(), f.origin, default_registration_params());
  ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
  EXPECT_NEAR(r.dx, kOffset.dx, 3.0 * r.sigma_dx + 1e-3);
  EXPECT_NEAR(r.dy, kOffset.dy, 3.0 * r.sigma_dy + 1e-3);
  EXPECT_NEAR(r.dz, kOffset.dz, 3.0 * r.sigma_dz + 1e-3) << "outliers pulled the height";
  EXPECT_NEAR(r.dyaw, kOffset.yaw, 3.0 * r.sigma_dyaw + 1e-3);
}

TEST(Registration, NonFinitePointsAreSkippedAndCounted) {
  auto map = map_of(Terrain::kRolling);
  test::TerrainFrame f = displaced_frame(Terrain::kRolling, kOffset);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < f.points.size(); i += 3) f.points[i].y = nan;
  f.points[1].x = 1e30F;
  const RegistrationResult r = ccmap::register_frame(*map, f.points.data(), f.points.size(), f.origin, default_registration_params());
  ASSERT_EQ(r.status, Status::kOk) << to_string(r.status);
  EXPECT_GT(r.points_rejected, r.points_sampled / 3U) << "non-finite samples were not counted";
  EXPECT_NEAR(r.dx, kOffset.dx, 3.0 * r.sigma_dx + 5e-4);
}

// ---------------------------------------------------------------------------------------------
// Refusals: a status that says which, and nothing claimed
// ---------------------------------------------------------------------------------------------

void expect_unclaimed(const RegistrationResult& r, Status expected, const char* what) {
  EXPECT_EQ(r.status, expected) << what << ": got " << to_string(r.status);
  EXPECT_EQ(r.dx, 0.0F) << what;
  EXPECT_EQ(r.dy, 0.0F) << what;
  EXPECT_EQ(r.dz, 0.0F) << what;
  EXPECT_EQ(r.dyaw, 0.0F) << what;
  EXPECT_EQ(r.sigma_dx, kInf) << what;
  EXPECT_EQ(r.sigma_dy, kInf) << what;
  EXPECT_EQ(r.sigma_dz, kInf) << what;
  EXPECT_EQ(r.sigma_dyaw, kInf) << what;
  for (int k = 0; k < 4; ++k) EXPECT_FALSE(r.observable[k]) << what;
  EXPECT_EQ(r.rank, 0U) << what;
}

TEST(RegistrationRefusals, EveryBadInputIsAnsweredAndNothingClaimed) {
  auto map = map_of(Terrain::kRolling);
  const test::TerrainFrame f = displaced_frame(Terrain::kRolling, kOffset);
  const RegistrationParams p = default_registration_params();
  const PointXYZ* pts = f.points.data();
  const std::size_t n = f.points.size();
  const float nan = std::numeric_limits<float>::quiet_NaN();

  Map uninitialised;
  expect_unclaimed(ccmap::register_frame(uninitialised, pts, n, f.origin, p), Status::kNotInitialised, "before init");
  expect_unclaimed(ccmap::register_frame(*map, nullptr, 10U, f.origin, p), Status::kInvalidArgument, "null points");
  RegistrationParams bad = p;
  bad.max_points = 0U;
  expect_unclaimed(ccmap::register_frame(*map, pts, n, f.origin, bad), Status::kInvalidArgument, "zero max_points");
  bad = p;
  bad.max_sigma_m = nan;
  expect_unclaimed(ccmap::register_frame(*map, pts, n, f.origin, bad), Status::kInvalidArgument, "NaN max_sigma_m");
  expect_unclaimed(ccmap::register_frame(*map, pts, n, PointXYZ{nan, 0.0F, 0.2F}, p), Status::kNonFiniteInput, "NaN origin");
  expect_unclaimed(ccmap::register_frame(*map, pts, n, PointXYZ{2e5F, 0.0F, 0.2F}, p), Status::kOutOfRange, "origin beyond 1e5 m");
  expect_unclaimed(ccmap::register_frame(*map, pts, n, PointXYZ{40.0F, 0.0F, 0.2F}, p), Status::kOutsideMap,
                   "a pose far from the map");
  expect_unclaimed(ccmap::register_frame(*map, pts, 0U, f.origin, p), Status::kDegenerateInput, "no points");
  std::vector<PointXYZ> all_nan(1000, PointXYZ{nan, nan, nan});
  expect_unclaimed(ccmap::register_frame(*map, all_nan.data(), all_nan.size(), f.origin, p), Status::kNonFiniteInput,
                   "every point NaN");
  std::vector<PointXYZ> one_spot(1000, PointXYZ{1.0F, 0.5F, 0.0F});
  expect_unclaimed(ccmap::register_frame(*map, one_spot.data(), one_spot.size(), f.origin, p), Status::kDegenerateInput,
                   "every point at one spot");
  // Points beyond every layer's range, and points mostly beyond the windows from a sensor near
  // the window's edge.
  std::vector<PointXYZ> far = f.points;
  for (PointXYZ& q : far) q.x += 30.0F;
  expect_unclaimed(ccmap::register_frame(*map, far.data(), far.size(), f.origin, p), Status::kOutsideMap,
                   "points beyond every layer's range");
  std::vector<PointXYZ> edge = f.points;
  const PointXYZ edge_origin{f.origin.x + 9.8F, f.origin.y, f.origin.z};
  for (PointXYZ& q : edge) q.x += 9.8F;
  expect_unclaimed(ccmap::register_frame(*map, edge.data(), edge.size(), edge_origin, p), Status::kOutsideMap,
                   "points beyond the windows");
  // Ground the map has never seen: behind the sensor.
  std::vector<PointXYZ> behind = f.points;
  for (PointXYZ& q : behind) q.x = f.origin.x - (q.x - f.origin.x);
  expect_unclaimed(ccmap::register_frame(*map, behind.data(), behind.size(), f.origin, p), Status::kInsufficientOverlap,
                   "ground the map does not know");
  // An empty map.
  Map empty;
  ASSERT_EQ(empty.init(default_stack_params(0.04F)), Status::kOk);
  expect_unclaimed(ccmap::register_frame(empty, pts, n, f.origin, p), Status::kInsufficientOverlap, "an empty map");
  // A pose error beyond the search bound.
  RegistrationParams tight = p;
  tight.max_translation_m = 0.02F;
  expect_unclaimed(ccmap::register_frame(*map, pts, n, f.origin, tight), Status::kNotConverged,
                   "a correction beyond max_translation_m");
  // Too few iterations to converge.
  RegistrationParams one = p;
  one.max_iterations = 1U;
  expect_unclaimed(ccmap::register_frame(*map, pts, n, f.origin, one), Status::kNotConverged, "one iteration");
  // Sensor-frame input: a pose that is no rotation, or not finite.
  Pose pose = test::identity_pose(f.origin);
  pose.rotation[0][0] = 1.5F;
  expect_unclaimed(ccmap::register_frame_sensor(*map, pts, n, pose, p), Status::kInvalidArgument, "a rotation entry of 1.5");
  pose = test::identity_pose(f.origin);
  pose.rotation[0][1] = 0.1F;
  expect_unclaimed(ccmap::register_frame_sensor(*map, pts, n, pose, p), Status::kInvalidArgument, "R^T R off the identity");
  pose = test::identity_pose(f.origin);
  pose.rotation[2][2] = nan;
  expect_unclaimed(ccmap::register_frame_sensor(*map, pts, n, pose, p), Status::kNonFiniteInput, "a NaN rotation");
  pose = test::identity_pose(PointXYZ{0.0F, nan, 0.2F});
  expect_unclaimed(ccmap::register_frame_sensor(*map, pts, n, pose, p), Status::kNonFiniteInput, "a NaN translation");
}

TEST(RegistrationRefusals, ParamsAreValidated) {
  EXPECT_EQ(validate_registration_params(default_registration_params()), Status::kOk);
  auto with = [](auto change) {
    RegistrationParams p = default_registration_params();
    change(p);
    return validate_registration_params(p);
  };
  EXPECT_EQ(with([](RegistrationParams& p) { p.max_points = kMaxRegistrationPoints + 1U; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](RegistrationParams& p) { p.max_iterations = 0U; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](RegistrationParams& p) { p.max_iterations = kMaxRegistrationIterations + 1U; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](RegistrationParams& p) { p.min_matches = 2U; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](RegistrationParams& p) { p.max_translation_m = 0.0F; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](RegistrationParams& p) { p.max_yaw_rad = 0.6F; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](RegistrationParams& p) { p.robust_sigmas = -1.0F; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](RegistrationParams& p) { p.model_variance_m2 = -1e-6F; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](RegistrationParams& p) { p.convergence_m = 0.0F; }), Status::kInvalidArgument);
  EXPECT_EQ(with([](RegistrationParams& p) { p.max_translation_m = std::numeric_limits<float>::infinity(); }),
            Status::kNonFiniteInput);
}

}  // namespace
}  // namespace ccmap
