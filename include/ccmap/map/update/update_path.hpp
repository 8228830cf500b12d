// The per-frame update path of a stack: chunks of points through the front, then each point to
// one cell. Owned by Stack<Config>; integrators need not read it. One job per file:
//   map/update/front.hpp         validation, transform, range, routing, finest index (vectorised)
//   map/update/kalman_batch.hpp  the Kalman layer's frame batch and its integer gate
//   map/update/layer_walk.hpp    the walk to the first window that holds a point; eq. (2)
//   map/update/gate.hpp          the outlier gate of CCM and OMG points, the held points
//   map/update/line_of_sight.hpp the gate's line-of-sight check
//   map/update/change.hpp        the change rule at the end of a frame
//   map/update/held_pool.hpp     where held points wait
// Data flows one way: point -> front -> (Kalman batch | walk -> gate -> one cell update).
//
// Per chunk, two passes: the points routed to a Kalman finest layer inside its window (81 % of a
// CADRE frame) are summed into their cells' batches (a few integer operations each), the rest
// are listed and walk the layers (CCM and OMG cells, refusals, per-point weights).
//
// The frame budget (StackParams::frame_point_budget, frame_time_budget_us; docs/integration.md,
// "The frame budget"): with a budget the chunks are taken in bit-reversed order, so that a frame
// cut short covers the whole field of view at a lower density; a chunk is processed whole or not
// at all, and the points of chunks not taken are counted (skipped_budget). Without a budget the
// chunks are taken in order.
//
// Single-event upsets (map/detail/integrity.hpp): every cell write keeps the cell's check (the
// CCM and OMG updates through a CheckRun per chunk, the Kalman fusion and the change rule
// through write_cell); the derived constants below are sealed
// (hash_constants) or recomputed each frame from sealed data (fine_window_, walk_); the frame
// records are rewritten at each frame's start, the held slots verified; indices read from
// per-frame scratch (the front's Kalman slot and codes, the pass-2 list) are masked or compared
// unsigned, so that no value of them indexes outside the storage.
//
// No heap, no exceptions; O(points) per frame plus O(cells of the finest layer and of the held
// points' pools).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/map/update/change.hpp"
#include "ccmap/map/update/front.hpp"
#include "ccmap/map/visibility/sight_table.hpp"
#include "ccmap/map/update/gate.hpp"
#include "ccmap/map/update/kalman_batch.hpp"
#include "ccmap/map/update/layer_walk.hpp"
#include "ccmap/platform/platform.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap::detail {

/// Chunk `j` of a frame of `chunks` chunks in the budget's order: the bit-reversed sequence of
/// [0, 2^bits) with the values >= chunks left out (next_budget_chunk walks it).
[[nodiscard]] inline std::uint32_t reverse_bits(std::uint32_t v, std::uint32_t bits) noexcept {
  std::uint32_t r = 0U;
  for (std::uint32_t b = 0U; b < bits; ++b) {
    r = (r << 1U) | ((v >> b) & 1U);
  }
  return r;
}

template <typename Config>
class UpdatePath {
 public:
  using Layers = LayerSet<Config>;
  static constexpr bool kKalman = Config::kFineKind == FineKind::kKalman;
  /// The Config carries the viewshed table: the CCM and OMG cells' highest points of the frame
  /// are kept for its confirmations (SightFeed). Compiled out otherwise: the presets' path runs
  /// no instruction of it.
  static constexpr bool kTops = kConfigEveryLineOfSight<Config>;
  /// The outlier gate, or its null object when the Config compiles it out (gate.hpp).
  using Gate = OutlierGate<Config>;
  using Batch = KalmanBatch<kKalman ? Layers::kFineCellCount : 1U>;
  /// A chunk's run of in-gate CCM points (gate.hpp).
  using Accepts = typename Gate::CcmAccepts;
  /// The gate's per-chunk copy of what judges a CCM point (gate.hpp, ccm_judge).
  using Judge = typename Gate::CcmJudge;

