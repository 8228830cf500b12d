#include "ccmap/map/classify.hpp"

#include <cmath>

#include "ccmap/map/calibration.hpp"
#include "ccmap/map/stack.hpp"

namespace ccmap {

Status validate_stack_params(const StackParams& p, int layer_count) noexcept {
  const float values[] = {p.finest_cell_width_m, p.coverage_tau,         p.min_weight,
                          p.obstacle_fraction,   p.max_inclination,      p.kalman_min_variance,
                          p.finest_max_sigma_m,  p.outlier_gate_sigma,   p.change_min_points,
                          p.change_share,        p.free_space_rays,      p.free_space_clear_frames,
                          p.sensor_view_axis[0], p.sensor_view_axis[1],  p.sensor_view_axis[2]};
  for (const float v : values) {
    if (!std::isfinite(v)) {
      return Status::kNonFiniteInput;
    }
  }
  for (const float t : p.normal_variance_threshold) {
    if (!std::isfinite(t)) {
      return Status::kNonFiniteInput;
    }
  }
  if (layer_count < 1 || layer_count > kMaxLayers) {
    return Status::kInvalidArgument;
  }
  if (!(p.finest_cell_width_m > 0.0F) || p.finest_cell_width_m * static_cast<float>(1 << (layer_count - 1)) > 100.0F) {
    return Status::kInvalidArgument;
  }
  // Cell indices of positions up to kMaxAbsCoordinateM must stay within +-2^29, so that the
  // window centre move_to snaps to (an even index) and the child index 2 * i used by pooling
  // fit int32 and grid::kMaxCellIndex: width >= 1e5 m / 2^29 = 0.19 mm.
  if (p.finest_cell_width_m * static_cast<float>(1 << 29) < kMaxAbsCoordinateM) {
    return Status::kInvalidArgument;
  }
  if (ccm_check_weight_limit(p.weight_limit) != Status::kOk || !(p.coverage_tau > 0.0F) ||
      p.coverage_tau > 1.0F || p.min_weight < 0.0F || !(p.obstacle_fraction > 0.0F) ||
      p.obstacle_fraction > 4.0F || !(p.max_inclination > 0.0F) || !(p.kalman_min_variance > 0.0F)) {
    return Status::kInvalidArgument;
  }
  // The gate: off (0) or 1 .. 100 standard deviations (below 1 it would hold most good points,
  // above 100 it gates nothing a float cell can tell apart). The change rule: at least one
  // point, a share in (0, 0.5] (above one half no two sides could both be surfaces). Checked
  // with the gate off too, so that switching it on never meets an invalid rule.
  const bool gate_off = p.outlier_gate_sigma >= 0.0F && p.outlier_gate_sigma <= 0.0F;  // 0 (no float ==)
  const bool gate_valid = gate_off || (p.outlier_gate_sigma >= 1.0F && p.outlier_gate_sigma <= 100.0F);
  if (!gate_valid || !(p.change_min_points >= 1.0F) || p.change_min_points > 65535.0F ||
      !(p.change_share > 0.0F) || p.change_share > 0.5F) {
    return Status::kInvalidArgument;
  }
  // Free space: whole numbers of rays (0 = off) and frames.
  if (!(p.free_space_rays >= 0.0F) || p.free_space_rays > 65535.0F ||
      std::floor(p.free_space_rays) < p.free_space_rays || !(p.free_space_clear_frames >= 1.0F) ||
      p.free_space_clear_frames > 255.0F || std::floor(p.free_space_clear_frames) < p.free_space_clear_frames) {
    return Status::kInvalidArgument;
  }
  return p.noise.validate();
}

Status check_position(float x, float y) noexcept {
  if (!std::isfinite(x) || !std::isfinite(y)) {
    return Status::kNonFiniteInput;
  }
  if (std::fabs(x) > kMaxAbsCoordinateM || std::fabs(y) > kMaxAbsCoordinateM) {
    return Status::kOutOfRange;
  }
  return Status::kOk;
}

float layer_threshold(const StackParams& params, int layer, float width) noexcept {
  if (layer >= 0 && layer < kMaxLayers && params.normal_variance_threshold[static_cast<std::size_t>(layer)] > 0.0F) {
    return params.normal_variance_threshold[static_cast<std::size_t>(layer)];
  }
  ThresholdCalibration calibration{};
  if (calibrate_normal_variance_threshold(width, params.obstacle_fraction * width, &calibration) == Status::kOk) {
    return calibration.threshold;
  }
  // Analytic fallback: a step of height h at 50 % coverage leaves sigma_s^2 = h^2 / 16.
  const float h = params.obstacle_fraction * width;
  return h * h * 0.0625F;
}

namespace {
template <typename Cell>
CellClass classify(const Cell& cell, const CcmSurface& surface, float width, const StackParams& params,
                   float threshold) noexcept {
  if (!(cell.weight >= params.min_weight) || !(cell.weight > 0.0F)) {
    return CellClass::kUnknown;
  }
  // Obstacle evidence before coverage: an obstacle's own shadow leaves its border cells partly
  // covered, and eq. (12) would call them unknown although the points that were seen already
  // spread beyond the threshold around their plane (docs/design.md, "Queries and classes").
  if (surface.normal_variance > threshold) {
    return CellClass::kObstacle;
  }
  if (!ccm_is_covered(cell, width, params.coverage_tau, params.min_weight)) {
    return CellClass::kUnknown;
  }
  if (ccm_inclination(surface) > params.max_inclination) {
    return CellClass::kSteep;
  }
  return CellClass::kTraversable;
}
}  // namespace

CellClass classify_ccm(const CcmCell& cell, float width, const StackParams& params, float threshold) noexcept {
  return classify(cell, ccm_surface(cell), width, params, threshold);
}
CellClass classify_ccm(const CcmPaperCell& cell, float width, const StackParams& params, float threshold) noexcept {
  return classify(cell, ccm_surface(cell), width, params, threshold);
}
CellClass classify_ccm(const CcmCell& cell, const CcmSurface& surface, float width, const StackParams& params,
                       float threshold) noexcept {
  return classify(cell, surface, width, params, threshold);
}
CellClass classify_ccm(const CcmPaperCell& cell, const CcmSurface& surface, float width, const StackParams& params,
                       float threshold) noexcept {
  return classify(cell, surface, width, params, threshold);
}

}  // namespace ccmap
