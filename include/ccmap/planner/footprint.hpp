// Footprint query: what the map says about the ground under a rover body, an oriented rectangle.
//
//   ccmap::Footprint body{x, y, std::cos(yaw), std::sin(yaw), 0.6F, 0.4F};   // heading as a vector
//   const ccmap::FootprintResult r = ccmap::query_footprint(map, body);
//   if (ccmap::footprint_class(r, ccmap::kDefaultMaxUnknownShare) != ccmap::CellClass::kTraversable) ...
//
// Every part of the rectangle is answered by the finest layer that knows it, with pooling, as
// Stack::query would answer each of its points (the answer of a map cell is computed once, not
// per point: planner/detail/region_walk.hpp). The result aggregates those answers over the exact
// area (cells clipped to the rectangle):
//  - worst_class: of the known parts, drop-off before obstacle before steep before traversable;
//    kUnknown when no part is known. A drop-off part (no layer knows it, lines of sight proved
//    the terrain drops there: map/visibility/free_space.hpp) counts as known, at the height
//    bound the rays proved, with no slope. How much unknown area a caller tolerates is its own threshold
//    (footprint_class).
//  - unknown_share: the share of the area no layer knows (or none holds: off the map).
//  - upset_share: the part of unknown_share answered unknown because its cell is distrusted (a
//    single-event upset: map/detail/integrity.hpp, "distrust"). footprint_class() answers
//    kUnknown for any upset area that no lethal part outranks, whatever the tolerated share.
//  - max_step_m: the larger of (a) max - min of the sub-cell height (eq. 10; a constant cell's
//    height) over the known parts, each plane evaluated over its exact part of the rectangle,
//    and (b) the largest relief read from a known part's normal variance, 4 sigma_s: the step
//    that at half coverage of a cell gives that sigma_s^2 (h^2/16, Section IV-E; the convention
//    of the layer thresholds).
//  - max_inclination: the largest inclination (gradient, not degrees) of a known part.
//  - min/max_height_m: the extremes of (a).
//  - the worst cell: the answering cell (layer, global index, centre) of the worst part: the
//    highest class, then the largest normal variance over its layer's threshold (obstacles) or
//    the largest inclination (steep, traversable); the first in walk order on ties.
//  - cells_visited: map cells read (pooling and the roughness filter included): the work done.
//
// Bounded: the rectangle's axis-aligned bounding box may touch at most kMaxFootprintCells cells
// of the finest layer (the cells of coarser layers it touches are fewer, ~4^-k as many); larger
// footprints are refused with kOutOfRange. docs/design.md section 6 gives the worst case of cells
// visited for CADRE; tests/planner/footprint_test.cpp asserts it.
//
// Frames and units: map frame, metres; the heading is a direction vector (the core evaluates
// no trigonometric function; build it with cos/sin of your yaw). No heap; stack use < 4 KiB.
#pragma once

#include <cmath>
#include <cstdint>

#include "ccmap/map/classify.hpp"
#include "ccmap/planner/detail/region.hpp"
#include "ccmap/planner/detail/region_walk.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/map/types.hpp"

