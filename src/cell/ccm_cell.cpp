// Out-of-line CCM cell functions (include/ccmap/cell/ccm_cell.hpp): one template per function,
// the lateral covariance s_xy compiled in for CcmCell and out for CcmPaperCell, and the public
// overloads of both cell types forwarding to it.
#include "ccmap/cell/ccm_cell.hpp"

#include <limits>

namespace ccmap {

namespace {

template <typename Cell>
Status merge(Cell& cell, const Cell& other, float weight_limit) noexcept {
  if (ccm_check_weight_limit(weight_limit) != Status::kOk) {
    return Status::kInvalidArgument;
  }
  if (!std::isfinite(other.weight) || other.weight < 0.0F) {
    return Status::kBadWeight;
  }
  if (!(other.weight > 0.0F)) {
    return Status::kOk;  // nothing to merge
  }
  const float weight = cell.weight + other.weight;
  const float share = other.weight / weight;                // W_b / W
  const float dx = other.mean_x - cell.mean_x;
  const float dy = other.mean_y - cell.mean_y;
  const float dz = other.mean_z - cell.mean_z;
  const float k = cell.weight * share;                      // W_a * W_b / W
  cell.mean_x += dx * share;
  cell.mean_y += dy * share;
  cell.mean_z += dz * share;
  cell.s_xx += other.s_xx + k * dx * dx;
  cell.s_yy += other.s_yy + k * dy * dy;
  cell.s_zz += other.s_zz + k * dz * dz;
  cell.s_xz += other.s_xz + k * dx * dz;
  cell.s_yz += other.s_yz + k * dy * dz;
  if constexpr (kHasLateralCovariance<Cell>) {
    cell.s_xy += other.s_xy + k * dx * dy;
  }
  cell.weight = weight;
  ccm_apply_weight_limit(cell, weight_limit);
  return Status::kOk;
}

template <typename Cell>
Status unmerge(const Cell& total, const Cell& part, Cell* rest) noexcept {
  bool done = false;
  const Status start = detail::unmerge_start(total, part, rest, &done);
  if (start != Status::kOk || done) {
    return start;
  }
  const float weight = total.weight - part.weight;  // W_r
  if (!(weight > 0.0F)) {
    return Status::kBadWeight;
  }
  const float ratio = part.weight / weight;  // W_p / W_r
  Cell out{};
  out.weight = weight;
  out.mean_x = total.mean_x + (total.mean_x - part.mean_x) * ratio;
  out.mean_y = total.mean_y + (total.mean_y - part.mean_y) * ratio;
  out.mean_z = total.mean_z + (total.mean_z - part.mean_z) * ratio;
  const float dx = out.mean_x - part.mean_x;  // d = mu_r - mu_p
  const float dy = out.mean_y - part.mean_y;
  const float dz = out.mean_z - part.mean_z;
  const float k = part.weight * (weight / total.weight);  // W_p W_r / W_t
  const float s_xx = total.s_xx - part.s_xx - k * dx * dx;
  const float s_yy = total.s_yy - part.s_yy - k * dy * dy;
  const float s_zz = total.s_zz - part.s_zz - k * dz * dz;
  out.s_xx = s_xx > 0.0F ? s_xx : 0.0F;
  out.s_yy = s_yy > 0.0F ? s_yy : 0.0F;
  out.s_zz = s_zz > 0.0F ? s_zz : 0.0F;
  out.s_xz = total.s_xz - part.s_xz - k * dx * dz;
  out.s_yz = total.s_yz - part.s_yz - k * dy * dz;
  if constexpr (kHasLateralCovariance<Cell>) {
    out.s_xy = total.s_xy - part.s_xy - k * dx * dy;
  }
  *rest = out;
  return Status::kOk;
}

bool batch_point_usable(const float* x, const float* y, const float* z, const float* weights,
                        float constant_weight, std::size_t i, CcmBatchCounts* counts) noexcept {
  const Status point_status = ccm_check_point(x[i], y[i], z[i]);
  if (point_status != Status::kOk) {
    if (counts != nullptr) {
      if (point_status == Status::kNonFiniteInput) {
        ++counts->rejected_non_finite;
      } else {
        ++counts->rejected_out_of_range;
      }
    }
    return false;
  }
  const float w = weights != nullptr ? weights[i] : constant_weight;
  if (ccm_check_weight(w) != Status::kOk) {
    if (counts != nullptr) {
      ++counts->rejected_weight;
    }
    return false;
  }
  return true;
}

template <typename Cell>
CcmBatchCounts update_batch(Cell& cell, const float* x, const float* y, const float* z, const float* weights,
                            float constant_weight, std::size_t n, float weight_limit) noexcept {
  CcmBatchCounts counts{0U, 0U, 0U, 0U};
  if (x == nullptr || y == nullptr || z == nullptr || n == 0U ||
      ccm_check_weight_limit(weight_limit) != Status::kOk) {
    return counts;
  }
  // Pass 1: weighted mean of the batch.
  float sum_w = 0.0F;
  float sum_x = 0.0F;
  float sum_y = 0.0F;
  float sum_z = 0.0F;
  for (std::size_t i = 0; i < n; ++i) {
    if (!batch_point_usable(x, y, z, weights, constant_weight, i, &counts)) {
      continue;
    }
    const float w = weights != nullptr ? weights[i] : constant_weight;
    ++counts.accepted;
    sum_w += w;
    sum_x += w * x[i];
    sum_y += w * y[i];
    sum_z += w * z[i];
  }
  if (counts.accepted == 0U || !(sum_w > 0.0F) || !std::isfinite(sum_w)) {
    counts.accepted = 0U;
    return counts;
  }
  Cell batch{};
  batch.weight = sum_w;
  batch.mean_x = sum_x / sum_w;
  batch.mean_y = sum_y / sum_w;
  batch.mean_z = sum_z / sum_w;
  // Pass 2: co-moments about the batch mean (no cancellation of large products).
  for (std::size_t i = 0; i < n; ++i) {
    if (!batch_point_usable(x, y, z, weights, constant_weight, i, nullptr)) {
      continue;
    }
    const float w = weights != nullptr ? weights[i] : constant_weight;
    const float dx = x[i] - batch.mean_x;
    const float dy = y[i] - batch.mean_y;
    const float dz = z[i] - batch.mean_z;
    batch.s_xx += w * dx * dx;
    batch.s_yy += w * dy * dy;
    batch.s_zz += w * dz * dz;
    batch.s_xz += w * dx * dz;
    batch.s_yz += w * dy * dz;
    if constexpr (kHasLateralCovariance<Cell>) {
      batch.s_xy += w * dx * dy;
    }
  }
  if (merge(cell, batch, weight_limit) != Status::kOk) {
    counts.accepted = 0U;
  }
  return counts;
}

template <typename Cell>
float elevation_variance(const Cell& cell, const CcmSurface& surface, float qx, float qy) noexcept {
  if (!(cell.weight > 0.0F)) {
    return 0.0F;
  }
  const float var_xx = cell.s_xx / cell.weight;
  const float var_yy = cell.s_yy / cell.weight;
  const float ox = qx - cell.mean_x;
  const float oy = qy - cell.mean_y;
  float leverage = 1.0F;
  if constexpr (kHasLateralCovariance<Cell>) {
    // d^T Sigma^+ d with the inverse the slopes use (ccm_surface).
    const detail::LateralInverse inv = detail::lateral_inverse(var_xx, var_yy, cell.s_xy / cell.weight);
    const float quadratic = inv.xx * ox * ox + 2.0F * inv.xy * ox * oy + inv.yy * oy * oy;
    leverage += quadratic > 0.0F ? quadratic : 0.0F;  // >= 0 in real arithmetic (PSD)
  } else {
    if (var_xx > kMinLateralVariance) {
      leverage += ox * ox / var_xx;
    }
    if (var_yy > kMinLateralVariance) {
      leverage += oy * oy / var_yy;
    }
  }
  // A tiny W (subnormal weights or weight limit) can overflow leverage / W: the plane is then
  // unconstrained, so the variance saturates at FLT_MAX instead of becoming Inf (or NaN as
  // 0 * Inf when the residual is 0).
  constexpr float kMax = std::numeric_limits<float>::max();
  float factor = 1.0F + leverage / cell.weight;
  factor = factor <= kMax ? factor : kMax;
  const float variance = surface.normal_variance * factor;
  return variance <= kMax ? variance : kMax;
}

template <typename Cell>
Cell pool4(const Cell children[4], float child_width_m, float weight_limit) noexcept {
  Cell out{};
  if (children == nullptr || !(child_width_m > 0.0F) || !std::isfinite(child_width_m) ||
      ccm_check_weight_limit(weight_limit) != Status::kOk) {
    return out;
  }
  const float half = 0.5F * child_width_m;
  float shifted_x[4] = {};
  float shifted_y[4] = {};
  bool observed[4] = {};
  float count = 0.0F;
  float total_weight = 0.0F;
  float mean_x = 0.0F;
  float mean_y = 0.0F;
  float mean_z = 0.0F;
  for (int i = 0; i < 4; ++i) {
    const Cell& child = children[i];
    observed[i] = child.weight > 0.0F && std::isfinite(child.weight);
    if (!observed[i]) {
      continue;
    }
    shifted_x[i] = child.mean_x + ((i & 1) != 0 ? half : -half);
    shifted_y[i] = child.mean_y + ((i & 2) != 0 ? half : -half);
    count += 1.0F;
    total_weight += child.weight;
    mean_x += shifted_x[i];                                   // eq. (13)
    mean_y += shifted_y[i];
    mean_z += child.mean_z;
  }
  if (!(count > 0.0F)) {
    return out;
  }
  const float inv_count = 1.0F / count;
  mean_x *= inv_count;
  mean_y *= inv_count;
  mean_z *= inv_count;
  float var_xx = 0.0F;
  float var_yy = 0.0F;
  float var_zz = 0.0F;
  float cov_xz = 0.0F;
  float cov_yz = 0.0F;
  float cov_xy = 0.0F;  // the between-children term always; the children's own in the full cell
  for (int i = 0; i < 4; ++i) {
    if (!observed[i]) {
      continue;
    }
    const Cell& child = children[i];
    const float inv_w = 1.0F / child.weight;
    const float dx = shifted_x[i] - mean_x;
    const float dy = shifted_y[i] - mean_y;
    const float dz = child.mean_z - mean_z;
    var_xx += child.s_xx * inv_w + dx * dx;                   // eq. (14)
    var_yy += child.s_yy * inv_w + dy * dy;
    var_zz += child.s_zz * inv_w + dz * dz;
    cov_xz += child.s_xz * inv_w + dx * dz;                   // eq. (15)
    cov_yz += child.s_yz * inv_w + dy * dz;
    if constexpr (kHasLateralCovariance<Cell>) {
      cov_xy += child.s_xy * inv_w + dx * dy;
    } else {
      cov_xy += dx * dy;
    }
  }
  if constexpr (!kHasLateralCovariance<Cell>) {
    // The paper cell has no place for cov_xy: store the parent's least-squares plane (the full
    // cell's solve on the pooled moments) in the form eqs. (9) and (11) read, so that neither
    // slope nor normal variance picks up the cross term (ccm_pool4's contract in the header).
    // Sums over n children: the solve is scale-invariant, the residual scales with n.
    const detail::LateralInverse inv = detail::lateral_inverse(var_xx, var_yy, cov_xy);
    const float a = inv.xx * cov_xz + inv.xy * cov_yz;
    const float b = inv.xy * cov_xz + inv.yy * cov_yz;
    float residual = var_zz - a * cov_xz - b * cov_yz;
    residual = residual > 0.0F ? residual : 0.0F;
    cov_xz = a * var_xx;
    cov_yz = b * var_yy;
    var_zz = residual + a * cov_xz + b * cov_yz;
  }
  out.weight = total_weight;
  out.mean_x = mean_x;
  out.mean_y = mean_y;
  out.mean_z = mean_z;
  const float scale = total_weight * inv_count;               // S = W * sigma^2
  out.s_xx = var_xx * scale;
  out.s_yy = var_yy * scale;
  out.s_zz = var_zz * scale;
  out.s_xz = cov_xz * scale;
  out.s_yz = cov_yz * scale;
  if constexpr (kHasLateralCovariance<Cell>) {
    out.s_xy = cov_xy * scale;
  }
  ccm_apply_weight_limit(out, weight_limit);
  return out;
}

}  // namespace

Status ccm_merge(CcmCell& cell, const CcmCell& other, float weight_limit) noexcept {
  return merge(cell, other, weight_limit);
}
Status ccm_merge(CcmPaperCell& cell, const CcmPaperCell& other, float weight_limit) noexcept {
  return merge(cell, other, weight_limit);
}

Status ccm_unmerge(const CcmCell& total, const CcmCell& part, CcmCell* rest) noexcept {
  return unmerge(total, part, rest);
}
Status ccm_unmerge(const CcmPaperCell& total, const CcmPaperCell& part, CcmPaperCell* rest) noexcept {
  return unmerge(total, part, rest);
}

CcmBatchCounts ccm_update_batch(CcmCell& cell, const float* x, const float* y, const float* z, const float* weights,
                                float constant_weight, std::size_t n, float weight_limit) noexcept {
  return update_batch(cell, x, y, z, weights, constant_weight, n, weight_limit);
}
CcmBatchCounts ccm_update_batch(CcmPaperCell& cell, const float* x, const float* y, const float* z,
                                const float* weights, float constant_weight, std::size_t n,
                                float weight_limit) noexcept {
  return update_batch(cell, x, y, z, weights, constant_weight, n, weight_limit);
}

float ccm_elevation_variance(const CcmCell& cell, const CcmSurface& surface, float qx, float qy) noexcept {
  return elevation_variance(cell, surface, qx, qy);
}
float ccm_elevation_variance(const CcmPaperCell& cell, const CcmSurface& surface, float qx, float qy) noexcept {
  return elevation_variance(cell, surface, qx, qy);
}

CcmCell ccm_pool4(const CcmCell children[4], float child_width_m, float weight_limit) noexcept {
  return pool4(children, child_width_m, weight_limit);
}
CcmPaperCell ccm_pool4(const CcmPaperCell children[4], float child_width_m, float weight_limit) noexcept {
  return pool4(children, child_width_m, weight_limit);
}

template <typename Cell>
Cell ccm_from_constant(float height, float variance, float weight, float cell_width_m) noexcept {
  static_assert(kIsCcmCell<Cell>, "ccm_from_constant makes a CcmCell or a CcmPaperCell");
  // cell_width_m is only validated: the constant cell is a sample at its centre (header).
  Cell out{};
  if (!(weight > 0.0F) || !std::isfinite(weight) || !std::isfinite(height) ||
      !std::isfinite(variance) || !(cell_width_m > 0.0F) || !std::isfinite(cell_width_m)) {
    return out;
  }
  out.weight = weight;
  out.mean_z = height;
  out.s_zz = (variance > 0.0F ? variance : 0.0F) * weight;
  return out;
}
template CcmCell ccm_from_constant<CcmCell>(float, float, float, float) noexcept;
template CcmPaperCell ccm_from_constant<CcmPaperCell>(float, float, float, float) noexcept;

}  // namespace ccmap