  /// Derives the front (index scale, routing bounds), the gate's constants and the budget.
  /// max_range_sq_m2: the routing table's squared ranges (m^2), per layer. Empties the frame
  /// batches and the held points. kInvalidArgument if the front refuses the width or bounds.
  [[nodiscard]] Status init(const StackParams& params, const float* max_range_sq_m2, const Layers& layers) noexcept {
    const Status status = set_constants(params, max_range_sq_m2, layers);
    gate_.init(params, max_range_sq_m2, layers);
    batch_.clear();
    return status;
  }

  /// The constants of init() alone, nothing else touched (Stack::set_params; the gate's held
  /// points are kept). On a refusal of the front configuration nothing is changed.
  [[nodiscard]] Status set_constants(const StackParams& params, const float* max_range_sq_m2,
                                     const Layers& layers) noexcept {
    FrontConfig front{};
    const Status status = make_front_config(layers.widths[0], max_range_sq_m2, Layers::kLayerCount, &front);
    if (status != Status::kOk) {
      return status;
    }
    front_ = front;
    constant_weight_ = params.noise.weight_mode() == sensor::WeightMode::kConstant;
    gate_.set_constants(params, max_range_sq_m2, layers);
    point_budget_ = params.frame_point_budget;
    time_budget_ns_ = std::uint64_t{params.frame_time_budget_us} * 1000U;
    return Status::kOk;
  }

  [[nodiscard]] const FrontConfig& front() const noexcept { return front_; }
  /// The front's chunk, scratch that no frame reads after its end (finish_frame): lent to the
  /// free-space stage, which runs after the frame (map/visibility/free_space.hpp), so that the
  /// stack carries one chunk, not two.
  [[nodiscard]] FrontChunk& scratch() noexcept { return chunk_; }

  /// Integrity hook (map/detail/integrity.hpp): adds every constant init() derives to the
  /// stack's seal of the update path (Stack::update_seal), verified by every mutating call. A
  /// constant added to init() belongs here too; per-frame copies of sealed data (fine_window_,
  /// walk_) are rewritten at each frame's start instead.
  void hash_constants(StateHasher& h) const noexcept {
    h.add(front_);
    h.add(point_budget_);
    h.add(time_budget_ns_);
    hash_bool_bytes(h, constant_weight_);
    gate_.hash_constants(h);
  }

  /// Folds map-frame points (weights may be nullptr: the noise model weighs them).
  /// sight: the free-space stage's viewshed table to feed with every chunk's lines of sight and
  /// the cells' highest points to keep (map/visibility/sight_table.hpp, SightFeed), or nullptr.
  void run_map(Layers& layers, const StackParams& params, const PointXYZ* points, const float* weights, std::size_t n,
               const FramePose& pose, FrameCounters& frame, const SightFeed* sight = nullptr) noexcept {
    const bool unit_weights = weights == nullptr && constant_weight_;
    set_tops(sight);
    run(layers, params, n, pose, frame, [&](std::size_t begin, std::size_t count, const FineWindow& fine) {
      front_map_chunk(points + begin, count, pose, front_, fine, chunk_);
      const float* chunk_weights = weights != nullptr ? weights + begin : nullptr;
      if (sight != nullptr) {
        sight->table->add_chunk(chunk_, count, nullptr, chunk_weights, pose.anchor);
      }
      return chunk_weights;
    }, unit_weights);
  }

  /// Folds sensor-frame points with the frame's pose (make_frame_pose with a rotation).
  void run_sensor(Layers& layers, const StackParams& params, const PointXYZ* points, std::size_t n,
                  const FramePose& pose, FrameCounters& frame, const SightFeed* sight = nullptr) noexcept {
    set_tops(sight);
    run(layers, params, n, pose, frame, [&](std::size_t begin, std::size_t count, const FineWindow& fine) {
      front_sensor_chunk(points + begin, count, pose, front_, fine, chunk_);
      if (sight != nullptr) {
        sight->table->add_chunk(chunk_, count, points + begin, nullptr, pose.anchor);
      }
      return static_cast<const float*>(nullptr);
    }, constant_weight_);
  }