namespace ccmap {

/// Largest axis-aligned bounding box of a footprint, in cells of the finest layer it touches:
/// 64 x 64 cells (2.56 m x 2.56 m at 4 cm: a 1 m x 2 m body at any heading fits).
inline constexpr std::uint32_t kMaxFootprintCells = 4096U;
/// Unknown share above which footprint_class() answers kUnknown by default (10 %).
inline constexpr float kDefaultMaxUnknownShare = 0.1F;
/// Relief per sigma_s (m/m): a step of height h covering half a cell leaves sigma_s = h / 4.
inline constexpr float kReliefPerNormalSigma = 4.0F;

/// An oriented rectangle in the map frame.
struct Footprint {
  float x;          ///< centre (m)
  float y;
  float heading_x;  ///< direction of the length axis; any length >= 1e-6 (normalised)
  float heading_y;
  float length_m;   ///< full extent along the heading (m), > 0
  float width_m;    ///< full extent across it (m), > 0
};

/// Answer of a footprint query. On status != kOk everything else is zero / kUnknown / -1.
struct FootprintResult {
  Status status;              ///< kOk; kOutsideMap if no layer holds any part; or the refusal
  CellClass worst_class;      ///< worst class of the known parts; kUnknown if none is known
  float unknown_share;        ///< [0, 1]: share of the area that no layer knows
  float max_step_m;           ///< largest step: height range or relief, see the header comment
  float max_inclination;      ///< largest inclination of a known part (dz/dxy)
  float min_height_m;         ///< lowest sub-cell height over the known parts (m, map frame)
  float max_height_m;         ///< highest
  float area_m2;              ///< area evaluated: length x width up to float slivers
  std::int32_t worst_layer;   ///< answering layer of the worst part; -1 if none is known
  CellIndex worst_index;      ///< its cell (global index in worst_layer)
  float worst_x;              ///< that cell's centre (m)
  float worst_y;
  std::uint32_t cells_visited;  ///< map cells read
  float upset_share;          ///< [0, unknown_share]: share of the area unknown because of an upset
};

/// The footprint's verdict: drop-off, obstacle or steep if any known part is (in that order); else
/// unknown if unknown_share > max_unknown_share, upset_share > 0 or no part is known; else
/// traversable.
/// kUnknown for a result whose status is neither kOk nor kOutsideMap.
[[nodiscard]] CellClass footprint_class(const FootprintResult& result, float max_unknown_share) noexcept;

namespace detail {

[[nodiscard]] inline FootprintResult empty_footprint_result(Status status) noexcept {
  FootprintResult r{};
  r.status = status;
  r.worst_class = CellClass::kUnknown;
  r.worst_layer = -1;
  return r;
}

/// kOk and the rectangle, or the refusal: kNonFiniteInput (NaN/Inf), kInvalidArgument (heading
/// shorter than 1e-6, extents not > 0), kOutOfRange (centre beyond kMaxAbsCoordinateM, or a
/// bounding box touching more than max_cells cells of width finest_width_m).
[[nodiscard]] Status make_footprint_rect(const Footprint& footprint, float finest_width_m, std::uint32_t max_cells,
                                         OrientedRect* out) noexcept;

/// Rank of a known class in the worst-part order (drop-off 4, obstacle 3, steep 2, traversable 1;
/// 0 unknown).
[[nodiscard]] constexpr int hazard_rank(CellClass c) noexcept {
  return c == CellClass::kDropOff
             ? 4
             : (c == CellClass::kObstacle ? 3 : (c == CellClass::kSteep ? 2 : (c == CellClass::kTraversable ? 1 : 0)));
}

/// Aggregates the pieces of a footprint walk into a FootprintResult (see the header comment).
template <typename Config>
class FootprintSink {
 public:
  FootprintSink(const OrientedRect& rect, const QueryView<Config>& view) noexcept : rect_(rect), view_(view) {}

  void operator()(const RegionPiece& piece, const RegionAnswer& a) noexcept {
    area_ += piece.area;
    held_ = held_ || a.layer >= 0;
    if (!a.known) {
      unknown_area_ += piece.area;
      if (a.upset) {
        upset_area_ += piece.area;
      }
      return;
    }
    const float ox = rect_.cx - a.centre_x;
    const float oy = rect_.cy - a.centre_y;
    float lo = 0.0F;
    float hi = 0.0F;
    if (piece.polygon != nullptr) {
      lo = answer_height(a, ox, oy, piece.polygon->x[0], piece.polygon->y[0]);
      hi = lo;
      for (int i = 1; i < piece.polygon->count; ++i) {
        const float h = answer_height(a, ox, oy, piece.polygon->x[i], piece.polygon->y[i]);
        lo = h < lo ? h : lo;
        hi = h > hi ? h : hi;
      }
    } else {
      // A plane over a whole square: its centre height -+ half * (|a| + |b|).
      const float centre = answer_height(a, ox, oy, piece.dx, piece.dy);
      const float reach = piece.half * (std::fabs(a.height_slope_x) + std::fabs(a.height_slope_y));
      lo = centre - reach;
      hi = centre + reach;
    }
    if (!known_) {
      min_height_ = lo;
      max_height_ = hi;
      known_ = true;
    } else {
      min_height_ = lo < min_height_ ? lo : min_height_;
      max_height_ = hi > max_height_ ? hi : max_height_;
    }
    max_normal_variance_ = a.normal_variance > max_normal_variance_ ? a.normal_variance : max_normal_variance_;
    max_inclination_ = a.inclination > max_inclination_ ? a.inclination : max_inclination_;
    const int rank = hazard_rank(a.cell_class);
    if (rank < worst_rank_) {
      return;
    }
    float severity = a.inclination;
    if (a.cell_class == CellClass::kObstacle) {
      const float threshold = view_.threshold(a.class_layer);
      severity = threshold > 0.0F ? a.normal_variance / threshold : a.normal_variance;
    }
    if (rank > worst_rank_ || severity > worst_severity_) {
      worst_rank_ = rank;
      worst_severity_ = severity;
      worst_class_ = a.cell_class;
      worst_layer_ = a.layer;
      worst_index_ = a.index;
      worst_x_ = a.centre_x;
      worst_y_ = a.centre_y;
    }
  }

