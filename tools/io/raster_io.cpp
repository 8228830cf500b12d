// raster_io.hpp through GDAL's C++ API (gdal_priv.h, ogr_spatialref.h).
#include "raster_io.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

namespace ccmap::tools {
namespace {

/// While alive, GDAL's messages go nowhere (the tools print one line per error); the last one
/// is read with CPLGetLastErrorMsg.
class QuietGdal {
 public:
  QuietGdal() {
    GDALAllRegister();  // idempotent
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
  }
  ~QuietGdal() { CPLPopErrorHandler(); }
  QuietGdal(const QuietGdal&) = delete;
  QuietGdal& operator=(const QuietGdal&) = delete;
  /// "what (GDAL: last message)", or "what" when GDAL said nothing.
  static std::string reason(const std::string& what) {
    const char* msg = CPLGetLastErrorMsg();
    return msg != nullptr && msg[0] != '\0' ? what + " (GDAL: " + msg + ")" : what;
  }
};

struct DatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(GDALDataset::ToHandle(d)); }
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

double class_number(const std::string& cell_class) {
  if (cell_class == "traversable") return kGeoTiffClassTraversable;
  if (cell_class == "obstacle") return kGeoTiffClassObstacle;
  if (cell_class == "steep") return kGeoTiffClassSteep;
  if (cell_class == "drop") return kGeoTiffClassDrop;
  return kGeoTiffClassUnknown;
}

}  // namespace

bool raster_io_available() { return true; }

std::string raster_io_unavailable_reason() { return {}; }

bool srs_from_epsg(int code, std::string* wkt, std::string* error) {
  const QuietGdal quiet;
  OGRSpatialReference srs;
  char* text = nullptr;
  if (code <= 0 || srs.importFromEPSG(code) != OGRERR_NONE || srs.exportToWkt(&text) != OGRERR_NONE) {
    CPLFree(text);
    *error = QuietGdal::reason("EPSG:" + std::to_string(code) + " is not a coordinate system GDAL knows");
    return false;
  }
  *wkt = text;
  CPLFree(text);
  return true;
}

bool write_layer_geotiff(const std::string& path, const std::vector<LayerCellRow>& rows, const LayerWindow& extent,
                         double cell_width_m, const std::string& srs_wkt, std::string* error) {
  const QuietGdal quiet;
  if (extent.nx <= 0 || extent.ny <= 0 || !(cell_width_m > 0.0)) {
    *error = path + ": empty raster window";
    return false;
  }
  const std::size_t nx = static_cast<std::size_t>(extent.nx), ny = static_cast<std::size_t>(extent.ny);
  // One plane per band, row 0 north (largest iy).
  std::vector<double> planes(kGeoTiffBands * nx * ny, std::numeric_limits<double>::quiet_NaN());
  for (const LayerCellRow& r : rows) {
    const std::int64_t gx = r.ix - extent.ix_min, gy = r.iy - extent.iy_min;
    if (gx < 0 || gy < 0 || gx >= extent.nx || gy >= extent.ny) continue;
    const std::size_t pixel = (ny - 1 - static_cast<std::size_t>(gy)) * nx + static_cast<std::size_t>(gx);
    const double values[kGeoTiffBands] = {r.height, r.slope_x, r.slope_y, r.normal_var, class_number(r.cell_class)};
    for (std::size_t b = 0; b < kGeoTiffBands; ++b) planes[b * nx * ny + pixel] = values[b];
  }
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (driver == nullptr) {
    *error = QuietGdal::reason("GDAL has no GTiff driver");
    return false;
  }
  CPLStringList options;
  options.AddNameValue("COMPRESS", "DEFLATE");
  options.AddNameValue("TILED", "YES");
  Dataset ds(driver->Create(path.c_str(), extent.nx, extent.ny, kGeoTiffBands, GDT_Float64, options.List()));
  if (!ds) {
    *error = QuietGdal::reason("cannot create " + path);
    return false;
  }
  double transform[6] = {static_cast<double>(extent.ix_min) * cell_width_m, cell_width_m, 0.0,
                         static_cast<double>(extent.iy_min + extent.ny) * cell_width_m, 0.0, -cell_width_m};
  bool ok = ds->SetGeoTransform(transform) == CE_None;
  if (ok && !srs_wkt.empty()) {
    OGRSpatialReference srs;
    ok = srs.importFromWkt(srs_wkt.c_str()) == OGRERR_NONE && ds->SetSpatialRef(&srs) == CE_None;
  }
  for (int b = 0; ok && b < kGeoTiffBands; ++b) {
    GDALRasterBand* band = ds->GetRasterBand(b + 1);
    band->SetDescription(kGeoTiffBandNames[b]);
    ok = band->SetNoDataValue(std::numeric_limits<double>::quiet_NaN()) == CE_None &&
         band->RasterIO(GF_Write, 0, 0, extent.nx, extent.ny, planes.data() + static_cast<std::size_t>(b) * nx * ny,
                        extent.nx, extent.ny, GDT_Float64, 0, 0, nullptr) == CE_None;
  }
  // Closing flushes the file: an error raised then is a failed write too (GDAL 3.6's GDALClose
  // returns nothing, so the error state tells).
  std::string why = ok ? std::string() : QuietGdal::reason("cannot write " + path);
  CPLErrorReset();
  ds.reset();
  if (why.empty() && CPLGetLastErrorType() >= CE_Failure) why = QuietGdal::reason("cannot write " + path);
  if (!why.empty()) {
    *error = why;
    return false;
  }
  return true;
}

