// The outlier gate of the update path (docs/design.md, "Outlier gate and change"): per point,
// whether it may be folded into its cell; per frame, what becomes of the points it held back.
// Compiled in only when the stack's Config has the gate (kConfigOutlierGate, map/config.hpp):
// a stack without it carries the null object OutlierGate<Config, false> (no storage, no work). Integrators need not read it.
//
// Per CCM or OMG point, in this order: the next finer layer's cell at the point, when it holds
// points, must not have the point outside its gate (dropped, gated_finer: a coarse layer's range
// error judged by more precise ground); for stereo, the line of sight must not pass under known
// ground (dropped, gated_occluded: map/update/line_of_sight.hpp); then the point's own cell's
// gate (cell/outlier_gate.hpp): outside, the point is held in the frame's pool (gated_held, or
// gated_pool_full when no slot is free), inside it is counted for the change rule and folded in
// by the caller. Kalman points are judged by the frame batch in integers
// (map/update/kalman_batch.hpp); those outside are held here. At the end of the frame the change
// rule decides per held cell (map/update/change.hpp).
//
// No heap, no exceptions; O(1) per point (the line of sight: O(layers)); O(slots + cells of the
// pools' layers) per frame.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/cell/outlier_gate.hpp"
#include "ccmap/core/assert.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/map/update/front.hpp"
#include "ccmap/map/update/held_pool.hpp"
#include "ccmap/map/update/layer_walk.hpp"
#include "ccmap/map/update/line_of_sight.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap::detail {

/// What the gate says about a point.
enum class GateOutcome : std::uint8_t {
  kFold = 0,      ///< inside: fold it into its cell
  kFiner = 1,     ///< dropped: outside the finer layer's cell's gate
  kOccluded = 2,  ///< dropped: its line of sight passes under known ground
  kHeld = 3,      ///< held in the pool for the change rule
  kPoolFull = 4,  ///< outside its cell's gate while no slot was free: dropped
};

template <typename Config, bool kCompiled = kConfigOutlierGate<Config>>
class OutlierGate;

/// A Config without the gate (map/config.hpp, kOutlierGate false): no storage, no work, never
/// on. The update path calls it as it calls the gate; what only a gate that is on does (the
/// back half's judging, the change rule) is compiled only where Gate::kCompiled.
template <typename Config>
class OutlierGate<Config, false> {
 public:
  using Layers = LayerSet<Config>;
  static constexpr bool kCompiled = false;
  static constexpr std::size_t kCcmSlots = 0U;
  static constexpr std::size_t kFineSlots = 0U;
  struct CcmJudge {};
  struct CcmAccepts {};
  void init(const StackParams&, const float*, const Layers&) noexcept {}
  void set_constants(const StackParams&, const float*, const Layers&) noexcept {}
  [[nodiscard]] bool on() const noexcept { return false; }
  [[nodiscard]] const GateConstants& constants(int) const noexcept { return kNoGate; }
  void begin_frame(const Layers&, const FramePose&, FrameCounters&) noexcept {}
  [[nodiscard]] CcmJudge ccm_judge() const noexcept { return CcmJudge{}; }
  void flush_accepts(CcmAccepts&) noexcept {}
  void hash_constants(StateHasher&) const noexcept {}
  [[nodiscard]] std::uint32_t pending_ccm_cells() const noexcept { return 0U; }
  [[nodiscard]] std::uint32_t pending_fine_cells() const noexcept { return 0U; }
  [[nodiscard]] std::uint32_t last_frame_slots() const noexcept { return 0U; }
  void note_frame_slots() noexcept {}

 private:
  static constexpr GateConstants kNoGate{0.0F, 0.0F};
};

