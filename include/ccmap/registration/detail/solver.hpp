// The registration solver: robust Gauss-Newton over (dx, dy, dz, dyaw), generic in where the
// samples come from (a frame's points, another map's cells) and what they are matched against
// (a stack's cells: registration/detail/stack_surface.hpp). docs/design.md, "Registration",
// states the model; this file implements it.
//
// Model. A sample is a map-frame position p (before the correction) with its own variance:
// along the ray from the rotation centre o (a stereo or lidar range error, m^2) and/or in z
// (another map's cell mean, m^2). With the correction applied,
//     q = Rz(yaw) (p - o) + o + t,
// its residual against the map's surface there is the vertical distance
//     r = q_z - h(q_x, q_y)                         h: the cell's plane, eq. (10)
// with the variance
//     var = ray_variance (n . u)^2 + own_variance + elevation_variance(q) + model_variance
// (u the unit ray, n = (-a, -b, 1): a range error moves the point along the ray, and only its
// part across the plane changes r; elevation_variance is the cell's sigma_s^2 (1 + (1 + d^T
// Sigma^+ d) / W), the plane's spread plus its own uncertainty at q). The gradient of r:
//     dr/d(dx, dy, dz, dyaw) = (-g_x, -g_y, 1, g_x (q_y - o_y) - g_y (q_x - o_x))
// where g is the plane's gradient and l the lever from o to where g belongs (a CCM cell's mean).
// The gradient is an estimate with covariance C_g (the least-squares plane's), so sum w J J^T
// over-states the information by N = sum w A C_g A^T (J = A g + e_z): a direction is observable
// only with its information in H - 3 N (once the bias, errors in variables; twice its scatter),
// and the covariance is that of H - N. A slope the map cannot tell from zero (flat ground seen with noise)
// then carries no information about x, y or yaw, and none is claimed. Weights are iteratively re-weighted Cauchy,
// w = 1 / (var (1 + r^2 / (c^2 var))), c = RegistrationParams::robust_sigmas.
//
// Each iteration accumulates the 4 x 4 normal equations over every sample (one pass; samples
// re-read, nothing stored per sample) and solves them in the observable subspace
// (detail::solve_normal_equations): a step along an unobservable direction is never taken.
// The step t <- Rz(dyaw_step) t + t_step, yaw <- yaw + dyaw_step composes the increment about o.
// Steps are clamped (kMaxStepM, kMaxStepRad) so that one bad association cannot throw the
// estimate away. Bounded: at most max_iterations passes over at most max_points samples.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "ccmap/core/status.hpp"
#include "ccmap/registration/detail/normal_equations.hpp"
#include "ccmap/registration/types.hpp"

