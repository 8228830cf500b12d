// The ccmap tool maps whole clouds by sweeping the stack over them in tiles (tools/cli/tiling.hpp).
// References: a brute-force count and a double-precision batch (tests/support/reference.hpp) of
// the points of every cell, and the library itself mapping a cloud that fits one window in one
// frame (no tiling involved).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "ccmap/grid/ring_grid.hpp"
#include "ccmap/map/stack.hpp"
#include "cli_run.hpp"
#include "map_runner.hpp"
#include "support/hash_unit.hpp"
#include "support/reference.hpp"
#include "temp_dir.hpp"
#include "tiling.hpp"

namespace fs = std::filesystem;
using ccmap::test::CliRun;
using ccmap::test::hash_unit;
using ccmap::test::read_rows;
using ccmap::test::run_ccmap;
using ccmap::test::TempDir;
using ccmap::test::XyzPoint;
using ccmap::tools::LayerCellRow;

namespace {

const char* const kTempPrefix = "ccmap_tiling_test_";
using Cell = std::pair<long long, long long>;

Cell cell_of(double x, double y, double w) {
  return {std::llround(std::floor(x / w)), std::llround(std::floor(y / w))};
}

/// The cells a point may belong to: one, or two per axis when it lies within 1e-7 m of an
/// edge (there the tool's double arithmetic decides, and either answer is right).
std::vector<Cell> candidate_cells(double x, double y, double w) {
  const double eps = 1e-7;
  std::set<Cell> c;
  for (double dx : {-eps, 0.0, eps}) {
    for (double dy : {-eps, 0.0, eps}) c.insert(cell_of(x + dx, y + dy, w));
  }
  return {c.begin(), c.end()};
}

/// Parses "origin (map frame): X Y Z" from the tool's output.
bool parse_origin(const std::string& out, double o[3]) {
  const std::size_t at = out.find("origin (map frame): ");
  return at != std::string::npos &&
         std::sscanf(out.c_str() + at, "origin (map frame): %lf %lf %lf", &o[0], &o[1], &o[2]) == 3;
}

std::vector<std::vector<LayerCellRow>> map_with_cli(const TempDir& dir, const std::string& preset,
                                                    const std::vector<XyzPoint>& points, std::string* out) {
  ccmap::test::write_ply(dir / (preset + ".ply"), points);
  const CliRun r = run_ccmap({"map", "--preset", preset, "--cloud", (dir / (preset + ".ply")).string(), "--out",
                              (dir / preset).string()});
  EXPECT_EQ(r.code, 0) << r.err;
  *out = r.out;
  std::vector<std::vector<LayerCellRow>> layers;
  const int count = ccmap::tools::preset_layer_count(preset);
  for (int k = 0; k < count; ++k) layers.push_back(read_rows(dir / preset / ("layer_" + std::to_string(k) + ".csv")));
  return layers;
}

// =============================================================================================
// Every point's cell, every layer, exactly once, with all its points (brute-force count)
// =============================================================================================

TEST(Tiling, EveryPointsCellOfEveryLayerIsExportedOnceWithAllItsPoints) {
  // 600 random 4 cm cells over 7.7 x 5.1 m (CADRE tiles are 1.92 m: 5 x 3 tiles and more), 1-6
  // points each, and points within 1e-9 m of every 64 cm grid line (tile edges among them),
  // where the float tile frame would put a point across the edge without the tool's care.
  const double x0 = 640.0, y0 = 384.0, w0 = 0.04;
  std::vector<XyzPoint> points;
  for (std::uint32_t c = 0; c < 600; ++c) {
    const long long ix = static_cast<long long>(hash_unit(c, 1) * 192.0F), iy = static_cast<long long>(hash_unit(c, 2) * 128.0F);
    const int n = 1 + static_cast<int>(hash_unit(c, 3) * 6.0F);
    for (int i = 0; i < n; ++i) {
      const double u = 0.02 + 0.96 * static_cast<double>(hash_unit(c * 8U + static_cast<std::uint32_t>(i), 4));
      const double v = 0.02 + 0.96 * static_cast<double>(hash_unit(c * 8U + static_cast<std::uint32_t>(i), 5));
      const double x = x0 + (static_cast<double>(ix) + u) * w0, y = y0 + (static_cast<double>(iy) + v) * w0;
      points.push_back(XyzPoint{x, y, 10.0 + 0.05 * (x - x0) + 0.01 * static_cast<double>(hash_unit(c, 6))});
    }
  }
  for (int k = 0; k <= 12; ++k) {
    for (double d : {-1e-9, 0.0, 1e-9}) {
      const double line = x0 + 0.64 * k;
      points.push_back(XyzPoint{line + d, y0 + 1.0 + 0.3 * k, 10.0});
      points.push_back(XyzPoint{x0 + 2.0 + 0.4 * k, y0 + 0.64 * (k % 8) + d, 10.0});
    }
  }
  const TempDir dir(kTempPrefix);
  std::string out;
  const std::vector<std::vector<LayerCellRow>> layers = map_with_cli(dir, "cadre", points, &out);
  ASSERT_EQ(layers.size(), 5U);
  long long read = 0, used = 0;
  ASSERT_TRUE(ccmap::test::summary_counts(out, &read, &used)) << out;
  EXPECT_EQ(used, static_cast<long long>(points.size())) << out;
  for (int k = 0; k < 5; ++k) {
    const double w = w0 * std::ldexp(1.0, k);
    std::map<Cell, double> counts;           // points of unambiguous cells
    std::set<Cell> possible, ambiguous;
    for (const XyzPoint& p : points) {
      const std::vector<Cell> c = candidate_cells(p.x, p.y, w);
      possible.insert(c.begin(), c.end());
      if (c.size() == 1) {
        counts[c[0]] += 1.0;
      } else {
        ambiguous.insert(c.begin(), c.end());
      }
    }
    std::set<Cell> seen;
    double total = 0.0;
    for (const LayerCellRow& r : layers[static_cast<std::size_t>(k)]) {
      const Cell c{r.ix, r.iy};
      EXPECT_TRUE(seen.insert(c).second) << "layer " << k << ": cell " << r.ix << "," << r.iy << " exported twice";
      EXPECT_EQ(possible.count(c), 1U) << "layer " << k << ": cell " << r.ix << "," << r.iy << " holds no point";
      // Kalman cells count their points; pooled CCM cells sum their children's (no limiter here).
      if (ambiguous.count(c) == 0) {
        EXPECT_EQ(r.weight, counts[c]) << "layer " << k << ": cell " << r.ix << "," << r.iy << " lacks points";
      }
      total += r.weight;
    }
    for (const auto& [c, n] : counts) {
      EXPECT_EQ(seen.count(c), 1U) << "layer " << k << ": cell " << c.first << "," << c.second << " (" << n
                                   << " points) missing";
    }
    EXPECT_EQ(total, static_cast<double>(points.size())) << "layer " << k << ": every point counted exactly once";
  }
}

// =============================================================================================
// CCM cells against a double-precision batch of their points
// =============================================================================================

TEST(Tiling, CcmCellsEqualADoublePrecisionBatchOfTheirPoints) {
  // 1500 random 8 cm cells over 61 x 41 m (3 x 2 tiles of 20.48 m), 3-12 points each, on a
  // tilted surface with a per-cell bump: the ccm preset's row of each cell must equal the
  // least-squares statistics of exactly its points, computed in double from the raw points (the
  // least-squares plane of the full CCM cell).
  const double x0 = 2000.0, y0 = 3000.0, w = 0.08;
  std::map<Cell, std::vector<ccmap::test::Point>> truth;  // points relative to the cell centre
  std::vector<XyzPoint> points;
  for (std::uint32_t c = 0; c < 1500; ++c) {
    const long long ix = static_cast<long long>(hash_unit(c, 11) * 762.0F), iy = static_cast<long long>(hash_unit(c, 12) * 512.0F);
    const int n = 3 + static_cast<int>(hash_unit(c, 13) * 10.0F);
    const Cell cell = cell_of(x0 + (static_cast<double>(ix) + 0.5) * w, y0 + (static_cast<double>(iy) + 0.5) * w, w);
    if (!truth[cell].empty()) continue;  // one batch per cell
    for (int i = 0; i < n; ++i) {
      const std::uint32_t id = c * 16U + static_cast<std::uint32_t>(i);
      const double u = 0.01 + 0.98 * static_cast<double>(hash_unit(id, 14)), v = 0.01 + 0.98 * static_cast<double>(hash_unit(id, 15));
      const double x = x0 + (static_cast<double>(ix) + u) * w, y = y0 + (static_cast<double>(iy) + v) * w;
      const double z = 50.0 + 0.15 * (x - x0) - 0.05 * (y - y0) + 0.02 * static_cast<double>(hash_unit(id, 16));
      points.push_back(XyzPoint{x, y, z});
      const double cx = (static_cast<double>(cell.first) + 0.5) * w, cy = (static_cast<double>(cell.second) + 0.5) * w;
      truth[cell].push_back(ccmap::test::Point{x - cx, y - cy, z});
    }
  }
  const TempDir dir(kTempPrefix);
  std::string out;
  const std::vector<std::vector<LayerCellRow>> layers = map_with_cli(dir, "ccm", points, &out);
  ASSERT_EQ(layers.size(), 1U);
  ASSERT_EQ(layers[0].size(), truth.size()) << out;
  std::size_t skipped = 0;
  for (const LayerCellRow& r : layers[0]) {
    const auto it = truth.find(Cell{r.ix, r.iy});
    ASSERT_NE(it, truth.end()) << "cell " << r.ix << "," << r.iy << " holds no point";
    const ccmap::test::RefMoments m = ccmap::test::reference_moments(it->second);
    // The full CCM cell's documented rule (docs/design.md 2.4): the least-squares plane, except
    // that a lateral covariance with det <= 1e-4 trace^2 is a line (its pseudo-inverse); cells
    // within 20 % of that bound are skipped (the float and the double may decide either way).
    const double trace = m.var_xx + m.var_yy, det = m.var_xx * m.var_yy - m.cov_xy * m.cov_xy;
    const double conditioning = det / (trace * trace);
    if (std::fabs(conditioning - 1e-4) < 0.2e-4) {
      ++skipped;
      continue;
    }
    double a = 0.0, b = 0.0, residual = 0.0;
    if (conditioning > 1e-4) {
      ccmap::test::RefPlane plane;
      ASSERT_TRUE(ccmap::test::reference_plane(it->second, &plane));
      a = plane.a;
      b = plane.b;
      residual = plane.residual_variance;
    } else {
      a = (m.var_xx * m.cov_xz + m.cov_xy * m.cov_yz) / (trace * trace);
      b = (m.cov_xy * m.cov_xz + m.var_yy * m.cov_yz) / (trace * trace);
      residual = std::max(0.0, m.var_zz - a * m.cov_xz - b * m.cov_yz);
    }
    const double height = m.mean_z - a * m.mean_x - b * m.mean_y;  // eq. (10) at the cell centre
    const std::string where = "cell " + std::to_string(r.ix) + "," + std::to_string(r.iy);
    EXPECT_EQ(r.weight, m.weight) << where;
    // The weight is exact: the cell holds exactly its points. The rest agrees to the core's
    // precision: CCM positions are floats relative to the cell (micrometres at most), which a
    // 3-point cell's plane amplifies (worst seen: 0.14 mm, slope 2.2e-3). Far below any threshold.
    EXPECT_NEAR(r.height, height, 3e-4) << where;
    EXPECT_NEAR(r.slope_x, a, 5e-3 * (1.0 + std::fabs(a))) << where;
    EXPECT_NEAR(r.slope_y, b, 5e-3 * (1.0 + std::fabs(b))) << where;
    EXPECT_NEAR(r.normal_var, residual, 1e-3 * residual + 5e-8) << where;
  }
  EXPECT_LT(skipped, truth.size() / 100) << "cells too close to the line guard to judge";
}

// =============================================================================================
// Tiled map == the library's one-window map of a cloud that fits one window
// =============================================================================================

/// A tilted surface with a 30 cm step at local x = 0, a 25 cm ridge over x in [0.52, 0.70) m and
/// 1 mm of noise, on a jittered grid of `spacing` over [-hx, hx] x [-hy, hy] around (cx, cy).
/// The step and the centre lines are tile edges of the tool, so its border cells need the
/// neighbours from the next tile (roughness filter); the ridge's edges lie inside cells of
/// every layer (CCM obstacles). Points keep >= 0.1 spacing from the lattice lines, which hold
/// every cell edge: no point is near an edge, where float and double may disagree.
std::vector<XyzPoint> step_scene(double cx, double cy, double hx, double hy, double spacing) {
  std::vector<XyzPoint> points;
  const int nx = static_cast<int>(std::lround(2 * hx / spacing)), ny = static_cast<int>(std::lround(2 * hy / spacing));
  std::uint32_t id = 0;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i, ++id) {
      const double lx = -hx + spacing * (i + 0.1 + 0.8 * static_cast<double>(hash_unit(id, 21)));
      const double ly = -hy + spacing * (j + 0.1 + 0.8 * static_cast<double>(hash_unit(id, 22)));
      const double z = 100.0 + 0.2 * lx - 0.1 * ly + (lx >= 0.0 ? 0.3 : 0.0) + (lx >= 0.52 && lx < 0.70 ? 0.25 : 0.0) +
                       0.001 * static_cast<double>(hash_unit(id, 23));
      points.push_back(XyzPoint{cx + lx, cy + ly, z});
    }
  }
  return points;
}

