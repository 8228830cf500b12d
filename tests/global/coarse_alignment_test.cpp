// Alignment beyond the capture range (include/ccmap/global/coarse_alignment.hpp): two maps of
// the same ground, the second built in a frame turned and moved by a known rigid motion of
// >= 1 m and >= 10 deg; the aligner must recover the motion (checked on points across the map,
// against the motion the test applied), claim on flat ground only dz (x, y, yaw exactly 0), and
// refuse without overlap. Analytic terrain always; the Mars DTM of ../shared/data scaled 1/20
// when the data is present (skipped with a message otherwise).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "ccmap/global/coarse_alignment.hpp"
#include "ccmap/global/patch_keeper.hpp"
#include "support/global_configs.hpp"
#include "support/terrain_data.hpp"

#ifndef CCMAP_TEST_DATA_DIR
#define CCMAP_TEST_DATA_DIR "../shared/data"
#endif

namespace ccmap {
namespace {

using AlignConfig = test::ThreeCcmConfig;
using Map = Stack<AlignConfig>;
using Aligner = CoarseAligner<AlignConfig>;
using Ground = std::function<float(float, float)>;

StackParams params() {
  StackParams p = default_stack_params(0.04F);
  p.outlier_gate_sigma = 0.0F;
  p.free_space_rays = 0.0F;
  return p;
}

/// The rigid motion from their frame to ours: p_ours = R(yaw) p_theirs + (dx, dy).
struct Motion {
  float dx, dy, yaw;
};

/// Feeds `map` the ground over a disc of `radius` about (cx, cy) (our frame), expressed in the
/// frame `m` maps into ours; points on a lattice of `spacing` (1 cm unless told) with
/// deterministic noise of +-`noise` (2 mm). With `out`, the points fed are copied there and
/// *origin is the sensor origin used.
void build(Map& map, const Ground& ground, float cx, float cy, float radius, const Motion& m, float spacing = 0.01F,
           float noise_m = 0.002F, std::vector<PointXYZ>* out = nullptr, PointXYZ* origin = nullptr) {
  ASSERT_EQ(map.init(params()), Status::kOk);
  const float c = std::cos(m.yaw);
  const float s = std::sin(m.yaw);
  // Their frame position of (cx, cy).
  const float tx = c * (cx - m.dx) + s * (cy - m.dy);
  const float ty = -s * (cx - m.dx) + c * (cy - m.dy);
  ASSERT_EQ(map.move_to(tx, ty), Status::kOk);
  std::vector<PointXYZ> points;
  std::uint32_t seed = 7U;
  for (float y = cy - radius; y <= cy + radius; y += spacing) {
    for (float x = cx - radius; x <= cx + radius; x += spacing) {
      if ((x - cx) * (x - cx) + (y - cy) * (y - cy) > radius * radius) {
        continue;
      }
      seed = seed * 1664525U + 1013904223U;
      const float noise = 2.0F * noise_m * (static_cast<float>(seed >> 8) / 16777216.0F - 0.5F);
      points.push_back(
          PointXYZ{c * (x - m.dx) + s * (y - m.dy), -s * (x - m.dx) + c * (y - m.dy), ground(x, y) + noise});
    }
  }
  const std::vector<float> weights(points.size(), 1.0F);
  FrameCounters counters{};
  ASSERT_EQ(map.update_frame(points.data(), weights.data(), points.size(), PointXYZ{tx, ty, 1.5F}, &counters),
            Status::kOk);
  ASSERT_GT(counters.received, 5000U);
  if (out != nullptr) {
    *out = points;
    *origin = PointXYZ{tx, ty, 1.5F};
  }
}

/// Largest horizontal distance, over their points of a disc, between where the correction puts
/// them and where the motion does.
float max_error(const AlignmentResult& a, const Motion& m, float cx, float cy, float radius) {
  const RegistrationResult& k = a.correction;
  const float ck = std::cos(k.dyaw);
  const float sk = std::sin(k.dyaw);
  const float cm = std::cos(m.yaw);
  const float sm = std::sin(m.yaw);
  float worst = 0.0F;
  for (int i = 0; i < 16; ++i) {
    const float angle = 0.3927F * static_cast<float>(i);
    const float ox = cx + radius * std::cos(angle);
    const float oy = cy + radius * std::sin(angle);
    // Their coordinates of that ground point.
    const float px = cm * (ox - m.dx) + sm * (oy - m.dy);
    const float py = -sm * (ox - m.dx) + cm * (oy - m.dy);
    const float qx = ck * (px - a.centre_x_m) - sk * (py - a.centre_y_m) + a.centre_x_m + k.dx;
    const float qy = sk * (px - a.centre_x_m) + ck * (py - a.centre_y_m) + a.centre_y_m + k.dy;
    worst = std::fmax(worst, std::hypot(qx - ox, qy - oy));
  }
  return worst;
}

float rolling(float x, float y) {
  return 0.25F * std::sin(1.3F * x + 0.4F) * std::cos(0.9F * y) + 0.15F * std::sin(0.7F * y - 0.5F * x) +
         0.05F * std::cos(3.1F * x);
}

RegistrationParams registration() {
  RegistrationParams r = default_registration_params();
  r.max_iterations = 30U;
  return r;
}

TEST(CoarseAlignment, RecoversMetresAndTensOfDegreesOnAnalyticTerrain) {
  static Map ours;
  static Map theirs;
  static Aligner aligner;
  build(ours, rolling, 0.0F, 0.0F, 4.8F, Motion{0.0F, 0.0F, 0.0F});
  const Motion motions[] = {{1.0F, 0.2F, 0.1745F}, {-0.8F, 1.1F, -0.21F}, {1.2F, -1.0F, 0.26F}};
  for (const Motion& m : motions) {
    build(theirs, rolling, 0.3F, -0.2F, 3.0F, m);
    // From the identity: their map frame taken for ours.
    CoarseReport report{};
    const AlignmentResult a = aligner.align(ours, theirs, MapOffset{0.0F, 0.0F, 0.0F}, registration(),
                                            default_coarse_search_params(), &report);
    ASSERT_EQ(a.correction.status, Status::kOk) << to_string(a.correction.status);
    EXPECT_TRUE(a.correction.observable[kAxisX] && a.correction.observable[kAxisY] &&
                a.correction.observable[kAxisYaw]);
    EXPECT_NEAR(a.correction.dyaw, m.yaw, 0.002F);
    EXPECT_LT(max_error(a, m, 0.3F, -0.2F, 2.5F), 0.01F) << "motion " << m.dx << " " << m.dy << " " << m.yaw;
    EXPECT_GT(report.candidates, 1000U);
  }
  // The registration alone, from the identity, does not get there (the point of the search).
  const AlignmentResult plain = align_maps(ours, theirs, MapOffset{0.0F, 0.0F, 0.0F}, registration());
  EXPECT_TRUE(plain.correction.status != Status::kOk || max_error(plain, motions[2], 0.3F, -0.2F, 2.5F) > 0.1F);
}

TEST(CoarseAlignment, FlatGroundClaimsOnlyHeight) {
  static Map ours;
  static Map theirs;
  static Aligner aligner;
  const Ground flat = [](float, float) { return 0.2F; };
  build(ours, flat, 0.0F, 0.0F, 4.0F, Motion{0.0F, 0.0F, 0.0F});
  build(theirs, [](float, float) { return 0.2F; }, 0.0F, 0.0F, 3.0F, Motion{1.0F, 0.5F, 0.2F});
  const AlignmentResult a =
      aligner.align(ours, theirs, MapOffset{0.0F, 0.0F, 0.1F}, registration(), default_coarse_search_params(), nullptr);
  ASSERT_EQ(a.correction.status, Status::kOk) << to_string(a.correction.status);
  EXPECT_TRUE(a.correction.observable[kAxisZ]);
  EXPECT_FALSE(a.correction.observable[kAxisX] || a.correction.observable[kAxisY] ||
               a.correction.observable[kAxisYaw]);
  EXPECT_EQ(a.correction.dx, 0.0F);
  EXPECT_EQ(a.correction.dy, 0.0F);
  EXPECT_EQ(a.correction.dyaw, 0.0F);
  EXPECT_NEAR(a.correction.dz, -0.1F, 0.002F);
}

TEST(CoarseAlignment, RefusesWithoutOverlapAndBadParameters) {
  static Map ours;
  static Map theirs;
  static Aligner aligner;
  build(ours, rolling, 0.0F, 0.0F, 3.0F, Motion{0.0F, 0.0F, 0.0F});
  build(theirs, rolling, 0.0F, 0.0F, 3.0F, Motion{0.0F, 0.0F, 0.0F});
  const AlignmentResult far = aligner.align(ours, theirs, MapOffset{40.0F, 0.0F, 0.0F}, registration(),
                                            default_coarse_search_params(), nullptr);
  EXPECT_NE(far.correction.status, Status::kOk);
  EXPECT_FALSE(far.correction.observable[kAxisX]);
  CoarseSearchParams bad = default_coarse_search_params();
  bad.range_yaw_rad = NAN;
  EXPECT_EQ(aligner.align(ours, theirs, MapOffset{}, registration(), bad, nullptr).correction.status,
            Status::kInvalidArgument);
  EXPECT_EQ(aligner.align(ours, theirs, MapOffset{NAN, 0.0F, 0.0F}, registration(), default_coarse_search_params(),
                          nullptr)
                .correction.status,
            Status::kOutOfRange);
}

// align_frame: the search on their map, the registration on the frame's own points. On a sparse
// frame (one point per 4 cm cell, +-5 mm noise: about what the Lone Star scan gives) their cells
// hold a few points each; the points fix the motion better than the cells' means, checked
// against the motion applied.
TEST(CoarseAlignment, AlignFrameRegistersTheFramesPoints) {
  static Map ours;
  static Map theirs;
  static Aligner aligner;
  build(ours, rolling, 0.0F, 0.0F, 4.8F, Motion{0.0F, 0.0F, 0.0F}, 0.04F, 0.005F);
  const Motion m{0.7F, -0.5F, -0.1571F};
  std::vector<PointXYZ> points;
  PointXYZ origin{};
  build(theirs, rolling, 0.3F, -0.2F, 1.7F, m, 0.04F, 0.005F, &points, &origin);
  RegistrationParams every_point = registration();
  every_point.max_points = 16384U;
  const AlignmentResult a = aligner.align_frame(ours, theirs, points.data(), points.size(), origin, MapOffset{},
                                                every_point, default_coarse_search_params(), nullptr);
  ASSERT_EQ(a.correction.status, Status::kOk) << to_string(a.correction.status);
  EXPECT_TRUE(a.correction.observable[kAxisX] && a.correction.observable[kAxisY] &&
              a.correction.observable[kAxisYaw]);
  EXPECT_EQ(a.cells, points.size());
  EXPECT_EQ(a.correction.points_sampled, points.size());
  const float frame_error = max_error(a, m, 0.3F, -0.2F, 1.5F);
  EXPECT_LT(frame_error, 0.005F);
  const AlignmentResult cells =
      aligner.align(ours, theirs, MapOffset{}, every_point, default_coarse_search_params(), nullptr);
  ASSERT_EQ(cells.correction.status, Status::kOk) << to_string(cells.correction.status);
  EXPECT_LT(frame_error, max_error(cells, m, 0.3F, -0.2F, 1.5F));
  // A nominal offset is applied to the points as to their cells: the same answer about it.
  const MapOffset shift{0.1F, -0.05F, 0.02F};
  const AlignmentResult shifted = aligner.align_frame(ours, theirs, points.data(), points.size(), origin, shift,
                                                      every_point, default_coarse_search_params(), nullptr);
  ASSERT_EQ(shifted.correction.status, Status::kOk) << to_string(shifted.correction.status);
  EXPECT_NEAR(shifted.correction.dyaw, a.correction.dyaw, 0.003F);
  EXPECT_NEAR(shifted.correction.dz, a.correction.dz - shift.z_m, 0.002F);
  // Non-finite points are counted and skipped; bad arguments refused.
  points[3] = PointXYZ{NAN, 0.0F, 0.0F};
  const AlignmentResult with_nan = aligner.align_frame(ours, theirs, points.data(), points.size(), origin,
                                                       MapOffset{}, every_point, default_coarse_search_params(), nullptr);
  ASSERT_EQ(with_nan.correction.status, Status::kOk);
  EXPECT_EQ(with_nan.correction.points_rejected, 1U);
  EXPECT_LT(max_error(with_nan, m, 0.3F, -0.2F, 1.5F), 0.005F);
  EXPECT_EQ(aligner.align_frame(ours, theirs, nullptr, 5U, origin, MapOffset{}, every_point,
                                default_coarse_search_params(), nullptr)
                .correction.status,
            Status::kInvalidArgument);
  EXPECT_EQ(aligner.align_frame(ours, theirs, points.data(), points.size(), PointXYZ{NAN, 0.0F, 1.5F}, MapOffset{},
                                every_point, default_coarse_search_params(), nullptr)
                .correction.status,
            Status::kNonFiniteInput);
  EXPECT_EQ(aligner.align_frame(ours, theirs, points.data(), points.size(), PointXYZ{1.0e9F, 0.0F, 1.5F},
                                MapOffset{}, every_point, default_coarse_search_params(), nullptr)
                .correction.status,
            Status::kOutOfRange);
}

// A revisit: a rover maps home, drives 40 m away (home leaves its windows into patches), and
// comes back with its pose drifted by 1 m and 10 deg. Its new view of home, in the drifted
// frame, is aligned against the old patches (read into a second stack bound to the same
// storage): the correction found is the drift.
TEST(CoarseAlignment, ARevisitFindsTheDriftAgainstOldPatches) {
  using Keeper = PatchKeeper<AlignConfig, 16>;
  static Map rover;
  static Map old_map;
  static Map view;
  static Keeper keeper;
  static Keeper reader;
  static Aligner aligner;
  const std::size_t slot = Keeper::kMaxPatchBytes + platform::RegionPatchStorage::kSlotHeaderBytes;
  std::vector<std::uint8_t> region(160U * slot);
  static platform::RegionPatchStorage storage;
  ASSERT_TRUE(storage.init(region.data(), region.size(), slot));
  build(rover, rolling, 0.0F, 0.0F, 4.5F, Motion{0.0F, 0.0F, 0.0F});
  ASSERT_EQ(keeper.init(rover, storage.table()), Status::kOk);
  for (int k = 1; k <= 200; ++k) {
    const float x = 0.2F * static_cast<float>(k);
    ASSERT_EQ(keeper.move_to(x, 0.0F, PatchPose{x, 0.0F, 0.0F, 0.003F * x, 0.0001F * x}, nullptr), Status::kOk);
  }
  EXPECT_GT(keeper.counters().cells_saved, 1000U);
  EXPECT_EQ(keeper.counters().cells_lost, 0U);
  const Motion drift{0.9F, -0.5F, 0.1745F};
  build(view, rolling, 0.3F, -0.2F, 3.0F, drift);
  ASSERT_EQ(old_map.init(params()), Status::kOk);
  PatchMoveReport read{};
  ASSERT_EQ(reader.init(old_map, storage.table(), &read), Status::kOk);
  EXPECT_EQ(read.cells_restored, keeper.counters().cells_saved);  // every cell that left, each once
  const AlignmentResult a =
      aligner.align(old_map, view, MapOffset{0.0F, 0.0F, 0.0F}, registration(), default_coarse_search_params(), nullptr);
  ASSERT_EQ(a.correction.status, Status::kOk) << to_string(a.correction.status);
  EXPECT_NEAR(a.correction.dyaw, drift.yaw, 0.002F);
  EXPECT_LT(max_error(a, drift, 0.3F, -0.2F, 2.5F), 0.01F);
}

TEST(CoarseAlignment, RecoversOneMetreAndTenDegreesOnTheMarsDtm) {
  static test::Dtm dtm;
  const std::string path = test::mars_dtm_file(test::terrain_data_dir(CCMAP_TEST_DATA_DIR));
  if (!test::load_dtm(path, 1.0F / 20.0F, &dtm)) {
    GTEST_SKIP() << "real-data file " << path << " is not available (set CCMAP_DATA_DIR)";
  }
  static Map ours;
  static Map theirs;
  static Aligner aligner;
  const Ground ground = [](float x, float y) { return dtm.at(x, y); };
  // The DTM at 1/20: 3.5 x 6.1 m; ours over its middle, theirs a 1.2 m disc moved 1 m, 10 deg.
  const float cx = 1.75F;
  const float cy = 3.0F;
  build(ours, ground, cx, cy, 1.7F, Motion{0.0F, 0.0F, 0.0F});
  const Motion m{0.8F, -0.6F, 0.1745F};
  build(theirs, ground, cx + 0.2F, cy - 0.3F, 1.2F, m);
  CoarseReport report{};
  const AlignmentResult a =
      aligner.align(ours, theirs, MapOffset{0.0F, 0.0F, 0.0F}, registration(), default_coarse_search_params(), &report);
  ASSERT_EQ(a.correction.status, Status::kOk) << to_string(a.correction.status);
  EXPECT_NEAR(a.correction.dyaw, m.yaw, 0.003F);
  EXPECT_LT(max_error(a, m, cx + 0.2F, cy - 0.3F, 1.0F), 0.01F);
}

}  // namespace
}  // namespace ccmap