Cloud read_dem(const std::string& path, std::string* srs_wkt) {
  const QuietGdal quiet;
  Cloud cloud;
  if (srs_wkt != nullptr) srs_wkt->clear();
  Dataset ds(GDALDataset::FromHandle(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  if (!ds) {
    cloud.error = QuietGdal::reason("cannot open " + path + " as a raster DEM");
    return cloud;
  }
  const int nx = ds->GetRasterXSize(), ny = ds->GetRasterYSize();
  if (ds->GetRasterCount() < 1 || nx <= 0 || ny <= 0) {
    cloud.error = path + ": the raster has no band";
    return cloud;
  }
  if (static_cast<std::uint64_t>(nx) * static_cast<std::uint64_t>(ny) > kMaxDemCells) {
    cloud.error = path + ": " + std::to_string(nx) + " x " + std::to_string(ny) + " cells, more than the " +
                  std::to_string(kMaxDemCells) + " a DEM may have here (crop it, e.g. gdal_translate -srcwin)";
    return cloud;
  }
  double gt[6] = {0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  if (ds->GetGeoTransform(gt) != CE_None) {
    cloud.error = path + ": no geotransform (cell size and position unknown)";
    return cloud;
  }
  if (srs_wkt != nullptr) {
    const OGRSpatialReference* srs = ds->GetSpatialRef();
    char* text = nullptr;
    if (srs != nullptr && srs->exportToWkt(&text) == OGRERR_NONE && text != nullptr) *srs_wkt = text;
    CPLFree(text);
  }
  GDALRasterBand* band = ds->GetRasterBand(1);
  GDALRasterBand* mask = band->GetMaskBand();
  int has_scale = 0, has_offset = 0;
  const double scale_value = band->GetScale(&has_scale), offset_value = band->GetOffset(&has_offset);
  const double scale = has_scale != 0 ? scale_value : 1.0, offset = has_offset != 0 ? offset_value : 0.0;
  std::vector<double> values(static_cast<std::size_t>(nx));
  std::vector<GByte> valid(static_cast<std::size_t>(nx));
  std::uint64_t no_data = 0;
  for (int row = 0; row < ny; ++row) {
    if (band->RasterIO(GF_Read, 0, row, nx, 1, values.data(), nx, 1, GDT_Float64, 0, 0, nullptr) != CE_None ||
        mask == nullptr ||
        mask->RasterIO(GF_Read, 0, row, nx, 1, valid.data(), nx, 1, GDT_Byte, 0, 0, nullptr) != CE_None) {
      Cloud failed;
      failed.error = QuietGdal::reason(path + ": cannot read row " + std::to_string(row));
      return failed;
    }
    for (int col = 0; col < nx; ++col) {
      const std::size_t c = static_cast<std::size_t>(col);
      if (valid[c] == 0) {
        ++no_data;
        continue;
      }
      ++cloud.declared;
      const double px = col + 0.5, py = row + 0.5;
      const double x = gt[0] + px * gt[1] + py * gt[2];
      const double y = gt[3] + px * gt[4] + py * gt[5];
      const double z = values[c] * scale + offset;
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
        ++cloud.skipped_non_finite;
        continue;
      }
      cloud.x.push_back(x);
      cloud.y.push_back(y);
      cloud.z.push_back(z);
    }
  }
  char description[160];
  std::snprintf(description, sizeof description, "DEM %s %d x %d cells of %g x %g m, %llu no-data",
                ds->GetDriver() != nullptr ? ds->GetDriver()->GetDescription() : "raster", nx, ny,
                std::hypot(gt[1], gt[4]), std::hypot(gt[2], gt[5]), static_cast<unsigned long long>(no_data));
  cloud.format = description;
  return cloud;
}

}  // namespace ccmap::tools
