// The ccmap command-line tool end to end: clouds in, CSV and pictures out, queries, errors.
// Most tests run the tool in-process through run_cli(); one spawns the built binary.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "ccmap/product/publish.hpp"
#include "cli_run.hpp"
#include "csv_writer.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
using ccmap::tools::LayerCellRow;

namespace {

using ccmap::test::CliRun;
using ccmap::test::read_rows;
using ccmap::test::summary_counts;
using ccmap::test::XyzPoint;

CliRun run(std::vector<std::string> args) { return ccmap::test::run_ccmap(std::move(args)); }

/// The test's own temporary directory, removed at its end, also when it fails.
using TempDir = ccmap::test::TempDir;
const char* const kTempPrefix = "ccmap_cli_test_";

/// Checks that a failed run printed exactly one line "ccmap: error: ..." containing `needle`.
void expect_one_line_error(const CliRun& r, const std::string& needle, const std::string& what) {
  EXPECT_NE(r.code, 0) << what;
  EXPECT_EQ(r.err.rfind("ccmap: error: ", 0), 0U) << what << ": " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << what << ": " << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << what << ": '" << needle << "' not in: " << r.err;
}

// --- the synthetic scene: an inclined plane with a 30 cm step ----------------------------------
// z = z0 + 0.2 (x - x0) - 0.1 (y - y0) + (x - x0 >= 0.84 ? 0.3 : 0) over a 3.2 x 3.2 m square
// centred on (x0, y0), points every 1 cm at the centres of a 1 cm grid (noise-free). x0, y0 are
// multiples of 0.64 m, so every preset's origin is (x0, y0) and the step lies in the middle of
// the 8 cm cells [0.80, 0.88) (of the 16 cm cells [0.80, 0.96), 32 cm ...).
constexpr double kSlopeX = 0.2, kSlopeY = -0.1, kStepX = 0.84, kStepHeight = 0.3, kHalfSide = 1.6;

struct Scene {
  double x0, y0, z0;
  double height(double x, double y) const {
    const double lx = x - x0, ly = y - y0;
    return z0 + kSlopeX * lx + kSlopeY * ly + (lx >= kStepX ? kStepHeight : 0.0);
  }
};

/// Writes the scene (local x in [x_min_local, x_max_local)) as a binary PLY with double coordinates.
void write_scene_ply(const fs::path& path, const Scene& s, double x_min_local = -kHalfSide,
                     double x_max_local = kHalfSide) {
  std::vector<XyzPoint> points;
  const int n = static_cast<int>(std::lround(2 * kHalfSide / 0.01));
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double lx = -kHalfSide + 0.005 + 0.01 * i, ly = -kHalfSide + 0.005 + 0.01 * j;
      if (lx < x_min_local || lx >= x_max_local) continue;
      const double x = s.x0 + lx, y = s.y0 + ly;
      points.push_back(XyzPoint{x, y, s.height(x, y)});
    }
  }
  ccmap::test::write_ply(path, points);
}

/// Checks an 8 cm CCM layer of the scene: every cell of the square observed, exact geometry
/// away from the step, obstacles on it.
void check_ccm_layer(const std::vector<LayerCellRow>& rows, const Scene& s, double res, std::size_t expected_cells) {
  ASSERT_EQ(rows.size(), expected_cells);
  int checked = 0, obstacles = 0;
  for (const LayerCellRow& r : rows) {
    ASSERT_DOUBLE_EQ(r.res, res);
    // Cell centre: (ix + 0.5) * res in the map frame, and inside the square.
    EXPECT_NEAR(r.cx, (static_cast<double>(r.ix) + 0.5) * res, 1e-6);
    EXPECT_NEAR(r.cy, (static_cast<double>(r.iy) + 0.5) * res, 1e-6);
    EXPECT_LT(std::fabs(r.cx - s.x0), kHalfSide);
    EXPECT_LT(std::fabs(r.cy - s.y0), kHalfSide);
    const double lo = r.cx - s.x0 - res / 2, hi = r.cx - s.x0 + res / 2;
    const bool step_inside = lo < kStepX && kStepX < hi;
    if (step_inside) {
      ++obstacles;
      EXPECT_EQ(r.cell_class, "obstacle") << "cell at local x " << r.cx - s.x0 << " holds the 30 cm step";
      continue;
    }
    ++checked;
    EXPECT_NEAR(r.height, s.height(r.cx, r.cy), 1e-3) << "height off at (" << r.cx << ", " << r.cy << ")";
    EXPECT_NEAR(r.slope_x, kSlopeX, 2e-3) << "slope_x off on the 0.2 plane at (" << r.cx << ", " << r.cy << ")";
    EXPECT_NEAR(r.slope_y, kSlopeY, 2e-3) << "slope_y off at (" << r.cx << ", " << r.cy << ")";
    EXPECT_LT(r.normal_var, 1e-6) << "a noise-free plane has no normal variance";
    EXPECT_EQ(r.cell_class, "traversable") << "at (" << r.cx << ", " << r.cy << ")";
  }
  EXPECT_GT(checked, 0);
  EXPECT_GT(obstacles, 0);
}

std::string data_dir() {
  const char* env = std::getenv("CCMAP_DATA_DIR");
  return env != nullptr ? env : CCMAP_DEFAULT_DATA_DIR;
}

}  // namespace

// =============================================================================================
// Mapping the synthetic scene
// =============================================================================================

