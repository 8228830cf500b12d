// The 4 x 4 algebra of registration with Eigen's fixed-size float types. Fixed-size Eigen
// objects live on the stack and never allocate (tests/registration/eigen_no_malloc_test.cpp
// runs this file under EIGEN_RUNTIME_NO_MALLOC); the core is built with -fno-exceptions, under
// which Eigen throws nothing; EIGEN_MAX_STATIC_ALIGN_BYTES is the same on every target (the
// ccmap_eigen target in the top CMakeLists.txt).
#include "ccmap/registration/detail/normal_equations.hpp"

#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace ccmap::detail {

namespace {

/// The share of an axis' squared length that must lie in the observable subspace for the axis
/// to be called observable: 0.99, i.e. within asin(0.1) = 5.7 deg of it.
constexpr float kAxisInSubspace = 0.99F;
/// Eigenvalues below this share of the largest are float noise of the decomposition.
constexpr float kRelativeEigenFloor = 1.0e-6F;

Solve4 refused() noexcept {
  Solve4 out{};
  out.ok = false;
  return out;
}

/// V^T M V with the rows and columns of unobservable directions replaced by the identity's:
/// the reduced matrix Q^T M Q, padded to 4 x 4 so that it stays a fixed-size type.
Eigen::Matrix4f reduced(const Eigen::Matrix4f& m, const Eigen::Matrix4f& v, const bool keep[4]) noexcept {
  Eigen::Matrix4f r = v.transpose() * m * v;
  for (int k = 0; k < 4; ++k) {
    if (!keep[k]) {
      r.row(k).setZero();
      r.col(k).setZero();
      r(k, k) = 1.0F;
    }
  }
  return r;
}

/// The eigen-decomposition (ascending eigenvalues, orthonormal eigenvectors); false if it did not
/// converge. Each of these helpers has its own frame (noinline), so that their Eigen temporaries
/// do not add up on the caller's stack (docs/performance.md, the stack of register_frame).
[[gnu::noinline]] bool decompose(const Eigen::Matrix4f& m, Eigen::Matrix4f* vectors, Eigen::Vector4f* values) noexcept {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4f> solver(m, Eigen::ComputeEigenvectors);
  if (solver.info() != Eigen::Success) {
    return false;
  }
  *vectors = solver.eigenvectors();
  *values = solver.eigenvalues();
  return true;
}

/// V y with y = (Q^T M Q)^-1 rhs in the kept directions (rhs in V's basis, 0 elsewhere); false
/// unless Q^T M Q is positive definite.
[[gnu::noinline]] bool reduced_solve(const Eigen::Matrix4f& m, const Eigen::Matrix4f& v, const bool keep[4],
                                     const Eigen::Vector4f& rhs, Eigen::Vector4f* out) noexcept {
  const Eigen::LDLT<Eigen::Matrix4f> ldlt(reduced(m, v, keep));
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) {
    return false;
  }
  *out = v * ldlt.solve(rhs);
  return out->allFinite();
}

/// V (Q^T M Q)^-1 V^T over the kept directions; false unless Q^T M Q is positive definite. Column
/// by column: a vector right-hand side keeps Eigen on its fixed-size vector paths (a matrix
/// right-hand side takes the blocked level-3 solver, which sizes a workspace at run time and,
/// without alloca, takes it from the heap: the Cortex-M7 image refused it).
[[gnu::noinline]] bool reduced_inverse(const Eigen::Matrix4f& m, const Eigen::Matrix4f& v, const bool keep[4],
                                       Eigen::Matrix4f* out) noexcept {
  const Eigen::LDLT<Eigen::Matrix4f> ldlt(reduced(m, v, keep));
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) {
    return false;
  }
  Eigen::Matrix4f inv;
  for (int k = 0; k < 4; ++k) {
    inv.col(k) = keep[k] ? Eigen::Vector4f(ldlt.solve(Eigen::Vector4f::Unit(k))) : Eigen::Vector4f::Zero();
  }
  for (int k = 0; k < 4; ++k) {
    if (!keep[k]) {
      inv.row(k).setZero();
    }
  }
  *out = v * inv * v.transpose();
  return out->allFinite();
}

}  // namespace

