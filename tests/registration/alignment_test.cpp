// Team alignment (registration/alignment.hpp): another rover's map of the same ground, built in
// a frame turned and shifted against ours by a known transform, aligned from the loaded stack,
// its snapshot and its exchange delta; flat ground; refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "ccmap/registration/alignment.hpp"
#include "support/terrain_frames.hpp"

namespace ccmap {
namespace {

using Map = Stack<CadreConfig>;
using test::Terrain;

/// Their frame against ours: p_theirs = Rz(-yaw)(p_ours - c) + c - t. The true correction of
/// their points (nominal offset 0) is then C(q) = Rz(yaw)(q + t - c) + c.
struct TheirFrame {
  double tx = 0.0, ty = 0.0, tz = 0.0, yaw = 0.0, cx = 1.5, cy = 0.0;
  PointXYZ to_theirs(const PointXYZ& p) const {
    const double cs = std::cos(-yaw), sn = std::sin(-yaw);
    const double x = p.x - cx, y = p.y - cy;
    return PointXYZ{static_cast<float>(cs * x - sn * y + cx - tx), static_cast<float>(sn * x + cs * y + cy - ty),
                    static_cast<float>(p.z - tz)};
  }
  void true_correction(double qx, double qy, double* x, double* y) const {
    const double cs = std::cos(yaw), sn = std::sin(yaw);
    const double u = qx + tx - cx, v = qy + ty - cy;
    *x = cs * u - sn * v + cx;
    *y = sn * u + cs * v + cy;
  }
};

std::unique_ptr<Map> build(Terrain terrain, const TheirFrame* frame, std::uint32_t seed0) {
  auto map = std::make_unique<Map>();
  EXPECT_EQ(map->init(default_stack_params(0.04F)), Status::kOk);
  for (std::uint32_t k = 0; k < 3; ++k) {
    test::TerrainFrameSpec spec;
    spec.terrain = terrain;
    spec.seed = seed0 + k;
    test::TerrainFrame f = test::make_terrain_frame(spec);
    if (frame != nullptr) {
      for (PointXYZ& p : f.points) p = frame->to_theirs(p);
      f.origin = frame->to_theirs(f.origin);
    }
    EXPECT_EQ(map->update_frame(f.points.data(), f.points.size(), f.origin, nullptr), Status::kOk);
  }
  return map;
}

/// Where a result puts their point q (nominal offset 0).
void apply(const AlignmentResult& a, double qx, double qy, double* x, double* y) {
  const RegistrationResult& r = a.correction;
  const double cs = std::cos(double(r.dyaw)), sn = std::sin(double(r.dyaw));
  *x = cs * (qx - a.centre_x_m) - sn * (qy - a.centre_y_m) + a.centre_x_m + r.dx;
  *y = sn * (qx - a.centre_x_m) + cs * (qy - a.centre_y_m) + a.centre_y_m + r.dy;
}

void expect_aligned(const AlignmentResult& a, const TheirFrame& t, const char* what) {
  ASSERT_EQ(a.correction.status, Status::kOk) << what << ": " << to_string(a.correction.status);
  for (int k = 0; k < 4; ++k) EXPECT_TRUE(a.correction.observable[k]) << what << ": axis " << k;
  EXPECT_NEAR(a.correction.dz, t.tz, 3.0 * a.correction.sigma_dz + 1e-3) << what;
  // Their points over the ground both maps hold land where the truth puts them.
  for (const double qx : {0.8, 1.6, 2.4, 3.2}) {
    for (const double qy : {-0.8, 0.0, 0.8}) {
      double ex = 0, ey = 0, gx = 0, gy = 0;
      t.true_correction(qx, qy, &ex, &ey);
      apply(a, qx, qy, &gx, &gy);
      EXPECT_NEAR(gx, ex, 4e-3) << what << ": their point (" << qx << ", " << qy << ") lands off in x";
      EXPECT_NEAR(gy, ey, 4e-3) << what << ": their point (" << qx << ", " << qy << ") lands off in y";
    }
  }
}

TEST(RegistrationAlignment, TheirMapTurnedAndShiftedIsAlignedFromStackSnapshotAndDelta) {
  const TheirFrame t{0.04, -0.03, 0.02, 0.015};
  auto ours = build(Terrain::kRolling, nullptr, 100U);
  auto theirs = build(Terrain::kRolling, &t, 200U);
  RegistrationParams p = default_registration_params();
  p.max_points = 20000U;  // every cell: the three sources then see the same cells
  const AlignmentResult from_stack = align_maps(*ours, *theirs, MapOffset{0.0F, 0.0F, 0.0F}, p);
  expect_aligned(from_stack, t, "loaded stack");
  EXPECT_GT(from_stack.cells, 1000U);

  std::vector<std::uint8_t> snapshot(snapshot_size<CadreConfig>());
  std::size_t written = 0;
  ASSERT_EQ(save_snapshot(*theirs, snapshot.data(), snapshot.size(), &written), Status::kOk);
  const AlignmentResult from_snapshot = align_snapshot(*ours, snapshot.data(), written, MapOffset{0.0F, 0.0F, 0.0F}, p);
  expect_aligned(from_snapshot, t, "snapshot");
  EXPECT_EQ(from_snapshot.cells, from_stack.cells);
  EXPECT_EQ(from_snapshot.correction.dx, from_stack.correction.dx) << "snapshot and stack hold the same cells";
  EXPECT_EQ(from_snapshot.correction.dyaw, from_stack.correction.dyaw);

  auto exchange = std::make_unique<MapExchange<CadreConfig>>();
  // Their origin in the team frame 3 finest cells east of ours: the nominal offset the delta carries.
  ASSERT_EQ(exchange->init(*theirs, ExchangeParams{2U, 1U, CellIndex{3, 0}, 0.0F}), Status::kOk);
  std::vector<std::uint8_t> delta(MapExchange<CadreConfig>::max_delta_size());
  ASSERT_EQ(exchange->export_delta(delta.data(), delta.size(), ExportOptions{0.0F, 0}, &written, nullptr), Status::kOk);
  const AlignmentResult from_delta = align_delta(*ours, delta.data(), written, CellIndex{3, 0}, 0.0F, p);
  expect_aligned(from_delta, t, "exchange delta");
  EXPECT_EQ(from_delta.cells, from_stack.cells) << "a first export sends every cell";
  EXPECT_NEAR(from_delta.correction.dx, from_stack.correction.dx, 2e-4) << "the delta holds the same cells";
  // The delta's origin 3 cells away from ours: the nominal offset moves their cells by 12 cm,
  // and the correction takes it back.
  const AlignmentResult shifted = align_delta(*ours, delta.data(), written, CellIndex{0, 0}, 0.0F, p);
  ASSERT_EQ(shifted.correction.status, Status::kOk) << to_string(shifted.correction.status);
  EXPECT_NEAR(shifted.correction.dx, from_delta.correction.dx - 0.12, 2e-3);
}

TEST(RegistrationAlignment, FlatGroundAlignsTheHeightOnly) {
  const TheirFrame t{0.04, -0.03, 0.02, 0.015};
  auto ours = build(Terrain::kFlat, nullptr, 100U);
  auto theirs = build(Terrain::kFlat, &t, 200U);
  const AlignmentResult a = align_maps(*ours, *theirs, MapOffset{0.0F, 0.0F, 0.0F}, default_registration_params());
  ASSERT_EQ(a.correction.status, Status::kOk);
  EXPECT_TRUE(a.correction.observable[kAxisZ]);
  EXPECT_FALSE(a.correction.observable[kAxisX] || a.correction.observable[kAxisY] || a.correction.observable[kAxisYaw]);
  EXPECT_EQ(a.correction.dx, 0.0F);
  EXPECT_EQ(a.correction.dy, 0.0F);
  EXPECT_NEAR(a.correction.dz, t.tz, 3.0 * a.correction.sigma_dz + 5e-4);
}

TEST(RegistrationAlignment, RefusalsClaimNothing) {
  auto ours = build(Terrain::kRolling, nullptr, 100U);
  auto theirs = build(Terrain::kRolling, nullptr, 200U);
  const RegistrationParams p = default_registration_params();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto refused = [](const AlignmentResult& a, Status expected, const char* what) {
    EXPECT_EQ(a.correction.status, expected) << what << ": got " << to_string(a.correction.status);
    EXPECT_EQ(a.correction.dx, 0.0F) << what;
    EXPECT_EQ(a.correction.dz, 0.0F) << what;
    EXPECT_FALSE(a.correction.observable[kAxisZ]) << what;
  };
  refused(align_maps(*ours, *theirs, MapOffset{nan, 0.0F, 0.0F}, p), Status::kOutOfRange, "a NaN offset");
  refused(align_maps(*ours, *theirs, MapOffset{0.0F, 2e5F, 0.0F}, p), Status::kOutOfRange, "an offset beyond 1e5 m");
  Map uninitialised;
  refused(align_maps(*ours, uninitialised, MapOffset{0.0F, 0.0F, 0.0F}, p), Status::kNotInitialised, "their map uninitialised");
  refused(align_maps(uninitialised, *theirs, MapOffset{0.0F, 0.0F, 0.0F}, p), Status::kNotInitialised, "ours uninitialised");
  Map other_width;
  ASSERT_EQ(other_width.init(default_stack_params(0.05F)), Status::kOk);
  refused(align_maps(*ours, other_width, MapOffset{0.0F, 0.0F, 0.0F}, p), Status::kMisaligned, "another cell width");
  refused(align_maps(*ours, *theirs, MapOffset{60.0F, 0.0F, 0.0F}, p), Status::kOutsideMap, "their map 60 m away");
  refused(align_maps(*ours, *theirs, MapOffset{-3.0F, 0.0F, 0.0F}, p), Status::kInsufficientOverlap,
          "their ground behind ours, where we saw nothing");
  std::vector<std::uint8_t> snapshot(snapshot_size<CadreConfig>());
  std::size_t written = 0;
  ASSERT_EQ(save_snapshot(*theirs, snapshot.data(), snapshot.size(), &written), Status::kOk);
  snapshot[written / 2] ^= 0x10U;
  refused(align_snapshot(*ours, snapshot.data(), written, MapOffset{0.0F, 0.0F, 0.0F}, p), Status::kCorrupt,
          "a snapshot with a flipped bit");
  refused(align_snapshot(*ours, nullptr, written, MapOffset{0.0F, 0.0F, 0.0F}, p), Status::kInvalidArgument, "no snapshot");
  std::vector<std::uint8_t> junk(200, 0x55U);
  refused(align_delta(*ours, junk.data(), junk.size(), CellIndex{0, 0}, 0.0F, p), Status::kCorrupt, "a delta of junk");
  refused(align_delta(*ours, nullptr, 10U, CellIndex{0, 0}, 0.0F, p), Status::kInvalidArgument, "no delta");
}

}  // namespace
}  // namespace ccmap