TEST(CliMap, CcmPresetInclinedPlaneWithStepLocalCoordinates) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.0, 0.0, 0.0};
  write_scene_ply(dir / "scene.ply", s);
  const CliRun r = run({"map", "--preset", "ccm", "--cloud", (dir / "scene.ply").string(), "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  long long read = 0, used = 0;
  ASSERT_TRUE(summary_counts(r.out, &read, &used)) << r.out;
  EXPECT_EQ(read, 320 * 320);
  EXPECT_EQ(used, 320 * 320) << r.out;
  check_ccm_layer(read_rows(dir / "out" / "layer_0.csv"), s, 0.08, 40U * 40U);
  EXPECT_FALSE(fs::exists(dir / "out" / "layer_1.csv"));
  for (const char* pic : {"layer_0_height.png", "layer_0_slope.png", "layer_0_normal_var.png", "layer_0_class.png"}) {
    EXPECT_TRUE(fs::exists(dir / "out" / pic)) << pic;
  }
}

TEST(CliMap, UtmSizedCoordinatesKeepMillimetres) {
  // x ~ 5.2e5, y ~ 4.9e6, z ~ 2235: float alone would have 3 cm / 50 cm steps here.
  const TempDir dir(kTempPrefix);
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "utm.ply", s);
  const CliRun r = run({"map", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<LayerCellRow> rows = read_rows(dir / "out" / "layer_0.csv");
  check_ccm_layer(rows, s, 0.08, 40U * 40U);
  // Global indices are map-frame indices: cell ix covers [ix * 0.08, (ix + 1) * 0.08).
  for (const LayerCellRow& row : rows) {
    ASSERT_EQ(row.ix, static_cast<long long>(std::floor(row.cx / 0.08)));
    ASSERT_EQ(row.iy, static_cast<long long>(std::floor(row.cy / 0.08)));
  }
}

TEST(CliMap, CadrePresetWritesFiveLayersFinestFirst) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "utm.ply", s);
  const CliRun r = run({"map", "--preset", "cadre", "--cloud", (dir / "utm.ply").string(), "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  long long read = 0, used = 0;
  ASSERT_TRUE(summary_counts(r.out, &read, &used)) << r.out;
  EXPECT_EQ(used, read) << "without poses the stack is swept over the whole cloud";
  const double widths[5] = {0.04, 0.08, 0.16, 0.32, 0.64};
  for (int k = 0; k < 5; ++k) {
    const fs::path csv = dir / "out" / ("layer_" + std::to_string(k) + ".csv");
    ASSERT_TRUE(fs::exists(csv)) << csv;
    const std::vector<LayerCellRow> rows = read_rows(csv);
    ASSERT_FALSE(rows.empty()) << "layer " << k;
    for (const LayerCellRow& row : rows) {
      ASSERT_EQ(row.layer, k);
      ASSERT_DOUBLE_EQ(row.res, widths[k]);
      EXPECT_NEAR(row.cx, (static_cast<double>(row.ix) + 0.5) * widths[k], 1e-6);
    }
    // Every layer covers the whole 3.2 m square (tiled), not only its window around the origin.
    const std::size_t cells_per_side = static_cast<std::size_t>(std::lround(3.2 / widths[k]));
    const std::size_t coarse_side = k == 4 ? 6U : cells_per_side;  // 64 cm cells overlap the square's edges
    EXPECT_EQ(rows.size(), coarse_side * coarse_side) << "layer " << k;
    if (k == 0) {
      // Piece-wise constant Kalman cells: height = mean of a symmetric 4 x 4 sample = the plane
      // at the centre; slopes 0.
      for (const LayerCellRow& row : rows) {
        EXPECT_EQ(row.slope_x, 0.0);
        EXPECT_EQ(row.slope_y, 0.0);
        const double lx = row.cx - s.x0;
        if (std::fabs(lx - kStepX) > 0.03) {
          EXPECT_NEAR(row.height, s.height(row.cx, row.cy), 1e-3) << "Kalman cell at local x " << lx;
        }
      }
    }
    if (k == 1) {
      // Every point went to the 4 cm layer; 8 cm CCM cells pool their four Kalman children,
      // which sample the plane at their centres: exact plane fits (docs/design.md 2.6).
      for (const LayerCellRow& row : rows) {
        const double lx = row.cx - s.x0;
        if (std::fabs(lx - kStepX) > 0.05) {
          EXPECT_NEAR(row.height, s.height(row.cx, row.cy), 1e-3);
          EXPECT_NEAR(row.slope_x, kSlopeX, 2e-3);
          EXPECT_EQ(row.cell_class, "traversable");
        }
      }
    }
  }
  EXPECT_NE(r.out.find("layer 4 (0.64 m"), std::string::npos) << r.out;
}

TEST(CliMap, ResAndWeightLimitFlags) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.0, 0.0, 0.0};
  write_scene_ply(dir / "scene.ply", s);
  const CliRun r = run({"map", "--preset=ccm", "--res", "0.16", "--wl", "50", "--cloud", (dir / "scene.ply").string(),
                     "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("W_l 50"), std::string::npos) << r.out;
  const std::vector<LayerCellRow> rows = read_rows(dir / "out" / "layer_0.csv");
  ASSERT_EQ(rows.size(), 20U * 20U);
  for (const LayerCellRow& row : rows) EXPECT_LE(row.weight, 50.0);
  const CliRun c = run({"map", "--preset", "cadre", "--res", "0.02", "--cloud", (dir / "scene.ply").string(), "--out",
                     (dir / "out2").string()});
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_NE(c.out.find("cell widths 0.02 0.04 0.08 0.16 0.32 m"), std::string::npos) << c.out;
}

TEST(CliMap, KalmanAndOmgPresets) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.0, 0.0, 0.0};
  write_scene_ply(dir / "scene.ply", s);
  for (const char* preset : {"kf", "omg"}) {
    const CliRun r = run({"map", "--preset", preset, "--cloud", (dir / "scene.ply").string(), "--out",
                       (dir / preset).string()});
    ASSERT_EQ(r.code, 0) << preset << ": " << r.err;
    const std::vector<LayerCellRow> rows = read_rows(dir / preset / "layer_0.csv");
    ASSERT_EQ(rows.size(), 40U * 40U) << preset;
    for (const LayerCellRow& row : rows) {
      EXPECT_EQ(row.slope_x, 0.0);
      if (std::fabs(row.cx - s.x0 - kStepX) > 0.05) {
        EXPECT_NEAR(row.height, s.height(row.cx, row.cy), 1e-3) << preset;
      }
    }
  }
}