Solve4 solve_normal_equations(const NormalEquations4& eq, float lever_m, float variance_factor, float max_sigma_m,
                              float noise_margin) noexcept {
  if (!(lever_m > 0.0F) || !(variance_factor >= 1.0F) || !(max_sigma_m > 0.0F) || !(noise_margin >= 1.0F) ||
      !std::isfinite(lever_m) || !std::isfinite(variance_factor) || !std::isfinite(noise_margin)) {
    return refused();
  }
  // Scale the yaw to a length: theta_s = lever * dyaw, so H_s = S^-1 H S^-1, b_s = S^-1 b with
  // S = diag(1, 1, 1, lever).
  const float inv_lever = 1.0F / lever_m;
  const float scale[4] = {1.0F, 1.0F, 1.0F, inv_lever};
  Eigen::Matrix4f h;
  Eigen::Matrix4f evidence;
  Eigen::Matrix4f noise;
  Eigen::Vector4f b;
  for (int i = 0; i < 4; ++i) {
    b(i) = eq.b[i] * scale[i];
    for (int j = i; j < 4; ++j) {
      const float s = scale[i] * scale[j];
      evidence(i, j) = evidence(j, i) = eq.e[i][j] * s;
      h(i, j) = h(j, i) = (eq.e[i][j] + eq.f[i][j]) * s;
      noise(i, j) = noise(j, i) = eq.n[i][j] * s;
    }
  }
  evidence(2, 2) += eq.height_evidence;
  if (!h.allFinite() || !evidence.allFinite() || !noise.allFinite() || !b.allFinite()) {
    return refused();
  }
  // Observability from the evidence less the gradients' noise information (its eigenvalues may
  // be negative: directions that noise alone explains fail the threshold like any other).
  Eigen::Matrix4f v;       // orthonormal columns
  Eigen::Vector4f lambda;  // ascending
  if (!decompose(evidence - noise_margin * noise, &v, &lambda)) {
    return refused();
  }
  // Observable: information / variance_factor >= 1 / max_sigma^2, i.e. the direction's sigma
  // sqrt(variance_factor / lambda) <= max_sigma.
  const float min_lambda = variance_factor / (max_sigma_m * max_sigma_m);
  const float floor_lambda = kRelativeEigenFloor * lambda(3);
  bool keep[4] = {false, false, false, false};
  Solve4 out{};
  out.rank = 0U;
  Eigen::Vector4f in_subspace = Eigen::Vector4f::Zero();
  for (int k = 0; k < 4; ++k) {
    keep[k] = lambda(k) >= min_lambda && lambda(k) > floor_lambda;
    if (keep[k]) {
      ++out.rank;
      in_subspace += v.col(k).cwiseProduct(v.col(k));
    }
  }
  Eigen::Vector4f step_s = Eigen::Vector4f::Zero();
  Eigen::Matrix4f cov_s = Eigen::Matrix4f::Zero();
  if (out.rank > 0U) {
    // Step: Gauss-Newton with H in the observable subspace, y = -(Q^T H Q)^-1 Q^T b.
    Eigen::Vector4f rhs = -(v.transpose() * b);
    for (int k = 0; k < 4; ++k) {
      rhs(k) = keep[k] ? rhs(k) : 0.0F;
    }
    if (!reduced_solve(h, v, keep, rhs, &step_s) || !reduced_inverse(evidence - noise, v, keep, &cov_s)) {
      return refused();
    }
    cov_s *= variance_factor;
  }
  if (!step_s.allFinite() || !cov_s.allFinite()) {
    return refused();
  }
  for (int i = 0; i < 4; ++i) {
    out.keep[i] = keep[i];
    for (int j = 0; j < 4; ++j) {
      out.basis[i][j] = v(i, j);
    }
    out.step[i] = step_s(i) * scale[i];
    out.axis_observable[i] = in_subspace(i) >= kAxisInSubspace;
    out.axis_share[i] = in_subspace(i);
    for (int j = 0; j < 4; ++j) {
      out.covariance[i][j] = cov_s(i, j) * scale[i] * scale[j];
    }
  }
  out.ok = true;
  return out;
}

bool jackknife_covariance(const GroupEquations4* groups, const bool* group_used, const Solve4& solve, float lever_m,
                          float covariance[4][4]) noexcept {
  if (!solve.ok || !(lever_m > 0.0F) || groups == nullptr || group_used == nullptr) {
    return false;
  }
  const float scale[4] = {1.0F, 1.0F, 1.0F, 1.0F / lever_m};
  Eigen::Matrix4f v;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      v(i, j) = solve.basis[i][j];
    }
  }
  auto scaled_group = [&scale](const GroupEquations4& eq, Eigen::Matrix4f* h, Eigen::Vector4f* b) {
    for (int i = 0; i < 4; ++i) {
      (*b)(i) = eq.b[i] * scale[i];
      for (int j = i; j < 4; ++j) {
        (*h)(i, j) = (*h)(j, i) = eq.h[i][j] * scale[i] * scale[j];
      }
    }
  };
  // The whole: the sum of the groups.
  Eigen::Matrix4f h_all = Eigen::Matrix4f::Zero();
  Eigen::Vector4f b_all = Eigen::Vector4f::Zero();
  for (int g = 0; g < kJackknifeGroups; ++g) {
    if (group_used[g]) {
      Eigen::Matrix4f h_g;
      Eigen::Vector4f b_g;
      scaled_group(groups[g], &h_g, &b_g);
      h_all += h_g;
      b_all += b_g;
    }
  }
  Eigen::Vector4f deltas[kJackknifeGroups];
  int used = 0;
  Eigen::Vector4f mean = Eigen::Vector4f::Zero();
  for (int g = 0; g < kJackknifeGroups; ++g) {
    if (!group_used[g]) {
      continue;
    }
    Eigen::Matrix4f h_g;
    Eigen::Vector4f b_g;
    scaled_group(groups[g], &h_g, &b_g);
    Eigen::Vector4f rhs = v.transpose() * (b_g - b_all);
    for (int k = 0; k < 4; ++k) {
      rhs(k) = solve.keep[k] ? rhs(k) : 0.0F;
    }
    if (!reduced_solve(h_all - h_g, v, solve.keep, rhs, &deltas[used])) {
      return false;  // the rest does not determine the subspace without this group: no estimate
    }
    mean += deltas[used];
    ++used;
  }
  if (used < 2) {
    return false;
  }
  mean /= static_cast<float>(used);
  Eigen::Matrix4f c = Eigen::Matrix4f::Zero();
  for (int k = 0; k < used; ++k) {
    const Eigen::Vector4f d = deltas[k] - mean;
    c += d * d.transpose();
  }
  c *= static_cast<float>(used - 1) / static_cast<float>(used);
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      covariance[i][j] = c(i, j) * scale[i] * scale[j];
    }
  }
  return true;
}

}  // namespace ccmap::detail
