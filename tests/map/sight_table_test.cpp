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
SightFrameConstants constants_of(const Frame& f, const FramePose& pose) {
  SightFrameConstants k{};
  k.sensor_u[0] = pose.anchor_fraction[0];
  k.sensor_u[1] = pose.anchor_fraction[1];
  k.z0 = f.origin.z;
  k.bin_scale = static_cast<float>(kSightBins) / std::sqrt(512.0F * 1.5F);
  k.cell_width_m = kWidth;
  k.sigma_c[2] = 3.0F * kStereoK;
  k.layers = 5;
  return k;
}

/// A table begun for the frame (on the heap: 261 KB).
std::unique_ptr<SightTable> begun_table(const Frame& f, const FramePose& pose) {
  auto table = std::make_unique<SightTable>();
  table->begin(constants_of(f, pose));
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

TEST(SightTable, NeverBoundsACellBelowTheLowestWalkedRayAndBoundsMostOfThem) {
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
    const auto table = begun_table(f, pose);
    const SightFrameConstants& k = table->constants();
    // The reference: lowest walked height per (layer, cell).
    std::map<std::tuple<int, std::int32_t, std::int32_t>, float> lowest;
    const std::int64_t ou[2] = {ray_u(pose.anchor.x, pose.anchor_fraction[0]), ray_u(pose.anchor.y, pose.anchor_fraction[1])};
    fill_table(f, config, pose, *table, [&](const FrontChunk& chunk, std::size_t count) {
      for (std::size_t i = 0; i < count; ++i) {
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
  EXPECT_GT(static_cast<double>(table_cells), 0.6 * static_cast<double>(walked_cells))
      << table_cells << " of " << walked_cells << " walked cells bounded by the table";
  std::printf("sight table: %zu of %zu walked cells bounded\n", table_cells, walked_cells);
}

// read_cell's answer against a brute-force reading of the swept table: the sectors wholly inside
// the cell's azimuth interval (sectors_inside), the first bin beyond its farthest corner, the
// lowest slope and the count of sectors holding one, taken sector by sector. Frames seen by a
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
          std::int32_t qmin = kSightEmpty;
          if (!holds_sensor && inside && bin < kSightBins) {
            for (int sector = lo; sector < hi; ++sector) {
              const std::int32_t q = table->slope(bin, sector);
              if (q != kSightEmpty) {
                ++covered;
                qmin = std::min(qmin, q);
              }
            }
          }
          SightCell c{};
          const bool answered = table->read_cell(x0, x1, y0, y1, &c);
          ASSERT_EQ(answered, covered > 0) << "trial " << trial << ": layer " << layer << " cell " << gx << "," << gy;
          if (answered) {
            EXPECT_EQ(c.qmin, qmin) << "trial " << trial << ": layer " << layer << " cell " << gx << "," << gy;
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

}  // namespace
