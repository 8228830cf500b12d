// Cost raster for planners: the map as a uint8_t grid in the convention of ROS costmap_2d / Nav2.
//
//   std::uint8_t cost[125 * 125];                                   // the caller's buffer
//   const ccmap::CostmapSpec spec{robot_x, robot_y, 0.04F, 125U, 0.3F};  // 5 m x 5 m at 4 cm, 0.3 m radius
//   ccmap::CostmapStats stats{};
//   if (ccmap::fill_costmap(map, spec, cost, sizeof cost, &stats) == ccmap::Status::kOk) { ...search... }
//
// Layout: pixel (ix, iy) is cost[ix + side * iy] and covers the map-frame square
// [x0 + ix r, x0 + (ix + 1) r) x [y0 + iy r, y0 + (iy + 1) r), x0 = centre_x - side r / 2 (same for
// y), r = resolution_m: row 0 at the lowest y, as in costmap_2d and nav_msgs/OccupancyGrid.
//
// Values (costmap_2d's): 0 free .. 252 cost, 253 inscribed, 254 lethal, 255 unknown. A pixel takes
// the worst of the map's answers over its whole square (each part answered by the finest layer
// that knows it, as Stack::query would: planner/detail/region_walk.hpp), in the order
//   lethal (a part is obstacle, steep or a drop-off) > unknown (a part is not known, or off the map,
//   or distrusted after a single-event upset: map/detail/integrity.hpp) > cost,
// so a pixel is free only if all of it is known and traversable. The cost of a traversable part:
//   cost = min(252, round(252 * max(inclination / max_inclination,
//                                   sqrt(normal_variance / threshold))))
// with the stack's max_inclination and the normal-variance threshold of the layer that classified
// the part (sqrt: the relief 4 sigma_s over the relief the threshold stands for, Section IV-E).
// Traversable parts have both ratios <= 1. With inflation_radius_m > 0, every pixel of cost
// 0 .. 252 whose centre lies within that distance of a lethal pixel's centre becomes 253
// (inscribed); unknown pixels stay 255 (Nav2's inflate_unknown = false). The radius in pixels is
// inflation_radius_m / resolution_m in float; a centre on the circle (within 1e-4 pixel) is inside.
//
// Budget: max_rows > 0 (and below side) fills only the band of max_rows rows about the raster's
// centre (rows (side - max_rows) / 2 onwards), as the frame budget bounds a frame update: the work
// below then scales with max_rows instead of side, and every pixel outside the band is 255
// (unknown, never free) and counted (CostmapStats::unknown, and its rows in rows_skipped).
// Inflation runs inside the band (a lethal pixel outside it, being unknown, inflates nothing).
// docs/performance.md section 14 gives the cost of the largest raster with and without it.
//
// Bounded: side <= kMaxCostmapSide, inflation radius <= kMaxInflationPixels pixels. Work: the
// region walk over the raster's part of the map windows (each map cell there once as a leaf, its
// ancestors pooled where finer layers are unknown), one write per pixel and leaf piece it
// overlaps, and for inflation side^2 (2 R + 1) steps of a sliding count (R the radius in pixels).
// No heap; stack use < 4 KiB.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "ccmap/planner/detail/region.hpp"
#include "ccmap/planner/detail/region_walk.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/map/types.hpp"

