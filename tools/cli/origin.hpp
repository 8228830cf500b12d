// Which points of a file the ccmap tool maps, and the local origin it subtracts (in double)
// before the float library sees them. Map-frame coordinates are the file's own (e.g. UTM).
//
// A point is mapped when all three coordinates lie within +-kMaxAbsWorldCoordinateM, within
// +-kMaxAbsCoordinateM (the library's range, cell/ccm_cell.hpp) of the origin on every axis, and
// inside --bounds if given. Others are counted (out of range, outside the bounds), never mapped,
// and never move the origin: it is a median, robust to outliers and to garbage values.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cloud_reader.hpp"

namespace ccmap::tools {

/// Largest |coordinate| (m) the tool takes from a file: beyond it a double has steps coarser
/// than 0.1 um, and cell indices of 0.19 mm cells (the smallest the library accepts) would
/// exceed 2^42. Far beyond any terrain frame (Earth's radius is 6.4e6 m).
inline constexpr double kMaxAbsWorldCoordinateM = 1.0e9;

/// An area limit in map-frame coordinates (--bounds): x_min <= x <= x_max, y_min <= y <= y_max.
struct AreaBounds {
  bool set = false;  ///< false: no limit
  double x_min = 0.0, y_min = 0.0, x_max = 0.0, y_max = 0.0;
  [[nodiscard]] bool contains(double x, double y) const {
    return !set || (x >= x_min && x <= x_max && y >= y_min && y <= y_max);
  }
};

/// The local origin of a mapped sequence: a multiple of the coarsest cell width on each axis,
/// so that every layer's cell grid is the map frame's grid of whole cells.
struct LocalOrigin {
  double xyz[3] = {0.0, 0.0, 0.0};           ///< map-frame position (m)
  std::int64_t cells[3] = {0, 0, 0};         ///< xyz / coarsest cell width (exact integers)
  double coarsest_width = 0.0;               ///< m
};

enum class PointFate : std::uint8_t {
  kMapped,         ///< within range and bounds
  kOutOfRange,     ///< beyond +-kMaxAbsWorldCoordinateM, or beyond the library's range from the origin
  kOutsideBounds,  ///< outside --bounds
};

/// Per-axis median of the points within +-kMaxAbsWorldCoordinateM and inside `bounds` (a coarse
/// first guess), then the per-axis median of those within +-kMaxAbsCoordinateM of the guess on
/// every axis (the guess itself if there is none), rounded to a multiple of `coarsest_width`.
/// False with a one-line reason if no point qualifies or coarsest_width is not positive.
[[nodiscard]] bool robust_origin(const std::vector<const Cloud*>& clouds, const AreaBounds& bounds,
                                 double coarsest_width, LocalOrigin* origin, std::string* error);

/// A file's per-point weight as the library's float: beyond float's range +-inf (NaN stays NaN),
/// which the library refuses and counts as a bad weight; never an out-of-range conversion.
[[nodiscard]] float weight_to_float(double w);

/// What becomes of the point (x, y, z) (map frame, finite) for this origin and bounds.
[[nodiscard]] PointFate classify_point(double x, double y, double z, const LocalOrigin& origin,
                                       const AreaBounds& bounds);

}  // namespace ccmap::tools
