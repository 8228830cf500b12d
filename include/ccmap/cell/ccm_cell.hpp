// Converging Covariance Map (CCM) cell: state, incremental update, batch merge, weight
// limiter, queries and pooling (paper Section IV, eqs. (1)-(15)), for two cell types: CcmCell,
// with the lateral covariance s_xy (the least-squares plane, rotation-invariant coverage; the
// library default), and CcmPaperCell, the paper's 9 floats. Every function takes both; one
// implementation each, the cross term compiled in or out (docs/design.md, "The CCM cell").
//
// Frames and units
//  - x, y are metres relative to the geometric centre of the cell (paper eq. (2):
//    mu_m = [M_x - C_x, M_y - C_y, M_z]); z is metres in the map frame of the owning stack
//    (never absolute world coordinates: see docs/design.md, "Float precision").
//  - Weights are dimensionless; with the default constant weight 1 a weight counts points.
//
// Everything here is float-only, allocation-free, exception-free and O(1) per call (the batch
// functions are O(n) in their input). Bad input is refused with a Status and leaves the cell
// bitwise unchanged.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "ccmap/core/assert.hpp"
#include "ccmap/core/status.hpp"

namespace ccmap {

/// Coordinates beyond this magnitude (metres) are refused: the map is local (a stack spans at
/// most a few hundred metres around its origin) and squares of larger values lose all digits.
inline constexpr float kMaxAbsCoordinateM = 1.0e5F;
/// Largest accepted single measurement weight.
inline constexpr float kMaxMeasurementWeight = 1.0e6F;
/// A lateral variance (m^2) at or below this is degenerate (all points on one line): the
/// inclination along that axis is reported as 0 and the cell is not covered.
inline constexpr float kMinLateralVariance = 1.0e-12F;
/// Weight limit meaning "never limit".
inline constexpr float kNoWeightLimit = std::numeric_limits<float>::infinity();

/// Which CCM cell a map keeps (a compile-time choice of its Config: map/config.hpp).
enum class CcmCellKind : std::uint8_t {
  kPaper = 0,  ///< the paper's 9 floats (Section IV-B): no lateral covariance, eq. (9) per axis
  kFull = 1,   ///< 10 floats: the full lateral covariance, exact least-squares plane (default)
};

/// The CCM cell with the full lateral covariance (10 floats, the library default): the paper's
/// state plus s_xy, so that slopes come from the 2 x 2 least-squares solve and coverage from the
/// smaller eigenvalue of the lateral covariance (docs/design.md, "The CCM cell"). A
/// zero-initialised cell is "never observed". S = W * sigma^2 (the co-moments), as in the paper.
/// The first nine floats are laid out as in CcmPaperCell.
struct CcmCell {
  float weight;  ///< W: accumulated measurement weight, 0 = never observed
  float mean_x;  ///< mu_c,x: m, relative to the cell centre
  float mean_y;  ///< mu_c,y: m, relative to the cell centre
  float mean_z;  ///< mu_c,z: m, map frame
  float s_xx;    ///< W * sigma_xx^2  (m^2)
  float s_yy;    ///< W * sigma_yy^2  (m^2)
  float s_zz;    ///< W * sigma_zz^2  (m^2)
  float s_xz;    ///< W * sigma_xz^2  (m^2)
  float s_yz;    ///< W * sigma_yz^2  (m^2)
  float s_xy;    ///< W * sigma_xy^2  (m^2): the lateral covariance the paper leaves out
};
static_assert(sizeof(CcmCell) == 10U * sizeof(float), "CcmCell must stay 10 packed floats");

/// The paper's 9 floats of one CCM cell (Section IV-B): no xy covariance, so slopes follow
/// eq. (9) per axis and coverage eq. (12) per axis, exact only where x and y are uncorrelated
/// in the cell. Kept so that the paper's experiments can be run as published.
struct CcmPaperCell {
  float weight;  ///< W: accumulated measurement weight, 0 = never observed
  float mean_x;  ///< mu_c,x: m, relative to the cell centre
  float mean_y;  ///< mu_c,y: m, relative to the cell centre
  float mean_z;  ///< mu_c,z: m, map frame
  float s_xx;    ///< W * sigma_xx^2  (m^2)
  float s_yy;    ///< W * sigma_yy^2  (m^2)
  float s_zz;    ///< W * sigma_zz^2  (m^2)
  float s_xz;    ///< W * sigma_xz^2  (m^2)
  float s_yz;    ///< W * sigma_yz^2  (m^2)
};
static_assert(sizeof(CcmPaperCell) == 9U * sizeof(float), "CcmPaperCell must stay 9 packed floats");

/// The cell type of a kind.
template <CcmCellKind Kind>
using CcmCellOf = std::conditional_t<Kind == CcmCellKind::kFull, CcmCell, CcmPaperCell>;

/// True for the two CCM cell types.
template <typename Cell>
inline constexpr bool kIsCcmCell = std::is_same_v<Cell, CcmCell> || std::is_same_v<Cell, CcmPaperCell>;

/// True for the cell that keeps the lateral covariance s_xy.
template <typename Cell>
inline constexpr bool kHasLateralCovariance = std::is_same_v<Cell, CcmCell>;

namespace detail {
/// Enables a function template for the two CCM cell types only.
template <typename Cell>
using IfCcmCell = std::enable_if_t<kIsCcmCell<Cell>, int>;
}  // namespace detail

/// Result of a batch fold: how many points were used and why the others were refused.
struct CcmBatchCounts {
  std::uint32_t accepted;
  std::uint32_t rejected_non_finite;
  std::uint32_t rejected_out_of_range;
  std::uint32_t rejected_weight;
};

// ---------------------------------------------------------------------------------------------
// Input validation
// ---------------------------------------------------------------------------------------------

/// kOk if (x, y, z) are finite and within kMaxAbsCoordinateM, else the reason.
[[nodiscard]] inline Status ccm_check_point(float x, float y, float z) noexcept {
  if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
    return Status::kNonFiniteInput;
  }
  if (std::fabs(x) > kMaxAbsCoordinateM || std::fabs(y) > kMaxAbsCoordinateM ||
      std::fabs(z) > kMaxAbsCoordinateM) {
    return Status::kOutOfRange;
  }
  return Status::kOk;
}

