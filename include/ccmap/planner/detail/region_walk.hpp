// The walk behind the planner queries (planner/footprint.hpp, planner/path_query.hpp,
// planner/costmap.hpp): every part of an oriented rectangle, answered by the finest layer that
// knows it, exactly as a point query there would be answered (Stack::query: the finest layer
// whose window holds the point and whose cell is known; a constant-layer answer takes slope,
// normal variance and class from the first CCM layer's pooled cell when that one is known).
// Integrators need not read it.
//
// How: a depth-first walk of the layers' quadtree over the rectangle, from the coarsest layer's
// cells down (an explicit stack, at most kLayerCount deep). A cell that no finer window overlaps is a leaf: the part of it inside the
// rectangle (the whole square, or the square clipped to a convex polygon) is one piece, and its
// answer is the first known cell on the path from the leaf up (layers whose window does not
// hold it skipped). Windows start on even indices, so a cell of layer k is either inside or
// outside the window of any layer j >= k. The answer of each cell on the current path is
// computed at most once and kept (one per layer) while the walk is below it: a CCM cell is
// pooled (detail::pooled) only when a piece below it asks, i.e. where every finer layer is
// unknown, and once per walk visit; a constant-layer piece asks the first CCM layer for its class.
//
// Cost: geometry per visited node (an overlap test, ~15 float operations; a clip, ~100, for a
// leaf on the rectangle's boundary) and cell reads per answer: 1 for a constant cell (+ 9 for
// the roughness filter when the first CCM layer does not know it), the pooling reads of a CCM
// cell (detail::pooled: up to 4^k cells below a cell of stack layer k). cells_read() counts
// every read. Pooling recurses at most kLayerCount deep (detail::pooled).
#pragma once

#include <cmath>
#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/grid/ring_grid.hpp"
#include "ccmap/map/query/answers.hpp"
#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/query/pooling.hpp"
#include "ccmap/planner/detail/region.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/map/types.hpp"

namespace ccmap::detail {

/// The planner queries' access to a stack's query view (Stack's friend).
template <typename Config>
struct PlannerAccess {
  [[nodiscard]] static QueryView<Config> view(const Stack<Config>& stack) noexcept { return stack.view(); }
};

/// The answer of a map cell to every point of a piece inside it (what Stack::query answers
/// there, less the point-dependent height). Compact (60 bytes, asserted below): the walk keeps one
/// per layer.
struct RegionAnswer {
  std::int16_t layer;        ///< answering layer; the finest holding the piece if none knows it; -1 if none holds it
  std::int16_t class_layer;  ///< layer whose cell gave class, slopes and normal variance
  bool known;                ///< false: no layer knows the piece (or none holds it)
  CellClass cell_class;      ///< kUnknown iff !known
  /// With !known: the answering cell (or one pooled into it, or a roughness neighbour) is
  /// distrusted (map/detail/integrity.hpp, "distrust"): no coarser layer was asked.
  bool upset;
  CellIndex index;           ///< answering cell (global index in `layer`)
  float slope_x;             ///< as QueryResult
  float slope_y;
  float inclination;
  float normal_variance;
  // Height at map point (x, y) of the piece: mean_z + height_slope_x * ((x - centre_x) - mean_x)
  //                                              + height_slope_y * ((y - centre_y) - mean_y),
  // eq. (10) for a CCM answer; a constant cell's height (slopes 0) for a constant-layer answer.
  float centre_x;
  float centre_y;
  float mean_x;
  float mean_y;
  float mean_z;
  float height_slope_x;
  float height_slope_y;
};
static_assert(kMaxLayers <= 32767, "layers fit int16");
static_assert(sizeof(RegionAnswer) == 60U, "RegionAnswer is documented as 60 bytes");

/// One part of the rectangle inside one leaf cell.
struct RegionPiece {
  const Polygon* polygon;  ///< the clipped part; nullptr when the whole square is inside
  float dx;                ///< square centre relative to the rectangle's centre (m)
  float dy;
  float half;              ///< half side of the leaf square (m)
  float area;              ///< m^2
};

template <typename Config>
class RegionWalk {
 public:
  using Layers = LayerSet<Config>;
  using View = QueryView<Config>;
  using FineCell = typename Layers::FineCell;
  static constexpr int kLayers = Layers::kLayerCount;

  /// Pieces of less area than kSliverWidthM times their cell's width are float slivers of a
  /// shared edge (a rectangle side on a cell edge leaves a strip a few rounding errors wide,
  /// ~0.1 um for a rectangle a metre across) and are not reported: a strip 1 um wide.
  static constexpr float kSliverWidthM = 1.0e-6F;

