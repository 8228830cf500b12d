// ccmap --geotiff and --dem (tools/io/raster_io.hpp) end to end. The GeoTIFFs are read back,
// and the DEMs written, with GDAL directly (not through the tool's raster_io), and checked
// against the layer CSV and an analytic scene: the georeference from the scene's geometry, the
// unobserved cells from the hole cut into it, the heights from the plane the DEM samples.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <cpl_string.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include "cli_run.hpp"
#include "temp_dir.hpp"

namespace fs = std::filesystem;
using ccmap::test::CliRun;
using ccmap::test::read_rows;
using ccmap::test::run_ccmap;
using ccmap::test::XyzPoint;
using ccmap::tools::LayerCellRow;

namespace {

const char* const kTempPrefix = "ccmap_raster_test_";

struct DatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(GDALDataset::ToHandle(d)); }
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

Dataset open_raster(const fs::path& path) {
  GDALAllRegister();
  return Dataset(GDALDataset::FromHandle(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
}

/// Band b (1-based) of a dataset, north-up rows, as doubles.
std::vector<double> read_band(GDALDataset& ds, int b) {
  const int nx = ds.GetRasterXSize(), ny = ds.GetRasterYSize();
  std::vector<double> v(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  EXPECT_EQ(ds.GetRasterBand(b)->RasterIO(GF_Read, 0, 0, nx, ny, v.data(), nx, ny, GDT_Float64, 0, 0, nullptr), CE_None);
  return v;
}

// --- the scene of the GeoTIFF test ----------------------------------------------------------
// A 3.2 x 3.2 m plane z = z0 + 0.2 (x - x0) - 0.1 (y - y0) around an absolute UTM-like centre
// (x0, y0), points every 1 cm at the centres of a 1 cm grid, with a 1.28 m square hole
// [x0 - 0.64, x0 + 0.64)^2. x0, y0 are multiples of 0.64 m (the coarsest cadre cell), so every
// layer's cells align with the scene: the cells of width w inside the hole are unobserved,
// (1.28 / w)^2 of them, and the others each hold points.
constexpr double kX0 = 515392.0, kY0 = 4918374.4, kZ0 = 2210.0;  // 805300 and 7684960 coarsest cells
constexpr double kHalf = 1.6, kHole = 0.64;

std::vector<XyzPoint> holed_plane() {
  std::vector<XyzPoint> points;
  for (int i = 0; i < 320; ++i) {
    for (int j = 0; j < 320; ++j) {
      const double lx = -kHalf + 0.005 + 0.01 * i, ly = -kHalf + 0.005 + 0.01 * j;
      if (std::fabs(lx) < kHole && std::fabs(ly) < kHole) continue;
      points.push_back({kX0 + lx, kY0 + ly, kZ0 + 0.2 * lx - 0.1 * ly});
    }
  }
  return points;
}

double class_code(const std::string& c) {
  if (c == "traversable") return 1.0;
  if (c == "obstacle") return 2.0;
  if (c == "steep") return 3.0;
  return 0.0;
}

}  // namespace

TEST(GeoTiff, GeoreferencedInAbsoluteCoordinatesBandsEqualTheCsvNanWhereUnobserved) {
  const ccmap::test::TempDir dir(kTempPrefix);
  ccmap::test::write_ply(dir / "holed.ply", holed_plane());
  const fs::path out = dir / "out";
  const CliRun r = run_ccmap({"map", "--preset", "cadre", "--cloud", (dir / "holed.ply").string(), "--out", out.string(),
                              "--geotiff", "--epsg", "32612"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("geotiff: "), std::string::npos) << r.out;
  const char* const band_names[5] = {"height", "slope_x", "slope_y", "normal_var", "class"};
  for (int k = 0; k < 5; ++k) {
    const double w = 0.04 * std::ldexp(1.0, k);
    const std::vector<LayerCellRow> rows = read_rows(out / ("layer_" + std::to_string(k) + ".csv"));
    ASSERT_FALSE(rows.empty()) << "layer " << k;
    const Dataset ds = open_raster(out / ("layer_" + std::to_string(k) + ".tif"));
    ASSERT_TRUE(ds) << "layer " << k << ": GDAL cannot open the GeoTIFF";
    ASSERT_EQ(ds->GetRasterCount(), 5);
    // The scene's extent in whole cells of width w: its points lie in [x0 - 1.595, x0 + 1.595].
    const long long cells_west = static_cast<long long>(std::ceil(1.595 / w));
    const long long cells_east = static_cast<long long>(std::floor(1.595 / w)) + 1;
    const int side = static_cast<int>(cells_west + cells_east);
    ASSERT_EQ(ds->GetRasterXSize(), side) << "layer " << k;
    ASSERT_EQ(ds->GetRasterYSize(), side) << "layer " << k;
    double gt[6];
    ASSERT_EQ(ds->GetGeoTransform(gt), CE_None);
    EXPECT_NEAR(gt[0], kX0 - static_cast<double>(cells_west) * w, 1e-6) << "layer " << k << ": west edge";
    EXPECT_NEAR(gt[3], kY0 + static_cast<double>(cells_east) * w, 1e-6) << "layer " << k << ": north edge";
    EXPECT_NEAR(gt[1], w, 1e-12);
    EXPECT_NEAR(gt[5], -w, 1e-12);
    EXPECT_EQ(gt[2], 0.0);
    EXPECT_EQ(gt[4], 0.0);
    const OGRSpatialReference* srs = ds->GetSpatialRef();
    ASSERT_NE(srs, nullptr) << "--epsg 32612 wrote no coordinate system";
    ASSERT_NE(srs->GetAuthorityCode(nullptr), nullptr);
    EXPECT_STREQ(srs->GetAuthorityCode(nullptr), "32612");

    std::vector<std::vector<double>> bands;
    for (int b = 1; b <= 5; ++b) {
      EXPECT_STREQ(ds->GetRasterBand(b)->GetDescription(), band_names[b - 1]);
      int has_nodata = 0;
      EXPECT_TRUE(std::isnan(ds->GetRasterBand(b)->GetNoDataValue(&has_nodata)));
      EXPECT_TRUE(has_nodata);
      bands.push_back(read_band(*ds, b));
    }
    // Pixel (col, row) <-> global cell (ix_min + col, iy_max - row): index the CSV by cell.
    std::map<std::pair<long long, long long>, const LayerCellRow*> by_cell;
    for (const LayerCellRow& c : rows) by_cell[{c.ix, c.iy}] = &c;
    const long long ix_min = std::llround(gt[0] / w), iy_max = std::llround(gt[3] / w) - 1;
    long long unobserved = 0, matched = 0;
    for (int row = 0; row < side; ++row) {
      for (int col = 0; col < side; ++col) {
        const std::size_t p = static_cast<std::size_t>(row) * static_cast<std::size_t>(side) + static_cast<std::size_t>(col);
        const auto it = by_cell.find({ix_min + col, iy_max - row});
        if (it == by_cell.end()) {
          ++unobserved;
          for (int b = 0; b < 5; ++b) EXPECT_TRUE(std::isnan(bands[b][p])) << "unobserved pixel has band " << b + 1;
          continue;
        }
        const LayerCellRow& c = *it->second;
        ++matched;
        // The CSV prints heights with 6 decimals and the rest with 7 significant digits.
        EXPECT_NEAR(bands[0][p], c.height, 5e-7) << "height of cell " << c.ix << "," << c.iy;
        EXPECT_NEAR(bands[1][p], c.slope_x, 1e-6 * std::fabs(c.slope_x) + 1e-12);
        EXPECT_NEAR(bands[2][p], c.slope_y, 1e-6 * std::fabs(c.slope_y) + 1e-12);
        EXPECT_NEAR(bands[3][p], c.normal_var, 1e-6 * std::fabs(c.normal_var) + 1e-30);
        EXPECT_EQ(bands[4][p], class_code(c.cell_class));
        // The pixel's centre is the CSV's cell centre: the georeference and the CSV agree.
        EXPECT_NEAR(gt[0] + (col + 0.5) * w, c.cx, 1e-6);
        EXPECT_NEAR(gt[3] - (row + 0.5) * w, c.cy, 1e-6);
      }
    }
    EXPECT_EQ(matched, static_cast<long long>(rows.size())) << "every CSV cell is a pixel";
    const long long hole_cells = std::llround(2.0 * kHole / w);
    EXPECT_EQ(unobserved, hole_cells * hole_cells) << "layer " << k << ": the hole's cells, and only they, are NaN";
  }
}

TEST(GeoTiff, RefusesAnUnknownEpsgCodeBeforeMapping) {
  const ccmap::test::TempDir dir(kTempPrefix);
  ccmap::test::write_ply(dir / "holed.ply", holed_plane());
  const fs::path out = dir / "out";
  for (const char* code : {"999998", "abc", "0", "4326.5"}) {
    const CliRun r = run_ccmap({"map", "--preset", "ccm", "--cloud", (dir / "holed.ply").string(), "--out", out.string(),
                                "--geotiff", "--epsg", code});
    EXPECT_EQ(r.code, 2) << code;
    EXPECT_EQ(r.err.rfind("ccmap: error: --epsg", 0), 0U) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  EXPECT_FALSE(fs::exists(out / "layer_0.csv")) << "refused before any output";
  const CliRun alone = run_ccmap({"map", "--preset", "ccm", "--cloud", (dir / "holed.ply").string(), "--out",
                                  out.string(), "--epsg", "32612"});
  EXPECT_EQ(alone.code, 2);
  EXPECT_NE(alone.err.find("--geotiff"), std::string::npos) << alone.err;
}

// --- DEMs -----------------------------------------------------------------------------------
// A 60 x 40 DEM of 0.5 m cells sampling z = 100 + 0.1 (x - xw) - 0.05 (y - ys) at the cell centres,
// its north-west corner at absolute (600000, 4100020) (EPSG:32633), a 6 x 4-cell block of no-data
// in it. Mapped with 1 m cells (2 x 2 DEM cells each), every cell's plane is exact.
constexpr double kDemWest = 600000.0, kDemNorth = 4100020.0, kDemCell = 0.5;
constexpr int kDemCols = 60, kDemRows = 40;
constexpr int kHoleCol0 = 20, kHoleRow0 = 10, kHoleCols = 6, kHoleRows = 4;
constexpr double kNoData = -9999.0;

double dem_plane(double x, double y) { return 100.0 + 0.1 * (x - kDemWest) - 0.05 * (y - (kDemNorth - kDemRows * kDemCell)); }

bool in_dem_hole(int col, int row) {
  return col >= kHoleCol0 && col < kHoleCol0 + kHoleCols && row >= kHoleRow0 && row < kHoleRow0 + kHoleRows;
}

/// Writes the DEM with GDAL's `driver` (GTiff, or AAIGrid through a copy of an in-memory one).
void write_dem(const fs::path& path, const char* driver_name) {
  GDALAllRegister();
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  ASSERT_NE(mem, nullptr);
  Dataset ds(mem->Create("", kDemCols, kDemRows, 1, GDT_Float32, nullptr));
  ASSERT_TRUE(ds);
  double gt[6] = {kDemWest, kDemCell, 0.0, kDemNorth, 0.0, -kDemCell};
  ds->SetGeoTransform(gt);
  OGRSpatialReference srs;
  ASSERT_EQ(srs.importFromEPSG(32633), OGRERR_NONE);
  ds->SetSpatialRef(&srs);
  std::vector<float> z(static_cast<std::size_t>(kDemCols) * kDemRows);
  for (int row = 0; row < kDemRows; ++row) {
    for (int col = 0; col < kDemCols; ++col) {
      const double x = kDemWest + (col + 0.5) * kDemCell, y = kDemNorth - (row + 0.5) * kDemCell;
      z[static_cast<std::size_t>(row) * kDemCols + static_cast<std::size_t>(col)] =
          static_cast<float>(in_dem_hole(col, row) ? kNoData : dem_plane(x, y));
    }
  }
  GDALRasterBand* band = ds->GetRasterBand(1);
  ASSERT_EQ(band->SetNoDataValue(kNoData), CE_None);
  ASSERT_EQ(band->RasterIO(GF_Write, 0, 0, kDemCols, kDemRows, z.data(), kDemCols, kDemRows, GDT_Float32, 0, 0, nullptr),
            CE_None);
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName(driver_name);
  ASSERT_NE(driver, nullptr);
  Dataset copy(driver->CreateCopy(path.c_str(), ds.get(), FALSE, nullptr, nullptr, nullptr));
  ASSERT_TRUE(copy) << "GDAL could not write " << path;
}

TEST(Dem, SyntheticDemMappedHeightsAndSlopesRecoveredNoDataSkipped) {
  const ccmap::test::TempDir dir(kTempPrefix);
  for (const char* driver : {"GTiff", "AAIGrid"}) {
    SCOPED_TRACE(driver);
    const fs::path dem = dir / (std::string("plane.") + (std::string(driver) == "GTiff" ? "tif" : "asc"));
    write_dem(dem, driver);
    const fs::path out = dir / (std::string("out_") + driver);
    const CliRun r = run_ccmap({"map", "--preset", "ccm", "--res", "1", "--dem", dem.string(), "--out", out.string(),
                                "--geotiff"});
    ASSERT_EQ(r.code, 0) << r.err;
    long long read = 0, used = 0;
    ASSERT_TRUE(ccmap::test::summary_counts(r.out, &read, &used)) << r.out;
    const long long with_data = kDemCols * kDemRows - kHoleCols * kHoleRows;
    EXPECT_EQ(read, with_data) << "one point per DEM cell with data";
    EXPECT_EQ(used, with_data) << r.out;
    const std::vector<LayerCellRow> rows = read_rows(out / "layer_0.csv");
    // 30 x 20 map cells of 1 m, less the 3 x 2 that lie wholly in the no-data block.
    EXPECT_EQ(rows.size(), static_cast<std::size_t>(30 * 20 - 3 * 2));
    for (const LayerCellRow& c : rows) {
      EXPECT_NEAR(c.height, dem_plane(c.cx, c.cy), 2e-3) << "height at (" << c.cx << ", " << c.cy << ")";
      EXPECT_NEAR(c.slope_x, 0.1, 1e-3) << "slope_x at (" << c.cx << ", " << c.cy << ")";
      EXPECT_NEAR(c.slope_y, -0.05, 1e-3) << "slope_y at (" << c.cx << ", " << c.cy << ")";
      EXPECT_GE(c.cx, kDemWest);
      EXPECT_LE(c.cx, kDemWest + kDemCols * kDemCell);
      EXPECT_LE(c.cy, kDemNorth);
    }
    // Without --epsg the GeoTIFF carries the DEM's coordinate system (the ASCII grid has none).
    const Dataset tif = open_raster(out / "layer_0.tif");
    ASSERT_TRUE(tif);
    const OGRSpatialReference* srs = tif->GetSpatialRef();
    if (std::string(driver) == "GTiff") {
      ASSERT_NE(srs, nullptr);
      ASSERT_NE(srs->GetAuthorityCode(nullptr), nullptr);
      EXPECT_STREQ(srs->GetAuthorityCode(nullptr), "32633");
    }
  }
}

TEST(Dem, RefusesWhatIsNotARasterWithOneLine) {
  const ccmap::test::TempDir dir(kTempPrefix);
  std::ofstream(dir / "text.asc") << "hello\n";
  const CliRun r = run_ccmap({"map", "--preset", "ccm", "--dem", (dir / "text.asc").string(), "--out", (dir / "o").string()});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err.rfind("ccmap: error: ", 0), 0U) << r.err;
  EXPECT_NE(r.err.find("text.asc"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "GDAL's own messages stay quiet: " << r.err;
}

// The HiRISE DTM crop of ../shared/data: 70 x 120 cells of 1.01 m, origin 0,0. Mapped with 2.02 m
// cells, each map cell holds 2 x 2 DEM cells symmetric about its centre, so its height is their
// mean (computed here in double from the file, read with GDAL).
TEST(Dem, RealHiriseDtmHeightsAreTheMeansOfTheirDemCells) {
  const char* env = std::getenv("CCMAP_DATA_DIR");
  const fs::path file = fs::path(env != nullptr ? env : CCMAP_DEFAULT_DATA_DIR) / "hirise_mars_dtm" / "mars_dtm_1.01m.asc";
  if (!fs::exists(file)) GTEST_SKIP() << "real data not found: " << file << " (set CCMAP_DATA_DIR to the folder holding hirise_mars_dtm/)";
  const Dataset dem = open_raster(file);
  ASSERT_TRUE(dem);
  const int nx = dem->GetRasterXSize(), ny = dem->GetRasterYSize();
  const std::vector<double> z = read_band(*dem, 1);
  double gt[6];
  ASSERT_EQ(dem->GetGeoTransform(gt), CE_None);
  const ccmap::test::TempDir dir(kTempPrefix);
  const fs::path out = dir / "out";
  const CliRun r = run_ccmap({"map", "--preset", "ccm", "--res", "2.02", "--dem", file.string(), "--out", out.string(), "--geotiff"});
  ASSERT_EQ(r.code, 0) << r.err;
  long long read = 0, used = 0;
  ASSERT_TRUE(ccmap::test::summary_counts(r.out, &read, &used)) << r.out;
  EXPECT_EQ(read, static_cast<long long>(nx) * ny) << "the crop has no no-data cell";
  const std::vector<LayerCellRow> rows = read_rows(out / "layer_0.csv");
  EXPECT_EQ(rows.size(), static_cast<std::size_t>((nx / 2) * (ny / 2)));
  int checked = 0;
  for (const LayerCellRow& c : rows) {
    // DEM columns/rows of the cell: x in [cx - 1.01, cx + 1.01), y likewise (rows count south).
    const int col0 = static_cast<int>(std::lround((c.cx - 1.01 - gt[0]) / gt[1]));
    const int row0 = static_cast<int>(std::lround((c.cy + 1.01 - gt[3]) / gt[5]));
    ASSERT_TRUE(col0 >= 0 && col0 + 1 < nx && row0 >= 0 && row0 + 1 < ny) << c.cx << ", " << c.cy;
    double mean = 0.0;
    for (int dr = 0; dr < 2; ++dr) {
      for (int dc = 0; dc < 2; ++dc) mean += z[static_cast<std::size_t>(row0 + dr) * nx + static_cast<std::size_t>(col0 + dc)];
    }
    mean /= 4.0;
    EXPECT_NEAR(c.height, mean, 2e-3) << "cell at (" << c.cx << ", " << c.cy << ")";
    ++checked;
  }
  EXPECT_EQ(checked, (nx / 2) * (ny / 2));
  const Dataset tif = open_raster(out / "layer_0.tif");
  ASSERT_TRUE(tif);
  double tgt[6];
  ASSERT_EQ(tif->GetGeoTransform(tgt), CE_None);
  EXPECT_NEAR(tgt[0], gt[0], 1e-9) << "the map's west edge is the DTM's";
  EXPECT_NEAR(tgt[3], gt[3], 1e-9) << "the map's north edge is the DTM's";
}
