// The front of the update path (map/update/front.hpp) against independent references: floor
// conversions and the map-frame index and fraction against the exact product in double, the
// float sensor -> map transform against the double-precision transform of the same float inputs
// (the documented error bounds), the finest index against grid::index_of_position (what queries
// use) at cell edges, routing against the float RoutingTable::select on double ranges, the Kalman
// slot against grid::buffer_offset, and the refusals of make_frame_pose.
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

/// One point through a chunk function (the chunk lives on the heap, not the test's stack).
struct One {
  std::int32_t code;
  std::int32_t ix0, iy0;
  float fx, fy, z;
  float range_sq;
  std::int32_t fine_slot, height_q14, range_key;
};
One front_one(bool sensor, const PointXYZ& p, const FramePose& pose, const FrontConfig& config,
              const FineWindow& fine = FineWindow{{0, 0}, 0, 0}) {
  static std::unique_ptr<FrontChunk> chunk = std::make_unique<FrontChunk>();
  if (sensor) {
    front_sensor_chunk(&p, 1, pose, config, fine, *chunk);
  } else {
    front_map_chunk(&p, 1, pose, config, fine, *chunk);
  }
  const FrontChunk& c = *chunk;
  return One{c.code[0], c.ix0[0], c.iy0[0], c.fx[0], c.fy[0], c.z[0], c.range_sq[0], c.fine_slot[0], c.height_q14[0],
             c.range_key[0]};
}

float from_bits(std::uint32_t u) {
  float v = 0.0F;
  std::memcpy(&v, &u, sizeof v);
  return v;
}

