// The 4 x 4 algebra of registration: normal equations of (dx, dy, dz, dyaw), their
// eigen-decomposition for observability, the step and the covariance restricted to the
// observable directions. Implemented in src/registration/detail/normal_equations.cpp with Eigen's
// fixed-size float types (Matrix4f, SelfAdjointEigenSolver<Matrix4f>: no heap, no exceptions);
// this header names no Eigen type, so the public API stays free of it.
#pragma once

#include <cstdint>

namespace ccmap::detail {

/// Normal equations H = sum w J J^T, b = sum w J r of a weighted least-squares problem in the
/// four parameters (dx, dy, dz, dyaw): J the residual's gradient, r the residual, w its weight.
/// H is kept in two parts by what the residual's gradient is: evidence (E, add with evidence:
/// a CCM cell's plane) or not (F: it steers the step, H = E + F, but only its height counts,
/// add_height_evidence, into the evidence's z entry, E_zz). Beside them N = sum w A C A^T over
/// the evidence, the part of E that errors in J contribute on average (J = A g + e_z from an
/// estimated surface gradient g with covariance C: J = (-g_x, -g_y, 1, g_x l_y - g_y l_x),
/// A = [-1 0; 0 -1; 0 0; l_y -l_x]).
struct NormalEquations4 {
  float e[4][4];  ///< evidence, symmetric: the add functions fill the upper triangle
  float f[4][4];  ///< the rest of H, likewise
  float n[4][4];  ///< the gradient-noise information of the evidence, likewise
  float b[4];
  float height_evidence;  ///< information about dz alone from the residuals in F

  void clear() noexcept {
    for (int i = 0; i < 4; ++i) {
      b[i] = 0.0F;
      for (int j = 0; j < 4; ++j) {
        e[i][j] = 0.0F;
        f[i][j] = 0.0F;
        n[i][j] = 0.0F;
      }
    }
    height_evidence = 0.0F;
  }
  /// Adds one residual r with gradient j and weight w to E (evidence) or F, and to b
  /// (14 multiply-adds).
  void add(const float j[4], float w, float r, bool evidence) noexcept {
    float (*m)[4] = evidence ? e : f;
    for (int row = 0; row < 4; ++row) {
      const float wj = w * j[row];
      b[row] += wj * r;
      for (int col = row; col < 4; ++col) {
        m[row][col] += wj * j[col];
      }
    }
  }
  /// Adds the information w about dz alone.
  void add_height_evidence(float w) noexcept { height_evidence += w; }
  /// Adds w A C A^T to N for the gradient covariance C = [var_gx cov; cov var_gy] and lever (lx, ly).
  /// With a = (-1, 0, 0, ly), c = (0, -1, 0, -lx): A C A^T = var_gx a a^T + var_gy c c^T +
  /// cov (a c^T + c a^T), zero in the z row and column.
  void add_gradient_noise(float w, float var_gx, float var_gy, float cov_gxy, float lx, float ly) noexcept {
    const float vx = w * var_gx;
    const float vy = w * var_gy;
    const float cv = w * cov_gxy;
    n[0][0] += vx;
    n[0][1] += cv;
    n[0][3] += cv * lx - vx * ly;
    n[1][1] += vy;
    n[1][3] += vy * lx - cv * ly;
    n[3][3] += vx * ly * ly + vy * lx * lx - 2.0F * cv * lx * ly;
  }
};

/// One block of ground's part of H (every residual, evidence or not) and b, for the jackknife:
/// 20 floats, where NormalEquations4 keeps 53.
struct GroupEquations4 {
  float h[4][4];  ///< upper triangle filled
  float b[4];
  void clear() noexcept {
    for (int i = 0; i < 4; ++i) {
      b[i] = 0.0F;
      for (int j = 0; j < 4; ++j) {
        h[i][j] = 0.0F;
      }
    }
  }
  void add(const float j[4], float w, float r) noexcept {
    for (int row = 0; row < 4; ++row) {
      const float wj = w * j[row];
      b[row] += wj * r;
      for (int col = row; col < 4; ++col) {
        h[row][col] += wj * j[col];
      }
    }
  }
};

/// Solution of the normal equations in the observable subspace.
struct Solve4 {
  float step[4];           ///< -H^+ b over the observable directions (m, m, m, rad)
  float covariance[4][4];  ///< variance_factor * H^+ over the observable directions
  bool axis_observable[4]; ///< the axis lies in the observable subspace (>= 99 % of its length squared)
  float axis_share[4];     ///< share of each axis' squared length in the observable subspace, 0..1
  std::uint8_t rank;       ///< observable directions
  bool ok;                 ///< false: non-finite input, or the eigen solver did not converge
  float basis[4][4];       ///< the directions (columns, in the yaw-scaled space), observable ones flagged in keep
  bool keep[4];
};

/// Groups of the delete-one-group jackknife (jackknife_covariance).
inline constexpr int kJackknifeGroups = 8;

/// Observability: the eigen-decomposition of E + height evidence - noise_margin N, scaled to lengths (the yaw
/// times lever_m, m; lever_m > 0) and divided by variance_factor (>= 1: the residuals' own
/// scatter beyond their model). A direction is observable when its standard deviation is at
/// most max_sigma_m and its eigenvalue at least 1e-6 of the largest (float resolution of the
/// decomposition); noise_margin >= 1 asks that much more information than noise in the
/// gradients alone gives (1 removes its bias only).
/// Step: the Gauss-Newton step of H in the observable subspace, -Q (Q^T H Q)^-1 Q^T b.
/// Covariance: variance_factor Q (Q^T (E - N) Q)^-1 Q^T (the evidence without the noise's bias).
/// Bounded work: Eigen's tridiagonal QR on a 4 x 4 matrix (at most 30 * 4 sweeps), two 4 x 4 LDLT.
[[nodiscard]] Solve4 solve_normal_equations(const NormalEquations4& eq, float lever_m, float variance_factor,
                                            float max_sigma_m, float noise_margin) noexcept;

/// The delete-one-group jackknife covariance of the solution in the observable subspace of
/// `solve` (solve_normal_equations with the same lever_m, at the same solution): the groups'
/// normal equations (H: every residual; b ~ 0 summed over all of them at the solution). Without
/// group g the solution moves by delta_g = (H - H_g)^-1 (b_g - b) restricted to the subspace;
/// the estimate is (G - 1) / G sum (delta_g - mean)(delta_g - mean)^T over the G groups that hold
/// samples (G >= 2; else false). Groups are blocks of ground, so what their samples share (a rock
/// seen differently from two places, a cell whose plane misleads) shows as scatter between
/// groups, which the model covariance, built on independent samples, cannot show.
[[nodiscard]] bool jackknife_covariance(const GroupEquations4* groups, const bool* group_used, const Solve4& solve,
                                        float lever_m, float covariance[4][4]) noexcept;

}  // namespace ccmap::detail
