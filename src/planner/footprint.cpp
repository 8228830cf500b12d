// Non-template parts of the footprint query (planner/footprint.hpp): the verdict and the body's
// rectangle.
#include <cmath>

#include "ccmap/map/classify.hpp"
#include "ccmap/planner/footprint.hpp"

namespace ccmap {

CellClass footprint_class(const FootprintResult& result, float max_unknown_share) noexcept {
  if (result.status != Status::kOk && result.status != Status::kOutsideMap) {
    return CellClass::kUnknown;
  }
  if (is_lethal(result.worst_class)) {
    return result.worst_class;
  }
  // NaN max_unknown_share: every share "exceeds" it (the safe answer).
  // An upset part is never tolerated (map/detail/integrity.hpp, "distrust").
  if (result.worst_class == CellClass::kUnknown || !(result.unknown_share <= max_unknown_share) ||
      result.upset_share > 0.0F) {
    return CellClass::kUnknown;
  }
  return CellClass::kTraversable;
}

namespace detail {

Status make_footprint_rect(const Footprint& f, float finest_width_m, std::uint32_t max_cells,
                           OrientedRect* out) noexcept {
  const float values[] = {f.x, f.y, f.heading_x, f.heading_y, f.length_m, f.width_m};
  for (const float v : values) {
    if (!std::isfinite(v)) {
      return Status::kNonFiniteInput;
    }
  }
  if (check_position(f.x, f.y) != Status::kOk) {
    return Status::kOutOfRange;
  }
  OrientedRect rect{};
  if (!(finest_width_m > 0.0F) || !make_oriented_rect(f.x, f.y, f.heading_x, f.heading_y, f.length_m, f.width_m, &rect)) {
    return Status::kInvalidArgument;
  }
  // Finest-layer cells the bounding box touches, counted in float (a huge footprint gives a
  // huge or infinite count, never an integer overflow).
  const float inv = 1.0F / finest_width_m;
  const float nx = std::floor((rect.cx + rect.half_extent_x) * inv) - std::floor((rect.cx - rect.half_extent_x) * inv) + 1.0F;
  const float ny = std::floor((rect.cy + rect.half_extent_y) * inv) - std::floor((rect.cy - rect.half_extent_y) * inv) + 1.0F;
  if (!(nx * ny <= static_cast<float>(max_cells))) {
    return Status::kOutOfRange;
  }
  *out = rect;
  return Status::kOk;
}

}  // namespace detail
}  // namespace ccmap
