// Names of the StackParams members as bits (parameter commands: Stack::set_params says which
// changed fields need a re-init). The C API's CCMAP_PARAM_* are these values (src/capi/capi.cpp
// asserts it); docs/icd.md lists which fields a running map takes (generated from docs/icd/).
#pragma once

#include <cstdint>
#include <cstring>

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

/// The param_field bits of the members whose bytes differ between `a` and `b` (bitwise: -0 and
/// +0 differ, a NaN equals itself).
[[nodiscard]] inline std::uint32_t changed_param_fields(const StackParams& a, const StackParams& b) noexcept {
  std::uint32_t mask = 0U;
  auto differ = [&mask](const auto& x, const auto& y, std::uint32_t bit) {
    mask |= std::memcmp(&x, &y, sizeof x) != 0 ? bit : 0U;
  };
  differ(a.finest_cell_width_m, b.finest_cell_width_m, param_field::kFinestCellWidth);
  differ(a.weight_limit, b.weight_limit, param_field::kWeightLimit);
  differ(a.coverage_tau, b.coverage_tau, param_field::kCoverageTau);
  differ(a.min_weight, b.min_weight, param_field::kMinWeight);
  differ(a.obstacle_fraction, b.obstacle_fraction, param_field::kObstacleFraction);
  differ(a.max_inclination, b.max_inclination, param_field::kMaxInclination);
  differ(a.kalman_min_variance, b.kalman_min_variance, param_field::kKalmanMinVariance);
  differ(a.normal_variance_threshold, b.normal_variance_threshold, param_field::kNormalVarianceThreshold);
  differ(a.finest_max_sigma_m, b.finest_max_sigma_m, param_field::kFinestMaxSigma);
  differ(a.outlier_gate_sigma, b.outlier_gate_sigma, param_field::kOutlierGateSigma);
  differ(a.change_min_points, b.change_min_points, param_field::kChangeMinPoints);
  differ(a.change_share, b.change_share, param_field::kChangeShare);
  differ(a.frame_point_budget, b.frame_point_budget, param_field::kFramePointBudget);
  differ(a.frame_time_budget_us, b.frame_time_budget_us, param_field::kFrameTimeBudget);
  differ(a.free_space_rays, b.free_space_rays, param_field::kFreeSpaceRays);
  differ(a.free_space_clear_frames, b.free_space_clear_frames, param_field::kFreeSpaceClearFrames);
  differ(a.sensor_view_axis, b.sensor_view_axis, param_field::kSensorViewAxis);
  differ(a.noise, b.noise, param_field::kNoise);
  return mask;
}

}  // namespace ccmap