  /// The Kalman finest layer's sums of the last frame, one record per cell in the layer's
  /// storage order (valid from the end of a frame to the next frame's start: the free-space
  /// stage's confirmations read them); nullptr without a Kalman finest layer.
  [[nodiscard]] const KalmanFrameSum* frame_sums() const noexcept {
    if constexpr (kKalman) {
      return &batch_.sum(0U);
    } else {
      return nullptr;
    }
  }

  /// The gate (its held cells and slots: Stack::held_cells, last_frame_held_cells).
  [[nodiscard]] const Gate& gate() const noexcept { return gate_; }

 private:
  /// Counts of one chunk, kept in registers and added to the frame's counters once.
  struct ChunkCounts {
    std::uint32_t used = 0U, non_finite = 0U, out_of_range = 0U, too_noisy = 0U, bad_weight = 0U, outside = 0U,
                  finer = 0U, occluded = 0U, held = 0U, pool_full = 0U;
  };

  /// The runs of pass 2 of one chunk: consecutive CCM points folded into one cell are a run
  /// (one compare per point, here), which opens that cell's check run (integrity.hpp, CheckRun)
  /// and, with the gate on, the gate's count of in-gate points (held_pool.hpp, AcceptRun); the
  /// OMG cells' check runs open themselves (CheckRun::write). Registers or the call stack.
  struct ChunkRuns {
    CheckRuns<Layers> checks{};
    std::uint32_t ccm_number = 0xFFFFFFFFU;  ///< the CCM cell of the open run (none: no cell has it)
  };

  void set_tops(const SightFeed* sight) noexcept {
    if constexpr (kTops) {
      tops_.ccm = sight != nullptr ? sight->ccm_top : nullptr;
      tops_.fine = sight != nullptr ? sight->fine_top : nullptr;
    } else {
      (void)sight;
    }
  }

  /// One frame: the chunks in order (no budget) or in the budget's order until it is spent,
  /// then the end of the frame. front(begin, count, fine) fills chunk_ and returns the chunk's
  /// weights (or nullptr).
  template <typename Front>
  void run(Layers& layers, const StackParams& params, std::size_t n, const FramePose& pose, FrameCounters& frame,
           Front&& front, bool unit_weights) noexcept {
    begin_frame(layers, pose, frame);
    const bool gate = gate_.on();
    const auto chunks = static_cast<std::uint32_t>((n + kFrontChunkPoints - 1U) / kFrontChunkPoints);
    auto one_chunk = [&](std::uint32_t c) {
      const std::size_t begin = std::size_t{c} * kFrontChunkPoints;
      const std::size_t count = n - begin < kFrontChunkPoints ? n - begin : kFrontChunkPoints;
      const float* weights = front(begin, count, fine_window_);
      if constexpr (Gate::kCompiled) {
        if (gate) {
          back_half<true>(layers, params, weights, count, unit_weights, frame);
          return count;
        }
      }
      back_half<false>(layers, params, weights, count, unit_weights, frame);
      return count;
    };
    if (point_budget_ == 0U && time_budget_ns_ == 0U) {
      for (std::uint32_t c = 0; c < chunks; ++c) {
        (void)one_chunk(c);
      }
    } else {
      std::uint32_t bits = 0U;
      while ((std::uint64_t{1} << bits) < chunks) {
        ++bits;
      }
      const std::uint64_t start = time_budget_ns_ > 0U ? platform::monotonic_ns() : 0U;
      std::size_t done = 0U;
      for (std::uint64_t j = 0; j < (std::uint64_t{1} << bits); ++j) {
        const std::uint32_t c = reverse_bits(static_cast<std::uint32_t>(j), bits);
        if (c >= chunks) {
          continue;
        }
        const std::size_t begin = std::size_t{c} * kFrontChunkPoints;
        const std::size_t count = n - begin < kFrontChunkPoints ? n - begin : kFrontChunkPoints;
        if (point_budget_ > 0U && done + count > point_budget_) {
          break;  // this chunk would exceed the budget: it and the rest are skipped
        }
        if (time_budget_ns_ > 0U && done > 0U && platform::monotonic_ns() - start >= time_budget_ns_) {
          break;
        }
        done += one_chunk(c);
      }
      frame.skipped_budget += static_cast<std::uint32_t>(n - done);
    }
    finish_frame(layers, params, frame);
  }

