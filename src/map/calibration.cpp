#include "ccmap/map/calibration.hpp"

#include <cmath>
#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"

namespace ccmap {

namespace {

Status check_step_inputs(float cell_width_m, float obstacle_height_m, float coverage,
                         int samples_per_axis, float noise_sigma_m) noexcept {
  if (!std::isfinite(cell_width_m) || !std::isfinite(obstacle_height_m) ||
      !std::isfinite(coverage) || !std::isfinite(noise_sigma_m)) {
    return Status::kNonFiniteInput;
  }
  if (!(cell_width_m > 0.0F) || !(obstacle_height_m > 0.0F) || coverage < 0.0F ||
      coverage > 1.0F || noise_sigma_m < 0.0F || samples_per_axis < 2 ||
      samples_per_axis > kCalibrationMaxSamplesPerAxis) {
    return Status::kInvalidArgument;
  }
  if (cell_width_m > kCalibrationMaxLengthM || obstacle_height_m > kCalibrationMaxLengthM ||
      noise_sigma_m > kCalibrationMaxLengthM) {
    return Status::kOutOfRange;
  }
  return Status::kOk;
}

/// murmur3's 32-bit finaliser: a bijection on uint32 with full avalanche.
std::uint32_t mix32(std::uint32_t v) noexcept {
  v ^= v >> 16U;
  v *= 0x85EBCA6BU;
  v ^= v >> 13U;
  v *= 0xC2B2AE35U;
  v ^= v >> 16U;
  return v;
}

/// Deterministic, approximately standard-normal variate for grid position `index`: the sum of
/// 12 uniforms in [0, 1) minus 6 (Irwin-Hall: mean 0, variance 1, bounded by +-6). Draw k of
/// position i hashes the distinct counter 12 i + k, so positions are independent. Integer
/// hashing and float sums only: the same value on every target (no libm).
float grid_noise(std::uint32_t index) noexcept {
  float sum = 0.0F;
  for (std::uint32_t k = 0U; k < 12U; ++k) {
    const std::uint32_t bits = mix32((index * 12U + k) * 0x9E3779B9U + 0x6A09E667U);
    sum += static_cast<float>(bits >> 8U) * (1.0F / 16777216.0F);  // 24 bits -> [0, 1)
  }
  return sum - 6.0F;
}

}  // namespace

float step_normal_variance(float cell_width_m, float obstacle_height_m, float coverage,
                           int samples_per_axis, float noise_sigma_m) noexcept {
  if (check_step_inputs(cell_width_m, obstacle_height_m, coverage, samples_per_axis,
                        noise_sigma_m) != Status::kOk) {
    return -1.0F;
  }
  const int n = samples_per_axis;
  const float half = 0.5F * cell_width_m;
  const float column = cell_width_m / static_cast<float>(n);  // n >= 2
  const float edge_x = half - coverage * cell_width_m;         // the step occupies x > edge_x
  // The paper cell, for both cell kinds: every column holds the same symmetric rows, so x and y
  // are uncorrelated (s_xy = 0 in exact arithmetic) and the full cell's normal variance equals
  // eq. (11); the paper cell evaluates it without the rounding noise of a computed s_xy, so a
  // paper-cell stack keeps its published thresholds bit for bit (docs/design.md, "Thresholds").
  CcmPaperCell cell{};
  for (int i = 0; i < n; ++i) {
    const float x_lo = -half + static_cast<float>(i) * column;
    const float x_hi = (i + 1 == n) ? half : x_lo + column;
    // One or two (x, z, weight) pieces per column: the cut column is split at the edge.
    float piece_x[2] = {0.5F * (x_lo + x_hi), 0.0F};
    float piece_z[2] = {0.0F, obstacle_height_m};
    float piece_w[2] = {1.0F, 0.0F};
    if (x_lo >= edge_x) {
      piece_z[0] = obstacle_height_m;  // whole column on the step
    } else if (x_hi > edge_x) {
      const float on_share = (x_hi - edge_x) / (x_hi - x_lo);  // in (0, 1); x_hi > x_lo
      piece_x[0] = 0.5F * (x_lo + edge_x);
      piece_w[0] = 1.0F - on_share;
      piece_x[1] = 0.5F * (edge_x + x_hi);
      piece_w[1] = on_share;
    }
    for (int j = 0; j < n; ++j) {
      const float y = -half + (static_cast<float>(j) + 0.5F) * column;
      const float noise =
          noise_sigma_m > 0.0F
              ? noise_sigma_m * grid_noise(static_cast<std::uint32_t>(i * n + j))
              : 0.0F;
      for (int p = 0; p < 2; ++p) {
        if (piece_w[p] > 0.0F) {
          if (ccm_update(cell, piece_x[p], y, piece_z[p] + noise, piece_w[p], kNoWeightLimit) !=
              Status::kOk) {
            return -1.0F;  // unreachable with the checked inputs
          }
        }
      }
    }
  }
  return ccm_surface(cell).normal_variance;  // eq. (11), >= 0
}

Status calibrate_normal_variance_threshold(float cell_width_m, float obstacle_height_m,
                                           ThresholdCalibration* out, float coverage,
                                           int samples_per_axis, float noise_sigma_m) noexcept {
  const Status input_status = check_step_inputs(cell_width_m, obstacle_height_m, coverage,
                                                samples_per_axis, noise_sigma_m);
  if (input_status != Status::kOk) {
    return input_status;
  }
  if (out == nullptr) {
    return Status::kInvalidArgument;
  }
  const float threshold = step_normal_variance(cell_width_m, obstacle_height_m, coverage,
                                               samples_per_axis, noise_sigma_m);
  if (!(threshold >= 0.0F)) {
    return Status::kInvalidArgument;  // unreachable with the checked inputs
  }
  const auto reaches = [&](float c) noexcept {
    return step_normal_variance(cell_width_m, obstacle_height_m, c, samples_per_axis,
                                noise_sigma_m) >= threshold;
  };
  const auto sweep_coverage = [](int k) noexcept {
    return static_cast<float>(k) / static_cast<float>(kCalibrationSweepSteps);
  };

  // Coarse sweep c_k = k / 100.
  bool flagged[kCalibrationSweepSteps + 1];
  int first = -1;
  int last = -1;
  for (int k = 0; k <= kCalibrationSweepSteps; ++k) {
    flagged[k] = reaches(sweep_coverage(k));
    if (flagged[k]) {
      if (first < 0) {
        first = k;
      }
      last = k;
    }
  }

  float from = coverage;  // the calibration coverage reaches its own threshold
  float to = coverage;
  if (first >= 0) {
    // Rising edge between c_{first-1} (below) and c_first (reaches).
    float edge_from = 0.0F;
    if (first > 0) {
      float lo = sweep_coverage(first - 1);
      float hi = sweep_coverage(first);
      for (int step = 0; step < kCalibrationBisectionSteps; ++step) {
        const float mid = 0.5F * (lo + hi);
        if (reaches(mid)) {
          hi = mid;
        } else {
          lo = mid;
        }
      }
      edge_from = hi;
    }
    // Falling edge between c_last (reaches) and c_{last+1} (below).
    float edge_to = 1.0F;
    if (last < kCalibrationSweepSteps) {
      float lo = sweep_coverage(last);
      float hi = sweep_coverage(last + 1);
      for (int step = 0; step < kCalibrationBisectionSteps; ++step) {
        const float mid = 0.5F * (lo + hi);
        if (reaches(mid)) {
          lo = mid;
        } else {
          hi = mid;
        }
      }
      edge_to = lo;
    }
    from = edge_from < from ? edge_from : from;
    to = edge_to > to ? edge_to : to;
  }

  bool contiguous = true;
  for (int k = 0; k <= kCalibrationSweepSteps; ++k) {
    const float c = sweep_coverage(k);
    if (c >= from && c <= to && !flagged[k]) {
      contiguous = false;
    }
  }

  out->threshold = threshold;
  out->detect_from_coverage = from;
  out->detect_to_coverage = to;
  out->interval_is_contiguous = contiguous;
  return Status::kOk;
}

}  // namespace ccmap