template <typename Config>
class OutlierGate<Config, true> {
 public:
  using Layers = LayerSet<Config>;
  static constexpr bool kCompiled = true;
  static constexpr bool kKalman = Config::kFineKind == FineKind::kKalman;
  static constexpr bool kCcmPool = Layers::kCcmLayerCount > 0;
  static constexpr bool kFinePool = Layers::kHasFine;
  static constexpr std::size_t kCcmSlots = kConfigCcmHeldSlots<Config> > 0U ? kConfigCcmHeldSlots<Config> : kHeldSlots;
  static constexpr std::size_t kFineSlots =
      kConfigFineHeldSlots<Config> > 0U ? kConfigFineHeldSlots<Config> : kFineHeldSlots;

  /// CCM cells as the layers store them.
  using CcmCellType = typename Layers::CcmCellType;
  using FineCell = typename Layers::FineCell;
  /// Held points of a Kalman cell: the sums of its frame batch, and their spread for the change
  /// rule (Welford, in float, of the heights about the first held one: rare points).
  struct KalmanHeld {
    std::int64_t sum_height_q14;  ///< sum of floor(z * 2^14)
    std::int64_t sum_range_key;   ///< sum of range keys (2^-12 m^2)
    std::int32_t origin_q14;      ///< the first held height, floor(z * 2^14)
    float mean_m;                 ///< mean of the held heights minus the origin (m)
    float spread_sum;             ///< sum of squared deviations from that mean (m^2)
  };
  using FineHeld = std::conditional_t<kKalman, KalmanHeld, OmgCell>;
  using CcmPool = HeldPool<CcmCellType, kCcmPool ? Layers::kCcmCellCount : 1U, kCcmPool ? kCcmSlots : 1U>;
  using FinePool = HeldPool<FineHeld, kFinePool ? Layers::kFineCellCount : 1U, kFinePool ? kFineSlots : 1U>;
  /// The in-gate points of the current run of one CCM cell (held_pool.hpp), kept by the caller
  /// for a chunk (count_accepted) and handed to flush_accepts() at its end.
  using CcmAccepts = AcceptRun<CcmPool>;

  /// Gate constants of every layer (k from the params, V from the routing bounds max_range_sq_m2),
  /// empty pools. The gate is on iff params.outlier_gate_sigma > 0.
  void init(const StackParams& params, const float* max_range_sq_m2, const Layers& layers) noexcept {
    set_constants(params, max_range_sq_m2, layers);
    ccm_held_.clear();
    fine_held_.clear();
    last_frame_slots_ = 0U;
  }

  /// The constants of init() alone, the pools kept (Stack::set_params: held points are judged
  /// under the new constants at the next frame's end).
  void set_constants(const StackParams& params, const float* max_range_sq_m2, const Layers& layers) noexcept {
    on_ = params.outlier_gate_sigma > 0.0F;
    // A cell is known from min_weight on (and never while empty).
    mature_weight_ = params.min_weight > 1.0e-30F ? params.min_weight : 1.0e-30F;
    line_of_sight_ = on_ && params.noise.kind() == sensor::SensorKind::kStereo;
    rule_ = ChangeRule{params.change_min_points, params.change_share};
    for (int layer = 0; layer < Layers::kLayerCount; ++layer) {
      const float sigma = layer_max_sigma(params, max_range_sq_m2[layer], layers.widths[layer], Layers::is_ccm(layer));
      const float floor_variance = gate_floor_variance(sigma, layers.widths[layer], params.max_inclination);
      constants_[layer] = make_gate_constants(params.outlier_gate_sigma, floor_variance);
      sight_margin_[layer] = params.outlier_gate_sigma * std::sqrt(floor_variance);
    }
  }

  [[nodiscard]] bool on() const noexcept { return on_; }
  [[nodiscard]] const GateConstants& constants(int layer) const noexcept { return constants_[layer]; }

