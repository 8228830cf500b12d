// Patches that outlive the window (include/ccmap/global/patch_keeper.hpp). A stack driven out
// and back through a PatchKeeper is checked against independent references: a stack whose
// window is wide enough never to scroll, fed the same points (bitwise, cell by cell); a
// double-precision batch of the points of each cell; stacks that never moved (multi-layer).
// Storage refusals and damaged patches are counted, never crash, never restore bad cells; the
// per-move patch writes stay within the stated bounds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "ccmap/global/patch_keeper.hpp"
#include "support/global_configs.hpp"

namespace ccmap {
namespace {

// One CCM layer of 32 x 32 cells of 8 cm (+-1.28 m), and the wide map of the same cells that
// never scrolls (SingleCcmConfig: 256 x 256, +-10.24 m).
using SmallCcmConfig = test::OneCcm8cmConfig;
// Three layers (Kalman 4 cm, CCM 8 and 16 cm), 32 cells a side.
struct SmallStackConfig {
  static constexpr FineKind kFineKind = FineKind::kKalman;
  static constexpr CcmCellKind kCcmCell = CcmCellKind::kFull;
  static constexpr std::int32_t kFineSide = 32;
  static constexpr std::array<std::int32_t, 2> kCcmSides{{32, 32}};
  static constexpr float kDefaultFinestCellWidthM = 0.04F;
};

using Small = Stack<SmallCcmConfig>;
using Wide = Stack<SingleCcmConfig>;
using SmallKeeper = PatchKeeper<SmallCcmConfig, 16>;

StackParams exact_params(float width) {
  StackParams p = default_stack_params(width);
  p.outlier_gate_sigma = 0.0F;
  p.free_space_rays = 0.0F;
  p.weight_limit = kNoWeightLimit;
  return p;
}

/// Analytic terrain (m).
float terrain(float x, float y) { return 0.3F * std::sin(0.7F * x) + 0.2F * std::cos(0.5F * y) + 0.02F * x; }

/// Deterministic points around (cx, cy) within +-half m, on the terrain with a small
/// deterministic ripple (so cells have a spread), the frame's seed varying them.
std::vector<PointXYZ> frame_points(float cx, float cy, float half, int count, std::uint32_t seed) {
  std::vector<PointXYZ> out;
  std::uint32_t s = seed * 2654435761U + 12345U;
  auto next = [&s]() {
    s = s * 1664525U + 1013904223U;
    return static_cast<float>(s >> 8) / 16777216.0F;
  };
  for (int i = 0; i < count; ++i) {
    const float x = cx + (2.0F * next() - 1.0F) * half;
    const float y = cy + (2.0F * next() - 1.0F) * half;
    out.push_back(PointXYZ{x, y, terrain(x, y) + 0.004F * (next() - 0.5F)});
  }
  return out;
}

/// Every cell of two CCM grids at the same global indices, bitwise.
template <typename GridA, typename GridB>
int count_cell_differences(const GridA& a, const GridB& b) {
  int differences = 0;
  a.for_each([&](CellIndex index, const auto& cell) {
    const auto* other = b.cell(index);
    if (other == nullptr) {
      differences += cell.weight > 0.0F ? 1 : 0;
      return;
    }
    differences += std::memcmp(&cell, other, sizeof cell) != 0 ? 1 : 0;
  });
  return differences;
}

struct Region {
  std::vector<std::uint8_t> bytes;
  platform::RegionPatchStorage storage;
  Region(std::size_t slots, std::size_t slot_bytes) : bytes(slots * slot_bytes) {
    EXPECT_TRUE(storage.init(bytes.data(), bytes.size(), slot_bytes));
  }
};

constexpr std::size_t kSlotBytes = SmallKeeper::kMaxPatchBytes + platform::RegionPatchStorage::kSlotHeaderBytes;

/// The drive: 8 m out along x (inside the wide map's +-10.24 m with the points' reach), a
/// sideways wiggle, and back, 0.1 m per frame.
std::vector<std::pair<float, float>> drive() {
  std::vector<std::pair<float, float>> poses;
  for (int k = 0; k <= 80; ++k) {
    poses.emplace_back(0.1F * static_cast<float>(k), 0.6F * std::sin(0.05F * static_cast<float>(k)));
  }
  for (int k = 80; k >= 0; --k) {
    poses.emplace_back(0.1F * static_cast<float>(k) + 0.03F, -0.4F * std::sin(0.04F * static_cast<float>(k)));
  }
  return poses;
}

/// Drives `map` through a keeper on `storage` and `wide` standing still at the origin, both fed
/// the same points (inside the small window); returns the points fed.
std::vector<PointXYZ> drive_both(Small& map, SmallKeeper& keeper, Wide& wide) {
  std::vector<PointXYZ> all;
  const auto poses = drive();
  std::uint32_t seed = 1U;
  for (const auto& [x, y] : poses) {
    PatchMoveReport report{};
    EXPECT_EQ(keeper.move_to(x, y, PatchPose{x, y, 0.0F, 0.01F, 0.001F}, &report), Status::kOk);
    EXPECT_LE(report.patches_written, SmallKeeper::max_writes_per_step());
    const auto points = frame_points(x, y, 1.1F, 400, seed++);
    const PointXYZ origin{x, y, 1.0F};
    FrameCounters small_counters{};
    FrameCounters wide_counters{};
    const std::vector<float> weights(points.size(), 1.0F);
    EXPECT_EQ(map.update_frame(points.data(), weights.data(), points.size(), origin, &small_counters), Status::kOk);
    EXPECT_EQ(wide.update_frame(points.data(), weights.data(), points.size(), origin, &wide_counters), Status::kOk);
    EXPECT_EQ(small_counters.received, wide_counters.received);
    all.insert(all.end(), points.begin(), points.end());
  }
  return all;
}

/// The small map with its keeper on a region, and the wide map, after drive_both.
struct DrivenPair {
  Small map;
  Wide wide;
  SmallKeeper keeper;
  Region region{256, kSlotBytes};
  std::vector<PointXYZ> points;
  DrivenPair() {
    EXPECT_EQ(map.init(exact_params(0.08F)), Status::kOk);
    EXPECT_EQ(wide.init(exact_params(0.08F)), Status::kOk);
    EXPECT_EQ(keeper.init(map, region.storage.table()), Status::kOk);
    points = drive_both(map, keeper, wide);
  }
};

TEST(PatchKeeper, DriveOutAndBackEqualsAMapThatNeverScrolledBitwise) {
  const auto pair = std::make_unique<DrivenPair>();
  Small& map = pair->map;
  Wide& wide = pair->wide;
  SmallKeeper& keeper = pair->keeper;
  // Back home: the window's cells equal the wide map's.
  int observed = 0;
  map.ccm_layer(0).for_each([&](CellIndex, const CcmCell& c) { observed += c.weight > 0.0F ? 1 : 0; });
  EXPECT_GT(observed, 900);
  EXPECT_EQ(count_cell_differences(map.ccm_layer(0), wide.ccm_layer(0)), 0);
  EXPECT_GT(keeper.counters().cells_restored, 1000U);
  EXPECT_EQ(keeper.counters().cells_lost, 0U);
  // And everywhere along the drive: move the window over it again and compare.
  for (float x = 0.0F; x <= 8.0F; x += 1.0F) {
    ASSERT_EQ(keeper.move_to(x, 0.0F, PatchPose{x, 0.0F, 0.0F, 0.0F, 0.0F}, nullptr), Status::kOk);
    EXPECT_EQ(count_cell_differences(map.ccm_layer(0), wide.ccm_layer(0)), 0) << "at x = " << x;
  }
}

TEST(PatchKeeper, RestoredCellsEqualADoubleBatchOfTheirPoints) {
  const auto pair = std::make_unique<DrivenPair>();
  const Small& map = pair->map;
  const std::vector<PointXYZ>& points = pair->points;
  // The batch: per cell of 8 cm, the count, mean and height variance of its points, in double.
  struct Batch {
    double n = 0.0, sx = 0.0, sy = 0.0, sz = 0.0, szz = 0.0;
  };
  std::map<std::pair<int, int>, Batch> batch;
  for (const PointXYZ& p : points) {
    Batch& b = batch[{static_cast<int>(std::floor(p.x / 0.08)), static_cast<int>(std::floor(p.y / 0.08))}];
    b.n += 1.0;
    b.sx += p.x;
    b.sy += p.y;
    b.sz += p.z;
    b.szz += static_cast<double>(p.z) * p.z;
  }
  int compared = 0;
  map.ccm_layer(0).for_each([&](CellIndex index, const CcmCell& c) {
    const auto found = batch.find({index.x, index.y});
    if (found == batch.end()) {
      EXPECT_EQ(c.weight, 0.0F);
      return;
    }
    const Batch& b = found->second;
    const double mean_z = b.sz / b.n;
    const double centre_x = (index.x + 0.5) * 0.08;
    EXPECT_EQ(static_cast<double>(c.weight), b.n);
    EXPECT_NEAR(c.mean_z, mean_z, 2e-6);
    EXPECT_NEAR(c.mean_x, b.sx / b.n - centre_x, 2e-6);
    EXPECT_NEAR(c.s_zz, b.szz - b.n * mean_z * mean_z, 1e-5 + 1e-3 * c.s_zz);
    ++compared;
  });
  EXPECT_GT(compared, 900);
}

TEST(PatchKeeper, EveryLayerOfAStackComesBackAsAStackThatNeverMovedHasIt) {
  using Config = SmallStackConfig;
  using Keeper = PatchKeeper<Config, 16>;
  static Stack<Config> map;
  static Stack<Config> home;  // never moves from the origin
  static Stack<Config> away;  // never moves from (30, 5)
  static Keeper keeper;
  Region region(128, Keeper::kMaxPatchBytes + platform::RegionPatchStorage::kSlotHeaderBytes);
  for (Stack<Config>* s : {&map, &home, &away}) {
    ASSERT_EQ(s->init(exact_params(0.04F)), Status::kOk);
  }
  ASSERT_EQ(away.move_to(30.0F, 5.0F), Status::kOk);
  ASSERT_EQ(keeper.init(map, region.storage.table()), Status::kOk);
  auto feed = [](Stack<Config>& s, float x, float y, std::uint32_t seed) {
    const auto points = frame_points(x, y, 2.5F, 3000, seed);
    const std::vector<float> weights(points.size(), 1.0F);
    const PointXYZ origin{x, y, 0.8F};
    ASSERT_EQ(s.update_frame(points.data(), weights.data(), points.size(), origin, nullptr), Status::kOk);
  };
  auto go = [&](float x0, float y0, float x1, float y1) {
    for (int k = 1; k <= 50; ++k) {
      const float t = static_cast<float>(k) / 50.0F;
      const float x = x0 + (x1 - x0) * t;
      const float y = y0 + (y1 - y0) * t;
      PatchMoveReport r{};
      ASSERT_EQ(keeper.move_to(x, y, PatchPose{x, y, 0.0F, 0.0F, 0.0F}, &r), Status::kOk);
      EXPECT_LE(r.patches_written, Keeper::max_writes_per_step());
    }
  };
  for (std::uint32_t f = 1; f <= 3; ++f) {
    feed(map, 0.0F, 0.0F, f);
    feed(home, 0.0F, 0.0F, f);
  }
  go(0.0F, 0.0F, 30.0F, 5.0F);
  for (std::uint32_t f = 10; f <= 12; ++f) {
    feed(map, 30.0F, 5.0F, f);
    feed(away, 30.0F, 5.0F, f);
  }
  go(30.0F, 5.0F, 0.0F, 0.0F);
  feed(map, 0.0F, 0.0F, 20U);
  feed(home, 0.0F, 0.0F, 20U);
  auto same = [](const Stack<Config>& a, const Stack<Config>& b) {
    int differences = count_cell_differences(a.fine_layer(), b.fine_layer());
    for (int i = 0; i < Stack<Config>::kCcmLayerCount; ++i) {
      differences += count_cell_differences(a.ccm_layer(i), b.ccm_layer(i));
    }
    return differences;
  };
  EXPECT_EQ(same(map, home), 0);
  // A jump straight back out (the whole window leaves at once): within max_writes_per_move().
  PatchMoveReport jump{};
  ASSERT_EQ(keeper.move_to(30.0F, 5.0F, PatchPose{30.0F, 5.0F, 0.0F, 0.0F, 0.0F}, &jump), Status::kOk);
  EXPECT_LE(jump.patches_written, Keeper::max_writes_per_move());
  EXPECT_GT(jump.cells_restored, 0U);
  EXPECT_EQ(same(map, away), 0);
  EXPECT_EQ(map.state_status(), Status::kOk);
  EXPECT_EQ(keeper.counters().cells_lost, 0U);
  EXPECT_EQ(keeper.counters().patches_refused, 0U);
}

// The paper's 9-float cell, with Kalman and OMG fine layers: each layer's cells after a drive
// 20 m away and back are bitwise those before it (the state before leaving is the reference).
template <typename Config>
void check_round_trip(FineKind fine) {
  using Keeper = PatchKeeper<Config, 16>;
  const auto map = std::make_unique<Stack<Config>>();
  const auto keeper = std::make_unique<Keeper>();
  Region region(64, Keeper::kMaxPatchBytes + platform::RegionPatchStorage::kSlotHeaderBytes);
  ASSERT_EQ(map->init(exact_params(0.04F)), Status::kOk);
  ASSERT_EQ(keeper->init(*map, region.storage.table()), Status::kOk);
  const auto points = frame_points(0.0F, 0.0F, 2.5F, 4000, 3U);
  const std::vector<float> weights(points.size(), 1.0F);
  ASSERT_EQ(map->update_frame(points.data(), weights.data(), points.size(), PointXYZ{0.0F, 0.0F, 0.8F}, nullptr),
            Status::kOk);
  auto cells = [&map]() {
    std::vector<std::uint8_t> bytes;
    auto add = [&bytes](CellIndex, const auto& c) {
      const auto* b = reinterpret_cast<const std::uint8_t*>(&c);
      bytes.insert(bytes.end(), b, b + sizeof c);
    };
    map->fine_layer().for_each(add);
    for (int i = 0; i < Stack<Config>::kCcmLayerCount; ++i) {
      map->ccm_layer(i).for_each(add);
    }
    return bytes;
  };
  const std::vector<std::uint8_t> before = cells();
  for (const float x : {5.0F, 10.0F, 20.0F, 10.0F, 0.0F}) {
    ASSERT_EQ(keeper->move_to(x, 0.0F, PatchPose{x, 0.0F, 0.0F, 0.0F, 0.0F}, nullptr), Status::kOk);
  }
  EXPECT_GT(keeper->counters().cells_restored, 1000U) << static_cast<int>(fine);
  EXPECT_TRUE(cells() == before) << static_cast<int>(fine);
  // Every restored cell carries its integrity check (Stack::cell_intact, what the scrub verifies).
  int broken = 0;
  map->fine_layer().for_each([&](CellIndex, const auto& c) { broken += map->cell_intact(c) ? 0 : 1; });
  for (int i = 0; i < Stack<Config>::kCcmLayerCount; ++i) {
    map->ccm_layer(i).for_each([&](CellIndex, const auto& c) { broken += map->cell_intact(c) ? 0 : 1; });
  }
  EXPECT_EQ(broken, 0);
  EXPECT_EQ(map->state_status(), Status::kOk);
}

struct PaperKalmanConfig : SmallStackConfig {
  // cppcheck-suppress duplInheritedMember ; the point of the derived configuration
  static constexpr CcmCellKind kCcmCell = CcmCellKind::kPaper;
};
struct FullOmgConfig : SmallStackConfig {
  // cppcheck-suppress duplInheritedMember ; the point of the derived configuration
  static constexpr FineKind kFineKind = FineKind::kOmg;
};

TEST(PatchKeeper, EveryCellKindComesBackBitwise) {
  check_round_trip<PaperKalmanConfig>(FineKind::kKalman);
  check_round_trip<FullOmgConfig>(FineKind::kOmg);
}

TEST(PatchKeeper, AFullStorageLosesCellsCountedAndTheMoveStillHappens) {
  static Small map;
  static SmallKeeper keeper;
  Region region(2, kSlotBytes);
  ASSERT_EQ(map.init(exact_params(0.08F)), Status::kOk);
  ASSERT_EQ(keeper.init(map, region.storage.table()), Status::kOk);
  const auto points = frame_points(0.0F, 0.0F, 1.2F, 4000, 7U);
  ASSERT_EQ(map.update_frame(points.data(), points.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
  PatchMoveReport r{};
  ASSERT_EQ(keeper.move_to(20.0F, 0.0F, PatchPose{20.0F, 0.0F, 0.0F, 0.0F, 0.0F}, &r), Status::kOk);
  EXPECT_EQ(r.patches_written, 2U);
  EXPECT_GT(r.cells_lost, 0U);
  EXPECT_EQ(keeper.counters().write_failures, 2U);  // the window at the origin covers 2 x 2 tiles, 2 slots
  EXPECT_EQ(keeper.counters().cells_lost + keeper.counters().cells_saved,
            static_cast<std::uint64_t>(r.cells_saved) + r.cells_lost);
  EXPECT_EQ(map.layer_centre(0).x, 2 * static_cast<std::int32_t>(std::floor(20.0F / 0.16F + 0.5F)));
}

TEST(PatchKeeper, ADamagedPatchIsRefusedAndNothingOfItRestored) {
  static Small map;
  static SmallKeeper keeper;
  Region region(16, kSlotBytes);
  ASSERT_EQ(map.init(exact_params(0.08F)), Status::kOk);
  ASSERT_EQ(keeper.init(map, region.storage.table()), Status::kOk);
  const auto points = frame_points(0.0F, 0.0F, 1.2F, 4000, 9U);
  ASSERT_EQ(map.update_frame(points.data(), points.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
  // The first patch written is tile (-1, -1): cells [-16, -1] on both axes.
  auto in_first_tile = [](CellIndex i) { return i.x >= -16 && i.x < 0 && i.y >= -16 && i.y < 0; };
  std::uint32_t first_tile_cells = 0U;
  map.ccm_layer(0).for_each(
      [&](CellIndex i, const CcmCell& c) { first_tile_cells += in_first_tile(i) && c.weight > 0.0F ? 1U : 0U; });
  ASSERT_GT(first_tile_cells, 100U);
  PatchMoveReport out{};
  ASSERT_EQ(keeper.move_to(20.0F, 0.0F, PatchPose{20.0F, 0.0F, 0.0F, 0.0F, 0.0F}, &out), Status::kOk);
  ASSERT_EQ(out.patches_written, 4U);
  // One bit of the first slot's patch body flipped: that patch fails its CRC.
  region.bytes[platform::RegionPatchStorage::kSlotHeaderBytes + detail::kPatchHeaderBytes + 100U] ^= 0x10U;
  PatchMoveReport back{};
  ASSERT_EQ(keeper.move_to(0.0F, 0.0F, PatchPose{}, &back), Status::kOk);
  EXPECT_EQ(back.patches_read, 3U);
  EXPECT_EQ(keeper.counters().patches_refused, 1U);
  EXPECT_EQ(back.cells_restored + first_tile_cells, out.cells_saved);
  map.ccm_layer(0).for_each([&](CellIndex i, const CcmCell& c) { EXPECT_FALSE(in_first_tile(i) && c.weight > 0.0F); });
  EXPECT_EQ(map.state_status(), Status::kOk);
  // Bad stamps and positions: refused, nothing written.
  EXPECT_EQ(keeper.move_to(1.0F, 0.0F, PatchPose{0.0F, 0.0F, 0.0F, -1.0F, 0.0F}, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(keeper.move_to(NAN, 0.0F, PatchPose{}, nullptr), Status::kNonFiniteInput);
  EXPECT_EQ(keeper.counters().moves, 2U);
  SmallKeeper unbound;
  EXPECT_EQ(unbound.move_to(0.0F, 0.0F, PatchPose{}, nullptr), Status::kNotInitialised);
}

TEST(PatchKeeper, AnUpsetCellComesBackDistrusted) {
  // A cell an upset damaged answers unknown with the reason upset; leaving the window and coming
  // back through a patch must not turn that into "never observed" (which another layer, or the
  // planner's tolerance of unknown area, could answer for), until points observe it again.
  static Small map;
  static SmallKeeper keeper;
  Region region(16, kSlotBytes);
  ASSERT_EQ(map.init(exact_params(0.08F)), Status::kOk);
  ASSERT_EQ(keeper.init(map, region.storage.table()), Status::kOk);
  const auto points = frame_points(0.0F, 0.0F, 1.2F, 4000, 11U);
  ASSERT_EQ(map.update_frame(points.data(), points.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
  // A known place, and a known place beside it in another patch tile.
  float px = 0.0F, py = 0.0F, qx = 0.0F, qy = 0.0F;
  for (int i = 0; i < 100 && !(map.query(px, py).status == Status::kOk); ++i) {
    px = 0.04F + 0.08F * static_cast<float>(i % 10);
    py = 0.04F + 0.08F * static_cast<float>(i / 10);
  }
  for (int i = 0; i < 100 && !(map.query(qx, qy).status == Status::kOk); ++i) {
    qx = -0.04F - 0.08F * static_cast<float>(i % 10);
    qy = -0.04F - 0.08F * static_cast<float>(i / 10);
  }
  ASSERT_EQ(map.query(px, py).status, Status::kOk);
  ASSERT_EQ(map.query(qx, qy).status, Status::kOk);
  const CcmCell* cell = map.ccm_layer(0).cell_at(px, py);
  ASSERT_NE(cell, nullptr);
  auto* bytes = reinterpret_cast<unsigned char*>(const_cast<CcmCell*>(cell));  // the upset
  bytes[4] = static_cast<unsigned char>(bytes[4] ^ 0x04U);
  const QueryResult hit = map.query(px, py);
  ASSERT_EQ(hit.status, Status::kUnknown);
  ASSERT_TRUE(hit.upset);
  ASSERT_EQ(keeper.move_to(20.0F, 0.0F, PatchPose{20.0F, 0.0F, 0.0F, 0.0F, 0.0F}, nullptr), Status::kOk);
  ASSERT_EQ(keeper.move_to(0.0F, 0.0F, PatchPose{}, nullptr), Status::kOk);
  const QueryResult back = map.query(px, py);
  EXPECT_EQ(back.status, Status::kUnknown);
  EXPECT_TRUE(back.upset) << "the upset's mark was lost through the patch";
  EXPECT_EQ(map.query(qx, qy).status, Status::kOk) << "an intact cell in another tile came back";
  EXPECT_EQ(map.state_status(), Status::kOk);
  // New points observe the place again: the mark is gone.
  ASSERT_EQ(map.update_frame(points.data(), points.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
  const QueryResult seen = map.query(px, py);
  EXPECT_EQ(seen.status, Status::kOk);
  EXPECT_FALSE(seen.upset);
}

TEST(PatchKeeper, APosixDirectoryHoldsThePatches) {
  char directory[] = "/tmp/ccmap_patches_XXXXXX";
  ASSERT_NE(mkdtemp(directory), nullptr);
  static platform::PosixDirectory state;
  platform::PatchStorage table{};
  ASSERT_TRUE(platform::posix_directory_storage(directory, &state, &table));
  EXPECT_FALSE(platform::posix_directory_storage("/nonexistent/ccmap", &state, &table));
  static Small map;
  static Wide wide;
  static SmallKeeper keeper;
  ASSERT_EQ(map.init(exact_params(0.08F)), Status::kOk);
  ASSERT_EQ(wide.init(exact_params(0.08F)), Status::kOk);
  ASSERT_EQ(keeper.init(map, table), Status::kOk);
  (void)drive_both(map, keeper, wide);
  EXPECT_EQ(count_cell_differences(map.ccm_layer(0), wide.ccm_layer(0)), 0);
  EXPECT_GT(keeper.counters().patches_written, 10U);
  // A patch read back has its stamp and key.
  std::vector<std::uint8_t> buffer(SmallKeeper::kMaxPatchBytes);
  PatchHeader h{};
  ASSERT_EQ(keeper.read_patch(platform::PatchKey{0, 5, 0}, buffer.data(), buffer.size(), &h), Status::kOk);
  EXPECT_EQ(h.key.tile_x, 5);
  EXPECT_EQ(h.tile_side, 16);
  EXPECT_GT(h.pose.x_m, 6.4F - 1.28F);  // written when the window's trailing edge passed the tile
  EXPECT_EQ(keeper.read_patch(platform::PatchKey{0, 500, 0}, buffer.data(), buffer.size(), &h), Status::kUnknown);
  const std::string command = std::string("rm -rf ") + directory;
  EXPECT_EQ(std::system(command.c_str()), 0);
}

}  // namespace
}  // namespace ccmap
