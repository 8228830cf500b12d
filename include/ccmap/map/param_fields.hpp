// Names of the StackParams members as bits (parameter commands: Stack::set_params says which
// changed fields need a re-init). The C API's CCMAP_PARAM_* are these values (src/capi/capi.cpp
// asserts it); docs/icd.md lists which fields a running map takes (generated from docs/icd/).
#pragma once

#include <cstdint>

#include "ccmap/core/float_bits.hpp"
#include "ccmap/map/config.hpp"

namespace ccmap {

namespace param_field {
inline constexpr std::uint32_t kFinestCellWidth = 1U << 0U;
inline constexpr std::uint32_t kWeightLimit = 1U << 1U;
inline constexpr std::uint32_t kCoverageTau = 1U << 2U;
inline constexpr std::uint32_t kMinWeight = 1U << 3U;
inline constexpr std::uint32_t kObstacleFraction = 1U << 4U;
inline constexpr std::uint32_t kMaxInclination = 1U << 5U;
inline constexpr std::uint32_t kKalmanMinVariance = 1U << 6U;
inline constexpr std::uint32_t kNormalVarianceThreshold = 1U << 7U;
inline constexpr std::uint32_t kFinestMaxSigma = 1U << 8U;
inline constexpr std::uint32_t kOutlierGateSigma = 1U << 9U;
inline constexpr std::uint32_t kChangeMinPoints = 1U << 10U;
inline constexpr std::uint32_t kChangeShare = 1U << 11U;
inline constexpr std::uint32_t kFramePointBudget = 1U << 12U;
inline constexpr std::uint32_t kFrameTimeBudget = 1U << 13U;
inline constexpr std::uint32_t kFreeSpaceRays = 1U << 14U;
inline constexpr std::uint32_t kFreeSpaceClearFrames = 1U << 15U;
inline constexpr std::uint32_t kSensorViewAxis = 1U << 16U;
inline constexpr std::uint32_t kNoise = 1U << 17U;
inline constexpr std::uint32_t kAll = (1U << 18U) - 1U;
/// Fields no running stack takes: the cell width binds every layer. The noise model and
/// finest_max_sigma_m need a re-init only when they change the routing (Stack::set_params).
inline constexpr std::uint32_t kReinitAlways = kFinestCellWidth;
}  // namespace param_field

/// The param_field bits of the members that differ between `a` and `b`, floats by their bits
/// (-0 and +0 differ, a NaN equals itself); the noise model by what it holds (its kind, weight
/// mode, reference range and coefficients).
[[nodiscard]] inline std::uint32_t changed_param_fields(const StackParams& a, const StackParams& b) noexcept {
  using detail::same_float_bits;
  std::uint32_t mask = 0U;
  auto differ = [&mask](bool same, std::uint32_t bit) { mask |= same ? 0U : bit; };
  differ(same_float_bits(a.finest_cell_width_m, b.finest_cell_width_m), param_field::kFinestCellWidth);
  differ(same_float_bits(a.weight_limit, b.weight_limit), param_field::kWeightLimit);
  differ(same_float_bits(a.coverage_tau, b.coverage_tau), param_field::kCoverageTau);
  differ(same_float_bits(a.min_weight, b.min_weight), param_field::kMinWeight);
  differ(same_float_bits(a.obstacle_fraction, b.obstacle_fraction), param_field::kObstacleFraction);
  differ(same_float_bits(a.max_inclination, b.max_inclination), param_field::kMaxInclination);
  differ(same_float_bits(a.kalman_min_variance, b.kalman_min_variance), param_field::kKalmanMinVariance);
  differ(same_float_bits(a.normal_variance_threshold.data(), b.normal_variance_threshold.data(),
                         a.normal_variance_threshold.size()),
         param_field::kNormalVarianceThreshold);
  differ(same_float_bits(a.finest_max_sigma_m, b.finest_max_sigma_m), param_field::kFinestMaxSigma);
  differ(same_float_bits(a.outlier_gate_sigma, b.outlier_gate_sigma), param_field::kOutlierGateSigma);
  differ(same_float_bits(a.change_min_points, b.change_min_points), param_field::kChangeMinPoints);
  differ(same_float_bits(a.change_share, b.change_share), param_field::kChangeShare);
  differ(a.frame_point_budget == b.frame_point_budget, param_field::kFramePointBudget);
  differ(a.frame_time_budget_us == b.frame_time_budget_us, param_field::kFrameTimeBudget);
  differ(same_float_bits(a.free_space_rays, b.free_space_rays), param_field::kFreeSpaceRays);
  differ(same_float_bits(a.free_space_clear_frames, b.free_space_clear_frames), param_field::kFreeSpaceClearFrames);
  differ(same_float_bits(a.sensor_view_axis.data(), b.sensor_view_axis.data(), a.sensor_view_axis.size()),
         param_field::kSensorViewAxis);
  const sensor::NoiseModel& na = a.noise;
  const sensor::NoiseModel& nb = b.noise;
  differ(na.kind() == nb.kind() && na.weight_mode() == nb.weight_mode() &&
             same_float_bits(na.reference_range_m(), nb.reference_range_m()) &&
             same_float_bits(na.stereo_sigma_per_range_sq(), nb.stereo_sigma_per_range_sq()) &&
             same_float_bits(na.lidar_sigma0_m(), nb.lidar_sigma0_m()) &&
             same_float_bits(na.lidar_sigma_per_m(), nb.lidar_sigma_per_m()),
         param_field::kNoise);
  return mask;
}

}  // namespace ccmap
