// The cost raster (planner/costmap.hpp) against independent references:
//  - a raster aligned with the 4 cm cells, pixel for pixel against the point query at the pixel
//    centre (each pixel then lies in one cell of every layer): lethal, unknown, and the documented
//    cost formula evaluated in double from the point answer and the classifying layer's threshold;
//  - an unaligned, coarser raster against point queries at samples inside each pixel: every
//    hazard or unknown sample marks its pixel, every cost is at least the samples' (the raster
//    takes the worst over the whole pixel);
//  - inflation against a brute-force disc dilation (every pixel against every lethal pixel);
//  - off the map, refusals, and the stats.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "ccmap/planner/costmap.hpp"
#include "support/planner_maps.hpp"

namespace ccmap {
namespace {

using Cadre = Stack<CadreConfig>;

const Cadre& terrain_map() {
  static const std::unique_ptr<Cadre> map =
      test::terrain_stack<CadreConfig>(0.04F, test::precise_lidar_params(0.04F), 4.0, 0.012);
  return *map;
}

/// The layer whose cell classified a point answer (the first CCM layer for a constant-layer
/// answer when it knows the point: Stack::query's rule).
int classifying_layer(const Cadre& map, const QueryResult& q, float x, float y) {
  if (!Cadre::layer_is_ccm(q.layer) && map.query_layer(Cadre::kFineLayerCount, x, y).status == Status::kOk) {
    return Cadre::kFineLayerCount;
  }
  return q.layer;
}

/// The documented value of one point answer, in double.
int expected_value(const Cadre& map, const QueryResult& q, float x, float y) {
  if (q.status != Status::kOk) return 255;
  if (q.cell_class == CellClass::kObstacle || q.cell_class == CellClass::kSteep) return 254;
  const double threshold = map.normal_variance_threshold(classifying_layer(map, q, x, y));
  const double ratio = std::max(double{q.inclination} / map.params().max_inclination,
                                std::sqrt(std::max(0.0, double{q.normal_variance}) / threshold));
  return static_cast<int>(std::min(252.0, std::floor(252.0 * ratio + 0.5)));
}

TEST(Costmap, AlignedPixelsTakeThePointAnswerAtTheirCentre) {
  const Cadre& map = terrain_map();
  // 4.96 m x 4.96 m at 4 cm around (2.6, -0.12): the origin (0.12, -2.6) and every pixel edge
  // on a 4 cm cell edge; the box, the ramp, and beyond x = 4 the unobserved ground.
  constexpr int kSide = 124;
  const CostmapSpec spec{2.6F, -0.12F, 0.04F, kSide, 0.0F};
  std::vector<std::uint8_t> cost(kSide * kSide, 7U);
  CostmapStats stats{};
  ASSERT_EQ(fill_costmap(map, spec, cost.data(), cost.size(), &stats), Status::kOk);
  int wrong = 0, rounding = 0;
  int counts[4] = {0, 0, 0, 0};  // free/cost, lethal, unknown, inscribed
  for (int iy = 0; iy < kSide; ++iy) {
    for (int ix = 0; ix < kSide; ++ix) {
      const float x = 0.12F + 0.04F * (static_cast<float>(ix) + 0.5F);
      const float y = -2.6F + 0.04F * (static_cast<float>(iy) + 0.5F);
      const QueryResult q = map.query(x, y);
      const int want = expected_value(map, q, x, y);
      const int got = cost[static_cast<std::size_t>(ix + kSide * iy)];
      // A cost may differ by one where 252 * ratio sits on a rounding boundary (float vs double).
      if (got != want && !(want <= 252 && got <= 252 && std::abs(got - want) <= 1)) {
        if (wrong++ < 5) {
          ADD_FAILURE() << "pixel (" << ix << ", " << iy << ") at (" << x << ", " << y << "): " << got << ", point query "
                        << want << " (layer " << q.layer << ", " << to_string(q.cell_class) << ")";
        }
      }
      rounding += got != want ? 1 : 0;
      ++counts[got <= 252 ? 0 : (got == 254 ? 1 : (got == 255 ? 2 : 3))];
    }
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_LE(rounding, 10) << "costs one off from the double evaluation";
  EXPECT_GT(counts[1], 20) << "the box and the ramp are lethal";
  EXPECT_GT(counts[2], 20) << "the unobserved ground beyond x = 4 is unknown";
  EXPECT_EQ(counts[3], 0) << "no inflation asked";
  EXPECT_EQ(stats.lethal, static_cast<std::uint32_t>(counts[1]));
  EXPECT_EQ(stats.unknown, static_cast<std::uint32_t>(counts[2]));
  EXPECT_EQ(stats.free + stats.cost, static_cast<std::uint32_t>(counts[0]));
  EXPECT_GT(stats.cells_visited, static_cast<std::uint32_t>(kSide * kSide / 4));
}

TEST(Costmap, EachPixelTakesTheWorstOfItsWholeSquare) {
  const Cadre& map = terrain_map();
  // 10 cm pixels, origin off the cell grid: every pixel spans parts of several cells.
  const CostmapSpec spec{0.013F, 0.029F, 0.1F, 60U, 0.0F};
  std::vector<std::uint8_t> cost(60U * 60U);
  ASSERT_EQ(fill_costmap(map, spec, cost.data(), cost.size(), nullptr), Status::kOk);
  const float x0 = 0.013F - 3.0F, y0 = 0.029F - 3.0F;
  int violations = 0, hazard_pixels = 0;
  for (int iy = 0; iy < 60; ++iy) {
    for (int ix = 0; ix < 60; ++ix) {
      const int got = cost[static_cast<std::size_t>(ix + 60 * iy)];
      bool lethal = false, unknown = false;
      int max_cost = 0;
      for (int sy = 0; sy < 6; ++sy) {
        for (int sx = 0; sx < 6; ++sx) {
          const float x = x0 + 0.1F * (static_cast<float>(ix) + (static_cast<float>(sx) + 0.5F) / 6.0F);
          const float y = y0 + 0.1F * (static_cast<float>(iy) + (static_cast<float>(sy) + 0.5F) / 6.0F);
          const QueryResult q = map.query(x, y);
          const int v = expected_value(map, q, x, y);
          lethal = lethal || v == 254;
          unknown = unknown || v == 255;
          if (v <= 252) max_cost = std::max(max_cost, v);
        }
      }
      const bool ok = lethal ? got == 254 : (unknown ? (got == 254 || got == 255) : (got >= 254 || got + 1 >= max_cost));
      hazard_pixels += got == 254 ? 1 : 0;
      if (!ok && violations++ < 5) {
        ADD_FAILURE() << "pixel (" << ix << ", " << iy << "): " << got << " but samples inside it say lethal " << lethal
                      << ", unknown " << unknown << ", cost up to " << max_cost;
      }
    }
  }
  EXPECT_EQ(violations, 0);
  EXPECT_GT(hazard_pixels, 5);
}

TEST(Costmap, InflationMarksTheDiscAroundLethalPixelsAndOnlyCostPixels) {
  const Cadre& map = terrain_map();
  for (const float radius : {0.04F, 0.1F, 0.3F, 0.32F}) {
    const CostmapSpec plain{0.2F, -0.12F, 0.04F, 125U, 0.0F};
    const CostmapSpec inflated{0.2F, -0.12F, 0.04F, 125U, radius};
    std::vector<std::uint8_t> a(125U * 125U), b(125U * 125U);
    ASSERT_EQ(fill_costmap(map, plain, a.data(), a.size(), nullptr), Status::kOk);
    CostmapStats stats{};
    ASSERT_EQ(fill_costmap(map, inflated, b.data(), b.size(), &stats), Status::kOk);
    std::vector<std::pair<int, int>> lethal;
    for (int i = 0; i < 125 * 125; ++i) {
      if (a[static_cast<std::size_t>(i)] == 254) lethal.emplace_back(i % 125, i / 125);
    }
    ASSERT_FALSE(lethal.empty());
    int wrong = 0, inscribed = 0;
    // The radius in pixels as documented (radius / resolution in float), centres on the circle
    // inside.
    const double r_px = static_cast<double>(radius / 0.04F) + 1e-4;
    for (int iy = 0; iy < 125; ++iy) {
      for (int ix = 0; ix < 125; ++ix) {
        const std::uint8_t before = a[static_cast<std::size_t>(ix + 125 * iy)];
        bool near = false;
        for (const auto& [lx, ly] : lethal) {
          const double d2 = double(ix - lx) * (ix - lx) + double(iy - ly) * (iy - ly);
          near = near || d2 <= r_px * r_px;
        }
        const std::uint8_t want = before <= 252 && near ? 253 : before;
        const std::uint8_t got = b[static_cast<std::size_t>(ix + 125 * iy)];
        inscribed += got == 253 ? 1 : 0;
        if (got != want && wrong++ < 5) {
          ADD_FAILURE() << "radius " << radius << ", pixel (" << ix << ", " << iy << "): " << int(got) << ", expected "
                        << int(want);
        }
      }
    }
    EXPECT_EQ(wrong, 0);
    EXPECT_GT(inscribed, 0);
    EXPECT_EQ(stats.inscribed, static_cast<std::uint32_t>(inscribed));
  }
}

TEST(Costmap, InflatingACallersRasterMatchesBruteForce) {
  // A 37 x 23 raster (not square) with scattered lethal, unknown and cost pixels.
  constexpr std::uint32_t kW = 37, kH = 23;
  std::vector<std::uint8_t> raster(kW * kH);
  std::uint32_t h = 7U;
  for (std::uint8_t& v : raster) {
    h = h * 1664525U + 1013904223U;
    const std::uint32_t r = h >> 24;
    v = r < 6 ? 254 : (r < 30 ? 255 : static_cast<std::uint8_t>(r % 200));
  }
  for (const float radius : {0.0F, 1.0F, 2.5F, 4.0F}) {
    std::vector<std::uint8_t> got = raster;
    ASSERT_EQ(inflate_costmap(got.data(), got.size(), kW, kH, radius), Status::kOk);
    int wrong = 0;
    for (std::uint32_t y = 0; y < kH; ++y) {
      for (std::uint32_t x = 0; x < kW; ++x) {
        bool near = false;
        for (std::uint32_t yy = 0; yy < kH; ++yy)
          for (std::uint32_t xx = 0; xx < kW; ++xx) {
            const double d2 = (double(x) - xx) * (double(x) - xx) + (double(y) - yy) * (double(y) - yy);
            near = near || (raster[yy * kW + xx] == 254 && d2 <= (radius + 1e-4) * (radius + 1e-4));
          }
        const std::uint8_t before = raster[y * kW + x];
        const std::uint8_t want = before <= 252 && near ? 253 : before;
        wrong += got[y * kW + x] != want ? 1 : 0;
      }
    }
    EXPECT_EQ(wrong, 0) << "radius " << radius << " px";
  }
  std::vector<std::uint8_t> untouched = raster;
  EXPECT_EQ(inflate_costmap(nullptr, 10, kW, kH, 1.0F), Status::kInvalidArgument);
  EXPECT_EQ(inflate_costmap(untouched.data(), untouched.size() - 1, kW, kH, 1.0F), Status::kInvalidArgument);
  EXPECT_EQ(inflate_costmap(untouched.data(), untouched.size(), 0U, kH, 1.0F), Status::kInvalidArgument);
  EXPECT_EQ(inflate_costmap(untouched.data(), untouched.size(), kMaxCostmapSide + 1U, 1U, 1.0F), Status::kInvalidArgument);
  EXPECT_EQ(inflate_costmap(untouched.data(), untouched.size(), kW, kH, std::nanf("")), Status::kNonFiniteInput);
  EXPECT_EQ(inflate_costmap(untouched.data(), untouched.size(), kW, kH, -1.0F), Status::kOutOfRange);
  EXPECT_EQ(inflate_costmap(untouched.data(), untouched.size(), kW, kH, 33.0F), Status::kOutOfRange);
  EXPECT_EQ(untouched, raster) << "a refused call changed the raster";
}

TEST(Costmap, OffTheMapIsUnknown) {
  const Cadre& map = terrain_map();
  std::vector<std::uint8_t> cost(50U * 50U);
  CostmapStats stats{};
  ASSERT_EQ(fill_costmap(map, CostmapSpec{100.0F, 0.0F, 0.1F, 50U, 0.2F}, cost.data(), cost.size(), &stats), Status::kOk);
  EXPECT_TRUE(std::all_of(cost.begin(), cost.end(), [](std::uint8_t c) { return c == 255; }));
  EXPECT_EQ(stats.unknown, 2500U);
  EXPECT_EQ(stats.cells_visited, 0U);
  // Straddling the edge of the coarsest window (x = 10.24): pixels beyond it are unknown.
  ASSERT_EQ(fill_costmap(map, CostmapSpec{10.24F, 0.0F, 0.08F, 50U, 0.0F}, cost.data(), cost.size(), nullptr),
            Status::kOk);
  for (int iy = 0; iy < 50; ++iy) {
    for (int ix = 25; ix < 50; ++ix) EXPECT_EQ(cost[static_cast<std::size_t>(ix + 50 * iy)], 255) << ix << ", " << iy;
  }
}

TEST(Costmap, ARowBudgetFillsTheCentralBandAndLeavesTheRestUnknownAndCounted) {
  // The reference is the same raster without a budget (the tests above hold it to the point
  // answers): inside the band every pixel farther than the inflation radius from the band's edge
  // equals it (a lethal pixel outside the band, unknown there, inflates nothing inside), every
  // pixel outside the band is 255 and counted, never free.
  const Cadre& map = terrain_map();
  constexpr std::uint32_t kSide = 100U;
  constexpr float kRadiusM = 0.12F;  // 3 pixels of 4 cm
  constexpr std::uint32_t kRadiusPx = 3U;
  std::vector<std::uint8_t> full(kSide * kSide);
  CostmapStats full_stats{};
  ASSERT_EQ(fill_costmap(map, CostmapSpec{0.5F, 0.2F, 0.04F, kSide, kRadiusM}, full.data(), full.size(), &full_stats),
            Status::kOk);
  EXPECT_EQ(full_stats.rows_skipped, 0U);
  for (const std::uint32_t rows : {1U, 17U, 40U, 99U}) {
    std::vector<std::uint8_t> band(kSide * kSide, 7U);
    CostmapSpec spec{0.5F, 0.2F, 0.04F, kSide, kRadiusM};
    spec.max_rows = rows;
    CostmapStats stats{};
    ASSERT_EQ(fill_costmap(map, spec, band.data(), band.size(), &stats), Status::kOk);
    const std::uint32_t first = (kSide - rows) / 2U;
    EXPECT_EQ(stats.rows_skipped, kSide - rows);
    std::uint32_t unknown_outside = 0U;
    for (std::uint32_t iy = 0; iy < kSide; ++iy) {
      const bool inside = iy >= first && iy < first + rows;
      const bool clear_of_edges = iy >= first + kRadiusPx && iy + kRadiusPx < first + rows;
      for (std::uint32_t ix = 0; ix < kSide; ++ix) {
        const std::size_t at = ix + kSide * iy;
        if (!inside) {
          EXPECT_EQ(band[at], kCostUnknown) << "budget " << rows << ": pixel (" << ix << ", " << iy << ") outside the band";
          unknown_outside += band[at] == kCostUnknown ? 1U : 0U;
        } else if (clear_of_edges) {
          EXPECT_EQ(band[at], full[at]) << "budget " << rows << ": pixel (" << ix << ", " << iy << ") differs";
        } else {
          // Near the band's edge only inflation may differ: never a lethal or unknown pixel.
          EXPECT_TRUE(band[at] == full[at] || (full[at] == kCostInscribed && band[at] <= kCostMaxTraversable))
              << "budget " << rows << ": pixel (" << ix << ", " << iy << ")";
        }
      }
    }
    EXPECT_EQ(unknown_outside, (kSide - rows) * kSide);
    EXPECT_EQ(stats.free + stats.cost + stats.inscribed + stats.lethal + stats.unknown, kSide * kSide);
    EXPECT_GE(stats.unknown, (kSide - rows) * kSide);
  }
  // A budget of 0 or of the side and above is no budget.
  for (const std::uint32_t rows : {0U, kSide, kSide + 5U}) {
    std::vector<std::uint8_t> all(kSide * kSide);
    CostmapSpec spec{0.5F, 0.2F, 0.04F, kSide, kRadiusM};
    spec.max_rows = rows;
    CostmapStats stats{};
    ASSERT_EQ(fill_costmap(map, spec, all.data(), all.size(), &stats), Status::kOk);
    EXPECT_EQ(all, full) << "budget " << rows;
    EXPECT_EQ(stats.rows_skipped, 0U);
  }
}

TEST(Costmap, RefusesBadInputAndLeavesTheBufferAlone) {
  const Cadre& map = terrain_map();
  std::vector<std::uint8_t> cost(100U * 100U, 42U);
  const CostmapSpec good{0.0F, 0.0F, 0.04F, 100U, 0.2F};
  EXPECT_EQ(fill_costmap(map, good, nullptr, cost.size(), nullptr), Status::kInvalidArgument);
  EXPECT_EQ(fill_costmap(map, good, cost.data(), cost.size() - 1, nullptr), Status::kBufferTooSmall);
  EXPECT_EQ(fill_costmap(map, CostmapSpec{0.0F, 0.0F, 0.0F, 100U, 0.0F}, cost.data(), cost.size(), nullptr),
            Status::kInvalidArgument);
  EXPECT_EQ(fill_costmap(map, CostmapSpec{0.0F, 0.0F, 0.04F, 0U, 0.0F}, cost.data(), cost.size(), nullptr),
            Status::kInvalidArgument);
  EXPECT_EQ(fill_costmap(map, CostmapSpec{0.0F, 0.0F, 0.04F, kMaxCostmapSide + 1U, 0.0F}, cost.data(), cost.size(),
                         nullptr),
            Status::kInvalidArgument);
  EXPECT_EQ(fill_costmap(map, CostmapSpec{0.0F, 0.0F, 0.04F, 100U, -0.1F}, cost.data(), cost.size(), nullptr),
            Status::kInvalidArgument);
  EXPECT_EQ(fill_costmap(map, CostmapSpec{std::nanf(""), 0.0F, 0.04F, 100U, 0.0F}, cost.data(), cost.size(), nullptr),
            Status::kNonFiniteInput);
  EXPECT_EQ(fill_costmap(map, CostmapSpec{0.0F, 0.0F, INFINITY, 100U, 0.0F}, cost.data(), cost.size(), nullptr),
            Status::kNonFiniteInput);
  EXPECT_EQ(fill_costmap(map, CostmapSpec{1e5F, 0.0F, 0.04F, 100U, 0.0F}, cost.data(), cost.size(), nullptr),
            Status::kOutOfRange);
  EXPECT_EQ(fill_costmap(map, CostmapSpec{0.0F, 0.0F, 0.04F, 100U, 1.3F}, cost.data(), cost.size(), nullptr),
            Status::kOutOfRange)
      << "33 pixels of inflation";
  EXPECT_TRUE(std::all_of(cost.begin(), cost.end(), [](std::uint8_t c) { return c == 42; }))
      << "a refused call wrote into the buffer";
  const auto fresh = std::make_unique<Cadre>();
  EXPECT_EQ(fill_costmap(*fresh, good, cost.data(), cost.size(), nullptr), Status::kNotInitialised);
}

TEST(Costmap, TheCostFunctionIsTheDocumentedOne) {
  EXPECT_EQ(traversable_cost(0.0F, 0.36F, 0.0F, 1e-4F), 0);
  EXPECT_EQ(traversable_cost(0.18F, 0.36F, 0.0F, 1e-4F), 126);  // half the inclination limit
  EXPECT_EQ(traversable_cost(0.0F, 0.36F, 0.25e-4F, 1e-4F), 126);  // half the relief
  EXPECT_EQ(traversable_cost(0.09F, 0.36F, 0.25e-4F, 1e-4F), 126);  // the larger ratio
  EXPECT_EQ(traversable_cost(0.36F, 0.36F, 0.0F, 1e-4F), 252);
  EXPECT_EQ(traversable_cost(1.0F, 0.36F, 0.0F, 1e-4F), 252);  // saturates
  EXPECT_EQ(traversable_cost(std::nanf(""), 0.36F, 0.0F, 1e-4F), 252);
}

}  // namespace
}  // namespace ccmap
