// Map snapshots: bitwise round trip after a traverse, the byte format, and rejection of every
// corrupted, truncated, version- or preset-mismatched snapshot with the stack left unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "ccmap/persistence/snapshot.hpp"
#include "support/reference.hpp"
#include "support/wire_bytes.hpp"

namespace ccmap {
namespace {

using test::Rng;
using Bytes = std::vector<std::uint8_t>;

// A small stack (4 x 4 Kalman, two 4 x 4 CCM layers: 1,680-byte snapshots) so that every bit
// flip and every truncation can be tried exhaustively.
struct TinyConfig {
  static constexpr FineKind kFineKind = FineKind::kKalman;
  static constexpr std::int32_t kFineSide = 4;
  static constexpr std::array<std::int32_t, 2> kCcmSides{{4, 4}};
  static constexpr float kDefaultFinestCellWidthM = 0.5F;
};
// Same layer count and kinds as TinyConfig, another side: must be told apart.
struct TinyWideConfig {
  static constexpr FineKind kFineKind = FineKind::kKalman;
  static constexpr std::int32_t kFineSide = 8;
  static constexpr std::array<std::int32_t, 2> kCcmSides{{4, 4}};
  static constexpr float kDefaultFinestCellWidthM = 0.5F;
};

sensor::NoiseModel precise_lidar() { return sensor::NoiseModel::lidar(sensor::LidarParams{0.0005F, 0.0F}); }

template <typename Config>
std::unique_ptr<Stack<Config>> make_stack(const StackParams& params) {
  auto stack = std::make_unique<Stack<Config>>();
  EXPECT_EQ(stack->init(params), Status::kOk);
  return stack;
}

template <typename Config>
Bytes save(const Stack<Config>& stack) {
  Bytes bytes(snapshot_size<Config>());
  std::size_t written = 0;
  EXPECT_EQ(save_snapshot(stack, bytes.data(), bytes.size(), &written), Status::kOk);
  EXPECT_EQ(written, bytes.size());
  return bytes;
}

using test::get_u32;
using test::put_f32;
using test::put_u32;
using test::reseal;

// Byte offsets of the format (snapshot.hpp).
constexpr std::size_t kVersionAt = 4;
constexpr std::size_t kSizeAt = 8;
constexpr std::size_t kFreeSpaceShapeAt = detail::kSnapshotHeaderBytes + detail::kSnapshotFingerprintBytes;
constexpr std::size_t kParamsAt = kFreeSpaceShapeAt + detail::kSnapshotFreeSpaceShapeBytes;
constexpr std::size_t kNoiseKindAt = kParamsAt + 104;
constexpr std::size_t kFirstLayerAt = kParamsAt + detail::kSnapshotParamsBytes;

// Terrain with a slope, a 30 cm step and a 12 cm box, sampled by a stereo-like fan in front of
// a robot driving along x; returns map-frame points.
float terrain(float x, float y) {
  float z = 0.05F * x + 0.02F * y;
  if (x > 3.0F && x < 3.6F && y > -0.5F && y < 0.5F) z += 0.3F;
  if (x > 1.5F && x < 1.7F && y > 0.4F && y < 0.6F) z += 0.12F;
  return z;
}

std::vector<PointXYZ> fan(Rng& rng, float robot_x, float robot_y, int n) {
  std::vector<PointXYZ> pts;
  for (int i = 0; i < n; ++i) {
    const float range = static_cast<float>(rng.uniform(0.3, 7.0));
    const float bearing = static_cast<float>(rng.uniform(-0.7, 0.7));
    const float x = robot_x + range * std::cos(bearing);
    const float y = robot_y + range * std::sin(bearing);
    pts.push_back(PointXYZ{x, y, terrain(x, y) + static_cast<float>(0.002 * rng.normal())});
  }
  return pts;
}

template <typename Config>
void traverse(Stack<Config>& stack, std::uint64_t seed, int steps, int points_per_frame) {
  Rng rng(seed);
  for (int step = 0; step < steps; ++step) {
    const float rx = 0.37F * static_cast<float>(step);
    const float ry = 0.11F * static_cast<float>(step % 5);
    ASSERT_EQ(stack.move_to(rx, ry), Status::kOk);
    const auto pts = fan(rng, rx, ry, points_per_frame);
    ASSERT_EQ(stack.update_frame(pts.data(), pts.size(), PointXYZ{rx, ry, 0.175F}, nullptr), Status::kOk);
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  (void)stack.move_to(nan, 0.0F);  // counted rejections, so that the counters are not all zero
  (void)stack.update_frame(nullptr, 2U, PointXYZ{0, 0, 0}, nullptr);
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_same_query(const QueryResult& a, const QueryResult& b, float x, float y) {
  const float fa[] = {a.cell_width_m, a.height_m, a.slope_x, a.slope_y, a.inclination, a.normal_variance, a.elevation_variance, a.weight};
  const float fb[] = {b.cell_width_m, b.height_m, b.slope_x, b.slope_y, b.inclination, b.normal_variance, b.elevation_variance, b.weight};
  ASSERT_TRUE(a.status == b.status && a.layer == b.layer && a.cell_class == b.cell_class &&
              std::memcmp(fa, fb, sizeof fa) == 0)
      << "loaded map answers differently at (" << x << ", " << y << "): status " << to_string(a.status)
      << " vs " << to_string(b.status) << ", height " << a.height_m << " vs " << b.height_m;
}

// Everything a user can observe, compared bitwise.
template <typename Config>
void expect_same_stack(const Stack<Config>& a, const Stack<Config>& b, float cx, float extent, float step) {
  using S = Stack<Config>;
  ASSERT_TRUE(b.initialised());
  EXPECT_EQ(std::memcmp(&a.params(), &b.params(), sizeof(StackParams)), 0) << "parameters differ";
  for (int k = 0; k < S::kLayerCount; ++k) {
    EXPECT_EQ(a.layer_centre(k), b.layer_centre(k)) << "layer " << k;
    EXPECT_TRUE(same_bits(a.layer_cell_width(k), b.layer_cell_width(k))) << "layer " << k;
    EXPECT_TRUE(same_bits(a.layer_max_range_sq(k), b.layer_max_range_sq(k))) << "routing of layer " << k;
    EXPECT_TRUE(same_bits(a.normal_variance_threshold(k), b.normal_variance_threshold(k))) << "threshold " << k;
  }
  EXPECT_EQ(std::memcmp(&a.total_counters(), &b.total_counters(), sizeof(FrameCounters)), 0);
  EXPECT_EQ(a.rejected_moves(), b.rejected_moves());
  EXPECT_EQ(a.rejected_frames(), b.rejected_frames());
  for (float y = -extent; y <= extent; y += step) {
    for (float x = cx - extent; x <= cx + extent; x += step) {
      expect_same_query(a.query(x, y), b.query(x, y), x, y);
      for (int k = 0; k < S::kLayerCount; k += 2) {
        expect_same_query(a.query_layer(k, x, y), b.query_layer(k, x, y), x, y);
      }
      if (::testing::Test::HasFatalFailure()) return;
    }
  }
  for (int k = 0; k < S::kLayerCount; ++k) {
    std::vector<CellRecord> ra(S::layer_capacity(k)), rb(S::layer_capacity(k));
    std::size_t na = 0, nb = 0;
    ASSERT_EQ(a.export_layer(k, ra.data(), ra.size(), &na), Status::kOk);
    ASSERT_EQ(b.export_layer(k, rb.data(), rb.size(), &nb), Status::kOk);
    ASSERT_EQ(na, nb) << "layer " << k << " exports a different number of cells";
    for (std::size_t i = 0; i < na; ++i) {
      const CellRecord& p = ra[i];
      const CellRecord& q = rb[i];
      const float fp[] = {p.centre_x, p.centre_y, p.weight, p.height_m, p.slope_x, p.slope_y, p.normal_variance, p.elevation_variance};
      const float fq[] = {q.centre_x, q.centre_y, q.weight, q.height_m, q.slope_x, q.slope_y, q.normal_variance, q.elevation_variance};
      ASSERT_TRUE(p.index == q.index && p.cell_class == q.cell_class && std::memcmp(fp, fq, sizeof fp) == 0)
          << "layer " << k << " export record " << i << " differs";
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Round trip
// ---------------------------------------------------------------------------------------------

/// Round trip after a traverse; then the same frames into both stacks. The future is the same
/// too (all but the duration of the last update, which is measured) when no cell had held points
/// awaiting the change rule at the save: those are not in the snapshot (snapshot.hpp).
void round_trip_after_a_traverse(const StackParams& params) {
  auto original = make_stack<CadreConfig>(params);
  traverse(*original, 11, 12, 20000);
  ASSERT_GT(original->total_counters().used, 100000U);
  // Held points are decided within kMaxHeldFrames frames, empty ones included.
  for (std::uint32_t i = 0; i < detail::kMaxHeldFrames; ++i) {
    ASSERT_EQ(original->update_frame(nullptr, 0U, PointXYZ{0.0F, 0.0F, 0.0F}, nullptr), Status::kOk);
  }
  const Bytes bytes = save(*original);

  auto loaded = std::make_unique<Stack<CadreConfig>>();  // never initialised: load does it
  ASSERT_EQ(load_snapshot(*loaded, bytes.data(), bytes.size()), Status::kOk);
  const float rx = 0.37F * 11.0F;
  expect_same_stack(*original, *loaded, rx, 10.5F, 0.09F);
  EXPECT_TRUE(save(*loaded) == bytes) << "a re-saved snapshot differs from the one loaded";
  EXPECT_GT(original->last_update_ns(), 0U) << "the original measured its last frame";
  EXPECT_EQ(loaded->last_update_ns(), 0U) << "a measured time is not map state: none since the load";
  EXPECT_EQ(loaded->held_cells(), 0U) << "a load starts with no held points";

  ASSERT_EQ(original->held_cells(), 0U) << "the fixture should leave nothing pending at the save";
  traverse(*original, 12, 3, 5000);
  traverse(*loaded, 12, 3, 5000);
  expect_same_stack(*original, *loaded, 0.37F * 2.0F, 10.5F, 0.09F);
  EXPECT_TRUE(save(*original) == save(*loaded)) << "two maps fed the same frames save different bytes";
}

TEST(Snapshot, RoundTripAfterATraverseAnswersEveryQueryBitwise) {
  StackParams off = default_stack_params(0.04F);
  off.outlier_gate_sigma = 0.0F;
  round_trip_after_a_traverse(off);
  round_trip_after_a_traverse(default_stack_params(0.04F));
}

TEST(Snapshot, HeldPointsAwaitingTheChangeRuleAreNotSaved) {
  // A cell of the 8 cm layer mapped at z = 0, then one point 0.5 m up: held, waiting for more
  // (change_min_points = 3). After a save and load, two more such points re-seed the cell in
  // the original (3 held) but only wait in the loaded stack (2 held): the documented loss.
  using S = Stack<SingleCcmConfig>;
  StackParams params = default_stack_params(0.08F);
  params.noise = precise_lidar();
  auto original = make_stack<SingleCcmConfig>(params);
  std::vector<PointXYZ> ground;
  for (int i = 0; i < 16; ++i) ground.push_back(PointXYZ{0.405F + 0.005F * (i % 4), 0.405F + 0.005F * (i / 4), 0.0F});
  ASSERT_EQ(original->update_frame(ground.data(), ground.size(), PointXYZ{0, 0, 1}, nullptr), Status::kOk);
  const PointXYZ up{0.42F, 0.42F, 0.5F};
  ASSERT_EQ(original->update_frame(&up, 1U, PointXYZ{0, 0, 1}, nullptr), Status::kOk);
  ASSERT_EQ(original->held_cells(), 1U);
  const Bytes bytes = save(*original);
  auto loaded = std::make_unique<S>();
  ASSERT_EQ(load_snapshot(*loaded, bytes.data(), bytes.size()), Status::kOk);
  EXPECT_EQ(loaded->held_cells(), 0U);
  const PointXYZ two[] = {{0.41F, 0.43F, 0.5F}, {0.43F, 0.41F, 0.5F}};
  FrameCounters a{}, b{};
  ASSERT_EQ(original->update_frame(two, 2U, PointXYZ{0, 0, 1}, &a), Status::kOk);
  ASSERT_EQ(loaded->update_frame(two, 2U, PointXYZ{0, 0, 1}, &b), Status::kOk);
  EXPECT_EQ(a.reseeded_cells, 1U) << "the original had 3 held points";
  EXPECT_EQ(b.reseeded_cells, 0U) << "the loaded stack has 2";
  EXPECT_EQ(loaded->held_cells(), 1U);
}

TEST(Snapshot, LoadOverAnInitialisedStackReplacesItsState) {
  const StackParams params = default_stack_params(0.04F);
  auto a = make_stack<CadreConfig>(params);
  traverse(*a, 5, 6, 5000);
  StackParams other = default_stack_params(0.05F);  // other widths: load must re-init
  other.noise = precise_lidar();
  auto b = make_stack<CadreConfig>(other);
  traverse(*b, 6, 4, 5000);
  const Bytes bytes = save(*a);
  ASSERT_EQ(load_snapshot(*b, bytes.data(), bytes.size()), Status::kOk);
  expect_same_stack(*a, *b, 0.37F * 5.0F, 10.5F, 0.25F);
}

template <typename Config>
void round_trip_with(const StackParams& params, float cx) {
  auto original = make_stack<Config>(params);
  traverse(*original, 21, 6, 8000);
  const Bytes bytes = save(*original);
  auto loaded = std::make_unique<Stack<Config>>();
  ASSERT_EQ(load_snapshot(*loaded, bytes.data(), bytes.size()), Status::kOk);
  expect_same_stack(*original, *loaded, cx, 10.0F, 0.23F);
}

TEST(Snapshot, RoundTripOfEveryPresetAndNoiseModel) {
  StackParams lidar = default_stack_params(0.08F);
  lidar.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.002F, 0.001F});
  lidar.noise.set_weight_mode(sensor::WeightMode::kInverseVariance, 2.0F);
  lidar.weight_limit = kNoWeightLimit;  // +inf is a valid limit and must survive the round trip
  lidar.normal_variance_threshold[0] = 0.0004F;
  round_trip_with<SingleCcmConfig>(lidar, 1.0F);
  round_trip_with<SingleKalmanConfig>(default_stack_params(0.08F), 1.0F);
  StackParams omg = default_stack_params(0.08F);
  omg.noise.set_weight_mode(sensor::WeightMode::kInverseVariance, 1.5F);
  round_trip_with<SingleOmgConfig>(omg, 1.0F);
  StackParams cadre_lidar = default_stack_params(0.04F);
  cadre_lidar.noise = precise_lidar();
  round_trip_with<CadreConfig>(cadre_lidar, 1.0F);
  round_trip_with<PaperCell<CadreConfig>>(default_stack_params(0.04F), 1.0F);
  round_trip_with<PaperCell<SingleCcmConfig>>(default_stack_params(0.08F), 1.0F);
}

TEST(SnapshotFormat, CellKindsAreTwoShapesAndVersionOneIsRefused) {
  // The same preset with the other CCM cell kind is another shape (36 vs 40 bytes per CCM
  // cell): intact, but refused with kVersionMismatch either way, the target left untouched.
  StackParams params = default_stack_params(0.5F);
  params.noise = precise_lidar();
  auto full = make_stack<TinyConfig>(params);
  auto paper = make_stack<PaperCell<TinyConfig>>(params);
  traverse(*full, 3, 2, 2000);
  traverse(*paper, 3, 2, 2000);
  const Bytes full_bytes = save(*full);
  const Bytes paper_bytes = save(*paper);
  ASSERT_EQ(full_bytes.size(), paper_bytes.size() + 32U * 4U) << "one more float per CCM cell";
  auto fresh_full = std::make_unique<Stack<TinyConfig>>();
  auto fresh_paper = std::make_unique<Stack<PaperCell<TinyConfig>>>();
  EXPECT_EQ(load_snapshot(*fresh_full, paper_bytes.data(), paper_bytes.size()), Status::kVersionMismatch);
  EXPECT_EQ(load_snapshot(*fresh_paper, full_bytes.data(), full_bytes.size()), Status::kVersionMismatch);
  EXPECT_FALSE(fresh_full->initialised());
  EXPECT_FALSE(fresh_paper->initialised());
  // A version-1 snapshot had exactly the paper cell's layout: one is made from a version-2
  // paper-cell snapshot by its version field (and CRC). It is refused with kVersionMismatch, by
  // the paper-cell stack too: version 1 predates the cell kinds.
  Bytes v1 = paper_bytes;
  v1[kVersionAt] = 1U;
  v1[kVersionAt + 1] = 0U;
  reseal(v1);
  const Bytes paper_before = save(*paper);
  EXPECT_EQ(load_snapshot(*paper, v1.data(), v1.size()), Status::kVersionMismatch) << "a version-1 snapshot loaded";
  EXPECT_EQ(load_snapshot(*fresh_full, v1.data(), v1.size()), Status::kVersionMismatch);
  EXPECT_TRUE(save(*paper) == paper_before) << "a refused version-1 load changed the stack";
}

// ---------------------------------------------------------------------------------------------
// Format
// ---------------------------------------------------------------------------------------------

TEST(SnapshotFormat, SizesHeaderAndCrcAreAsDocumented) {
  EXPECT_EQ(crc32_update(0U, reinterpret_cast<const std::uint8_t*>("123456789"), 9U), 0xCBF43926U)
      << "not the IEEE 802.3 / zlib CRC-32";
  const auto* abc = reinterpret_cast<const std::uint8_t*>("123456789");
  EXPECT_EQ(crc32_update(crc32_update(0U, abc, 4U), abc + 4, 5U), 0xCBF43926U) << "CRC does not continue";
  EXPECT_EQ(snapshot_size<CadreConfig>(), 516428U);  // docs/integration.md quotes this figure
  EXPECT_EQ(snapshot_size<PaperCell<CadreConfig>>(), 475468U);
  EXPECT_EQ((snapshot_size<WithFreeSpace<CadreConfig, false>>()), 459084U);
  // 292 bytes of header, shape, parameters, counters and CRC; per layer its centre, its cells and
  // (with free space) a 4-byte record per cell.
  EXPECT_EQ(snapshot_size<TinyConfig>(), 292U + 3U * 8U + 16U * (12U + 4U) + 32U * (40U + 4U));
  EXPECT_EQ((snapshot_size<WithFreeSpace<TinyConfig, false>>()), 292U + 3U * 8U + 16U * 12U + 32U * 40U);
  static_assert(snapshot_size<SingleCcmConfig>() == 292U + 8U + 65536U * 44U, "single CCM size");
  static_assert(snapshot_size<PaperCell<SingleCcmConfig>>() == 292U + 8U + 65536U * 40U, "single paper CCM size");

  auto stack = make_stack<TinyConfig>(default_stack_params(0.5F));
  ASSERT_EQ(stack->move_to(3.0F, -2.0F), Status::kOk);
  const Bytes b = save(*stack);
  EXPECT_EQ(b[0], 'C');
  EXPECT_EQ(b[1], 'C');
  EXPECT_EQ(b[2], 'M');
  EXPECT_EQ(b[3], 'S');
  EXPECT_EQ(b[kVersionAt], kSnapshotFormatVersion & 0xFF);
  EXPECT_EQ(b[kVersionAt + 1], kSnapshotFormatVersion >> 8);
  EXPECT_EQ(get_u32(b, kSizeAt), b.size()) << "size field is not little-endian total size";
  EXPECT_EQ(b[12], static_cast<std::uint8_t>(FineKind::kKalman));
  EXPECT_EQ(b[13], 3) << "layer count";
  EXPECT_EQ(get_u32(b, 16), 4U) << "first side";
  float width = 0.0F;
  const std::uint32_t width_bits = get_u32(b, kParamsAt);
  std::memcpy(&width, &width_bits, 4);
  EXPECT_EQ(width, 0.5F) << "finest width is not the first parameter";
  const CellIndex c = stack->layer_centre(0);
  EXPECT_EQ(static_cast<std::int32_t>(get_u32(b, kFirstLayerAt)), c.x);
  EXPECT_EQ(static_cast<std::int32_t>(get_u32(b, kFirstLayerAt + 4)), c.y);
  EXPECT_EQ(get_u32(b, b.size() - 4), crc32_update(0U, b.data(), b.size() - 4));
}

// ---------------------------------------------------------------------------------------------
// Rejection (the target stack must be bitwise unchanged after every refused load)
// ---------------------------------------------------------------------------------------------

template <typename Config>
void expect_refused(Stack<Config>& target, const Bytes& target_before, const std::uint8_t* data, std::size_t size,
                    Status expected, const char* what, std::size_t detail_value) {
  const Status s = load_snapshot(target, data, size);
  ASSERT_EQ(s, expected) << what << " " << detail_value << " gave " << to_string(s);
  ASSERT_TRUE(save(target) == target_before) << what << " " << detail_value << " changed the stack";
}

class SnapshotTiny : public ::testing::Test {
 protected:
  void SetUp() override {
    StackParams params = default_stack_params(0.5F);
    params.noise = precise_lidar();
    source_ = make_stack<TinyConfig>(params);
    Rng rng(7);
    for (int frame = 0; frame < 4; ++frame) {
      std::vector<PointXYZ> pts;
      for (int i = 0; i < 3000; ++i) {
        const float x = static_cast<float>(rng.uniform(-3.9, 3.9));
        const float y = static_cast<float>(rng.uniform(-3.9, 3.9));
        pts.push_back(PointXYZ{x, y, terrain(x + 2.0F, y)});
      }
      ASSERT_EQ(source_->update_frame(pts.data(), pts.size(), PointXYZ{0, 0, 1}, nullptr), Status::kOk);
    }
    snapshot_ = save(*source_);
    StackParams other = default_stack_params(0.5F);
    target_ = make_stack<TinyConfig>(other);  // holds a different, known state
    ASSERT_EQ(target_->move_to(-2.0F, 1.0F), Status::kOk);
    const PointXYZ p{-2.1F, 1.1F, 0.3F};
    ASSERT_EQ(target_->update_frame(&p, 1U, PointXYZ{-2.0F, 1.0F, 0.5F}, nullptr), Status::kOk);
    target_before_ = save(*target_);
    ASSERT_NE(snapshot_, target_before_);
  }
  std::unique_ptr<Stack<TinyConfig>> source_;
  std::unique_ptr<Stack<TinyConfig>> target_;
  Bytes snapshot_;
  Bytes target_before_;
};

TEST_F(SnapshotTiny, EverySingleBitFlipIsRejected) {
  Bytes b = snapshot_;
  for (std::size_t bit = 0; bit < b.size() * 8U; ++bit) {
    b[bit / 8U] ^= static_cast<std::uint8_t>(1U << (bit % 8U));
    const Status s = load_snapshot(*target_, b.data(), b.size());
    ASSERT_TRUE(s == Status::kCorrupt || s == Status::kVersionMismatch)
        << "bit " << bit << " (byte " << bit / 8U << ") flipped gave " << to_string(s);
    b[bit / 8U] ^= static_cast<std::uint8_t>(1U << (bit % 8U));
  }
  EXPECT_TRUE(save(*target_) == target_before_) << "a refused load changed the stack";
  ASSERT_EQ(load_snapshot(*target_, b.data(), b.size()), Status::kOk) << "the intact snapshot must still load";
}

TEST_F(SnapshotTiny, EveryTruncationAndTrailingByteIsRejected) {
  for (std::size_t size = 0; size < snapshot_.size(); ++size) {
    expect_refused(*target_, target_before_, snapshot_.data(), size, Status::kCorrupt, "truncated to", size);
  }
  Bytes longer = snapshot_;
  longer.push_back(0U);
  expect_refused(*target_, target_before_, longer.data(), longer.size(), Status::kCorrupt, "one trailing byte", 0U);
}

TEST_F(SnapshotTiny, VersionMagicAndPresetMismatchesAreRejected) {
  Bytes b = snapshot_;
  b[kVersionAt] = static_cast<std::uint8_t>(kSnapshotFormatVersion + 1U);
  reseal(b);
  expect_refused(*target_, target_before_, b.data(), b.size(), Status::kVersionMismatch, "next version", 0U);
  b = snapshot_;
  b[kVersionAt] = 0U;
  reseal(b);
  expect_refused(*target_, target_before_, b.data(), b.size(), Status::kVersionMismatch, "version 0", 0U);
  b = snapshot_;
  b[0] = 'X';
  reseal(b);
  expect_refused(*target_, target_before_, b.data(), b.size(), Status::kCorrupt, "bad magic", 0U);

  // Snapshots of other configurations, intact: kVersionMismatch (documented choice).
  auto wide = make_stack<TinyWideConfig>(default_stack_params(0.5F));
  const Bytes wide_bytes = save(*wide);
  expect_refused(*target_, target_before_, wide_bytes.data(), wide_bytes.size(), Status::kVersionMismatch,
                 "TinyWideConfig snapshot", 0U);
  auto ccm = make_stack<SingleCcmConfig>(default_stack_params(0.08F));
  const Bytes ccm_bytes = save(*ccm);
  expect_refused(*target_, target_before_, ccm_bytes.data(), ccm_bytes.size(), Status::kVersionMismatch,
                 "SingleCcmConfig snapshot", 0U);
  auto cadre = std::make_unique<Stack<CadreConfig>>();
  EXPECT_EQ(load_snapshot(*cadre, snapshot_.data(), snapshot_.size()), Status::kVersionMismatch);
  EXPECT_FALSE(cadre->initialised()) << "a refused load initialised the stack";
  auto omg = make_stack<SingleOmgConfig>(default_stack_params(0.08F));
  auto kalman = std::make_unique<Stack<SingleKalmanConfig>>();
  const Bytes omg_bytes = save(*omg);
  EXPECT_EQ(load_snapshot(*kalman, omg_bytes.data(), omg_bytes.size()), Status::kVersionMismatch)
      << "an OMG snapshot must not load into a Kalman stack of the same size";
}

TEST_F(SnapshotTiny, ForgedContentWithAValidCrcIsRejected) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  struct Forgery {
    const char* what;
    std::size_t at;
    float value;
  };
  const std::size_t first_cell = kFirstLayerAt + 8U;
  const std::size_t first_ccm_cell = first_cell + 16U * 12U + 8U;
  const Forgery floats[] = {
      {"NaN width", kParamsAt, nan},
      {"zero width", kParamsAt, 0.0F},
      {"denormal width", kParamsAt, 1e-40F},
      {"NaN weight limit", kParamsAt + 4, nan},
      {"-inf weight limit", kParamsAt + 4, -inf},
      {"tau 2", kParamsAt + 8, 2.0F},
      {"inf threshold", kParamsAt + 28 + 8, inf},
      {"finest sigma starving layer 1", kParamsAt + 60, 1.0F},
      {"outlier gate of 0.5 sigma", kParamsAt + 64, 0.5F},
      {"NaN outlier gate", kParamsAt + 64, nan},
      {"change of 0 points", kParamsAt + 68, 0.0F},
      {"change share above one half", kParamsAt + 72, 0.6F},
      {"change share 0", kParamsAt + 72, 0.0F},
      {"fractional free-space rays", kParamsAt + 84, 10.5F},
      {"free-space rays beyond 65535", kParamsAt + 84, 70000.0F},
      {"free-space clear frames 0", kParamsAt + 88, 0.0F},
      {"NaN sensor view axis", kParamsAt + 96, nan},
      {"negative lidar sigma", kNoiseKindAt + 8, -1.0F},
      {"NaN Kalman height", first_cell, nan},
      {"inf Kalman variance", first_cell + 4, inf},
      {"negative Kalman weight", first_cell + 8, -1.0F},
      {"negative CCM weight", first_ccm_cell, -2.0F},
      {"NaN CCM s_yz", first_ccm_cell + 32, nan},
      {"inf CCM s_xy", first_ccm_cell + 36, inf},
  };
  for (const Forgery& f : floats) {
    Bytes b = snapshot_;
    put_f32(b, f.at, f.value);
    reseal(b);
    expect_refused(*target_, target_before_, b.data(), b.size(), Status::kCorrupt, f.what, f.at);
  }
  struct ByteForgery {
    const char* what;
    std::size_t at;
    std::uint8_t value;
  };
  const ByteForgery bytes[] = {
      {"reserved header", 6, 1},        {"reserved fingerprint", 14, 1},
      {"reserved free-space shape", kFreeSpaceShapeAt + 2, 1},
      {"noise kind 7", kNoiseKindAt, 7}, {"weight mode 9", kNoiseKindAt + 1, 9},
      {"reserved noise", kNoiseKindAt + 2, 1},
      {"odd centre", kFirstLayerAt, static_cast<std::uint8_t>(snapshot_[kFirstLayerAt] ^ 1U)},
      {"centre beyond 2^30", kFirstLayerAt + 3, 0x60},
  };
  for (const ByteForgery& f : bytes) {
    Bytes b = snapshot_;
    b[f.at] = f.value;
    reseal(b);
    expect_refused(*target_, target_before_, b.data(), b.size(), Status::kCorrupt, f.what, f.at);
  }
  Bytes b = snapshot_;
  put_u32(b, kSizeAt, static_cast<std::uint32_t>(b.size() + 4U));
  b.insert(b.end() - 4, {0, 0, 0, 0});
  reseal(b);
  expect_refused(*target_, target_before_, b.data(), b.size(), Status::kCorrupt, "consistent but longer", 0U);
}

TEST_F(SnapshotTiny, BadCallsAreRefused) {
  Bytes b(snapshot_.size());
  std::size_t written = 77;
  EXPECT_EQ(save_snapshot(*source_, b.data(), b.size() - 1, &written), Status::kBufferTooSmall);
  EXPECT_EQ(written, 0U);
  EXPECT_EQ(save_snapshot(*source_, nullptr, b.size(), &written), Status::kInvalidArgument);
  EXPECT_EQ(save_snapshot(*source_, b.data(), b.size(), nullptr), Status::kInvalidArgument);
  Stack<TinyConfig> never_initialised;
  written = 77;
  EXPECT_EQ(save_snapshot(never_initialised, b.data(), b.size(), &written), Status::kNotInitialised);
  EXPECT_EQ(written, 0U);
  expect_refused(*target_, target_before_, nullptr, snapshot_.size(), Status::kInvalidArgument, "nullptr", 0U);
  // A bigger buffer is fine; *written is the snapshot size.
  Bytes big(snapshot_.size() + 100U);
  ASSERT_EQ(save_snapshot(*source_, big.data(), big.size(), &written), Status::kOk);
  EXPECT_EQ(written, snapshot_.size());
  EXPECT_TRUE(std::equal(snapshot_.begin(), snapshot_.end(), big.begin()));
}

TEST(SnapshotCadre, DenseSampleOfBitFlipsAndTruncationsIsRejected) {
  auto source = make_stack<CadreConfig>(default_stack_params(0.04F));
  traverse(*source, 3, 4, 4000);
  const Bytes snapshot = save(*source);
  auto target = make_stack<CadreConfig>(default_stack_params(0.04F));
  const Bytes target_before = save(*target);
  Bytes b = snapshot;
  // Every bit of the header, fingerprint, parameters and first layer header, then a sample.
  std::vector<std::size_t> bits;
  for (std::size_t bit = 0; bit < (kFirstLayerAt + 8U) * 8U; ++bit) bits.push_back(bit);
  Rng rng(99);
  for (int i = 0; i < 400; ++i) bits.push_back(static_cast<std::size_t>(rng.next() % (b.size() * 8U)));
  for (std::size_t bit = b.size() * 8U - 32U; bit < b.size() * 8U; ++bit) bits.push_back(bit);  // the CRC
  for (const std::size_t bit : bits) {
    b[bit / 8U] ^= static_cast<std::uint8_t>(1U << (bit % 8U));
    const Status s = load_snapshot(*target, b.data(), b.size());
    ASSERT_TRUE(s == Status::kCorrupt || s == Status::kVersionMismatch) << "bit " << bit << " gave " << to_string(s);
    b[bit / 8U] ^= static_cast<std::uint8_t>(1U << (bit % 8U));
  }
  for (int i = 0; i < 60; ++i) {
    const std::size_t size = static_cast<std::size_t>(rng.next() % snapshot.size());
    ASSERT_EQ(load_snapshot(*target, snapshot.data(), size), Status::kCorrupt) << "truncated to " << size;
  }
  EXPECT_TRUE(save(*target) == target_before) << "a refused load changed the stack";
}

}  // namespace
}  // namespace ccmap