  [[nodiscard]] FootprintResult result(std::uint32_t cells_visited) const noexcept {
    FootprintResult r = empty_footprint_result(held_ ? Status::kOk : Status::kOutsideMap);
    r.cells_visited = cells_visited;
    r.area_m2 = area_;
    r.unknown_share = area_ > 0.0F ? unknown_area_ / area_ : 1.0F;
    r.unknown_share = r.unknown_share > 1.0F ? 1.0F : r.unknown_share;
    r.upset_share = area_ > 0.0F ? upset_area_ / area_ : 0.0F;
    r.upset_share = r.upset_share > r.unknown_share ? r.unknown_share : r.upset_share;
    if (!known_) {
      return r;
    }
    r.worst_class = worst_class_;
    r.min_height_m = min_height_;
    r.max_height_m = max_height_;
    const float range = max_height_ - min_height_;
    const float relief = kReliefPerNormalSigma * std::sqrt(max_normal_variance_);
    r.max_step_m = relief > range ? relief : range;
    r.max_inclination = max_inclination_;
    r.worst_layer = worst_layer_;
    r.worst_index = worst_index_;
    r.worst_x = worst_x_;
    r.worst_y = worst_y_;
    return r;
  }

 private:
  const OrientedRect& rect_;
  const QueryView<Config>& view_;
  float area_ = 0.0F;
  float unknown_area_ = 0.0F;
  float upset_area_ = 0.0F;
  bool held_ = false;
  bool known_ = false;
  float min_height_ = 0.0F;
  float max_height_ = 0.0F;
  float max_normal_variance_ = 0.0F;
  float max_inclination_ = 0.0F;
  int worst_rank_ = 0;
  float worst_severity_ = -1.0F;
  CellClass worst_class_ = CellClass::kUnknown;
  std::int32_t worst_layer_ = -1;
  CellIndex worst_index_{0, 0};
  float worst_x_ = 0.0F;
  float worst_y_ = 0.0F;
};

/// The footprint query over an already validated rectangle (the path query samples through it).
template <typename Config>
[[nodiscard]] FootprintResult footprint_over(const QueryView<Config>& view, const OrientedRect& rect) noexcept {
  RegionWalk<Config> walk(view);
  FootprintSink<Config> sink(rect, view);
  walk.run(rect, sink);
  return sink.result(walk.cells_read());
}

}  // namespace detail

/// The footprint query (see the header comment). kNotInitialised before init; refusals as
/// detail::make_footprint_rect states.
template <typename Config>
[[nodiscard]] FootprintResult query_footprint(const Stack<Config>& stack, const Footprint& footprint) noexcept {
  const Status state = stack.state_status();  // kNotInitialised, or kCorrupt after an upset
  if (state != Status::kOk) {
    return detail::empty_footprint_result(state);
  }
  detail::OrientedRect rect{};
  const Status status = detail::make_footprint_rect(footprint, stack.layer_cell_width(0), kMaxFootprintCells, &rect);
  if (status != Status::kOk) {
    return detail::empty_footprint_result(status);
  }
  return detail::footprint_over(detail::PlannerAccess<Config>::view(stack), rect);
}

}  // namespace ccmap
