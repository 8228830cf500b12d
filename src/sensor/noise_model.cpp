#include "ccmap/sensor/noise_model.hpp"

#include <cmath>
#include <limits>

namespace ccmap::sensor {

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kMaxFinite = std::numeric_limits<float>::max();

/// True for a finite value >= 0 (false for NaN, negative, +inf).
bool finite_non_negative(float v) noexcept { return v >= 0.0F && v <= kMaxFinite; }
}  // namespace

NoiseModel NoiseModel::stereo(const StereoParams& params) noexcept {
  NoiseModel model;
  model.kind_ = SensorKind::kStereo;
  if (!std::isfinite(params.focal_px) || !std::isfinite(params.baseline_m) ||
      !std::isfinite(params.disparity_sigma_px)) {
    model.param_state_ = ParamState::kNonFinite;
  } else if (!(params.focal_px > 0.0F) || !(params.baseline_m > 0.0F) ||
             !(params.disparity_sigma_px >= 0.0F)) {
    model.param_state_ = ParamState::kInvalid;
  } else {
    // k = sigma_d / (f * b) (1/m). f * b can underflow to 0 for absurd inputs: k is then
    // not finite and the model is refused. An overflow of f * b gives k = 0 (noise-free).
    const float k = params.disparity_sigma_px / (params.focal_px * params.baseline_m);
    if (std::isfinite(k)) {
      model.stereo_k_ = k;
      model.param_state_ = ParamState::kOk;
    } else {
      model.param_state_ = ParamState::kInvalid;
    }
  }
  model.set_weight_mode(WeightMode::kConstant);
  return model;
}

NoiseModel NoiseModel::lidar(const LidarParams& params) noexcept {
  NoiseModel model;
  model.kind_ = SensorKind::kLidar;
  if (!std::isfinite(params.sigma0_m) || !std::isfinite(params.sigma_per_m)) {
    model.param_state_ = ParamState::kNonFinite;
  } else if (!(params.sigma0_m >= 0.0F) || !(params.sigma_per_m >= 0.0F)) {
    model.param_state_ = ParamState::kInvalid;
  } else {
    model.lidar_sigma0_m_ = params.sigma0_m;
    model.lidar_sigma_per_m_ = params.sigma_per_m;
    model.param_state_ = ParamState::kOk;
  }
  model.set_weight_mode(WeightMode::kConstant);
  return model;
}

Status NoiseModel::param_status() const noexcept {
  switch (param_state_) {
    case ParamState::kOk: return Status::kOk;
    case ParamState::kNonFinite: return Status::kNonFiniteInput;
    case ParamState::kInvalid: return Status::kInvalidArgument;
    case ParamState::kUnset: break;
  }
  return Status::kNotInitialised;
}

Status NoiseModel::validate() const noexcept {
  const Status params = param_status();
  return params != Status::kOk ? params : weight_status_;
}

void NoiseModel::set_weight_mode(WeightMode mode, float reference_range_m) noexcept {
  weight_mode_ = mode;
  reference_range_m_ = reference_range_m;
  reference_sigma_m_ = 0.0F;
  if (mode == WeightMode::kConstant) {
    weight_status_ = Status::kOk;
    return;
  }
  if (mode != WeightMode::kInverseVariance) {
    weight_status_ = Status::kInvalidArgument;  // a value outside the enum
    return;
  }
  if (!std::isfinite(reference_range_m)) {
    weight_status_ = Status::kNonFiniteInput;
    return;
  }
  if (!(reference_range_m > 0.0F)) {
    weight_status_ = Status::kInvalidArgument;
    return;
  }
  // sigma_ref from r_ref^2 exactly as weight_at_range_sq computes sigma, so that a point at
  // the reference range weighs exactly 1.
  const float sigma_ref = sigma_at_range_sq(reference_range_m * reference_range_m);
  if (!(sigma_ref > 0.0F) || !(sigma_ref <= kMaxFinite)) {
    // A noise-free model (or r_ref^2 overflowing) has nothing to normalise by.
    weight_status_ = param_state_ == ParamState::kOk ? Status::kInvalidArgument : Status::kOk;
    return;
  }
  reference_sigma_m_ = sigma_ref;
  weight_status_ = Status::kOk;
}

float NoiseModel::sigma_at_range_sq(float range_sq_m2) const noexcept {
  if (param_state_ != ParamState::kOk || !finite_non_negative(range_sq_m2)) {
    return kInf;
  }
  if (kind_ == SensorKind::kStereo) {
    return stereo_k_ * range_sq_m2;  // sigma = k * r^2 (may overflow to +inf: conservative)
  }
  return lidar_sigma0_m_ + lidar_sigma_per_m_ * std::sqrt(range_sq_m2);  // sigma0 + s * r
}

float NoiseModel::sigma_at_range(float range_m) const noexcept {
  if (param_state_ != ParamState::kOk || !finite_non_negative(range_m)) {
    return kInf;
  }
  if (kind_ == SensorKind::kStereo) {
    return sigma_at_range_sq(range_m * range_m);
  }
  return lidar_sigma0_m_ + lidar_sigma_per_m_ * range_m;
}