  /// min_piece_width_m: pieces of area <= min_piece_width_m * cell width are dropped (0: only
  /// empty pieces; the tests use it to see every piece).
  explicit RegionWalk(const View& view, float min_piece_width_m = kSliverWidthM) noexcept
      : view_(view), layers_(view.layers()), min_piece_width_m_(min_piece_width_m) {}

  /// Calls sink(const RegionPiece&, const RegionAnswer&) for every piece of `rect`, depth first
  /// (each cell's pieces contiguous). The pieces partition the rectangle, up to dropped slivers.
  template <typename Sink>
  void run(const OrientedRect& rect, Sink& sink) noexcept {
    rect_ = rect;
    const int top = kLayers - 1;
    const float w = layers_.widths[top];
    const float inv = 1.0F / w;
    // floor() of finite values within kMaxAbsCoordinateM + a few metres: well inside int32.
    const auto x0 = static_cast<std::int32_t>(std::floor((rect.cx - rect.half_extent_x) * inv));
    const auto x1 = static_cast<std::int32_t>(std::floor((rect.cx + rect.half_extent_x) * inv));
    const auto y0 = static_cast<std::int32_t>(std::floor((rect.cy - rect.half_extent_y) * inv));
    const auto y1 = static_cast<std::int32_t>(std::floor((rect.cy + rect.half_extent_y) * inv));
    for (std::int32_t iy = y0; iy <= y1; ++iy) {
      for (std::int32_t ix = x0; ix <= x1; ++ix) {
        walk_tree(top, CellIndex{ix, iy}, sink);
      }
    }
  }

  /// Cells read so far (constant cells, CCM cells of every pooling, roughness neighbours).
  [[nodiscard]] std::uint32_t cells_read() const noexcept { return reads_.reads; }
  /// Quadtree nodes visited so far (cells tested against the rectangle, leaves included).
  [[nodiscard]] std::uint32_t nodes_visited() const noexcept { return nodes_; }

 private:
  /// Depth-first over the quadtree below top-layer cell `root`, children in the order
  /// (0,0) (1,0) (0,1) (1,1). An explicit stack of at most kLayerCount entries instead of
  /// recursion: the walk's own stack use does not grow with the depth.
  template <typename Sink>
  void walk_tree(int top, CellIndex root, Sink& sink) noexcept {
    struct Node {
      CellIndex cell;
      std::int16_t layer;
      std::int16_t next_child;  ///< -1: not yet entered; then the next child to push (4: done)
      bool inside;             ///< known to lie wholly inside the rectangle
      bool children_inside;
    };
    Node stack[Layers::kLayerSlots];
    int depth = 0;
    stack[0] = Node{root, static_cast<std::int16_t>(top), -1, false, false};
    while (depth >= 0) {
      Node& n = stack[depth];
      if (n.next_child < 0) {
        n.next_child = 0;
        ++nodes_;
        const int k = n.layer;
        const float w = layers_.widths[k];
        const float half = 0.5F * w;
        const float dx = grid::cell_centre(n.cell.x, w) - rect_.cx;
        const float dy = grid::cell_centre(n.cell.y, w) - rect_.cy;
        const Overlap overlap = n.inside ? Overlap::kInside : square_overlap(rect_, dx, dy, half);
        if (overlap == Overlap::kNone) {
          --depth;
          continue;
        }
        path_[k] = n.cell;
        answered_[k] = false;
        if (k == 0 || !finer_window_overlaps(k, n.cell)) {
          leaf(k, dx, dy, half, overlap == Overlap::kPartial, sink);
          --depth;
          continue;
        }
        n.children_inside = overlap == Overlap::kInside;
      }
      // A node of layer k sits at depth top - k and layer-0 nodes are leaves, so depth + 1 <
      // kLayerCount here; the second test only states it to the compiler.
      if (n.next_child == 4 || depth + 1 >= static_cast<int>(Layers::kLayerSlots)) {
        --depth;
        continue;
      }
      const int i = n.next_child++;
      stack[depth + 1] = Node{CellIndex{2 * n.cell.x + (i & 1), 2 * n.cell.y + (i >> 1)},
                              static_cast<std::int16_t>(n.layer - 1), -1, n.children_inside, false};
      ++depth;
    }
  }

