// The integer front of the update path (map/update/front.hpp) against independent references:
// exact conversions against double arithmetic, the fixed-point sensor -> map transform against
// the double-precision transform of the same float inputs (the documented error bound), the
// finest index against grid::index_of_position (what queries use) at cell edges, routing against
// the float RoutingTable::select on double ranges, and the refusals of make_frame_pose.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "ccmap/grid/ring_index.hpp"
#include "ccmap/map/update/front.hpp"
#include "ccmap/sensor/noise_model.hpp"
#include "support/reference.hpp"

namespace ccmap::detail {
namespace {

/// One point through a chunk function (the chunk is 18 KB: heap, not the test's stack).
struct One {
  std::int32_t code;
  std::int32_t ix0, iy0;
  std::int64_t range_sq;
  std::int64_t q18[3];  ///< sensor-frame input only
};
One front_one(bool sensor, const PointXYZ& p, const FramePose& pose, const FrontConfig& config) {
  static std::unique_ptr<FrontChunk> chunk = std::make_unique<FrontChunk>();
  if (sensor) {
    front_sensor_chunk(&p, 1, pose, config, *chunk);
  } else {
    front_map_chunk(&p, 1, pose, config, *chunk);
  }
  One o{chunk->code[0], chunk->ix0[0], chunk->iy0[0], chunk->range_sq[0], {0, 0, 0}};
  for (int a = 0; a < 3; ++a) o.q18[a] = chunk->q18[a][0];
  return o;
}

float from_bits(std::uint32_t u) {
  float v = 0.0F;
  std::memcpy(&v, &u, sizeof v);
  return v;
}

/// floor(v * 2^18) in double (exact: a float times a power of two fits a double).
std::int64_t reference_q18(float v) { return static_cast<std::int64_t>(std::floor(std::ldexp(double{v}, 18))); }

TEST(Front, FloorToInt64EqualsTheCompilersConversion) {
  // 1 <= v < 2^63: biased exponents 127 .. 189, with mantissas from the edges and between.
  const std::uint32_t mantissas[] = {0x000000U, 0x000001U, 0x2AAAAAU, 0x400000U, 0x555555U, 0x7FFFFEU, 0x7FFFFFU};
  int checked = 0;
  for (std::uint32_t exponent = 127U; exponent <= 189U; ++exponent) {
    for (const std::uint32_t mantissa : mantissas) {
      const float v = from_bits((exponent << 23) | mantissa);
      ASSERT_EQ(floor_to_int64(v), static_cast<std::int64_t>(v)) << "v = " << v;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 63 * 7);
  EXPECT_EQ(floor_to_int64(1.0F), 1);
  EXPECT_EQ(floor_to_int64(2.75F), 2);
  EXPECT_EQ(floor_to_int64(8388607.5F), 8388607);  // 2^23 - 0.5: exact in float
  EXPECT_EQ(floor_to_int64(9.0e18F), static_cast<std::int64_t>(9.0e18F));
}

TEST(Front, Q18ConversionIsTheExactFloor) {
  test::Rng rng(1);
  std::vector<float> values = {0.0F, -0.0F, 1e-45F, -1e-45F, 1.17549435e-38F, -3.0e-6F, 3.8146973e-6F,
                               -3.8146973e-6F, 0.04F, -0.04F, 1.0F, -1.0F, 2047.9999F, -2047.9999F, 99999.99F,
                               -1.0e5F, 1.0e5F, 131071.99F, -131071.99F};
  for (int i = 0; i < 200000; ++i) {
    // Random bit patterns over every exponent below 2^17 (uniform in log scale), both signs.
    const auto exponent = static_cast<std::uint32_t>(rng.next() % 144U);  // biased 0..143
    const auto mantissa = static_cast<std::uint32_t>(rng.next() & 0x7FFFFFU);
    const std::uint32_t sign = static_cast<std::uint32_t>(rng.next() & 1U) << 31;
    values.push_back(from_bits(sign | (exponent << 23) | mantissa));
  }
  int small_checked = 0;
  for (const float v : values) {
    ASSERT_EQ(q18_floor(bits_of(v)), reference_q18(v)) << "v = " << v;
    if (std::fabs(v) < 2048.0F) {
      ASSERT_EQ(q18_floor_small(bits_of(v)), reference_q18(v)) << "v = " << v;
      ++small_checked;
    }
  }
  EXPECT_GT(small_checked, 100000);
}

/// A random rotation (unit quaternion in double, rounded to float entries).
Pose random_pose(test::Rng& rng, double translation_range) {
  double q[4];
  double n = 0.0;
  do {
    n = 0.0;
    for (double& c : q) {
      c = rng.uniform(-1.0, 1.0);
      n += c * c;
    }
  } while (n < 0.01 || n > 1.0);
  for (double& c : q) c /= std::sqrt(n);
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                          {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                          {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  Pose pose{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) pose.rotation[i][j] = static_cast<float>(r[i][j]);
  }
  pose.translation = PointXYZ{static_cast<float>(rng.uniform(-translation_range, translation_range)),
                              static_cast<float>(rng.uniform(-translation_range, translation_range)),
                              static_cast<float>(rng.uniform(-5.0, 5.0))};
  return pose;
}

FrontConfig unbounded_front(float width) {
  const float bounds[1] = {std::numeric_limits<float>::infinity()};
  FrontConfig config{};
  EXPECT_EQ(make_front_config(width, bounds, 1, &config), Status::kOk);
  return config;
}

/// Largest per-axis error (m) of the fixed-point transform against double over random poses
/// and sensor points within `radius` m of the sensor; also the mean error (bias) per axis.
void transform_error(double radius, double translation_range, double* worst, double* mean_error) {
  test::Rng rng(7);
  const FrontConfig config = unbounded_front(0.04F);
  double sum[3] = {0.0, 0.0, 0.0};
  int n = 0;
  *worst = 0.0;
  for (int p = 0; p < 200; ++p) {
    const Pose pose = random_pose(rng, translation_range);
    FramePose fixed{};
    ASSERT_EQ(make_frame_pose(pose.translation, &pose.rotation[0][0], &fixed), Status::kOk);
    for (int i = 0; i < 2000; ++i) {
      const PointXYZ s{static_cast<float>(rng.uniform(-radius, radius)), static_cast<float>(rng.uniform(-radius, radius)),
                       static_cast<float>(rng.uniform(-radius, radius))};
      const One f = front_one(true, s, fixed, config);
      ASSERT_EQ(f.code, 0) << "a point within " << radius << " m must be routed";
      const double t[3] = {pose.translation.x, pose.translation.y, pose.translation.z};
      for (int r = 0; r < 3; ++r) {
        const double m = double{pose.rotation[r][0]} * s.x + double{pose.rotation[r][1]} * s.y +
                         double{pose.rotation[r][2]} * s.z + t[r];
        const double e = std::ldexp(static_cast<double>(f.q18[r]), -18) - m;
        *worst = std::max(*worst, std::fabs(e));
        sum[r] += e;
      }
      ++n;
    }
  }
  *mean_error = std::max({std::fabs(sum[0]), std::fabs(sum[1]), std::fabs(sum[2])}) / n;
}

TEST(Front, SensorTransformWithinEightMicrometresOfDoubleWithinTenMetres) {
  double worst = 0.0, bias = 0.0;
  transform_error(10.0, 100.0, &worst, &bias);
  std::printf("[ front    ] sensor -> map within 10 m: worst %.2f um per axis, bias %.3f um\n", worst * 1e6, bias * 1e6);
  EXPECT_LT(worst, 8.0e-6) << "docs/design.md states < 8 um per axis within 10 m of the sensor";
  EXPECT_LT(bias, 0.5e-6) << "the floor of the Q18 conversion must be compensated (unbiased transform)";
}

TEST(Front, SensorTransformWithinTwelveMicrometresAtTwoKilometres) {
  double worst = 0.0, bias = 0.0;
  transform_error(1400.0, 1000.0, &worst, &bias);  // |s| per axis < 2^11 m
  std::printf("[ front    ] sensor -> map within 1.4 km: worst %.2f um per axis\n", worst * 1e6);
  EXPECT_LT(worst, 12.0e-6);
}

TEST(Front, FinestIndexEqualsWhatQueriesLocateAtEveryEdge) {
  // The update path and grid::index_of_position (RingGrid::locate) must name the same cell for
  // every map-frame float, including the floats right at and around every cell edge.
  int checked = 0;
  for (const float width : {0.04F, 0.05F, 0.1F, 0.3F, 0.0002F, 1.0F}) {
    const FrontConfig config = unbounded_front(width);
    FramePose pose{};
    ASSERT_EQ(make_frame_pose(PointXYZ{0.0F, 0.0F, 1.0F}, nullptr, &pose), Status::kOk);
    const float inv = 1.0F / width;
    const double limit = 9.0e4;
    const auto edges = static_cast<std::int64_t>(std::min(3000.0, limit / width));
    std::vector<std::int64_t> ks;
    for (std::int64_t k = -edges; k <= edges; ++k) ks.push_back(k);
    const auto far = static_cast<std::int64_t>(limit / width);
    for (std::int64_t k = far - 200; k <= far; ++k) {
      ks.push_back(k);
      ks.push_back(-k);
    }
    for (const std::int64_t k : ks) {
      float x = static_cast<float>(static_cast<double>(k) * width);
      for (int s = 0; s < 3; ++s) x = std::nextafter(x, -std::numeric_limits<float>::infinity());
      for (int s = 0; s < 7; ++s, x = std::nextafter(x, std::numeric_limits<float>::infinity())) {
        CellIndex located{};
        ASSERT_TRUE(grid::index_of_position(x, -x, inv, &located)) << x;
        const One f = front_one(false, PointXYZ{x, -x, 0.0F}, pose, config);
        ASSERT_EQ(f.code, 0);
        ASSERT_EQ(f.ix0, located.x) << "x = " << x << " m, width " << width;
        ASSERT_EQ(f.iy0, located.y) << "y = " << -x << " m, width " << width;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100000);
}

TEST(Front, RangeAndRoutingAgreeWithTheFloatTableOnDoubleRanges) {
  // The CADRE routing table; RoutingTable::select on the double range rounded to float is the
  // reference. Points within 1e-5 (relative) of a bound may go either way (the front's Q16
  // quantisation): they are counted, not compared.
  const float widths[5] = {0.04F, 0.08F, 0.16F, 0.32F, 0.64F};
  sensor::RoutingTable<5> table{};
  ASSERT_EQ(sensor::build_routing_table(sensor::cadre_stereo(), widths, sensor::constant_layer_max_sigma(0.04F), &table),
            Status::kOk);
  FrontConfig config{};
  ASSERT_EQ(make_front_config(0.04F, table.max_range_sq, 5, &config), Status::kOk);
  FramePose pose{};
  const PointXYZ origin{1.25F, -0.5F, 0.175F};
  ASSERT_EQ(make_frame_pose(origin, nullptr, &pose), Status::kOk);
  test::Rng rng(3);
  int ambiguous = 0, compared = 0;
  for (int i = 0; i < 300000; ++i) {
    const PointXYZ p{static_cast<float>(rng.uniform(-7.0, 7.0)), static_cast<float>(rng.uniform(-7.0, 7.0)),
                     static_cast<float>(rng.uniform(-1.0, 1.0))};
    const double dx = double{p.x} - origin.x, dy = double{p.y} - origin.y, dz = double{p.z} - origin.z;
    const double r2 = dx * dx + dy * dy + dz * dz;
    const One f = front_one(false, p, pose, config);
    // Q16 range: |error of each offset| < 2^-16 + 2 * 2^-18 m (the floors of the Q16 shift and of
    // both Q18 conversions), so |error of r^2| < 2 sqrt(3) r (2^-16 + 2^-17) + 3 (...)^2.
    const double e = 2.0 * std::sqrt(3.0 * r2) * 2.3e-5 + 1e-8;
    ASSERT_NEAR(std::ldexp(static_cast<double>(f.range_sq), -32), r2, e) << i;
    bool near_bound = false;
    for (float b : table.max_range_sq) near_bound = near_bound || std::fabs(r2 - b) < 1e-5 * b;
    if (near_bound) {
      ++ambiguous;
      continue;
    }
    const int expected = table.select(static_cast<float>(r2));
    ASSERT_EQ(f.code == std::int32_t{kFrontTooNoisy} ? -1 : f.code, expected) << "r^2 = " << r2;
    ++compared;
  }
  EXPECT_GT(compared, 290000);
  EXPECT_LT(ambiguous, 200);
}

TEST(Front, RefusesWhatIsNotARigidPose) {
  FramePose pose{};
  const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, identity, &pose), Status::kOk);
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, identity, nullptr), Status::kInvalidArgument);
  float r[9];
  std::memcpy(r, identity, sizeof r);
  r[4] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, r, &pose), Status::kNonFiniteInput);
  const float scaled[9] = {2, 0, 0, 0, 2, 0, 0, 0, 2};
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, scaled, &pose), Status::kInvalidArgument);
  const float shear[9] = {1, 0.5F, 0, 0, 1, 0, 0, 0, 1};
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, shear, &pose), Status::kInvalidArgument);
  const float shrunk[9] = {0.99F, 0, 0, 0, 0.99F, 0, 0, 0, 0.99F};
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, shrunk, &pose), Status::kInvalidArgument);
  const float mirror[9] = {1, 0, 0, 0, 1, 0, 0, 0, -1};  // orthonormal: accepted (a reflection is rigid in R^T R)
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, mirror, &pose), Status::kOk);
  EXPECT_EQ(make_frame_pose(PointXYZ{2.0e5F, 0, 0}, identity, &pose), Status::kOutOfRange);
  EXPECT_EQ(make_frame_pose(PointXYZ{0, std::numeric_limits<float>::infinity(), 0}, identity, &pose),
            Status::kNonFiniteInput);
}