  /// The start of a frame: the walk's windows, the finest layer's window for the front's Kalman
  /// slots, the Kalman gate's intervals, the gate's camera and the slots of cells that left.
  void begin_frame(const Layers& layers, const FramePose& pose, FrameCounters& frame) noexcept {
    walk_.begin_frame(layers);
    if constexpr (kKalman) {
      const CellIndex min = layers.window_min(0);
      std::int32_t log2 = 0;
      while ((std::int32_t{1} << log2) < Config::kFineSide) {
        ++log2;
      }
      fine_window_ = FineWindow{min, Config::kFineSide, log2};
    } else {
      fine_window_ = FineWindow{CellIndex{0, 0}, 0, 0};
    }
    // The frame records rewritten whole, with or without the gate (integrity: no sum of an
    // earlier frame or an upset between frames survives).
    if (gate_.on()) {
      if constexpr (kKalman) {
        batch_.template begin_frame<true>(layers.fine_storage, gate_.constants(0));
      }
      gate_.begin_frame(layers, pose, frame);
      return;
    }
    if constexpr (kKalman) {
      batch_.template begin_frame<false>(layers.fine_storage, no_gate_);
    }
  }

  /// Back half of one chunk. kGate: the outlier gate is on, chosen once per chunk so that the
  /// paper's update runs no gate instruction.
  template <bool kGate>
  void back_half(Layers& layers, const StackParams& params, const float* weights, std::size_t count,
                 bool unit_weights, FrameCounters& frame) noexcept {
    ChunkCounts c{};
    std::size_t others = 0U;
    if constexpr (kKalman) {
      if (unit_weights) {
        // Pass 1: the Kalman batch entries, the common case, in runs of one cell.
        const GateConstants& gate0 = gate_.constants(0);
        typename Batch::Run run{};
        for (std::size_t i = 0; i < count;) {
          const std::int32_t entry = chunk_.fine_slot[i];
          if (entry < 0) {
            others_[others++] = static_cast<std::uint16_t>(i);
            ++i;
            continue;
          }
          // Integrity: masked to the records (the front writes (slot & mask) or -1; an upset in
          // the chunk between the front and here must not index past them).
          const auto slot = static_cast<std::int32_t>(static_cast<std::uint32_t>(entry) & kFineSlotMask);
          if (slot != run.slot) {
            batch_.start(run, slot);
          }
          const std::size_t next =
              batch_.template add_while_inside<kGate>(run, chunk_.fine_slot, chunk_.height_q14, chunk_.range_key, i, count);
          if (next > i) {
            i = next;
            continue;
          }
          // Entry i is outside its cell's gate (or opens a never-observed cell's interval).
          if constexpr (kGate) {
            if (!batch_.template add<true>(run, chunk_.height_q14[i], chunk_.range_key[i], gate0)) {
              const CellIndex index{chunk_.ix0[i], chunk_.iy0[i]};
              count_outcome(gate_.hold_kalman(static_cast<std::uint32_t>(slot), index, chunk_.height_q14[i],
                                              chunk_.range_key[i]),
                            c);
            }
          }
          ++i;
        }
        batch_.flush(run);
        c.used += run.flushed;
      } else {
        for (std::size_t i = 0; i < count; ++i) {
          others_[others++] = static_cast<std::uint16_t>(i);
        }
      }
    } else {
      for (std::size_t i = 0; i < count; ++i) {
        others_[others++] = static_cast<std::uint16_t>(i);
      }
    }
    // Pass 2: everything else walks the layers. Integrity: entries masked to the chunk; the CCM
    // and OMG writes keep their cells' checks through the chunk's runs (ChunkRuns).
    ChunkRuns runs{};
    Accepts accepts{};
    Judge judge{};
    if constexpr (kGate) {
      judge = gate_.ccm_judge();
    }
    float* ccm_top = nullptr;  // kTops: SightFeed::ccm_top or nullptr (a register)
    if constexpr (kTops) {
      ccm_top = tops_.ccm;
    }
    for (std::size_t j = 0; j < others; ++j) {
      apply<kGate>(layers, params, others_[j] & (kFrontChunkPoints - 1U), weights, unit_weights, c, runs, accepts,
                   judge, ccm_top);
    }
    runs.checks.close(layers);
    if constexpr (kGate) {
      gate_.flush_accepts(accepts);
      c.used += accepts.handed();  // the CCM points folded in, counted by their runs
    }
    frame.used += c.used;
    frame.rejected_non_finite += c.non_finite;
    frame.rejected_out_of_range += c.out_of_range;
    frame.too_noisy += c.too_noisy;
    frame.rejected_weight += c.bad_weight;
    frame.outside_map += c.outside;
    frame.gated_finer += c.finer;
    frame.gated_occluded += c.occluded;
    frame.gated_held += c.held;
    frame.gated_pool_full += c.pool_full;
  }