TEST(CliMap, TwoFramesWithPosesGiveTheSameMapAsOne) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "west.ply", s, -kHalfSide, 0.0);
  write_scene_ply(dir / "east.ply", s, 0.0, kHalfSide);
  {
    std::ofstream poses(dir / "poses.txt");
    poses.precision(17);
    poses << "# x y z yaw\n" << s.x0 << ' ' << s.y0 << ' ' << s.z0 + 1.0 << " 0\n"
          << s.x0 + 0.3 << ' ' << s.y0 << ' ' << s.z0 + 1.0 << " 1.57\n";
  }
  const CliRun r = run({"map", "--preset", "ccm", "--cloud", (dir / "west.ply").string(), "--cloud",
                     (dir / "east.ply").string(), "--poses", (dir / "poses.txt").string(), "--out",
                     (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("frame 2: east.ply"), std::string::npos) << r.out;
  // The first cloud's centroid is 0.8 m west of x0; rounded to 8 cm it still sits on the grid.
  check_ccm_layer(read_rows(dir / "out" / "layer_0.csv"), s, 0.08, 40U * 40U);
}

TEST(CliMap, NonFinitePointsAreSkippedAndCounted) {
  const TempDir dir(kTempPrefix);
  {
    std::ofstream out(dir / "pts.xyz");
    for (int j = 0; j < 40; ++j) {
      for (int i = 0; i < 40; ++i) out << 0.005 + 0.01 * i << ' ' << 0.005 + 0.01 * j << " 1.0\n";
    }
    out << "nan 0 0\n0 inf 0\n0 0 -inf\n";
  }
  const CliRun r = run({"map", "--preset", "ccm", "--cloud", (dir / "pts.xyz").string(), "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("non-finite 3"), std::string::npos) << r.out;
  long long read = 0, used = 0;
  ASSERT_TRUE(summary_counts(r.out, &read, &used)) << r.out;
  EXPECT_EQ(read, 1603);
  EXPECT_EQ(used, 1600);
}

namespace {

/// nx x ny points `spacing` apart at the centres of a grid from (x0, y0), on z = 5 + 0.1 (x - x0).
std::vector<XyzPoint> good_patch(int nx, int ny, double x0, double y0, double spacing) {
  std::vector<XyzPoint> points;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double x = x0 + spacing * (i + 0.5), y = y0 + spacing * (j + 0.5);
      points.push_back(XyzPoint{x, y, 5.0 + 0.1 * (x - x0)});
    }
  }
  return points;
}

/// The set of (ix, iy) cells of width w holding the points.
std::set<std::pair<long long, long long>> cells_of(const std::vector<XyzPoint>& points, double w) {
  std::set<std::pair<long long, long long>> cells;
  for (const XyzPoint& p : points) cells.insert({std::llround(std::floor(p.x / w)), std::llround(std::floor(p.y / w))});
  return cells;
}

std::set<std::pair<long long, long long>> cells_of(const std::vector<LayerCellRow>& rows) {
  std::set<std::pair<long long, long long>> cells;
  for (const LayerCellRow& r : rows) cells.insert({r.ix, r.iy});
  return cells;
}

}  // namespace

TEST(CliMap, HostileValuesBesideGoodPointsAreCountedAndTheGoodOnesMapped) {
  // 300 good points and four bad lines: before, the origin was the centroid of every parsed
  // value (-5.9e18), every point fell out of range, and the CADRE picture window overflowed int64.
  const TempDir dir(kTempPrefix);
  const std::vector<XyzPoint> good = good_patch(20, 15, 12.3, 45.6, 0.01);
  {
    std::ofstream out(dir / "hostile.xyz");
    out.precision(17);
    for (const XyzPoint& p : good) out << p.x << ' ' << p.y << ' ' << p.z << "\n";
    out << "nan 0 0\n0 inf 0\n1e30 1e30 1e30\n-1e38 0 0\n";
  }
  for (const char* preset : {"ccm", "cadre", "kf"}) {
    const CliRun r = run({"map", "--preset", preset, "--cloud", (dir / "hostile.xyz").string(), "--out",
                          (dir / preset).string()});
    ASSERT_EQ(r.code, 0) << preset << ": " << r.err;
    long long read = 0, used = 0;
    ASSERT_TRUE(summary_counts(r.out, &read, &used)) << r.out;
    EXPECT_EQ(read, 304) << preset;
    EXPECT_EQ(used, 300) << preset << ": every good point is mapped\n" << r.out;
    EXPECT_EQ(ccmap::test::summary_count(r.out, "non-finite "), 2) << r.out;
    EXPECT_EQ(ccmap::test::summary_count(r.out, "out of range "), 2) << "1e30 and -1e38 are out of range\n" << r.out;
    // The origin is the good points' median, rounded to the coarsest cell width.
    double ox = 0, oy = 0, oz = 0;
    const std::size_t at = r.out.find("origin (map frame): ");
    ASSERT_NE(at, std::string::npos) << r.out;
    ASSERT_EQ(std::sscanf(r.out.c_str() + at, "origin (map frame): %lf %lf %lf", &ox, &oy, &oz), 3) << r.out;
    EXPECT_LT(std::fabs(ox - 12.4), 0.33) << r.out;
    EXPECT_LT(std::fabs(oy - 45.675), 0.33) << r.out;
    EXPECT_LT(std::fabs(oz - 5.01), 0.33) << r.out;
    const std::vector<LayerCellRow> rows = read_rows(dir / preset / "layer_0.csv");
    const double w = std::string(preset) == "cadre" ? 0.04 : 0.08;
    EXPECT_EQ(cells_of(rows), cells_of(good, w)) << preset << ": the layer holds exactly the good points' cells";
  }
}

TEST(CliMap, OneFarReturnNeitherMovesTheOriginNorDropsGoodPoints) {
  // 900 good points within a 0.6 m patch and one return 12.7 km away: before, the centroid
  // moved the window and 3 % of the good points fell outside the map.
  const TempDir dir(kTempPrefix);
  const std::vector<XyzPoint> good = good_patch(30, 30, 3.0, 4.0, 0.02);
  std::vector<XyzPoint> with_far = good;
  with_far.push_back(XyzPoint{9000.0, -9000.0, 40.0});
  ccmap::test::write_ply(dir / "good.ply", good);
  ccmap::test::write_ply(dir / "far.ply", with_far);
  for (const char* preset : {"ccm", "cadre"}) {
    const CliRun a = run({"map", "--preset", preset, "--cloud", (dir / "good.ply").string(), "--out",
                          (dir / (std::string(preset) + "_good")).string()});
    const CliRun b = run({"map", "--preset", preset, "--cloud", (dir / "far.ply").string(), "--out",
                          (dir / (std::string(preset) + "_far")).string()});
    ASSERT_EQ(a.code, 0) << a.err;
    ASSERT_EQ(b.code, 0) << b.err;
    long long read = 0, used = 0;
    ASSERT_TRUE(summary_counts(b.out, &read, &used)) << b.out;
    EXPECT_EQ(used, 901) << preset << ": the far return is mapped too, in its own tile\n" << b.out;
    EXPECT_EQ(ccmap::test::summary_count(b.out, "outside map "), 0) << b.out;
    const std::size_t at_a = a.out.find("origin (map frame): "), at_b = b.out.find("origin (map frame): ");
    ASSERT_NE(at_b, std::string::npos);
    EXPECT_EQ(a.out.substr(at_a, a.out.find('\n', at_a) - at_a), b.out.substr(at_b, b.out.find('\n', at_b) - at_b))
        << "one far return must not move the origin";
    const int layers = std::string(preset) == "cadre" ? 5 : 1;
    for (int k = 0; k < layers; ++k) {
      const std::string name = "layer_" + std::to_string(k) + ".csv";
      const std::vector<LayerCellRow> ra = read_rows(dir / (std::string(preset) + "_good") / name);
      std::vector<LayerCellRow> rb = read_rows(dir / (std::string(preset) + "_far") / name);
      // The far return's own cell is the only extra row; every other row is unchanged.
      ASSERT_EQ(rb.size(), ra.size() + 1) << preset << " layer " << k;
      rb.erase(std::remove_if(rb.begin(), rb.end(), [](const LayerCellRow& r) { return r.cx > 8000.0; }), rb.end());
      ASSERT_EQ(rb.size(), ra.size());
      for (std::size_t i = 0; i < ra.size(); ++i) {
        EXPECT_EQ(ra[i].ix, rb[i].ix);
        EXPECT_EQ(ra[i].iy, rb[i].iy);
        EXPECT_EQ(ra[i].weight, rb[i].weight);
        EXPECT_EQ(ra[i].height, rb[i].height) << preset << " layer " << k << " cell " << ra[i].ix << "," << ra[i].iy;
        EXPECT_EQ(ra[i].cell_class, rb[i].cell_class);
      }
    }
  }
}

TEST(CliMap, BoundsLimitTheMappedArea) {
  const TempDir dir(kTempPrefix);
  const std::vector<XyzPoint> good = good_patch(100, 50, 100.0, 200.0, 0.02);  // 2 x 1 m
  ccmap::test::write_ply(dir / "patch.ply", good);
  // x in [100.5, 101.3], y in [200.1, 200.9], absolute coordinates.
  const CliRun r = run({"map", "--preset", "ccm", "--cloud", (dir / "patch.ply").string(), "--bounds",
                        "100.5,200.1,101.3,200.9", "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  std::vector<XyzPoint> inside;
  for (const XyzPoint& p : good) {
    if (p.x >= 100.5 && p.x <= 101.3 && p.y >= 200.1 && p.y <= 200.9) inside.push_back(p);
  }
  long long read = 0, used = 0;
  ASSERT_TRUE(summary_counts(r.out, &read, &used)) << r.out;
  EXPECT_EQ(used, static_cast<long long>(inside.size())) << r.out;
  EXPECT_EQ(ccmap::test::summary_count(r.out, "outside map "), static_cast<long long>(good.size() - inside.size()))
      << "points outside --bounds are counted as outside map\n" << r.out;
  EXPECT_EQ(cells_of(read_rows(dir / "out" / "layer_0.csv")), cells_of(inside, 0.08));
  // Bounds that hold no point: a one-line error, no output.
  const CliRun none = run({"map", "--preset", "ccm", "--cloud", (dir / "patch.ply").string(), "--bounds",
                           "0,0,1,1", "--out", (dir / "none").string()});
  expect_one_line_error(none, "no point inside --bounds", "bounds without points");
}

TEST(CliMap, PerPointWeightsFromTheFileReplaceTheSensorModel) {
  // One 32 cm cell, a checkerboard of heights 1 (weight 9) and 0 (weight 1): the weighted mean
  // is 0.9 (unweighted it would be 0.5); points with weight -1 and 1e300 are refused as bad weights.
  const TempDir dir(kTempPrefix);
  {
    std::ofstream out(dir / "weighted.xyz");
    for (int j = 0; j < 32; ++j) {
      for (int i = 0; i < 32; ++i) {
        const bool high = (i + j) % 2 == 0;
        out << 0.005 + 0.01 * i << ' ' << 0.005 + 0.01 * j << ' ' << (high ? 1.0 : 0.0) << ' ' << (high ? 9 : 1) << "\n";
      }
    }
    out << "0.1 0.1 5.0 -1\n0.1 0.1 5.0 1e300\n";  // 1e300 exceeds float: a bad weight, not a conversion
  }
  const CliRun r = run({"map", "--preset", "ccm", "--res", "0.32", "--wl", "1e6", "--cloud",
                        (dir / "weighted.xyz").string(), "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("bad weight 2"), std::string::npos) << r.out;
  const auto rows = read_rows(dir / "out" / "layer_0.csv");
  ASSERT_EQ(rows.size(), 1U);
  EXPECT_NEAR(rows[0].weight, 512.0 * 9.0 + 512.0, 1e-3) << "the file's weights must be summed";
  EXPECT_NEAR(rows[0].height, 0.9, 0.01) << "height must be the weighted mean";
}

// =============================================================================================
// Query
// =============================================================================================

TEST(CliQuery, AnswersAtAMapFramePoint) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "utm.ply", s);
  const double qx = s.x0 - 0.51, qy = s.y0 + 0.33;  // sub-cell position, away from the step
  char at[128];
  std::snprintf(at, sizeof at, "%.6f,%.6f", qx, qy);
  const CliRun r = run({"query", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--at", at});
  ASSERT_EQ(r.code, 0) << r.err;
  std::map<std::string, std::string> kv;
  std::istringstream lines(r.out);
  std::string line;
  while (std::getline(lines, line)) {
    const std::size_t colon = line.find(": ");
    ASSERT_NE(colon, std::string::npos) << "not 'key: value': " << line;
    kv[line.substr(0, colon)] = line.substr(colon + 2);
  }
  for (const char* key : {"status", "layer", "cell_width_m", "height_m", "slope_x", "slope_y", "inclination",
                          "normal_variance_m2", "elevation_variance_m2", "class", "upset"}) {
    EXPECT_EQ(kv.count(key), 1U) << key;
  }
  EXPECT_EQ(kv["upset"], "0") << "a map made in-process has had no upset";
  EXPECT_EQ(kv["status"], "ok");
  EXPECT_EQ(kv["layer"], "0");
  EXPECT_EQ(kv["class"], "traversable");
  EXPECT_NEAR(std::stod(kv["height_m"]), s.height(qx, qy), 1e-3) << "sub-cell height (eq. 10)";
  EXPECT_NEAR(std::stod(kv["slope_x"]), kSlopeX, 2e-3);
  EXPECT_NEAR(std::stod(kv["inclination"]), std::hypot(kSlopeX, kSlopeY), 2e-3);

  std::snprintf(at, sizeof at, "%.6f,%.6f", s.x0 + 500.0, s.y0);
  const CliRun far = run({"query", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--at", at});
  ASSERT_EQ(far.code, 0) << far.err;
  EXPECT_NE(far.out.find("status: outside_map"), std::string::npos) << far.out;
  // Far beyond the library's range (and int64 cell indices): outside the map, no overflow.
  const CliRun huge = run({"query", "--preset", "cadre", "--cloud", (dir / "utm.ply").string(), "--at", "1e300,-1e300"});
  ASSERT_EQ(huge.code, 0) << huge.err;
  EXPECT_NE(huge.out.find("status: outside_map"), std::string::npos) << huge.out;
}

/// "key: value" lines of a query's output.
std::map<std::string, std::string> key_values(const std::string& text) {
  std::map<std::string, std::string> kv;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    const std::size_t colon = line.find(": ");
    EXPECT_NE(colon, std::string::npos) << "not 'key: value': " << line;
    if (colon != std::string::npos) kv[line.substr(0, colon)] = line.substr(colon + 2);
  }
  return kv;
}

TEST(CliQuery, FootprintOfTheBodyOnThePlaneAndOnTheStep) {
  // The scene's plane (0.2, -0.1) with its 30 cm step at local x = 0.84, the ccm preset (8 cm).
  const TempDir dir(kTempPrefix);
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "utm.ply", s);
  char at[128];
  // A 0.6 x 0.4 m body along x, 0.5 m clear of the step: traversable, the plane's height range
  // 0.2 * 0.6 + 0.1 * 0.4 = 0.16 m, its inclination atan(|(0.2, -0.1)|) = 12.6 deg.
  std::snprintf(at, sizeof at, "%.6f,%.6f", s.x0 - 0.2, s.y0 + 0.1);
  const CliRun flat = run({"query", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--at", at,
                           "--footprint", "0.6,0.4"});
  ASSERT_EQ(flat.code, 0) << flat.err;
  std::map<std::string, std::string> kv = key_values(flat.out);
  EXPECT_EQ(kv["class"], "traversable") << "the point answer is still there";
  EXPECT_EQ(kv["footprint_class"], "traversable");
  EXPECT_NEAR(std::stod(kv["footprint_unknown_share"]), 0.0, 1e-6);
  EXPECT_EQ(kv["footprint_upset_share"], "0.000000");
  EXPECT_NEAR(std::stod(kv["footprint_max_step_m"]), 0.16, 2e-3);
  EXPECT_NEAR(std::stod(kv["footprint_max_inclination_deg"]), 12.604, 0.05);
  // Turned by 90 deg the body spans 0.6 m along y: 0.2 * 0.4 + 0.1 * 0.6 = 0.14 m.
  const CliRun turned = run({"query", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--at", at,
                             "--footprint", "0.6,0.4,90"});
  ASSERT_EQ(turned.code, 0) << turned.err;
  EXPECT_NEAR(std::stod(key_values(turned.out)["footprint_max_step_m"]), 0.14, 2e-3);
  // Over the step: obstacle, a step of at least the 30 cm edge.
  std::snprintf(at, sizeof at, "%.6f,%.6f", s.x0 + 0.84, s.y0 + 0.1);
  const CliRun step = run({"query", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--at", at,
                           "--footprint", "0.6,0.4,30"});
  ASSERT_EQ(step.code, 0) << step.err;
  kv = key_values(step.out);
  EXPECT_EQ(kv["footprint_class"], "obstacle");
  EXPECT_GT(std::stod(kv["footprint_max_step_m"]), 0.3);
  // Half off the observed square (x local 1.6): unknown at the default 10 %, traversable at 60 %.
  std::snprintf(at, sizeof at, "%.6f,%.6f", s.x0 + 1.6, s.y0 - 1.0);
  const CliRun edge = run({"query", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--at", at,
                           "--footprint", "0.64,0.4"});
  ASSERT_EQ(edge.code, 0) << edge.err;
  kv = key_values(edge.out);
  EXPECT_EQ(kv["footprint_class"], "unknown");
  EXPECT_NEAR(std::stod(kv["footprint_unknown_share"]), 0.5, 1e-4);
  const CliRun tolerant = run({"query", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--at", at,
                               "--footprint", "0.64,0.4", "--max-unknown-share", "0.6"});
  ASSERT_EQ(tolerant.code, 0) << tolerant.err;
  EXPECT_EQ(key_values(tolerant.out)["footprint_class"], "traversable");
}

TEST(CliQuery, PathFindsTheStepAndTheEndOfTheObservedGround) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "utm.ply", s);
  // Along +x from local (-1.0, 0.1): the body's front (0.3 m ahead) enters the 8 cm cell
  // [0.80, 0.88) that holds the step just after 1.5 m (2 cm steps: at 1.52).
  char path[256];
  std::snprintf(path, sizeof path, "%.6f,%.6f:%.6f,%.6f", s.x0 - 1.0, s.y0 + 0.1, s.x0 + 0.7, s.y0 + 0.1);
  const CliRun r = run({"query", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--path", path,
                        "--footprint", "0.6,0.4", "--step", "0.02"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::map<std::string, std::string> kv = key_values(r.out);
  ASSERT_NE(kv["first_hazard_m"], "none") << r.out;
  EXPECT_NEAR(std::stod(kv["first_hazard_m"]), 1.52, 0.025);
  EXPECT_EQ(kv["hazard_class"], "obstacle");
  EXPECT_NEAR(std::stod(kv["hazard_x"]), s.x0 - 1.0 + std::stod(kv["first_hazard_m"]), 1e-3) << "absolute coordinates";
  EXPECT_EQ(kv["first_unknown_m"], "none");
  EXPECT_NEAR(std::stod(kv["path_length_m"]), 1.7, 1e-5);
  EXPECT_EQ(kv["path_poses"], "86") << "no unknown footprint: every pose evaluated (1.7 m / 2 cm + 1)";
  // Along -y from local (-0.5, 0): more than 10 % of the body (0.06 m of its 0.6 m) is beyond the
  // observed square (y = -1.6) once its front (0.3 m ahead) passes -1.66: 1.6 - 0.3 + 0.06 = 1.36 m.
  std::snprintf(path, sizeof path, "%.6f,%.6f:%.6f,%.6f:%.6f,%.6f", s.x0 - 0.5, s.y0, s.x0 - 0.5, s.y0 - 0.5, s.x0 - 0.5,
                s.y0 - 2.0);
  const CliRun out = run({"query", "--preset", "ccm", "--cloud", (dir / "utm.ply").string(), "--path", path,
                          "--footprint", "0.6,0.4"});
  ASSERT_EQ(out.code, 0) << out.err;
  kv = key_values(out.out);
  EXPECT_EQ(kv["first_hazard_m"], "none");
  ASSERT_NE(kv["first_unknown_m"], "none") << out.out;
  EXPECT_NEAR(std::stod(kv["first_unknown_m"]), 1.36, 0.05);
}

TEST(CliMap, CostmapPerLayerAsPgmAndPng) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "utm.ply", s);
  const CliRun r = run({"map", "--preset", "cadre", "--cloud", (dir / "utm.ply").string(), "--out",
                        (dir / "out").string(), "--costmap", "--inflate", "0.1"});
  ASSERT_EQ(r.code, 0) << r.err;
  const double widths[5] = {0.04, 0.08, 0.16, 0.32, 0.64};
  for (int k = 0; k < 5; ++k) {
    SCOPED_TRACE(testing::Message() << "layer " << k);
    const fs::path png = dir / "out" / ("costmap_" + std::to_string(k) + ".png");
    const fs::path pgm = dir / "out" / ("costmap_" + std::to_string(k) + ".pgm");
    ASSERT_TRUE(fs::exists(png)) << png;
    ASSERT_TRUE(fs::exists(pgm)) << pgm;
    std::ifstream in(pgm, std::ios::binary);
    std::string magic;
    int w = 0, h = 0, maxval = 0;
    in >> magic >> w >> h >> maxval;
    in.get();
    EXPECT_EQ(magic, "P5");
    EXPECT_EQ(maxval, 255);
    std::vector<unsigned char> pixels(static_cast<std::size_t>(w * h));
    in.read(reinterpret_cast<char*>(pixels.data()), static_cast<std::streamsize>(pixels.size()));
    ASSERT_TRUE(in) << "truncated " << pgm;
    // One pixel per cell of the layer's observed area (the 3.2 m square, tiled: every cell), rows
    // north first; each pixel's class from the layer's CSV.
    const std::vector<LayerCellRow> rows = read_rows(dir / "out" / ("layer_" + std::to_string(k) + ".csv"));
    ASSERT_FALSE(rows.empty());
    std::int64_t ix0 = rows[0].ix, ix1 = rows[0].ix, iy0 = rows[0].iy, iy1 = rows[0].iy;
    for (const LayerCellRow& row : rows) {
      ix0 = std::min(ix0, row.ix);
      ix1 = std::max(ix1, row.ix);
      iy0 = std::min(iy0, row.iy);
      iy1 = std::max(iy1, row.iy);
    }
    ASSERT_EQ(w, ix1 - ix0 + 1);
    ASSERT_EQ(h, iy1 - iy0 + 1);
    EXPECT_GE(w, static_cast<int>(std::lround(3.2 / widths[k])));  // 64 cm cells straddle the square: 6
    EXPECT_LE(w, static_cast<int>(std::lround(3.2 / widths[k])) + 1);
    int lethal = 0, inscribed = 0, wrong = 0;
    for (const LayerCellRow& row : rows) {
      const unsigned char v = pixels[static_cast<std::size_t>((iy1 - row.iy) * w + (row.ix - ix0))];
      const bool hazard = row.cell_class == "obstacle" || row.cell_class == "steep";
      const bool ok = hazard ? v == 254 : (row.cell_class == "unknown" ? v == 255 : v <= 253);
      wrong += ok ? 0 : 1;
      lethal += v == 254 ? 1 : 0;
      inscribed += v == 253 ? 1 : 0;
    }
    EXPECT_EQ(wrong, 0) << "pixels whose value does not match their cell's class";
    if (k <= 2) {
      EXPECT_GT(lethal, 0) << "the step is lethal";
    }
    // 10 cm of inflation: 2.5 pixels at 4 cm, 1.25 at 8 cm, less than a pixel beyond.
    EXPECT_EQ(inscribed > 0, k <= 1) << inscribed << " inscribed pixels";
  }
  EXPECT_NE(r.out.find("costmap 0 (80 x 80 at 0.04 m)"), std::string::npos) << r.out;
}

TEST(CliErrors, PlannerOptionsAreCheckedWithOneLine) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.0, 0.0, 0.0};
  write_scene_ply(dir / "scene.ply", s);
  const std::string cloud = (dir / "scene.ply").string();
  const std::string out = (dir / "out").string();
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--at", "0,0", "--footprint", "0.6"}),
                        "--footprint", "one number");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--at", "0,0", "--footprint", "0.6,-1"}),
                        "--footprint", "negative width");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--at", "0,0", "--footprint", "30,30"}),
                        "refused the footprint", "beyond the footprint limit");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--path", "0,0:1,0"}), "--path requires --footprint",
                        "path without a body");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--path", "0,0:1,0", "--footprint", "0.6,0.4,10"}),
                        "YAW_DEG", "yaw with a path");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--path", "0,0", "--footprint", "0.6,0.4"}),
                        "--path", "one point");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--path", "0,0:1,x", "--footprint", "0.6,0.4"}),
                        "--path", "not a number");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--path", "0,0:1,0", "--footprint",
                             "0.6,0.4", "--step", "0.001"}),
                        "refused the path query", "too many poses");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--at", "0,0", "--path", "0,0:1,0",
                             "--footprint", "0.6,0.4"}),
                        "--at excludes --path", "both queries");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--at", "0,0", "--max-unknown-share", "2"}),
                        "--max-unknown-share", "share above 1");
  expect_one_line_error(run({"query", "--preset", "ccm", "--cloud", cloud, "--at", "0,0", "--costmap"}), "--costmap",
                        "costmap on a query");
  expect_one_line_error(run({"map", "--preset", "ccm", "--cloud", cloud, "--out", out, "--inflate", "0.1"}),
                        "--inflate requires --costmap", "inflate alone");
  expect_one_line_error(run({"map", "--preset", "ccm", "--cloud", cloud, "--out", out, "--footprint", "0.6,0.4"}),
                        "--footprint belongs to 'ccmap query'", "footprint on map");
  expect_one_line_error(run({"map", "--preset", "ccm", "--cloud", cloud, "--out", out, "--costmap", "--inflate", "5"}),
                        "--inflate: 5 m is 62.5 cells of layer 0", "inflation beyond 32 pixels");
}

