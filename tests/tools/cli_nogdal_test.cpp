// The ccmap CLI as built without GDAL (ccmap_cli_lib_nogdal: tools/io/raster_io_unavailable.cpp):
// --geotiff, --epsg and --dem are refused up front with the reason and exit 2, no output is
// written, and the rest of the tool still maps.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
using ccmap::test::CliRun;
using ccmap::test::run_ccmap;

TEST(CliWithoutGdal, GeoTiffAndDemRefusedSayingWhyTheRestMaps) {
  const ccmap::test::TempDir dir("ccmap_cli_nogdal_test_");
  std::vector<ccmap::test::XyzPoint> points;
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 40; ++j) points.push_back({0.01 * i, 0.01 * j, 0.0});
  }
  ccmap::test::write_ply(dir / "flat.ply", points);
  const std::string cloud = (dir / "flat.ply").string(), out = (dir / "out").string();
  const std::vector<std::vector<std::string>> refused = {
      {"map", "--preset", "ccm", "--cloud", cloud, "--out", out, "--geotiff"},
      {"map", "--preset", "ccm", "--cloud", cloud, "--out", out, "--geotiff", "--epsg", "32612"},
      {"map", "--preset", "ccm", "--dem", cloud, "--out", out},
      {"query", "--preset", "ccm", "--dem", cloud, "--at", "0,0"},
  };
  for (const std::vector<std::string>& args : refused) {
    const CliRun r = run_ccmap(args);
    EXPECT_EQ(r.code, 2) << args.back();
    EXPECT_EQ(r.err.rfind("ccmap: error: ", 0), 0U) << r.err;
    EXPECT_NE(r.err.find("built without GDAL"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir / "out" / "layer_0.csv")) << "refused before any output";
  const CliRun ok = run_ccmap({"map", "--preset", "ccm", "--cloud", cloud, "--out", out});
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_TRUE(fs::exists(dir / "out" / "layer_0.csv"));
  EXPECT_FALSE(fs::exists(dir / "out" / "layer_0.tif"));
}