/// kOk if 0 < w <= kMaxMeasurementWeight (NaN fails), else kBadWeight.
[[nodiscard]] inline Status ccm_check_weight(float w) noexcept {
  return (w > 0.0F && w <= kMaxMeasurementWeight) ? Status::kOk : Status::kBadWeight;
}

/// Smallest accepted weight limit W_l. Below it the limiter scales W and S towards the
/// subnormal range, where their ratio (the variances) loses every digit and can overflow
/// (found by the stack fuzzer with W_l = 5.5e-41).
inline constexpr float kMinWeightLimit = 1.0e-3F;

/// kOk if W_l >= kMinWeightLimit (kNoWeightLimit allowed), else kInvalidArgument (NaN fails).
[[nodiscard]] inline Status ccm_check_weight_limit(float weight_limit) noexcept {
  return weight_limit >= kMinWeightLimit ? Status::kOk : Status::kInvalidArgument;
}

// ---------------------------------------------------------------------------------------------
// Weight limiter, eqs. (6)-(7)
// ---------------------------------------------------------------------------------------------

namespace detail {
/// Scales every co-moment S by `scale` (the caller sets the new weight W = scale * W): the
/// variances S / W and the mean stay, the weight of future measurements relative to the cell
/// grows by 1 / scale. The weight limiter (eq. 7) and the motion fading (map/detail/motion.hpp)
/// both go through here, so every co-moment of the cell (s_xy included in the full cell) is
/// scaled by both.
template <typename Cell, IfCcmCell<Cell> = 0>
inline void ccm_scale_comoments(Cell& cell, float scale) noexcept {
  cell.s_xx *= scale;
  cell.s_yy *= scale;
  cell.s_zz *= scale;
  cell.s_xz *= scale;
  cell.s_yz *= scale;
  if constexpr (kHasLateralCovariance<Cell>) {
    cell.s_xy *= scale;
  }
}
}  // namespace detail