struct RefRow {
  double weight, height, slope_x, slope_y, normal_var, elev_var;
  std::string cell_class;
};

/// The library alone: one Stack<Config> centred on (ox, oy), every point in one frame (local
/// coordinates subtracted in double), the tool's parameters (default params, lidar 5 mm).
template <typename Config>
std::vector<std::map<Cell, RefRow>> one_window_map(const std::vector<XyzPoint>& points, const double origin[3],
                                                   float finest) {
  auto stack = std::make_unique<ccmap::Stack<Config>>();
  ccmap::StackParams params = ccmap::default_stack_params(finest);
  params.noise = ccmap::sensor::NoiseModel::lidar(ccmap::sensor::LidarParams{0.005F, 0.0F});
  params.outlier_gate_sigma = 0.0F;  // as the CLI maps by default (tools/cli/map_runner.hpp)
  EXPECT_EQ(stack->init(params), ccmap::Status::kOk);
  EXPECT_EQ(stack->move_to(0.0F, 0.0F), ccmap::Status::kOk);
  std::vector<ccmap::PointXYZ> local;
  for (const XyzPoint& p : points) {
    local.push_back(ccmap::PointXYZ{static_cast<float>(p.x - origin[0]), static_cast<float>(p.y - origin[1]),
                                    static_cast<float>(p.z - origin[2])});
  }
  ccmap::FrameCounters counters{};
  EXPECT_EQ(stack->update_frame(local.data(), local.size(), ccmap::PointXYZ{0.0F, 0.0F, 0.0F}, &counters),
            ccmap::Status::kOk);
  EXPECT_EQ(counters.used, local.size()) << "the reference cloud must fit the one window";
  std::vector<std::map<Cell, RefRow>> layers;
  for (int k = 0; k < ccmap::Stack<Config>::kLayerCount; ++k) {
    std::vector<ccmap::CellRecord> records(ccmap::Stack<Config>::layer_capacity(k));
    std::size_t written = 0;
    EXPECT_EQ(stack->export_layer(k, records.data(), records.size(), &written), ccmap::Status::kOk);
    const double w = static_cast<double>(finest) * std::ldexp(1.0, k);
    const long long ox = std::llround(origin[0] / w), oy = std::llround(origin[1] / w);
    std::map<Cell, RefRow> rows;
    for (std::size_t i = 0; i < written; ++i) {
      const ccmap::CellRecord& c = records[i];
      rows[Cell{ox + c.index.x, oy + c.index.y}] =
          RefRow{c.weight, static_cast<double>(c.height_m) + origin[2], c.slope_x, c.slope_y, c.normal_variance,
                 c.elevation_variance, ccmap::to_string(c.cell_class)};
    }
    layers.push_back(std::move(rows));
  }
  return layers;
}

