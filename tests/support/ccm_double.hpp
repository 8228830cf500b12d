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
    if (weight > weight_limit) {
      const double scale = weight_limit / weight;
      s_xx *= scale;
      s_yy *= scale;
      s_zz *= scale;
      s_xz *= scale;
      s_yz *= scale;
      s_xy *= scale;
      weight = weight_limit;
    }
  }
  double var_xx() const { return weight > 0.0 ? s_xx / weight : 0.0; }
  double var_yy() const { return weight > 0.0 ? s_yy / weight : 0.0; }
  double var_zz() const { return weight > 0.0 ? s_zz / weight : 0.0; }
  double cov_xz() const { return weight > 0.0 ? s_xz / weight : 0.0; }
  double cov_yz() const { return weight > 0.0 ? s_yz / weight : 0.0; }
  double cov_xy() const { return weight > 0.0 ? s_xy / weight : 0.0; }
};

}  // namespace ccmap::test
