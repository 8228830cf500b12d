// The layers of a stack (paper Fig. 2) as one statically sized object: an optional piece-wise
// constant finest layer (Kalman or OMG cells) and the CCM layers, cell widths doubling, every
// window a ring buffer over storage inside this object. Owned by Stack<Config>; the update path,
// pooling and queries read and write cells through it. Integrators need not read it.
//
// Layer numbering: 0 is the finest layer; with a constant finest layer, CCM layer c is stack
// layer c + 1. Cell width of layer k: w_0 * 2^k (exact in float).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/core/assert.hpp"
#include "ccmap/grid/ring_grid.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap::detail {

/// The largest range noise (m) a layer of cell width `width` (m) receives: sigma_m at its
/// routing bound max_range_sq_m2 (m^2; a point reaches a layer only from a range within the
/// bound of the layer it was routed to, which is at most this one's), capped by what the
/// routing admits (a CCM layer's IV-G bound, finest_max_sigma_m for a constant finest layer)
/// where that is smaller or sigma_m is not finite.
[[nodiscard]] inline float layer_max_sigma(const StackParams& params, float max_range_sq_m2, float width,
                                           bool ccm_layer) noexcept {
  const float admitted = ccm_layer ? sensor::max_sigma_for_cell_width(width) : params.finest_max_sigma_m;
  const float sigma = params.noise.sigma_at_range_sq(max_range_sq_m2);
  return sigma <= admitted ? sigma : admitted;
}

template <std::size_t N>
constexpr std::size_t sum_of_squares(const std::array<std::int32_t, N>& sides) noexcept {
  std::size_t total = 0U;
  for (std::size_t i = 0; i < N; ++i) {
    total += static_cast<std::size_t>(sides[i]) * static_cast<std::size_t>(sides[i]);
  }
  return total;
}

template <std::size_t N>
constexpr bool all_valid_sides(const std::array<std::int32_t, N>& sides) noexcept {
  for (std::size_t i = 0; i < N; ++i) {
    // Power of two, >= 4 so that half a side is even: windows then start on even indices
    // and every coarse cell covers exactly 2 x 2 cells of the next finer layer.
    if (!grid::is_power_of_two(sides[i]) || sides[i] < 4) {
      return false;
    }
  }
  return true;
}

/// The cells of a layer that no move has cleared since a mark: the intersection of every window
/// of the layer since then, [min, end) on each axis (empty when min >= end; all zero: empty, so a
/// static stack stays in .bss). A move clears exactly the cells of the old window outside the new
/// one, so a cell is inside the intersection iff it was in the window at the mark and has never
/// left since; a cell that left and re-entered is outside it (it holds only what arrived after
/// its return). Four integers per layer, updated by each move: map exchange (persistence/exchange.hpp)
/// uses it to know which cells still hold what was last sent, without a word per cell.
struct KeptWindow {
  CellIndex min{0, 0};
  CellIndex end{0, 0};

  /// From now on: the window [window_min, window_min + side) on each axis.
  void mark(CellIndex window_min, std::int32_t side) noexcept {
    min = window_min;
    end = CellIndex{window_min.x + side, window_min.y + side};
  }
  /// A move to the window [window_min, window_min + side): keep the intersection.
  void intersect(CellIndex window_min, std::int32_t side) noexcept {
    const CellIndex window_end{window_min.x + side, window_min.y + side};
    min = CellIndex{min.x > window_min.x ? min.x : window_min.x, min.y > window_min.y ? min.y : window_min.y};
    end = CellIndex{end.x < window_end.x ? end.x : window_end.x, end.y < window_end.y ? end.y : window_end.y};
  }
  [[nodiscard]] bool contains(CellIndex index) const noexcept {
    return index.x >= min.x && index.x < end.x && index.y >= min.y && index.y < end.y;
  }
};

template <typename Config>
struct LayerSet {
  static constexpr bool kHasFine = Config::kFineKind != FineKind::kNone;
  static constexpr int kFineLayerCount = kHasFine ? 1 : 0;
  static constexpr int kCcmLayerCount = static_cast<int>(Config::kCcmSides.size());
  static constexpr int kLayerCount = kFineLayerCount + kCcmLayerCount;
  using FineCell = std::conditional_t<Config::kFineKind == FineKind::kOmg, OmgCell, KalmanCell>;
  /// CcmCell (full) or CcmPaperCell, by the Config's kCcmCell (map/config.hpp).
  using CcmCellType = CcmCellOf<kConfigCcmCell<Config>>;

  static_assert(kLayerCount >= 1 && kLayerCount <= kMaxLayers, "1..kMaxLayers layers");
  static_assert(!kHasFine || (grid::is_power_of_two(Config::kFineSide) && Config::kFineSide >= 4),
                "fine side must be a power of two >= 4");
  static_assert(kHasFine || Config::kFineSide == 0, "no fine layer: kFineSide must be 0");
  static_assert(all_valid_sides(Config::kCcmSides), "CCM sides must be powers of two >= 4");

  static constexpr std::size_t kFineCellCount =
      kHasFine ? static_cast<std::size_t>(Config::kFineSide) * static_cast<std::size_t>(Config::kFineSide) : 1U;
  static constexpr std::size_t kCcmCellCount = kCcmLayerCount > 0 ? sum_of_squares(Config::kCcmSides) : 1U;
  static constexpr std::size_t kLayerSlots = static_cast<std::size_t>(kLayerCount);
  static constexpr std::size_t kCcmSlots = kCcmLayerCount > 0 ? static_cast<std::size_t>(kCcmLayerCount) : 1U;