/// If W > W_l: S *= W_l / W (eq. 7, every co-moment, s_xy included), W = W_l (eq. 6). The
/// variances S/W and the mean are unchanged; only the relative weight of future measurements is
/// held at w / W_l. Precondition: weight_limit > 0 (checked by the public update functions); a
/// violation (NaN included) is reported to the assert hook and leaves the cell unchanged.
template <typename Cell, detail::IfCcmCell<Cell> = 0>
inline void ccm_apply_weight_limit(Cell& cell, float weight_limit) noexcept {
  CCMAP_ASSERT_OR_RETURN(weight_limit > 0.0F, );
  if (cell.weight > weight_limit) {
    detail::ccm_scale_comoments(cell, weight_limit / cell.weight);
    cell.weight = weight_limit;
  }
}

// ---------------------------------------------------------------------------------------------
// Incremental update, eqs. (1)-(5)
// ---------------------------------------------------------------------------------------------

namespace detail {
/// The update without input checks: the hot path for callers that validated already.
/// Eq. (4)/(5) in the West/Welford form: with d = mu_m - mu_{c,t-1}, gain = w / W_t and
/// W_{t-1} = W_t - w,
///   S_ij += w * d_i * (mu_m,j - mu_{c,t,j}) = (w * W_{t-1} / W_t) * d_i * d_j = k * d_i * d_j,
/// k = W_{t-1} * gain, which equals the paper's eq. (5) exactly in real arithmetic but adds a
/// small, well conditioned term instead of subtracting large products of means. The full cell
/// adds s_xy in the same form (one more product and sum). Paper cell: 25 float operations and one
/// division; full cell: 27 (+ 5 or 6 multiplications and a division while the limiter engages).
template <typename Cell, IfCcmCell<Cell> = 0>
inline void ccm_update_unchecked(Cell& cell, float x, float y, float z, float w, float weight_limit) noexcept {
  const float previous_weight = cell.weight;
  const float weight = previous_weight + w;             // eq. (1)
  const float gain = w / weight;                        // w_t / W_t, weight > 0
  const float dx = x - cell.mean_x;                     // mu_m - mu_{c,t-1}
  const float dy = y - cell.mean_y;
  const float dz = z - cell.mean_z;
  cell.mean_x += gain * dx;                             // eq. (3)
  cell.mean_y += gain * dy;
  cell.mean_z += gain * dz;
  const float k = previous_weight * gain;               // = w * W_{t-1} / W_t
  const float kdx = k * dx;
  const float kdy = k * dy;
  const float kdz = k * dz;
  cell.s_xx += kdx * dx;                                // eq. (4)
  cell.s_yy += kdy * dy;
  cell.s_zz += kdz * dz;
  cell.s_xz += kdx * dz;                                // eq. (5), stable form
  cell.s_yz += kdy * dz;
  if constexpr (kHasLateralCovariance<Cell>) {
    cell.s_xy += kdx * dy;                              // the same form for the xy covariance
  }
  cell.weight = weight;
  ccm_apply_weight_limit(cell, weight_limit);           // eqs. (6)-(7)
}
}  // namespace detail

/// Folds one measurement (x, y relative to the cell centre, z map frame, weight w) into the
/// cell and applies the limiter. Refused (cell unchanged): non-finite or out-of-range
/// coordinates, bad weight, bad limit.
template <typename Cell, detail::IfCcmCell<Cell> = 0>
[[nodiscard]] inline Status ccm_update(Cell& cell, float x, float y, float z, float w, float weight_limit) noexcept {
  const Status point_status = ccm_check_point(x, y, z);
  if (point_status != Status::kOk) {
    return point_status;
  }
  if (ccm_check_weight(w) != Status::kOk) {
    return Status::kBadWeight;
  }
  if (ccm_check_weight_limit(weight_limit) != Status::kOk) {
    return Status::kInvalidArgument;
  }
  detail::ccm_update_unchecked(cell, x, y, z, w, weight_limit);
  return Status::kOk;
}

