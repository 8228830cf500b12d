// Stitching (include/ccmap/global/patch_stitcher.hpp). The analytic case: a rover drives a 6 m
// square whose odometry drifts in heading only (a constant rate per metre, sigmas growing as a
// random walk), its stack maps the terrain in the drifted frame through a PatchKeeper; a loop
// closure with the simulation's own drift is shared over the chain and the patches re-stamped.
// Checked against the simulated truth: every patch written after the anchor carries, read back
// from the storage, the true correction (truth after odometry pose, in the anchor's frame) of a
// frame no farther from the patch than its writer; no patch of the anchor or before changes; the cells of every patch are bytewise untouched; the
// work per restamp_step stays within its max_patches. Refusals are counted, never crash.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "ccmap/global/patch_stitcher.hpp"
#include "support/global_configs.hpp"

namespace ccmap {
namespace {

using StitchConfig = test::OneCcm8cmConfig;  // patches of 1.28 m
using Map = Stack<StitchConfig>;
using Keeper = PatchKeeper<StitchConfig, 16>;
using Pose = test::DrivePose;
using Stitcher = PatchStitcher<256, 512>;
constexpr std::size_t kSlotBytes = Keeper::kMaxPatchBytes + platform::RegionPatchStorage::kSlotHeaderBytes;

double terrain(double x, double y) { return 0.3 * std::sin(0.7 * x) + 0.2 * std::cos(0.5 * y) + 0.02 * x; }

/// The ground within 1 m of the true pose, as the rover places it with its believed pose.
std::vector<PointXYZ> frame(const Pose& truth, const Pose& believed) {
  return test::ground_seen_from(truth, believed, 1.0, 0.05, terrain);
}

constexpr double kStep = 0.3;   // m per move
constexpr double kRate = 0.01;  // heading drift, rad per metre
constexpr int kPerSide = 20;    // a 6 m square

struct Drive {
  Map map;
  Keeper keeper;
  Stitcher stitcher;
  std::vector<std::uint8_t> region = std::vector<std::uint8_t>(512U * kSlotBytes);
  platform::RegionPatchStorage storage;
  std::vector<Pose> truth, believed;  // per node
  std::vector<PatchPose> stamps;
  Drive() {
    StackParams params = default_stack_params(0.08F);
    params.free_space_rays = 0.0F;
    EXPECT_EQ(map.init(params), Status::kOk);
    EXPECT_TRUE(storage.init(region.data(), region.size(), kSlotBytes));
    EXPECT_EQ(keeper.init(map, storage.table()), Status::kOk);
    EXPECT_EQ(stitcher.attach(keeper), Status::kOk);
    Pose t{0.0, 0.0, 0.0}, b{0.0, 0.0, 0.0};
    double travelled = 0.0;
    for (int leg = 0; leg < 4; ++leg) {
      for (int k = 0; k < kPerSide; ++k) {
        const PatchPose stamp{static_cast<float>(b.x), static_cast<float>(b.y), static_cast<float>(b.yaw),
                              static_cast<float>(0.02 * std::sqrt(travelled)),
                              static_cast<float>(0.01 * std::sqrt(travelled))};
        PatchMoveReport report{};
        EXPECT_EQ(stitcher.move_to(keeper, stamp.x_m, stamp.y_m, stamp, &report), Status::kOk);
        const auto points = frame(t, b);
        EXPECT_EQ(map.update_frame(points.data(), points.size(), PointXYZ{stamp.x_m, stamp.y_m, 1.0F}, nullptr),
                  Status::kOk);
        truth.push_back(t);
        believed.push_back(b);
        stamps.push_back(stamp);
        const double turn = k == kPerSide - 1 ? M_PI / 2.0 : 0.0;
        t = Pose{t.x + kStep * std::cos(t.yaw), t.y + kStep * std::sin(t.yaw), t.yaw + turn};
        b = Pose{b.x + kStep * std::cos(b.yaw), b.y + kStep * std::sin(b.yaw), b.yaw + turn + kRate * kStep};
        travelled += kStep;
      }
    }
  }
  /// The truth of node k seen from the anchor's believed pose (the frame the closure keeps).
  [[nodiscard]] Pose reference(std::size_t anchor, std::size_t k) const {
    const double turn = believed[anchor].yaw - truth[anchor].yaw;
    const double c = std::cos(turn), s = std::sin(turn);
    const double dx = truth[k].x - truth[anchor].x, dy = truth[k].y - truth[anchor].y;
    return Pose{believed[anchor].x + c * dx - s * dy, believed[anchor].y + s * dx + c * dy, truth[k].yaw + turn};
  }
};

/// Calls fn(key, header, bytes) for every stored patch over the drive's tiles (8 cm cells, 16 a tile).
template <typename Fn>
void for_each_patch(Drive& d, Fn&& fn) {
  std::vector<std::uint8_t> buffer(Keeper::kMaxPatchBytes);
  for (std::int32_t ty = -8; ty <= 8; ++ty) {
    for (std::int32_t tx = -8; tx <= 8; ++tx) {
      PatchHeader h{};
      const platform::PatchKey key{0, tx, ty};
      const Status s = d.keeper.read_patch(key, buffer.data(), buffer.size(), &h);
      if (s == Status::kOk) {
        fn(key, h, buffer);
      } else {
        EXPECT_EQ(s, Status::kUnknown);
      }
    }
  }
}

/// The node whose stamp a header carries (bitwise), or -1.
int node_of(const Drive& d, const PatchHeader& h) {
  for (std::size_t k = 0; k < d.stamps.size(); ++k) {
    if (std::memcmp(&d.stamps[k], &h.pose, sizeof h.pose) == 0) {
      return static_cast<int>(k);
    }
  }
  return -1;
}

TEST(PatchStitcher, AHeadingDriftIsRemovedFromEveryPatchWrittenSinceTheAnchor) {
  const auto d = std::make_unique<Drive>();
  const std::size_t anchor = 10U;
  const std::size_t last = d->truth.size() - 1U;
  ASSERT_EQ(d->stitcher.node_count(), d->truth.size());
  // Before: every patch's corrected pose is its writing pose, and the cells as written.
  std::vector<std::vector<std::uint8_t>> before;
  int patches = 0;
  int after_anchor = 0;
  for_each_patch(*d, [&](const platform::PatchKey&, const PatchHeader& h, const std::vector<std::uint8_t>& bytes) {
    EXPECT_EQ(h.corrected.x_m, h.pose.x_m);
    EXPECT_EQ(h.corrected.yaw_rad, h.pose.yaw_rad);
    const int k = node_of(*d, h);
    ASSERT_GE(k, 0);
    after_anchor += static_cast<std::size_t>(k) > anchor ? 1 : 0;
    before.push_back(bytes);
    ++patches;
  });
  EXPECT_GT(patches, 20);
  EXPECT_GT(after_anchor, 15);
  // The closure: the drift of the last node relative to the anchor, from the simulation.
  const Pose ref = d->reference(anchor, last);
  const Pose& b = d->believed[last];
  EXPECT_GT(std::fabs(ref.yaw - b.yaw), 0.2);  // 0.01 rad/m over 21 m
  ASSERT_EQ(d->stitcher.close_loop(anchor, static_cast<float>(ref.x - b.x), static_cast<float>(ref.y - b.y),
                                   static_cast<float>(ref.yaw - b.yaw)),
            Status::kOk);
  EXPECT_GE(d->stitcher.pending(), static_cast<std::uint32_t>(after_anchor));
  // Re-stamped two patches per call at most.
  std::uint32_t restamped = 0U;
  int calls = 0;
  StitchReport r{};
  do {
    d->stitcher.restamp_step(d->keeper, 2U, &r);
    EXPECT_LE(r.restamped + r.failed, 2U);
    EXPECT_EQ(r.failed, 0U);
    restamped += r.restamped;
    ++calls;
  } while (r.remaining > 0U && calls < 1000);
  EXPECT_EQ(r.remaining, 0U);
  EXPECT_EQ(restamped, static_cast<std::uint32_t>(after_anchor));
  EXPECT_EQ(calls, (after_anchor + 1) / 2);
  // After: the truth in the anchor's frame, or the pose unchanged; the cells bytewise as before.
  std::size_t i = 0U;
  double worst_m = 0.0;
  int nearer = 0;  // patches that took another node's correction than their writer's
  for_each_patch(*d, [&](const platform::PatchKey& key, const PatchHeader& h, const std::vector<std::uint8_t>& bytes) {
    const double key_x = key.tile_x, key_y = key.tile_y;
    const int k = node_of(*d, h);
    ASSERT_GE(k, 0);
    if (static_cast<std::size_t>(k) <= anchor) {
      EXPECT_EQ(std::memcmp(&h.corrected, &h.pose, sizeof h.corrected), 0);
    } else {
      // The header's correction M = C W^-1 applied to the believed pose of a node j must give
      // that node's true pose, for a node j no farther from the tile's centre than the writer.
      const double turn = static_cast<double>(h.corrected.yaw_rad) - h.pose.yaw_rad;
      const double c = std::cos(turn), s = std::sin(turn);
      const double tile = 16 * 0.08;
      const double cx = (key_x + 0.5) * tile, cy = (key_y + 0.5) * tile;
      const auto far = [&](std::size_t j) { return std::hypot(d->believed[j].x - cx, d->believed[j].y - cy); };
      double best = 1e9;
      for (std::size_t j = 0; j <= static_cast<std::size_t>(k); ++j) {
        const Pose& bj = d->believed[j];
        const Pose want = d->reference(anchor, j);
        const double x = h.corrected.x_m + c * (bj.x - h.pose.x_m) - s * (bj.y - h.pose.y_m);
        const double y = h.corrected.y_m + s * (bj.x - h.pose.x_m) + c * (bj.y - h.pose.y_m);
        const double error = std::hypot(x - want.x, y - want.y) + std::fabs(bj.yaw + turn - want.yaw);
        if (far(j) <= far(static_cast<std::size_t>(k)) + 1e-6) {
          best = std::fmin(best, error);
        }
      }
      worst_m = std::fmax(worst_m, best);
      nearer += std::hypot(h.corrected.x_m - d->reference(anchor, k).x, h.corrected.y_m - d->reference(anchor, k).y) >
                        1e-3
                    ? 1
                    : 0;
    }
    ASSERT_LT(i, before.size());
    const std::size_t size = Keeper::patch_size(0);
    EXPECT_EQ(std::memcmp(bytes.data() + detail::kPatchHeaderBytes, before[i].data() + detail::kPatchHeaderBytes,
                          size - detail::kPatchHeaderBytes - 4U),
              0);
    EXPECT_EQ(std::memcmp(bytes.data(), before[i].data(), detail::kPatchCorrectedOffset), 0);
    ++i;
  });
  EXPECT_LT(worst_m, 2e-4);
  EXPECT_GT(nearer, 10);
  // The drift was large: the uncorrected poses are off by decimetres.
  const Pose mid = d->reference(anchor, 50U);
  EXPECT_GT(std::hypot(d->believed[50].x - mid.x, d->believed[50].y - mid.y), 0.3);
}

TEST(PatchStitcher, RefusalsAreCountedAndChangeNothing) {
  const auto d = std::make_unique<Drive>();
  const std::uint32_t moves = d->keeper.counters().moves;
  // A stamp whose sigmas shrink: refused before the keeper moves.
  const PatchPose shrinking{0.0F, 0.0F, 0.0F, 0.0F, 0.0F};
  PatchMoveReport report{};
  EXPECT_EQ(d->stitcher.move_to(d->keeper, 0.0F, 0.0F, shrinking, &report), Status::kInvalidArgument);
  EXPECT_EQ(d->keeper.counters().moves, moves);
  // Closures the chain refuses.
  EXPECT_EQ(d->stitcher.close_loop(d->truth.size() - 1U, 0.1F, 0.0F, 0.0F), Status::kInvalidArgument);
  EXPECT_EQ(d->stitcher.close_loop(0U, NAN, 0.0F, 0.0F), Status::kInvalidArgument);
  EXPECT_EQ(d->stitcher.pending(), 0U);
  // A damaged patch: its re-stamp fails, counted; the others are done.
  std::size_t damaged = 0U;
  for (std::size_t s = 0; s < d->storage.slots() && damaged == 0U; ++s) {
    std::uint8_t* slot = d->region.data() + s * kSlotBytes;
    std::uint32_t used = 0U;
    std::memcpy(&used, slot, 4U);
    if (used != 0U) {
      slot[platform::RegionPatchStorage::kSlotHeaderBytes + 200U] ^= 0x01U;
      damaged = 1U;
    }
  }
  ASSERT_EQ(damaged, 1U);
  ASSERT_EQ(d->stitcher.close_loop(0U, 0.5F, -0.2F, 0.1F), Status::kOk);
  const std::uint32_t marked = d->stitcher.pending();
  StitchReport r{};
  d->stitcher.restamp_step(d->keeper, 100000U, &r);
  EXPECT_EQ(r.remaining, 0U);
  EXPECT_EQ(r.failed, 1U);
  EXPECT_EQ(r.restamped + r.failed, marked);
  EXPECT_EQ(d->stitcher.restamp_failures(), 1U);
  EXPECT_GE(d->keeper.counters().patches_refused, 1U);
  // A restamp of a patch that was never written, and of a bad pose.
  EXPECT_EQ(d->keeper.restamp(platform::PatchKey{0, 1000, 1000}, PlanarPose{0.0F, 0.0F, 0.0F}), Status::kUnknown);
  EXPECT_EQ(d->keeper.restamp(platform::PatchKey{0, 0, 0}, PlanarPose{INFINITY, 0.0F, 0.0F}),
            Status::kInvalidArgument);
  EXPECT_EQ(d->keeper.restamp(platform::PatchKey{3, 0, 0}, PlanarPose{0.0F, 0.0F, 0.0F}), Status::kInvalidArgument);
}

TEST(PatchStitcher, AFullChainOrLogStillMovesAndCountsTheUntrackedWrites) {
  auto map = std::make_unique<Map>();
  auto keeper = std::make_unique<Keeper>();
  auto stitcher = std::make_unique<PatchStitcher<4, 2>>();
  std::vector<std::uint8_t> region(64U * kSlotBytes);
  platform::RegionPatchStorage storage;
  StackParams params = default_stack_params(0.08F);
  params.free_space_rays = 0.0F;
  ASSERT_EQ(map->init(params), Status::kOk);
  ASSERT_TRUE(storage.init(region.data(), region.size(), kSlotBytes));
  ASSERT_EQ(keeper->init(*map, storage.table()), Status::kOk);
  EXPECT_EQ(stitcher->attach(*keeper), Status::kOk);
  std::uint32_t written = 0U;
  for (int k = 0; k < 12; ++k) {
    const float x = 0.5F * static_cast<float>(k);
    const Pose p{x, 0.0, 0.0};
    PatchMoveReport report{};
    ASSERT_EQ(stitcher->move_to(*keeper, x, 0.0F, PatchPose{x, 0.0F, 0.0F, 0.01F * x, 0.001F * x}, &report),
              Status::kOk);
    written += report.patches_written;
    const auto points = frame(p, p);
    ASSERT_EQ(map->update_frame(points.data(), points.size(), PointXYZ{x, 0.0F, 1.0F}, nullptr), Status::kOk);
  }
  EXPECT_EQ(keeper->counters().moves, 12U);
  EXPECT_EQ(stitcher->node_count(), 4U);
  EXPECT_EQ(stitcher->logged_patches(), 2U);
  EXPECT_GT(written, 2U);
  EXPECT_GT(stitcher->untracked_writes(), 0U);
  EXPECT_LE(stitcher->untracked_writes(), written);
}

}  // namespace
}  // namespace ccmap