  [[nodiscard]] static constexpr std::int32_t side(int layer) noexcept {
    if (layer < 0 || layer >= kLayerCount) {
      return 0;
    }
    if (kHasFine && layer == 0) {
      return Config::kFineSide;
    }
    return Config::kCcmSides[static_cast<std::size_t>(layer - kFineLayerCount)];
  }
  [[nodiscard]] static constexpr std::size_t capacity(int layer) noexcept {
    return static_cast<std::size_t>(side(layer)) * static_cast<std::size_t>(side(layer));
  }
  [[nodiscard]] static constexpr bool is_ccm(int layer) noexcept {
    return layer >= kFineLayerCount && layer < kLayerCount;
  }

  /// Binds every layer (centred on the origin, all cells empty) with widths w_0 * 2^k.
  /// kInvalidArgument if a grid refuses its width (validate_stack_params prevents it).
  [[nodiscard]] Status init(float finest_width_m) noexcept {
    float width = finest_width_m;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      widths[layer] = width;
      width *= 2.0F;
    }
    const CellIndex origin{0, 0};
    if constexpr (kHasFine) {
      if (fine.init(fine_storage, Config::kFineSide, widths[0], origin) != Status::kOk) {
        return Status::kInvalidArgument;
      }
    }
    std::size_t offset = 0U;
    for (int c = 0; c < kCcmLayerCount; ++c) {
      const std::int32_t s = Config::kCcmSides[static_cast<std::size_t>(c)];
      if (ccm[c].init(ccm_storage + offset, s, widths[c + kFineLayerCount], origin) != Status::kOk) {
        return Status::kInvalidArgument;
      }
      offset += static_cast<std::size_t>(s) * static_cast<std::size_t>(s);
    }
    for (int layer = 0; layer < kLayerCount; ++layer) {
      kept[layer].mark(window_min(layer), side(layer));
    }
    return Status::kOk;
  }

  /// The CCM grid of stack layer `layer`. Precondition: is_ccm(layer); a violation is reported
  /// to the assert hook and answered with the first CCM grid (never a grid outside the set).
  [[nodiscard]] RingGrid<CcmCellType>& ccm_grid(int layer) noexcept {
    CCMAP_ASSERT_OR_RETURN(is_ccm(layer), ccm[0]);  // issue 23: precondition asserted
    return ccm[layer - kFineLayerCount];
  }
  [[nodiscard]] const RingGrid<CcmCellType>& ccm_grid(int layer) const noexcept {
    CCMAP_ASSERT_OR_RETURN(is_ccm(layer), ccm[0]);  // issue 23: precondition asserted
    return ccm[layer - kFineLayerCount];
  }

  /// Global index of (x, y) in `layer` if its window holds it.
  [[nodiscard]] bool locate(int layer, float x, float y, CellIndex* index) const noexcept {
    if (is_ccm(layer)) {
      return ccm_grid(layer).locate(x, y, index);
    }
    if constexpr (kHasFine) {
      return layer == 0 && fine.locate(x, y, index);
    } else {
      return false;
    }
  }

  [[nodiscard]] bool contains(int layer, CellIndex index) const noexcept {
    if (is_ccm(layer)) {
      return ccm_grid(layer).contains(index);
    }
    if constexpr (kHasFine) {
      return layer == 0 && fine.contains(index);
    } else {
      return false;
    }
  }

  /// Window centre of a layer (global cell index); {0, 0} for a bad layer.
  [[nodiscard]] CellIndex centre(int layer) const noexcept {
    if (is_ccm(layer)) {
      return ccm_grid(layer).centre();
    }
    if constexpr (kHasFine) {
      if (layer == 0) {
        return fine.centre();
      }
    }
    return CellIndex{0, 0};
  }

  /// Lowest global index of a layer's window; {0, 0} for a bad layer.
  [[nodiscard]] CellIndex window_min(int layer) const noexcept {
    const CellIndex c = centre(layer);
    return CellIndex{c.x - side(layer) / 2, c.y - side(layer) / 2};
  }

  /// Re-centres layer `layer` on the global index `centre` (and narrows its KeptWindow).
  [[nodiscard]] Status move_layer(int layer, CellIndex new_centre) noexcept {
    Status status = Status::kOk;
    if (is_ccm(layer)) {
      status = ccm_grid(layer).move_to(new_centre);
    } else {
      if constexpr (kHasFine) {
        status = fine.move_to(new_centre);
      } else {
        (void)new_centre;
      }
    }
    if (status == Status::kOk && layer >= 0 && layer < kLayerCount) {
      kept[layer].intersect(window_min(layer), side(layer));
    }
    return status;
  }

  // ---- state (zero-initialised: a static LayerSet lives in .bss) ----
  FineCell fine_storage[kFineCellCount]{};
  CcmCellType ccm_storage[kCcmCellCount]{};
  RingGrid<FineCell> fine{};
  RingGrid<CcmCellType> ccm[kCcmSlots]{};
  float widths[kLayerSlots]{};
  /// Per layer, the cells no move has cleared since the last mark (KeptWindow); marked by init
  /// and by map exchange. Not map state: not in snapshots.
  KeptWindow kept[kLayerSlots]{};
  /// Integrity hook (map/detail/integrity.hpp): one 16-bit check per cell, beside the cells;
  /// every writer of a cell keeps it, readers use a cell only when it agrees. Last member on
  /// purpose: between the cells and the grids it moved the grids' offsets and cost 0.8 M aarch64
  /// instructions per CADRE flight cycle (docs/performance.md, "Single-event upsets").
  CellChecks<kFineCellCount, kCcmCellCount> checks{};
};

}  // namespace ccmap::detail
