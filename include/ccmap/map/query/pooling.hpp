// Pooling at query time (paper Section IV-F): a CCM cell's answer is its own statistics merged
// (Chan) with the pool of its four children when they lie inside the next finer layer,
// recursively down to the finest layer. Points are written once, to one layer; coarse cells are
// formed from fine ones only when asked. Integrators need not read it.
//
// Cost: at most 4^(layer) cell reads for a cell of stack layer `layer` (341 for the coarsest
// CADRE layer), independent of map size and point count. Recursion depth <= the layer count.
#pragma once

#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/core/assert.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/detail/layers.hpp"

namespace ccmap::detail {

/// Height and height variance of a piece-wise constant cell.
template <typename FineCell>
[[nodiscard]] float fine_height(const FineCell& cell) noexcept {
  return cell.height;
}
[[nodiscard]] inline float fine_variance(const KalmanCell& cell) noexcept { return cell.variance; }
[[nodiscard]] inline float fine_variance(const OmgCell& cell) noexcept { return omg_variance(cell); }

/// Counts cell reads for callers that report them (the planner queries' cells_visited); the
/// point queries pass NoReadCount, which compiles to nothing.
struct NoReadCount {
  void add(std::uint32_t) noexcept {}
};
struct ReadCount {
  std::uint32_t reads = 0U;
  void add(std::uint32_t n) noexcept { reads += n; }
};

/// The statistics of CCM stack layer `layer`'s cell `index` as a query sees them; the
/// distrusted cell (detail::distrust_mark) if that cell or any cell pooled into it is distrusted
/// (map/detail/integrity.hpp). Preconditions: LayerSet<Config>::is_ccm(layer) and the layer's window contains `index`
/// (so 2 * index fits int32: windows stay within +-2^30); a violation is reported to the assert
/// hook and answered with the empty cell (unknown). `count` is told every cell read.
template <typename Config, typename Count>
[[nodiscard]] typename LayerSet<Config>::CcmCellType pooled(const LayerSet<Config>& layers, float weight_limit,
                                                            int layer, CellIndex index, Count& count) noexcept {
  using Layers = LayerSet<Config>;
  using Cell = typename Layers::CcmCellType;
  CCMAP_ASSERT_OR_RETURN(Layers::is_ccm(layer) && layers.contains(layer, index), Cell{});
  const Cell* own = layers.ccm_grid(layer).cell(index);
  count.add(1U);
  // Integrity: a distrusted cell (an upset changed it, or the scrub reset it) makes the pool
  // distrusted: what it held is lost, and the pool without it could hide a hazard
  // (map/detail/integrity.hpp, "distrust").
  if (own != nullptr && cell_distrusted(layers, *own)) {
    return distrusted_cell<Cell>();
  }
  Cell result = own != nullptr ? *own : Cell{};
  if (layer == 0) {
    return result;
  }
  const int child_layer = layer - 1;
  const CellIndex first{index.x * 2, index.y * 2};
  // Windows are aligned (every window starts on an even index): either all four children lie
  // inside the finer window or none does.
  if (!layers.contains(child_layer, first)) {
    return result;
  }
  Cell children[4] = {};
  bool any = false;
  for (int i = 0; i < 4; ++i) {
    const CellIndex child{first.x + (i & 1), first.y + (i >> 1)};
    if (Layers::is_ccm(child_layer)) {
      children[i] = pooled(layers, weight_limit, child_layer, child, count);
      if (distrust_mark(children[i])) {
        return children[i];  // integrity: a distrusted cell below
      }
    } else {
      if constexpr (Layers::kHasFine) {
        const typename Layers::FineCell& c = layers.fine.cell_unchecked(child);
        count.add(1U);
        if (cell_distrusted(layers, c)) {
          return distrusted_cell<Cell>();  // integrity: a distrusted cell below
        }
        children[i] = ccm_from_constant<Cell>(fine_height(c), fine_variance(c), c.weight, layers.widths[child_layer]);
      }
    }
    any = any || children[i].weight > 0.0F;
  }
  if (!any) {
    return result;
  }
  Cell merged = ccm_pool4(children, layers.widths[child_layer], weight_limit);
  if (result.weight > 0.0F) {
    (void)ccm_merge(merged, result, weight_limit);
  }
  return merged;
}

/// The same without counting (point queries, pooled_cell, export).
template <typename Config>
[[nodiscard]] typename LayerSet<Config>::CcmCellType pooled(const LayerSet<Config>& layers, float weight_limit,
                                                            int layer, CellIndex index) noexcept {
  NoReadCount none;
  return pooled(layers, weight_limit, layer, index, none);
}

}  // namespace ccmap::detail
