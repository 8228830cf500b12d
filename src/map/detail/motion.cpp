// Uncertainty with motion: the per-cell rules of map/detail/motion.hpp.
#include "ccmap/map/detail/motion.hpp"

#include "ccmap/cell/ccm_cell.hpp"

namespace ccmap::detail {

namespace {
template <typename Cell>
void forget_ccm(Cell& cell, float sigma_sq, float min_weight) noexcept {
  const CcmSurface surface = ccm_surface(cell);
  const float inclination_sq = surface.slope_x * surface.slope_x + surface.slope_y * surface.slope_y;
  if (!(inclination_sq > 0.0F)) {
    return;
  }
  // sigma_s^2 / W' = sigma_s^2 / W + i^2 sigma^2  <=>  W' = W sigma_s^2 / (sigma_s^2 + W i^2 sigma^2).
  // An overflowing product gives W' = 0 (then the floor), never NaN (every factor is > 0).
  const float growth = cell.weight * inclination_sq * sigma_sq;
  const float residual = surface.normal_variance;
  float weight = residual > 0.0F ? cell.weight * (residual / (residual + growth)) : 0.0F;
  // Floor: min(W, min_weight), and never below kMinWeightLimit (subnormal co-moments lose every
  // digit, as the weight limiter's own floor argues).
  float floor = min_weight > kMinWeightLimit ? min_weight : kMinWeightLimit;
  floor = cell.weight < floor ? cell.weight : floor;
  if (!(weight >= floor)) {
    weight = floor;
  }
  if (!(weight < cell.weight)) {
    return;
  }
  ccm_scale_comoments(cell, weight / cell.weight);  // as the limiter, eq. (7): variances unchanged
  cell.weight = weight;
}
}  // namespace

void ccm_forget_for_motion(CcmCell& cell, float sigma_sq, float min_weight) noexcept {
  forget_ccm(cell, sigma_sq, min_weight);
}
void ccm_forget_for_motion(CcmPaperCell& cell, float sigma_sq, float min_weight) noexcept {
  forget_ccm(cell, sigma_sq, min_weight);
}

float grown_variance(float variance, float gx, float gy, float sigma_sq) noexcept {
  const float grown = variance + (gx * gx + gy * gy) * sigma_sq;
  return grown <= kMaxHeightVariance ? grown : kMaxHeightVariance;
}

float neighbour_gradient(bool low_seen, float low, bool high_seen, float high, float h, float w) noexcept {
  if (low_seen && high_seen) {
    return (high - low) / (2.0F * w);
  }
  if (high_seen) {
    return (high - h) / w;
  }
  if (low_seen) {
    return (h - low) / w;
  }
  return 0.0F;
}

}  // namespace ccmap::detail