namespace ccmap {

inline constexpr std::uint8_t kCostFree = 0U;
inline constexpr std::uint8_t kCostMaxTraversable = 252U;
inline constexpr std::uint8_t kCostInscribed = 253U;
inline constexpr std::uint8_t kCostLethal = 254U;
inline constexpr std::uint8_t kCostUnknown = 255U;
/// Largest raster side (pixels): a 1 MiB buffer (asserted below).
inline constexpr std::uint32_t kMaxCostmapSide = 1024U;
static_assert(std::uint64_t{kMaxCostmapSide} * kMaxCostmapSide == std::uint64_t{1} << 20, "1 MiB of cost bytes");
/// Largest inflation radius, in pixels.
inline constexpr std::int32_t kMaxInflationPixels = 32;

struct CostmapSpec {
  float centre_x = 0.0F;            ///< raster centre, map frame (m)
  float centre_y = 0.0F;
  float resolution_m = 0.0F;        ///< pixel side (m), > 0
  std::uint32_t side = 0U;          ///< pixels per axis, 1 .. kMaxCostmapSide
  float inflation_radius_m = 0.0F;  ///< 0: no inflation; at most kMaxInflationPixels * resolution_m
  /// Row budget: 0 (or side and above) fills every row; else only the central band of max_rows
  /// rows, every other pixel unknown (see the header comment).
  std::uint32_t max_rows = 0U;
};

/// Pixel counts of a filled raster and the map cells read.
struct CostmapStats {
  std::uint32_t free;        ///< cost 0
  std::uint32_t cost;        ///< cost 1 .. 252
  std::uint32_t inscribed;
  std::uint32_t lethal;
  std::uint32_t unknown;
  std::uint32_t cells_visited;
  std::uint32_t rows_skipped;  ///< rows left unknown by the row budget (CostmapSpec::max_rows)
};

/// The cost of a traversable part (formula in the header comment): 0 .. 252.
[[nodiscard]] std::uint8_t traversable_cost(float inclination, float max_inclination, float normal_variance,
                                            float threshold) noexcept;

/// The inflation of fill_costmap for a raster the caller assembled (width x height pixels,
/// row-major, costmap_2d values): every pixel of cost 0 .. 252 whose centre lies within
/// radius_pixels of a lethal pixel's centre becomes 253. Refused (raster untouched):
/// kInvalidArgument (null, width or height 0 or above kMaxCostmapSide, capacity below
/// width x height), kNonFiniteInput, kOutOfRange (radius negative or above kMaxInflationPixels).
[[nodiscard]] Status inflate_costmap(std::uint8_t* cost, std::size_t capacity, std::uint32_t width,
                                     std::uint32_t height, float radius_pixels) noexcept;

namespace detail {

/// Ranks while the raster is filled (max = worst): costs 0 .. 252, then unknown, then lethal.
inline constexpr std::uint8_t kRankUnknown = 253U;
inline constexpr std::uint8_t kRankLethal = 254U;

/// kOk, or the refusal of a spec: kNonFiniteInput; kInvalidArgument (resolution not > 0, side 0
/// or above kMaxCostmapSide, negative radius); kOutOfRange (raster beyond kMaxAbsCoordinateM,
/// radius above kMaxInflationPixels pixels).
[[nodiscard]] Status check_costmap_spec(const CostmapSpec& spec) noexcept;

/// Marks every pixel of cost 0 .. 252 within radius_pixels (0 .. kMaxInflationPixels) of a
/// lethal pixel (pixel centres) as inscribed, in a width x height raster (row-major). Exact disc
/// (integer half-widths per row offset), sliding counts per row, in place.
void inflate_lethal(std::uint32_t width, std::uint32_t height, float radius_pixels, std::uint8_t* cost) noexcept;

/// Converts ranks to costmap values (unknown rank -> 255; lethal and costs keep their value).
void ranks_to_costs(std::size_t pixels, std::uint8_t* cost) noexcept;

/// Counts the pixels of each kind into *stats (cells_visited untouched).
void count_costs(std::size_t pixels, const std::uint8_t* cost, CostmapStats* stats) noexcept;

/// Writes the rank of each piece into the pixels it overlaps (max).
template <typename Config>
class CostmapSink {
 public:
  CostmapSink(const OrientedRect& rect, const QueryView<Config>& view, const CostmapSpec& spec, float x0, float y0,
              std::uint8_t* cost) noexcept
      : rect_(rect), view_(view), spec_(spec), cost_(cost), inv_res_(1.0F / spec.resolution_m),
        offset_x_(rect.cx - x0), offset_y_(rect.cy - y0) {}

