// The global map of a patch directory (tools/global_map: the assembler and the ccmap_global_map
// tool). A rover drives 21 m of a 6 m square over analytic terrain with odometry whose heading
// drifts 0.01 rad/m, mapping in its drifted frame through a PatchKeeper on a POSIX patch
// directory; a loop closure with the simulation's own drift (in the analytic case, the one an
// alignment would measure) is stitched (PatchStitcher) and the patches re-stamped. The drive
// stops 3 m before the start: a window that came back over the start's patches in the drifted
// frame would merge its cells into them at the wrong place (docs/design.md section 13.6).
// References: the terrain itself (the height RMS of the global map at its pixel centres, with and
// without the corrections), the GeoTIFF read back with GDAL, a damaged file beside good ones
// (counted, the good ones all used).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <gdal_priv.h>

#include "ccmap/global/patch_stitcher.hpp"
#include "global_map.hpp"
#include "support/global_configs.hpp"
#include "temp_dir.hpp"

namespace ccmap {
namespace {

using GlobalConfig = test::OneCcm4cmConfig;
using Map = Stack<GlobalConfig>;
using Pose = test::DrivePose;
using test::TempDir;
using Keeper = PatchKeeper<GlobalConfig, 16>;
using Stitcher = PatchStitcher<256, 4096>;

double terrain(double x, double y) { return 0.3 * std::sin(0.7 * x) + 0.2 * std::cos(0.5 * y) + 0.02 * x; }

/// The ground within 1 m of the true pose, as the rover places it with its believed pose.
std::vector<PointXYZ> frame(const Pose& truth, const Pose& believed) {
  return test::ground_seen_from(truth, believed, 1.0, 0.02, terrain);
}

/// Drives 70 steps of the square into `directory`, closes the loop and re-stamps every patch.
/// Returns the pose error at the closure before it (m).
double drive_and_stitch(const std::string& directory) {
  const auto map = std::make_unique<Map>();
  const auto keeper = std::make_unique<Keeper>();
  const auto stitcher = std::make_unique<Stitcher>();
  platform::PosixDirectory dir{};
  platform::PatchStorage storage{};
  StackParams params = default_stack_params(0.04F);
  params.free_space_rays = 0.0F;
  EXPECT_TRUE(platform::posix_directory_storage(directory.c_str(), &dir, &storage));
  EXPECT_EQ(map->init(params), Status::kOk);
  EXPECT_EQ(keeper->init(*map, storage), Status::kOk);
  EXPECT_EQ(stitcher->attach(*keeper), Status::kOk);
  Pose t{0.0, 0.0, 0.0}, b{0.0, 0.0, 0.0};
  double travelled = 0.0;
  for (int k = 0; k <= 70; ++k) {  // 70 steps of 0.3 m
    const PatchPose stamp{static_cast<float>(b.x), static_cast<float>(b.y), static_cast<float>(b.yaw),
                          static_cast<float>(0.02 * std::sqrt(travelled)),
                          static_cast<float>(0.01 * std::sqrt(travelled))};
    EXPECT_EQ(stitcher->move_to(*keeper, stamp.x_m, stamp.y_m, stamp, nullptr), Status::kOk);
    const auto points = frame(t, b);
    EXPECT_EQ(map->update_frame(points.data(), points.size(), PointXYZ{stamp.x_m, stamp.y_m, 1.0F}, nullptr),
              Status::kOk);
    if (k == 70) {
      break;
    }
    const double turn = k % 20 == 19 ? M_PI / 2.0 : 0.0;
    t = Pose{t.x + 0.3 * std::cos(t.yaw), t.y + 0.3 * std::sin(t.yaw), t.yaw + turn};
    b = Pose{b.x + 0.3 * std::cos(b.yaw), b.y + 0.3 * std::sin(b.yaw), b.yaw + turn + 0.01 * 0.3};
    travelled += 0.3;
  }
  // The window leaves the start's last cells into patches too: a move far away.
  EXPECT_EQ(stitcher->move_to(*keeper, 20.0F, 20.0F,
                              PatchPose{static_cast<float>(b.x), static_cast<float>(b.y), static_cast<float>(b.yaw),
                                        static_cast<float>(0.02 * std::sqrt(travelled)),
                                        static_cast<float>(0.01 * std::sqrt(travelled))},
                              nullptr),
            Status::kOk);
  // The closure: the anchor (node 0) is the truth; the last node is off by the drift. Both the
  // last real node and the move away take it (the same pose).
  EXPECT_EQ(stitcher->close_loop(0U, static_cast<float>(t.x - b.x), static_cast<float>(t.y - b.y),
                                 static_cast<float>(t.yaw - b.yaw)),
            Status::kOk);
  StitchReport r{};
  stitcher->restamp_step(*keeper, 100000U, &r);
  EXPECT_EQ(r.failed, 0U);
  EXPECT_EQ(r.remaining, 0U);
  EXPECT_GT(r.restamped, 100U);
  EXPECT_EQ(keeper->counters().cells_lost, 0U);
  return std::hypot(t.x - b.x, t.y - b.y);
}

struct Rms {
  double rms = 0.0;
  int pixels = 0;
};
Rms height_rms(const tools::GlobalRaster& r) {
  double sum = 0.0;
  int n = 0;
  for (int iy = 0; iy < r.ny; ++iy) {
    for (int ix = 0; ix < r.nx; ++ix) {
      const float h = r.height[static_cast<std::size_t>(iy * r.nx + ix)];
      if (std::isfinite(h)) {
        const double x = (static_cast<double>(r.ix_min + ix) + 0.5) * r.cell_width_m;
        const double y = (static_cast<double>(r.iy_min + iy) + 0.5) * r.cell_width_m;
        sum += std::pow(h - terrain(x, y), 2);
        ++n;
      }
    }
  }
  return Rms{n > 0 ? std::sqrt(sum / n) : 0.0, n};
}

struct Stitched {
  TempDir dir{"ccmap_global_map_"};
  double closure_error_m = drive_and_stitch(dir.path().string());
};
const Stitched& stitched() {
  static const Stitched s;  // one drive for every test
  return s;
}

TEST(GlobalMap, TheStitchedMapMatchesTheTerrainAndTheUnstitchedOneDoesNot) {
  const Stitched& s = stitched();
  EXPECT_GT(s.closure_error_m, 0.5);
  std::vector<tools::GlobalPatch> patches;
  tools::PatchDirectoryCounts counts;
  std::string error;
  ASSERT_TRUE(tools::read_patch_directory(s.dir.path().string(), 0, &patches, &counts, &error)) << error;
  EXPECT_EQ(counts.refused, 0);
  EXPECT_EQ(counts.used, counts.files);
  EXPECT_GT(counts.used, 100);
  tools::GlobalMapOptions options;
  tools::GlobalRaster corrected, raw;
  ASSERT_TRUE(tools::assemble_global_map(patches, options, &corrected, &error)) << error;
  options.apply_corrections = false;
  ASSERT_TRUE(tools::assemble_global_map(patches, options, &raw, &error)) << error;
  const Rms after = height_rms(corrected);
  const Rms before = height_rms(raw);
  std::printf("global map: %d pixels, height RMS %.4f m stitched, %.4f m unstitched (closure error %.3f m)\n",
              after.pixels, after.rms, before.rms, s.closure_error_m);
  // The drive's band: 21 m x 2 m wide at 4 cm, most of it observed.
  EXPECT_GT(after.pixels, 15000);
  EXPECT_LT(after.rms, 0.002);
  EXPECT_GT(before.rms, 20.0 * after.rms);
  // Flat-ish analytic terrain: no hazards.
  EXPECT_EQ(corrected.hazard_pixels, 0);
}

TEST(GlobalMap, TheToolWritesAGeoTiffThatGdalReadsBackAsTheRaster) {
  const Stitched& s = stitched();
  const std::string tif = (s.dir / "global.tif").string();
  const std::string command =
      std::string(CCMAP_GLOBAL_MAP_BINARY) + " --patches " + s.dir.path().string() + " --out " + tif + " > /dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0);
  std::vector<tools::GlobalPatch> patches;
  tools::GlobalRaster raster;
  std::string error;
  ASSERT_TRUE(tools::read_patch_directory(s.dir.path().string(), 0, &patches, nullptr, &error));
  ASSERT_TRUE(tools::assemble_global_map(patches, tools::GlobalMapOptions{}, &raster, &error));
  GDALAllRegister();
  GDALDataset* ds = GDALDataset::FromHandle(GDALOpenEx(tif.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr,
                                                       nullptr, nullptr));
  ASSERT_NE(ds, nullptr);
  ASSERT_EQ(ds->GetRasterXSize(), raster.nx);
  ASSERT_EQ(ds->GetRasterYSize(), raster.ny);
  ASSERT_EQ(ds->GetRasterCount(), 5);
  double gt[6] = {};
  ASSERT_EQ(ds->GetGeoTransform(gt), CE_None);
  EXPECT_DOUBLE_EQ(gt[0], static_cast<double>(raster.ix_min) * raster.cell_width_m);
  EXPECT_DOUBLE_EQ(gt[3], static_cast<double>(raster.iy_min + raster.ny) * raster.cell_width_m);
  std::vector<double> height(static_cast<std::size_t>(raster.nx) * static_cast<std::size_t>(raster.ny));
  std::vector<double> cls(height.size());
  ASSERT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, raster.nx, raster.ny, height.data(), raster.nx, raster.ny,
                                           GDT_Float64, 0, 0, nullptr),
            CE_None);
  ASSERT_EQ(ds->GetRasterBand(5)->RasterIO(GF_Read, 0, 0, raster.nx, raster.ny, cls.data(), raster.nx, raster.ny,
                                           GDT_Float64, 0, 0, nullptr),
            CE_None);
  GDALClose(GDALDataset::ToHandle(ds));
  // Row 0 of the file is the highest y; the terrain at each pixel's centre from the geotransform.
  double sum = 0.0;
  int n = 0, mismatches = 0;
  for (int row = 0; row < raster.ny; ++row) {
    for (int col = 0; col < raster.nx; ++col) {
      const double h = height[static_cast<std::size_t>(row * raster.nx + col)];
      const float want = raster.height[static_cast<std::size_t>((raster.ny - 1 - row) * raster.nx + col)];
      mismatches += (std::isfinite(h) != std::isfinite(want) || (std::isfinite(h) && h != want)) ? 1 : 0;
      if (std::isfinite(h)) {
        const double x = gt[0] + (col + 0.5) * gt[1], y = gt[3] + (row + 0.5) * gt[5];
        sum += std::pow(h - terrain(x, y), 2);
        ++n;
        EXPECT_EQ(cls[static_cast<std::size_t>(row * raster.nx + col)] == 2.0, false);  // no obstacles here
      }
    }
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(n, 15000);
  EXPECT_LT(std::sqrt(sum / n), 0.002);
  std::remove(tif.c_str());
}

TEST(GlobalMap, ADamagedPatchFileIsCountedAndTheGoodOnesAllUsed) {
  const Stitched& s = stitched();
  std::vector<tools::GlobalPatch> patches;
  tools::PatchDirectoryCounts clean;
  std::string error;
  ASSERT_TRUE(tools::read_patch_directory(s.dir.path().string(), 0, &patches, &clean, &error));
  // A copy of a good patch with one byte flipped, under another key, and a short file.
  TempDir damaged("ccmap_global_map_bad_");
  for (const auto& entry : std::filesystem::directory_iterator(s.dir.path())) {
    std::filesystem::copy(entry.path(), damaged / entry.path().filename());
  }
  std::filesystem::path first;
  for (const auto& entry : std::filesystem::directory_iterator(s.dir.path())) {
    first = entry.path().extension() == ".ccp" ? entry.path() : first;
  }
  std::ifstream in(first, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  bytes[300] = static_cast<char>(bytes[300] ^ 0x40);
  std::ofstream(damaged / "L0_900_900.ccp", std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  std::ofstream(damaged / "L0_901_900.ccp", std::ios::binary) << "CCMP";
  tools::PatchDirectoryCounts counts;
  std::vector<tools::GlobalPatch> kept;
  ASSERT_TRUE(tools::read_patch_directory(damaged.path().string(), 0, &kept, &counts, &error));
  EXPECT_EQ(counts.refused, 2);
  EXPECT_EQ(counts.used, clean.used);
  EXPECT_EQ(kept.size(), patches.size());
  EXPECT_FALSE(tools::read_patch_directory((s.dir / "missing").string(), 0, &kept, &counts, &error));
  EXPECT_NE(error.find("cannot read"), std::string::npos);
}

}  // namespace
}  // namespace ccmap