  /// A point of the Kalman frame batch in cell slot `slot` of the finest layer.
  template <bool kGate>
  void kalman_point(Layers& layers, std::uint32_t slot, std::size_t i, const GateConstants& gate0,
                    ChunkCounts& c) noexcept {
    if constexpr (kKalman) {
      const std::int32_t h = chunk_.height_q14[i];
      const std::int32_t key = chunk_.range_key[i];
      if constexpr (kGate) {
        if (!batch_.template add<true>(slot, h, key, gate0)) {
          const CellIndex index{chunk_.ix0[i], chunk_.iy0[i]};
          count_outcome(gate_.hold_kalman(slot, index, h, key), c);
        } else {
          ++c.used;
        }
      } else {
        (void)batch_.template add<false>(slot, h, key, gate0);  // always inside without the gate
        ++c.used;
      }
    } else {
      (void)layers;
      (void)slot;
      (void)i;
      (void)gate0;
      (void)c;
    }
  }

  /// The gate's verdict on point i of the chunk in CCM cell `number` of `layer`, which
  /// suspect_ccm() named (gate.hpp, judge_suspect_ccm). Out of line: rare, and a member so that
  /// the hot loop passes no addresses of the walk, the chunk or the gate. Called only by
  /// back_half<true>, which exists only when the gate is compiled in (a member of a class
  /// template is instantiated only where it is used).
  [[nodiscard]] __attribute__((noinline)) GateOutcome judge_suspect_ccm(const Layers& layers, int layer,
                                                                        std::uint32_t number, std::size_t i, float x,
                                                                        float y, float w, float weight_limit) noexcept {
    return gate_.judge_suspect_ccm(layers, walk_, layer, number, chunk_, i, x, y, w, weight_limit);
  }

  /// Adds a gate outcome other than kFold to the chunk's counts.
  static void count_outcome(GateOutcome outcome, ChunkCounts& c) noexcept {
    switch (outcome) {
      case GateOutcome::kFiner: ++c.finer; break;
      case GateOutcome::kOccluded: ++c.occluded; break;
      case GateOutcome::kHeld: ++c.held; break;
      case GateOutcome::kPoolFull: ++c.pool_full; break;
      case GateOutcome::kFold: ++c.used; break;  // GCOVR_EXCL_LINE: callers pass the other outcomes only
    }
  }

