// The per-frame update path of a stack: the integer front of every point (map/update/front.hpp),
// the back half that walks the layers and updates one cell, and the per-frame batches of the
// piece-wise constant Kalman layer. Owned by Stack<Config>; integrators need not read it.
//
// Data flows one way: point -> front (validate, transform, range, route, index) -> the routed
// layer or the first coarser one whose window holds the point -> one cell update.
// No heap, no exceptions; O(points) per frame plus O(touched Kalman cells).
//
// With the outlier gate on (StackParams::outlier_gate_sigma > 0; docs/design.md, "Outlier gate
// and change"), a point outside its cell's gate is held back (CCM and OMG cells: in the frame's
// HeldPool, map/update/held_pool.hpp; Kalman cells: in their frame batch) and the end of the
// frame drops, merges or re-seeds per cell (change_verdict, cell/outlier_gate.hpp).
//
// Cost (docs/performance.md): under QEMU user mode every float instruction is a soft-float
// helper call, so the back half forms a CCM cell's relative position in fixed point (one
// conversion per axis), the Kalman batch takes no float operation per point (its gate is an
// integer compare against a reference set once per cell and frame) and the CCM and OMG gates
// are 6 float operations without division.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/cell/outlier_gate.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/update/front.hpp"
#include "ccmap/map/update/held_pool.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap::detail {

/// Position relative to a cell centre, from a Q18 coordinate and the cell's index: the exact
/// integer (q + 1/2) * 2^22 - (i + 1/2) * w * 2^40 in Q40 (w * 2^40 is an exact integer for every
/// float width of 2^-17 m or more, so for every width the stack accepts), converted once to float: one rounding (relative
/// 2^-24), against three for x - (i + 0.5) * w in float. The + 1/2 Q18 unit centres the floor of
/// the Q18 conversion (unbiased; |error| <= 1.9 um).
[[nodiscard]] inline float relative_to_centre(std::int64_t q18, std::int32_t index, std::int64_t width_q40) noexcept {
  constexpr std::int64_t kHalfQ18InQ40 = std::int64_t{1} << 21;
  // |q18| < 2^35 -> |q40| < 2^57; |index * width_q40| <= 1e5 m * 2^40 < 2^57: no overflow.
  const std::int64_t point_q40 = q18 * (std::int64_t{1} << 22) + kHalfQ18InQ40;
  const std::int64_t centre_q40 = static_cast<std::int64_t>(index) * width_q40 + width_q40 / 2;
  const std::int64_t relative = point_q40 - centre_q40;
  return static_cast<float>(relative) * 9.09494702e-13F;  // 2^-40
}

template <typename Config>
class UpdatePath {
 public:
  using Layers = LayerSet<Config>;

  /// Derives the front (index scale, routing bounds in fixed point), the cell widths in Q40, the
  /// weighting mode and the outlier gate of every layer. max_range_sq_m2: the routing table's
  /// squared ranges (m^2), per layer. Empties the frame batches and the held points.
  [[nodiscard]] Status init(const StackParams& params, const float* max_range_sq_m2, const Layers& layers) noexcept {
    const Status status = make_front_config(layers.widths[0], max_range_sq_m2, Layers::kLayerCount, &front_);
    for (int layer = 0; layer < Layers::kLayerCount; ++layer) {
      // Exact: a float width >= 2^-17 m times 2^40 is an integer below 2^47 (validated widths).
      width_q40_[layer] = floor_to_int64(layers.widths[layer] * 1099511627776.0F);
    }
    constant_weight_ = params.noise.weight_mode() == sensor::WeightMode::kConstant;
    stereo_ = params.noise.kind() == sensor::SensorKind::kStereo && params.noise.validate() == Status::kOk;
    stereo_k_ = stereo_ ? params.noise.stereo_sigma_per_range_sq() : 0.0F;
    gate_on_ = params.outlier_gate_sigma > 0.0F;
    rule_ = ChangeRule{params.change_min_points, params.change_share};
    line_of_sight_ = gate_on_ && params.noise.kind() == sensor::SensorKind::kStereo;
    for (int layer = 0; layer < Layers::kLayerCount; ++layer) {
      const float sigma = layer_max_sigma(params, max_range_sq_m2[layer], layers.widths[layer], layer);
      const float floor_variance = gate_floor_variance(sigma, layers.widths[layer], params.max_inclination);
      gate_[layer] = make_gate_constants(params.outlier_gate_sigma, floor_variance);
      sight_margin_[layer] = params.outlier_gate_sigma * std::sqrt(floor_variance);
    }
    if constexpr (kKalman) {
      fine_touched_count_ = 0U;
      for (FineFrameSum& sum : fine_sums_) {
        sum = FineFrameSum{};
      }
    }
    ccm_held_.clear();
    fine_held_.clear();
    return status;
  }

