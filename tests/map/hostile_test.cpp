// Hostile input catalogue at the stack level (Stack<CadreConfig>, default_stack_params(0.04F)).
// Each test names one kind of bad or extreme input and its defined outcome: refused with a
// Status, counted, and the map unchanged. "Unchanged" is proven on the whole map state: the raw
// storage of every layer and every window, compared bitwise (support/map_state.hpp), never by
// one query. Cell-level degenerate input is covered in tests/cell/ccm_cell_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/poses.hpp"
#include "support/hash_unit.hpp"
#include "support/map_state.hpp"

namespace ccmap {
namespace {

using S = Stack<CadreConfig>;
using test::raw_map_state;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kDenormMin = std::numeric_limits<float>::denorm_min();
constexpr float kFloatMax = std::numeric_limits<float>::max();

// A nearly noise-free lidar: every point satisfies IV-G for every layer, so it goes to the
// finest layer whose window holds it (routing by window only: border tests need that).
sensor::NoiseModel precise_lidar() { return sensor::NoiseModel::lidar(sensor::LidarParams{0.0005F, 0.0F}); }

using ccmap::test::hash_unit;

std::unique_ptr<S> make_stack(const StackParams& params) {
  auto stack = std::make_unique<S>();
  EXPECT_EQ(stack->init(params), Status::kOk);
  return stack;
}

/// A stack with data in every layer: an inclined, slightly rough plane 0.5 m below a sensor at
/// the origin, out to 6 m (the default stereo model routes it over layers 0..4; a precise lidar
/// fills the finest window holding each point, which leaves layer 3 empty: same extent as 2).
std::unique_ptr<S> filled_stack(StackParams params = default_stack_params(0.04F), bool every_layer = true) {
  auto stack = make_stack(params);
  std::vector<PointXYZ> pts;
  for (float y = -6.0F; y < 6.0F; y += 0.031F) {
    for (float x = -6.0F; x < 6.0F; x += 0.029F) {
      pts.push_back(PointXYZ{x, y, -0.5F + 0.05F * x + 0.01F * hash_unit(static_cast<std::uint32_t>(pts.size()), 1U)});
    }
  }
  FrameCounters c{};
  EXPECT_EQ(stack->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kOk);
  EXPECT_GT(c.used, 10000U);
  std::size_t observed[S::kLayerCount] = {};
  stack->fine_layer().for_each([&](CellIndex, const S::FineCell& cell) { observed[0] += cell.weight > 0.0F ? 1U : 0U; });
  for (int k = 1; k < S::kLayerCount; ++k) {
    stack->ccm_layer(k - 1).for_each([&](CellIndex, const CcmCell& cell) { observed[k] += cell.weight > 0.0F ? 1U : 0U; });
  }
  for (int k = 0; k < S::kLayerCount; ++k) {
    EXPECT_TRUE(observed[k] > 10U || !every_layer) << "fixture: layer " << k << " should hold data";
  }
  return stack;
}

bool counters_equal(const FrameCounters& a, const FrameCounters& b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

std::uint32_t rejected_sum(const FrameCounters& c) {
  return c.used + c.rejected_non_finite + c.rejected_out_of_range + c.rejected_weight + c.outside_map + c.too_noisy;
}

/// One frame of `pts` that must be refused point by point: status kOk, every point counted in
/// the expected bucket, nothing used, the whole map bitwise unchanged.
void expect_points_refused(S& stack, const std::vector<PointXYZ>& pts, std::uint32_t FrameCounters::*bucket,
                           const char* what) {
  const auto before = raw_map_state(stack);
  FrameCounters c{};
  ASSERT_EQ(stack.update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kOk) << what;
  EXPECT_EQ(c.received, pts.size()) << what;
  EXPECT_EQ(c.used, 0U) << what << ": a refused point was folded into the map";
  EXPECT_EQ(c.*bucket, pts.size()) << what << ": refused points counted under the wrong reason";
  EXPECT_EQ(rejected_sum(c), c.received) << what << ": counters do not add up";
  EXPECT_TRUE(raw_map_state(stack) == before) << what << ": the map changed";
}

// ---------------------------------------------------------------------------------------------
// Coordinates
// ---------------------------------------------------------------------------------------------

TEST(StackHostile, NaNCoordinatesAreCountedAsNonFiniteAndLeaveTheMapUnchanged) {
  auto stack = filled_stack();
  const std::vector<PointXYZ> pts = {{kNaN, 0.3F, 0.0F}, {0.3F, kNaN, 0.0F}, {0.3F, 0.3F, kNaN},
                                     {-kNaN, -kNaN, -kNaN}, {kNaN, 1e30F, 0.0F}};
  expect_points_refused(*stack, pts, &FrameCounters::rejected_non_finite, "NaN coordinates");
}

TEST(StackHostile, InfiniteCoordinatesAreCountedAsNonFiniteAndLeaveTheMapUnchanged) {
  auto stack = filled_stack();
  const std::vector<PointXYZ> pts = {{kInf, 0.3F, 0.0F}, {0.3F, -kInf, 0.0F}, {0.3F, 0.3F, kInf},
                                     {-kInf, kInf, -kInf}};
  expect_points_refused(*stack, pts, &FrameCounters::rejected_non_finite, "infinite coordinates");
}

TEST(StackHostile, HugeCoordinatesAreCountedAsOutOfRangeAndLeaveTheMapUnchanged) {
  auto stack = filled_stack();
  const float just_above = std::nextafter(kMaxAbsCoordinateM, kInf);
  const std::vector<PointXYZ> pts = {{just_above, 0.3F, 0.0F}, {0.3F, -just_above, 0.0F},
                                     {0.3F, 0.3F, just_above}, {kFloatMax, 0.3F, 0.0F},
                                     {0.3F, 0.3F, -kFloatMax}, {1e30F, 1e30F, 1e30F}};
  expect_points_refused(*stack, pts, &FrameCounters::rejected_out_of_range, "huge coordinates");
}

TEST(StackHostile, FiniteButFarPointsAreCountedAsTooNoisyOrOutsideAndLeaveTheMapUnchanged) {
  // |coordinate| == kMaxAbsCoordinateM is accepted as a number, but no layer can take it: the
  // stereo noise at 1e5 m fails IV-G for every layer (too_noisy); with a precise lidar the point
  // is outside every window (outside_map).
  auto stack = filled_stack();
  expect_points_refused(*stack, {{kMaxAbsCoordinateM, 0.3F, 0.0F}, {0.3F, 0.3F, -kMaxAbsCoordinateM}},
                        &FrameCounters::too_noisy, "far points, stereo");
  StackParams params = default_stack_params(0.04F);
  params.noise = precise_lidar();
  auto lidar_stack = filled_stack(params, /*every_layer=*/false);
  expect_points_refused(*lidar_stack, {{kMaxAbsCoordinateM, 0.3F, 0.0F}, {-20.0F, 0.3F, 0.0F}},
                        &FrameCounters::outside_map, "far points, lidar");
}

TEST(StackHostile, PointAtTheSensorOriginIsCountedAsTooNoisy) {
  // Range 0 has no defined noise direction; routing refuses range^2 <= 0 (RoutingTable::select).
  auto stack = filled_stack();
  const auto before = raw_map_state(*stack);
  const PointXYZ origin{0.25F, 0.25F, -0.5F};
  FrameCounters c{};
  ASSERT_EQ(stack->update_frame(&origin, 1U, origin, &c), Status::kOk);
  EXPECT_EQ(c.too_noisy, 1U);
  EXPECT_TRUE(raw_map_state(*stack) == before);
}

TEST(StackHostile, DenormalCoordinatesAreUsedAndTheMapStaysFinite) {
  // Denormals are valid, tiny coordinates: used like any point near the origin. The cell index
  // of a negative denormal may be 0 instead of -1 (grid::index_of_position documents the -0
  // underflow); either way the point lands in exactly one cell and nothing becomes NaN/Inf.
  auto stack = filled_stack();
  const std::vector<PointXYZ> pts = {{kDenormMin, kDenormMin, kDenormMin},     {-kDenormMin, -kDenormMin, -kDenormMin},
                                     {1e-40F, -1e-40F, 1e-39F},                {-1e-38F, 1e-45F, 0.0F},
                                     {-0.0F, -0.0F, -0.0F},                    {0.3F, 0.3F, 1e-40F}};
  FrameCounters c{};
  // Sensor 0.5 m above, so the range is never 0.
  ASSERT_EQ(stack->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 0.5F}, &c), Status::kOk);
  // Taken, or judged by the outlier gate against the filled map (held or dropped by the finer
  // layer): none refused.
  EXPECT_EQ(c.used + c.gated_held + c.gated_finer, pts.size()) << "denormal coordinates are valid input";
  EXPECT_TRUE(test::all_stored_finite(*stack)) << "denormal input produced NaN/Inf in the map";
  for (const PointXYZ& p : pts) {
    const QueryResult q = stack->query(p.x, p.y);
    EXPECT_TRUE(std::isfinite(q.height_m) && std::isfinite(q.elevation_variance) && std::isfinite(q.normal_variance));
  }
  // A denormal sensor origin is valid too.
  ASSERT_EQ(stack->update_frame(pts.data(), 1U, PointXYZ{kDenormMin, -kDenormMin, 0.5F}, &c), Status::kOk);
  EXPECT_EQ(c.used + c.gated_held + c.gated_finer, 1U);
  EXPECT_TRUE(test::all_stored_finite(*stack));
}

// ---------------------------------------------------------------------------------------------
// Weights
// ---------------------------------------------------------------------------------------------

// update_frame(points, weights, n, origin, counters) (per-point weights) is detected at compile
// time: when the overload exists it is tested at the stack level, else through the cell API.
template <typename Stack, typename = void>
struct HasWeightsOverload : std::false_type {};
template <typename Stack>
struct HasWeightsOverload<Stack, std::void_t<decltype(std::declval<Stack&>().update_frame(
                                     std::declval<const PointXYZ*>(), std::declval<const float*>(),
                                     std::size_t{}, std::declval<const PointXYZ&>(),
                                     std::declval<FrameCounters*>()))>> : std::true_type {};

const float kBadWeights[] = {kNaN, -kNaN, -1.0F, -kDenormMin, 0.0F, -0.0F, kInf, -kInf,
                             std::nextafter(kMaxMeasurementWeight, kInf), kFloatMax};

template <typename Stack>
void check_bad_weights_at_stack_level(Stack& stack) {
  const std::size_t n = sizeof kBadWeights / sizeof kBadWeights[0];
  std::vector<PointXYZ> pts(n, PointXYZ{0.3F, 0.3F, -0.5F});
  const auto before = raw_map_state(stack);
  FrameCounters c{};
  ASSERT_EQ(stack.update_frame(pts.data(), kBadWeights, n, PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kOk);
  EXPECT_EQ(c.received, n);
  EXPECT_EQ(c.used, 0U) << "a point with a bad weight was folded into the map";
  EXPECT_EQ(c.rejected_weight, n);
  EXPECT_TRUE(raw_map_state(stack) == before) << "bad weights changed the map";
  // The largest valid weight and a denormal weight are accepted and keep the map finite.
  const float good[] = {kMaxMeasurementWeight, kDenormMin};
  ASSERT_EQ(stack.update_frame(pts.data(), good, 2U, PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kOk);
  EXPECT_EQ(c.used, 2U);
  EXPECT_TRUE(test::all_stored_finite(stack));
}

TEST(StackHostile, NaNNegativeZeroAndHugeWeightsAreRefusedAndLeaveTheStateUnchanged) {
  if constexpr (HasWeightsOverload<S>::value) {
    auto stack = filled_stack();
    check_bad_weights_at_stack_level(*stack);
    RecordProperty("weights_tested_at", "stack (update_frame with per-point weights) and cell API");
  } else {
    // No per-point weights in the stack API yet (weights come from the noise model, which
    // clamps them to a valid range): the cell update is where a weight is checked.
    RecordProperty("weights_tested_at", "cell API (Stack has no per-point weight overload)");
  }
  // Cell API: every bad weight is refused with kBadWeight and the cell stays bitwise unchanged.
  CcmCell ccm{};
  ASSERT_EQ(ccm_update(ccm, 0.01F, 0.02F, 0.3F, 1.0F, 1000.0F), Status::kOk);
  ASSERT_EQ(ccm_update(ccm, -0.01F, 0.0F, 0.4F, 1.0F, 1000.0F), Status::kOk);
  OmgCell omg{};
  ASSERT_EQ(omg_update(omg, 0.3F, 1e-4F, 1.0F, 1000.0F), Status::kOk);
  for (const float w : kBadWeights) {
    const CcmCell ccm_before = ccm;
    const OmgCell omg_before = omg;
    EXPECT_EQ(ccm_update(ccm, 0.0F, 0.0F, 0.5F, w, 1000.0F), Status::kBadWeight) << "weight " << w;
    EXPECT_EQ(omg_update(omg, 0.5F, 1e-4F, w, 1000.0F), Status::kBadWeight) << "weight " << w;
    EXPECT_EQ(std::memcmp(&ccm, &ccm_before, sizeof ccm), 0) << "weight " << w << " changed the CCM cell";
    EXPECT_EQ(std::memcmp(&omg, &omg_before, sizeof omg), 0) << "weight " << w << " changed the OMG cell";
  }
  // Huge but valid weights and a denormal weight keep every number finite.
  for (const float w : {kMaxMeasurementWeight, kDenormMin, 1e-30F}) {
    EXPECT_EQ(ccm_update(ccm, 0.04F, -0.04F, 0.5F, w, 1000.0F), Status::kOk);
    const CcmSurface s = ccm_surface(ccm);
    EXPECT_TRUE(std::isfinite(ccm.weight) && std::isfinite(ccm.s_zz) && std::isfinite(s.normal_variance) &&
                std::isfinite(s.slope_x))
        << "weight " << w;
  }
}

TEST(StackHostile, InverseVarianceWeightsFromTheModelStayValidAtExtremeRanges) {
  // The only weights the current stack API produces come from the noise model; in inverse-
  // variance mode they are clamped, so no range (tiny, huge) can produce a refused weight.
  StackParams params = default_stack_params(0.04F);
  params.noise.set_weight_mode(sensor::WeightMode::kInverseVariance, 1.0F);
  auto stack = make_stack(params);
  const std::vector<PointXYZ> pts = {{0.02F, 0.02F, 0.0F}, {kDenormMin, 0.0F, 0.0F}, {1e-20F, 0.0F, 0.0F},
                                     {1.5F, 0.1F, -0.5F}, {9.0F, 0.1F, -0.5F}};
  FrameCounters c{};
  ASSERT_EQ(stack->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kOk);
  EXPECT_EQ(c.rejected_weight, 0U);
  EXPECT_EQ(rejected_sum(c), c.received);
  EXPECT_TRUE(test::all_stored_finite(*stack));
}

// ---------------------------------------------------------------------------------------------
// Frames
// ---------------------------------------------------------------------------------------------

TEST(StackHostile, EmptyFramesAreAcceptedAndChangeNothing) {
  auto stack = filled_stack();
  const auto before = raw_map_state(*stack);
  const FrameCounters totals = stack->total_counters();
  const PointXYZ one{0.3F, 0.3F, -0.5F};
  FrameCounters c{};
  c.received = 77U;  // must be overwritten
  ASSERT_EQ(stack->update_frame(nullptr, 0U, PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kOk);
  EXPECT_TRUE(counters_equal(c, FrameCounters{})) << "an empty frame reported counts";
  ASSERT_EQ(stack->update_frame(&one, 0U, PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kOk);
  const Pose pose = test::identity_pose();
  ASSERT_EQ(stack->update_frame_sensor(nullptr, 0U, pose, &c), Status::kOk);
  EXPECT_TRUE(raw_map_state(*stack) == before) << "an empty frame changed the map";
  EXPECT_TRUE(counters_equal(stack->total_counters(), totals)) << "an empty frame changed the totals";
  EXPECT_EQ(stack->rejected_frames(), 0U);
  // Null points with n > 0: the frame is refused as a whole and counted.
  EXPECT_EQ(stack->update_frame(nullptr, 5U, PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kInvalidArgument);
  EXPECT_TRUE(counters_equal(c, FrameCounters{}));
  EXPECT_EQ(stack->rejected_frames(), 1U);
  EXPECT_TRUE(raw_map_state(*stack) == before);
}

/// 10^6 points 7 cm below the filled ground in one cell. Gate off: every point is folded in.
/// Gate on: every point is held (outside the cell's gate) and the frame re-seeds the cell from
/// them (the held statistics are built by the same update, limiter included). Either way the
/// cell ends at W_l with the points' statistics and no other byte of the map changes.
void million_points_in_one_cell(bool gate) {
  StackParams params = default_stack_params(0.04F);
  if (!gate) params.outlier_gate_sigma = 0.0F;
  auto stack = filled_stack(params);
  // One 8 cm cell of layer 1, 1.5 m from the sensor: the default stereo model routes it there
  // (layer 0 takes r <= 1.32 m, layer 1 r <= 1.86 m).
  const int layer = 1;
  const float w = stack->layer_cell_width(layer);
  const CellIndex index{19, 2};  // x in [1.52, 1.60), y in [0.16, 0.24)
  const float x0 = static_cast<float>(index.x) * w;
  const float y0 = static_cast<float>(index.y) * w;
  constexpr std::uint32_t kPoints = 1000000U;
  std::vector<PointXYZ> pts(kPoints);
  for (std::uint32_t i = 0; i < kPoints; ++i) {
    // Strictly inside the cell: u in [1/64, 63/64).
    const float u = (1.0F + 62.0F * hash_unit(i, 11U)) * (1.0F / 64.0F);
    const float v = (1.0F + 62.0F * hash_unit(i, 12U)) * (1.0F / 64.0F);
    pts[i] = PointXYZ{x0 + w * u, y0 + w * v, -0.5F + 0.02F * hash_unit(i, 13U)};
  }
  auto expected = raw_map_state(*stack);
  FrameCounters c{};
  ASSERT_EQ(stack->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kOk);
  if (gate) {
    ASSERT_EQ(c.gated_held, kPoints) << "every point should be held: 7 cm below a cell of a few mm";
    ASSERT_EQ(c.gated_admitted, kPoints) << "all of them should re-seed the cell";
    ASSERT_EQ(c.reseeded_cells, 1U);
    ASSERT_EQ(stack->held_cells(), 0U);
  } else {
    ASSERT_EQ(c.used, kPoints) << "every point should land in the one cell";
  }
  const CcmCell* cell = stack->ccm_layer(layer - 1).cell(index);
  ASSERT_NE(cell, nullptr);
  EXPECT_EQ(cell->weight, stack->params().weight_limit) << "the limiter should hold W at W_l";
  for (const float v : {cell->mean_x, cell->mean_y, cell->mean_z, cell->s_xx, cell->s_yy, cell->s_zz, cell->s_xz,
                        cell->s_yz}) {
    ASSERT_TRUE(std::isfinite(v)) << "NaN/Inf after 10^6 points in one cell";
  }
  EXPECT_LE(std::fabs(cell->mean_x), 0.5F * w);
  EXPECT_LE(std::fabs(cell->mean_y), 0.5F * w);
  // Uniform over 62/64 of the cell: variance (62/64 w)^2 / 12 (the limiter keeps S/W).
  const double expected_var = (62.0 / 64.0 * w) * (62.0 / 64.0 * w) / 12.0;
  EXPECT_NEAR(cell->s_xx / cell->weight, expected_var, 0.1 * expected_var);
  EXPECT_NEAR(cell->s_zz / cell->weight, 0.02 * 0.02 / 12.0, 0.1 * 0.02 * 0.02 / 12.0);
  // Every other byte of the map is unchanged: patch the one cell into the old state.
  const std::size_t offset = test::layer_byte_offset(*stack, layer) +
                             grid::buffer_offset(index, S::layer_side(layer)) * sizeof(CcmCell);
  std::memcpy(expected.data() + offset, cell, sizeof(CcmCell));
  EXPECT_TRUE(raw_map_state(*stack) == expected) << "10^6 points in one cell changed another cell";
}

TEST(StackHostile, MillionPointsInOneCellSaturateAtTheWeightLimitAndTouchNothingElse) {
  million_points_in_one_cell(false);
  million_points_in_one_cell(true);
}

// ---------------------------------------------------------------------------------------------
// Cell edges and layer borders
// ---------------------------------------------------------------------------------------------

/// Feeds one point as its own frame and checks the routing contract: with the precise lidar a
/// point goes to the finest layer whose window holds it (as that layer's locate() says), exactly
/// one cell changes, and it is the cell locate() names; or no layer holds it (outside_map) and
/// nothing changes. Returns the layer that took it (-1: none).
int feed_and_check_one(S& stack, PointXYZ p, const char* what) {
  const auto before = raw_map_state(stack);
  FrameCounters c{};
  EXPECT_EQ(stack.update_frame(&p, 1U, PointXYZ{p.x, p.y, p.z + 0.5F}, &c), Status::kOk) << what;
  int expected_layer = -1;
  CellIndex expected_index{};
  for (int k = 0; k < S::kLayerCount && expected_layer < 0; ++k) {
    const bool holds = S::layer_is_ccm(k) ? stack.ccm_layer(k - 1).locate(p.x, p.y, &expected_index)
                                          : stack.fine_layer().locate(p.x, p.y, &expected_index);
    if (holds) {
      expected_layer = k;
    }
  }
  const auto after = raw_map_state(stack);
  if (expected_layer < 0) {
    EXPECT_EQ(c.outside_map, 1U) << what;
    EXPECT_TRUE(after == before) << what << ": a point outside every window changed the map";
    return -1;
  }
  EXPECT_EQ(c.used, 1U) << what;
  // Exactly one cell changed, the one locate() names.
  const std::size_t cell_bytes = S::layer_is_ccm(expected_layer) ? sizeof(CcmCell) : sizeof(S::FineCell);
  const std::size_t offset = test::layer_byte_offset(stack, expected_layer) +
                             grid::buffer_offset(expected_index, S::layer_side(expected_layer)) * cell_bytes;
  auto patched = before;
  std::memcpy(patched.data() + offset, after.data() + offset, cell_bytes);
  EXPECT_NE(std::memcmp(before.data() + offset, after.data() + offset, cell_bytes), 0)
      << what << ": the cell locate() names did not change";
  EXPECT_TRUE(patched == after) << what << ": a cell other than the one locate() names changed";
  if (S::layer_is_ccm(expected_layer)) {
    // The stored offset from the cell centre is at most half a cell, plus float rounding of the
    // position inside the cell (map/update/layer_walk.hpp, LayerWalk::relative: within 2^-24 of a
    // cell; the bound keeps the old 2^-19 m allowance).
    const CcmCell* cell = stack.ccm_layer(expected_layer - 1).cell(expected_index);
    const float half = 0.5F * stack.layer_cell_width(expected_layer);
    const float limit = half * (1.0F + 1e-5F) + 1.9073486e-6F;  // 2^-19 m
    EXPECT_LE(std::fabs(cell->mean_x), limit) << what;
    EXPECT_LE(std::fabs(cell->mean_y), limit) << what;
  }
  return expected_layer;
}

TEST(StackHostile, PointsExactlyOnCellEdgesLandInExactlyOneCell) {
  StackParams params = default_stack_params(0.04F);
  params.noise = precise_lidar();
  auto stack = make_stack(params);
  // Edges of every layer, around the robot, on both axes and at corners: x = i * w as float
  // (0.04 m and its multiples are not exact floats: the rounding is part of the test), plus the
  // neighbouring floats.
  int fed = 0;
  for (int k = 0; k < S::kLayerCount; ++k) {
    const float w = stack->layer_cell_width(k);
    for (int i = -3; i <= 3; ++i) {
      const float edge = static_cast<float>(i) * w;
      for (const float x : {edge, std::nextafter(edge, -kInf), std::nextafter(edge, kInf)}) {
        feed_and_check_one(*stack, PointXYZ{x, 0.013F, 0.0F}, "edge on x");
        feed_and_check_one(*stack, PointXYZ{0.013F, x, 0.0F}, "edge on y");
        feed_and_check_one(*stack, PointXYZ{x, x, 0.0F}, "corner");
        fed += 3;
      }
    }
  }
  EXPECT_EQ(stack->total_counters().used, static_cast<std::uint32_t>(fed));
  EXPECT_TRUE(test::all_stored_finite(*stack));
}

TEST(StackHostile, PointsExactlyOnLayerBordersGoToTheFinestLayerHoldingThem) {
  StackParams params = default_stack_params(0.04F);
  params.noise = precise_lidar();
  auto stack = make_stack(params);
  ASSERT_EQ(stack->move_to(0.37F, -0.21F), Status::kOk);  // windows off the origin
  int used = 0, outside = 0;
  for (int k = 0; k < S::kLayerCount; ++k) {
    const float w = stack->layer_cell_width(k);
    const CellIndex centre = stack->layer_centre(k);
    const std::int32_t half = S::layer_side(k) / 2;
    // Lower border (inclusive) and upper border (exclusive) of the window on each axis.
    const float lo_x = static_cast<float>(centre.x - half) * w;
    const float hi_x = static_cast<float>(centre.x + half) * w;
    const float lo_y = static_cast<float>(centre.y - half) * w;
    const float hi_y = static_cast<float>(centre.y + half) * w;
    const float mid_y = static_cast<float>(centre.y) * w + 0.013F;
    const float mid_x = static_cast<float>(centre.x) * w + 0.013F;
    for (const float b : {lo_x, hi_x}) {
      for (const float x : {b, std::nextafter(b, -kInf), std::nextafter(b, kInf)}) {
        const int got = feed_and_check_one(*stack, PointXYZ{x, mid_y, 0.0F}, "x border");
        (got < 0 ? outside : used) += 1;
      }
    }
    for (const float b : {lo_y, hi_y}) {
      for (const float y : {b, std::nextafter(b, -kInf), std::nextafter(b, kInf)}) {
        const int got = feed_and_check_one(*stack, PointXYZ{mid_x, y, 0.0F}, "y border");
        (got < 0 ? outside : used) += 1;
      }
    }
    for (const float x : {lo_x, hi_x}) {
      for (const float y : {lo_y, hi_y}) {
        const int got = feed_and_check_one(*stack, PointXYZ{x, y, 0.0F}, "window corner");
        (got < 0 ? outside : used) += 1;
      }
    }
  }
  // The coarsest layer's upper borders are outside the map, its lower borders inside.
  EXPECT_GT(outside, 0) << "the outermost borders should be outside the map";
  EXPECT_EQ(stack->total_counters().used, static_cast<std::uint32_t>(used));
  EXPECT_EQ(stack->total_counters().outside_map, static_cast<std::uint32_t>(outside));
}

// ---------------------------------------------------------------------------------------------
// Poses and moves
// ---------------------------------------------------------------------------------------------

TEST(StackHostile, NaNOrInfinitePosesAreRefusedCountedAndLeaveTheMapUnchanged) {
  auto stack = filled_stack();
  const auto before = raw_map_state(*stack);
  const FrameCounters totals = stack->total_counters();
  const std::vector<PointXYZ> pts = {{0.3F, 0.3F, -0.5F}, {1.0F, -0.2F, -0.5F}};
  std::uint32_t frames = 0, moves = 0;
  for (const float bad : {kNaN, kInf, -kInf}) {
    for (int i = 0; i < 3; ++i) {
      PointXYZ origin{0.0F, 0.0F, 0.0F};
      (i == 0 ? origin.x : i == 1 ? origin.y : origin.z) = bad;
      FrameCounters c{};
      c.used = 99U;
      EXPECT_EQ(stack->update_frame(pts.data(), pts.size(), origin, &c), Status::kNonFiniteInput);
      EXPECT_TRUE(counters_equal(c, FrameCounters{})) << "a refused frame must report zero counts";
      ++frames;
    }
    for (int i = 0; i < 12; ++i) {
      Pose pose = test::identity_pose();
      if (i < 9) {
        pose.rotation[i / 3][i % 3] = bad;
      } else {
        (i == 9 ? pose.translation.x : i == 10 ? pose.translation.y : pose.translation.z) = bad;
      }
      FrameCounters c{};
      EXPECT_EQ(stack->update_frame_sensor(pts.data(), pts.size(), pose, &c), Status::kNonFiniteInput)
          << "pose element " << i;
      EXPECT_TRUE(counters_equal(c, FrameCounters{}));
      ++frames;
    }
    EXPECT_EQ(stack->move_to(bad, 0.0F), Status::kNonFiniteInput);
    EXPECT_EQ(stack->move_to(0.0F, bad), Status::kNonFiniteInput);
    moves += 2;
  }
  // Out-of-range poses: refused as kOutOfRange.
  PointXYZ far{2e5F, 0.0F, 0.0F};
  EXPECT_EQ(stack->update_frame(pts.data(), pts.size(), far, nullptr), Status::kOutOfRange);
  ++frames;
  EXPECT_EQ(stack->move_to(0.0F, -2e5F), Status::kOutOfRange);
  ++moves;
  EXPECT_EQ(stack->rejected_frames(), frames);
  EXPECT_EQ(stack->rejected_moves(), moves);
  EXPECT_TRUE(raw_map_state(*stack) == before) << "a refused pose changed the map";
  EXPECT_TRUE(counters_equal(stack->total_counters(), totals)) << "a refused frame changed the totals";
}

TEST(StackHostile, TeleportBeyondTheStackClearsEveryLayerAndNothingComesBack) {
  auto stack = filled_stack();
  const auto at_origin = raw_map_state(*stack);
  // A move larger than the whole stack (20.48 m): every layer's window leaves its old cells.
  ASSERT_EQ(stack->move_to(731.3F, -412.9F), Status::kOk);
  auto zero_storage_bytes = [&]() {
    std::size_t nonzero = 0;
    test::for_each_stored_float(*stack, [&](float v) { nonzero += (v != 0.0F || std::signbit(v)) ? 1U : 0U; });
    return nonzero;
  };
  EXPECT_EQ(zero_storage_bytes(), 0U) << "a teleport must clear every cell of every layer";
  for (int k = 0; k < S::kLayerCount; ++k) {
    const float w = stack->layer_cell_width(k);
    EXPECT_NEAR(static_cast<float>(stack->layer_centre(k).x) * w, 731.3F, w) << "layer " << k;
    EXPECT_NEAR(static_cast<float>(stack->layer_centre(k).y) * w, -412.9F, w) << "layer " << k;
  }
  // The map works there.
  const PointXYZ p{731.5F, -412.7F, 3.0F};
  FrameCounters c{};
  ASSERT_EQ(stack->update_frame(&p, 1U, PointXYZ{731.3F, -412.9F, 3.5F}, &c), Status::kOk);
  EXPECT_EQ(c.used, 1U);
  // Teleport home: the old data was forgotten, not resurrected from stale slots.
  ASSERT_EQ(stack->move_to(0.0F, 0.0F), Status::kOk);
  EXPECT_EQ(zero_storage_bytes(), 0U) << "stale cells reappeared after teleporting back";
  EXPECT_FALSE(raw_map_state(*stack) == at_origin);
  // Teleports to the edge of the accepted range work; one step beyond is refused, map unchanged.
  ASSERT_EQ(stack->move_to(kMaxAbsCoordinateM, -kMaxAbsCoordinateM), Status::kOk);
  ASSERT_EQ(stack->update_frame(&p, 1U, PointXYZ{kMaxAbsCoordinateM, -kMaxAbsCoordinateM, 0.0F}, &c), Status::kOk);
  const PointXYZ edge{kMaxAbsCoordinateM - 0.3F, -kMaxAbsCoordinateM + 0.2F, 0.0F};
  ASSERT_EQ(stack->update_frame(&edge, 1U, PointXYZ{kMaxAbsCoordinateM, -kMaxAbsCoordinateM, 0.5F}, &c),
            Status::kOk);
  EXPECT_EQ(c.used, 1U) << "a point near the edge of the accepted range should be mapped";
  const auto at_edge = raw_map_state(*stack);
  EXPECT_EQ(stack->move_to(std::nextafter(kMaxAbsCoordinateM, kInf), 0.0F), Status::kOutOfRange);
  EXPECT_TRUE(raw_map_state(*stack) == at_edge);
  EXPECT_TRUE(test::all_stored_finite(*stack));
}

TEST(StackHostile, HundredThousandUnitMovesBackAndForthLeaveTheMapBitwiseUnchanged) {
  // Data only where every window visited holds it (|x|, |y| <= 1 m; the walk stays within
  // 3 fine cells + snapping of the origin), then 10^5 moves of +-1 fine cell (4 cm), alternating
  // axes, a reflected random walk, then home. The whole map must come back bitwise: no drift of
  // any window, no cell lost or altered, nothing left behind by the cells that came and went.
  StackParams params = default_stack_params(0.04F);
  auto stack = make_stack(params);
  std::vector<PointXYZ> pts;
  for (float y = -1.0F; y <= 1.0F; y += 0.013F) {
    for (float x = -1.0F; x <= 1.0F; x += 0.017F) {
      pts.push_back(PointXYZ{x, y, -0.5F + 0.1F * x * y});
    }
  }
  FrameCounters c{};
  ASSERT_EQ(stack->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 0.0F}, &c), Status::kOk);
  ASSERT_EQ(c.used, pts.size());
  const auto before = raw_map_state(*stack);
  const float w = stack->layer_cell_width(0);
  std::int32_t x = 0, y = 0;
  std::uint32_t rng = 12345U;
  int moves = 0;
  for (; moves < 100000; ++moves) {
    rng = rng * 1664525U + 1013904223U;
    std::int32_t step = (rng >> 31) != 0U ? 1 : -1;
    std::int32_t& v = (moves % 2 == 0) ? x : y;
    if (v + step > 3 || v + step < -3) step = -step;
    v += step;
    ASSERT_EQ(stack->move_to(static_cast<float>(x) * w, static_cast<float>(y) * w), Status::kOk);
  }
  while (x != 0 || y != 0) {
    (x != 0 ? x : y) += (x != 0 ? (x > 0 ? -1 : 1) : (y > 0 ? -1 : 1));
    ASSERT_EQ(stack->move_to(static_cast<float>(x) * w, static_cast<float>(y) * w), Status::kOk);
    ++moves;
  }
  EXPECT_GE(moves, 100000);
  EXPECT_GT(stack->fine_layer().cells_cleared_by_moves(), 100000U) << "the walk should move the fine window";
  EXPECT_TRUE(raw_map_state(*stack) == before) << "10^5 back-and-forth moves changed the map";
}

TEST(StackHostile, MovesToTheEdgeOfTheRangeWithTinyCellWidthsAreSafe) {
  // The map frame spans +-kMaxAbsCoordinateM; with very small cells the window centre index
  // (position / width) leaves int32. Either init refuses the width, or every move to the edge of
  // the range lands every layer near the position, or it is refused with the map unchanged.
  for (const float width : {1e-6F, 1e-5F, 5e-5F, 1e-4F, 2e-4F, 1e-3F}) {
    SCOPED_TRACE(testing::Message() << "finest width " << width);
    StackParams params = default_stack_params(width);
    auto stack = std::make_unique<S>();
    if (stack->init(params) != Status::kOk) {
      EXPECT_LT(width, 2e-4F) << "a usable width was refused";
      continue;
    }
    for (const float x : {kMaxAbsCoordinateM, -kMaxAbsCoordinateM, 0.5F * kMaxAbsCoordinateM}) {
      const auto before = raw_map_state(*stack);
      const Status moved = stack->move_to(x, -x);
      if (moved != Status::kOk) {
        EXPECT_TRUE(raw_map_state(*stack) == before) << "a refused move changed the map";
        continue;
      }
      for (int k = 0; k < S::kLayerCount; ++k) {
        const double w = stack->layer_cell_width(k);
        EXPECT_NEAR(stack->layer_centre(k).x * w, x, 2.0 * w + 1e-3 * std::fabs(x)) << "layer " << k;
        EXPECT_NEAR(stack->layer_centre(k).y * w, -x, 2.0 * w + 1e-3 * std::fabs(x)) << "layer " << k;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Queries
// ---------------------------------------------------------------------------------------------

void expect_empty(const QueryResult& q, Status status, const char* what) {
  EXPECT_EQ(q.status, status) << what;
  EXPECT_EQ(q.layer, -1) << what;
  const float numbers[] = {q.height_m, q.slope_x, q.slope_y, q.inclination, q.normal_variance,
                           q.elevation_variance, q.weight};
  for (const float v : numbers) {
    EXPECT_EQ(v, 0.0F) << what << ": a refused query must answer zeros";
  }
  EXPECT_EQ(q.cell_class, CellClass::kUnknown) << what;
}

TEST(StackHostile, QueriesOutsideTheMapAnswerOutsideMapWithZeros) {
  auto stack = filled_stack();
  const auto before = raw_map_state(*stack);
  const float outer = 0.5F * static_cast<float>(S::layer_side(S::kLayerCount - 1)) *
                      stack->layer_cell_width(S::kLayerCount - 1);  // 10.24 m
  const std::pair<float, float> outside[] = {
      {outer + 0.01F, 0.0F}, {0.0F, -outer - 0.01F}, {100.0F, 100.0F}, {-kMaxAbsCoordinateM, 0.0F},
      {kFloatMax, 0.0F},     {0.0F, -kFloatMax},     {kNaN, 0.0F},     {0.0F, kNaN},
      {kInf, kInf},          {-kInf, 0.0F},          {1e30F, -1e30F}};
  for (const auto& [x, y] : outside) {
    expect_empty(stack->query(x, y), Status::kOutsideMap, "query outside");
    for (int k = 0; k < S::kLayerCount; ++k) {
      expect_empty(stack->query_layer(k, x, y), Status::kOutsideMap, "query_layer outside");
    }
  }
  for (const int bad_layer : {-1, S::kLayerCount, 1000, std::numeric_limits<int>::min()}) {
    expect_empty(stack->query_layer(bad_layer, 0.3F, 0.3F), Status::kInvalidArgument, "bad layer");
    const CcmCell pooled = stack->pooled_cell(bad_layer, CellIndex{0, 0});
    EXPECT_EQ(pooled.weight, 0.0F);
  }
  // pooled_cell of the fine layer (not CCM) and of indices far outside: the zero cell.
  const CellIndex far_indices[] = {{1 << 30, 0}, {0, -(1 << 30)}, {std::numeric_limits<std::int32_t>::min(), 0},
                                   {std::numeric_limits<std::int32_t>::max(), std::numeric_limits<std::int32_t>::max()}};
  EXPECT_EQ(stack->pooled_cell(0, CellIndex{0, 0}).weight, 0.0F);
  for (const CellIndex i : far_indices) {
    for (int k = 1; k < S::kLayerCount; ++k) {
      SCOPED_TRACE(testing::Message() << "layer " << k << " index (" << i.x << ", " << i.y << ")");
      const CcmCell cell = stack->pooled_cell(k, i);
      const CcmCell zero{};
      EXPECT_EQ(std::memcmp(&cell, &zero, sizeof cell), 0) << "pooled_cell outside the window should be the zero cell";
    }
  }
  // Just outside each CCM layer's window (where a finer window may still extend: equal extents).
  for (int k = 1; k < S::kLayerCount; ++k) {
    const CellIndex lo = stack->ccm_layer(k - 1).window_min();
    const CellIndex hi = stack->ccm_layer(k - 1).window_max();
    for (const CellIndex i : {CellIndex{lo.x - 1, lo.y}, CellIndex{hi.x + 1, hi.y}, CellIndex{lo.x, lo.y - 1},
                              CellIndex{hi.x, hi.y + 1}}) {
      const CcmCell cell = stack->pooled_cell(k, i);
      const CcmCell zero{};
      EXPECT_EQ(std::memcmp(&cell, &zero, sizeof cell), 0)
          << "pooled_cell just outside layer " << k << "'s window should be the zero cell";
    }
  }
  // Exports with bad arguments.
  std::size_t written = 5U;
  CellRecord one{};
  EXPECT_EQ(stack->export_layer(0, nullptr, 1U << 20, &written), Status::kInvalidArgument);
  EXPECT_EQ(written, 0U);
  EXPECT_EQ(stack->export_layer(0, &one, 1U, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(stack->export_layer(S::kLayerCount, &one, 1U, &written), Status::kInvalidArgument);
  EXPECT_EQ(stack->export_layer(1, &one, 1U, &written), Status::kBufferTooSmall);
  EXPECT_TRUE(raw_map_state(*stack) == before);
}

}  // namespace
}  // namespace ccmap