  /// Every other entry: refusals, weights, the walk, one CCM, Kalman or OMG cell.
  template <bool kGate>
  __attribute__((always_inline)) void apply(Layers& layers, const StackParams& params, std::size_t i, const float* weights, bool unit_weights,
             ChunkCounts& c, ChunkRuns& runs, Accepts& accepts, const Judge& judge,
                                             float* ccm_top) noexcept {  // NOLINT(readability-non-const-parameter): written when kTops (WithEveryLineOfSight configs), unused otherwise
    const std::int32_t code = chunk_.code[i];
    // Unsigned (integrity): a negative code, which the front never writes, is refused with them
    // (uncounted) rather than starting the walk below layer 0.
    if (static_cast<std::uint32_t>(code) >= kFrontNonFinite) {
      c.non_finite += code == std::int32_t{kFrontNonFinite} ? 1U : 0U;
      c.out_of_range += code == std::int32_t{kFrontOutOfRange} ? 1U : 0U;
      c.too_noisy += code == std::int32_t{kFrontTooNoisy} ? 1U : 0U;
      return;
    }
    float weight = 1.0F;  // the constant model's weight: always valid
    if (!unit_weights) {
      weight = weights != nullptr ? weights[i] : params.noise.weight_at_range_sq(chunk_.range_sq[i]);
      if (ccm_check_weight(weight) != Status::kOk) {
        ++c.bad_weight;
        return;
      }
    }
    const std::int32_t ix0 = chunk_.ix0[i];
    const std::int32_t iy0 = chunk_.iy0[i];
    const typename LayerWalk<Config>::Hit hit = walk_.find(code, ix0, iy0);
    if (hit.layer >= Layers::kLayerCount) {
      ++c.outside;
      return;
    }
    if (Layers::is_ccm(hit.layer)) {
      const float x = walk_.relative(hit.layer, ix0, chunk_.fx[i], front_.width);
      const float y = walk_.relative(hit.layer, iy0, chunk_.fy[i], front_.width);
      auto& cell = layers.ccm_storage[hit.number];
      if constexpr (kGate) {
        // The common case, a point inside the gate of a known cell, takes one branch; the
        // rest is out of line (judge_suspect_ccm), so that this loop keeps its registers.
        if (__builtin_expect(Gate::suspect_ccm(judge, cell, chunk_.z[i], hit.layer), 0)) {
          const GateOutcome outcome =
              judge_suspect_ccm(layers, hit.layer, hit.number, i, x, y, weight, params.weight_limit);
          if (outcome != GateOutcome::kFold) {
            count_outcome(outcome, c);
            return;
          }
        }
      }
      // kTops: the height read once, for the run's first point and the update (the presets' path
      // reads it in the update alone, as before: its code stays the same).
      [[maybe_unused]] float z = 0.0F;
      if constexpr (kTops) {
        z = chunk_.z[i];
      }
      if (hit.number != runs.ccm_number) {  // a run of another cell starts
        runs.ccm_number = hit.number;
        runs.checks.ccm.open(layers, cell);
        if constexpr (kGate) {
          gate_.start_run(accepts, hit.number);
        }
        if constexpr (kTops) {
          // The run's first point is the cell's highest of the frame if it is higher than the
          // runs' before (SightFeed: the first point of each run, not every point, for the budget).
          if (ccm_top != nullptr) {
            float& top = ccm_top[hit.number];
            top = std::fmax(top, z);
          }
        }
      }
      if constexpr (kGate) {
        gate_.count_accepted(accepts);  // and in c.used at the chunk's end
      } else {
        ++c.used;
      }
      runs.checks.ccm.write([&](auto& written) {
        ccm_update_unchecked(written, x, y, kTops ? z : chunk_.z[i], weight, params.weight_limit);
      });
      return;
    }
    if constexpr (kKalman) {
      // Kalman gains come from the range variance, not from weights.
      kalman_point<kGate>(layers, hit.number, i, gate_.constants(0), c);
    } else if constexpr (Layers::kHasFine) {
      const float variance = measurement_variance(params, chunk_.range_sq[i]);
      const float z = chunk_.z[i];
      if constexpr (kGate) {
        const GateOutcome outcome =
            gate_.judge_omg(layers, hit.number, CellIndex{ix0, iy0}, z, variance, weight, params.weight_limit);
        if (outcome != GateOutcome::kFold) {
          count_outcome(outcome, c);
          return;
        }
      }
      auto& cell = layers.fine_storage[hit.number];
      runs.checks.fine.write(layers, cell,
                      [&](auto& written) { omg_update_unchecked(written, z, variance, weight, params.weight_limit); });
      if constexpr (kTops) {
        if (tops_.fine != nullptr) {  // (not the presets' fine kind: one point at a time)
          float& top = tops_.fine[hit.number & (Layers::kFineCellCount - 1U)];
          top = std::fmax(top, z);
        }
      }
      ++c.used;
    }
  }