  /// The largest range noise (m) layer `layer` (cell width `width`) receives: sigma_m at its
  /// routing bound max_range_sq_m2 (m^2; a point reaches a layer only from a range within the
  /// bound of the layer it was routed to, which is at most this one's), capped by what the
  /// routing admits (a CCM layer's IV-G bound, finest_max_sigma_m for a constant finest layer)
  /// where that is smaller or sigma_m is not finite.
  [[nodiscard]] static float layer_max_sigma(const StackParams& params, float max_range_sq_m2, float width,
                                             int layer) noexcept {
    const float admitted = Layers::is_ccm(layer) ? sensor::max_sigma_for_cell_width(width) : params.finest_max_sigma_m;
    const float sigma = params.noise.sigma_at_range_sq(max_range_sq_m2);
    return sigma <= admitted ? sigma : admitted;
  }

  /// Folds map-frame points (weights may be nullptr: the noise model weighs them).
  void run_map(Layers& layers, const StackParams& params, const PointXYZ* points, const float* weights, std::size_t n,
               const FramePose& pose, FrameCounters& frame) noexcept {
    begin_frame(layers, pose, frame);
    const bool unit_weights = weights == nullptr && constant_weight_;
    for (std::size_t begin = 0; begin < n; begin += kFrontChunkPoints) {
      const std::size_t count = n - begin < kFrontChunkPoints ? n - begin : kFrontChunkPoints;
      front_map_chunk(points + begin, count, pose, front_, chunk_);
      const float* chunk_weights = weights != nullptr ? weights + begin : nullptr;
      if (gate_on_) {
        back_half<true>(layers, params, points + begin, chunk_weights, count, unit_weights, frame);
      } else {
        back_half<false>(layers, params, points + begin, chunk_weights, count, unit_weights, frame);
      }
    }
    finish_frame(layers, params, frame);
  }

  /// Folds sensor-frame points with the frame's fixed-point pose (make_frame_pose with a rotation).
  void run_sensor(Layers& layers, const StackParams& params, const PointXYZ* points, std::size_t n,
                  const FramePose& pose, FrameCounters& frame) noexcept {
    begin_frame(layers, pose, frame);
    for (std::size_t begin = 0; begin < n; begin += kFrontChunkPoints) {
      const std::size_t count = n - begin < kFrontChunkPoints ? n - begin : kFrontChunkPoints;
      front_sensor_chunk(points + begin, count, pose, front_, chunk_);
      if (gate_on_) {
        back_half<true>(layers, params, nullptr, nullptr, count, constant_weight_, frame);
      } else {
        back_half<false>(layers, params, nullptr, nullptr, count, constant_weight_, frame);
      }
    }
    finish_frame(layers, params, frame);
  }

  [[nodiscard]] const FrontConfig& front() const noexcept { return front_; }
  /// Cells whose held points await the change rule (CCM layers; the finest layer).
  [[nodiscard]] std::uint32_t pending_ccm_cells() const noexcept { return ccm_held_.used(); }
  [[nodiscard]] std::uint32_t pending_fine_cells() const noexcept { return fine_held_.used(); }
  /// Slots the last frame had taken at its end, before the change rule (both pools).
  [[nodiscard]] std::uint32_t last_frame_slots() const noexcept { return last_frame_slots_; }

  /// Integrity hook (map/detail/integrity.hpp): adds every constant init() derives to the
  /// stack's state seal. A constant added to init() belongs here too.
  void hash_constants(StateHasher& h) const noexcept {
    h.add(front_);
    h.add(width_q40_);
    h.add(gate_);
    h.add(rule_);
    h.add(sight_margin_);
    const unsigned char* flags[] = {reinterpret_cast<const unsigned char*>(&gate_on_),
                                    reinterpret_cast<const unsigned char*>(&line_of_sight_),
                                    reinterpret_cast<const unsigned char*>(&constant_weight_),
                                    reinterpret_cast<const unsigned char*>(&stereo_)};
    const unsigned char bytes[4] = {*flags[0], *flags[1], *flags[2], *flags[3]};  // read as bytes, not as bool
    h.add(bytes);
    h.add(stereo_k_);
  }

 private:
  static constexpr bool kKalman = Config::kFineKind == FineKind::kKalman;
  static constexpr bool kCcmPool = Layers::kCcmLayerCount > 0;
  static constexpr bool kFinePool = Layers::kHasFine;

