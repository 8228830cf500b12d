// Cell math on the target against double-precision references computed on the host
// (cell_reference.inc, written by make_cell_reference.cpp from the same inputs): the CCM update
// of the full cell (eqs. 1-5 and s_xy), its queries (the least-squares plane, eq. 10), pooling
// (eqs. 13-15), the weight limiter (eqs. 6-7), and the Kalman and OMG cells. Also analytic
// values: a noise-free 20 deg plane.
//
// Tolerances are bounds on float rounding, not on the statistics. Each quantity gets a
// relative share of its own scale (1e-6 for means and weights, 1e-5 for second moments, 1e-4
// for slopes and the difference sigma_s^2) plus, for the z moments, a term for the rounding of
// z itself: 1e-7 * |z| per unit of the other factor (the ulp of z is 6e-8 |z|; the case 250 m
// above the origin needs it). The errors measured on x86-64 (bitwise the same on the board) use
// at most 0.2 of these bounds; a wrong equation misses them by orders of magnitude.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "cell_inputs.hpp"
#include "harness.hpp"

namespace {

using namespace ccmap::test::cells;

#include "cell_reference.inc"

float value(std::uint32_t b) {
  float f = 0.0F;
  std::memcpy(&f, &b, sizeof f);
  return f;
}

/// The cell of case c, point after point (no limiter).
ccmap::CcmCell fold(int c) {
  ccmap::CcmCell cell{};
  bool accepted = true;
  for (std::uint32_t i = 0; i < ccm_point_count(c); ++i) {
    const Input p = ccm_point(c, i);
    accepted = accepted && ccmap::ccm_update(cell, p.x, p.y, p.z, p.w, ccmap::kNoWeightLimit) == ccmap::Status::kOk;
  }
  BM_CHECK(accepted, "a valid point was refused by ccm_update");
  return cell;
}

/// Compares a cell with its reference. `z_scale` (m): the size of z in the case.
void compare(const ccmap::CcmCell& cell, const CcmReference& ref, float z_scale) {
  const float w = cell.weight;
  const float length = kCellWidthM;
  const float lateral_var = length * length / 12.0F;   // variance scale of x and y
  const float z_rounding = 1e-7F * z_scale;             // m: rounding of z and of the z mean
  const float var_zz_ref = value(ref.var_zz);
  const float z_spread = std::sqrt(var_zz_ref);
  BM_CHECK_NEAR(w, value(ref.weight), 1e-6F * value(ref.weight), "weight (eq. 1) differs from the sum of weights");
  BM_CHECK_NEAR(cell.mean_x, value(ref.mean_x), 1e-6F * length, "mean_x (eq. 3) off");
  BM_CHECK_NEAR(cell.mean_y, value(ref.mean_y), 1e-6F * length, "mean_y (eq. 3) off");
  BM_CHECK_NEAR(cell.mean_z, value(ref.mean_z), 1e-6F * z_scale, "mean_z (eq. 3) off");
  BM_CHECK_NEAR(ccmap::ccm_variance(cell.s_xx, w), value(ref.var_xx), 1e-5F * lateral_var, "var_xx (eq. 4) off");
  BM_CHECK_NEAR(ccmap::ccm_variance(cell.s_yy, w), value(ref.var_yy), 1e-5F * lateral_var, "var_yy (eq. 4) off");
  BM_CHECK_NEAR(ccmap::ccm_variance(cell.s_zz, w), var_zz_ref, 1e-5F * var_zz_ref + z_rounding * z_spread,
                "var_zz (eq. 4) off");
  const float cov_bound = 1e-5F * lateral_var + z_rounding * length;
  BM_CHECK_NEAR(ccmap::ccm_variance(cell.s_xz, w), value(ref.cov_xz), cov_bound, "cov_xz (eq. 5) off");
  BM_CHECK_NEAR(ccmap::ccm_variance(cell.s_yz, w), value(ref.cov_yz), cov_bound, "cov_yz (eq. 5) off");
  BM_CHECK_NEAR(ccmap::ccm_variance(cell.s_xy, w), value(ref.cov_xy), 1e-5F * lateral_var, "cov_xy off");
  const ccmap::CcmSurface surface = ccmap::ccm_surface(cell);
  BM_CHECK_NEAR(surface.slope_x, value(ref.slope_x), 1e-4F, "slope_x off the least-squares plane");
  BM_CHECK_NEAR(surface.slope_y, value(ref.slope_y), 1e-4F, "slope_y off the least-squares plane");
  // sigma_s^2 is a difference of near-equal terms: absolute bound against var_zz.
  BM_CHECK_NEAR(surface.normal_variance, value(ref.normal_variance), 1e-4F * var_zz_ref + z_rounding * z_spread,
                "normal_variance off the plane's residual");
  BM_CHECK_NEAR(ccmap::ccm_inclination(surface), value(ref.inclination), 1e-4F, "inclination off");
  BM_CHECK_NEAR(ccmap::ccm_height_at(cell, surface, kQueryX, kQueryY), value(ref.height_at_query),
                1e-6F * z_scale + 1e-6F, "sub-cell height (eq. 10) off");
}

}  // namespace