template <typename Config>
void expect_tiled_equals_one_window(const std::string& preset, const std::vector<XyzPoint>& points, float finest,
                                    double cx, double cy) {
  const TempDir dir(kTempPrefix);
  std::string out;
  const std::vector<std::vector<LayerCellRow>> tiled = map_with_cli(dir, preset, points, &out);
  double origin[3] = {0.0, 0.0, 0.0};
  ASSERT_TRUE(parse_origin(out, origin)) << out;
  ASSERT_NEAR(origin[0], cx, 1e-6) << "the scene is centred on a coarse grid point: the tool's origin";
  ASSERT_NEAR(origin[1], cy, 1e-6);
  origin[0] = cx;  // exactly
  origin[1] = cy;
  ASSERT_NE(out.find("tiles mapped: 4"), std::string::npos) << preset << ": the scene must span 2 x 2 tiles\n" << out;
  const std::vector<std::map<Cell, RefRow>> reference = one_window_map<Config>(points, origin, finest);
  ASSERT_EQ(tiled.size(), reference.size());
  for (std::size_t k = 0; k < tiled.size(); ++k) {
    ASSERT_EQ(tiled[k].size(), reference[k].size()) << preset << " layer " << k;
    std::size_t classes[4] = {0, 0, 0, 0};
    for (const LayerCellRow& r : tiled[k]) {
      const auto it = reference[k].find(Cell{r.ix, r.iy});
      ASSERT_NE(it, reference[k].end()) << preset << " layer " << k << " cell " << r.ix << "," << r.iy;
      const RefRow& e = it->second;
      const std::string where = preset + " layer " + std::to_string(k) + " cell " + std::to_string(r.ix) + "," +
                                std::to_string(r.iy) + " (x " + std::to_string(r.cx - cx) + " m from the centre)";
      // The two runs place x, y in different frames (tile corner vs window centre), so the float
      // positions of a CCM point differ in their last bits: worst seen 42 um of height and 1.1e-3
      // of slope in a cell holding a 25 cm step. Piece-wise constant cells agree to the CSV's 1 um.
      EXPECT_NEAR(r.weight, e.weight, 1e-4 * e.weight) << where;
      EXPECT_NEAR(r.height, e.height, 1e-4) << where;
      EXPECT_NEAR(r.slope_x, e.slope_x, 3e-3 * (1.0 + std::fabs(e.slope_x))) << where;
      EXPECT_NEAR(r.slope_y, e.slope_y, 3e-3 * (1.0 + std::fabs(e.slope_y))) << where;
      EXPECT_NEAR(r.normal_var, e.normal_var, 1e-3 * e.normal_var + 1e-8) << where;
      EXPECT_NEAR(r.elev_var, e.elev_var, 1e-3 * e.elev_var + 1e-8) << where;
      EXPECT_EQ(r.cell_class, e.cell_class) << where;
      classes[r.cell_class == "traversable" ? 1 : r.cell_class == "obstacle" ? 2 : r.cell_class == "steep" ? 3 : 0]++;
    }
    EXPECT_GT(classes[1], 0U) << preset << " layer " << k << ": the plane must be traversable somewhere";
    // Pooled from piece-wise constant children, a step at a child edge reads as a slope: steep.
    EXPECT_GT(classes[2] + classes[3], 0U) << preset << " layer " << k << ": the step must be a hazard somewhere";
  }
}