  /// Start of a frame: the camera for the line of sight; each pool's slots verified against
  /// their seals (integrity: a slot an upset changed between frames is dropped, counted in
  /// corrupted_slots, and every tag rewritten); then a slot whose cell left its layer's window
  /// (a move since the last frame cleared the cell) is dropped with its points.
  void begin_frame(const Layers& layers, const FramePose& pose, FrameCounters& frame) noexcept {
    sight_.begin_frame(pose);
    finer_ = FinerCache{};
    frame.corrupted_slots += ccm_held_.verify_seals() + fine_held_.verify_seals();  // integrity hook
    auto gone = [&layers](const auto& slot) { return !layers.contains(slot.layer, slot.index); };
    auto dropped = [&frame](const auto& slot) { frame.gated_dropped += slot.count; };
    if constexpr (kCcmPool) {
      ccm_held_.drop_if(gone, dropped);
    }
    if constexpr (kFinePool) {
      fine_held_.drop_if(gone, dropped);
    }
  }

  /// What suspect_ccm() reads, copied by the caller once per chunk (ccm_judge()): a copy whose
  /// address is never taken stays in registers or on the stack, where the CCM cells' float
  /// stores cannot force it to be read again from the gate for every point.
  struct CcmJudge {
    GateConstants constants[Layers::kLayerSlots];
    float mature_weight;
  };
  [[nodiscard]] CcmJudge ccm_judge() const noexcept {
    CcmJudge judge{};
    for (std::size_t layer = 0; layer < Layers::kLayerSlots; ++layer) {
      judge.constants[layer] = constants_[layer];
    }
    judge.mature_weight = mature_weight_;
    return judge;
  }

  /// True if a point at height z (m) of CCM cell `cell` (layer `layer`) is one its cell cannot
  /// admit alone: outside the cell's gate, or the cell not yet known (weight below min_weight:
  /// its statistics are no judge yet); judge_suspect_ccm() decides then. False: the point is
  /// inside the gate of a known cell, which agrees with ground that was itself judged when it
  /// was young; it is folded in with the own gate's 6 float operations alone (docs/design.md,
  /// "Outlier gate and change": what this costs and what it changes), and the caller counts it
  /// (count_accepted) once it has folded it. `judge`: this gate's ccm_judge().
  [[nodiscard]] __attribute__((always_inline)) static bool suspect_ccm(const CcmJudge& judge, const CcmCellType& cell,
                                                                       float z, int layer) noexcept {
    return ccm_outside_gate(cell, z, judge.constants[layer]) || !(cell.weight >= judge.mature_weight);
  }

  /// Judges point i of the chunk, which suspect_ccm() named, in CCM cell `number` of layer
  /// `layer`, with position (x, y) (m) relative to the cell's centre and weight w: the
  /// range-error checks (finer layer, line of sight) first; a point that passes them and lies
  /// outside its cell's gate is held (folded into its slot here). kFold: the caller folds it in.
  [[nodiscard]] GateOutcome judge_suspect_ccm(const Layers& layers, const LayerWalk<Config>& walk, int layer,
                                              std::uint32_t number, const FrontChunk& chunk, std::size_t i, float x,
                                              float y, float w, float weight_limit) noexcept {
    const float z = chunk.z[i];
    const GateOutcome first = range_error(layers, walk, layer, chunk, i);
    if (first != GateOutcome::kFold || !ccm_outside_gate(layers.ccm_storage[number], z, constants_[layer])) {
      return first;
    }
    auto* slot = ccm_held_.hold(number, CellIndex{chunk.ix0[i] >> layer, chunk.iy0[i] >> layer}, layer);
    if (slot == nullptr) {
      return GateOutcome::kPoolFull;
    }
    ccm_update_unchecked(slot->held, x, y, z, w, weight_limit);
    return GateOutcome::kHeld;
  }

  /// Counts a point folded into the cell of the current run (start_run; suspect_ccm() was
  /// false, or judge_suspect_ccm() said kFold), for the change rule's count of in-gate points
  /// (held_pool.hpp, AcceptRun).
  __attribute__((always_inline)) void count_accepted(CcmAccepts& accepts) noexcept { accepts.add(); }
  /// A run of points folded into CCM cell `number` starts (the update path's runs: ChunkRuns):
  /// the last run's in-gate points to the pool.
  void start_run(CcmAccepts& accepts, std::uint32_t number) noexcept { accepts.start(ccm_held_, number); }

