// Independent double-precision references for the cell tests: batch (not incremental)
// weighted means, covariances and least-squares planes, computed from the raw points.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ccmap::test {

struct Point {
  double x;
  double y;
  double z;
  double w = 1.0;
};

/// Weighted population moments, the batch definition of what a CCM cell estimates.
struct RefMoments {
  double weight = 0.0;
  double mean_x = 0.0, mean_y = 0.0, mean_z = 0.0;
  double var_xx = 0.0, var_yy = 0.0, var_zz = 0.0, cov_xz = 0.0, cov_yz = 0.0, cov_xy = 0.0;

  double slope_x() const { return var_xx > 0.0 ? cov_xz / var_xx : 0.0; }
  double slope_y() const { return var_yy > 0.0 ? cov_yz / var_yy : 0.0; }
  /// Smaller eigenvalue of the lateral covariance [var_xx cov_xy; cov_xy var_yy] (closed form).
  double lateral_min_variance() const {
    const double mid = 0.5 * (var_xx + var_yy);
    const double half_gap = 0.5 * (var_xx - var_yy);
    return mid - std::sqrt(half_gap * half_gap + cov_xy * cov_xy);
  }
  /// Paper eq. (11) evaluated in double.
  double normal_variance() const {
    double r = var_zz;
    if (var_xx > 0.0) r -= cov_xz * cov_xz / var_xx;
    if (var_yy > 0.0) r -= cov_yz * cov_yz / var_yy;
    return r > 0.0 ? r : 0.0;
  }
};

inline RefMoments reference_moments(const std::vector<Point>& points) {
  RefMoments m;
  for (const Point& p : points) {
    m.weight += p.w;
    m.mean_x += p.w * p.x;
    m.mean_y += p.w * p.y;
    m.mean_z += p.w * p.z;
  }
  if (m.weight <= 0.0) return m;
  m.mean_x /= m.weight;
  m.mean_y /= m.weight;
  m.mean_z /= m.weight;
  for (const Point& p : points) {
    const double dx = p.x - m.mean_x, dy = p.y - m.mean_y, dz = p.z - m.mean_z;
    m.var_xx += p.w * dx * dx;
    m.var_yy += p.w * dy * dy;
    m.var_zz += p.w * dz * dz;
    m.cov_xz += p.w * dx * dz;
    m.cov_yz += p.w * dy * dz;
    m.cov_xy += p.w * dx * dy;
  }
  m.var_xx /= m.weight;
  m.var_yy /= m.weight;
  m.var_zz /= m.weight;
  m.cov_xz /= m.weight;
  m.cov_yz /= m.weight;
  m.cov_xy /= m.weight;
  return m;
}

/// Weighted least-squares plane z = c + a x + b y (normal equations, Cramer's rule) and the
/// weighted mean squared residual. Returns false if the 3x3 system is singular.
struct RefPlane {
  double a = 0.0, b = 0.0, c = 0.0, residual_variance = 0.0;
};

inline bool reference_plane(const std::vector<Point>& pts, RefPlane* out) {
  double s[3][3] = {}, r[3] = {};
  double wsum = 0.0;
  for (const Point& p : pts) {
    const double v[3] = {1.0, p.x, p.y};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) s[i][j] += p.w * v[i] * v[j];
      r[i] += p.w * v[i] * p.z;
    }
    wsum += p.w;
  }
  auto det3 = [](const double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  };
  const double d = det3(s);
  if (std::fabs(d) < 1e-300) return false;
  double sol[3];
  for (int k = 0; k < 3; ++k) {
    double m[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m[i][j] = (j == k) ? r[i] : s[i][j];
    sol[k] = det3(m) / d;
  }
  out->c = sol[0];
  out->a = sol[1];
  out->b = sol[2];
  double res = 0.0;
  for (const Point& p : pts) {
    const double e = p.z - (out->c + out->a * p.x + out->b * p.y);
    res += p.w * e * e;
  }
  out->residual_variance = wsum > 0.0 ? res / wsum : 0.0;
  return true;
}

/// Small deterministic generator (splitmix64) so that tests do not depend on the standard
/// library's distribution implementations and give the same points on every target.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0));
  }
  /// Standard normal (Box-Muller).
  double normal() {
    double u1 = uniform(0.0, 1.0);
    if (u1 < 1e-300) u1 = 1e-300;
    const double u2 = uniform(0.0, 1.0);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  std::uint64_t state_;
};

}  // namespace ccmap::test
