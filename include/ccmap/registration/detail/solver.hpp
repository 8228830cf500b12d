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
//     dr/d(dx, dy, dz, dyaw) = (-g_x, -g_y, 1, g_x l_y - g_y l_x)
// where g is the plane's gradient and l the lever from o to where g belongs (a CCM cell's mean;
// the centre of a bilinear patch). Weights are iteratively re-weighted Cauchy,
// w = 1 / (var (1 + r^2 / (c^2 var))), c = RegistrationParams::robust_sigmas.
//
// Evidence. Every sample steers the step (H = sum w J J^T, b = sum w J r), but what is claimed
// comes from the evidence E:
//  - a CCM cell's plane is evidence about x, y and yaw too. Its gradient is an estimate with
//    covariance C_g (the least-squares plane's), so w J J^T over-states the information by
//    w A C_g A^T (J = A g + e_z), summed in N: a direction is observable only with its
//    information in E - 2 N (once the bias, errors in variables; once its scatter), and the
//    covariance is that of E - N. A slope the map cannot tell from zero (flat ground seen with
//    noise) carries no information about x, y or yaw, and none is claimed.
//  - the bilinear surface of constant cells (the finest layer) is evidence about the height only,
//    and only as far as its gradient leaves the height free of x and y within the search bound
//    sigma_p = max_translation_m: w / (1 + w |g|^2 sigma_p^2). Measured: constant cells at rocks
//    seen from two places disagree (shadows), and their gradients claimed a yaw to 1 mrad that
//    was 11 mrad off (docs/design.md, "Registration").
// The claimed covariance is the larger of E - N's and a delete-one-group jackknife's over blocks
// of ground (what blocks disagree on is not known, whatever the model says).
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

#include "ccmap/core/sin_cos.hpp"
#include "ccmap/core/status.hpp"
#include "ccmap/registration/detail/normal_equations.hpp"
#include "ccmap/registration/types.hpp"

namespace ccmap::detail {

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
  /// The gradient is evidence about x, y and yaw (a CCM cell's plane). False: it steers the
  /// step, but only the height counts as evidence, and only as far as the gradient leaves it
  /// unaffected by x and y (the bilinear surface of constant cells: see registration_pass).
  bool gradient_is_evidence;
};

enum class SurfaceAnswer : std::uint8_t { kKnown, kUnknown, kOutside };

/// Samples a source refused in one pass, by reason.
struct SampleRefusals {
  std::uint32_t non_finite = 0U;    ///< a NaN or infinite coordinate
  std::uint32_t out_of_reach = 0U;  ///< beyond kMaxAbsCoordinateM, or too noisy for every layer
};

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

/// How many times the gradients' noise information N is taken off the evidence E to judge
/// observability (see the file comment): a direction counts when its information is at least
/// this many times what noise in the map's slopes alone would give it (flat ground: E = N on
/// average).
inline constexpr float kGradientNoiseMargin = 2.0F;

/// The residuals fit their model when their mean squared normalised value (the variance
/// factor) is at most this: only then do the estimate's sigmas end the iterations.
inline constexpr float kFitFactor = 2.0F;

/// Largest step of one iteration: 10 cm horizontally and vertically, 0.05 rad in yaw.
inline constexpr float kMaxStepM = 0.10F;
inline constexpr float kMaxStepRad = 0.05F;
/// Smallest lever arm used to scale the yaw (m): below it the yaw is a rotation in place.
inline constexpr float kMinLeverM = 1.0e-3F;
/// An axis whose share in the observable subspace is below this (1 % of its length) gets exactly
/// no correction: what remains is float rounding of the decomposition.
inline constexpr float kAxisAbsent = 1.0e-4F;
static_assert(kJackknifeGroups == 8, "registration_pass hashes blocks to 3 bits");