TEST(Front, FloorToInt32IsTheFloorInDouble) {
  // |v| < 2^31: every exponent, both signs, mantissas random and at the edges.
  test::Rng rng(1);
  int checked = 0;
  for (std::uint32_t exponent = 0U; exponent < 127U + 31U; ++exponent) {
    for (int k = 0; k < 400; ++k) {
      const std::uint32_t mantissa = k < 3 ? (k == 0 ? 0U : (k == 1 ? 1U : 0x7FFFFFU))
                                           : static_cast<std::uint32_t>(rng.next() & 0x7FFFFFU);
      for (const std::uint32_t sign : {0U, 0x80000000U}) {
        const float v = from_bits(sign | (exponent << 23) | mantissa);
        ASSERT_EQ(std::int64_t{floor_to_int32(v)}, static_cast<std::int64_t>(std::floor(double{v}))) << "v = " << v;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100000);
}

/// The map-frame index and fraction of x against the exact product in double (a float times a
/// float is exact in double).
void expect_exact_map_cell(const One& f, float x, float inv, bool y_axis) {
  const double exact = double{x} * double{inv};
  const auto index = static_cast<std::int64_t>(std::floor(exact));
  const double fraction = exact - static_cast<double>(index);
  ASSERT_EQ(y_axis ? f.iy0 : f.ix0, index) << "x = " << x;
  // The fraction is the exact remainder rounded once (|remainder| < 2: within 2^-23).
  ASSERT_NEAR(y_axis ? f.fy : f.fx, fraction, 1.2e-7) << "x = " << x;
}

TEST(Front, MapFrameIndexAndFractionAreTheExactProduct) {
  test::Rng rng(2);
  int checked = 0;
  for (const float width : {0.04F, 0.05F, 0.1F, 0.3F, 0.0002F, 1.0F, 3.0F}) {
    const float bounds[1] = {std::numeric_limits<float>::infinity()};
    FrontConfig config{};
    ASSERT_EQ(make_front_config(width, bounds, 1, &config), Status::kOk);
    FramePose pose{};
    ASSERT_EQ(make_frame_pose(PointXYZ{0.0F, 0.0F, 1.0F}, nullptr, config, &pose), Status::kOk);
    for (int i = 0; i < 30000; ++i) {
      // Uniform in log scale over the map's range, both signs.
      const double magnitude = std::pow(10.0, rng.uniform(-6.0, 5.0));
      const auto x = static_cast<float>(rng.uniform(0.0, 1.0) < 0.5 ? -magnitude : magnitude);
      const float y = -x;
      const One f = front_one(false, PointXYZ{x, y, 0.5F}, pose, config);
      ASSERT_EQ(f.code, 0);
      expect_exact_map_cell(f, x, config.inv_width, false);
      expect_exact_map_cell(f, y, config.inv_width, true);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 7 * 30000);
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

/// Largest per-axis error (m) of the float transform against double over random poses and
/// sensor points within `radius` m of the sensor; also the mean error (bias) per axis. The
/// front's map-frame position of a point is (index + fraction) / fl(1/w_0) on x and y, its
/// height on z.
void transform_error(double radius, double translation_range, double* worst, double* mean_error) {
  test::Rng rng(7);
  const FrontConfig config = unbounded_front(0.04F);
  double sum[3] = {0.0, 0.0, 0.0};
  int n = 0;
  *worst = 0.0;
  for (int p = 0; p < 200; ++p) {
    const Pose pose = random_pose(rng, translation_range);
    FramePose frame{};
    ASSERT_EQ(make_frame_pose(pose.translation, &pose.rotation[0][0], config, &frame), Status::kOk);
    for (int i = 0; i < 2000; ++i) {
      const PointXYZ s{static_cast<float>(rng.uniform(-radius, radius)), static_cast<float>(rng.uniform(-radius, radius)),
                       static_cast<float>(rng.uniform(-radius, radius))};
      const One f = front_one(true, s, frame, config);
      ASSERT_EQ(f.code, 0) << "a point within " << radius << " m must be routed";
      const double t[3] = {pose.translation.x, pose.translation.y, pose.translation.z};
      const double got[3] = {(static_cast<double>(f.ix0) + f.fx) / double{config.inv_width},
                             (static_cast<double>(f.iy0) + f.fy) / double{config.inv_width}, double{f.z}};
      for (int r = 0; r < 3; ++r) {
        const double m = double{pose.rotation[r][0]} * s.x + double{pose.rotation[r][1]} * s.y +
                         double{pose.rotation[r][2]} * s.z + t[r];
        const double e = got[r] - m;
        *worst = std::max(*worst, std::fabs(e));
        sum[r] += e;
      }
      ++n;
    }
  }
  *mean_error = std::max({std::fabs(sum[0]), std::fabs(sum[1]), std::fabs(sum[2])}) / n;
}

TEST(Front, SensorTransformWithinThreeMicrometresOfDoubleWithinTenMetres) {
  double worst = 0.0, bias = 0.0;
  transform_error(10.0, 100.0, &worst, &bias);
  std::printf("[ front    ] sensor -> map within 10 m: worst %.2f um per axis, bias %.3f um\n", worst * 1e6, bias * 1e6);
  EXPECT_LT(worst, 3.0e-6) << "docs/design.md states < 3 um per axis within 10 m of the sensor";
  EXPECT_LT(bias, 0.05e-6) << "round-to-nearest float arithmetic: an unbiased transform";
}

TEST(Front, SensorTransformWithinTwoTenMillionthsOfTheRangeAtTwoKilometres) {
  double worst = 0.0, bias = 0.0;
  transform_error(1400.0, 1000.0, &worst, &bias);  // |s| per axis < 2^11 m
  std::printf("[ front    ] sensor -> map within 1.4 km: worst %.1f um per axis\n", worst * 1e6);
  // Float offsets of up to 2.4 km: the error grows with the offset (relative 2^-23 per
  // operation), 0.3 mm at 1.4 km (docs/design.md).
  EXPECT_LT(worst, 2.0e-7 * 1400.0 * std::sqrt(3.0));
}

TEST(Front, ChunksOfManyPointsEqualOnePointAtATimeBitForBit) {
  // On aarch64 the chunks run four points at a time in NEON, on x86-64 their routing, slot,
  // height and key eight at a time in vector extensions (the AVX2 clone, or SSE2 halves in the
  // coverage build), and the rest (and a chunk of one point) in the portable loops: both must
  // give the same bits, refusals, NaN, Inf, the sensor itself, points near the limit and the
  // Kalman slot included. Elsewhere both are the portable loops (the check holds trivially).
  const float widths[5] = {0.04F, 0.08F, 0.16F, 0.32F, 0.64F};
  sensor::RoutingTable<5> table{};
  ASSERT_EQ(sensor::build_routing_table(sensor::cadre_stereo(), widths, sensor::constant_layer_max_sigma(0.04F), &table),
            Status::kOk);
  FrontConfig config{};
  ASSERT_EQ(make_front_config(0.04F, table.max_range_sq, 5, &config), Status::kOk);
  test::Rng rng(11);
  const FineWindow fine{{-40, 0}, 64, 6};
  const float specials[] = {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -0.0F,
                            0.0F, 2047.99F, -2048.0F, 1e-40F};
  int compared = 0;
  for (int f = 0; f < 40; ++f) {
    const Pose pose = random_pose(rng, f < 20 ? 50.0 : 99000.0);  // the second half near the map's limit
    FramePose frame{};
    ASSERT_EQ(make_frame_pose(pose.translation, &pose.rotation[0][0], config, &frame), Status::kOk);
    std::vector<PointXYZ> pts(kFrontChunkPoints);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      pts[i] = PointXYZ{static_cast<float>(rng.uniform(-4.0, 4.0)), static_cast<float>(rng.uniform(-4.0, 4.0)),
                        static_cast<float>(rng.uniform(-1.0, 3.0))};
      if (rng.uniform(0.0, 1.0) < 0.1) {
        (i % 3 == 0 ? pts[i].x : (i % 3 == 1 ? pts[i].y : pts[i].z)) = specials[i % 7];
      }
      if (i == 5) pts[i] = PointXYZ{0.0F, 0.0F, 0.0F};  // the sensor itself
    }
    const bool sensor = f % 2 == 0;  // both chunk functions
    if (!sensor) {
      for (PointXYZ& q : pts) {  // map-frame points around the pose
        q = PointXYZ{q.x + pose.translation.x, q.y + pose.translation.y, q.z + pose.translation.z};
        if (f % 4 == 1) q.x *= 1.0e-4F;  // and some that need the exact path (|x / w| >= 2^23 at w = 0.0002 m below)
      }
    }
    auto chunk = std::make_unique<FrontChunk>();
    if (sensor) {
      front_sensor_chunk(pts.data(), pts.size(), frame, config, fine, *chunk);
    } else {
      front_map_chunk(pts.data(), pts.size(), frame, config, fine, *chunk);
    }
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const One o = front_one(sensor, pts[i], frame, config, fine);
      ASSERT_EQ(chunk->code[i], o.code) << "point " << i << " of frame " << f;
      if (o.code >= std::int32_t{kFrontNonFinite}) {
        ASSERT_EQ(chunk->fine_slot[i], -1);
        continue;
      }
      ASSERT_EQ(chunk->ix0[i], o.ix0);
      ASSERT_EQ(chunk->iy0[i], o.iy0);
      ASSERT_EQ(bits_of(chunk->fx[i]), bits_of(o.fx));
      ASSERT_EQ(bits_of(chunk->fy[i]), bits_of(o.fy));
      ASSERT_EQ(bits_of(chunk->z[i]), bits_of(o.z));
      ASSERT_EQ(bits_of(chunk->range_sq[i]), bits_of(o.range_sq));
      ASSERT_EQ(chunk->fine_slot[i], o.fine_slot);
      ASSERT_EQ(chunk->height_q14[i], o.height_q14);
      ASSERT_EQ(chunk->range_key[i], o.range_key);
      ++compared;
    }
  }
  EXPECT_GT(compared, 2000);
}

TEST(Front, EveryLayerCountRoutesAsTheFloatTable) {
  // Stacks of 1 .. 8 layers: the chunk functions are instantiated per layer count; each must
  // route every point as RoutingTable::select on the double range (bounds doubling from 1 m^2,
  // the last one unbounded for some counts, points near a bound left out).
  test::Rng rng(21);
  for (int layers = 1; layers <= kFrontMaxLayers; ++layers) {
    std::vector<float> bounds;
    for (int k = 0; k < layers; ++k) {
      bounds.push_back(layers % 2 == 0 && k == layers - 1 ? std::numeric_limits<float>::infinity()
                                                           : static_cast<float>(1 << k));
    }
    FrontConfig config{};
    ASSERT_EQ(make_front_config(0.05F, bounds.data(), layers, &config), Status::kOk);
    FramePose map_pose{};
    ASSERT_EQ(make_frame_pose(PointXYZ{0.5F, -0.5F, 0.2F}, nullptr, config, &map_pose), Status::kOk);
    const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    FramePose sensor_pose{};
    ASSERT_EQ(make_frame_pose(PointXYZ{0.5F, -0.5F, 0.2F}, identity, config, &sensor_pose), Status::kOk);
    std::vector<PointXYZ> map_points, sensor_points;
    std::vector<bool> on_bound;
    for (int i = 0; i < 64; ++i) {
      PointXYZ s{static_cast<float>(rng.uniform(-12.0, 12.0)), static_cast<float>(rng.uniform(-12.0, 12.0)),
                 static_cast<float>(rng.uniform(-1.0, 1.0))};
      // Every eighth point exactly on an even layer's bound (r^2 = 2^k, exact in float in both
      // frames): a bound belongs to its own layer (the comparison is r^2 > bound, not >=).
      const int k = (i / 8) % layers;
      const bool exact = i % 8 == 3 && k % 2 == 0 && std::isfinite(bounds[static_cast<std::size_t>(k)]);
      if (exact) s = PointXYZ{static_cast<float>(1 << (k / 2)), 0.0F, 0.0F};
      on_bound.push_back(exact);
      sensor_points.push_back(s);
      map_points.push_back(PointXYZ{s.x + 0.5F, s.y - 0.5F, s.z + 0.2F});
    }
    auto chunk = std::make_unique<FrontChunk>();
    for (const bool sensor : {false, true}) {
      if (sensor) {
        front_sensor_chunk(sensor_points.data(), sensor_points.size(), sensor_pose, config, FineWindow{}, *chunk);
      } else {
        front_map_chunk(map_points.data(), map_points.size(), map_pose, config, FineWindow{}, *chunk);
      }
      for (std::size_t i = 0; i < sensor_points.size(); ++i) {
        const PointXYZ& s = sensor_points[i];
        const double r2 = double{s.x} * s.x + double{s.y} * s.y + double{s.z} * s.z;
        bool near = false;
        int expected = -1;
        for (int k = 0; k < layers; ++k) {
          near = near || std::fabs(r2 - double{bounds[static_cast<std::size_t>(k)]}) < 1e-4;
          if (expected < 0 && r2 <= double{bounds[static_cast<std::size_t>(k)]}) expected = k;
        }
        if (near && !on_bound[i]) continue;
        ASSERT_EQ(chunk->code[i] == std::int32_t{kFrontTooNoisy} ? -1 : chunk->code[i], expected)
            << layers << " layers, " << (sensor ? "sensor" : "map") << " frame, r^2 = " << r2;
      }
    }
  }
}

TEST(Front, FinestIndexEqualsWhatQueriesLocateAtEveryEdge) {
  // The update path and grid::index_of_position (RingGrid::locate) must name the same cell for
  // every map-frame float, including the floats right at and around every cell edge.
  int checked = 0;
  for (const float width : {0.04F, 0.05F, 0.1F, 0.3F, 0.0002F, 1.0F}) {
    const FrontConfig config = unbounded_front(width);
    FramePose pose{};
    ASSERT_EQ(make_frame_pose(PointXYZ{0.0F, 0.0F, 1.0F}, nullptr, config, &pose), Status::kOk);
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
  // reference. Points within 1e-6 (relative) of a bound may go either way (the float range's
  // rounding): they are counted, not compared.
  const float widths[5] = {0.04F, 0.08F, 0.16F, 0.32F, 0.64F};
  sensor::RoutingTable<5> table{};
  ASSERT_EQ(sensor::build_routing_table(sensor::cadre_stereo(), widths, sensor::constant_layer_max_sigma(0.04F), &table),
            Status::kOk);
  FrontConfig config{};
  ASSERT_EQ(make_front_config(0.04F, table.max_range_sq, 5, &config), Status::kOk);
  FramePose pose{};
  const PointXYZ origin{1.25F, -0.5F, 0.175F};
  ASSERT_EQ(make_frame_pose(origin, nullptr, config, &pose), Status::kOk);
  test::Rng rng(3);
  int ambiguous = 0, compared = 0;
  for (int i = 0; i < 300000; ++i) {
    const PointXYZ p{static_cast<float>(rng.uniform(-7.0, 7.0)), static_cast<float>(rng.uniform(-7.0, 7.0)),
                     static_cast<float>(rng.uniform(-1.0, 1.0))};
    const double dx = double{p.x} - origin.x, dy = double{p.y} - origin.y, dz = double{p.z} - origin.z;
    const double r2 = dx * dx + dy * dy + dz * dz;
    const One f = front_one(false, p, pose, config);
    // Float offsets (one rounding each), squares and sums: within a few ulp of r^2.
    ASSERT_NEAR(double{f.range_sq}, r2, 6.0e-7 * r2 + 1e-12) << i;
    ASSERT_EQ(f.range_key, static_cast<std::int32_t>(std::floor(std::min(double{f.range_sq}, 524287.0) * 4096.0)));
    bool near_bound = false;
    for (float b : table.max_range_sq) near_bound = near_bound || std::fabs(r2 - b) < 1e-6 * b;
    if (near_bound) {
      ++ambiguous;
      continue;
    }
    const int expected = table.select(static_cast<float>(r2));
    ASSERT_EQ(f.code == std::int32_t{kFrontTooNoisy} ? -1 : f.code, expected) << "r^2 = " << r2;
    ++compared;
  }
  EXPECT_GT(compared, 299000);
  EXPECT_LT(ambiguous, 50);
}

TEST(Front, KalmanSlotIsTheBufferOffsetInsideTheFineWindowAndRoutedToIt) {
  const float bounds[2] = {1.0F, std::numeric_limits<float>::infinity()};
  FrontConfig config{};
  ASSERT_EQ(make_front_config(0.04F, bounds, 2, &config), Status::kOk);
  FramePose pose{};
  ASSERT_EQ(make_frame_pose(PointXYZ{0.1F, -0.2F, 0.0F}, nullptr, config, &pose), Status::kOk);
  const FineWindow fine{{-32, -40}, 64, 6};
  test::Rng rng(4);
  int inside = 0;
  for (int i = 0; i < 20000; ++i) {
    const PointXYZ p{static_cast<float>(rng.uniform(-2.0, 2.0)), static_cast<float>(rng.uniform(-2.0, 2.0)), 0.0F};
    const One f = front_one(false, p, pose, config, fine);
    const bool in_window = f.ix0 >= -32 && f.ix0 < 32 && f.iy0 >= -40 && f.iy0 < 24;
    if (f.code == 0 && in_window) {
      ASSERT_EQ(f.fine_slot, static_cast<std::int32_t>(grid::buffer_offset(CellIndex{f.ix0, f.iy0}, 64)));
      ++inside;
    } else {
      ASSERT_EQ(f.fine_slot, -1) << "routed " << f.code << ", index " << f.ix0 << ", " << f.iy0;
    }
    ASSERT_EQ(f.height_q14, 0);
  }
  EXPECT_GT(inside, 1000);
}

TEST(Front, RefusesWhatIsNotARigidPose) {
  const FrontConfig config = unbounded_front(0.04F);
  FramePose pose{};
  const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, identity, config, &pose), Status::kOk);
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, identity, config, nullptr), Status::kInvalidArgument);
  float r[9];
  std::memcpy(r, identity, sizeof r);
  r[4] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, r, config, &pose), Status::kNonFiniteInput);
  const float scaled[9] = {2, 0, 0, 0, 2, 0, 0, 0, 2};
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, scaled, config, &pose), Status::kInvalidArgument);
  const float shear[9] = {1, 0.5F, 0, 0, 1, 0, 0, 0, 1};
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, shear, config, &pose), Status::kInvalidArgument);
  const float shrunk[9] = {0.99F, 0, 0, 0, 0.99F, 0, 0, 0, 0.99F};
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, shrunk, config, &pose), Status::kInvalidArgument);
  const float mirror[9] = {1, 0, 0, 0, 1, 0, 0, 0, -1};  // orthonormal: accepted (a reflection is rigid in R^T R)
  EXPECT_EQ(make_frame_pose(PointXYZ{0, 0, 0}, mirror, config, &pose), Status::kOk);
  EXPECT_EQ(make_frame_pose(PointXYZ{2.0e5F, 0, 0}, identity, config, &pose), Status::kOutOfRange);
  EXPECT_EQ(make_frame_pose(PointXYZ{0, std::numeric_limits<float>::infinity(), 0}, identity, config, &pose),
            Status::kNonFiniteInput);
}

