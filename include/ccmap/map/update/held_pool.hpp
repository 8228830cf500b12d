// The points that the outlier gate held back, per cell, until the change rule decides what they
// were (cell/outlier_gate.hpp, change_verdict; docs/design.md, "Outlier gate and change").
// Evidence of a change may take several frames to gather in a sparsely seen cell (a lidar scan
// putting one point per frame into it, a frame handed over in chunks), so a cell's held points
// stay in its slot from frame to frame until the rule decides: at most kMaxHeldFrames frames.
// Part of the update path, not of the cells: never written to snapshots (a load starts with an
// empty pool; a cell whose change was pending then needs change_min_points held points anew).
// Integrators need not read it.
//
// Per cell of the layers a pool serves, one 16-bit tag: during a frame, the number of the
// frame's points the cell took inside its gate (saturating at 32767) while the cell has no slot,
// or the index of its slot. A slot holds the held points' own statistics (for CCM and OMG cells
// a cell of the same kind, built by the same update from an empty cell), the cell's number,
// global index and layer, the points inside and outside its gate since the slot was taken, and
// the frames it has lived. Slots go to cells in the order of their first held point; when all
// kSlots are taken, a held point of a cell without a slot is dropped and counted
// (gated_pool_full), so a change over more cells than that gets in over several frames.
// No heap, no exceptions; O(1) per point; O(cells of the pool's layers + slots) per frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "ccmap/grid/ring_grid.hpp"

namespace ccmap::detail {

/// Slots of the CCM layers' pool by default (Config::kCcmHeldSlots overrides it, map/config.hpp):
/// cells with held points. The CADRE traverse with 1 % of its pixels mismatched (the heaviest
/// case measured, docs/performance.md "Outlier gate: what it costs") takes at most 356.
inline constexpr std::size_t kHeldSlots = 512U;
/// Slots of the finest layer's pool by default (Config::kFineHeldSlots): that traverse takes at
/// most 866 (with 512 it dropped 76,533 held points for want of a slot).
inline constexpr std::size_t kFineHeldSlots = 1024U;
/// A slot whose points have not come to a decision after this many frames is dropped.
inline constexpr std::uint32_t kMaxHeldFrames = 8U;

template <typename Held, std::size_t kCells, std::size_t kSlots>
class HeldPool {
 public:
  static_assert(kCells >= 1U && kCells <= 0xFFFFFFFFU, "cells are numbered in 32 bits");
  static_assert(kSlots >= 1U && kSlots <= 0x7FFFU, "slot indices fit the 15 bits of a tag");

  struct Slot {
    Held held;               ///< statistics of the held points
    CellIndex index;         ///< global index of the cell in its layer
    std::uint32_t cell;      ///< number of the cell (its offset in the layers' storage)
    std::uint32_t accepted;  ///< points inside the cell's gate since the slot was taken
    std::uint32_t count;     ///< points held here
    std::int32_t layer;      ///< stack layer of the cell
    std::uint32_t frames;    ///< frames ended since the slot was taken
  };

  /// Counts a point of cell `cell` (< kCells) inside its gate.
  void accept(std::uint32_t cell) noexcept {
    std::uint16_t& tag = tags_[cell];
    if ((tag & kSlotBit) != 0U) {
      ++slots_[tag & kIndexMask].accepted;
    } else if (tag < kIndexMask) {
      ++tag;
    }
  }

  /// The slot to fold a held point of cell `cell` (< kCells; global index `index` in `layer`)
  /// into, its count already raised; taken on the cell's first held point, with the points
  /// the cell took inside its gate earlier in this frame. nullptr if every slot is taken.
  [[nodiscard]] Slot* hold(std::uint32_t cell, CellIndex index, int layer) noexcept {
    std::uint16_t& tag = tags_[cell];
    if ((tag & kSlotBit) != 0U) {
      Slot& slot = slots_[tag & kIndexMask];
      ++slot.count;
      return &slot;
    }
    if (used_ == kSlots) {
      return nullptr;
    }
    Slot& slot = slots_[used_];
    slot = Slot{Held{}, index, cell, tag, 1U, layer, 0U};
    tag = static_cast<std::uint16_t>(kSlotBit | used_);
    ++used_;
    return &slot;
  }

  /// The end of a frame: keep(slot) for every slot in the order they were taken; a slot is
  /// kept (its frames raised) if keep returns true, freed otherwise. Then every tag is reset
  /// for the next frame (kept slots keep theirs).
  template <typename Keep>
  void end_frame(Keep&& keep) noexcept {
    std::uint32_t kept = 0U;
    for (std::uint32_t i = 0; i < used_; ++i) {
      Slot& slot = slots_[i];
      if (keep(slot)) {
        ++slot.frames;
        slots_[kept++] = slot;
      }
    }
    used_ = kept;
    retag();
  }

  /// Frees every slot for which gone(slot) is true (its cell left its layer's window), in
  /// order, and calls dropped(slot) for each. Between frames only.
  template <typename Gone, typename Dropped>
  void drop_if(Gone&& gone, Dropped&& dropped) noexcept {
    std::uint32_t kept = 0U;
    for (std::uint32_t i = 0; i < used_; ++i) {
      const Slot& slot = slots_[i];
      if (gone(slot)) {
        dropped(slot);
      } else {
        slots_[kept++] = slot;
      }
    }
    if (kept != used_) {
      used_ = kept;
      retag();
    }
  }

  /// Empties the pool (every tag 0, no slot).
  void clear() noexcept {
    used_ = 0U;
    retag();
  }

  [[nodiscard]] std::uint32_t used() const noexcept { return used_; }

 private:
  static constexpr std::uint16_t kSlotBit = 0x8000U;
  static constexpr std::uint16_t kIndexMask = 0x7FFFU;

  void retag() noexcept {
    std::memset(tags_, 0, sizeof tags_);
    for (std::uint32_t i = 0; i < used_; ++i) {
      tags_[slots_[i].cell] = static_cast<std::uint16_t>(kSlotBit | i);
    }
  }

  // ---- zero-initialised: a static stack lives in .bss ----
  std::uint16_t tags_[kCells]{};
  Slot slots_[kSlots]{};
  std::uint32_t used_ = 0U;
};

}  // namespace ccmap::detail