/// What one pass over the samples gathered.
struct RegistrationPass {
  std::uint32_t sampled = 0U;   ///< finite samples
  std::uint32_t rejected = 0U;  ///< non-finite, out of range or too noisy
  std::uint32_t non_finite = 0U;  ///< of those, non-finite
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
/// the SampleRefusals; Surface::at(x, y, layer, &plane) answers the map there. With `groups`
/// (kJackknifeGroups of them), each sample is also added to the group of its block of ground
/// (block_m square blocks, hashed), and group_used says which received any.
template <typename Samples, typename Surface>
void registration_pass(const Samples& samples, const Surface& surface, float ox, float oy, float oz,
                       const RigidState& state, const RegistrationParams& params, NormalEquations4* eq,
                       RegistrationPass* pass, GroupEquations4* groups = nullptr, bool* group_used = nullptr,
                       float block_m = 1.0F) noexcept {
  eq->clear();
  if (groups != nullptr) {
    for (int g = 0; g < kJackknifeGroups; ++g) {
      groups[g].clear();
      group_used[g] = false;
    }
  }
  const float inv_block = 1.0F / block_m;
  RegistrationPass acc{};
  bool first = true;
  const float c2 = params.robust_sigmas * params.robust_sigmas;
  const SampleRefusals refused = samples.for_each([&](const RegistrationSample& s) {
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
    eq->add(j, w, r, plane.gradient_is_evidence);
    if (groups != nullptr) {
      // |q| <= ~1e5 m and block_m >= 1 cm keep the block indices within int32.
      const auto bx = static_cast<std::uint32_t>(static_cast<std::int32_t>(std::floor(qx * inv_block)));
      const auto by = static_cast<std::uint32_t>(static_cast<std::int32_t>(std::floor(qy * inv_block)));
      const std::uint32_t g = ((bx * 73856093U) ^ (by * 19349663U)) >> 29U;  // top 3 bits: 8 groups
      groups[g].add(j, w, r);
      group_used[g] = true;
    }
    if (plane.gradient_is_evidence) {
      // Errors in the gradient: E[g g^T] = g_true g_true^T + C_g, so J J^T over-states the
      // information by A C_g A^T (J = A g + e_z, A = [-1 0; 0 -1; 0 0; ly -lx]).
      eq->add_gradient_noise(w, plane.var_gx, plane.var_gy, plane.cov_gxy, lx, ly);
    } else {
      // A gradient that is no evidence leaves x and y open within the search bound sigma_p =
      // max_translation_m, so the height constrains dz only to within |g| sigma_p.
      const float g2 = gx * gx + gy * gy;
      const float prior = params.max_translation_m * params.max_translation_m;
      eq->add_height_evidence(w / (1.0F + w * g2 * prior));
    }
    ++acc.matched;
    acc.sum_w += w;
    acc.sum_w_lever_sq += w * (lx * lx + ly * ly);
    acc.sum_robust += robust;
    acc.sum_robust_e2 += robust * e2;
  });
  acc.rejected = refused.non_finite + refused.out_of_reach;
  acc.non_finite = refused.non_finite;
  *pass = acc;
}

/// The final pass at the converged state (finish_registration): the normal equations there,
/// solved for observability and the covariance; *pass, *lever, *e2 (the mean squared normalised
/// residual) as gathered. Its own frame (noinline): the normal equations and the eigen solver's
/// temporaries are not on the stack beside the jackknife's groups.
template <typename Samples, typename Surface>
[[gnu::noinline]] Solve4 final_pass(const Samples& samples, const Surface& surface, float ox, float oy, float oz,
                                    const RigidState& state, const RegistrationParams& params, RegistrationPass* pass,
                                    float* lever, float* e2) noexcept {
  NormalEquations4 eq{};
  registration_pass(samples, surface, ox, oy, oz, state, params, &eq, pass);
  float l = pass->sum_w > 0.0F ? std::sqrt(pass->sum_w_lever_sq / pass->sum_w) : 0.0F;
  *lever = l > kMinLeverM ? l : kMinLeverM;
  *e2 = pass->sum_robust > 0.0F ? pass->sum_robust_e2 / pass->sum_robust : 0.0F;
  if (pass->matched < params.min_matches) {
    Solve4 refused{};
    refused.ok = false;
    return refused;
  }
  return solve_normal_equations(eq, *lever, *e2 > 1.0F ? *e2 : 1.0F, params.max_sigma_m, kGradientNoiseMargin);
}

/// The jackknife's pass at the converged state (finish_registration): the normal equations per
/// block of ground (block_m squares), and the delete-one-group covariance in the subspace of
/// `solve`. Its own frame (noinline), as final_pass.
template <typename Samples, typename Surface>
[[gnu::noinline]] bool jackknife_pass(const Samples& samples, const Surface& surface, float ox, float oy, float oz,
                                      const RigidState& state, const RegistrationParams& params, float block_m,
                                      const Solve4& solve, float lever, float covariance[4][4]) noexcept {
  NormalEquations4 unused{};
  RegistrationPass pass{};
  GroupEquations4 groups[kJackknifeGroups];
  bool group_used[kJackknifeGroups] = {};
  registration_pass(samples, surface, ox, oy, oz, state, params, &unused, &pass, groups, group_used, block_m);
  return jackknife_covariance(groups, group_used, solve, lever, covariance);
}

/// The end of a converged registration (solve_registration): observability and the covariance
/// at the solution (final_pass), the jackknife (jackknife_pass), the claims. Two passes over the
/// samples, one per helper, so that their buffers never share the stack.
template <typename Samples, typename Surface>
[[gnu::noinline]] RegistrationResult finish_registration(const Samples& samples, const Surface& surface, float ox,
                                                         float oy, float oz, const RigidState& state,
                                                         const RegistrationParams& params, float block_m,
                                                         std::uint32_t iterations) noexcept {
  RegistrationPass pass{};
  float final_lever = kMinLeverM;
  float final_e2 = 0.0F;
  const Solve4 final_solve = final_pass(samples, surface, ox, oy, oz, state, params, &pass, &final_lever, &final_e2);
  if (!final_solve.ok) {
    RegistrationResult r = unclaimed_result(Status::kNotConverged);
    r.iterations = iterations;
    r.points_sampled = pass.sampled;
    r.points_rejected = pass.rejected;
    r.points_matched = pass.matched;
    return r;
  }
  // The jackknife's covariance where it is larger than the model's: what blocks of ground
  // disagree on is not known, whatever the model says. Without an estimate (fewer than two
  // blocks, or a block the rest cannot do without) nothing beyond dz is claimed.
  float jack[4][4] = {};
  const bool jack_ok = jackknife_pass(samples, surface, ox, oy, oz, state, params, block_m, final_solve, final_lever, jack);
  constexpr float kInf = std::numeric_limits<float>::infinity();
  RegistrationResult r{};
  r.status = Status::kOk;
  const float values[4] = {state.tx, state.ty, state.tz, state.yaw};
  float out[4] = {};
  float sigma[4] = {};
  for (int i = 0; i < 4; ++i) {
    float variance = final_solve.covariance[i][i];
    if (jack_ok) {
      variance = jack[i][i] > variance ? jack[i][i] : variance;
    } else if (i != kAxisZ) {
      variance = kInf;
    }
    const float limit = i == kAxisYaw ? params.max_sigma_m / final_lever : params.max_sigma_m;
    const float sd = std::sqrt(variance);
    r.observable[i] = final_solve.axis_observable[i] && sd <= limit;
    out[i] = final_solve.axis_share[i] < kAxisAbsent ? 0.0F : values[i];
    sigma[i] = kInf;
    if (r.observable[i]) {
      sigma[i] = sd;
    }
  }
  r.dx = out[0];
  r.dy = out[1];
  r.dz = out[2];
  r.dyaw = out[3];
  r.sigma_dx = sigma[0];
  r.sigma_dy = sigma[1];
  r.sigma_dz = sigma[2];
  r.sigma_dyaw = sigma[3];
  r.rank = final_solve.rank;
  r.iterations = iterations;
  r.points_sampled = pass.sampled;
  r.points_rejected = pass.rejected;
  r.points_matched = pass.matched;
  r.lever_m = final_lever;
  r.residual_sigma = std::sqrt(final_e2);
  return r;
}

/// The iterations of solve_registration: a refusal, or kOk (nothing claimed yet) with the
/// converged state and the iterations used. Its own frame (noinline).
template <typename Samples, typename Surface>
[[gnu::noinline]] RegistrationResult iterate_registration(const Samples& samples, const Surface& surface, float ox,
                                                          float oy, float oz, const RegistrationParams& params,
                                                          float extent_floor_m, RigidState* converged_state,
                                                          std::uint32_t* converged_iterations) noexcept {
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
        // Nothing usable: every sample non-finite; else beyond every layer's reach (a frame far
        // from the map); else there were no points.
        return unclaimed(pass.rejected == 0U               ? Status::kDegenerateInput
                         : pass.non_finite == pass.rejected ? Status::kNonFiniteInput
                                                            : Status::kOutsideMap);
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
    // The step's subspace: what the information fixes, whatever the residuals say so far (far
    // from the solution they are all large, and a variance factor from them would forbid every
    // step). The residuals' fit enters the claims, at the solution.
    const Solve4 solve = solve_normal_equations(eq, lever, 1.0F, params.max_sigma_m, kGradientNoiseMargin);
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
    // Converged: the step moves no point by more than convergence_m, or, once the residuals fit
    // their model (variance factor <= kFitFactor), by no more than a quarter of its own standard
    // deviation (the samples' cells and robust weights can switch between states that differ by
    // less than the answer is known: a cycle there is noise). Far from the solution the
    // residuals do not fit, their sigmas say nothing, and only convergence_m ends the iterations.
    const bool fits = variance_factor <= kFitFactor;
    bool converged = true;
    for (int i = 0; i < 4; ++i) {
      const float length = i == kAxisYaw ? lever : 1.0F;
      const float variance = solve.covariance[i][i] * variance_factor;
      const float quarter_sigma = fits ? 0.25F * std::sqrt(variance > 0.0F ? variance : 0.0F) : 0.0F;
      const float bound = params.convergence_m > quarter_sigma * length ? params.convergence_m : quarter_sigma * length;
      converged = converged && std::fabs(step[i]) * length <= bound;
    }
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
    *converged_state = state;
    *converged_iterations = iterations;
    return unclaimed(Status::kOk);  // a marker: solve_registration goes on
  }
}

/// Runs the registration. (ox, oy, oz): the rotation centre (the sensor origin of a frame).
/// `extent_floor_m`: samples spanning less than this in both x and y are a degenerate frame.
/// `block_m`: the side of the blocks of ground the jackknife groups samples by (>= 0.01 m).
/// Preconditions: params validated. The iterations and the end each have their own frame.
template <typename Samples, typename Surface>
[[nodiscard]] RegistrationResult solve_registration(const Samples& samples, const Surface& surface, float ox, float oy,
                                                    float oz, const RegistrationParams& params,
                                                    float extent_floor_m, float block_m) noexcept {
  RigidState state{};
  std::uint32_t iterations = 0U;
  const RegistrationResult iterated =
      iterate_registration(samples, surface, ox, oy, oz, params, extent_floor_m, &state, &iterations);
  if (iterated.status != Status::kOk) {
    return iterated;
  }
  return finish_registration(samples, surface, ox, oy, oz, state, params, block_m, iterations);
}

}  // namespace ccmap::detail