  /// One piece: the leaf square (clipped when partial) and its answer. Not inlined into the walk,
  /// so that the clip's and pooling's locals do not enlarge the walk's frame.
  template <typename Sink>
  [[gnu::noinline]] void leaf(int k, float dx, float dy, float half, bool partial, Sink& sink) noexcept {
    const float w = 2.0F * half;
    RegionPiece piece{nullptr, dx, dy, half, w * w};
    if (partial) {
      piece.area = clip_square(rect_, dx, dy, half, &polygon_);
      if (!(piece.area > min_piece_width_m_ * w)) {
        return;
      }
      piece.polygon = &polygon_;
    }
    sink(piece, resolve(k));
  }

  /// True if the window of some layer finer than k overlaps layer-k cell c.
  [[nodiscard]] bool finer_window_overlaps(int k, CellIndex c) const noexcept {
    for (int j = 0; j < k; ++j) {
      const RingGrid<typename Layers::CcmCellType>* ccm = Layers::is_ccm(j) ? &layers_.ccm_grid(j) : nullptr;
      CellIndex lo{};
      CellIndex hi{};
      if (ccm != nullptr) {
        lo = ccm->window_min();
        hi = ccm->window_max();
      } else {
        if constexpr (Layers::kHasFine) {
          lo = layers_.fine.window_min();
          hi = layers_.fine.window_max();
        }
      }
      // Cell c spans [c * 2^(k-j), (c + 1) * 2^(k-j) - 1] in layer j (int64: |c| <= 2^30).
      const std::int64_t scale = std::int64_t{1} << (k - j);
      const std::int64_t cx0 = std::int64_t{c.x} * scale;
      const std::int64_t cy0 = std::int64_t{c.y} * scale;
      if (cx0 <= hi.x && cx0 + scale - 1 >= lo.x && cy0 <= hi.y && cy0 + scale - 1 >= lo.y) {
        return true;
      }
    }
    return false;
  }

  /// The answer of the leaf at layer k: the first cell on its path up that is known or, as
  /// Stack::query, an unobserved drop-off (map/visibility/free_space.hpp); else the unknown answer
  /// of the finest layer holding it (layer -1: none does). A distrusted cell on the way ends the
  /// search with its upset answer, as Stack::query.
  [[nodiscard]] const RegionAnswer& resolve(int k) noexcept {
    const RegionAnswer* unknown = nullptr;
    for (int j = k; j < kLayers; ++j) {
      if (!layers_.contains(j, path_[j])) {
        continue;
      }
      const RegionAnswer& a = answer(j);
      if (a.known || a.upset) {
        return a;
      }
      if (view_.unobserved_drop(j, path_[j]) && drop_below_is_empty(j)) {
        reads_.add(1U);
        drop_ = unknown_answer(j);
        const QueryResult q = view_.drop_answer(j, path_[j]);
        drop_.known = true;
        drop_.cell_class = CellClass::kDropOff;
        drop_.index = path_[j];
        drop_.centre_x = grid::cell_centre(path_[j].x, layers_.widths[j]);
        drop_.centre_y = grid::cell_centre(path_[j].y, layers_.widths[j]);
        drop_.mean_z = q.height_m;  // the upper bound: the terrain lies at or below it
        return drop_;
      }
      unknown = unknown == nullptr ? &a : unknown;
    }
    if (unknown == nullptr) {
      outside_ = unknown_answer(-1);
      unknown = &outside_;
    }
    return *unknown;
  }

  /// True if no finer layer holds a point below path_[j] (the leaf's own layer: nothing finer;
  /// a coarser CCM cell: its pooled weight is 0), as Stack::query requires of a drop-off answer.
  [[nodiscard]] bool drop_below_is_empty(int j) noexcept {
    if (j == 0 || !Layers::is_ccm(j) || !layers_.contains(j - 1, CellIndex{2 * path_[j].x, 2 * path_[j].y})) {
      return true;  // nothing finer holds this cell's children
    }
    return !(pooled(layers_, view_.params().weight_limit, j, path_[j], reads_).weight > 0.0F);
  }

  [[nodiscard]] static RegionAnswer unknown_answer(int layer) noexcept {
    RegionAnswer a{};
    a.known = false;
    a.upset = false;
    a.layer = static_cast<std::int16_t>(layer);
    a.class_layer = static_cast<std::int16_t>(layer);
    a.cell_class = CellClass::kUnknown;
    return a;
  }

  /// The answer of path_[j] (inside layer j's window), computed once per visit of that cell.
  /// The kept answer is returned inline; the computation is a call of its own (its register
  /// saves then stay off the kept answer's path).
  const RegionAnswer& answer(int j) noexcept {
    if (answered_[j]) {
      return answers_[j];
    }
    return compute_answer(j);
  }