namespace ccmap::detail {

/// sin and cos of theta (|theta| <= 7), + - * and floor only: declared with the planner's path
/// sweep (planner/path_query.hpp), defined in src/planner/planner_support.cpp. Declared here
/// too so that this header does not pull the planner into the stack's own header.
void sin_cos(float theta, float* sine, float* cosine) noexcept;

/// One sample (frame point or cell mean), map frame, before the correction.
struct RegistrationSample {
  float x;
  float y;
  float z;
  float ray_variance;  ///< m^2, along the line from the rotation centre; 0: none
  float own_variance;  ///< m^2, of z
  int layer;           ///< the finest stack layer to match it against
};

/// The map's surface at a query point.
struct SurfacePlane {
  float height;    ///< m, the plane at the point
  float slope_x;   ///< the plane's gradient dz/dx
  float slope_y;
  float var_gx;    ///< the gradient's covariance (its estimate's, from the cell's statistics)
  float var_gy;
  float cov_gxy;
  float lever_x;   ///< map-frame position the gradient belongs to (m): a CCM cell's mean, the point
  float lever_y;
  float variance;  ///< m^2, elevation variance of the surface at the point
};

enum class SurfaceAnswer : std::uint8_t { kKnown, kUnknown, kOutside };

/// A result that claims nothing (status != kOk).
[[nodiscard]] inline RegistrationResult unclaimed_result(Status status) noexcept {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  RegistrationResult r{};
  r.status = status;
  r.sigma_dx = kInf;
  r.sigma_dy = kInf;
  r.sigma_dz = kInf;
  r.sigma_dyaw = kInf;
  return r;
}

/// kOk for a rotation matrix (row-major 3 x 3) as update_frame_sensor accepts it: finite
/// (else kNonFiniteInput), every |r_ij| <= 1.001 and R^T R within 1e-3 of the identity (else
/// kInvalidArgument). src/registration/registration.cpp.
[[nodiscard]] Status check_registration_rotation(const float* rotation) noexcept;

/// How many times the gradients' noise information N is taken off H to judge observability
/// (see registration_pass): a direction counts when its information is at least this many times
/// what noise in the map's slopes alone would give it (flat ground: E[sum w g g^T] = N).
inline constexpr float kGradientNoiseMargin = 2.0F;

/// Largest step of one iteration: 10 cm horizontally and vertically, 0.05 rad in yaw.
inline constexpr float kMaxStepM = 0.10F;
inline constexpr float kMaxStepRad = 0.05F;
/// Smallest lever arm used to scale the yaw (m): below it the yaw is a rotation in place.
inline constexpr float kMinLeverM = 1.0e-3F;
/// An axis whose share in the observable subspace is below this gets exactly no correction.
inline constexpr float kAxisAbsent = 0.01F;

/// What one pass over the samples gathered.
struct RegistrationPass {
  std::uint32_t sampled = 0U;   ///< finite samples
  std::uint32_t rejected = 0U;  ///< non-finite, out of range or too noisy
  std::uint32_t matched = 0U;   ///< on a known cell
  std::uint32_t unknown = 0U;   ///< inside the map, on no known cell
  std::uint32_t outside = 0U;   ///< outside every window
  float sum_w = 0.0F;           ///< sum of weights (1/m^2)
  float sum_w_lever_sq = 0.0F;  ///< sum of weight * horizontal distance^2 from the centre
  float sum_robust = 0.0F;      ///< sum of the robust factors
  float sum_robust_e2 = 0.0F;   ///< sum of robust factor * normalised residual^2
  float min_x = 0.0F, max_x = 0.0F, min_y = 0.0F, max_y = 0.0F;  ///< extent of the finite samples
};

/// The rigid correction being estimated.
struct RigidState {
  float tx = 0.0F, ty = 0.0F, tz = 0.0F, yaw = 0.0F;
  float cos_yaw = 1.0F, sin_yaw = 0.0F;
};

/// One pass: every sample through the correction, matched, weighted, accumulated into eq.
/// Samples::for_each(fn) calls fn(const RegistrationSample&) for every usable sample and returns
/// how many it refused (non-finite, out of range, too noisy); Surface::at(x, y, layer, &plane)
/// answers the map there.
template <typename Samples, typename Surface>
void registration_pass(const Samples& samples, const Surface& surface, float ox, float oy, float oz,
                       const RigidState& state, const RegistrationParams& params, NormalEquations4* eq,
                       RegistrationPass* pass) noexcept {
  eq->clear();
  RegistrationPass acc{};
  bool first = true;
  const float c2 = params.robust_sigmas * params.robust_sigmas;
  acc.rejected = samples.for_each([&](const RegistrationSample& s) {
    ++acc.sampled;
    if (first) {
      acc.min_x = acc.max_x = s.x;
      acc.min_y = acc.max_y = s.y;
      first = false;
    } else {
      acc.min_x = s.x < acc.min_x ? s.x : acc.min_x;
      acc.max_x = s.x > acc.max_x ? s.x : acc.max_x;
      acc.min_y = s.y < acc.min_y ? s.y : acc.min_y;
      acc.max_y = s.y > acc.max_y ? s.y : acc.max_y;
    }
    const float px = s.x - ox;
    const float py = s.y - oy;
    const float dx = state.cos_yaw * px - state.sin_yaw * py;  // q - o, horizontal
    const float dy = state.sin_yaw * px + state.cos_yaw * py;
    const float qx = dx + ox + state.tx;
    const float qy = dy + oy + state.ty;
    const float qz = s.z + state.tz;
    SurfacePlane plane{};
    const SurfaceAnswer answer = surface.at(qx, qy, s.layer, &plane);
    if (answer != SurfaceAnswer::kKnown) {
      if (answer == SurfaceAnswer::kOutside) {
        ++acc.outside;
      } else {
        ++acc.unknown;
      }
      return;
    }
    const float r = qz - plane.height;
    float var = s.own_variance + plane.variance + params.model_variance_m2;
    if (s.ray_variance > 0.0F) {
      // (n . u)^2 with u the unit ray from the sensor to q, n = (-a, -b, 1) (not normalised: r
      // is vertical, so a range error e moves it by e (u_z - a u_x - b u_y)).
      const float rx = qx - ox;
      const float ry = qy - oy;
      const float rz = qz - oz;
      const float len_sq = rx * rx + ry * ry + rz * rz;
      if (len_sq > 0.0F) {
        const float across = rz - plane.slope_x * rx - plane.slope_y * ry;
        var += s.ray_variance * (across * across / len_sq);
      }
    }
    if (!(var > 0.0F) || !std::isfinite(r) || !std::isfinite(var)) {
      ++acc.unknown;
      return;
    }
    const float e2 = r * r / var;
    const float robust = 1.0F / (1.0F + e2 / c2);
    const float w = robust / var;
    // The yaw's lever: from o to where the gradient belongs (a CCM cell's mean: its plane's
    // gradient is that of the surface there; using the point would claim the tilt of a curved
    // cell as information about the yaw).
    const float lx = plane.lever_x - ox;
    const float ly = plane.lever_y - oy;
    const float gx = plane.slope_x;
    const float gy = plane.slope_y;
    const float j[4] = {-gx, -gy, 1.0F, gx * ly - gy * lx};
    eq->add(j, w, r);
    // Errors in the gradient: E[g g^T] = g_true g_true^T + C_g, so J J^T over-states the
    // information by A C_g A^T (J = A g + e_z, A = [-1 0; 0 -1; 0 0; ly -lx]).
    eq->add_gradient_noise(w, plane.var_gx, plane.var_gy, plane.cov_gxy, lx, ly);
    ++acc.matched;
    acc.sum_w += w;
    acc.sum_w_lever_sq += w * (lx * lx + ly * ly);
    acc.sum_robust += robust;
    acc.sum_robust_e2 += robust * e2;
  });
  *pass = acc;
}

/// Runs the registration. (ox, oy, oz): the rotation centre (the sensor origin of a frame).
/// `extent_floor_m`: samples spanning less than this in both x and y are a degenerate frame.
/// Preconditions: params validated.
template <typename Samples, typename Surface>
[[nodiscard]] RegistrationResult solve_registration(const Samples& samples, const Surface& surface, float ox, float oy,
                                                    float oz, const RegistrationParams& params,
                                                    float extent_floor_m) noexcept {
  RigidState state{};
  NormalEquations4 eq{};
  RegistrationPass pass{};
  std::uint32_t iterations = 0U;  // passes over the samples, each followed by a solve
  float previous[4] = {0.0F, 0.0F, 0.0F, 0.0F};  // the last step taken
  auto unclaimed = [&](Status why) {
    RegistrationResult r = unclaimed_result(why);
    r.iterations = iterations;
    r.points_sampled = pass.sampled;
    r.points_rejected = pass.rejected;
    r.points_matched = pass.matched;
    return r;
  };
  for (;;) {
    registration_pass(samples, surface, ox, oy, oz, state, params, &eq, &pass);
    ++iterations;
    if (iterations == 1U) {
      // What the frame itself is, before anything about the map.
      if (pass.sampled == 0U) {
        return unclaimed(pass.rejected > 0U ? Status::kNonFiniteInput : Status::kDegenerateInput);
      }
      if (pass.sampled < 3U || (pass.max_x - pass.min_x < extent_floor_m && pass.max_y - pass.min_y < extent_floor_m)) {
        return unclaimed(Status::kDegenerateInput);
      }
    }
    if (pass.matched < params.min_matches) {
      // Before any step: the pose is off the map (most samples outside every window) or the
      // map does not know enough of this ground. After steps: the estimate walked off.
      return unclaimed(iterations > 1U                                 ? Status::kNotConverged
                       : pass.outside > pass.unknown + pass.matched ? Status::kOutsideMap
                                                                     : Status::kInsufficientOverlap);
    }
    float lever = pass.sum_w > 0.0F ? std::sqrt(pass.sum_w_lever_sq / pass.sum_w) : 0.0F;
    lever = lever > kMinLeverM ? lever : kMinLeverM;
    const float mean_e2 = pass.sum_robust > 0.0F ? pass.sum_robust_e2 / pass.sum_robust : 0.0F;
    const float variance_factor = mean_e2 > 1.0F ? mean_e2 : 1.0F;
    const Solve4 solve = solve_normal_equations(eq, lever, variance_factor, params.max_sigma_m, kGradientNoiseMargin);
    if (!solve.ok) {
      return unclaimed(Status::kNotConverged);
    }
    float step[4] = {solve.step[0], solve.step[1], solve.step[2], solve.step[3]};
    for (int i = 0; i < 4; ++i) {
      if (solve.axis_share[i] < kAxisAbsent) {
        step[i] = 0.0F;  // float crumbs of the decomposition along an absent axis
      }
    }
    // A step that turns back on the previous one (the samples' cells and robust weights change
    // between two states) is halved: a two-state cycle then closes geometrically.
    const float turn = step[0] * previous[0] + step[1] * previous[1] + step[2] * previous[2] +
                       step[3] * previous[3] * lever * lever;
    if (turn < 0.0F) {
      for (float& v : step) {
        v *= 0.5F;
      }
    }
    for (int i = 0; i < 4; ++i) {
      previous[i] = step[i];
    }
    const bool converged = std::sqrt(step[0] * step[0] + step[1] * step[1]) <= params.convergence_m &&
                           std::fabs(step[2]) <= params.convergence_m &&
                           std::fabs(step[3]) * lever <= params.convergence_m;
    if (!converged && iterations >= params.max_iterations) {
      return unclaimed(Status::kNotConverged);
    }
    // Clamp and apply (composed about o: t <- Rz(d) t + dt).
    const float horizontal = std::sqrt(step[0] * step[0] + step[1] * step[1]);
    if (horizontal > kMaxStepM) {
      step[0] *= kMaxStepM / horizontal;
      step[1] *= kMaxStepM / horizontal;
    }
    step[2] = step[2] > kMaxStepM ? kMaxStepM : (step[2] < -kMaxStepM ? -kMaxStepM : step[2]);
    step[3] = step[3] > kMaxStepRad ? kMaxStepRad : (step[3] < -kMaxStepRad ? -kMaxStepRad : step[3]);
    float ds = 0.0F;
    float dc = 1.0F;
    sin_cos(step[3], &ds, &dc);
    const float tx = dc * state.tx - ds * state.ty + step[0];
    const float ty = ds * state.tx + dc * state.ty + step[1];
    state.tx = tx;
    state.ty = ty;
    state.tz += step[2];
    state.yaw += step[3];
    sin_cos(state.yaw, &state.sin_yaw, &state.cos_yaw);
    if (std::sqrt(state.tx * state.tx + state.ty * state.ty) > params.max_translation_m ||
        std::fabs(state.tz) > params.max_translation_m || std::fabs(state.yaw) > params.max_yaw_rad) {
      return unclaimed(Status::kNotConverged);
    }
    if (!converged) {
      continue;
    }
    // Converged: the last pass was within convergence_m of the solution; its normal equations
    // give observability and the covariance.
    constexpr float kInf = std::numeric_limits<float>::infinity();
    RegistrationResult r{};
    r.status = Status::kOk;
    const float values[4] = {state.tx, state.ty, state.tz, state.yaw};
    float out[4] = {};
    float sigma[4] = {};
    for (int i = 0; i < 4; ++i) {
      r.observable[i] = solve.axis_observable[i];
      out[i] = solve.axis_share[i] < kAxisAbsent ? 0.0F : values[i];
      sigma[i] = solve.axis_observable[i] ? std::sqrt(solve.covariance[i][i]) : kInf;
    }
    r.dx = out[0];
    r.dy = out[1];
    r.dz = out[2];
    r.dyaw = out[3];
    r.sigma_dx = sigma[0];
    r.sigma_dy = sigma[1];
    r.sigma_dz = sigma[2];
    r.sigma_dyaw = sigma[3];
    r.rank = solve.rank;
    r.iterations = iterations;
    r.points_sampled = pass.sampled;
    r.points_rejected = pass.rejected;
    r.points_matched = pass.matched;
    r.lever_m = lever;
    r.residual_sigma = std::sqrt(mean_e2);
    return r;
  }
}

}  // namespace ccmap::detail
