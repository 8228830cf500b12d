// The change rule at the end of a frame (docs/design.md, "Outlier gate and change"): for every
// cell whose points the outlier gate held back (map/update/gate.hpp), change_verdict
// (cell/outlier_gate.hpp) decides from the counts inside and outside the gate whether the held
// points were outliers (dropped), a second surface in the cell (merged beside what it holds) or
// the cell's new content (re-seed: the cell becomes them); a cell without enough evidence keeps
// its slot for up to kMaxHeldFrames frames. Counted in the frame's counters. Integrators need
// not read it.
//
// Runs after the Kalman frame batch is fused (map/update/kalman_batch.hpp), with that frame's
// counts of points inside each Kalman cell's gate still readable. O(slots + cells of the pools'
// layers) per frame; no heap, no exceptions.
#pragma once

#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/cell/outlier_gate.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/map/update/gate.hpp"
#include "ccmap/map/update/held_pool.hpp"

namespace ccmap::detail {

/// The verdict for a slot at the end of a frame, counted in the frame's counters.
template <typename Slot>
[[nodiscard]] ChangeVerdict counted_verdict(const Slot& slot, bool tight, const ChangeRule& rule,
                                            FrameCounters& frame) noexcept {
  const bool may_wait = slot.frames + 1U < kMaxHeldFrames;
  const ChangeVerdict v = change_verdict(slot.accepted, slot.count, tight, may_wait, rule);
  switch (v) {
    case ChangeVerdict::kDrop:
      frame.gated_dropped += slot.count;
      break;
    case ChangeVerdict::kReseed:
      frame.gated_admitted += slot.count;
      ++frame.reseeded_cells;
      break;
    case ChangeVerdict::kMerge:
      frame.gated_admitted += slot.count;
      ++frame.merged_cells;
      break;
    case ChangeVerdict::kPending:
      break;
  }
  return v;
}

/// Applies the change rule to every held cell of both pools. `accepted_this_frame(cell)`: the
/// frame's points inside the gate of Kalman cell `cell` (its batch count; unused otherwise);
/// `fuse_held(cell, held, count)`: folds a Kalman slot's held sums into the cell as one batch.
/// Integrity (map/detail/integrity.hpp): every cell it writes keeps its check; a slot's layer is
/// clamped to the stack's before it picks gate constants, and slots whose cell number an upset
/// put out of range are dropped by the pool (counted in corrupted_slots); the pools are sealed
/// for the next frame at the end.
template <typename Config, typename AcceptedThisFrame, typename FuseHeld>
void apply_change_rule(OutlierGate<Config>& gate, LayerSet<Config>& layers, const StackParams& params,
                       FrameCounters& frame, AcceptedThisFrame&& accepted_this_frame, FuseHeld&& fuse_held) noexcept {
  using Gate = OutlierGate<Config>;
  using Layers = LayerSet<Config>;
  const ChangeRule& rule = gate.rule();
  // Integrity: a layer an upset changed picks the constants of layer 0, never an index outside them.
  const auto layer_of = [](const auto& slot) { return slot.layer >= 0 && slot.layer < Layers::kLayerCount ? slot.layer : 0; };
  if constexpr (Gate::kCcmPool) {
    frame.corrupted_slots += gate.ccm_pool().end_frame([&](const auto& slot) {
      auto& cell = layers.ccm_storage[slot.cell];
      const bool tight = held_is_tight(slot.held.s_zz, slot.held.weight, gate.constants(layer_of(slot)));
      switch (counted_verdict(slot, tight, rule, frame)) {
        case ChangeVerdict::kReseed:
          // The held points folded into an empty cell, limiter included.
          write_cell(layers, cell, [&](auto& written) { written = slot.held; });
          return false;
        case ChangeVerdict::kMerge:
          // Cannot fail: the limit was validated at init, the held weight is > 0 and finite.
          write_cell(layers, cell, [&](auto& written) { (void)ccm_merge(written, slot.held, params.weight_limit); });
          return false;
        case ChangeVerdict::kPending:
          return true;
        case ChangeVerdict::kDrop:
          break;
      }
      return false;
    });
  }
  if constexpr (Gate::kFinePool) {
    frame.corrupted_slots += gate.fine_pool().end_frame([&](auto& slot) {
      bool tight = false;
      if constexpr (Gate::kKalman) {
        slot.accepted += accepted_this_frame(slot.cell);
        tight = held_is_tight(slot.held.spread_sum, static_cast<float>(slot.count), gate.constants(0));
      } else {
        tight = held_is_tight(slot.held.s, slot.held.weight, gate.constants(0));
      }
      const ChangeVerdict v = counted_verdict(slot, tight, rule, frame);
      if (v == ChangeVerdict::kReseed || v == ChangeVerdict::kMerge) {
        write_cell(layers, layers.fine_storage[slot.cell], [&](auto& cell) {
          if (v == ChangeVerdict::kReseed) {
            cell = typename Gate::FineCell{};
          }
          if constexpr (Gate::kKalman) {
            fuse_held(cell, slot.held, slot.count);
          } else {
            // Cannot fail: the limit was validated at init, the held statistics are finite.
            (void)omg_merge(cell, slot.held, params.weight_limit);
          }
        });
      }
      return v == ChangeVerdict::kPending;
    });
  }
  gate.seal_pools();  // integrity hook: the slots as they wait for the next frame
}

}  // namespace ccmap::detail