  /// CCM cells as the layers store them.
  using CcmCellType = std::remove_all_extents_t<decltype(Layers::ccm_storage)>;
  using FineCell = typename Layers::FineCell;
  /// Held points of a Kalman cell: the sums of its frame batch, and their spread for the change
  /// rule (Welford, in float, of the heights about the first held one: rare points, not the hot
  /// path).
  struct KalmanHeld {
    std::int64_t sum_height_q14;  ///< sum of floor(z * 2^14)
    std::uint64_t sum_range_key;  ///< sum of routing keys (squared ranges, 2^-12 m^2)
    std::int32_t origin_q14;      ///< the first held height, floor(z * 2^14)
    float mean_m;                 ///< mean of the held heights minus the origin (m)
    float spread_sum;             ///< sum of squared deviations from that mean (m^2)
  };
  using FineHeld = std::conditional_t<kKalman, KalmanHeld, OmgCell>;

  static constexpr std::size_t kFineBatchSlots = kKalman ? Layers::kFineCellCount : 1U;
  /// Integrity: touched-list entries and positions are masked with this (a power of two).
  static constexpr std::uint32_t kTouchedMask = static_cast<std::uint32_t>(kFineBatchSlots - 1U);
  static_assert((kFineBatchSlots & (kFineBatchSlots - 1U)) == 0U, "the touched list is masked");
  /// Integrity: the touched count as a loop bound, whatever its bits.
  [[nodiscard]] std::uint32_t touched_count() const noexcept {
    return fine_touched_count_ <= kFineBatchSlots ? fine_touched_count_ : static_cast<std::uint32_t>(kFineBatchSlots);
  }
  static constexpr std::size_t kCcmPoolCells = kCcmPool ? Layers::kCcmCellCount : 1U;
  static constexpr std::size_t kCcmPoolSlots = kCcmPool ? kHeldSlots : 1U;
  static constexpr std::size_t kFinePoolCells = kFinePool ? Layers::kFineCellCount : 1U;
  static constexpr std::size_t kFinePoolSlots = kFinePool ? kHeldSlots : 1U;
  using CcmPool = HeldPool<CcmCellType, kCcmPoolCells, kCcmPoolSlots>;
  using FinePool = HeldPool<FineHeld, kFinePoolCells, kFinePoolSlots>;

  /// Counts of one chunk, kept in registers and added to the frame's counters once.
  struct ChunkCounts {
    std::uint32_t used = 0U, non_finite = 0U, out_of_range = 0U, too_noisy = 0U, bad_weight = 0U, outside = 0U,
                  finer = 0U, occluded = 0U, held = 0U, pool_full = 0U;
  };