// =============================================================================================
// The CCM cell: full (lateral covariance) by default, the paper's 9 floats with --paper-cell
// =============================================================================================

TEST(CliMap, DiagonalHalfCellsOnATwelveDegreePlaneWithBothCells) {
  // Issue 11's measurement: every 16 cm cell of a 12 deg plane along y seen on one diagonal half
  // (x + y < 0 relative to the cell centre), points on a 5 mm grid. The paper's cell reports
  // slope_x = -b/2 (sigma_xy = -sigma_xx / 2 on that triangle) and calls the cell covered; the
  // full cell gives slope_x = 0 and calls it unknown (its smaller lateral eigenvalue is w^2/36).
  const TempDir dir(kTempPrefix);
  const double b = std::tan(12.0 * M_PI / 180.0), w = 0.16, x0 = 0.16 * 4000.0, y0 = 0.16 * 9000.0;
  {
    std::ofstream out(dir / "diagonal.xyz");
    out.precision(12);
    for (int j = 0; j < 320; ++j) {
      for (int i = 0; i < 320; ++i) {
        const double lx = 0.0025 + 0.005 * i, ly = 0.0025 + 0.005 * j;  // local, from the square's corner
        const double fx = std::fmod(lx, w), fy = std::fmod(ly, w);     // from the cell's corner
        if (fx + fy >= w - 1e-9) continue;                              // the seen half: x + y < 0
        out << x0 + lx << ' ' << y0 + ly << ' ' << 10.0 + b * ly << '\n';
      }
    }
  }
  for (const bool paper : {false, true}) {
    std::vector<std::string> args = {"map", "--preset", "ccm", "--res", "0.16", "--cloud", (dir / "diagonal.xyz").string(),
                                     "--out", (dir / (paper ? "paper" : "full")).string()};
    if (paper) args.push_back("--paper-cell");
    const CliRun r = run(args);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find(paper ? "CCM cell paper (9 floats)" : "CCM cell full (10 floats)"), std::string::npos) << r.out;
    const std::vector<LayerCellRow> rows = read_rows(dir / (paper ? "paper" : "full") / "layer_0.csv");
    int inner = 0;
    for (const LayerCellRow& c : rows) {
      const double lx = c.cx - x0, ly = c.cy - y0;
      if (lx < w || ly < w || lx > 1.6 - w || ly > 1.6 - w) continue;  // inner cells of the 1.6 m square
      ++inner;
      if (paper) {
        EXPECT_NEAR(c.slope_x, -0.5 * b, 0.01) << "paper cell: slope_x on a diagonal half";
        EXPECT_EQ(c.cell_class, "traversable") << "paper cell: covered per axis";
      } else {
        EXPECT_NEAR(c.slope_x, 0.0, 2e-3) << "full cell: slope_x off 0 on a 12 deg plane along y";
        EXPECT_NEAR(c.slope_y, b, 2e-3) << "full cell: slope_y off tan 12 deg";
        EXPECT_EQ(c.cell_class, "unknown") << "full cell: a diagonal half cell is not covered";
      }
    }
    EXPECT_EQ(inner, 64) << "test premise: the inner 8 x 8 cells of the 10 x 10 square";
  }
  // Saved paper-cell maps merge with --paper-cell, and give the same paper-cell answer: slope_x -b/2.
  for (const char* half : {"h1", "h2"}) {
    ASSERT_EQ(run({"map", "--preset", "ccm", "--res", "0.16", "--paper-cell", "--cloud", (dir / "diagonal.xyz").string(),
                   "--out", (dir / half).string(), "--save", (dir / (std::string(half) + ".map")).string()})
                  .code,
              0);
  }
  const CliRun merged = run({"merge", "--preset", "ccm", "--paper-cell", "--in", (dir / "h1.map").string(), "--in",
                             (dir / "h2.map").string(), "--out", (dir / "merged").string()});
  ASSERT_EQ(merged.code, 0) << merged.err;
  int merged_inner = 0;
  for (const LayerCellRow& c : read_rows(dir / "merged" / "layer_0.csv")) {
    const double lx = c.cx - x0, ly = c.cy - y0;
    if (lx < w || ly < w || lx > 1.6 - w || ly > 1.6 - w) continue;
    ++merged_inner;
    EXPECT_NEAR(c.slope_x, -0.5 * b, 0.01) << "merged paper cells: slope_x on a diagonal half";
  }
  EXPECT_EQ(merged_inner, 64);
  const CliRun kf = run({"map", "--preset", "kf", "--paper-cell", "--cloud", (dir / "diagonal.xyz").string(), "--out",
                         (dir / "kf").string()});
  expect_one_line_error(kf, "--paper-cell", "--paper-cell with a preset without CCM layers");
}

