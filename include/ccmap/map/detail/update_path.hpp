// The per-frame update path of a stack: the integer front of every point (map/detail/front.hpp),
// the back half that walks the layers and updates one cell, and the per-frame batches of the
// piece-wise constant Kalman layer. Owned by Stack<Config>; integrators need not read it.
//
// Data flows one way: point -> front (validate, transform, range, route, index) -> the routed
// layer or the first coarser one whose window holds the point -> one cell update.
// No heap, no exceptions; O(points) per frame plus O(touched Kalman cells).
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

template <typename Config>
class UpdatePath {
 public:
  using Layers = LayerSet<Config>;

  /// Derives the front (index scale, routing bounds in fixed point) and the weighting mode.
  /// max_range_sq_m2: the routing table's squared ranges (m^2), one per layer.
  [[nodiscard]] Status init(const StackParams& params, const float* max_range_sq_m2, const Layers& layers) noexcept {
    const Status status = make_front_config(layers.widths[0], max_range_sq_m2, Layers::kLayerCount, &front_);
    constant_weight_ = params.noise.weight_mode() == sensor::WeightMode::kConstant;
    stereo_ = params.noise.kind() == sensor::SensorKind::kStereo && params.noise.validate() == Status::kOk;
    stereo_k_ = stereo_ ? params.noise.stereo_sigma_per_range_sq() : 0.0F;
    if constexpr (Config::kFineKind == FineKind::kKalman) {
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
    for (std::size_t i = 0; i < n; ++i) {
      const PointXYZ& p = points[i];
      apply(layers, params, front_map_point(p.x, p.y, p.z, pose, front_), &p,
            weights != nullptr ? weights + i : nullptr, unit_weights, frame);
    }
    finish_fine_frame(layers, params);
  }

  /// Folds sensor-frame points with the frame's fixed-point pose (make_frame_pose with a rotation).
  void run_sensor(Layers& layers, const StackParams& params, const PointXYZ* points, std::size_t n,
                  const FramePose& pose, FrameCounters& frame) noexcept {
    for (std::size_t i = 0; i < n; ++i) {
      const PointXYZ& p = points[i];
      apply(layers, params, front_sensor_point(p.x, p.y, p.z, pose, front_), nullptr, nullptr, constant_weight_,
            frame);
    }
    finish_fine_frame(layers, params);
  }

  [[nodiscard]] const FrontConfig& front() const noexcept { return front_; }

 private:
  /// Back half for one point. The layer walk uses index_k = index_0 >> k (floor division by
  /// 2^k): widths are w_0 * 2^k exactly and 1/w_k = (1/w_0) * 2^-k exactly in float, so
  /// floor(q / w_k) = floor(floor(q / w_0) / 2^k), the index locate() computes. (>> of a
  /// negative int32 is an arithmetic shift with gcc and clang, the floor division; C++20 makes
  /// it standard.) `map_point` is the caller's float point for map-frame input, nullptr for
  /// sensor-frame input (the CCM update then takes the Q18 position rounded to float).
  void apply(Layers& layers, const StackParams& params, const PointFront& front, const PointXYZ* map_point,
             const float* weight_in, bool unit_weights, FrameCounters& frame) noexcept {
    const std::uint32_t code = front.code;
    if (code >= kFrontNonFinite) {
      frame.rejected_non_finite += code == kFrontNonFinite ? 1U : 0U;
      frame.rejected_out_of_range += code == kFrontOutOfRange ? 1U : 0U;
      frame.too_noisy += code == kFrontTooNoisy ? 1U : 0U;
      return;
    }
    float weight = 1.0F;  // the constant model's weight: always valid
    if (!unit_weights) {
      weight = weight_in != nullptr ? *weight_in : params.noise.weight_at_range_sq(to_range_sq_m2(front.range_sq));
      if (ccm_check_weight(weight) != Status::kOk) {
        ++frame.rejected_weight;
        return;
      }
    }
    for (int layer = static_cast<int>(code); layer < Layers::kLayerCount; ++layer) {
      const CellIndex index{front.ix0 >> layer, front.iy0 >> layer};
      if (Layers::is_ccm(layer)) {
        RingGrid<CcmCell>& grid = layers.ccm_grid(layer);
        if (!grid.contains(index)) {
          continue;
        }
        const float width = layers.widths[layer];
        const float x = map_point != nullptr ? map_point->x : q18_to_float(front.q18[0]);
        const float y = map_point != nullptr ? map_point->y : q18_to_float(front.q18[1]);
        const float z = map_point != nullptr ? map_point->z : q18_to_float(front.q18[2]);
        ccm_update_unchecked(grid.cell_unchecked(index), x - grid::cell_centre(index.x, width),
                             y - grid::cell_centre(index.y, width), z, weight, params.weight_limit);
      } else {
        if constexpr (Layers::kHasFine) {
          if (!layers.fine.contains(index)) {
            continue;
          }
          const float z = map_point != nullptr ? map_point->z : q18_to_float(front.q18[2]);
          fine_point(layers, params, index, front, z, weight);
        }
      }
      ++frame.used;
      return;
    }
    ++frame.outside_map;
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

  /// One point for the piece-wise constant layer. Kalman: the frame's points of a cell are
  /// collected in integers (count, Q14 heights, squared ranges: no float operation per point)
  /// and fused once per frame by finish_fine_frame: n measurements of the variance at the
  /// cell's mean squared range, i.e. one update with their mean and R / n (docs/design.md,
  /// "Frame batches"). OMG: one update per point.
  void fine_point(Layers& layers, const StackParams& params, CellIndex index, const PointFront& front, float z,
                  float weight) noexcept {
    if constexpr (Config::kFineKind == FineKind::kKalman) {
      (void)params;
      (void)z;       // the batch takes the Q14 height
      (void)weight;  // Kalman gains come from the range variance, not from weights
      const std::size_t slot = grid::buffer_offset(index, Config::kFineSide);
      FineFrameSum& sum = fine_sums_[slot];
      if (sum.count == 0U) {
        fine_touched_[fine_touched_count_++] = static_cast<std::uint32_t>(slot);
      }
      ++sum.count;
      // |Q14 height| <= 1e5 m * 2^14 < 2^31: 2^32 of them stay below 2^63.
      sum.sum_height_q14 += front.height_q14;
      const auto r = static_cast<std::uint64_t>(front.range_sq);
      const std::uint64_t total = sum.sum_range_sq + r;
      sum.sum_range_sq = total < r ? UINT64_MAX : total;  // saturating (a saturated range is INT64_MAX)
      (void)layers;
    } else if constexpr (Config::kFineKind == FineKind::kOmg) {
      const float variance = fine_measurement_variance(params, to_range_sq_m2(front.range_sq));
      omg_update_unchecked(layers.fine.cell_unchecked(index), z, variance, weight, params.weight_limit);
    } else {
      (void)layers;
      (void)params;
      (void)index;
      (void)front;
      (void)z;
      (void)weight;
    }
  }

  /// Fuses each touched Kalman cell's batch of this frame and clears the batches.
  void finish_fine_frame(Layers& layers, const StackParams& params) noexcept {
    if constexpr (Config::kFineKind == FineKind::kKalman) {
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
        const std::uint64_t mean_range = sum.sum_range_sq / sum.count;
        const float variance = fine_measurement_variance(
            params, to_range_sq_m2(static_cast<std::int64_t>(mean_range > INT64_MAX ? INT64_MAX : mean_range)));
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
    std::uint64_t sum_range_sq;   ///< saturating sum of squared ranges (2^-32 m^2)
  };
  static constexpr std::size_t kFineBatchSlots = Config::kFineKind == FineKind::kKalman ? Layers::kFineCellCount : 1U;

  // ---- zero-initialised (a static stack lives in .bss); derived at init ----
  FrontConfig front_{};
  FineFrameSum fine_sums_[kFineBatchSlots]{};
  std::uint32_t fine_touched_[kFineBatchSlots]{};
  std::uint32_t fine_touched_count_ = 0U;
  bool constant_weight_ = false;
  bool stereo_ = false;
  float stereo_k_ = 0.0F;  ///< stereo sigma per range^2 (1/m) when stereo_
};

}  // namespace ccmap::detail
