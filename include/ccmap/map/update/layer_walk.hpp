// The layer walk of the update path: from the layer a point is routed to (paper Section IV-G),
// the first layer, that one or coarser, whose window holds the point, and the point's position
// relative to the centre of its cell there (paper eq. 2). Integrators need not read it.
//
// Indices: layer k's cell of a point is index_k = index_0 >> k (floor division by 2^k): widths
// are w_0 * 2^k exactly and 1/w_k = (1/w_0) * 2^-k exactly in float, so floor(q / w_k) =
// floor(floor(q / w_0) / 2^k), the index a query locates. (>> of a negative int32 is an
// arithmetic shift with gcc and clang, the floor division; C++20 makes it standard.)
// Position inside the cell, from the front's finest index and fraction (map/update/front.hpp):
// in finest cells (index_0 mod 2^k) + fraction, whose centre is at 2^(k-1); times w_0, metres.
// Every operand is small (< 2^k + 1), so the position is within 2^-24 of a cell of the truth.
//
// The windows are copied once per frame (they move only between frames). No heap, no
// exceptions; O(layers) per point at most, O(1) for the layer it is routed to.
#pragma once

#include <cstddef>
#include <cstdint>

#include "ccmap/map/detail/layers.hpp"

namespace ccmap::detail {

template <typename Config>
class LayerWalk {
 public:
  using Layers = LayerSet<Config>;
  static constexpr int kLayerCount = Layers::kLayerCount;

  /// Where a point's cell is: its layer (kLayerCount: no window holds it) and the cell's number
  /// in the layer's storage (the fine storage for layer 0 of a stack with a constant finest
  /// layer, else the CCM storage: layers.ccm_storage[number]).
  struct Hit {
    int layer;
    std::uint32_t number;
  };

  /// Per-layer constants of the frame: windows, buffer geometry, storage offsets.
  void begin_frame(const Layers& layers) noexcept {
    std::uint32_t offset = 0U;
    for (int k = 0; k < kLayerCount; ++k) {
      Window& w = windows_[k];
      const CellIndex min = layers.window_min(k);
      const auto side = static_cast<std::uint32_t>(Layers::side(k));
      w.min_x = min.x;
      w.min_y = min.y;
      w.side = side;
      w.mask = side - 1U;
      std::uint32_t log2 = 0U;
      while ((1U << log2) < side) {
        ++log2;
      }
      w.log2_side = log2;
      w.offset = Layers::is_ccm(k) ? offset : 0U;
      if (Layers::is_ccm(k)) {
        offset += side * side;
      }
      w.sub_mask = (1 << k) - 1;
      w.centre = 0.5F * static_cast<float>(1 << k);
    }
  }

  /// The first layer from `from` on whose window holds the point of finest index (ix0, iy0).
  [[nodiscard]] Hit find(int from, std::int32_t ix0, std::int32_t iy0) const noexcept {
    for (int k = from; k < kLayerCount; ++k) {
      const Window& w = windows_[k];
      const auto ix = static_cast<std::uint32_t>(ix0 >> k);
      const auto iy = static_cast<std::uint32_t>(iy0 >> k);
      // Unsigned wrap: inside iff 0 <= index - min < side (|index|, |min| <= 2^30 + 2^14).
      if (ix - static_cast<std::uint32_t>(w.min_x) < w.side && iy - static_cast<std::uint32_t>(w.min_y) < w.side) {
        return Hit{k, w.offset + (((iy & w.mask) << w.log2_side) | (ix & w.mask))};
      }
    }
    return Hit{kLayerCount, 0U};
  }

  /// The same test for one layer: the cell number, or false when its window does not hold it.
  [[nodiscard]] bool holds(int layer, std::int32_t ix0, std::int32_t iy0, std::uint32_t* number) const noexcept {
    const Window& w = windows_[layer];
    const auto ix = static_cast<std::uint32_t>(ix0 >> layer);
    const auto iy = static_cast<std::uint32_t>(iy0 >> layer);
    if (ix - static_cast<std::uint32_t>(w.min_x) < w.side && iy - static_cast<std::uint32_t>(w.min_y) < w.side) {
      *number = w.offset + (((iy & w.mask) << w.log2_side) | (ix & w.mask));
      return true;
    }
    return false;
  }

  /// Position (m) of a point relative to the centre of its layer-`layer` cell along one axis,
  /// from its finest index and fraction (map/update/front.hpp): ((i0 mod 2^k) + f - 2^(k-1)) w_0.
  [[nodiscard]] float relative(int layer, std::int32_t i0, float fraction, float finest_width) const noexcept {
    const Window& w = windows_[layer];
    return (static_cast<float>(i0 & w.sub_mask) + fraction - w.centre) * finest_width;
  }

 private:
  struct Window {
    std::int32_t min_x;
    std::int32_t min_y;
    std::uint32_t side;
    std::uint32_t mask;
    std::uint32_t log2_side;
    std::uint32_t offset;  ///< first cell number of the layer in its storage
    std::int32_t sub_mask;  ///< 2^k - 1: finest cells inside a layer-k cell, minus one
    float centre;           ///< 2^(k-1): the cell centre in finest cells
  };
  Window windows_[Layers::kLayerSlots]{};
};

}  // namespace ccmap::detail