// =============================================================================================
// Errors: one line, non-zero exit, no output files
// =============================================================================================

TEST(CliErrors, BadInputGivesOneLineAndNonZeroExit) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.0, 0.0, 0.0};
  write_scene_ply(dir / "scene.ply", s);
  const std::string good = (dir / "scene.ply").string();
  const std::string out = (dir / "out").string();
  {
    std::ofstream(dir / "trunc.ply", std::ios::binary)
        << "ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\nproperty float y\n"
           "property float z\nend_header\n0123456789";
    std::ofstream(dir / "bad.las", std::ios::binary) << "LASF" << std::string(300, '\0');
    std::ofstream(dir / "empty.ply") << "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
                                        "property float y\nproperty float z\nend_header\n";
    std::ofstream(dir / "comments.txt") << "# nothing here\n\n";
    std::ofstream(dir / "allnan.txt") << "nan 1 2\n1 inf 2\n";
    std::ofstream(dir / "garbage.xyz") << "hello world\n";
    std::ofstream(dir / "poses1.txt") << "0 0 0 0\n0 0 0 0\n";
  }
  struct Case {
    std::vector<std::string> args;
    std::string needle;
  };
  const std::vector<Case> cases = {
      {{"map", "--preset", "ccm", "--cloud", (dir / "missing.ply").string(), "--out", out}, "missing.ply"},
      {{"map", "--preset", "ccm", "--cloud", (dir / "trunc.ply").string(), "--out", out}, "truncated"},
      {{"map", "--preset", "ccm", "--cloud", (dir / "bad.las").string(), "--out", out}, "bad.las"},
      {{"map", "--preset", "ccm", "--cloud", (dir / "empty.ply").string(), "--out", out}, "empty cloud"},
      {{"map", "--preset", "ccm", "--cloud", (dir / "comments.txt").string(), "--out", out}, "empty cloud"},
      {{"map", "--preset", "ccm", "--cloud", (dir / "allnan.txt").string(), "--out", out}, "non-finite"},
      {{"map", "--preset", "ccm", "--cloud", (dir / "garbage.xyz").string(), "--out", out}, "line 1"},
      {{"map", "--preset", "bogus", "--cloud", good, "--out", out}, "unknown preset 'bogus'"},
      {{"map", "--cloud", good, "--out", out}, "--preset"},
      {{"map", "--preset", "ccm", "--out", out}, "--cloud"},
      {{"map", "--preset", "ccm", "--cloud", good}, "--out"},
      {{"map", "--preset", "ccm", "--res", "abc", "--cloud", good, "--out", out}, "not a number"},
      {{"map", "--preset", "ccm", "--res", "-0.1", "--cloud", good, "--out", out}, "out of range"},
      {{"map", "--preset", "ccm", "--res", "nan", "--cloud", good, "--out", out}, "out of range"},
      {{"map", "--preset", "ccm", "--res", "0.08x", "--cloud", good, "--out", out}, "not a number"},
      {{"map", "--preset", "ccm", "--wl", "0", "--cloud", good, "--out", out}, "--wl"},
      {{"map", "--preset", "ccm", "--res"}, "--res: 1 required METRES missing"},
      {{"map", "--preset", "ccm", "--cloud", good, "--out", out, "--colour", "red"}, "not expected: red --colour"},
      {{"map", "--preset", "ccm", "--cloud", good, "--out", out, "stray"}, "not expected: stray"},
      {{"map", "--preset", "ccm", "--preset", "kf", "--cloud", good, "--out", out}, "--preset: At Most 1"},
      {{"map", "--preset", "ccm", "--cloud", good, "--out", out, "--at", "1,2"}, "--at belongs to 'ccmap query'"},
      {{"map", "--preset", "ccm", "--cloud", good, "--poses", (dir / "poses1.txt").string(), "--out", out},
       "2 poses for 1 clouds"},
      {{"map", "--preset", "ccm", "--cloud", good, "--poses", (dir / "nope.txt").string(), "--out", out}, "nope.txt"},
      {{"query", "--preset", "ccm", "--cloud", good, "--at", "1"}, "--at"},
      {{"query", "--preset", "ccm", "--cloud", good, "--at", "1,x"}, "not a number"},
      {{"query", "--preset", "ccm", "--cloud", good}, "--at"},
      {{"map", "--preset", "ccm", "--cloud", good, "--bounds", "1,2,3", "--out", out}, "XMIN,YMIN,XMAX,YMAX"},
      {{"map", "--preset", "ccm", "--cloud", good, "--bounds", "1,2,3,4,5", "--out", out}, "XMIN,YMIN,XMAX,YMAX"},
      {{"map", "--preset", "ccm", "--cloud", good, "--bounds", "3,0,1,4", "--out", out}, "XMIN < XMAX"},
      {{"map", "--preset", "ccm", "--cloud", good, "--bounds", "0,0,inf,4", "--out", out}, "finite"},
      {{"map", "--preset", "ccm", "--cloud", good, "--bounds", "0,a,1,4", "--out", out}, "not a number"},
      {{"frobnicate"}, "unknown command"},
  };
  for (const Case& c : cases) {
    std::string joined;
    for (const std::string& a : c.args) joined += a + " ";
    expect_one_line_error(run(c.args), c.needle, joined);
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "layer_0.csv")) << "no output after a failed run";
}