  /// The end of a chunk: the last run's in-gate points to the pool.
  void flush_accepts(CcmAccepts& accepts) noexcept { accepts.flush(ccm_held_); }

  /// Judges a point of an OMG finest cell (number `number`, global index `index`) with
  /// measurement variance `variance` and weight w.
  [[nodiscard]] GateOutcome judge_omg(const Layers& layers, std::uint32_t number, CellIndex index, float z,
                                      float variance, float w, float weight_limit) noexcept {
    if constexpr (kFinePool && !kKalman) {
      if (omg_outside_gate(layers.fine_storage[number], z, constants_[0])) {
        auto* slot = fine_held_.hold(number, index, 0);
        if (slot == nullptr) {
          return GateOutcome::kPoolFull;
        }
        omg_update_unchecked(slot->held, z, variance, w, weight_limit);
        return GateOutcome::kHeld;
      }
      fine_held_.accept(number);
    } else {
      (void)layers;
      (void)number;
      (void)index;
      (void)z;
      (void)variance;
      (void)w;
      (void)weight_limit;
    }
    return GateOutcome::kFold;
  }

  /// Holds a Kalman point (Q14 height h, range key) that its cell's frame batch refused.
  [[nodiscard]] GateOutcome hold_kalman(std::uint32_t number, CellIndex index, std::int32_t h,
                                        std::int32_t key) noexcept {
    if constexpr (kKalman) {
      auto* held = fine_held_.hold(number, index, 0);
      if (held == nullptr) {
        return GateOutcome::kPoolFull;
      }
      KalmanHeld& k = held->held;
      if (held->count == 1U) {
        k.origin_q14 = h;
      }
      // |Q14 height| <= 1.04e5 m * 2^14 < 2^31 and keys < 2^31: a slot's sums over
      // kMaxHeldFrames frames of at most 2^32 points each stay below 2^63 / 2^31 * 2^31.
      k.sum_height_q14 += h;
      k.sum_range_key += key;
      const float v = static_cast<float>(std::int64_t{h} - std::int64_t{k.origin_q14}) * kHeightMPerQ14;  // m
      const float delta = v - k.mean_m;
      k.mean_m += delta / static_cast<float>(held->count);
      k.spread_sum += delta * (v - k.mean_m);
      return GateOutcome::kHeld;
    } else {
      (void)number;
      (void)index;
      (void)h;
      (void)key;
      return GateOutcome::kFold;
    }
  }

  /// End of a frame, after the change rule: the pools' slots as they wait for the next frame are
  /// sealed (integrity hook, map/detail/integrity.hpp).
  void seal_pools() noexcept {
    ccm_held_.seal();
    fine_held_.seal();
  }

  /// Integrity hook (map/detail/integrity.hpp): adds every constant init() derives to the
  /// stack's seal of the update path (Stack::update_seal). A constant added to init() belongs
  /// here too.
  void hash_constants(StateHasher& h) const noexcept {
    h.add(constants_);
    h.add(sight_margin_);
    h.add(rule_);
    h.add(mature_weight_);
    hash_bool_bytes(h, on_);
    hash_bool_bytes(h, line_of_sight_);
  }

  /// The change rule at the end of a frame (map/update/change.hpp applies it).
  [[nodiscard]] const ChangeRule& rule() const noexcept { return rule_; }
  [[nodiscard]] CcmPool& ccm_pool() noexcept { return ccm_held_; }
  [[nodiscard]] FinePool& fine_pool() noexcept { return fine_held_; }
  /// Cells whose held points await the change rule (CCM layers; the finest layer).
  [[nodiscard]] std::uint32_t pending_ccm_cells() const noexcept { return ccm_held_.used(); }
  [[nodiscard]] std::uint32_t pending_fine_cells() const noexcept { return fine_held_.used(); }
  /// Slots the last frame had taken at its end, before the change rule (both pools).
  [[nodiscard]] std::uint32_t last_frame_slots() const noexcept { return last_frame_slots_; }
  void note_frame_slots() noexcept { last_frame_slots_ = ccm_held_.used() + fine_held_.used(); }

