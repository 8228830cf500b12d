// The global map: the patches of a patch store (include/ccmap/global/patch_keeper.hpp, a POSIX
// patch directory) placed at their corrected poses (patch_stitcher.hpp) into one raster. Host
// code (std library, double): used by the ccmap_global_map tool (one GeoTIFF) and the Python
// module (ccmap.read_global_map). A bad patch file beside good ones is counted and skipped.
//
// Placement: a patch's cells were mapped in the odometry frame of the rover that wrote it; the
// patch header holds that writing pose W and its corrected pose C (equal until a loop closure
// re-stamped the patch). A cell's footprint (the square of its global indices) and its plane
// (centroid, slopes) are moved by the rigid motion C W^-1 of the plane (heights unchanged); each
// raster pixel of the same width takes the cells whose moved footprints hold its centre. A
// pixel's height is the weight-weighted mean of those cells' planes at its centre, its slopes
// and normal variance their weighted means, its weight their sum (a point count for unit weights), its class
// the worst of theirs (hazard order: drop-off, obstacle, steep, traversable, unknown), each cell
// classified as the stack does (classify_ccm with the layer's threshold).
//
// What it does not do: CCM layers only (Kalman and OMG fine layers hold no plane); one layer a
// raster (the layers of a stack are different widths: docs/design.md section 13.6); no z correction.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "ccmap/global/patch_keeper.hpp"
#include "layer_images.hpp"

namespace ccmap::tools {

/// One patch of a CCM layer, its cells in slot order (row j, column i: slot j T + i). Paper
/// cells (kind 4) are held as CcmCell with s_xy = 0 (their slopes and coverage are the same).
struct GlobalPatch {
  PatchHeader header{};
  std::vector<CcmCell> cells;
};

/// What reading a patch directory found.
struct PatchDirectoryCounts {
  int files = 0;         ///< *.ccp files of the layer
  int used = 0;          ///< patches read and checked
  int refused = 0;       ///< failed a check (size, magic, version, CRC, key, a cell); skipped
  int unsupported = 0;   ///< a fine layer's patch (Kalman, OMG): skipped
  std::vector<std::string> refused_names;
};

/// Checks one patch's bytes (header, CRC, cells) and decodes it; false for any failure.
[[nodiscard]] bool parse_global_patch(const std::uint8_t* data, std::size_t size, GlobalPatch* out);

/// Reads every patch of `layer` in `directory` (files L<layer>_<tx>_<ty>.ccp). False with a
/// message only when the directory cannot be read; bad files are counted and skipped.
[[nodiscard]] bool read_patch_directory(const std::string& directory, int layer, std::vector<GlobalPatch>* patches,
                                        PatchDirectoryCounts* counts, std::string* error);

struct GlobalMapOptions {
  bool apply_corrections = true;    ///< false: every patch at its writing pose (no stitching)
  StackParams params = default_stack_params(0.04F);  ///< classification (min_weight, tau, max_inclination)
  float normal_variance_threshold = 0.0F;  ///< obstacle threshold (m^2); <= 0: the library's for the width
  std::int64_t max_pixels = 64LL * 1024LL * 1024LL;  ///< a larger extent is refused
};

/// The raster: pixel (ix, iy), index iy * nx + ix, covers [(ix_min + ix) w, (ix_min + ix + 1) w)
/// x [(iy_min + iy) w, ...) of the map frame (row 0 the lowest y). NaN: no cell placed there.
struct GlobalRaster {
  double cell_width_m = 0.0;
  std::int64_t ix_min = 0;
  std::int64_t iy_min = 0;
  int nx = 0;
  int ny = 0;
  std::vector<float> height;      ///< m, map frame
  std::vector<float> slope_x;     ///< dz/dx of the weighted mean plane (map frame)
  std::vector<float> slope_y;     ///< dz/dy
  std::vector<float> normal_var;  ///< m^2
  std::vector<float> weight;      ///< sum of the cells' weights
  std::vector<float> cell_class;  ///< CellClass as a number (0 unknown .. 4 drop-off)
  std::int64_t cells_placed = 0;  ///< observed cells placed
  std::int64_t hazard_pixels = 0; ///< pixels of class obstacle, steep or drop-off
};

/// Places every observed cell of `patches` (one layer: equal cell widths, else refused).
[[nodiscard]] bool assemble_global_map(const std::vector<GlobalPatch>& patches, const GlobalMapOptions& options,
                                       GlobalRaster* raster, std::string* error);

/// The raster's pixels with data as layer rows (tools/io/csv_writer.hpp: the cell_class as the
/// library names it), for the CLI's GeoTIFF writer (write_layer_geotiff: bands height, slope_x,
/// slope_y, normal_var, class) and CSV; extent: the raster's.
[[nodiscard]] std::vector<LayerCellRow> global_map_rows(const GlobalRaster& raster, LayerWindow* extent);

}  // namespace ccmap::tools