  void operator()(const RegionPiece& piece, const RegionAnswer& a) noexcept {
    // The piece is axis aligned (the walk's rectangle has heading (1, 0)): its bounding box.
    float lo_x = piece.dx - piece.half;
    float hi_x = piece.dx + piece.half;
    float lo_y = piece.dy - piece.half;
    float hi_y = piece.dy + piece.half;
    if (piece.polygon != nullptr) {
      lo_x = hi_x = piece.polygon->x[0];
      lo_y = hi_y = piece.polygon->y[0];
      for (int i = 1; i < piece.polygon->count; ++i) {
        lo_x = piece.polygon->x[i] < lo_x ? piece.polygon->x[i] : lo_x;
        hi_x = piece.polygon->x[i] > hi_x ? piece.polygon->x[i] : hi_x;
        lo_y = piece.polygon->y[i] < lo_y ? piece.polygon->y[i] : lo_y;
        hi_y = piece.polygon->y[i] > hi_y ? piece.polygon->y[i] : hi_y;
      }
    }
    const std::uint8_t rank = rank_of(a);
    // Pixels whose interior the piece overlaps; kEdge (1e-3 pixel) absorbs the rounding of a
    // piece edge that lies on a pixel edge.
    constexpr float kEdge = 1.0e-3F;
    const std::int32_t side = static_cast<std::int32_t>(spec_.side);
    const std::int32_t ix0 = clamp(static_cast<std::int32_t>(std::floor((lo_x + offset_x_) * inv_res_ + kEdge)), side);
    const std::int32_t ix1 = clamp(static_cast<std::int32_t>(std::ceil((hi_x + offset_x_) * inv_res_ - kEdge)) - 1, side);
    const std::int32_t iy0 = clamp(static_cast<std::int32_t>(std::floor((lo_y + offset_y_) * inv_res_ + kEdge)), side);
    const std::int32_t iy1 = clamp(static_cast<std::int32_t>(std::ceil((hi_y + offset_y_) * inv_res_ - kEdge)) - 1, side);
    for (std::int32_t iy = iy0; iy <= iy1; ++iy) {
      std::uint8_t* row = cost_ + static_cast<std::size_t>(iy) * spec_.side;
      for (std::int32_t ix = ix0; ix <= ix1; ++ix) {
        row[ix] = row[ix] > rank ? row[ix] : rank;
      }
    }
  }

 private:
  [[nodiscard]] static std::int32_t clamp(std::int32_t i, std::int32_t side) noexcept {
    return i < 0 ? 0 : (i >= side ? side - 1 : i);
  }

  [[nodiscard]] std::uint8_t rank_of(const RegionAnswer& a) const noexcept {
    if (!a.known) {
      return kRankUnknown;
    }
    if (is_lethal(a.cell_class)) {
      return kRankLethal;
    }
    return traversable_cost(a.inclination, view_.params().max_inclination, a.normal_variance,
                            view_.threshold(a.class_layer));
  }

