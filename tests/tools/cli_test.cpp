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
#include <sstream>
#include <string>
#include <vector>

#include "cli.hpp"
#include "csv_writer.hpp"

namespace fs = std::filesystem;
using ccmap::tools::LayerCellRow;

namespace {

struct CliRun {
  int code;
  std::string out;
  std::string err;
};

CliRun run(std::vector<std::string> args) {
  args.insert(args.begin(), "ccmap");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::ostringstream out, err;
  const int code = ccmap::tools::run_cli(static_cast<int>(args.size()), argv.data(), out, err);
  return CliRun{code, out.str(), err.str()};
}

fs::path temp_dir() {
  const fs::path dir = fs::temp_directory_path() /
                       ("ccmap_cli_test_" + std::to_string(::getpid()) + "_" +
                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

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

/// Writes the scene as a binary little-endian PLY with double coordinates.
void write_scene_ply(const fs::path& path, const Scene& s, double x_min_local = -kHalfSide,
                     double x_max_local = kHalfSide) {
  std::vector<double> xyz;
  const int n = static_cast<int>(std::lround(2 * kHalfSide / 0.01));
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double lx = -kHalfSide + 0.005 + 0.01 * i, ly = -kHalfSide + 0.005 + 0.01 * j;
      if (lx < x_min_local || lx >= x_max_local) continue;
      const double x = s.x0 + lx, y = s.y0 + ly;
      xyz.insert(xyz.end(), {x, y, s.height(x, y)});
    }
  }
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << xyz.size() / 3
      << "\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
  out.write(reinterpret_cast<const char*>(xyz.data()), static_cast<std::streamsize>(xyz.size() * sizeof(double)));
}

std::vector<LayerCellRow> read_rows(const fs::path& path) {
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "layer,ix,iy,cx,cy,res,weight,height,slope_x,slope_y,normal_var,elev_var,class") << path;
  std::vector<LayerCellRow> rows;
  std::string error;
  EXPECT_TRUE(ccmap::tools::read_layer_csv(path.string(), &rows, &error)) << error;
  return rows;
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

/// "points: read N, used M, ..." from the summary.
bool summary_counts(const std::string& out, long long* read, long long* used) {
  const std::size_t at = out.find("points: read ");
  return at != std::string::npos && std::sscanf(out.c_str() + at, "points: read %lld, used %lld", read, used) == 2;
}

}  // namespace

// =============================================================================================
// Mapping the synthetic scene
// =============================================================================================