TEST(Front, RefusalCodesOfSensorPoints) {
  const FrontConfig config = unbounded_front(0.04F);
  FramePose pose{};
  const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  ASSERT_EQ(make_frame_pose(PointXYZ{99990.0F, 0, 0}, identity, &pose), Status::kOk);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_EQ(front_one(true, PointXYZ{nan, 0, 0}, pose, config).code, std::int32_t{kFrontNonFinite});
  EXPECT_EQ(front_one(true, PointXYZ{0, 0, -inf}, pose, config).code, std::int32_t{kFrontNonFinite});
  EXPECT_EQ(front_one(true, PointXYZ{2048.0F, 0, 0}, pose, config).code, std::int32_t{kFrontOutOfRange});
  EXPECT_EQ(front_one(true, PointXYZ{2047.9F, 0, 0}, pose, config).code, std::int32_t{kFrontOutOfRange})
      << "beyond 1e5 m in the map frame";
  EXPECT_EQ(front_one(true, PointXYZ{-2047.9F, 0, 0}, pose, config).code, 0);
  EXPECT_EQ(front_one(true, PointXYZ{0, 0, 0}, pose, config).code, std::int32_t{kFrontTooNoisy})
      << "the sensor itself has no range";
}

TEST(Front, RefusalCodesOfMapPointsAndFarPoints) {
  const FrontConfig config = unbounded_front(0.04F);
  FramePose pose{};
  ASSERT_EQ(make_frame_pose(PointXYZ{-3000.0F, 0, 0}, nullptr, &pose), Status::kOk);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(front_one(false, PointXYZ{0, nan, 0}, pose, config).code, std::int32_t{kFrontNonFinite});
  EXPECT_EQ(front_one(false, PointXYZ{0, 0, 1.0001e5F}, pose, config).code, std::int32_t{kFrontOutOfRange});
  EXPECT_EQ(front_one(false, PointXYZ{-3000.0F, 0, 0}, pose, config).code, std::int32_t{kFrontTooNoisy});
  // 3 km from the sensor: a saturated range, taken by an unbounded layer, indexed exactly.
  const One far = front_one(false, PointXYZ{1.0e5F, -12.34F, 0}, pose, config);
  EXPECT_EQ(far.code, 0);
  EXPECT_EQ(far.range_sq, INT64_MAX);
  CellIndex located{};
  ASSERT_TRUE(grid::index_of_position(1.0e5F, -12.34F, 1.0F / 0.04F, &located));
  EXPECT_EQ(far.ix0, located.x);
  EXPECT_EQ(far.iy0, located.y);
}

}  // namespace
}  // namespace ccmap::detail