TEST(Tiling, CadreTiledMapEqualsTheOneWindowMap) {
  // 2.4 x 2.4 m fits the 4 cm layer's +-1.28 m window; the tool's 1.92 m tiles cut it into four.
  const double c = 0.64 * 1000.0;
  expect_tiled_equals_one_window<ccmap::CadreConfig>("cadre", step_scene(c, c, 1.2, 1.2, 0.01), 0.04F, c, c);
}

TEST(Tiling, SingleLayerTiledMapsEqualTheOneWindowMap) {
  // A 20 x 1.2 m strip fits the 256 x 8 cm window (+-10.24 m); the tool's tile edges cross it
  // at the step and along its middle.
  const double c = 0.08 * 5000.0;
  const std::vector<XyzPoint> strip = step_scene(c, c, 10.0, 0.6, 0.02);
  expect_tiled_equals_one_window<ccmap::SingleKalmanConfig>("kf", strip, 0.08F, c, c);
  expect_tiled_equals_one_window<ccmap::SingleOmgConfig>("omg", strip, 0.08F, c, c);
  expect_tiled_equals_one_window<ccmap::SingleCcmConfig>("ccm", strip, 0.08F, c, c);
}

TEST(Tiling, QueryAnswersAsTheTiledMapDoes) {
  // ccmap query maps only the query point's tile; its answer at a 4 cm cell centre is that
  // cell's row of the whole tiled map (height of the Kalman layer), in every tile.
  const double c = 0.64 * 1000.0;
  const std::vector<XyzPoint> scene = step_scene(c, c, 1.2, 1.2, 0.01);
  const TempDir dir(kTempPrefix);
  std::string out;
  const std::vector<std::vector<LayerCellRow>> tiled = map_with_cli(dir, "cadre", scene, &out);
  ASSERT_FALSE(tiled.empty());
  int checked = 0;
  for (const LayerCellRow& r : tiled[0]) {
    if (r.cell_class == "unknown" || (r.ix + 7 * r.iy) % 97 != 0) continue;  // a sample in every tile
    char at[96];
    std::snprintf(at, sizeof at, "%.9f,%.9f", r.cx, r.cy);
    const CliRun q = run_ccmap({"query", "--preset", "cadre", "--cloud", (dir / "cadre.ply").string(), "--at", at});
    ASSERT_EQ(q.code, 0) << q.err;
    EXPECT_NE(q.out.find("status: ok\nlayer: 0\n"), std::string::npos) << at << "\n" << q.out;
    const std::size_t h = q.out.find("height_m: ");
    ASSERT_NE(h, std::string::npos);
    EXPECT_NEAR(std::stod(q.out.substr(h + 10)), r.height, 2e-6) << "query at " << at;
    ++checked;
  }
  EXPECT_GT(checked, 20);
  const CliRun far = run_ccmap({"query", "--preset", "cadre", "--cloud", (dir / "cadre.ply").string(), "--at",
                                std::to_string(c + 50.0) + "," + std::to_string(c)});
  ASSERT_EQ(far.code, 0) << far.err;
  EXPECT_NE(far.out.find("status: outside_map"), std::string::npos) << "no tile of the map there\n" << far.out;
}