TEST(CliMap, CcmPresetInclinedPlaneWithStepLocalCoordinates) {
  const fs::path dir = temp_dir();
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
  const fs::path dir = temp_dir();
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
  const fs::path dir = temp_dir();
  const Scene s{0.64 * 805292.0, 0.64 * 7684950.0, 2235.0};
  write_scene_ply(dir / "utm.ply", s);
  const CliRun r = run({"map", "--preset", "cadre", "--cloud", (dir / "utm.ply").string(), "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  long long read = 0, used = 0;
  ASSERT_TRUE(summary_counts(r.out, &read, &used)) << r.out;
  EXPECT_EQ(used, read) << "the 3.2 m square lies inside the 8 cm layer's +-2.56 m window";
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
    if (k == 0) {
      // Piece-wise constant Kalman cells: height = mean of a symmetric 4 x 4 sample = the plane
      // at the centre; slopes 0. The 4 cm layer spans +-1.28 m.
      EXPECT_EQ(rows.size(), 64U * 64U);
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
      // 8 cm CCM cells outside the 4 cm window get the points directly: exact plane fits.
      for (const LayerCellRow& row : rows) {
        const double lx = row.cx - s.x0, ly = row.cy - s.y0;
        if (std::max(std::fabs(lx), std::fabs(ly)) > 1.28 && std::fabs(lx - kStepX) > 0.05) {
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
  const fs::path dir = temp_dir();
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
  const fs::path dir = temp_dir();
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
  const fs::path dir = temp_dir();
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
  const fs::path dir = temp_dir();
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

TEST(CliMap, PerPointWeightsFromTheFileReplaceTheSensorModel) {
  // One 32 cm cell, a checkerboard of heights 1 (weight 9) and 0 (weight 1): the weighted mean
  // is 0.9 (unweighted it would be 0.5); one point with weight -1 is refused as a bad weight.
  const fs::path dir = temp_dir();
  {
    std::ofstream out(dir / "weighted.xyz");
    for (int j = 0; j < 32; ++j) {
      for (int i = 0; i < 32; ++i) {
        const bool high = (i + j) % 2 == 0;
        out << 0.005 + 0.01 * i << ' ' << 0.005 + 0.01 * j << ' ' << (high ? 1.0 : 0.0) << ' ' << (high ? 9 : 1) << "\n";
      }
    }
    out << "0.1 0.1 5.0 -1\n";
  }
  const CliRun r = run({"map", "--preset", "ccm", "--res", "0.32", "--wl", "1e6", "--cloud",
                        (dir / "weighted.xyz").string(), "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("bad weight 1"), std::string::npos) << r.out;
  const auto rows = read_rows(dir / "out" / "layer_0.csv");
  ASSERT_EQ(rows.size(), 1U);
  EXPECT_NEAR(rows[0].weight, 512.0 * 9.0 + 512.0, 1e-3) << "the file's weights must be summed";
  EXPECT_NEAR(rows[0].height, 0.9, 0.01) << "height must be the weighted mean";
}

// =============================================================================================
// Query
// =============================================================================================

TEST(CliQuery, AnswersAtAMapFramePoint) {
  const fs::path dir = temp_dir();
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
                          "normal_variance_m2", "elevation_variance_m2", "class"}) {
    EXPECT_EQ(kv.count(key), 1U) << key;
  }
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
}

// =============================================================================================
// The CCM cell: full (lateral covariance) by default, the paper's 9 floats with --paper-cell
// =============================================================================================

TEST(CliMap, DiagonalHalfCellsOnATwelveDegreePlaneWithBothCells) {
  // Issue 11's measurement: every 16 cm cell of a 12 deg plane along y seen on one diagonal half
  // (x + y < 0 relative to the cell centre), points on a 5 mm grid. The paper's cell reports
  // slope_x = -b/2 (sigma_xy = -sigma_xx / 2 on that triangle) and calls the cell covered; the
  // full cell gives slope_x = 0 and calls it unknown (its smaller lateral eigenvalue is w^2/36).
  const fs::path dir = temp_dir();
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
  const CliRun kf = run({"map", "--preset", "kf", "--paper-cell", "--cloud", (dir / "diagonal.xyz").string(), "--out",
                         (dir / "kf").string()});
  expect_one_line_error(kf, "--paper-cell", "--paper-cell with a preset without CCM layers");
}

// =============================================================================================
// Errors: one line, non-zero exit, no output files
// =============================================================================================

TEST(CliErrors, BadInputGivesOneLineAndNonZeroExit) {
  const fs::path dir = temp_dir();
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
      {{"map", "--preset", "ccm", "--res"}, "needs a value"},
      {{"map", "--preset", "ccm", "--colour", "red"}, "unknown option '--colour'"},
      {{"map", "--preset", "ccm", "stray"}, "unexpected argument 'stray'"},
      {{"map", "--preset", "ccm", "--cloud", good, "--poses", (dir / "poses1.txt").string(), "--out", out},
       "2 poses for 1 clouds"},
      {{"map", "--preset", "ccm", "--cloud", good, "--poses", (dir / "nope.txt").string(), "--out", out}, "nope.txt"},
      {{"query", "--preset", "ccm", "--cloud", good, "--at", "1"}, "--at"},
      {{"query", "--preset", "ccm", "--cloud", good, "--at", "1,x"}, "not a number"},
      {{"query", "--preset", "ccm", "--cloud", good}, "--at"},
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
  const fs::path dir = temp_dir();
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
  const fs::path dir = temp_dir();
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

  // The whole scan through the CADRE stack (+-10.24 m of its 32 x 41 m lie inside the map).
  const CliRun s = run({"map", "--preset", "cadre", "--cloud", las.string(), "--out", (dir / "las").string()});
  ASSERT_EQ(s.code, 0) << s.err;
  ASSERT_TRUE(summary_counts(s.out, &read, &used)) << s.out;
  EXPECT_EQ(read, 518862);
  EXPECT_GT(used, 100000) << s.out;
  for (int k = 0; k < 5; ++k) {
    EXPECT_FALSE(read_rows(dir / "las" / ("layer_" + std::to_string(k) + ".csv")).empty()) << "layer " << k;
  }
}
