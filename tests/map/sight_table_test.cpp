// The viewshed table of every line of sight (map/visibility/sight_table.hpp) against the exact
// integer ray walk (map/visibility/ray_walk.hpp), ray by ray: on random frames every routed point's
// line of sight is walked as the sampled stage walks it (shortened by three range errors), and
// each cell of every CADRE-like window keeps the lowest height at which a walked ray crossed it.
// The table's bound of a cell must never lie below that (it would claim free space no ray showed),
// and a cell the table bounds must have been crossed by some walked ray. The table must also bound
// most of the cells the walk bounds (a table that bounds nothing would pass the first check).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <utility>
#include <vector>

#include "ccmap/map/update/front.hpp"
#include "ccmap/map/visibility/ray_walk.hpp"
#include "ccmap/map/visibility/sight_table.hpp"

namespace {

using ccmap::CellIndex;
using ccmap::PointXYZ;
using ccmap::Status;
using namespace ccmap::detail;  // NOLINT: the stage's detail types throughout

constexpr float kWidth = 0.04F;
constexpr float kStereoK = 0.01F;  // sigma = k r^2 (m)
/// The walk places a ray's ends at 1/256 of a finest cell (ray_u): at the steepest slope the
/// table keeps (8) that moves a height by up to 2 * 8 * w_0 / 256 = 2.5 mm; 1.5 mm covers the
/// slopes of these frames (|slope| < 5), less than the records' own 3.9 mm bound unit.
constexpr float kWalkResolutionM = 1.5e-3F;

RayWindows windows_around(CellIndex anchor) {
  RayWindows w;
  w.layers = 5;
  const std::int32_t sides[5] = {64, 64, 64, 32, 32};
  for (int k = 0; k < 5; ++k) {
    const std::int32_t cx = (anchor.x >> k) & ~1;
    const std::int32_t cy = (anchor.y >> k) & ~1;
    w.side[k] = sides[k];
    w.min[k] = CellIndex{cx - sides[k] / 2, cy - sides[k] / 2};
  }
  return w;
}

struct Frame {
  PointXYZ origin;
  std::vector<PointXYZ> points;
};

/// Points all around the sensor, or within `view_rad` of a random heading (a camera's view).
Frame random_frame(std::mt19937& rng, float view_rad = 6.2831853F) {
  std::uniform_real_distribution<float> pos(-20.0F, 20.0F);
  std::uniform_real_distribution<float> height(0.15F, 1.2F);
  std::uniform_real_distribution<float> heading(0.0F, 6.2831853F);
  const float first = view_rad < 6.2831853F ? heading(rng) : 0.0F;
  std::uniform_real_distribution<float> angle(first, first + view_rad);
  std::uniform_real_distribution<float> unit(0.0F, 1.0F);
  Frame f;
  f.origin = PointXYZ{pos(rng), pos(rng), height(rng)};
  for (int i = 0; i < 6000; ++i) {
    const float a = angle(rng);
    const float r = 0.2F + 9.0F * unit(rng) * unit(rng);  // denser near, as a camera sees
    const float ground = -0.6F + 0.9F * unit(rng);
    f.points.push_back(PointXYZ{f.origin.x + r * std::cos(a), f.origin.y + r * std::sin(a), ground});
  }
  return f;
}

/// The table's constants for a frame of these tests (five layers, the stereo range error).
SightFrameConstants constants_of(const Frame& f, const FramePose& pose, int stride, int phase) {
  SightFrameConstants k{};
  k.stride = stride;
  k.phase = phase;
  k.sensor_u[0] = pose.anchor_fraction[0];
  k.sensor_u[1] = pose.anchor_fraction[1];
  k.z0 = f.origin.z;
  k.bin_scale = static_cast<float>(kSightBins) / std::sqrt(512.0F * 1.5F);
  k.cell_width_m = kWidth;
  k.sigma_c[2] = 3.0F * kStereoK;
  k.layers = 5;
  return k;
}

/// A table begun for the frame (on the heap: 261 KB), fed by one point in `stride`.
std::unique_ptr<SightTable> begun_table(const Frame& f, const FramePose& pose, int stride = 1, int phase = 0) {
  auto table = std::make_unique<SightTable>();
  table->begin(constants_of(f, pose, stride, phase));
  return table;
}

/// Runs the front over the frame chunk by chunk and feeds the table; per_chunk(chunk, count)
/// then sees each chunk.
template <typename PerChunk>
void fill_table(const Frame& f, const FrontConfig& config, const FramePose& pose, SightTable& table,
                PerChunk&& per_chunk) {
  auto chunk = std::make_unique<FrontChunk>();
  const FineWindow none{CellIndex{0, 0}, 0, 0};
  for (std::size_t begin = 0; begin < f.points.size(); begin += kFrontChunkPoints) {
    const std::size_t count = std::min(kFrontChunkPoints, f.points.size() - begin);
    front_map_chunk(f.points.data() + begin, count, pose, config, none, *chunk);
    table.add_chunk(*chunk, count, nullptr, nullptr, pose.anchor);
    per_chunk(*chunk, count);
  }
}

/// The table fed by every stride-th point against the walks of those points alone: never a bound
/// below the lowest walked ray, no bound where no walked ray crossed, and most walked cells
/// bounded (at least `share` of them).
void check_against_the_walk(int stride, double share) {
  std::mt19937 rng(31U);
  const float bounds[5] = {1.0e30F, 1.0e30F, 1.0e30F, 1.0e30F, 1.0e30F};
  FrontConfig config{};
  ASSERT_EQ(make_front_config(kWidth, bounds, 5, &config), Status::kOk);
  std::size_t checked = 0U, walked_cells = 0U, table_cells = 0U;
  for (int trial = 0; trial < 6; ++trial) {
    const Frame f = random_frame(rng);
    FramePose pose{};
    ASSERT_EQ(make_frame_pose(f.origin, nullptr, config, &pose), Status::kOk);
    const RayWindows w = windows_around(pose.anchor);
    const auto table = begun_table(f, pose, stride, trial * 7);
    const SightFrameConstants& k = table->constants();
    // The reference: lowest walked height per (layer, cell), over the points the table samples
    // (SightTable::sampled_point in each chunk of 256).
    std::map<std::tuple<int, std::int32_t, std::int32_t>, float> lowest;
    const std::int64_t ou[2] = {ray_u(pose.anchor.x, pose.anchor_fraction[0]), ray_u(pose.anchor.y, pose.anchor_fraction[1])};
    fill_table(f, config, pose, *table, [&](const FrontChunk& chunk, std::size_t count) {
      for (std::size_t j = 0; SightTable::sampled_point(j, stride, k.phase) < count; ++j) {
        const std::size_t i = SightTable::sampled_point(j, stride, k.phase);
        if (chunk.code[i] < 0 || chunk.code[i] >= 5) {
          continue;
        }
        const std::int64_t eu[2] = {ray_u(chunk.ix0[i], chunk.fx[i]), ray_u(chunk.iy0[i], chunk.fy[i])};
        // Shortened as the sampled stage shortens it (free_space.hpp, cast()).
        const double range = std::sqrt(static_cast<double>(chunk.range_sq[i]));
        const double f_keep = 1.0 - 3.0 * kStereoK * range;
        if (!(f_keep > 0.0)) {
          continue;
        }
        const RayU ray{{ou[0], ou[1]},
                       {static_cast<std::int64_t>(static_cast<double>(eu[0] - ou[0]) * f_keep),
                        static_cast<std::int64_t>(static_cast<double>(eu[1] - ou[1]) * f_keep)}};
        // Heights along the full ray, in double: z0 + (z - z0) * |walked position| / |full|.
        const double full = std::hypot(static_cast<double>(eu[0] - ou[0]), static_cast<double>(eu[1] - ou[1]));
        const double walked = std::hypot(static_cast<double>(ray.delta[0]), static_cast<double>(ray.delta[1]));
        if (!(full > 0.0)) {
          continue;
        }
        const double dz = static_cast<double>(chunk.z[i]) - f.origin.z;
        walk_ray(w, ray, [&](const RayVisit& v) {
          const double t = (dz < 0.0 ? v.t_in : v.t_out) * walked / full;
          const auto key = std::make_tuple(v.layer, v.index.x, v.index.y);
          const float z = static_cast<float>(f.origin.z + dz * t);
          auto it = lowest.find(key);
          if (it == lowest.end()) {
            lowest.emplace(key, z);
          } else if (z < it->second) {
            it->second = z;
          }
        });
      }
    });
    table->sweep();
    for (int layer = 0; layer < 5; ++layer) {
      for (std::int32_t j = 0; j < w.side[layer]; ++j) {
        for (std::int32_t i = 0; i < w.side[layer]; ++i) {
          const std::int32_t gx = w.min[layer].x + i, gy = w.min[layer].y + j;
          const float cw = static_cast<float>(1 << layer);
          const float x0 = static_cast<float>((std::int64_t{gx} * (std::int64_t{1} << layer)) - pose.anchor.x) - k.sensor_u[0];
          const float y0 = static_cast<float>((std::int64_t{gy} * (std::int64_t{1} << layer)) - pose.anchor.y) - k.sensor_u[1];
          const auto it = lowest.find(std::make_tuple(layer, gx, gy));
          walked_cells += it != lowest.end() ? 1U : 0U;
          SightCell c{};
          if (!table->read_cell(x0, x0 + cw, y0, y0 + cw, &c)) {
            continue;
          }
          ++table_cells;
          const float bound = k.z0 + static_cast<float>(c.qmin) * kSightSlopeUnit * kWidth *
                                         (c.qmin < 0 ? c.s_near : c.s_far);
          ASSERT_NE(it, lowest.end()) << "trial " << trial << ": layer " << layer << " cell " << gx << "," << gy
                                      << " bounded at " << bound << " m by the table, crossed by no walked ray";
          EXPECT_GE(bound, it->second - kWalkResolutionM) << "trial " << trial << ": layer " << layer << " cell " << gx << ","
                                                 << gy << ": the table's bound lies below every walked ray";
          ++checked;
        }
      }
    }
  }
  // Most cells the walk bounds are bounded by the table too (the rest: cells narrower than two
  // sectors, rays ending within a bin of the cell).
  EXPECT_GT(checked, 1000U);
  EXPECT_GT(static_cast<double>(table_cells), share * static_cast<double>(walked_cells))
      << table_cells << " of " << walked_cells << " walked cells bounded by the table";
  std::printf("sight table, stride %d: %zu of %zu walked cells bounded\n", stride, table_cells, walked_cells);
}

TEST(SightTable, NeverBoundsACellBelowTheLowestWalkedRayAndBoundsMostOfThem) { check_against_the_walk(1, 0.6); }

// The sampled table (one point in 2, 4, 8, 16; the NEON pass's de-interleaving loads on
// aarch64) against the walks of the points it samples.
TEST(SightTable, SampledEveryStrideThPointNeverBoundsBelowItsWalkedRays) {
  for (const int stride : {2, 4, 8, 16}) {
    SCOPED_TRACE(stride);
    check_against_the_walk(stride, 0.6);
  }
}

// The stride a free_space_rays value selects (the table's encoding in free_space_rays).
TEST(SightTable, StrideOfRays) {
  EXPECT_EQ(sight_stride_of_rays(kFreeSpaceEveryRay), 1);
  EXPECT_EQ(sight_stride_of_rays(free_space_table_rays(2)), 2);
  EXPECT_EQ(sight_stride_of_rays(free_space_table_rays(4)), 4);
  EXPECT_EQ(sight_stride_of_rays(free_space_table_rays(8)), 8);
  EXPECT_EQ(sight_stride_of_rays(free_space_table_rays(16)), 16);
  EXPECT_EQ(sight_stride_of_rays(65533.0F), 2);  // 3 rounds down
  EXPECT_EQ(sight_stride_of_rays(free_space_table_rays(16) - 1.0F), 0);  // the sampled walk
  EXPECT_EQ(sight_stride_of_rays(128.0F), 0);
  EXPECT_EQ(sight_stride_of_rays(0.0F), 0);
  EXPECT_EQ(SightTable::stride_of(3), 1);
  EXPECT_EQ(SightTable::stride_of(16), 16);
}

// The sampled points: one in `stride` of a chunk, each once, in increasing order; every
// stride-th point up to 4, groups of four points 4 apart beyond, each group at its phase inside
// its block of 4 stride points (sampled_count agrees). Over the phases of strides 8 and 16 every
// point of the chunk but the last three of each block is sampled.
TEST(SightTable, SamplesOnePointInStride) {
  for (const int stride : {1, 2, 4, 8, 16}) {
    const auto s = static_cast<std::size_t>(stride);
    std::vector<bool> ever(kFrontChunkPoints, false);
    for (int phase = 0; phase < 64; ++phase) {
      SCOPED_TRACE(testing::Message() << "stride " << stride << " phase " << phase);
      std::vector<std::size_t> points;
      for (std::size_t j = 0; SightTable::sampled_point(j, stride, phase) < kFrontChunkPoints; ++j) {
        points.push_back(SightTable::sampled_point(j, stride, phase));
        ever[points.back()] = true;
      }
      EXPECT_EQ(points.size(), kFrontChunkPoints / s);
      EXPECT_TRUE(std::is_sorted(points.begin(), points.end()));
      EXPECT_EQ(std::adjacent_find(points.begin(), points.end()), points.end());
      const std::size_t p = stride <= 4 ? 0U : static_cast<std::size_t>(phase) % (4U * s - 15U);
      for (std::size_t j = 0; j < points.size(); ++j) {
        const std::size_t expected = stride <= 4 ? j * s : (j / 4U) * 4U * s + p + (j % 4U) * 4U;
        EXPECT_EQ(points[j], expected);
        // A group's one load reads 4 min(stride, 4) points from its first: inside its block.
        if (j % 4U == 0U) {
          EXPECT_LE(points[j] + 4U * (stride <= 4 ? s : 4U), (j / 4U + 1U) * 4U * s) << "a group's load leaves its block";
        }
      }
      for (std::size_t count = 0; count <= kFrontChunkPoints; ++count) {
        const auto below = static_cast<std::size_t>(
            std::count_if(points.begin(), points.end(), [count](std::size_t i) { return i < count; }));
        EXPECT_EQ(SightTable::sampled_count(count, stride, phase), below) << count;
      }
    }
    if (stride > 4) {
      // Every point but the last three of each block (a group's load stays inside its block).
      const std::size_t blocks = kFrontChunkPoints / (4U * s);
      EXPECT_EQ(static_cast<std::size_t>(std::count(ever.begin(), ever.end(), true)), kFrontChunkPoints - 3U * blocks)
          << stride;
    }
  }
}

// read_cell's answer against a brute-force reading of the swept table: the sectors wholly inside
// the cell's azimuth interval (sectors_inside), the first bin beyond its farthest corner, the
// lowest and highest slope and the count of sectors holding one, taken sector by sector (on
// aarch64 read_cell takes eight sectors a turn). Frames seen by a
// 90 degree view, so that most cells' sectors hold no ray (read_cell's early answer from the
// sweep's count), and the view crosses sector 0 in some (the interval's wrap).
TEST(SightTable, ReadsEveryCellAsTheSectorBySectorLoopDoes) {
  std::mt19937 rng(3131U);
  const float bounds[5] = {1.0e30F, 1.0e30F, 1.0e30F, 1.0e30F, 1.0e30F};
  FrontConfig config{};
  ASSERT_EQ(make_front_config(kWidth, bounds, 5, &config), Status::kOk);
  std::size_t read = 0U, refused_without_rays = 0U;
  for (int trial = 0; trial < 8; ++trial) {
    const Frame f = random_frame(rng, 1.5707963F);
    FramePose pose{};
    ASSERT_EQ(make_frame_pose(f.origin, nullptr, config, &pose), Status::kOk);
    const RayWindows w = windows_around(pose.anchor);
    const auto table = begun_table(f, pose);
    const SightFrameConstants& k = table->constants();
    fill_table(f, config, pose, *table, [](const FrontChunk&, std::size_t) {});
    table->sweep();
    for (int layer = 0; layer < 5; ++layer) {
      const float cw = static_cast<float>(1 << layer);
      for (std::int32_t j = 0; j < w.side[layer]; ++j) {
        for (std::int32_t i = 0; i < w.side[layer]; ++i) {
          const std::int32_t gx = w.min[layer].x + i, gy = w.min[layer].y + j;
          const float x0 = static_cast<float>((std::int64_t{gx} * (std::int64_t{1} << layer)) - pose.anchor.x) - k.sensor_u[0];
          const float y0 = static_cast<float>((std::int64_t{gy} * (std::int64_t{1} << layer)) - pose.anchor.y) - k.sensor_u[1];
          const float x1 = x0 + cw, y1 = y0 + cw;
          // The brute force.
          const bool holds_sensor = x0 <= 0.0F && x1 >= 0.0F && y0 <= 0.0F && y1 >= 0.0F;
          const float fx = std::max(x0 * x0, x1 * x1), fy = std::max(y0 * y0, y1 * y1);
          const int bin = table->first_bin_beyond(std::sqrt(fx + fy));
          int lo = 0, hi = 0;
          const bool inside = SightTable::sectors_inside(x0, x1, y0, y1, static_cast<float>(kSightSectors) * 0.25F, &lo, &hi);
          int covered = 0;
          std::int32_t qmin = kSightEmpty, qmax = -32768;
          if (!holds_sensor && inside && bin < kSightBins) {
            for (int sector = lo; sector < hi; ++sector) {
              const std::int32_t q = table->slope(bin, sector);
              if (q != kSightEmpty) {
                ++covered;
                qmin = std::min(qmin, q);
                qmax = std::max(qmax, q);
              }
            }
          }
          SightCell c{};
          const bool answered = table->read_cell(x0, x1, y0, y1, &c);
          ASSERT_EQ(answered, covered > 0) << "trial " << trial << ": layer " << layer << " cell " << gx << "," << gy;
          if (answered) {
            EXPECT_EQ(c.qmin, qmin) << "trial " << trial << ": layer " << layer << " cell " << gx << "," << gy;
            EXPECT_EQ(c.qmax, qmax) << "trial " << trial << ": layer " << layer << " cell " << gx << "," << gy;
            EXPECT_EQ(c.covered, covered) << "trial " << trial << ": layer " << layer << " cell " << gx << "," << gy;
            EXPECT_EQ(c.bin, bin);
            ++read;
          } else if (!holds_sensor && inside && bin < kSightBins) {
            ++refused_without_rays;
          }
        }
      }
    }
  }
  // Both answers occur often: cells in the view and cells whose sectors hold no ray.
  EXPECT_GT(read, 2000U);
  EXPECT_GT(refused_without_rays, 2000U);
  std::printf("sight table: %zu cells read, %zu with no ray in their sectors\n", read, refused_without_rays);
}

// The cells pass reads only the columns row_span gives: every cell outside them must read
// nothing (read_cell false), on frames seen all around (no wedge), by a 90 and a 30 degree view
// (the wedge, crossing sector 0 in some), near and far. The spans must also leave out most cells
// of the narrow views (a span of every column would pass the first check).
TEST(SightTable, ReadsNothingOutsideTheRowSpans) {
  std::mt19937 rng(313U);
  const float bounds[5] = {1.0e30F, 1.0e30F, 1.0e30F, 1.0e30F, 1.0e30F};
  FrontConfig config{};
  ASSERT_EQ(make_front_config(kWidth, bounds, 5, &config), Status::kOk);
  std::size_t outside = 0U, inside = 0U, read = 0U;
  const float views[3] = {6.2831853F, 1.5707963F, 0.5235988F};
  for (int trial = 0; trial < 12; ++trial) {
    const Frame f = random_frame(rng, views[trial % 3]);
    FramePose pose{};
    ASSERT_EQ(make_frame_pose(f.origin, nullptr, config, &pose), Status::kOk);
    const RayWindows w = windows_around(pose.anchor);
    const auto table = begun_table(f, pose, trial % 2 == 0 ? 1 : 4);
    const SightFrameConstants& k = table->constants();
    fill_table(f, config, pose, *table, [](const FrontChunk&, std::size_t) {});
    table->sweep();
    for (int layer = 0; layer < 5; ++layer) {
      const float cw = static_cast<float>(1 << layer);
      const float bx = static_cast<float>((std::int64_t{w.min[layer].x} * (std::int64_t{1} << layer)) - pose.anchor.x) - k.sensor_u[0];
      for (std::int32_t j = 0; j < w.side[layer]; ++j) {
        const std::int32_t gy = w.min[layer].y + j;
        const float y0 = static_cast<float>((std::int64_t{gy} * (std::int64_t{1} << layer)) - pose.anchor.y) - k.sensor_u[1];
        std::int32_t lo = 0, hi = -1;
        const bool any = table->row_span(y0, y0 + cw, bx, cw, w.side[layer], &lo, &hi);
        if (any) {
          ASSERT_GE(lo, 0);
          ASSERT_LT(hi, w.side[layer]);
        }
        for (std::int32_t i = 0; i < w.side[layer]; ++i) {
          const std::int32_t gx = w.min[layer].x + i;
          const float x0 = static_cast<float>((std::int64_t{gx} * (std::int64_t{1} << layer)) - pose.anchor.x) - k.sensor_u[0];
          SightCell c{};
          const bool answered = table->read_cell(x0, x0 + cw, y0, y0 + cw, &c);
          read += answered ? 1U : 0U;
          if (any && i >= lo && i <= hi) {
            ++inside;
            continue;
          }
          ++outside;
          ASSERT_FALSE(answered) << "trial " << trial << ": layer " << layer << " cell " << gx << "," << gy
                                 << " reads a bound outside its row's span [" << lo << ", " << hi << "]";
        }
      }
    }
  }
  EXPECT_GT(read, 2000U);
  EXPECT_GT(outside, inside) << outside << " cells outside the spans, " << inside << " inside";
  std::printf("sight table: %zu cells outside the spans, %zu inside, %zu read\n", outside, inside, read);
}

}  // namespace
