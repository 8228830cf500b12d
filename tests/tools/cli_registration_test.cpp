// `ccmap map --register` and `ccmap merge --align` (issue 22): a rover's frames over rolling
// ground at UTM-sized coordinates whose second pose is off by a known error; two saved maps of
// the same ground whose second is displaced by a known offset.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "support/terrain_frames.hpp"
#include "temp_dir.hpp"

namespace {

namespace fs = std::filesystem;
using ccmap::test::CliRun;
using ccmap::test::run_ccmap;
using ccmap::test::TempDir;
using ccmap::test::XyzPoint;

const char* const kTempPrefix = "ccmap_cli_registration_test_";
constexpr double kX0 = 512345.0, kY0 = 4918000.0, kZ0 = 1500.0;  // absolute coordinates of the local frame

/// A frame of rolling ground (tests/support/terrain_frames.hpp) seen from (sx, sy), in absolute
/// coordinates, every point moved by -error (the rover's pose is off by -error: registration
/// should answer +error).
std::vector<XyzPoint> frame(double sx, std::uint32_t seed, const double error[3]) {
  ccmap::test::TerrainFrameSpec spec;
  spec.terrain = ccmap::test::Terrain::kRolling;
  spec.sensor_x = sx;
  spec.seed = seed;
  const ccmap::test::TerrainFrame f = ccmap::test::make_terrain_frame(spec);
  std::vector<XyzPoint> out;
  for (const ccmap::PointXYZ& p : f.points) {
    out.push_back(XyzPoint{kX0 + p.x - error[0], kY0 + p.y - error[1], kZ0 + p.z - error[2]});
  }
  return out;
}

/// "registration N: NAME: ok correction DX DY DZ m DYAW rad" -> the four numbers; false if absent.
bool correction_of(const std::string& out, const std::string& head, double v[4]) {
  const std::size_t at = out.find(head);
  if (at == std::string::npos) return false;
  const std::size_t c = out.find(" correction ", at);
  return c != std::string::npos && std::sscanf(out.c_str() + c, " correction %lf %lf %lf m %lf rad", &v[0], &v[1], &v[2], &v[3]) == 4;
}

TEST(CliRegistration, RegisterCorrectsAFrameWhosePoseIsOff) {
  const TempDir dir(kTempPrefix);
  const double none[3] = {0.0, 0.0, 0.0};
  const double error[3] = {0.03, -0.02, 0.015};
  ccmap::test::write_ply(dir / "a.ply", frame(0.0, 1U, none));
  ccmap::test::write_ply(dir / "b.ply", frame(0.1, 2U, error));
  ccmap::test::write_ply(dir / "c.ply", frame(0.2, 3U, error));  // the same error: carried from b
  {
    std::ofstream poses(dir / "poses.txt");
    // The believed sensor positions (x y z yaw): the third pose already carries b's error.
    poses.precision(10);
    poses << kX0 << ' ' << kY0 << ' ' << kZ0 + 0.175 << " 0\n";
    poses << kX0 + 0.1 - error[0] << ' ' << kY0 - error[1] << ' ' << kZ0 + 0.175 - error[2] << " 0\n";
    poses << kX0 + 0.2 - error[0] << ' ' << kY0 - error[1] << ' ' << kZ0 + 0.175 - error[2] << " 0\n";
  }
  const CliRun r = run_ccmap({"map", "--preset", "cadre", "--sensor", "stereo", "--cloud", (dir / "a.ply").string(),
                              "--cloud", (dir / "b.ply").string(), "--cloud", (dir / "c.ply").string(), "--poses",
                              (dir / "poses.txt").string(), "--register", "--out", (dir / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  double v[4];
  ASSERT_TRUE(correction_of(r.out, "registration 2: b.ply: ok", v)) << r.out;
  EXPECT_NEAR(v[0], error[0], 3e-3) << r.out;
  EXPECT_NEAR(v[1], error[1], 3e-3) << r.out;
  EXPECT_NEAR(v[2], error[2], 1e-3) << r.out;
  EXPECT_NEAR(v[3], 0.0, 2e-3) << r.out;
  EXPECT_EQ(r.out.find("registration 1:"), std::string::npos) << "the first frame starts the map";
  // The third frame, moved by b's correction first, needs almost none of its own.
  ASSERT_TRUE(correction_of(r.out, "registration 3: c.ply: ok", v)) << r.out;
  EXPECT_LT(std::hypot(v[0], v[1]), 3e-3) << r.out;
  EXPECT_LT(std::fabs(v[2]), 1e-3) << r.out;
}

TEST(CliRegistration, RegisterNeedsPoses) {
  const TempDir dir(kTempPrefix);
  const double none[3] = {0.0, 0.0, 0.0};
  ccmap::test::write_ply(dir / "a.ply", frame(0.0, 1U, none));
  const CliRun r = run_ccmap({"map", "--preset", "cadre", "--cloud", (dir / "a.ply").string(), "--register", "--out",
                              (dir / "out").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--register needs --poses"), std::string::npos) << r.err;
}

TEST(CliRegistration, MergeAlignReportsTheOffsetAndAppliesWhatTheGridTakes) {
  // Two rovers' saved maps of the same ground; the second's clouds are 0.45 m east and 2 cm high
  // of where they belong (its pose was off). Placed by the saved origins (the absolute
  // coordinates), --align reports the correction (-0.45, 0, -0.02), applies dz and the nearest
  // whole 64 cm cell (-0.64 m), and names the remainder (+0.19 m) as not applied.
  const TempDir dir(kTempPrefix);
  const double none[3] = {0.0, 0.0, 0.0};
  const double off[3] = {-0.45, 0.0, -0.02};  // frame() subtracts: the points move by +0.45 m, +2 cm
  for (const char* name : {"a", "b"}) {
    const bool second = name[0] == 'b';
    ccmap::test::write_ply(dir / (std::string(name) + ".ply"), frame(0.0, second ? 5U : 4U, second ? off : none));
    std::ofstream poses(dir / (std::string(name) + ".txt"));
    poses.precision(10);
    poses << kX0 + (second ? 0.45 : 0.0) << ' ' << kY0 << ' ' << kZ0 + 0.175 << " 0\n";
  }
  for (const char* name : {"a", "b"}) {
    const std::string n(name);
    const CliRun r = run_ccmap({"map", "--preset", "cadre", "--sensor", "stereo", "--cloud", (dir / (n + ".ply")).string(),
                                "--poses", (dir / (n + ".txt")).string(), "--out", (dir / n).string(), "--save",
                                (dir / (n + ".map")).string()});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  const CliRun m = run_ccmap({"merge", "--preset", "cadre", "--in", (dir / "a.map").string(), "--in",
                              (dir / "b.map").string(), "--align", "--out", (dir / "ab").string()});
  ASSERT_EQ(m.code, 0) << m.err << m.out;
  double v[4];
  ASSERT_TRUE(correction_of(m.out, "alignment " + (dir / "b.map").string() + ": ok", v)) << m.out;
  // Placed by the saved origins, b keeps its absolute coordinates: the correction is its error.
  EXPECT_NEAR(v[0], -0.45, 0.01) << m.out;
  EXPECT_NEAR(v[1], 0.0, 0.01) << m.out;
  EXPECT_NEAR(v[2], -0.02, 2e-3) << m.out;
  EXPECT_NE(m.out.find(": applied -0.640 0.000 -0.02"), std::string::npos) << "one whole 64 cm cell west, dz\n" << m.out;
  EXPECT_NE(m.out.find("not applied 0.19"), std::string::npos) << "the 19 cm remainder, named\n" << m.out;
}

}  // namespace