TEST(Front, RefusalCodesOfSensorPoints) {
  const FrontConfig config = unbounded_front(0.04F);
  FramePose pose{};
  const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  ASSERT_EQ(make_frame_pose(PointXYZ{99990.0F, 0, 0}, identity, config, &pose), Status::kOk);
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
  ASSERT_EQ(make_frame_pose(PointXYZ{-3000.0F, 0, 0}, nullptr, config, &pose), Status::kOk);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(front_one(false, PointXYZ{0, nan, 0}, pose, config).code, std::int32_t{kFrontNonFinite});
  EXPECT_EQ(front_one(false, PointXYZ{0, 0, 1.0001e5F}, pose, config).code, std::int32_t{kFrontOutOfRange});
  EXPECT_EQ(front_one(false, PointXYZ{-3000.0F, 0, 0}, pose, config).code, std::int32_t{kFrontTooNoisy});
  // 103 km from the sensor: the float range, taken by an unbounded layer, indexed exactly.
  const One far = front_one(false, PointXYZ{1.0e5F, -12.34F, 0}, pose, config);
  EXPECT_EQ(far.code, 0);
  EXPECT_NEAR(double{far.range_sq}, 103000.0 * 103000.0 + 12.34 * 12.34, 1e-6 * 103000.0 * 103000.0);
  CellIndex located{};
  ASSERT_TRUE(grid::index_of_position(1.0e5F, -12.34F, 1.0F / 0.04F, &located));
  EXPECT_EQ(far.ix0, located.x);
  EXPECT_EQ(far.iy0, located.y);
}

}  // namespace
}  // namespace ccmap::detail