// =============================================================================================
// The pieces
// =============================================================================================

TEST(Tiling, PlanFitsEveryLayersWindow) {
  for (const std::string& preset : ccmap::tools::preset_names()) {
    std::string error;
    auto runner = ccmap::tools::make_map_runner(preset, &error);
    ASSERT_NE(runner, nullptr) << error;
    ccmap::tools::RunnerOptions options;
    options.preset = preset;
    ASSERT_TRUE(runner->init(options, &error)) << error;
    const int layers = runner->layer_count();
    std::vector<double> widths;
    for (int k = 0; k < layers; ++k) widths.push_back(static_cast<double>(runner->layer_cell_width(k)));
    ccmap::tools::TilePlan plan;
    ASSERT_TRUE(ccmap::tools::plan_tiles(*runner, widths, 0, &plan, &error)) << error;
    const std::int32_t coarse = 1 << (layers - 1);
    EXPECT_EQ(plan.tile_cells % coarse, 0) << preset << ": tiles must hold whole coarsest cells";
    EXPECT_EQ(plan.margin_cells, runner->layer_is_ccm(0) ? 0 : 1) << preset;
    EXPECT_GE(plan.tile_cells + 2 * plan.margin_cells + 2 * coarse, runner->layer_side(0))
        << preset << ": the tile should use the finest window (less than two coarse cells lost)";
    // The windows with the stack at the planned centre (in layer-k cells of the tile frame).
    ASSERT_TRUE(runner->move_to(plan.centre_m, plan.centre_m, &error)) << error;
    for (int k = 0; k < layers; ++k) {
      std::int32_t wx = 0, wy = 0;
      runner->layer_window_min(k, &wx, &wy);
      const std::int32_t lo = k == 0 ? -plan.margin_cells : 0;
      const std::int32_t hi = k == 0 ? plan.tile_cells + plan.margin_cells : plan.tile_cells >> k;
      EXPECT_LE(wx, lo) << preset << " layer " << k;
      EXPECT_LE(wy, lo) << preset << " layer " << k;
      EXPECT_GE(wx + runner->layer_side(k), hi) << preset << " layer " << k;
      EXPECT_GE(wy + runner->layer_side(k), hi) << preset << " layer " << k;
    }
    if (preset == "cadre") {
      EXPECT_EQ(plan.tile_cells, 48) << "3 x 64 cm inside the 64 x 4 cm window with a 1-cell ring";
    }
    ASSERT_TRUE(ccmap::tools::plan_tiles(*runner, widths, 2 * coarse, &plan, &error)) << error;
    EXPECT_EQ(plan.tile_cells, 2 * coarse) << preset << ": a tile limit is honoured";
  }
}