float NoiseModel::max_range_sq_for_sigma(float sigma_m) const noexcept {
  if (param_state_ != ParamState::kOk || !(sigma_m >= 0.0F)) {
    return 0.0F;
  }
  if (kind_ == SensorKind::kStereo) {
    if (!(stereo_k_ > 0.0F)) {
      return kInf;  // noise-free stereo: sigma 0 at every range
    }
    return sigma_m / stereo_k_;  // k * r^2 <= sigma  <=>  r^2 <= sigma / k
  }
  if (sigma_m < lidar_sigma0_m_) {
    return 0.0F;  // below the floor: no range satisfies it
  }
  if (!(lidar_sigma_per_m_ > 0.0F)) {
    return kInf;  // constant noise at or below sigma_m everywhere
  }
  const float range = (sigma_m - lidar_sigma0_m_) / lidar_sigma_per_m_;
  return range * range;
}

float NoiseModel::max_range_for_sigma(float sigma_m) const noexcept {
  if (param_state_ != ParamState::kOk || !(sigma_m >= 0.0F)) {
    return 0.0F;
  }
  if (kind_ == SensorKind::kLidar && sigma_m >= lidar_sigma0_m_ && lidar_sigma_per_m_ > 0.0F) {
    return (sigma_m - lidar_sigma0_m_) / lidar_sigma_per_m_;  // no sqrt round trip
  }
  return std::sqrt(max_range_sq_for_sigma(sigma_m));  // sqrt(inf) = inf, sqrt(0) = 0
}

float NoiseModel::weight_at_range_sq(float range_sq_m2) const noexcept {
  if (weight_mode_ != WeightMode::kInverseVariance || param_state_ != ParamState::kOk ||
      weight_status_ != Status::kOk) {
    return 1.0F;
  }
  const float sigma = sigma_at_range_sq(range_sq_m2);
  if (!(sigma > 0.0F)) {
    return kMaxInverseVarianceWeight;  // sigma 0: stereo at range 0
  }
  // w = (sigma_ref / sigma)^2. The ratio is clamped first to [1e-2, 1e2] (squares 1e-4, 1e4:
  // outside the final bounds, so the result is unchanged) so that the square cannot overflow.
  // sigma = +inf (bad range) gives ratio 0 -> the minimum weight.
  float ratio = reference_sigma_m_ / sigma;
  ratio = ratio < 1.0e-2F ? 1.0e-2F : (ratio > 1.0e2F ? 1.0e2F : ratio);
  const float weight = ratio * ratio;
  if (weight < kMinInverseVarianceWeight) {
    return kMinInverseVarianceWeight;
  }
  return weight > kMaxInverseVarianceWeight ? kMaxInverseVarianceWeight : weight;
}

float max_sigma_for_cell_width(float cell_width_m) noexcept {
  if (!(cell_width_m >= 0.0F)) {
    return 0.0F;
  }
  return cell_width_m * kIvgSigmaPerCellWidth;  // sigma_m <= w / (2 sqrt(12))
}

float min_cell_width_for_sigma(float sigma_m) noexcept {
  if (!(sigma_m >= 0.0F)) {
    return kInf;
  }
  return sigma_m * kIvgCellWidthPerSigma;  // w >= 2 sqrt(12) sigma_m
}

namespace detail {

Status build_routing_table_impl(const NoiseModel& model, const float* cell_widths_m, int layers,
                                bool finest_exempt, float finest_max_sigma_m,
                                float* max_range_sq_out) noexcept {
  if (cell_widths_m == nullptr || max_range_sq_out == nullptr || layers < 1) {
    return Status::kInvalidArgument;
  }
  const Status model_status = model.validate();
  if (model_status != Status::kOk) {
    return model_status;
  }
  for (int k = 0; k < layers; ++k) {
    const float width = cell_widths_m[k];
    if (!std::isfinite(width)) {
      return Status::kNonFiniteInput;
    }
    if (!(width > 0.0F) || (k > 0 && !(width > cell_widths_m[k - 1]))) {
      return Status::kInvalidArgument;  // widths must be > 0 and strictly increasing
    }
  }
  if (finest_exempt) {
    if (std::isnan(finest_max_sigma_m)) {
      return Status::kNonFiniteInput;
    }
    if (!(finest_max_sigma_m > 0.0F)) {
      return Status::kInvalidArgument;
    }
    if (layers >= 2 && !(finest_max_sigma_m < max_sigma_for_cell_width(cell_widths_m[1]))) {
      return Status::kInvalidArgument;  // layer 1 would never receive a point
    }
  }
  // All checks passed: from here on nothing fails, so the output is written whole or not at
  // all. Widths increase strictly and sigma_m(r) is monotone, so the limits are
  // non-decreasing in k (the exempt limit is below layer 1's by the check above).
  for (int k = 0; k < layers; ++k) {
    const float sigma_max = (finest_exempt && k == 0)
                                ? finest_max_sigma_m
                                : max_sigma_for_cell_width(cell_widths_m[k]);  // IV-G
    const float range_sq = model.max_range_sq_for_sigma(sigma_max);
    max_range_sq_out[k] = range_sq > kMaxFinite ? kMaxFinite : range_sq;
  }
  return Status::kOk;
}

}  // namespace detail

NoiseModel cadre_stereo() noexcept { return NoiseModel::stereo(kCadreStereoParams); }

// Compiles the header-only routing code under the core warning wall.
template struct RoutingTable<5>;

}  // namespace ccmap::sensor