  /// The two range-error checks of a coarse layer's point: the next finer layer's cell, then
  /// the line of sight.
  [[nodiscard]] GateOutcome range_error(const Layers& layers, const LayerWalk<Config>& walk, int layer,
                                        const FrontChunk& chunk, std::size_t i) noexcept {
    const float z = chunk.z[i];
    if (layer > 0 && layer < Layers::kLayerCount &&
        contradicted_by_finer(layers, walk, layer, chunk.ix0[i], chunk.iy0[i], z)) {
      return GateOutcome::kFiner;
    }
    if (line_of_sight_ && sight_.occluded(layers, walk, layer, chunk.ix0[i], chunk.iy0[i], chunk.fx[i], chunk.fy[i], z,
                                          sight_margin_[layer])) {
      return GateOutcome::kOccluded;
    }
    return GateOutcome::kFold;
  }

  /// True if the next finer layer's cell at the point (finest index ix0, iy0) holds points and z
  /// lies outside that cell's gate with the constants of the point's own layer (its range noise
  /// class). A point routed by its range to a coarse layer while a finer layer knows the ground
  /// there is, when the two disagree, a range error: the finer cell, made of more precise points,
  /// is the better judge. Precondition: layer >= 1 (asserted; false if not). Consecutive points of a stereo row mostly
  /// share the finer cell: its number is kept from the last point (windows do not move within
  /// a frame, so the same index names the same cell).
  [[nodiscard]] bool contradicted_by_finer(const Layers& layers, const LayerWalk<Config>& walk, int layer,
                                           std::int32_t ix0, std::int32_t iy0, float z) noexcept {
    CCMAP_ASSERT_OR_RETURN(layer >= 1, false);  // no finer layer: nothing contradicts
    const int finer = layer - 1;
    const std::int32_t fx = ix0 >> finer;
    const std::int32_t fy = iy0 >> finer;
    if (!finer_.cached || finer != finer_.layer || fx != finer_.x || fy != finer_.y) {
      finer_.cached = true;
      finer_.layer = finer;
      finer_.x = fx;
      finer_.y = fy;
      finer_.holds = walk.holds(finer, ix0, iy0, &finer_.number);
    }
    if (!finer_.holds) {
      return false;
    }
    const GateConstants& gate = constants_[layer];
    if (Layers::is_ccm(finer)) {
      return ccm_outside_gate(layers.ccm_storage[finer_.number], z, gate);
    }
    if constexpr (kKalman) {
      return kalman_outside_gate(layers.fine_storage[finer_.number], z, gate);
    } else if constexpr (kFinePool) {
      return omg_outside_gate(layers.fine_storage[finer_.number], z, gate);
    } else {
      return false;
    }
  }

  /// The finer cell of the last point the finer check judged (all zero: none this frame, and a
  /// static stack's bytes stay zero).
  struct FinerCache {
    bool cached = false;
    int layer = 0;
    std::int32_t x = 0;
    std::int32_t y = 0;
    std::uint32_t number = 0U;
    bool holds = false;
  };

 private:
  // ---- zero-initialised (a static stack lives in .bss); derived at init ----
  CcmPool ccm_held_{};                         ///< held points of CCM cells
  FinePool fine_held_{};                       ///< held points of finest-layer cells
  GateConstants constants_[Layers::kLayerSlots]{};
  float sight_margin_[Layers::kLayerSlots]{};  ///< k sqrt(V) per layer (m)
  LineOfSight<Config> sight_{};
  FinerCache finer_{};
  ChangeRule rule_{};
  std::uint32_t last_frame_slots_ = 0U;
  float mature_weight_ = 0.0F;  ///< the weight from which a cell's own gate judges alone (min_weight)
  bool on_ = false;
  bool line_of_sight_ = false;
};

}  // namespace ccmap::detail