BM_CASE(cell_math, ccm_update_cloud_matches_double_batch) { compare(fold(kCloud), kCcmReference[kCloud], 0.1F); }

BM_CASE(cell_math, ccm_update_weighted_step_matches_double_batch) {
  compare(fold(kWeighted), kCcmReference[kWeighted], 0.12F);
}

BM_CASE(cell_math, ccm_update_far_above_origin_matches_double_batch) {
  compare(fold(kFarOffset), kCcmReference[kFarOffset], 250.0F);
}

BM_CASE(cell_math, ccm_plane_20_degrees) {
  const ccmap::CcmCell cell = fold(kPlane20);
  compare(cell, kCcmReference[kPlane20], 0.4F);
  // Analytic: a noise-free plane has exactly its gradient and no residual.
  const ccmap::CcmSurface surface = ccmap::ccm_surface(cell);
  BM_CHECK_NEAR(surface.slope_x, kPlane20SlopeX, 2e-5F, "slope_x of the 20 deg plane is not tan20 cos30");
  BM_CHECK_NEAR(surface.slope_y, kPlane20SlopeY, 2e-5F, "slope_y of the 20 deg plane is not tan20 sin30");
  BM_CHECK_NEAR(ccmap::ccm_inclination(surface), kTan20, 2e-5F, "inclination of the 20 deg plane is not tan 20 deg");
  BM_CHECK_NEAR(surface.normal_variance, 0.0F, 1e-9F, "a plane has a normal variance");
}

BM_CASE(cell_math, ccm_pool4_matches_double_batch_of_the_union) {
  ccmap::CcmCell children[4] = {};
  bool accepted = true;
  for (std::uint32_t i = 0; i < ccm_point_count(kPooled); ++i) {
    const Input p = ccm_point(kPooled, i);
    const int k = pooled_child(p);
    accepted = accepted && ccmap::ccm_update(children[k], p.x - child_offset_x(k), p.y - child_offset_y(k), p.z, p.w,
                                             ccmap::kNoWeightLimit) == ccmap::Status::kOk;
  }
  BM_CHECK(accepted, "a valid point was refused by ccm_update");
  // Equal point counts per child: equal-area pooling (eqs. 13-15) equals the union's moments.
  compare(ccmap::ccm_pool4(children, 0.5F * kCellWidthM, ccmap::kNoWeightLimit), kCcmReference[kPooled], 0.05F);
}

BM_CASE(cell_math, weight_limiter_holds_relative_weight) {
  ccmap::CcmCell cell{};
  bool accepted = true;
  for (std::uint32_t i = 0; i < kLimiterSettle + kLimiterSteps; ++i) {
    const float z = i < kLimiterSettle ? 0.0F : 1.0F;
    const float x = 0.05F * (ccmap::test::hash_unit(i, 31U) - 0.5F);
    accepted = accepted && ccmap::ccm_update(cell, x, -x, z, 1.0F, kLimiterWeightLimit) == ccmap::Status::kOk;
  }
  BM_CHECK(accepted, "a valid point was refused by ccm_update");
  BM_CHECK_NEAR(cell.weight, value(kLimiterReference.weight), 0.0F, "the limiter does not hold W at W_l (eq. 6)");
  BM_CHECK_NEAR(cell.mean_z, value(kLimiterReference.mean_z), 2e-5F,
                "mean after the limiter engaged is not 1 - (W_l / (W_l + 1))^k");
}

BM_CASE(cell_math, kalman_and_omg_match_double_fusion) {
  ccmap::KalmanCell kalman{};
  ccmap::OmgCell omg{};
  bool accepted = true;
  for (std::uint32_t i = 0; i < kConstantCount; ++i) {
    const Input m = constant_measurement(i);
    accepted = accepted && ccmap::kalman_update(kalman, m.z, m.y) == ccmap::Status::kOk;
    accepted = accepted && ccmap::omg_update(omg, m.z, m.y, m.w) == ccmap::Status::kOk;
  }
  BM_CHECK(accepted, "a valid measurement was refused");
  const float kalman_variance = value(kConstantReference.kalman_variance);
  BM_CHECK_NEAR(kalman.height, value(kConstantReference.kalman_height), 1e-6F, "Kalman height is not the information-weighted mean");
  BM_CHECK_NEAR(kalman.variance, kalman_variance, 1e-4F * kalman_variance, "Kalman variance is not 1 / sum(1/R)");
  BM_CHECK_NEAR(kalman.weight, static_cast<float>(kConstantCount), 0.0F, "Kalman weight does not count measurements");
  BM_CHECK_NEAR(omg.weight, value(kConstantReference.omg_weight), 1e-5F * value(kConstantReference.omg_weight),
                "OMG weight is not the sum of weights");
  BM_CHECK_NEAR(omg.height, value(kConstantReference.omg_height), 1e-6F, "OMG height is not the weighted mean");
  const float omg_variance = value(kConstantReference.omg_variance);
  BM_CHECK_NEAR(ccmap::omg_variance(omg), omg_variance, 1e-4F * omg_variance, "OMG mixture variance off");
}