// ---------------------------------------------------------------------------------------------
// Batch merge (pairwise merge of Chan, Golub & LeVeque)
// ---------------------------------------------------------------------------------------------

/// Merges the statistics `other` into `cell`:
///   W = W_a + W_b,  d = mu_b - mu_a,  mu = mu_a + d * W_b / W,
///   S_ij = S_a,ij + S_b,ij + d_i * d_j * W_a * W_b / W   (s_xy too in the full cell),
/// then applies the limiter. Both cells must describe the same cell (same centre).
/// An empty `other` leaves `cell` unchanged. Refused: bad limit, or `other` holding a negative
/// or non-finite weight (kBadWeight).
[[nodiscard]] Status ccm_merge(CcmCell& cell, const CcmCell& other, float weight_limit) noexcept;
[[nodiscard]] Status ccm_merge(CcmPaperCell& cell, const CcmPaperCell& other, float weight_limit) noexcept;

namespace detail {
/// The start every unmerge (ccm_, kalman_, omg_unmerge) shares: kInvalidArgument for rest ==
/// nullptr, kBadWeight for a negative or non-finite weight; for an empty part *rest = total and
/// *done = true (nothing to take out). Cell: any cell with a float `weight`.
template <typename Cell>
[[nodiscard]] Status unmerge_start(const Cell& total, const Cell& part, Cell* rest, bool* done) noexcept {
  *done = false;
  if (rest == nullptr) {
    return Status::kInvalidArgument;
  }
  if (!std::isfinite(total.weight) || !std::isfinite(part.weight) || total.weight < 0.0F || part.weight < 0.0F) {
    return Status::kBadWeight;
  }
  if (!(part.weight > 0.0F)) {
    *rest = total;
    *done = true;
  }
  return Status::kOk;
}
}  // namespace detail

/// The inverse of ccm_merge without the limiter: given total = part (+) rest (Chan's merge in
/// real arithmetic), writes rest:
///   W_r = W_t - W_p,  mu_r = mu_t + (mu_t - mu_p) * W_p / W_r,
///   S_r,ij = S_t,ij - S_p,ij - d_i * d_j * W_p * W_r / W_t,  d = mu_r - mu_p,
/// the diagonal clamped at 0 (rounding). An empty `part` gives rest = total. Map exchange uses it
/// to take what a cell gained since it was last sent (persistence/exchange.hpp).
/// Precision: a cancellation. Relative to float rounding of `total`, the error of mu_r grows
/// like W_t / W_r and that of S_r like (W_t / W_r) * S_t / S_r; it is exact only in real
/// arithmetic, and meaningless once the limiter has scaled `total` (the caller must not ask).
/// Refused (*rest untouched): rest == nullptr (kInvalidArgument); a negative or non-finite
/// weight, or W_t <= W_p with a non-empty part: nothing is left (kBadWeight).
/// The full cell's s_xy follows the off-diagonal rule (no clamp).
[[nodiscard]] Status ccm_unmerge(const CcmCell& total, const CcmCell& part, CcmCell* rest) noexcept;
[[nodiscard]] Status ccm_unmerge(const CcmPaperCell& total, const CcmPaperCell& part, CcmPaperCell* rest) noexcept;

/// Folds n points (x[i], y[i] relative to the cell centre, z[i] map frame) into the cell in one
/// step: a two-pass weighted mean/co-moment of the batch followed by ccm_merge. `weights` may
/// be nullptr (every point then weighs `constant_weight`). Invalid points are skipped and
/// counted. Equal to n sequential ccm_update calls within float rounding when the limiter does
/// not engage inside the batch (the limiter acts once, after the merge).
[[nodiscard]] CcmBatchCounts ccm_update_batch(CcmCell& cell, const float* x, const float* y, const float* z,
                                              const float* weights, float constant_weight, std::size_t n,
                                              float weight_limit) noexcept;