TEST(CliErrors, HelpTexts) {
  const CliRun top = run({"--help"});
  EXPECT_EQ(top.code, 0);
  EXPECT_NE(top.out.find("usage: ccmap"), std::string::npos);
  const CliRun map = run({"map", "--help"});
  EXPECT_EQ(map.code, 0);
  EXPECT_NE(map.out.find("--preset NAME"), std::string::npos);
  EXPECT_NE(map.out.find("cadre"), std::string::npos);
  const CliRun query = run({"query", "--help"});
  EXPECT_EQ(query.code, 0);
  EXPECT_NE(query.out.find("--at X,Y"), std::string::npos);
  EXPECT_NE(run({}).code, 0);
}

TEST(CliErrors, TheBuiltBinaryExitsNonZeroWithOneLine) {
  const TempDir dir(kTempPrefix);
  const std::string err_file = (dir / "err.txt").string();
  const std::string help = std::string("'") + CCMAP_CLI_BINARY + "' map --help > /dev/null 2>&1";
  const int help_status = std::system(help.c_str());
  ASSERT_TRUE(WIFEXITED(help_status));
  EXPECT_EQ(WEXITSTATUS(help_status), 0);
  const std::string bad = std::string("'") + CCMAP_CLI_BINARY + "' map --preset ccm --cloud '" +
                          (dir / "missing.las").string() + "' --out '" + (dir / "o").string() + "' > /dev/null 2> '" +
                          err_file + "'";
  const int status = std::system(bad.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  std::ifstream in(err_file);
  std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(all.rfind("ccmap: error: cannot open", 0), 0U) << all;
  EXPECT_EQ(std::count(all.begin(), all.end(), '\n'), 1);
}

// =============================================================================================
// Real data (/work/shared/data, or $CCMAP_DATA_DIR)
// =============================================================================================

TEST(CliRealData, LoneStarCropAndScan) {
  const fs::path data = data_dir();
  const fs::path crop = data / "lone_star_tls" / "lone_star_crop_10x10m_x515386.6_y4918368.4.xyz";
  const fs::path las = data / "lone_star_tls" / "lone-star.las";
  if (!fs::exists(crop) || !fs::exists(las)) {
    GTEST_SKIP() << "real data not found under " << data << " (set CCMAP_DATA_DIR to the folder holding lone_star_tls/)";
  }
  const TempDir dir(kTempPrefix);
  // The 10 x 10 m crop fits the 8 cm CCM layer (+-10.24 m): every finite point is used.
  const CliRun r = run({"map", "--preset", "ccm", "--res", "0.16", "--cloud", crop.string(), "--out", (dir / "crop").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  long long read = 0, used = 0;
  ASSERT_TRUE(summary_counts(r.out, &read, &used)) << r.out;
  EXPECT_EQ(read, 53810);
  EXPECT_EQ(used, read) << r.out;
  const std::vector<LayerCellRow> rows = read_rows(dir / "crop" / "layer_0.csv");
  ASSERT_GT(rows.size(), 2000U) << "a 10 x 10 m patch holds ~3900 cells of 16 cm";
  std::size_t traversable = 0;
  for (const LayerCellRow& row : rows) {
    // The crop: x 515386.6 .. 515396.6, y 4918368.4 .. 4918378.4, z 2324.44 .. 2335.01.
    ASSERT_GT(row.cx, 515386.6 - 0.08);
    ASSERT_LT(row.cx, 515396.6 + 0.08);
    ASSERT_GT(row.cy, 4918368.4 - 0.08);
    ASSERT_LT(row.cy, 4918378.4 + 0.08);
    if (row.cell_class != "unknown") {  // an unknown cell may hold 3 points: its plane extrapolates
      ASSERT_GT(row.height, 2324.0);
      ASSERT_LT(row.height, 2335.5);
    }
    if (row.cell_class == "traversable") ++traversable;
  }
  EXPECT_GT(traversable, rows.size() / 2) << "geothermal ground with ~4.6 deg median slope is mostly traversable";

  // The whole 32 x 41 m scan: wider than every window (ccm: +-10.24 m), mapped whole by tiling.
  for (const char* preset : {"ccm", "cadre"}) {
    const fs::path out = dir / (std::string("las_") + preset);
    const CliRun s = run({"map", "--preset", preset, "--cloud", las.string(), "--out", out.string()});
    ASSERT_EQ(s.code, 0) << s.err;
    ASSERT_TRUE(summary_counts(s.out, &read, &used)) << s.out;
    EXPECT_EQ(read, 518862);
    EXPECT_EQ(used, read) << preset << ": every point of the file is mapped\n" << s.out;
    EXPECT_EQ(ccmap::test::summary_count(s.out, "outside map "), 0) << preset << ": " << s.out;
    EXPECT_NE(s.out.find("progress: "), std::string::npos) << "a long run prints progress lines";
    const int layers = std::string(preset) == "cadre" ? 5 : 1;
    for (int k = 0; k < layers; ++k) {
      const std::vector<LayerCellRow> layer = read_rows(out / ("layer_" + std::to_string(k) + ".csv"));
      ASSERT_FALSE(layer.empty()) << preset << " layer " << k;
      double x_min = layer[0].cx, x_max = layer[0].cx, y_min = layer[0].cy, y_max = layer[0].cy;
      for (const LayerCellRow& row : layer) {
        x_min = std::min(x_min, row.cx);
        x_max = std::max(x_max, row.cx);
        y_min = std::min(y_min, row.cy);
        y_max = std::max(y_max, row.cy);
      }
      EXPECT_GT(x_max - x_min, 30.0) << preset << " layer " << k << ": the scan is 32.4 m wide";
      EXPECT_GT(y_max - y_min, 38.0) << preset << " layer " << k << ": the scan is 40.8 m long";
    }
  }
}

// =============================================================================================
// Saving and merging maps
// =============================================================================================

namespace {

/// Rows of a layer CSV keyed by their absolute cell index.
std::map<std::pair<long long, long long>, LayerCellRow> by_index(const std::vector<LayerCellRow>& rows) {
  std::map<std::pair<long long, long long>, LayerCellRow> out;
  for (const LayerCellRow& r : rows) out[{r.ix, r.iy}] = r;
  return out;
}

/// Every cell of `got` is in `want` and agrees in weight and class exactly, in height, slope and
/// normal variance within float rounding (the merge adds in another order).
void expect_same_layer(const std::vector<LayerCellRow>& got_rows, const std::vector<LayerCellRow>& want_rows,
                       const std::string& what) {
  const auto got = by_index(got_rows), want = by_index(want_rows);
  ASSERT_EQ(got.size(), want.size()) << what;
  for (const auto& [index, g] : got) {
    const auto it = want.find(index);
    ASSERT_NE(it, want.end()) << what << ": cell (" << index.first << ", " << index.second << ") only in the merge";
    const LayerCellRow& w = it->second;
    ASSERT_EQ(g.weight, w.weight) << what;
    ASSERT_EQ(g.cell_class, w.cell_class) << what << " at (" << g.cx << ", " << g.cy << ")";
    ASSERT_NEAR(g.height, w.height, 2e-5) << what << " at (" << g.cx << ", " << g.cy << ")";
    ASSERT_NEAR(g.slope_x, w.slope_x, 1e-4 * (1.0 + std::fabs(w.slope_x))) << what;
    ASSERT_NEAR(g.slope_y, w.slope_y, 1e-4 * (1.0 + std::fabs(w.slope_y))) << what;
    ASSERT_NEAR(g.normal_var, w.normal_var, 1e-7 + 1e-4 * w.normal_var) << what;
  }
}

}  // namespace

TEST(CliMerge, TwoHalvesSavedAndMergedEqualOneMapOfBothInAbsoluteCoordinates) {
  // West and east halves of the scene at UTM-sized coordinates: their centroids, and so the
  // origins each 'ccmap map' subtracts, lie 1.6 m apart. Merged through the saved origins they
  // must give the map of both clouds made in one run.
  const TempDir dir(kTempPrefix);
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "west.ply", s, -kHalfSide, 0.0);
  write_scene_ply(dir / "east.ply", s, 0.0, kHalfSide);
  const CliRun west = run({"map", "--preset", "ccm", "--cloud", (dir / "west.ply").string(), "--out",
                           (dir / "west").string(), "--save", (dir / "west.map").string()});
  ASSERT_EQ(west.code, 0) << west.err;
  EXPECT_NE(west.out.find("saved: "), std::string::npos) << west.out;
  const CliRun east = run({"map", "--preset", "ccm", "--cloud", (dir / "east.ply").string(), "--out",
                           (dir / "east").string(), "--save", (dir / "east.map").string()});
  ASSERT_EQ(east.code, 0) << east.err;
  EXPECT_EQ(fs::file_size(dir / "west.map"), 2883884U + 48U) << "the single-CCM snapshot (full cells) and the origin record";
  const CliRun both = run({"map", "--preset", "ccm", "--cloud", (dir / "west.ply").string(), "--cloud",
                           (dir / "east.ply").string(), "--out", (dir / "both").string()});
  ASSERT_EQ(both.code, 0) << both.err;
  const CliRun merged = run({"merge", "--preset", "ccm", "--in", (dir / "west.map").string(), "--in",
                             (dir / "east.map").string(), "--out", (dir / "merged").string()});
  ASSERT_EQ(merged.code, 0) << merged.err;
  EXPECT_NE(merged.out.find(" 0 outside the first map's windows"), std::string::npos) << merged.out;
  const std::vector<LayerCellRow> rows = read_rows(dir / "merged" / "layer_0.csv");
  check_ccm_layer(rows, s, 0.08, 40U * 40U);  // absolute coordinates, the whole square
  expect_same_layer(rows, read_rows(dir / "both" / "layer_0.csv"), "merged halves vs one run");
  EXPECT_TRUE(fs::exists(dir / "merged" / "layer_0_class.png"));
}

TEST(CliMerge, CadreHalvesMergeWhereTheFirstMapsWindowsReach) {
  // Without --poses a saved CADRE map is one stack at the origin (the CSV files cover every
  // tile): the 4 cm layer holds +-1.28 m of it, the 64 cm layer +-10.24 m. Merged into the west
  // map, the east map's coarse cells land in the west map's windows, its fine cells beyond them
  // are counted as outside.
  const TempDir dir(kTempPrefix);
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "west.ply", s, -kHalfSide, 0.0);
  write_scene_ply(dir / "east.ply", s, 0.0, kHalfSide);
  for (const char* half : {"west", "east"}) {
    const CliRun r = run({"map", "--preset", "cadre", "--cloud", (dir / (std::string(half) + ".ply")).string(), "--out",
                          (dir / half).string(), "--save", (dir / (std::string(half) + ".map")).string()});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find("saved map: one stack at the origin"), std::string::npos) << r.out;
  }
  const CliRun merged = run({"merge", "--preset", "cadre", "--in", (dir / "west.map").string(), "--in",
                             (dir / "east.map").string(), "--out", (dir / "merged").string()});
  ASSERT_EQ(merged.code, 0) << merged.err;
  long long merged_cells = 0, outside = 0;
  const std::size_t at = merged.out.find("cells merged, ");
  ASSERT_NE(at, std::string::npos) << merged.out;
  ASSERT_EQ(std::sscanf(merged.out.c_str() + merged.out.rfind(", ", at - 1) + 2, "%lld cells merged, %lld outside",
                        &merged_cells, &outside),
            2)
      << merged.out;
  EXPECT_GT(merged_cells, 0);
  EXPECT_GT(outside, 0) << "the east map's 4 cm cells beyond the west map's 4 cm window";
  // The 64 cm layer knows both halves.
  bool west_cell = false, east_cell = false;
  for (const LayerCellRow& row : read_rows(dir / "merged" / "layer_4.csv")) {
    west_cell = west_cell || row.cx < s.x0 - 0.64;
    east_cell = east_cell || row.cx > s.x0 + 0.64;
  }
  EXPECT_TRUE(west_cell && east_cell) << "the merged 64 cm layer does not span both halves";
}

