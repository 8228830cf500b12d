// Per-layer CSV export of a map: one row per observed cell (weight > 0), map-frame coordinates
// in double (absolute world coordinates such as UTM keep their sub-millimetre digits).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ccmap::tools {

/// The exact header line of a layer CSV (without the newline).
inline constexpr const char* kLayerCsvHeader =
    "layer,ix,iy,cx,cy,res,weight,height,slope_x,slope_y,normal_var,elev_var,class";

/// One exported cell, map frame (origin added back), metres / m^2.
struct LayerCellRow {
  int layer = 0;
  std::int64_t ix = 0;       ///< map-frame global cell index: cell covers [ix*res, (ix+1)*res)
  std::int64_t iy = 0;
  double cx = 0.0;           ///< cell centre, map frame (m)
  double cy = 0.0;
  double res = 0.0;          ///< cell width (m)
  double weight = 0.0;
  double height = 0.0;       ///< height at the cell centre, map frame (m)
  double slope_x = 0.0;      ///< a = dz/dx; 0 for piece-wise constant cells
  double slope_y = 0.0;      ///< b = dz/dy
  double normal_var = 0.0;   ///< surface-normal variance (m^2); constant cells: their variance
  double elev_var = 0.0;     ///< elevation variance (m^2)
  std::string cell_class;    ///< unknown, traversable, obstacle, steep
};

/// Writes the header and one line per row. False with a message on an I/O error.
[[nodiscard]] bool write_layer_csv(const std::string& path, const std::vector<LayerCellRow>& rows,
                                   std::string* error);

/// Reads a file written by write_layer_csv (for tests and scripts). False with a message if the
/// header differs or a line is malformed.
[[nodiscard]] bool read_layer_csv(const std::string& path, std::vector<LayerCellRow>* rows, std::string* error);

}  // namespace ccmap::tools