[[nodiscard]] CcmBatchCounts ccm_update_batch(CcmPaperCell& cell, const float* x, const float* y, const float* z,
                                              const float* weights, float constant_weight, std::size_t n,
                                              float weight_limit) noexcept;

// ---------------------------------------------------------------------------------------------
// Queries, eqs. (8)-(12)
// ---------------------------------------------------------------------------------------------

/// Variances sigma^2 = S / W (m^2); 0 for a never-observed cell.
[[nodiscard]] inline float ccm_variance(float s, float weight) noexcept {
  return weight > 0.0F ? s / weight : 0.0F;
}

/// Inclinations (dz/dx, dz/dy; dimensionless gradients) and the surface-normal variance.
struct CcmSurface {
  float slope_x;          ///< a: eq. (9) (paper cell) or the 2 x 2 solve (full cell)
  float slope_y;          ///< b
  float normal_variance;  ///< sigma_s^2, eq. (11) or its full form, clamped to >= 0 (m^2)
};

/// Below this ratio det / trace^2 of the lateral covariance (about lambda_min / lambda_max: a
/// strip of points narrower than 1 % of its length) the full cell treats its points as a line:
/// float rounding of the co-moments (relative ~1e-6) would otherwise decide the slope across it.
inline constexpr float kMinLateralConditioning = 1.0e-4F;

namespace detail {
/// The (pseudo-)inverse of the lateral covariance [var_xx cov_xy; cov_xy var_yy] (m^2), in 1/m^2:
///  - trace <= kMinLateralVariance (all points at one spot): 0, no slope at all;
///  - det <= kMinLateralConditioning * trace^2 (a line of points): the pseudo-inverse of the
///    rank-1 matrix, Sigma / trace^2, so the slope along the line is kept and none is invented
///    across it;
///  - otherwise the inverse [var_yy -cov_xy; -cov_xy var_xx] / det.
struct LateralInverse {
  float xx;
  float yy;
  float xy;
};
[[nodiscard]] inline LateralInverse lateral_inverse(float var_xx, float var_yy, float cov_xy) noexcept {
  const float trace = var_xx + var_yy;
  if (!(trace > kMinLateralVariance)) {
    return LateralInverse{0.0F, 0.0F, 0.0F};
  }
  const float trace_sq = trace * trace;
  const float det = var_xx * var_yy - cov_xy * cov_xy;
  if (det > kMinLateralConditioning * trace_sq) {
    const float inv_det = 1.0F / det;
    return LateralInverse{var_yy * inv_det, var_xx * inv_det, -cov_xy * inv_det};
  }
  const float inv_trace_sq = 1.0F / trace_sq;
  return LateralInverse{var_xx * inv_trace_sq, var_yy * inv_trace_sq, cov_xy * inv_trace_sq};
}
}  // namespace detail

