#include "ccmap/map/detail/front.hpp"

#include <cmath>

namespace ccmap::detail {
namespace {

/// round(v * 2^frac_bits) (half away from zero) of a finite float with |v * 2^frac_bits| < 2^62,
/// exact, in integer operations. Per-frame constants only (not the per-point path).
std::int64_t fixed_round(float v, int frac_bits) noexcept {
  const std::uint32_t bits = bits_of(v);
  const std::uint32_t biased = (bits >> 23) & 0xFFU;
  const std::int64_t significand = static_cast<std::int64_t>((bits & 0x7FFFFFU) | (biased != 0U ? 0x800000U : 0U));
  const std::int32_t exponent = static_cast<std::int32_t>(biased) + (biased == 0U ? 1 : 0);
  // v * 2^frac = significand * 2^(exponent - 150 + frac)
  const std::int32_t up = exponent - 150 + frac_bits;
  std::int64_t magnitude = 0;
  if (up >= 0) {
    magnitude = significand << up;  // precondition: < 2^62
  } else if (up > -63) {
    const std::int32_t down = -up;
    magnitude = (significand + (std::int64_t{1} << (down - 1))) >> down;
  }
  return (bits >> 31) != 0U ? -magnitude : magnitude;
}

}  // namespace

Status make_front_config(float finest_width_m, const float* max_range_sq_m2, int layers, FrontConfig* out) noexcept {
  if (out == nullptr || max_range_sq_m2 == nullptr || layers < 1 || layers > kFrontMaxLayers ||
      !(finest_width_m > 0.0F) || !std::isfinite(finest_width_m)) {
    return Status::kInvalidArgument;
  }
  const float inv_w0 = 1.0F / finest_width_m;  // the value RingGrid::init computes
  // Index of |x| <= kMaxAbsCoordinateM within +-2^30, and the product q18 * mult below 2^63:
  // 1/w_0 in [1e-3, 2^30 / 1e5]; validate_stack_params accepts only widths inside.
  if (!(inv_w0 >= 1.0e-3F) || !(inv_w0 * kMaxAbsCoordinateM < 1073741824.0F)) {
    return Status::kInvalidArgument;
  }
  FrontConfig f{};
  const std::uint32_t inv_bits = bits_of(inv_w0);
  f.index_mult = static_cast<std::int64_t>((inv_bits & 0x7FFFFFU) | 0x800000U);
  // q * 2^-18 * mult * 2^(e - 150) = (q * mult) * 2^-(168 - e)
  f.index_shift = 168 - static_cast<std::int32_t>((inv_bits >> 23) & 0xFFU);
  for (std::int64_t& bound : f.max_range_sq) {
    bound = INT64_MAX;
  }
  for (int k = 0; k < layers; ++k) {
    const float units = max_range_sq_m2[k] * 4294967296.0F;  // m^2 -> 2^-32 m^2 (exact scale)
    // A bound beyond int64 (including the +inf of an unbounded model) never refuses.
    f.max_range_sq[k] = !(units < 9.0e18F) ? INT64_MAX : static_cast<std::int64_t>(units);
  }
  f.layers = static_cast<std::uint32_t>(layers);
  *out = f;
  return Status::kOk;
}

Status make_frame_pose(const PointXYZ& origin, const float* rotation_row_major, FramePose* out) noexcept {
  if (out == nullptr) {
    return Status::kInvalidArgument;
  }
  const Status origin_status = ccm_check_point(origin.x, origin.y, origin.z);
  if (origin_status != Status::kOk) {
    return origin_status;
  }
  FramePose pose{};
  const float o[3] = {origin.x, origin.y, origin.z};
  for (int a = 0; a < 3; ++a) {
    pose.origin_q18[a] = q18_floor(bits_of(o[a]));
    pose.translation_q18[a] = fixed_round(o[a], kPositionFracBits);
  }
  if (rotation_row_major != nullptr) {
    const float* r = rotation_row_major;
    for (int i = 0; i < 9; ++i) {
      if (!std::isfinite(r[i])) {
        return Status::kNonFiniteInput;
      }
      if (std::fabs(r[i]) > 1.001F) {
        return Status::kInvalidArgument;
      }
    }
    // R^T R = I within 1e-3: a rigid transform, not a scaling or shear (the Q30 format and the
    // range taken in the sensor frame assume it).
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const float dot = r[i] * r[j] + r[3 + i] * r[3 + j] + r[6 + i] * r[6 + j];
        const float expected = i == j ? 1.0F : 0.0F;
        if (std::fabs(dot - expected) > 1.0e-3F) {
          return Status::kInvalidArgument;
        }
      }
    }
    for (int i = 0; i < 9; ++i) {
      pose.rotation_q30[i] = static_cast<std::int32_t>(fixed_round(r[i], kRotationFracBits));
    }
    for (int row = 0; row < 3; ++row) {
      // Rounding to Q18 (+ half a Q48 -> Q18 step) and the mean of the floor in the Q18
      // conversion of each coordinate (+ half a unit, rotated): unbiased results.
      const std::int64_t row_sum = std::int64_t{pose.rotation_q30[3 * row]} + pose.rotation_q30[3 * row + 1] +
                                   pose.rotation_q30[3 * row + 2];
      pose.rotation_bias_q48[row] = (std::int64_t{1} << (kRotationFracBits - 1)) + (row_sum >> 1);
    }
  }
  *out = pose;
  return Status::kOk;
}

}  // namespace ccmap::detail
