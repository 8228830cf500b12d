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
// or the index of its slot. The update path hands CCM cells' in-gate points over by runs
// (AcceptRun, below), OMG cells' one by one. A slot holds the held points' own statistics (for
// CCM and OMG cells a cell of the same kind, built by the same update from an empty cell), the
// cell's number, global index and layer, the points inside and outside its gate since the slot
// was taken, and the frames it has lived. Slots go to cells in the order of their first held
// point; when all kSlots are taken, a held point of a cell without a slot is dropped and counted
// (gated_pool_full), so a change over more cells than that gets in over several frames.
// No heap, no exceptions; O(1) per point; O(cells of the pool's layers + slots) per frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "ccmap/grid/ring_grid.hpp"
#include "ccmap/map/detail/integrity.hpp"

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
      ++slots_[tag & kSlotMask].accepted;  // integrity: masked to the slots (a power of two)
    } else if (tag < kIndexMask) {
      ++tag;
    }
  }

  /// Counts `n` points of cell `cell` (< kCells) inside its gate: accept(cell) n times, in
  /// one step (AcceptRun hands a run's points over so).
  void accept(std::uint32_t cell, std::uint32_t n) noexcept {
    std::uint16_t& tag = tags_[cell];
    if ((tag & kSlotBit) != 0U) {
      slots_[tag & kSlotMask].accepted += n;  // integrity: masked to the slots (a power of two)
    } else {
      const std::uint32_t sum = std::uint32_t{tag} + n;
      tag = static_cast<std::uint16_t>(sum < kIndexMask ? sum : kIndexMask);
    }
  }

  /// The slot to fold a held point of cell `cell` (< kCells; global index `index` in `layer`)
  /// into, its count already raised; taken on the cell's first held point, with the points
  /// the cell took inside its gate earlier in this frame. nullptr if every slot is taken.
  [[nodiscard]] Slot* hold(std::uint32_t cell, CellIndex index, int layer) noexcept {
    std::uint16_t& tag = tags_[cell];
    if ((tag & kSlotBit) != 0U) {
      Slot& slot = slots_[tag & kSlotMask];  // integrity: masked to the slots (a power of two)
      ++slot.count;
      return &slot;
    }
    if (used_ >= kSlots) {  // integrity: >=, so that no value of used_ indexes past the slots
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
  /// for the next frame (kept slots keep theirs). Integrity: a slot whose cell number an upset
  /// during the frame put out of range (>= kCells) is freed without keep(); returns how many
  /// (FrameCounters::corrupted_slots), so that keep() may index the cells by slot.cell.
  template <typename Keep>
  [[nodiscard]] std::uint32_t end_frame(Keep&& keep) noexcept {
    std::uint32_t kept = 0U;
    std::uint32_t corrupted = 0U;
    const std::uint32_t used = clamped_used();  // integrity
    for (std::uint32_t i = 0; i < used; ++i) {
      Slot& slot = slots_[i];
      if (slot.cell >= kCells) {  // integrity
        ++corrupted;
        continue;
      }
      if (keep(slot)) {
        ++slot.frames;
        slots_[kept++] = slot;
      }
    }
    used_ = kept;
    retag();
    return corrupted;
  }

  /// Frees every slot for which gone(slot) is true (its cell left its layer's window), in
  /// order, and calls dropped(slot) for each. Between frames only.
  template <typename Gone, typename Dropped>
  void drop_if(Gone&& gone, Dropped&& dropped) noexcept {
    std::uint32_t kept = 0U;
    const std::uint32_t used = clamped_used();  // integrity
    for (std::uint32_t i = 0; i < used; ++i) {
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
    seal();
  }

  // ---- integrity (map/detail/integrity.hpp): slots live from frame to frame ----
  /// Between frames: records a check of every slot (its bytes) and a copy of the slot count.
  void seal() noexcept {
    used_copy_ = used_;
    const std::uint32_t used = clamped_used();
    for (std::uint32_t i = 0; i < used; ++i) {
      seals_[i] = cell_signature(slots_[i]);
    }
  }
  /// At the next frame's start: drops every slot whose bytes no longer match their check or
  /// whose cell number is out of range (all of them if the slot count disagrees with its copy),
  /// then rewrites every tag from the slots (a tag that changed between frames is restored).
  /// Returns the slots dropped (FrameCounters::corrupted_slots; their points are not counted
  /// again: their counts are not trusted).
  [[nodiscard]] std::uint32_t verify_seals() noexcept {
    std::uint32_t dropped = 0U;
    if (used_ != used_copy_ || used_ > kSlots) {
      dropped = used_ <= kSlots ? used_ : (used_copy_ <= kSlots ? used_copy_ : 1U);
      used_ = 0U;
    }
    std::uint32_t kept = 0U;
    for (std::uint32_t i = 0; i < used_; ++i) {
      if (cell_signature(slots_[i]) == seals_[i] && slots_[i].cell < kCells) {
        seals_[kept] = seals_[i];
        slots_[kept++] = slots_[i];
      } else {
        ++dropped;
      }
    }
    used_ = kept;
    used_copy_ = kept;
    retag();
    return dropped;
  }

  [[nodiscard]] std::uint32_t used() const noexcept { return used_; }

 private:
  static constexpr std::uint16_t kSlotBit = 0x8000U;
  static constexpr std::uint16_t kIndexMask = 0x7FFFU;
  /// Integrity: a tag's slot index is masked with this, so that no tag indexes past the slots.
  static constexpr std::uint16_t kSlotMask = static_cast<std::uint16_t>(kSlots - 1U);
  static_assert((kSlots & (kSlots - 1U)) == 0U, "slot indices are masked: kSlots must be a power of two");

  void retag() noexcept {
    std::memset(tags_, 0, sizeof tags_);
    const std::uint32_t used = clamped_used();  // integrity
    for (std::uint32_t i = 0; i < used; ++i) {
      if (slots_[i].cell < kCells) {  // integrity: a corrupted cell number indexes nothing
        tags_[slots_[i].cell] = static_cast<std::uint16_t>(kSlotBit | i);
      }
    }
  }
  /// Integrity: the slot count as an index bound, whatever its bits.
  [[nodiscard]] std::uint32_t clamped_used() const noexcept {
    return used_ <= kSlots ? used_ : static_cast<std::uint32_t>(kSlots);
  }

  // ---- zero-initialised: a static stack lives in .bss ----
  std::uint16_t tags_[kCells]{};
  Slot slots_[kSlots]{};
  std::uint32_t used_ = 0U;
  std::uint32_t used_copy_ = 0U;  ///< integrity: used_ as sealed between frames
  CellCheck seals_[kSlots]{};     ///< integrity: check of each slot's bytes, sealed between frames
};

/// The in-gate points of a run of consecutive points folded into one cell, counted in a
/// register and handed to the pool at once (HeldPool::accept(cell, n)) when a run of another
/// cell starts and at the end of the chunk. The caller says when a run starts (start(); the
/// update path's runs of consecutive points in one CCM cell, map/update/update_path.hpp
/// ChunkRuns, which also open the cells' check runs): consecutive points of a frame mostly fall
/// into the same cell (a CADRE frame's CCM points come in runs of six on average), so a point
/// costs an add instead of a tag's load, test and store. The change rule reads the counts only at the
/// frame's end, and a slot starts with its cell's tag and takes what is handed over after it,
/// so the counts it reads are per-point accept()'s whether a run is handed over before or after
/// its cell's slot is taken; with one exception: when the tag had saturated (32,767 points)
/// before the slot, a run open at that moment counts in full (at most kFrontChunkPoints more).
/// Lives in registers or on the call stack for one chunk, never in the map.
template <typename Pool>
class AcceptRun {
 public:
  /// A run of cell `cell` starts: the last run's points go to its cell.
  void start(Pool& pool, std::uint32_t cell) noexcept {
    flush(pool);
    cell_ = cell;
  }
  /// One more point of the run inside its cell's gate.
  void add() noexcept { ++count_; }
  /// The run's points so far to its cell (the run goes on).
  void flush(Pool& pool) noexcept {
    if (count_ != 0U) {
      pool.accept(cell_, count_);
      handed_ += count_;
      count_ = 0U;
    }
  }
  /// Points handed to the pool so far, all runs: after the last flush, every point add()
  /// counted (the update path's count of CCM points folded in).
  [[nodiscard]] std::uint32_t handed() const noexcept { return handed_; }

 private:
  std::uint32_t cell_ = 0U;
  std::uint32_t count_ = 0U;
  std::uint32_t handed_ = 0U;
};

}  // namespace ccmap::detail