/// Slopes and normal variance of a cell. Never NaN/Inf for a cell built by this library.
///  - Paper cell, eqs. (9), (11): a = sigma_xz^2 / sigma_xx^2, b = sigma_yz^2 / sigma_yy^2,
///    sigma_s^2 = sigma_zz^2 - sigma_xz^4 / sigma_xx^2 - sigma_yz^4 / sigma_yy^2; a degenerate
///    lateral axis (variance <= kMinLateralVariance) contributes slope 0 and no reduction.
///    Exact only where x and y are uncorrelated in the cell.
///  - Full cell: [a b]^T = Sigma_xy^-1 [sigma_xz^2 sigma_yz^2]^T (the least-squares plane),
///    sigma_s^2 = sigma_zz^2 - a sigma_xz^2 - b sigma_yz^2 (its residual), with the guards of
///    detail::lateral_inverse (a line of points: slope along it only).
template <typename Cell, detail::IfCcmCell<Cell> = 0>
[[nodiscard]] inline CcmSurface ccm_surface(const Cell& cell) noexcept {
  CcmSurface out{0.0F, 0.0F, 0.0F};
  if (!(cell.weight > 0.0F)) {
    return out;
  }
  const float var_xx = cell.s_xx / cell.weight;
  const float var_yy = cell.s_yy / cell.weight;
  const float var_zz = cell.s_zz / cell.weight;
  const float cov_xz = cell.s_xz / cell.weight;
  const float cov_yz = cell.s_yz / cell.weight;
  float residual = var_zz;
  if constexpr (kHasLateralCovariance<Cell>) {
    const detail::LateralInverse inv = detail::lateral_inverse(var_xx, var_yy, cell.s_xy / cell.weight);
    out.slope_x = inv.xx * cov_xz + inv.xy * cov_yz;
    out.slope_y = inv.xy * cov_xz + inv.yy * cov_yz;
    residual -= out.slope_x * cov_xz + out.slope_y * cov_yz;
  } else {
    if (var_xx > kMinLateralVariance) {
      out.slope_x = cov_xz / var_xx;
      residual -= cov_xz * out.slope_x;
    }
    if (var_yy > kMinLateralVariance) {
      out.slope_y = cov_yz / var_yy;
      residual -= cov_yz * out.slope_y;
    }
  }
  out.normal_variance = residual > 0.0F ? residual : 0.0F;
  return out;
}

/// Total inclination i_total = sqrt(a^2 + b^2) (dimensionless gradient magnitude).
[[nodiscard]] inline float ccm_inclination(const CcmSurface& surface) noexcept {
  return std::sqrt(surface.slope_x * surface.slope_x + surface.slope_y * surface.slope_y);
}

/// Sub-cell height at (qx, qy) relative to the cell centre, eqs. (8)-(10):
/// h_q = c + a*q_x + b*q_y with c = mu_z - a*mu_x - b*mu_y. For a never-observed cell: 0.
template <typename Cell, detail::IfCcmCell<Cell> = 0>
[[nodiscard]] inline float ccm_height_at(const Cell& cell, const CcmSurface& surface, float qx, float qy) noexcept {
  return cell.mean_z + surface.slope_x * (qx - cell.mean_x) + surface.slope_y * (qy - cell.mean_y);
}

/// Elevation variance at (qx, qy): the variance of a new sample there under the cell's plane
/// model, sigma_s^2 * (1 + (1 + d^T Sigma_xy^+ d) / W) with d = q - mu: the residual spread plus
/// the uncertainty of the fitted plane (W counts points for weight 1). Paper cell: Sigma_xy^+ is
/// diag(1/sigma_xx^2, 1/sigma_yy^2) (a degenerate axis contributes 0); full cell: the
/// (pseudo-)inverse of detail::lateral_inverse, the same one the slopes use.
[[nodiscard]] float ccm_elevation_variance(const CcmCell& cell, const CcmSurface& surface, float qx,
                                           float qy) noexcept;
[[nodiscard]] float ccm_elevation_variance(const CcmPaperCell& cell, const CcmSurface& surface, float qx,
                                           float qy) noexcept;

/// Coverage (eq. 12 and its rotation-invariant form), with W >= min_weight, comparing variances
/// with the full cell's sigma_r^2 = w^2 / 12 (no square root):
///  - paper cell: sigma_xx^2, sigma_yy^2 >= tau^2 w^2 / 12 (eq. 12 per axis);
///  - full cell: the smaller eigenvalue of the lateral covariance >= tau^2 w^2 / 12, i.e. the
///    points spread at least tau times as far as a fully covered cell's along *every* direction
///    (tested as: Sigma_xy - t I positive semi-definite, t = tau^2 w^2 / 12). A half cell cut
///    on a diagonal is judged as strictly as one cut along an axis (docs/design.md, "Coverage").
/// A partly covered cell is unknown.
template <typename Cell, detail::IfCcmCell<Cell> = 0>
[[nodiscard]] inline bool ccm_is_covered(const Cell& cell, float cell_width_m, float tau, float min_weight) noexcept {
  if (!(cell.weight >= min_weight) || !(cell.weight > 0.0F)) {
    return false;
  }
  const float needed = tau * tau * cell_width_m * cell_width_m * (1.0F / 12.0F);
  if constexpr (kHasLateralCovariance<Cell>) {
    const float inv_weight = 1.0F / cell.weight;
    const float excess_x = cell.s_xx * inv_weight - needed;
    const float excess_y = cell.s_yy * inv_weight - needed;
    const float cov_xy = cell.s_xy * inv_weight;
    return excess_x >= 0.0F && excess_y >= 0.0F && excess_x * excess_y >= cov_xy * cov_xy;
  } else {
    return cell.s_xx >= needed * cell.weight && cell.s_yy >= needed * cell.weight;
  }
}