  [[gnu::noinline]] const RegionAnswer& compute_answer(int j) noexcept {
    answered_[j] = true;
    RegionAnswer& a = answers_[j];
    a = unknown_answer(j);
    const CellIndex c = path_[j];
    a.index = c;
    a.centre_x = grid::cell_centre(c.x, layers_.widths[j]);
    a.centre_y = grid::cell_centre(c.y, layers_.widths[j]);
    if (Layers::is_ccm(j)) {
      const typename Layers::CcmCellType cell = pooled(layers_, view_.params().weight_limit, j, c, reads_);
      if (distrust_mark(cell)) {
        a.upset = true;  // integrity: a distrusted cell in the pool
        return a;
      }
      const typename View::CcmAnswer ccm = view_.ccm_answer(j, cell);
      if (ccm.cell_class == CellClass::kUnknown) {
        return a;
      }
      a.known = true;
      a.cell_class = ccm.cell_class;
      a.slope_x = ccm.surface.slope_x;
      a.slope_y = ccm.surface.slope_y;
      a.inclination = ccm_inclination(ccm.surface);
      a.normal_variance = ccm.surface.normal_variance;
      a.mean_x = cell.mean_x;
      a.mean_y = cell.mean_y;
      a.mean_z = cell.mean_z;
      a.height_slope_x = ccm.surface.slope_x;
      a.height_slope_y = ccm.surface.slope_y;
      return a;
    }
    if constexpr (Layers::kHasFine) {
      const FineCell& cell = layers_.fine.cell_unchecked(c);
      reads_.add(1U);
      // Integrity: a distrusted cell is upset. Its check is read only when it would answer (with
      // CCM layers, a cell that looks unknown is checked by the first CCM layer's pooling, which
      // the walk asks next: the piece is upset there), so an unknown cell costs no signature.
      if (distrust_mark(cell)) {
        a.upset = true;
        return a;
      }
      if (!view_.fine_known(cell)) {
        if constexpr (Layers::kCcmLayerCount == 0) {
          a.upset = !cell_intact(layers_, cell);
        }
        return a;
      }
      if (!cell_intact(layers_, cell)) {
        a.upset = true;
        return a;
      }
      a.known = true;
      a.mean_z = cell.height;
      a.normal_variance = fine_variance(cell);
      // Hazards are a CCM matter: the first CCM layer's cell there, when it knows it.
      constexpr int first_ccm = Layers::kFineLayerCount;
      if (Layers::kCcmLayerCount > 0 && layers_.contains(first_ccm, path_[first_ccm])) {
        const RegionAnswer& ccm = answer(first_ccm);
        if (ccm.upset) {
          a.known = false;  // hazards are a CCM matter: its class is lost
          a.upset = true;
          a.mean_z = 0.0F;
          a.normal_variance = 0.0F;
          return a;
        }
        if (ccm.known) {
          a.class_layer = static_cast<std::int16_t>(first_ccm);
          a.cell_class = ccm.cell_class;
          a.slope_x = ccm.slope_x;
          a.slope_y = ccm.slope_y;
          a.inclination = ccm.inclination;
          a.normal_variance = ccm.normal_variance;
          return a;
        }
      }
      reads_.add(9U);  // the cell and its 8 neighbours
      a.cell_class = view_.roughness_class(c);
      if (a.cell_class == CellClass::kUnknown) {
        a.known = false;  // a distrusted neighbour (QueryView::roughness_class)
        a.upset = true;
      }
    }
    return a;
  }

  const View& view_;
  const Layers& layers_;
  float min_piece_width_m_;
  OrientedRect rect_{};
  CellIndex path_[Layers::kLayerSlots]{};
  bool answered_[Layers::kLayerSlots]{};
  RegionAnswer answers_[Layers::kLayerSlots]{};
  RegionAnswer outside_{};  ///< the answer of a piece no layer holds
  RegionAnswer drop_{};     ///< the answer of a piece no layer knows but a drop-off holds
  Polygon polygon_{};
  ReadCount reads_{};
  std::uint32_t nodes_ = 0U;
};

/// Height of an answer at the point (dx, dy) relative to the rectangle centre (rect_cx, rect_cy).
[[nodiscard]] inline float answer_height(const RegionAnswer& a, float offset_x, float offset_y, float dx,
                                         float dy) noexcept {
  // offset = rectangle centre - answering cell centre: (x - centre) = dx + offset.
  return a.mean_z + a.height_slope_x * ((dx + offset_x) - a.mean_x) + a.height_slope_y * ((dy + offset_y) - a.mean_y);
}

}  // namespace ccmap::detail
