// Double-precision twin of the CCM cell's incremental update (ccm_cell.hpp, eqs. 1-7): the same
// Welford form and the same weight limiter, in double, with the lateral co-moment s_xy of the
// full cell (a paper-cell comparison ignores it). Fed the same float inputs in lockstep with a
// float cell, it separates the float rounding of the library from the statistics.
#pragma once

namespace ccmap::test {

struct CcmCellDouble {
  double weight = 0.0;
  double mean_x = 0.0, mean_y = 0.0, mean_z = 0.0;
  double s_xx = 0.0, s_yy = 0.0, s_zz = 0.0, s_xz = 0.0, s_yz = 0.0, s_xy = 0.0;

  void update(double x, double y, double z, double w, double weight_limit) {
    const double previous = weight;
    const double total = previous + w;
    const double gain = w / total;
    const double dx = x - mean_x, dy = y - mean_y, dz = z - mean_z;
    mean_x += gain * dx;
    mean_y += gain * dy;
    mean_z += gain * dz;
    const double k = w * (previous / total);
    s_xx += k * dx * dx;
    s_yy += k * dy * dy;
    s_zz += k * dz * dz;
    s_xz += k * dx * dz;
    s_yz += k * dy * dz;
    s_xy += k * dx * dy;
    weight = total;
    if (weight > weight_limit) scale_to(weight_limit);
  }
  /// Scales every co-moment by new_weight / weight and sets the weight (the limiter of eqs. 6-7,
  /// the fading of an uncertain move): the means stay. Precondition: weight > 0.
  void scale_to(double new_weight) {
    const double scale = new_weight / weight;
    s_xx *= scale;
    s_yy *= scale;
    s_zz *= scale;
    s_xz *= scale;
    s_yz *= scale;
    s_xy *= scale;
    weight = new_weight;
  }
  double var_xx() const { return weight > 0.0 ? s_xx / weight : 0.0; }
  double var_yy() const { return weight > 0.0 ? s_yy / weight : 0.0; }
  double var_zz() const { return weight > 0.0 ? s_zz / weight : 0.0; }
  double cov_xz() const { return weight > 0.0 ? s_xz / weight : 0.0; }
  double cov_yz() const { return weight > 0.0 ? s_yz / weight : 0.0; }
  double cov_xy() const { return weight > 0.0 ? s_xy / weight : 0.0; }

  /// Slopes (a, b) by the documented rule (docs/design.md section 2), in double. Paper cell:
  /// eq. (9) per axis, 0 along an axis of variance <= 1e-12. Full cell: the 2 x 2 solve with
  /// the lateral covariance; trace <= 1e-12: no slope; det <= 1e-4 trace^2 (a line of points):
  /// the pseudo-inverse Sigma / trace^2.
  void slopes(bool full_cell, double* a, double* b) const {
    const double vxx = var_xx(), vyy = var_yy(), cxz = cov_xz(), cyz = cov_yz();
    if (!full_cell) {
      *a = vxx > 1e-12 ? cxz / vxx : 0.0;
      *b = vyy > 1e-12 ? cyz / vyy : 0.0;
      return;
    }
    const double cxy = cov_xy(), trace = vxx + vyy, det = vxx * vyy - cxy * cxy;
    double ixx = 0.0, iyy = 0.0, ixy = 0.0;
    if (trace > 1e-12 && det > 1e-4 * trace * trace) {
      ixx = vyy / det;
      iyy = vxx / det;
      ixy = -cxy / det;
    } else if (trace > 1e-12) {
      ixx = vxx / (trace * trace);
      iyy = vyy / (trace * trace);
      ixy = cxy / (trace * trace);
    }
    *a = ixx * cxz + ixy * cyz;
    *b = ixy * cxz + iyy * cyz;
  }
};

}  // namespace ccmap::test