  /// Measurement variance (m^2) of the piece-wise constant layer at squared range r^2 (m^2):
  /// sigma_m(r)^2 from the noise model, at least kalman_min_variance (which also catches NaN).
  [[nodiscard]] static float measurement_variance(const StackParams& params, float range_sq) noexcept {
    const float sigma = params.noise.sigma_at_range_sq(range_sq);
    const float variance = sigma * sigma;
    return variance >= params.kalman_min_variance ? variance : params.kalman_min_variance;
  }

  /// One Kalman batch update of `count` > 0 points with these sums (kalman_batch.hpp, batch_mean).
  static void fuse_sums(KalmanCell& cell, const StackParams& params, std::int64_t sum_height_q14,
                        std::int64_t sum_range_key, std::uint32_t count) noexcept {
    const BatchMean mean = batch_mean(sum_height_q14, sum_range_key, count);
    kalman_update_batch_unchecked(cell, mean.height_m, measurement_variance(params, mean.range_sq_m2), count,
                                  params.kalman_min_variance);
  }

  /// The end of a frame: the Kalman layer's batches, then the change rule for every cell with
  /// held points (slots kept while their verdict is kPending, then sealed). The batches are
  /// emptied by the next frame's begin_frame.
  void finish_frame(Layers& layers, const StackParams& params, FrameCounters& frame) noexcept {
    if constexpr (kKalman) {
      KalmanCell* cells = layers.fine_storage;
      batch_.fuse([&](std::uint32_t slot, const KalmanFrameSum& sum) {
        write_cell(layers, cells[slot], [&](KalmanCell& cell) {
          fuse_sums(cell, params, sum.sum_height_q14, sum.sum_range_key, sum.count);
        });
      });
    }
    gate_.note_frame_slots();
    if constexpr (Gate::kCompiled) {
      if (gate_.on()) {
        apply_change_rule(
            gate_, layers, params, frame, [&](std::uint32_t cell) { return batch_.sum(cell).count; },
            [&]([[maybe_unused]] auto& cell, [[maybe_unused]] const auto& held,
                [[maybe_unused]] std::uint32_t count) {  // only a Kalman layer fuses its held points here
              if constexpr (kKalman) {
                // The held points as one more batch: their mean, the variance at their mean squared range.
                fuse_sums(cell, params, held.sum_height_q14, held.sum_range_key, count);
              }
            });
      }
    }
    // The records are rewritten at the next frame's start (begin_frame).
  }

  // ---- zero-initialised (a static stack lives in .bss); derived at init ----
  FrontConfig front_{};
  FrontChunk chunk_{};
  FineWindow fine_window_{};
  LayerWalk<Config> walk_{};
  Batch batch_{};
  Gate gate_{};                                ///< the outlier gate (a null object if compiled out)
  std::uint16_t others_[kFrontChunkPoints]{};  ///< chunk entries for the walk (pass 2)
  std::uint32_t point_budget_ = 0U;
  std::uint64_t time_budget_ns_ = 0U;
  bool constant_weight_ = false;
  /// kTops: SightFeed::ccm_top and fine_top of the frame, or nullptr (an empty member in the
  /// presets, which fits the padding after constant_weight_: their layout stays as it was).
  struct Tops {
    float* ccm = nullptr;
    float* fine = nullptr;
  };
  struct NoTops {};
  std::conditional_t<kTops, Tops, NoTops> tops_{};
  static constexpr GateConstants no_gate_{0.0F, 0.0F};
  /// Integrity: the front's Kalman slots are masked with this (the finest layer's cells: a power of two).
  static constexpr std::uint32_t kFineSlotMask = static_cast<std::uint32_t>((kKalman ? Layers::kFineCellCount : 1U) - 1U);
};

}  // namespace ccmap::detail
