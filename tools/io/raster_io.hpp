// Raster I/O of the host tools through GDAL (Debian libgdal-dev): map layers written as
// georeferenced GeoTIFFs, and raster DEMs (GeoTIFF, ESRI ASCII grid, anything GDAL reads) read
// as point clouds. GDAL is optional at configure time (CCMAP_WITH_GDAL, cmake/CcmapHostLibs.cmake):
// without it raster_io.cpp is replaced by raster_io_unavailable.cpp, whose functions refuse with
// raster_io_unavailable_reason() and touch no file.
//
// GDAL's own messages never reach stderr: they are collected into the one-line `error`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cloud_reader.hpp"
#include "csv_writer.hpp"
#include "layer_images.hpp"

namespace ccmap::tools {

/// True when this build reads and writes rasters (built with GDAL).
[[nodiscard]] bool raster_io_available();

/// Why rasters are refused in this build; empty when raster_io_available().
[[nodiscard]] std::string raster_io_unavailable_reason();

/// Bands of a layer GeoTIFF, in order (band 1 first). All Float64, no-data NaN (unobserved
/// cells): height (m, absolute), slope_x = dz/dx, slope_y = dz/dy, normal variance (m^2) as in
/// the layer CSV, and the class as a number (kGeoTiffClass*).
inline constexpr int kGeoTiffBands = 5;
inline constexpr const char* kGeoTiffBandNames[kGeoTiffBands] = {"height", "slope_x", "slope_y", "normal_var", "class"};
inline constexpr double kGeoTiffClassUnknown = 0.0;
inline constexpr double kGeoTiffClassTraversable = 1.0;
inline constexpr double kGeoTiffClassObstacle = 2.0;
inline constexpr double kGeoTiffClassSteep = 3.0;
inline constexpr double kGeoTiffClassDrop = 4.0;  ///< a drop-off (weight 0, height its upper bound)

/// The WKT of EPSG:`code`, or false with a message (an unknown code). For --epsg, checked
/// before any mapping.
[[nodiscard]] bool srs_from_epsg(int code, std::string* wkt, std::string* error);

/// Writes the cells of `rows` inside `extent` (map-frame global indices, one pixel per cell of
/// width `cell_width_m`; north up: pixel row 0 holds iy = iy_min + ny - 1) as a GeoTIFF with
/// the bands above. Geotransform: top-left corner (ix_min * w, (iy_min + ny) * w), pixel w x -w,
/// i.e. the cells' absolute map-frame coordinates. `srs_wkt` (may be empty: none) is the
/// coordinate system written. False with a message on an I/O or GDAL error.
[[nodiscard]] bool write_layer_geotiff(const std::string& path, const std::vector<LayerCellRow>& rows,
                                       const LayerWindow& extent, double cell_width_m, const std::string& srs_wkt,
                                       std::string* error);

/// Largest DEM read as a cloud (cells): 24 bytes per point in the cloud, so about 2.4 GB.
inline constexpr std::uint64_t kMaxDemCells = 100000000ULL;

/// Reads band 1 of a raster DEM as a cloud: one point per cell with data, at the cell centre
/// (the raster's geotransform, rotation terms included), z = value * scale + offset of the band.
/// Cells GDAL's mask marks as no-data are skipped and not declared; cells with data but a
/// non-finite value are counted in skipped_non_finite. `declared` counts the cells with data.
/// Refused (ok() false): no file, not a raster, no geotransform (no metric cells), more than
/// kMaxDemCells cells. *srs_wkt (may be null) receives the raster's coordinate system or "".
[[nodiscard]] Cloud read_dem(const std::string& path, std::string* srs_wkt);

}  // namespace ccmap::tools