TEST(CliMerge, RefusalsSayWhy) {
  const TempDir dir(kTempPrefix);
  const Scene s{0.0, 0.0, 0.0};
  write_scene_ply(dir / "scene.ply", s);
  ASSERT_EQ(run({"map", "--preset", "ccm", "--cloud", (dir / "scene.ply").string(), "--out", (dir / "a").string(),
                 "--save", (dir / "a.map").string()})
                .code,
            0);
  ASSERT_EQ(run({"map", "--preset", "ccm", "--res", "0.16", "--cloud", (dir / "scene.ply").string(), "--out",
                 (dir / "b").string(), "--save", (dir / "coarse.map").string()})
                .code,
            0);
  const std::string a = (dir / "a.map").string(), out = (dir / "m").string();
  expect_one_line_error(run({"merge", "--preset", "ccm", "--in", a, "--out", out}), "two or more --in", "one input");
  expect_one_line_error(run({"merge", "--preset", "cadre", "--in", a, "--in", a, "--out", out}), "is it a cadre map",
                        "another preset");
  // The CCM cell kind is part of a map's shape: a full-cell map is not read as paper cells.
  expect_one_line_error(run({"merge", "--preset", "ccm", "--paper-cell", "--in", a, "--in", a, "--out", out}),
                        "saved with --paper-cell", "full-cell maps merged as paper cells");
  expect_one_line_error(run({"merge", "--preset", "ccm", "--in", a, "--in", (dir / "coarse.map").string(), "--out", out}),
                        "misaligned", "another cell width");
  expect_one_line_error(run({"merge", "--preset", "ccm", "--in", a, "--in", a, "--offset", "0.05,0", "--out", out}),
                        "misaligned", "an offset off the grid");
  expect_one_line_error(run({"merge", "--preset", "ccm", "--in", a, "--in", a, "--cloud", "x.ply", "--out", out}),
                        "bring their own parameters", "a cloud");
  expect_one_line_error(run({"map", "--preset", "ccm", "--cloud", (dir / "scene.ply").string(), "--in", a, "--out", out}),
                        "--in belongs to 'ccmap merge'", "--in with map");
  // A corrupt origin record, a truncated file, a flipped snapshot byte.
  std::vector<char> bytes;
  {
    std::ifstream in(a, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  auto write = [&](const std::string& name, const std::vector<char>& b) {
    std::ofstream o(dir / name, std::ios::binary);
    o.write(b.data(), static_cast<std::streamsize>(b.size()));
    return (dir / name).string();
  };
  std::vector<char> bad = bytes;
  bad[bad.size() - 30] ^= 1;
  expect_one_line_error(run({"merge", "--preset", "ccm", "--in", a, "--in", write("bad_origin.map", bad), "--out", out}),
                        "origin record after the snapshot is corrupt", "a corrupt origin record");
  expect_one_line_error(
      run({"merge", "--preset", "ccm", "--in", a, "--in",
           write("short.map", std::vector<char>(bytes.begin(), bytes.end() - 10)), "--out", out}),
      "expected a snapshot of this preset", "a truncated file");
  bad = bytes;
  bad[1000] ^= 1;
  expect_one_line_error(run({"merge", "--preset", "ccm", "--in", a, "--in", write("bad_snapshot.map", bad), "--out", out}),
                        "does not merge (corrupt)", "a flipped snapshot byte");
  // A plain snapshot (flight software's, no origin record) has its origin at 0: --offset places
  // it in x and y; its heights are relative to 0, the first map's to its origin, so z moves by
  // minus the first map's origin height.
  const std::string plain = write("plain.snap", std::vector<char>(bytes.begin(), bytes.end() - 48));
  const CliRun r = run({"merge", "--preset", "ccm", "--in", a, "--in", plain, "--offset", "0.08,-0.16", "--out", out});
  ASSERT_EQ(r.code, 0) << r.err;
  double ox = 0.0, oy = 0.0, oz = 0.0, dz = 1.0;
  const std::size_t origin_at = r.out.find("(origin ");
  const std::size_t offset_at = r.out.find("offset 0.080 -0.160 ");
  ASSERT_NE(origin_at, std::string::npos) << r.out;
  ASSERT_NE(offset_at, std::string::npos) << r.out;
  ASSERT_EQ(std::sscanf(r.out.c_str() + origin_at, "(origin %lf %lf %lf", &ox, &oy, &oz), 3) << r.out;
  ASSERT_EQ(std::sscanf(r.out.c_str() + offset_at, "offset 0.080 -0.160 %lf", &dz), 1) << r.out;
  EXPECT_NEAR(dz, -oz, 1e-9) << r.out;
}

// 'ccmap product': the header and every cell it prints against the map's own answers (a CADRE
// stack mapped here, its product published into buffers in memory and written to a file).
TEST(CliProduct, PrintsEveryCellAsTheMapAnswersIt) {
  const TempDir dir(kTempPrefix);
  static ccmap::Stack<ccmap::CadreConfig> stack;
  ASSERT_EQ(stack.init(ccmap::default_stack_params(0.04F)), ccmap::Status::kOk);
  std::vector<ccmap::PointXYZ> points;
  for (int j = 0; j < 60; ++j) {
    for (int i = 0; i < 60; ++i) {
      const float x = -0.9F + 0.03F * static_cast<float>(i);
      const float y = -0.9F + 0.03F * static_cast<float>(j);
      points.push_back({x, y, 0.05F * x + ((x > 0.3F && x < 0.6F && std::fabs(y) < 0.2F) ? 0.3F : 0.0F)});
    }
  }
  ASSERT_EQ(stack.update_frame(points.data(), points.size(), ccmap::PointXYZ{0.0F, 0.0F, 0.8F}, nullptr),
            ccmap::Status::kOk);
  std::vector<std::uint32_t> storage(3U * ccmap::product_size(64U, 64U) / 4U);
  ccmap::ProductBuffers buffers{};
  ASSERT_EQ(ccmap::product_buffers_init(&buffers, storage.data(), storage.size() * 4U), ccmap::Status::kOk);
  ccmap::ProductSpec spec{};
  spec.layer = 1;
  spec.tag = 42U;
  ASSERT_EQ(ccmap::publish_product(stack, spec, buffers), ccmap::Status::kOk);
  std::vector<std::uint8_t> bytes(ccmap::product_size(64U, 64U));
  std::size_t written = 0U;
  ASSERT_EQ(ccmap::product_read(buffers, bytes.data(), bytes.size(), &written), ccmap::Status::kOk);
  const std::filesystem::path file = dir / "p.ccmp";
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                              static_cast<std::streamsize>(written));
  const CliRun run = ccmap::test::run_ccmap({"product", "--in", file.string(), "--cells", "--png", (dir / "p").string()});
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("\ntag 42\n"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("\nlayer 1\n"), std::string::npos) << run.out;
  std::istringstream lines(run.out.substr(run.out.find("ix iy class")));
  std::string header;
  std::getline(lines, header);
  const float w = stack.layer_cell_width(1);
  int rows = 0, known = 0;
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream f(line);
    int ix = 0, iy = 0, cost = 0, layer = 0;
    std::string cell_class, status;
    float height = 0.0F;
    f >> ix >> iy >> cell_class >> cost >> status >> layer >> height;
    const ccmap::QueryResult q = stack.query((static_cast<float>(ix) + 0.5F) * w, (static_cast<float>(iy) + 0.5F) * w);
    EXPECT_EQ(cell_class, ccmap::to_string(q.cell_class)) << line;
    EXPECT_EQ(status, ccmap::to_string(q.status)) << line;
    if (q.status == ccmap::Status::kOk) {
      ++known;
      EXPECT_NEAR(height, q.height_m, 1e-5F) << line;
    }
    ++rows;
  }
  EXPECT_EQ(rows, 64 * 64);
  EXPECT_GT(known, 100);
  EXPECT_TRUE(std::filesystem::exists(dir / "p_class.png") && std::filesystem::exists(dir / "p_height.png"));
  bytes[300] ^= 1U;
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                              static_cast<std::streamsize>(written));
  const CliRun damaged = ccmap::test::run_ccmap({"product", "--in", file.string()});
  EXPECT_EQ(damaged.code, 1);
  EXPECT_NE(damaged.err.find("not a whole map product (corrupt)"), std::string::npos) << damaged.err;
}