// ---------------------------------------------------------------------------------------------
// Pooling, eqs. (13)-(15)
// ---------------------------------------------------------------------------------------------

/// Pools four child cells of width `child_width_m` into their parent (width 2*child_width_m).
/// Child order: index = ix + 2*iy with ix, iy in {0,1}; child centre offset from the parent
/// centre is ((ix - 0.5) * child_width_m, (iy - 0.5) * child_width_m).
///
/// Rule (docs/design.md, "Pooling"): each observed child's mean is first shifted into the
/// parent frame by its centre offset; observed children are then combined with equal area
/// weights 1/n (eqs. 13-15 use 1/4: every child stands for the same ground area, whatever
/// its point density), unobserved children (W = 0) are left out so that they neither pull
/// the mean towards the parent centre nor invent variance. The pooled weight is the sum of the
/// children's weights, then limited to weight_limit (variances unchanged). With no observed
/// child the result is the zero cell.
///
/// The observed children's means are correlated in x and y when 3 of 4 (an L) or two diagonal
/// children are observed. The full cell carries that cross term (and its children's own): the
/// parent's slope is the least-squares plane of the observed children for every pattern, and
/// its coverage (the smaller eigenvalue) fails for every pattern but all four children
/// (tests/cell/ccm_lateral_test.cpp, all 15). The paper cell cannot hold it; its parent stores
/// the same least-squares plane in the form eqs. (9) and (11) read (s_xz = a s_xx,
/// s_yz = b s_yy, s_zz raised so that eq. (11) gives the plane's residual), so its slope and
/// normal variance are exact too, but its per-axis coverage still passes an L (sigma 0.96 of
/// the full cell's per axis) and two diagonal children (1.0): only the two-adjacent pattern fails.
[[nodiscard]] CcmCell ccm_pool4(const CcmCell children[4], float child_width_m, float weight_limit) noexcept;
[[nodiscard]] CcmPaperCell ccm_pool4(const CcmPaperCell children[4], float child_width_m, float weight_limit) noexcept;

/// A piece-wise constant cell (height, variance of height, weight) seen as a CCM cell of type
/// Cell (CcmCell or CcmPaperCell): a sample of the surface at the cell centre, i.e. mean
/// (0, 0, height), no lateral variance or covariance, sigma_zz^2 = variance. Used to pool the
/// finest, piece-wise constant layer into the first CCM layer. Why a point and not a uniform
/// surfel: a constant cell keeps no slope, so a surfel with lateral variance w^2/12 but zero
/// covariance would bias every pooled slope low by a factor 3/4 (the pooled sigma_xx^2 =
/// w^2/12 + w^2/4 against a covariance of s w^2/4); as centre samples four children reproduce a
/// plane's slope exactly, and the pooled lateral variance (w_child/2)^2 is 0.866^2 of the uniform
/// value, above the coverage bound tau = 0.8. Weight <= 0 or non-finite input gives the zero
/// cell; cell_width_m must be > 0.
template <typename Cell = CcmCell>
[[nodiscard]] Cell ccm_from_constant(float height, float variance, float weight, float cell_width_m) noexcept;
extern template CcmCell ccm_from_constant<CcmCell>(float, float, float, float) noexcept;
extern template CcmPaperCell ccm_from_constant<CcmPaperCell>(float, float, float, float) noexcept;

}  // namespace ccmap
