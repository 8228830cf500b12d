// The per-frame update path of a stack: the integer front of every point (map/detail/front.hpp),
// the back half that walks the layers and updates one cell, and the per-frame batches of the
// piece-wise constant Kalman layer. Owned by Stack<Config>; integrators need not read it.
//
// Data flows one way: point -> front (validate, transform, range, route, index) -> the routed
// layer or the first coarser one whose window holds the point -> one cell update.
// No heap, no exceptions; O(points) per frame plus O(touched Kalman cells).
//
// Cost (docs/performance.md): under QEMU user mode every float instruction is a soft-float
// helper call, so the back half forms a CCM cell's relative position in fixed point (one
// conversion per axis) and the Kalman batch takes no float operation per point.
#pragma once

#include <cstddef>
#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/detail/front.hpp"
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

  /// Derives the front (index scale, routing bounds in fixed point), the cell widths in Q40 and
  /// the weighting mode. max_range_sq_m2: the routing table's squared ranges (m^2), per layer.
  [[nodiscard]] Status init(const StackParams& params, const float* max_range_sq_m2, const Layers& layers) noexcept {
    const Status status = make_front_config(layers.widths[0], max_range_sq_m2, Layers::kLayerCount, &front_);
    for (int layer = 0; layer < Layers::kLayerCount; ++layer) {
      // Exact: a float width >= 2^-17 m times 2^40 is an integer below 2^47 (validated widths).
      width_q40_[layer] = floor_to_int64(layers.widths[layer] * 1099511627776.0F);
    }
    constant_weight_ = params.noise.weight_mode() == sensor::WeightMode::kConstant;
    stereo_ = params.noise.kind() == sensor::SensorKind::kStereo && params.noise.validate() == Status::kOk;
    stereo_k_ = stereo_ ? params.noise.stereo_sigma_per_range_sq() : 0.0F;
    if constexpr (kKalman) {
      fine_touched_count_ = 0U;
      for (FineFrameSum& sum : fine_sums_) {
        sum = FineFrameSum{};
      }
    }
    return status;
  }

  /// Folds map-frame points (weights may be nullptr: the noise model weighs them).
  void run_map(Layers& layers, const StackParams& params, const PointXYZ* points, const float* weights, std::size_t n,
               const FramePose& pose, FrameCounters& frame) noexcept {
    const bool unit_weights = weights == nullptr && constant_weight_;
    for (std::size_t begin = 0; begin < n; begin += kFrontChunkPoints) {
      const std::size_t count = n - begin < kFrontChunkPoints ? n - begin : kFrontChunkPoints;
      front_map_chunk(points + begin, count, pose, front_, chunk_);
      back_half(layers, params, points + begin, weights != nullptr ? weights + begin : nullptr, count, unit_weights,
                frame);
    }
    finish_fine_frame(layers, params);
  }

  /// Folds sensor-frame points with the frame's fixed-point pose (make_frame_pose with a rotation).
  void run_sensor(Layers& layers, const StackParams& params, const PointXYZ* points, std::size_t n,
                  const FramePose& pose, FrameCounters& frame) noexcept {
    for (std::size_t begin = 0; begin < n; begin += kFrontChunkPoints) {
      const std::size_t count = n - begin < kFrontChunkPoints ? n - begin : kFrontChunkPoints;
      front_sensor_chunk(points + begin, count, pose, front_, chunk_);
      back_half(layers, params, nullptr, nullptr, count, constant_weight_, frame);
    }
    finish_fine_frame(layers, params);
  }

  [[nodiscard]] const FrontConfig& front() const noexcept { return front_; }

 private:
  static constexpr bool kKalman = Config::kFineKind == FineKind::kKalman;

  /// Counts of one chunk, kept in registers and added to the frame's counters once.
  struct ChunkCounts {
    std::uint32_t used = 0U, non_finite = 0U, out_of_range = 0U, too_noisy = 0U, bad_weight = 0U, outside = 0U;
  };

  /// Back half of one chunk. `map_points` is the caller's map-frame chunk (the CCM and OMG
  /// updates take the float z from it), or nullptr for sensor-frame input (z from the Q18 position).
  void back_half(Layers& layers, const StackParams& params, const PointXYZ* map_points, const float* weights,
                 std::size_t count, bool unit_weights, FrameCounters& frame) noexcept {
    ChunkCounts c{};
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
            kalman_point(CellIndex{chunk_.ix0[i], chunk_.iy0[i]}, i);
            ++c.used;
            continue;
          }
        }
      }
      apply(layers, params, i, map_points, weights, unit_weights, c);
    }
    frame.used += c.used;
    frame.rejected_non_finite += c.non_finite;
    frame.rejected_out_of_range += c.out_of_range;
    frame.too_noisy += c.too_noisy;
    frame.rejected_weight += c.bad_weight;
    frame.outside_map += c.outside;
  }

  /// Every other entry: refusals, weights, the layer walk. The walk uses index_k = index_0 >> k
  /// (floor division by 2^k): widths are w_0 * 2^k exactly and 1/w_k = (1/w_0) * 2^-k exactly in
  /// float, so floor(q / w_k) = floor(floor(q / w_0) / 2^k), the index locate() computes. (>> of
  /// a negative int32 is an arithmetic shift with gcc and clang, the floor division; C++20 makes
  /// it standard.)
  void apply(Layers& layers, const StackParams& params, std::size_t i, const PointXYZ* map_points,
             const float* weights, bool unit_weights, ChunkCounts& c) noexcept {
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
        RingGrid<typename Layers::CcmCellType>& grid = layers.ccm_grid(layer);
        if (!grid.contains(index)) {
          continue;
        }
        const std::int64_t width_q40 = width_q40_[layer];
        ccm_update_unchecked(grid.cell_unchecked(index), relative_to_centre(chunk_.q18[0][i], index.x, width_q40),
                             relative_to_centre(chunk_.q18[1][i], index.y, width_q40), height(i, map_points), weight,
                             params.weight_limit);
      } else {
        if constexpr (Layers::kHasFine) {
          if (!layers.fine.contains(index)) {
            continue;
          }
          if constexpr (kKalman) {
            kalman_point(index, i);  // Kalman gains come from the range variance, not from weights
          } else {
            const float variance = fine_measurement_variance(params, to_range_sq_m2(chunk_.range_sq[i]));
            omg_update_unchecked(layers.fine.cell_unchecked(index), height(i, map_points), variance, weight,
                                 params.weight_limit);
          }
        }
      }
      ++c.used;
      return;
    }
    ++c.outside;
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
  /// "Frame batches").
  /// Precondition: the fine window contains `index`.
  void kalman_point(CellIndex index, std::size_t i) noexcept {
    if constexpr (kKalman) {
      const std::size_t slot = grid::buffer_offset(index, Config::kFineSide);
      FineFrameSum& sum = fine_sums_[slot];
      if (sum.count == 0U) {
        fine_touched_[fine_touched_count_++] = static_cast<std::uint32_t>(slot);
      }
      ++sum.count;
      // |Q14 height| <= 1e5 m * 2^14 < 2^31 and routing keys < 2^32: 2^32 of either stay below
      // 2^63 / 2^64, so neither sum can overflow within one frame (at most 2^32 points).
      sum.sum_height_q14 += chunk_.height_q14[i];
      sum.sum_range_key += chunk_.range_key[i];
    } else {
      (void)index;
      (void)i;
    }
  }

  /// Fuses each touched Kalman cell's batch of this frame and clears the batches.
  void finish_fine_frame(Layers& layers, const StackParams& params) noexcept {
    if constexpr (kKalman) {
      KalmanCell* cells = layers.fine.storage();
      for (std::uint32_t t = 0; t < fine_touched_count_; ++t) {
        const std::uint32_t slot = fine_touched_[t];
        FineFrameSum& sum = fine_sums_[slot];
        const auto count = static_cast<std::int64_t>(sum.count);
        // Mean in integers (exact), then one rounding to float; + 0.5 unit removes the bias of
        // the floor in the Q14 conversion (uniform error, sigma = 2^-14 m / sqrt(12) = 18 um).
        std::int64_t whole = sum.sum_height_q14 / count;
        std::int64_t rest = sum.sum_height_q14 % count;
        if (rest < 0) {
          --whole;
          rest += count;
        }
        const float mean_q14 = static_cast<float>(whole) +
                               (static_cast<float>(rest) + 0.5F * static_cast<float>(count)) / static_cast<float>(count);
        const float mean_z = mean_q14 * 6.10351562e-5F;  // 2^-14
        // Mean squared range from the keys (floored to 2^-12 m^2: + half a key removes the bias).
        const std::uint64_t whole_key = sum.sum_range_key / sum.count;  // integer mean, then the rest
        const std::uint64_t rest_key = sum.sum_range_key % sum.count;
        const float mean_key = static_cast<float>(whole_key) +
                               (static_cast<float>(rest_key) + 0.5F * static_cast<float>(count)) / static_cast<float>(count);
        const float variance = fine_measurement_variance(params, mean_key * 2.44140625e-4F);  // 2^-12 m^2
        kalman_update_batch_unchecked(cells[slot], mean_z, variance, sum.count, params.kalman_min_variance);
        sum = FineFrameSum{};
      }
      fine_touched_count_ = 0U;
    } else {
      (void)layers;
      (void)params;
    }
  }

  /// Per-frame batch of a Kalman cell (all zero between frames).
  struct FineFrameSum {
    std::uint32_t count;
    std::int64_t sum_height_q14;  ///< sum of floor(z * 2^14)
    std::uint64_t sum_range_key;  ///< sum of routing keys (squared ranges, 2^-12 m^2)
  };
  static constexpr std::size_t kFineBatchSlots = kKalman ? Layers::kFineCellCount : 1U;

  // ---- zero-initialised (a static stack lives in .bss); derived at init ----
  FrontConfig front_{};
  FrontChunk chunk_{};
  std::int64_t width_q40_[Layers::kLayerSlots]{};  ///< cell width of each layer, Q40 m (exact)
  FineFrameSum fine_sums_[kFineBatchSlots]{};
  std::uint32_t fine_touched_[kFineBatchSlots]{};
  std::uint32_t fine_touched_count_ = 0U;
  bool constant_weight_ = false;
  bool stereo_ = false;
  float stereo_k_ = 0.0F;  ///< stereo sigma per range^2 (1/m) when stereo_
};

}  // namespace ccmap::detail