  const OrientedRect& rect_;
  const QueryView<Config>& view_;
  const CostmapSpec& spec_;
  std::uint8_t* cost_;
  float inv_res_;
  float offset_x_;  ///< rectangle centre - raster origin (m)
  float offset_y_;
};

/// The map windows' union bounding box (m): [x0, x1] x [y0, y1].
template <typename Config>
void windows_bounds(const LayerSet<Config>& layers, float* x0, float* y0, float* x1, float* y1) noexcept {
  for (int k = 0; k < LayerSet<Config>::kLayerCount; ++k) {
    const float w = layers.widths[k];
    const std::int32_t half = LayerSet<Config>::side(k) / 2;
    const CellIndex c = layers.centre(k);
    const float lx = static_cast<float>(c.x - half) * w;
    const float ly = static_cast<float>(c.y - half) * w;
    const float hx = static_cast<float>(c.x + half) * w;
    const float hy = static_cast<float>(c.y + half) * w;
    *x0 = k == 0 || lx < *x0 ? lx : *x0;
    *y0 = k == 0 || ly < *y0 ? ly : *y0;
    *x1 = k == 0 || hx > *x1 ? hx : *x1;
    *y1 = k == 0 || hy > *y1 ? hy : *y1;
  }
}

}  // namespace detail

/// Fills cost[0 .. side^2) (see the header comment). Refused (buffer untouched): kNotInitialised,
/// kInvalidArgument (null buffer), kBufferTooSmall (capacity < side^2), and the spec's refusals
/// (detail::check_costmap_spec). stats may be nullptr.
template <typename Config>
[[nodiscard]] Status fill_costmap(const Stack<Config>& stack, const CostmapSpec& spec, std::uint8_t* cost,
                                  std::size_t capacity, CostmapStats* stats) noexcept {
  if (stats != nullptr) {
    *stats = CostmapStats{};
  }
  const Status state = stack.state_status();  // kNotInitialised, or kCorrupt after an upset
  if (state != Status::kOk) {
    return state;
  }
  if (cost == nullptr) {
    return Status::kInvalidArgument;
  }
  const Status status = detail::check_costmap_spec(spec);
  if (status != Status::kOk) {
    return status;
  }
  const std::size_t pixels = static_cast<std::size_t>(spec.side) * spec.side;
  if (capacity < pixels) {
    return Status::kBufferTooSmall;
  }
  const float extent = static_cast<float>(spec.side) * spec.resolution_m;
  const float x0 = spec.centre_x - 0.5F * extent;
  const float y0 = spec.centre_y - 0.5F * extent;
  // The row budget: the band [first_row, first_row + rows) about the centre.
  const std::uint32_t rows = spec.max_rows > 0U && spec.max_rows < spec.side ? spec.max_rows : spec.side;
  const std::uint32_t first_row = (spec.side - rows) / 2U;
  const float band_y0 = y0 + static_cast<float>(first_row) * spec.resolution_m;
  const float band_y1 = rows == spec.side ? y0 + extent : y0 + static_cast<float>(first_row + rows) * spec.resolution_m;
  const detail::QueryView<Config> view = detail::PlannerAccess<Config>::view(stack);
  float wx0 = 0.0F, wy0 = 0.0F, wx1 = 0.0F, wy1 = 0.0F;
  detail::windows_bounds(view.layers(), &wx0, &wy0, &wx1, &wy1);
  // The walk covers the band's part of the windows' bounding box; the rest is off the map.
  const float dx0 = x0 > wx0 ? x0 : wx0;
  const float dy0 = band_y0 > wy0 ? band_y0 : wy0;
  const float dx1 = x0 + extent < wx1 ? x0 + extent : wx1;
  const float dy1 = band_y1 < wy1 ? band_y1 : wy1;
  // Pixels wholly inside the walked domain start as cost 0 (the walk raises them); the others
  // have a part off the map: unknown.
  const float inv = 1.0F / spec.resolution_m;
  const std::int32_t side = static_cast<std::int32_t>(spec.side);
  const bool walk = dx0 < dx1 && dy0 < dy1;
  const float in_x0 = walk ? std::ceil((dx0 - x0) * inv - 1.0e-3F) : 0.0F;
  const float in_x1 = walk ? std::floor((dx1 - x0) * inv + 1.0e-3F) : 0.0F;  // exclusive
  const float in_y0 = walk ? std::ceil((dy0 - y0) * inv - 1.0e-3F) : 0.0F;
  const float in_y1 = walk ? std::floor((dy1 - y0) * inv + 1.0e-3F) : 0.0F;
  for (std::int32_t iy = 0; iy < side; ++iy) {
    const auto fy = static_cast<float>(iy);
    const auto row = static_cast<std::uint32_t>(iy);
    const bool row_in = fy >= in_y0 && fy + 1.0F <= in_y1 && row >= first_row && row < first_row + rows;
    for (std::int32_t ix = 0; ix < side; ++ix) {
      const auto fx = static_cast<float>(ix);
      const bool in = row_in && fx >= in_x0 && fx + 1.0F <= in_x1;
      cost[static_cast<std::size_t>(iy) * spec.side + static_cast<std::size_t>(ix)] = in ? 0U : detail::kRankUnknown;
    }
  }
  std::uint32_t reads = 0U;
  if (walk) {
    detail::OrientedRect rect{};
    if (detail::make_oriented_rect(0.5F * (dx0 + dx1), 0.5F * (dy0 + dy1), 1.0F, 0.0F, dx1 - dx0, dy1 - dy0, &rect)) {
      detail::RegionWalk<Config> region(view);
      detail::CostmapSink<Config> sink(rect, view, spec, x0, y0, cost);
      region.run(rect, sink);
      reads = region.cells_read();
    }
  }
  detail::ranks_to_costs(pixels, cost);
  if (spec.inflation_radius_m > 0.0F) {
    detail::inflate_lethal(spec.side, rows, spec.inflation_radius_m / spec.resolution_m,
                           cost + static_cast<std::size_t>(first_row) * spec.side);
  }
  if (stats != nullptr) {
    detail::count_costs(pixels, cost, stats);
    stats->cells_visited = reads;
    stats->rows_skipped = spec.side - rows;
  }
  return Status::kOk;
}

}  // namespace ccmap
