// The chunked update path (update_frame, update_frame_sensor) against the per-point reference
// (update_frame_sequential) on the same frames: every cell of every layer (Kalman, OMG, CCM)
// and every counter must be bitwise equal. The tolerance is 0 ulp by design: the chunked path
// performs the same float operations in the same order (see map/frame_chunk.hpp), so any
// difference is a bug, not rounding.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/cadre_frames.hpp"

namespace ccmap {
namespace {

template <typename Config>
std::unique_ptr<Stack<Config>> make_stack(const StackParams& params) {
  auto stack = std::make_unique<Stack<Config>>();
  EXPECT_EQ(stack->init(params), Status::kOk);
  return stack;
}

bool same_counters(const FrameCounters& a, const FrameCounters& b) {
  return a.received == b.received && a.used == b.used && a.rejected_non_finite == b.rejected_non_finite &&
         a.rejected_out_of_range == b.rejected_out_of_range && a.rejected_weight == b.rejected_weight &&
         a.outside_map == b.outside_map && a.too_noisy == b.too_noisy;
}

/// Number of cells (over all layers) whose bits differ; also checks the windows.
template <typename Config>
int differing_cells(const Stack<Config>& a, const Stack<Config>& b) {
  using S = Stack<Config>;
  int differ = 0;
  if constexpr (S::kHasFine) {
    const auto& fa = a.fine_layer();
    const auto& fb = b.fine_layer();
    for (std::size_t i = 0; i < fa.cell_count(); ++i) {
      differ += std::memcmp(&fa.storage()[i], &fb.storage()[i], sizeof(typename S::FineCell)) != 0;
    }
  }
  for (int c = 0; c < S::kCcmLayerCount; ++c) {
    const auto& ca = a.ccm_layer(c);
    const auto& cb = b.ccm_layer(c);
    for (std::size_t i = 0; i < ca.cell_count(); ++i) {
      differ += std::memcmp(&ca.storage()[i], &cb.storage()[i], sizeof(CcmCell)) != 0;
    }
  }
  return differ;
}

/// A CADRE frame with hostile points mixed in: NaN, Inf, out-of-range, the sensor origin
/// itself (range 0), too far for every layer, outside every window (lidar-like).
std::vector<PointXYZ> hostile_frame(const test::CadreFrame& frame) {
  std::vector<PointXYZ> pts = frame.map_points;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < pts.size(); i += 997) {
    switch ((i / 997) % 7) {
      case 0: pts[i].x = nan; break;
      case 1: pts[i].z = -inf; break;
      case 2: pts[i].y = 2.0e5F; break;
      case 3: pts[i] = frame.sensor_origin; break;
      case 4: pts[i].x = 7.0F; break;                     // beyond the 64 cm layer's range
      case 5: pts[i].x = -1.0e-39F; pts[i].y = -0.0F; break;  // subnormal / negative zero
      default: pts[i].x = 1.0e4F; break;                  // far outside every window
    }
  }
  return pts;
}

template <typename Config>
void expect_fast_equals_sequential(const StackParams& params, const std::vector<PointXYZ>& pts,
                                   const float* weights, const PointXYZ& origin, const char* what) {
  auto fast = make_stack<Config>(params);
  auto reference = make_stack<Config>(params);
  for (int frame = 0; frame < 2; ++frame) {  // the second frame folds into observed cells
    FrameCounters cf{};
    FrameCounters cr{};
    ASSERT_EQ(fast->update_frame(pts.data(), weights, pts.size(), origin, &cf), Status::kOk);
    ASSERT_EQ(reference->update_frame_sequential(pts.data(), weights, pts.size(), origin, &cr), Status::kOk);
    EXPECT_TRUE(same_counters(cf, cr)) << what << ": counters differ (used " << cf.used << " vs " << cr.used
                                       << ", too noisy " << cf.too_noisy << " vs " << cr.too_noisy << ")";
    EXPECT_TRUE(pts.empty() || cf.used > 0U) << what;
  }
  EXPECT_EQ(differing_cells(*fast, *reference), 0) << what << ": the chunked update changed cells differently";
}

TEST(UpdatePath, CadreFrameEqualsSequentialBitwise) {
  const test::CadreFrame frame = test::make_cadre_frame(test::cadre_sequence_spec(0));
  expect_fast_equals_sequential<CadreConfig>(default_stack_params(0.04F), frame.map_points, nullptr,
                                             frame.sensor_origin, "cadre");
}

TEST(UpdatePath, HostilePointsAreCountedAsTheSequentialPathCountsThem) {
  const test::CadreFrame frame = test::make_cadre_frame(test::cadre_sequence_spec(1, 400, 250));
  const std::vector<PointXYZ> pts = hostile_frame(frame);
  expect_fast_equals_sequential<CadreConfig>(default_stack_params(0.04F), pts, nullptr, frame.sensor_origin,
                                             "cadre hostile");
  auto stack = make_stack<CadreConfig>(default_stack_params(0.04F));
  FrameCounters counters{};
  ASSERT_EQ(stack->update_frame(pts.data(), pts.size(), frame.sensor_origin, &counters), Status::kOk);
  EXPECT_GT(counters.rejected_non_finite, 0U);
  EXPECT_GT(counters.rejected_out_of_range, 0U);
  EXPECT_GT(counters.too_noisy, 0U);
  EXPECT_EQ(counters.used + counters.rejected_non_finite + counters.rejected_out_of_range + counters.too_noisy +
                counters.outside_map + counters.rejected_weight,
            counters.received);
}

TEST(UpdatePath, OmgKalmanAndSingleCcmStacksEqualSequentialBitwise) {
  const test::CadreFrame frame = test::make_cadre_frame(test::cadre_sequence_spec(2, 400, 250));
  StackParams params = default_stack_params(0.08F);
  expect_fast_equals_sequential<SingleOmgConfig>(params, frame.map_points, nullptr, frame.sensor_origin, "omg");
  expect_fast_equals_sequential<SingleKalmanConfig>(params, frame.map_points, nullptr, frame.sensor_origin, "kalman");
  expect_fast_equals_sequential<SingleCcmConfig>(params, frame.map_points, nullptr, frame.sensor_origin, "ccm");
  // A small weight limit makes the CCM and OMG limiters act on most cells.
  params.weight_limit = 20.0F;
  expect_fast_equals_sequential<SingleOmgConfig>(params, frame.map_points, nullptr, frame.sensor_origin, "omg, W_l 20");
  expect_fast_equals_sequential<SingleCcmConfig>(params, frame.map_points, nullptr, frame.sensor_origin, "ccm, W_l 20");
}

TEST(UpdatePath, PerPointWeightsAndInverseVarianceWeightsEqualSequential) {
  const test::CadreFrame frame = test::make_cadre_frame(test::cadre_sequence_spec(3, 400, 250));
  std::vector<float> weights(frame.map_points.size());
  for (std::size_t i = 0; i < weights.size(); ++i) {
    weights[i] = 0.25F + 0.001F * static_cast<float>(i % 1000);
  }
  // Bad weights: refused and counted, as the sequential path does.
  weights[10] = 0.0F;
  weights[11] = -1.0F;
  weights[12] = std::numeric_limits<float>::quiet_NaN();
  weights[13] = 2.0e6F;
  weights[14] = std::numeric_limits<float>::infinity();
  expect_fast_equals_sequential<CadreConfig>(default_stack_params(0.04F), frame.map_points, weights.data(),
                                             frame.sensor_origin, "cadre, per-point weights");
  expect_fast_equals_sequential<SingleOmgConfig>(default_stack_params(0.08F), frame.map_points, weights.data(),
                                                 frame.sensor_origin, "omg, per-point weights");
  auto stack = make_stack<CadreConfig>(default_stack_params(0.04F));
  FrameCounters counters{};
  ASSERT_EQ(stack->update_frame(frame.map_points.data(), weights.data(), weights.size(), frame.sensor_origin, &counters),
            Status::kOk);
  EXPECT_EQ(counters.rejected_weight, 5U) << "every bad per-point weight must be refused and counted";

  StackParams inverse = default_stack_params(0.04F);
  inverse.noise.set_weight_mode(sensor::WeightMode::kInverseVariance, 1.0F);
  expect_fast_equals_sequential<CadreConfig>(inverse, frame.map_points, nullptr, frame.sensor_origin,
                                             "cadre, inverse-variance weights");
}

TEST(UpdatePath, PerPointWeightsChangeTheCcmMean) {
  // Two points in one CCM cell, weights 3 and 1: the mean sits at 1/4 of the way.
  StackParams params = default_stack_params(0.08F);
  params.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.0005F, 0.0F});
  auto stack = make_stack<SingleCcmConfig>(params);
  const PointXYZ pts[2] = {{0.01F, 0.01F, 0.0F}, {0.05F, 0.01F, 0.4F}};
  const float weights[2] = {3.0F, 1.0F};
  ASSERT_EQ(stack->update_frame(pts, weights, 2U, PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
  const CcmCell* cell = stack->ccm_layer(0).cell(CellIndex{0, 0});
  ASSERT_NE(cell, nullptr);
  EXPECT_FLOAT_EQ(cell->weight, 4.0F);
  EXPECT_NEAR(cell->mean_z, 0.1F, 1e-6F) << "weighted mean ignores the per-point weights";
}

TEST(UpdatePath, SensorFrameEqualsTransformedPointsSequentially) {
  const test::CadreFrame frame = test::make_cadre_frame(test::cadre_sequence_spec(4, 400, 250));
  auto fast = make_stack<CadreConfig>(default_stack_params(0.04F));
  auto reference = make_stack<CadreConfig>(default_stack_params(0.04F));
  FrameCounters cf{};
  FrameCounters cr{};
  ASSERT_EQ(fast->update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, &cf),
            Status::kOk);
  // The transform as the stack documents it, p_map = R p + t, evaluated in the same order.
  const Eigen::Matrix3f& r = frame.pose.rotation;
  const Eigen::Vector3f& t = frame.pose.translation;
  std::vector<PointXYZ> mapped(frame.sensor_points.size());
  for (std::size_t i = 0; i < mapped.size(); ++i) {
    const PointXYZ& p = frame.sensor_points[i];
    mapped[i] = PointXYZ{r(0, 0) * p.x + r(0, 1) * p.y + r(0, 2) * p.z + t.x(),
                         r(1, 0) * p.x + r(1, 1) * p.y + r(1, 2) * p.z + t.y(),
                         r(2, 0) * p.x + r(2, 1) * p.y + r(2, 2) * p.z + t.z()};
  }
  ASSERT_EQ(reference->update_frame_sequential(mapped.data(), nullptr, mapped.size(),
                                               PointXYZ{t.x(), t.y(), t.z()}, &cr),
            Status::kOk);
  EXPECT_TRUE(same_counters(cf, cr));
  EXPECT_EQ(cf.used, cf.received) << "every synthetic CADRE point must land in the stack";
  EXPECT_EQ(differing_cells(*fast, *reference), 0) << "sensor-frame update differs from the sequential update";
}

TEST(UpdatePath, ChunkBoundariesAndTinyFrames) {
  const test::CadreFrame frame = test::make_cadre_frame(test::cadre_sequence_spec(5, 125, 80));
  for (const std::size_t n : {std::size_t{0}, std::size_t{1}, detail::kFrameChunkPoints - 1U, detail::kFrameChunkPoints,
                              detail::kFrameChunkPoints + 1U, std::size_t{3} * detail::kFrameChunkPoints + 7U}) {
    const std::vector<PointXYZ> pts(frame.map_points.begin(), frame.map_points.begin() + static_cast<std::ptrdiff_t>(n));
    expect_fast_equals_sequential<CadreConfig>(default_stack_params(0.04F), pts, nullptr, frame.sensor_origin,
                                               "chunk boundary");
  }
}

}  // namespace
}  // namespace ccmap