  /// Back half of one chunk. `map_points` is the caller's map-frame chunk (the CCM and OMG
  /// updates take the float z from it), or nullptr for sensor-frame input (z from the Q18 position).
  /// kGate: the outlier gate is on (gate_on_), chosen once per chunk so that the paper's update
  /// runs the code it ran before the gate.
  template <bool kGate>
  // cppcheck-suppress unusedPrivateFunction ; called as back_half<true> / back_half<false>
  void back_half(Layers& layers, const StackParams& params, const PointXYZ* map_points, const float* weights,
                 std::size_t count, bool unit_weights, FrameCounters& frame) noexcept {
    ChunkCounts c{};
    CheckRuns<Layers> runs{};  // integrity hook: the chunk's writes keep the cells' checks
    // The Kalman batch entry, the common case (81 % of a CADRE frame): a point routed to the
    // finest layer inside its window, no per-point weight. The window is constant over the frame.
    const CellIndex fine_min = kKalman ? layers.fine.window_min() : CellIndex{0, 0};
    for (std::size_t i = 0; i < count; ++i) {
      const std::int32_t code = chunk_.code[i];
      if constexpr (kKalman) {
        if (code == 0 && unit_weights) {
          // Unsigned wrap: inside iff 0 <= index - min < side (|index|, |min| <= 2^30 + 2^14).
          constexpr auto kSide = static_cast<std::uint32_t>(Config::kFineSide);
          const std::uint32_t rx = static_cast<std::uint32_t>(chunk_.ix0[i]) - static_cast<std::uint32_t>(fine_min.x);
          const std::uint32_t ry = static_cast<std::uint32_t>(chunk_.iy0[i]) - static_cast<std::uint32_t>(fine_min.y);
          // cppcheck-suppress unsignedLessThanZero ; kSide is 0 only where kKalman is false
          if (rx < kSide && ry < kSide) {
            kalman_point<kGate>(layers, CellIndex{chunk_.ix0[i], chunk_.iy0[i]}, i, c);
            continue;
          }
        }
      }
      apply<kGate>(layers, params, i, map_points, weights, unit_weights, c, runs);
    }
    runs.close(layers);  // integrity hook
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

  /// Every other entry: refusals, weights, the layer walk. The walk uses index_k = index_0 >> k
  /// (floor division by 2^k): widths are w_0 * 2^k exactly and 1/w_k = (1/w_0) * 2^-k exactly in
  /// float, so floor(q / w_k) = floor(floor(q / w_0) / 2^k), the index locate() computes. (>> of
  /// a negative int32 is an arithmetic shift with gcc and clang, the floor division; C++20 makes
  /// it standard.)
  template <bool kGate>
  void apply(Layers& layers, const StackParams& params, std::size_t i, const PointXYZ* map_points,
             const float* weights, bool unit_weights, ChunkCounts& c, CheckRuns<Layers>& runs) noexcept {
    const std::int32_t code = chunk_.code[i];
    if (code >= std::int32_t{kFrontNonFinite}) {
      c.non_finite += code == std::int32_t{kFrontNonFinite} ? 1U : 0U;
      c.out_of_range += code == std::int32_t{kFrontOutOfRange} ? 1U : 0U;
      c.too_noisy += code == std::int32_t{kFrontTooNoisy} ? 1U : 0U;
      return;
    }
    float weight = 1.0F;  // the constant model's weight: always valid
    if (!unit_weights) {
      weight = weights != nullptr ? weights[i] : params.noise.weight_at_range_sq(to_range_sq_m2(chunk_.range_sq[i]));
      if (ccm_check_weight(weight) != Status::kOk) {
        ++c.bad_weight;
        return;
      }
    }
    const std::int32_t ix0 = chunk_.ix0[i];
    const std::int32_t iy0 = chunk_.iy0[i];
    for (int layer = code; layer < Layers::kLayerCount; ++layer) {
      const CellIndex index{ix0 >> layer, iy0 >> layer};
      if (Layers::is_ccm(layer)) {
        auto& grid = layers.ccm_grid(layer);
        if (!grid.contains(index)) {
          continue;
        }
        const std::int64_t width_q40 = width_q40_[layer];
        auto& cell = grid.cell_unchecked(index);
        const float x = relative_to_centre(chunk_.q18[0][i], index.x, width_q40);
        const float y = relative_to_centre(chunk_.q18[1][i], index.y, width_q40);
        const float z = height(i, map_points);
        if constexpr (kGate) {
          if (contradicted_by_finer(layers, layer, ix0, iy0, z)) {
            ++c.finer;
            return;
          }
          if (line_of_sight_ && occluded(layers, layer, i, z)) {
            ++c.occluded;
            return;
          }
          const auto number = static_cast<std::uint32_t>(&cell - layers.ccm_storage);
          if (ccm_outside_gate(cell, z, gate_[layer])) {
            if (auto* slot = hold(ccm_held_, number, index, layer, c)) {
              ccm_update_unchecked(slot->held, x, y, z, weight, params.weight_limit);
            }
            return;
          }
          ccm_held_.accept(number);
        }
        runs.ccm.touch(layers, cell);  // integrity hook
        ccm_update_unchecked(cell, x, y, z, weight, params.weight_limit);
        ++c.used;
        return;
      }
      if constexpr (Layers::kHasFine) {
        if (!layers.fine.contains(index)) {
          continue;
        }
        if constexpr (kKalman) {
          kalman_point<kGate>(layers, index, i, c);  // Kalman gains come from the range variance, not from weights
        } else {
          FineCell& cell = layers.fine.cell_unchecked(index);
          const float variance = fine_measurement_variance(params, to_range_sq_m2(chunk_.range_sq[i]));
          const float z = height(i, map_points);
          if constexpr (kGate) {
            const auto number = static_cast<std::uint32_t>(&cell - layers.fine_storage);
            if (omg_outside_gate(cell, z, gate_[layer])) {
              if (auto* slot = hold(fine_held_, number, index, layer, c)) {
                omg_update_unchecked(slot->held, z, variance, weight, params.weight_limit);
              }
              return;
            }
            fine_held_.accept(number);
          }
          runs.fine.touch(layers, cell);  // integrity hook
          omg_update_unchecked(cell, z, variance, weight, params.weight_limit);
          ++c.used;
        }
        return;
      }
    }
    ++c.outside;
  }

  /// True if the next finer layer's cell at the point (finest indices ix0, iy0) holds points and
  /// z lies outside that cell's gate with the constants of the point's own layer (its range
  /// noise class). A point routed by its range to a coarse layer while a finer layer knows the
  /// ground there is, when the two disagree, a range error: a stereo mismatch far along a steep
  /// near ray lands metres underground in a cell whose own direct points come only from such
  /// errors (the ground at that place is nearer and goes to the finer layer); the finer cell,
  /// made of more precise points, is the better judge (docs/design.md, "Outlier gate and change").
  [[nodiscard]] bool contradicted_by_finer(const Layers& layers, int layer, std::int32_t ix0, std::int32_t iy0,
                                           float z) const noexcept {
    if (layer == 0) {
      return false;
    }
    const int finer = layer - 1;
    const CellIndex index{ix0 >> finer, iy0 >> finer};
    const GateConstants& gate = gate_[layer];
    if (Layers::is_ccm(finer)) {
      const auto& grid = layers.ccm_grid(finer);
      return grid.contains(index) && ccm_outside_gate(grid.cell_unchecked(index), z, gate);
    }
    if constexpr (Layers::kHasFine) {
      if (!layers.fine.contains(index)) {
        return false;
      }
      if constexpr (kKalman) {
        return kalman_outside_gate(layers.fine.cell_unchecked(index), z, gate);
      } else {
        return omg_outside_gate(layers.fine.cell_unchecked(index), z, gate);
      }
    } else {
      return false;
    }
  }

  /// True if the point's line of sight from the sensor passes under known ground at its middle:
  /// at the midpoint of sensor and point (Q18, floored), the finest layer (up to the point's own)
  /// whose window holds it and whose cell there holds points has a height (a CCM cell's mean, a
  /// constant cell's height) above the line by more than the margin k sqrt(V) of the point's
  /// layer. Such a point cannot have been seen: a range too long for its ray (a stereo mismatch,
  /// docs/design.md, "Outlier gate and change"). Stereo only: a stereo frame's origin is its
  /// camera; map-frame lidar clouds may come with a nominal origin.
  [[nodiscard]] bool occluded(const Layers& layers, int layer, std::size_t i, float z) const noexcept {
    const std::int64_t mx = (chunk_.q18[0][i] + sight_origin_q18_[0]) >> 1;
    const std::int64_t my = (chunk_.q18[1][i] + sight_origin_q18_[1]) >> 1;
    // The finest index of the midpoint, as the front computes it: floor(q * fl(1 / w_0)).
    const auto ix0 = static_cast<std::int32_t>((mx * front_.index_mult) >> front_.index_shift);
    const auto iy0 = static_cast<std::int32_t>((my * front_.index_mult) >> front_.index_shift);
    const float line = 0.5F * (z + sight_origin_z_);
    for (int k = 0; k <= layer; ++k) {
      const CellIndex index{ix0 >> k, iy0 >> k};
      float ground = 0.0F;
      bool known = false;
      if (Layers::is_ccm(k)) {
        const auto& grid = layers.ccm_grid(k);
        if (!grid.contains(index)) {
          continue;
        }
        const auto& cell = grid.cell_unchecked(index);
        known = cell.weight > 0.0F;
        ground = cell.mean_z;
      } else if constexpr (Layers::kHasFine) {
        if (!layers.fine.contains(index)) {
          continue;
        }
        const FineCell& cell = layers.fine.cell_unchecked(index);
        known = cell.weight > 0.0F;
        ground = cell.height;
      }
      if (known) {
        return ground - line > sight_margin_[layer];
      }
    }
    return false;
  }

  /// The slot of a point outside its cell's gate, counted as held, or nullptr (counted as
  /// dropped) when every slot of the pool is taken.
  template <typename Pool>
  [[nodiscard]] static typename Pool::Slot* hold(Pool& pool, std::uint32_t number, CellIndex index, int layer,
                                                 ChunkCounts& c) noexcept {
    typename Pool::Slot* slot = pool.hold(number, index, layer);
    ++(slot != nullptr ? c.held : c.pool_full);
    return slot;
  }

  /// Map-frame height (m) of chunk entry i for the float cell updates: the caller's float for
  /// map-frame input, the Q18 position rounded once to float (+ half a unit: unbiased) otherwise.
  [[nodiscard]] float height(std::size_t i, const PointXYZ* map_points) const noexcept {
    if (map_points != nullptr) {
      return map_points[i].z;
    }
    return static_cast<float>(2 * chunk_.q18[2][i] + 1) * 1.90734863e-6F;  // 2^-19: (q + 1/2) * 2^-18
  }

  /// Measurement variance (m^2) of the piece-wise constant layer at squared range r^2 (m^2):
  /// sigma_m(r)^2, at least kalman_min_variance (which also catches NaN).
  [[nodiscard]] float fine_measurement_variance(const StackParams& params, float range_sq) const noexcept {
    // Stereo: sigma = k r^2 inline, the value sigma_at_range_sq returns for the finite positive
    // ranges that routing lets through; other models call it.
    const float sigma = stereo_ ? stereo_k_ * range_sq : params.noise.sigma_at_range_sq(range_sq);
    const float variance = sigma * sigma;
    return variance >= params.kalman_min_variance ? variance : params.kalman_min_variance;
  }

  /// One point of the Kalman layer's frame batch: the frame's points of a cell are collected in
  /// integers (count, Q14 heights, squared ranges as routing keys, 2^-12 m^2: no float operation
  /// per point) and fused once per frame by finish_fine_frame: n measurements of the variance at
  /// the cell's mean squared range, i.e. one update with their mean and R / n (docs/design.md,
  /// "Frame batches"). With the gate on, the cell's first point of the frame sets the gate's
  /// reference (the cell's height before the frame, or that point's own for a never-observed
  /// cell) and half-width (kalman_gate_half_width), both floored to Q14; a point whose
  /// |Q14 height - reference| exceeds the half-width is held in the cell's slot (sums of the
  /// same kind) instead. Precondition: the fine window contains `index`.
  template <bool kGate>
  void kalman_point(Layers& layers, CellIndex index, std::size_t i, ChunkCounts& c) noexcept {
    if constexpr (kKalman) {
      const std::size_t slot = grid::buffer_offset(index, Config::kFineSide);
      FineFrameSum& sum = fine_sums_[slot];
      const std::int32_t h = chunk_.height_q14[i];
      if constexpr (!kGate) {
        if (sum.count == 0U) {  // gate off: every point of the frame is inside (points stays 0)
          fine_touched_[fine_touched_count_++ & kTouchedMask] = static_cast<std::uint32_t>(slot);  // integrity: masked
        }
      } else {
        if (sum.points == 0U) {
          fine_touched_[fine_touched_count_++ & kTouchedMask] = static_cast<std::uint32_t>(slot);  // integrity: masked
          const KalmanCell& cell = layers.fine.storage()[slot];
          sum.reference_q14 = cell.weight > 0.0F ? q14_floor_of(cell.height) : h;
          sum.gate_q14 = q14_half_width(kalman_gate_half_width(cell, gate_[0]));
        }
        ++sum.points;
        const std::int64_t d = std::int64_t{h} - std::int64_t{sum.reference_q14};
        if (static_cast<std::uint64_t>(d < 0 ? -d : d) > std::uint64_t{sum.gate_q14}) {
          if (auto* held = hold(fine_held_, static_cast<std::uint32_t>(slot), index, 0, c)) {
            KalmanHeld& k = held->held;
            if (held->count == 1U) {
              k.origin_q14 = h;
            }
            k.sum_height_q14 += h;
            k.sum_range_key += chunk_.range_key[i];
            const float v = static_cast<float>(std::int64_t{h} - std::int64_t{k.origin_q14}) * 6.10351562e-5F;  // m
            const float delta = v - k.mean_m;
            k.mean_m += delta / static_cast<float>(held->count);
            k.spread_sum += delta * (v - k.mean_m);
          }
          return;
        }
      }
      // |Q14 height| <= 1e5 m * 2^14 < 2^31 and routing keys < 2^32: 2^32 of either stay below
      // 2^63 / 2^64, so no sum can overflow within one frame (at most 2^32 points), nor a slot's
      // held sums over kMaxHeldFrames frames of at most 2^32 points each (2^35 < 2^63 / 2^31).
      ++sum.count;
      sum.sum_height_q14 += h;
      sum.sum_range_key += chunk_.range_key[i];
      ++c.used;
    } else {
      (void)layers;
      (void)index;
      (void)i;
      (void)c;
    }
  }

  /// floor(v 2^14) for |v| <= 1e5 m (a Kalman cell's height: a mean of accepted heights).
  /// Integrity: saturated at the int32 range (NaN: INT32_MIN), so that a cell an upset changed
  /// converts without undefined behaviour (its check tells the readers; the gate only misjudges).
  [[nodiscard]] static std::int32_t q14_floor_of(float v) noexcept {
    const float q = std::floor(v * 16384.0F);
    if (q >= -2147483648.0F && q < 2147483648.0F) {
      return static_cast<std::int32_t>(q);
    }
    return q > 0.0F ? std::int32_t{2147483647} : std::int32_t{-2147483647 - 1};
  }
  /// floor(v 2^14) of a gate half-width v >= 0 (m), saturated at 2^31 units (131 km).
  [[nodiscard]] static std::uint32_t q14_half_width(float v) noexcept {
    const float units = v * 16384.0F;
    return units < 2147483648.0F ? static_cast<std::uint32_t>(units) : 0x80000000U;
  }

  /// The start of a frame: a slot whose cell left its layer's window (a move since the last
  /// frame cleared the cell) is dropped with its points.
  void begin_frame(const Layers& layers, const FramePose& pose, FrameCounters& frame) noexcept {
    // Integrity hook (map/detail/integrity.hpp): the frame batches and touched list start empty,
    // the held-point slots as sealed at the last frame's end, whatever happened between frames.
    restore_frame_state(fine_sums_, &fine_touched_count_, ccm_held_, fine_held_, frame);
    if (!gate_on_) {
      return;
    }
    for (int a = 0; a < 3; ++a) {
      sight_origin_q18_[a] = pose.origin_q18[a];
    }
    sight_origin_z_ = q18_to_float(pose.origin_q18[2]);
    auto gone = [&layers](const auto& slot) { return !layers.contains(slot.layer, slot.index); };
    auto dropped = [&frame](const auto& slot) { frame.gated_dropped += slot.count; };
    if constexpr (kCcmPool) {
      ccm_held_.drop_if(gone, dropped);
    }
    if constexpr (kFinePool) {
      fine_held_.drop_if(gone, dropped);
    }
  }

  /// The end of a frame: the Kalman layer's batches, then the change rule for every cell with
  /// held points (slots kept while their verdict is kPending).
  void finish_frame(Layers& layers, const StackParams& params, FrameCounters& frame) noexcept {
    if constexpr (kKalman) {
      fuse_fine_batches(layers, params);
    }
    last_frame_slots_ = ccm_held_.used() + fine_held_.used();
    if (gate_on_) {
      if constexpr (kCcmPool) {
        ccm_held_.end_frame([&](const auto& slot) {
          auto& cell = layers.ccm_storage[slot.cell];
          const bool tight = held_is_tight(slot.held.s_zz, slot.held.weight, gate_[slot.layer]);
          const std::uint64_t before = cell_signature_wide(cell);  // integrity hook
          switch (verdict(slot, tight, frame)) {
            case ChangeVerdict::kReseed:
              cell = slot.held;  // the held points folded into an empty cell, limiter included
              rewrite_check(layers, cell, before);  // integrity hook
              return false;
            case ChangeVerdict::kMerge:
              // Cannot fail: the limit was validated at init, the held weight is > 0 and finite.
              (void)ccm_merge(cell, slot.held, params.weight_limit);
              rewrite_check(layers, cell, before);  // integrity hook
              return false;
            case ChangeVerdict::kPending:
              return true;
            case ChangeVerdict::kDrop:
              break;
          }
          return false;
        });
      }
      if constexpr (kFinePool) {
        fine_held_.end_frame([&](auto& slot) {
          bool tight = false;
          if constexpr (kKalman) {
            slot.accepted += fine_sums_[slot.cell].count;  // this frame's points inside the gate
            tight = held_is_tight(slot.held.spread_sum, static_cast<float>(slot.count), gate_[0]);
          } else {
            tight = held_is_tight(slot.held.s, slot.held.weight, gate_[0]);
          }
          const ChangeVerdict v = verdict(slot, tight, frame);
          if (v == ChangeVerdict::kReseed || v == ChangeVerdict::kMerge) {
            admit_fine(layers, params, slot, v == ChangeVerdict::kReseed);
          }
          return v == ChangeVerdict::kPending;
        });
      }
    }
    if constexpr (kKalman) {
      const std::uint32_t touched = touched_count();  // integrity: clamped
      for (std::uint32_t t = 0; t < touched; ++t) {
        fine_sums_[fine_touched_[t] & kTouchedMask] = FineFrameSum{};  // integrity: masked
      }
      fine_touched_count_ = 0U;
    }
    ccm_held_.seal();  // integrity hook: the slots as they wait for the next frame
    fine_held_.seal();
  }

  /// The change rule for a slot at the end of a frame, counted in the frame's counters.
  template <typename Slot>
  [[nodiscard]] ChangeVerdict verdict(const Slot& slot, bool tight, FrameCounters& frame) const noexcept {
    const bool may_wait = slot.frames + 1U < kMaxHeldFrames;
    const ChangeVerdict v = change_verdict(slot.accepted, slot.count, tight, may_wait, rule_);
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

  /// Admits the held points of a finest-layer slot: re-seed (the cell emptied first) or merge.
  template <typename Slot>
  void admit_fine(Layers& layers, const StackParams& params, const Slot& slot, bool reseed) noexcept {
    FineCell& cell = layers.fine_storage[slot.cell];
    const std::uint64_t before = cell_signature_wide(cell);  // integrity hook
    if (reseed) {
      cell = FineCell{};
    }
    if constexpr (kKalman) {
      // The held points as one more batch: their mean, the variance at their mean squared range.
      fuse_batch(cell, params, slot.held.sum_height_q14, slot.held.sum_range_key, slot.count);
    } else {
      // Cannot fail: the limit was validated at init, the held statistics are finite.
      (void)omg_merge(cell, slot.held, params.weight_limit);
    }
    rewrite_check(layers, cell, before);  // integrity hook
  }

  /// Fuses each touched Kalman cell's batch of this frame (the points inside the gate).
  void fuse_fine_batches(Layers& layers, const StackParams& params) noexcept {
    if constexpr (kKalman) {
      KalmanCell* cells = layers.fine.storage();
      const std::uint32_t touched = touched_count();  // integrity: clamped
      for (std::uint32_t t = 0; t < touched; ++t) {
        const std::uint32_t slot = fine_touched_[t] & kTouchedMask;  // integrity: masked
        const FineFrameSum& sum = fine_sums_[slot];
        if (sum.count > 0U) {
          const std::uint64_t before = cell_signature_wide(cells[slot]);  // integrity hook
          fuse_batch(cells[slot], params, sum.sum_height_q14, sum.sum_range_key, sum.count);
          rewrite_check(layers, cells[slot], before);  // integrity hook
        }
      }
    } else {
      (void)layers;
      (void)params;
    }
  }

  /// One Kalman batch update of `count` > 0 points with these sums: their mean height (the
  /// floored Q14 mean, + half a unit: unbiased) and the variance at their mean squared range
  /// (from the keys floored to 2^-12 m^2, + half a key likewise), divided by count.
  void fuse_batch(KalmanCell& cell, const StackParams& params, std::int64_t sum_height_q14,
                  std::uint64_t sum_range_key, std::uint32_t count) const noexcept {
    const auto n = static_cast<std::int64_t>(count);
    std::int64_t whole = sum_height_q14 / n;
    std::int64_t rest = sum_height_q14 % n;
    if (rest < 0) {
      --whole;
      rest += n;
    }
    const float mean_q14 = static_cast<float>(whole) +
                           (static_cast<float>(rest) + 0.5F * static_cast<float>(n)) / static_cast<float>(n);
    const float mean_z = mean_q14 * 6.10351562e-5F;  // 2^-14
    const std::uint64_t whole_key = sum_range_key / count;  // integer mean, then the rest
    const std::uint64_t rest_key = sum_range_key % count;
    const float mean_key =
        static_cast<float>(whole_key) + (static_cast<float>(rest_key) + 0.5F * static_cast<float>(n)) / static_cast<float>(n);
    const float variance = fine_measurement_variance(params, mean_key * 2.44140625e-4F);  // 2^-12 m^2
    kalman_update_batch_unchecked(cell, mean_z, variance, count, params.kalman_min_variance);
  }

  /// Per-frame batch of a Kalman cell (all zero between frames).
  struct FineFrameSum {
    std::uint32_t count;          ///< points inside the gate (every point with the gate off)
    std::uint32_t points;         ///< with the gate on: every point of the frame (held ones included); else 0
    std::int64_t sum_height_q14;  ///< sum of floor(z * 2^14) of the points inside
    std::uint64_t sum_range_key;  ///< sum of their routing keys (squared ranges, 2^-12 m^2)
    std::int32_t reference_q14;   ///< gate reference, floor(h * 2^14), set by the frame's first point
    std::uint32_t gate_q14;       ///< gate half-width, floor(. * 2^14)
  };

  // ---- zero-initialised (a static stack lives in .bss); derived at init ----
  FrontConfig front_{};
  FrontChunk chunk_{};
  std::int64_t width_q40_[Layers::kLayerSlots]{};  ///< cell width of each layer, Q40 m (exact)
  FineFrameSum fine_sums_[kFineBatchSlots]{};
  std::uint32_t fine_touched_[kFineBatchSlots]{};
  std::uint32_t fine_touched_count_ = 0U;
  CcmPool ccm_held_{};                         ///< held points of CCM cells
  FinePool fine_held_{};                       ///< held points of finest-layer cells
  GateConstants gate_[Layers::kLayerSlots]{};  ///< per layer (cell/outlier_gate.hpp)
  ChangeRule rule_{};
  float sight_margin_[Layers::kLayerSlots]{};  ///< k sqrt(V) per layer (m)
  std::int64_t sight_origin_q18_[3]{};         ///< this frame's sensor position (Q18)
  float sight_origin_z_ = 0.0F;                ///< its height (m)
  std::uint32_t last_frame_slots_ = 0U;
  bool gate_on_ = false;
  bool line_of_sight_ = false;
  bool constant_weight_ = false;
  bool stereo_ = false;
  float stereo_k_ = 0.0F;  ///< stereo sigma per range^2 (1/m) when stereo_
};

}  // namespace ccmap::detail