TEST(Tiling, FloatInCellNamesTheCellTheLibraryLocates) {
  // Positions at and within 1e-9 m of the edges of cells -31..30 of a tile frame: the float the
  // tool hands over must lie in the cell it decided on, as the library's own RingGrid::locate
  // sees it, and within the library's position quantum of the position.
  int nudged = 0;
  const std::pair<float, double> widths[] = {{0.04F, 0.04}, {0.08F, 0.08}, {0.1F, 0.1}, {0.3F, 0.3}};
  for (const auto& [width, w] : widths) {  // the library's float width, the user's decimal
    std::vector<ccmap::CcmCell> storage(64U * 64U);
    ccmap::RingGrid<ccmap::CcmCell> grid;
    ASSERT_EQ(grid.init(storage.data(), 64, width, ccmap::CellIndex{0, 0}), ccmap::Status::kOk);
    for (int i = -31; i < 31; ++i) {
      for (const double d : {-1e-9, -1e-12, 0.0, 1e-12, 1e-9}) {
        const double local = i * w + d;
        const long long cell = static_cast<long long>(std::floor(local / w));
        float v = 0.0F;
        ASSERT_TRUE(ccmap::tools::float_in_cell(local, cell, 1.0F / width, &v)) << local;
        ccmap::CellIndex located{};
        ASSERT_TRUE(grid.locate(v, 0.0F, &located)) << v;
        EXPECT_EQ(located.x, cell) << "width " << width << ", position " << local;
        // Within the library's position quantum (2^-18 m) and a few float steps.
        EXPECT_LE(std::fabs(static_cast<double>(v) - local), std::ldexp(1.0, -18) + 4.0 * std::ldexp(1.0, -23) * (std::fabs(local) + w));
        nudged += v != static_cast<float>(local) ? 1 : 0;
      }
    }
  }
  EXPECT_GT(nudged, 0) << "some edge positions must need a step: otherwise this test tests nothing";
  float v = 0.0F;
  EXPECT_FALSE(ccmap::tools::float_in_cell(0.5, 100, 1.0F / 0.04F, &v)) << "a cell far from the position is an error";
}

}  // namespace
