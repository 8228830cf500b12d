// The 4 x 4 algebra of registration with Eigen's fixed-size float types. Fixed-size Eigen
// objects live on the stack and never allocate (tests/registration/eigen_no_malloc_test.cpp
// runs this file under EIGEN_RUNTIME_NO_MALLOC); the core is built with -fno-exceptions, under
// which Eigen throws nothing; EIGEN_MAX_STATIC_ALIGN_BYTES is the same on every target (the
// ccmap_eigen target in the top CMakeLists.txt).
#include "ccmap/registration/detail/normal_equations.hpp"

#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Core>

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

/// One Jacobi rotation of the symmetric a (all of it) and of the eigenvector columns v in the
/// (p, q) plane that zeroes a[p][q] (Numerical Recipes' form: theta = (a_qq - a_pp) / (2 a_pq),
/// t = sgn(theta) / (|theta| + sqrt(theta^2 + 1)), A' = P^T A P, V' = V P).
void jacobi_rotate(float a[4][4], float v[4][4], int p, int q) noexcept {
  const float apq = a[p][q];
  const float h = a[q][q] - a[p][p];
  const float g = 100.0F * std::fabs(apq);
  float t = 0.0F;
  if (!(std::fabs(h) + g > std::fabs(h))) {
    t = apq / h;  // theta beyond float: t = 1 / (2 theta)
  } else {
    const float theta = 0.5F * h / apq;
    t = 1.0F / (std::fabs(theta) + std::sqrt(theta * theta + 1.0F));
    t = theta < 0.0F ? -t : t;
  }
  const float c = 1.0F / std::sqrt(t * t + 1.0F);
  const float s = t * c;
  for (int k = 0; k < 4; ++k) {
    const float akp = a[k][p];
    const float akq = a[k][q];
    a[k][p] = c * akp - s * akq;
    a[k][q] = s * akp + c * akq;
  }
  for (int k = 0; k < 4; ++k) {
    const float apk = a[p][k];
    const float aqk = a[q][k];
    a[p][k] = c * apk - s * aqk;
    a[q][k] = s * apk + c * aqk;
  }
  a[p][q] = 0.0F;
  a[q][p] = 0.0F;
  for (int k = 0; k < 4; ++k) {
    const float vkp = v[k][p];
    const float vkq = v[k][q];
    v[k][p] = c * vkp - s * vkq;
    v[k][q] = s * vkp + c * vkq;
  }
}

/// Sweeps of the cyclic Jacobi method before it gives up (it converges quadratically: a 4 x 4
/// float matrix takes 4 to 6).
constexpr int kJacobiSweeps = 50;

/// The eigen-decomposition (ascending eigenvalues, orthonormal eigenvectors) of the symmetric m
/// (its upper triangle is read) by the cyclic Jacobi method on plain arrays: no workspace sized
/// at run time, so no heap path in the object (Eigen's SelfAdjointEigenSolver tridiagonalises
/// through a self-adjoint product on dynamic blocks, whose workspace comes from malloc above
/// EIGEN_STACK_ALLOCATION_LIMIT: the symbol stayed in the archive). False if it did not
/// converge or a value is not finite. Each of these helpers has its own frame (noinline), so
/// that their temporaries do not add up on the caller's stack (docs/performance.md, the stack
/// of register_frame).
[[gnu::noinline]] bool decompose(const Eigen::Matrix4f& m, Eigen::Matrix4f* vectors, Eigen::Vector4f* values) noexcept {
  float a[4][4];
  float v[4][4];
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      a[i][j] = i <= j ? m(i, j) : m(j, i);
      v[i][j] = i == j ? 1.0F : 0.0F;
    }
  }
  bool converged = false;
  for (int sweep = 1; sweep <= kJacobiSweeps; ++sweep) {
    float off = 0.0F;
    for (int p = 0; p < 3; ++p) {
      for (int q = p + 1; q < 4; ++q) {
        off += std::fabs(a[p][q]);
      }
    }
    if (!(off > 0.0F)) {
      converged = !std::isnan(off);  // 0; a NaN never converges
      break;
    }
    // The first sweeps rotate only the larger elements; later, an element negligible beside
    // both diagonal entries is set to 0 (its rotation would change neither).
    const float threshold = sweep < 4 ? 0.2F * off / 16.0F : 0.0F;
    for (int p = 0; p < 3; ++p) {
      for (int q = p + 1; q < 4; ++q) {
        const float g = 100.0F * std::fabs(a[p][q]);
        if (sweep > 4 && !(std::fabs(a[p][p]) + g > std::fabs(a[p][p])) &&
            !(std::fabs(a[q][q]) + g > std::fabs(a[q][q]))) {
          a[p][q] = 0.0F;
          a[q][p] = 0.0F;
        } else if (std::fabs(a[p][q]) > threshold) {
          jacobi_rotate(a, v, p, q);
        }
      }
    }
  }
  if (!converged) {
    return false;
  }
  // Ascending order (selection sort of the four, columns with them).
  int order[4] = {0, 1, 2, 3};
  for (int i = 0; i < 3; ++i) {
    int least = i;
    for (int j = i + 1; j < 4; ++j) {
      least = a[order[j]][order[j]] < a[order[least]][order[least]] ? j : least;
    }
    const int swap = order[i];
    order[i] = order[least];
    order[least] = swap;
  }
  for (int k = 0; k < 4; ++k) {
    (*values)(k) = a[order[k]][order[k]];
    for (int i = 0; i < 4; ++i) {
      (*vectors)(i, k) = v[i][order[k]];
    }
  }
  return values->allFinite() && vectors->allFinite();
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
