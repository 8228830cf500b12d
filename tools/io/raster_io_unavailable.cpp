// raster_io.hpp in a build without GDAL (CCMAP_WITH_GDAL=OFF, or AUTO without libgdal-dev):
// every raster request is refused with the reason, and no file is touched.
#include "raster_io.hpp"

namespace ccmap::tools {

bool raster_io_available() { return false; }

std::string raster_io_unavailable_reason() {
  return "this ccmap was built without GDAL (tools/install-deps gdal, then configure with -DCCMAP_WITH_GDAL=ON)";
}

bool srs_from_epsg(int, std::string*, std::string* error) {
  *error = raster_io_unavailable_reason();
  return false;
}

bool write_layer_geotiff(const std::string&, const std::vector<LayerCellRow>&, const LayerWindow&, double,
                         const std::string&, std::string* error) {
  *error = raster_io_unavailable_reason();
  return false;
}

Cloud read_dem(const std::string& path, std::string* srs_wkt) {
  if (srs_wkt != nullptr) srs_wkt->clear();
  Cloud cloud;
  cloud.error = path + ": " + raster_io_unavailable_reason();
  return cloud;
}

}  // namespace ccmap::tools
