// Plane geometry of the planner queries (planner/footprint.hpp, planner/path_query.hpp,
// planner/costmap.hpp): an oriented rectangle, the overlap of a map cell (an axis-aligned square)
// with it, and the part of the cell inside it. Integrators need not read it.
//
// Frames and units: map-frame metres. Squares and polygons are given relative to the
// rectangle's centre, so that the arithmetic works on small numbers (a cell 100 m from the
// stack origin keeps 7.6 um steps in its centre; offsets from a rectangle a few metres away
// keep ~0.1 um). Float only, no trigonometry (a heading is a direction vector).
#pragma once

#include <cmath>
#include <cstdint>

namespace ccmap::detail {

/// An oriented rectangle: centre, unit heading (the length axis), half extents, and the
/// derived figures the overlap test needs.
struct OrientedRect {
  float cx;              ///< centre, map frame (m)
  float cy;
  float ux;              ///< unit heading: the length axis
  float uy;
  float half_length;     ///< along (ux, uy), m
  float half_width;      ///< along the left normal (-uy, ux), m
  float half_extent_x;   ///< half extents of the axis-aligned bounding box (m)
  float half_extent_y;
  float corner_reach;    ///< |ux| + |uy|: an axis-aligned square of half side h projects onto
                         ///< either rectangle axis with half extent h * corner_reach
};

/// Builds the rectangle centred at (x, y) with its length axis along (heading_x, heading_y)
/// (any length > 0: normalised here) and full extents length_m x width_m. False (nothing
/// written) for non-finite input, a heading shorter than 1e-6 or extents that are not > 0.
[[nodiscard]] bool make_oriented_rect(float x, float y, float heading_x, float heading_y, float length_m,
                                      float width_m, OrientedRect* out) noexcept;

enum class Overlap : std::uint8_t {
  kNone = 0,     ///< no common interior (touching edges count as none)
  kPartial = 1,  ///< some of the square lies outside
  kInside = 2,   ///< the whole square lies inside
};

/// How the axis-aligned square of half side `half`, centred (dx, dy) from the rectangle's
/// centre, overlaps the rectangle: the separating-axis test on the two axes of each. Exact up to
/// float rounding of the projections (~1e-7 relative): a square that only touches the boundary
/// may come out kPartial with a sliver of zero area, or kNone.
[[nodiscard]] inline Overlap square_overlap(const OrientedRect& r, float dx, float dy, float half) noexcept {
  if (std::fabs(dx) >= half + r.half_extent_x || std::fabs(dy) >= half + r.half_extent_y) {
    return Overlap::kNone;
  }
  const float s = std::fabs(dx * r.ux + dy * r.uy);  // along the length axis
  const float t = std::fabs(dy * r.ux - dx * r.uy);  // along the left normal
  const float reach = half * r.corner_reach;
  if (s >= r.half_length + reach || t >= r.half_width + reach) {
    return Overlap::kNone;
  }
  return (s + reach <= r.half_length && t + reach <= r.half_width) ? Overlap::kInside : Overlap::kPartial;
}

/// A convex polygon, vertices counter-clockwise, relative to the rectangle's centre (m).
/// Clipping a square by the rectangle's four sides adds at most one vertex per side (8); the
/// arrays leave room for rounding that makes a nearly degenerate piece locally non-convex.
struct Polygon {
  static constexpr int kMaxVertices = 12;
  float x[kMaxVertices];
  float y[kMaxVertices];
  int count;
};

/// The part of the square (half side `half`, centred (dx, dy) from the rectangle's centre)
/// inside the rectangle, written to *out (Sutherland-Hodgman against the four sides); returns
/// its area (m^2, shoelace formula), 0 when nothing is left.
[[nodiscard]] float clip_square(const OrientedRect& r, float dx, float dy, float half, Polygon* out) noexcept;

}  // namespace ccmap::detail
