// An independent double-precision model of registration's normal equations, written from
// docs/design.md ("Registration") and registration/types.hpp, not from the library's code: its
// own sampling, routing, cell planes (least squares from the raw co-moments), bilinear surface,
// variances, robust weights, evidence, observability (Eigen, double) and jackknife. It reads the
// stack's raw cells through the public accessors only.
//
// evaluate(correction) builds the normal equations at a correction and answers the Gauss-Newton
// step from there, which axes are observable and their standard deviations (model and jackknife).
// At the library's solution the step must vanish and the answers agree.
#pragma once

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "ccmap/map/stack.hpp"

namespace ccmap::test {

struct ReferenceAnswer {
  bool ok = false;
  int matched = 0;
  double step[4] = {0, 0, 0, 0};    ///< Gauss-Newton step from the correction (m, m, m, rad)
  bool observable[4] = {false, false, false, false};
  double sigma_model[4] = {0, 0, 0, 0};
  double sigma_jack[4] = {0, 0, 0, 0};
  double lever = 0.0;
};

template <typename Config>
class ReferenceRegistration {
  static_assert(Stack<Config>::kCcmCellKind == CcmCellKind::kFull, "the reference models the full CCM cell");

 public:
  using S = Stack<Config>;

  ReferenceRegistration(const S& stack, const std::vector<PointXYZ>& points, PointXYZ origin,
                        const RegistrationParams& params)
      : stack_(stack), params_(params), ox_(origin.x), oy_(origin.y), oz_(origin.z) {
    // Every k-th point, k = ceil(n / max_points), from k / 2 (registration/registration.hpp).
    const std::size_t n = points.size();
    const std::size_t k = std::max<std::size_t>(1, (n + params.max_points - 1) / params.max_points);
    const double sigma_per_r2 = stack.params().noise.stereo_sigma_per_range_sq();
    for (std::size_t i = k / 2; i < n; i += k) {
      const PointXYZ& p = points[i];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
      const double dx = double(p.x) - ox_, dy = double(p.y) - oy_, dz = double(p.z) - oz_;
      const double r2 = dx * dx + dy * dy + dz * dz;
      int layer = -1;
      for (int l = 0; l < S::kLayerCount; ++l) {
        if (r2 <= double(stack.layer_max_range_sq(l))) {
          layer = l;
          break;
        }
      }
      if (layer < 0) continue;
      const double sigma = sigma_per_r2 * r2;
      samples_.push_back(Sample{p.x, p.y, p.z, sigma * sigma, layer});
    }
  }

  /// The answer at correction (dx, dy, dz, dyaw).
  ReferenceAnswer evaluate(const double c[4]) const {
    using M4 = Eigen::Matrix4d;
    using V4 = Eigen::Vector4d;
    M4 h = M4::Zero(), e = M4::Zero(), noise = M4::Zero();
    V4 b = V4::Zero();
    M4 hg[8];
    V4 bg[8];
    bool used[8] = {};
    for (int g = 0; g < 8; ++g) {
      hg[g].setZero();
      bg[g].setZero();
    }
    double sum_w = 0, sum_wl2 = 0, sum_rob = 0, sum_rob_e2 = 0;
    int matched = 0;
    const double cs = std::cos(c[3]), sn = std::sin(c[3]);
    const double block = stack_.layer_cell_width(S::kLayerCount - 1);
    for (const Sample& s : samples_) {
      const double px = s.x - ox_, py = s.y - oy_;
      const double qx = cs * px - sn * py + ox_ + c[0];
      const double qy = sn * px + cs * py + oy_ + c[1];
      const double qz = s.z + c[2];
      Plane pl;
      if (!surface(qx, qy, s.layer, &pl)) continue;
      const double r = qz - pl.h;
      double var = pl.var + params_.model_variance_m2;
      const double rx = qx - ox_, ry = qy - oy_, rz = qz - oz_;
      const double across = rz - pl.gx * rx - pl.gy * ry;
      var += s.ray_var * across * across / (rx * rx + ry * ry + rz * rz);
      const double e2 = r * r / var;
      const double c2 = double(params_.robust_sigmas) * params_.robust_sigmas;
      const double robust = 1.0 / (1.0 + e2 / c2);
      const double w = robust / var;
      const double lx = pl.lx - ox_, ly = pl.ly - oy_;
      V4 j(-pl.gx, -pl.gy, 1.0, pl.gx * ly - pl.gy * lx);
      h += w * j * j.transpose();
      b += w * j * r;
      const auto bx = static_cast<std::uint32_t>(static_cast<std::int32_t>(std::floor(float(qx) * float(1.0 / block))));
      const auto by = static_cast<std::uint32_t>(static_cast<std::int32_t>(std::floor(float(qy) * float(1.0 / block))));
      const std::uint32_t g = ((bx * 73856093U) ^ (by * 19349663U)) >> 29U;
      hg[g] += w * j * j.transpose();
      bg[g] += w * j * r;
      used[g] = true;
      if (pl.evidence) {
        e += w * j * j.transpose();
        Eigen::Matrix<double, 4, 2> a;
        a << -1, 0, 0, -1, 0, 0, ly, -lx;
        Eigen::Matrix2d cg;
        cg << pl.vgx, pl.cgxy, pl.cgxy, pl.vgy;
        noise += w * a * cg * a.transpose();
      } else {
        const double prior = double(params_.max_translation_m) * params_.max_translation_m;
        e(2, 2) += w / (1.0 + w * (pl.gx * pl.gx + pl.gy * pl.gy) * prior);
      }
      ++matched;
      sum_w += w;
      sum_wl2 += w * (lx * lx + ly * ly);
      sum_rob += robust;
      sum_rob_e2 += robust * e2;
    }
    ReferenceAnswer out;
    out.matched = matched;
    if (matched < int(params_.min_matches)) return out;
    const double lever = std::max(1e-3, std::sqrt(sum_wl2 / sum_w));
    out.lever = lever;
    const double vf = std::max(1.0, sum_rob_e2 / sum_rob);
    // Yaw as a length: S = diag(1, 1, 1, lever).
    const V4 sc(1, 1, 1, 1.0 / lever);
    const M4 sm = sc.asDiagonal();
    const M4 hs = sm * h * sm, es = sm * e * sm, ns = sm * noise * sm;
    const V4 bs = sm * b;
    Eigen::SelfAdjointEigenSolver<M4> eig(es - 2.0 * ns);
    const double max_sigma = params_.max_sigma_m;
    std::vector<int> kept;
    for (int k = 0; k < 4; ++k) {
      const double l = eig.eigenvalues()(k);
      if (l >= vf / (max_sigma * max_sigma) && l > 1e-6 * eig.eigenvalues()(3)) kept.push_back(k);
    }
    Eigen::MatrixXd q(4, static_cast<Eigen::Index>(kept.size()));
    for (std::size_t i = 0; i < kept.size(); ++i) q.col(Eigen::Index(i)) = eig.eigenvectors().col(kept[i]);
    V4 share = V4::Zero();
    for (std::size_t i = 0; i < kept.size(); ++i) share += q.col(Eigen::Index(i)).cwiseProduct(q.col(Eigen::Index(i)));
    V4 step = V4::Zero();
    M4 cov = M4::Zero(), jack = M4::Zero();
    if (!kept.empty()) {
      const Eigen::MatrixXd hq = q.transpose() * hs * q;
      step = -q * hq.ldlt().solve(q.transpose() * bs);
      const Eigen::MatrixXd eq = q.transpose() * (es - ns) * q;
      cov = vf * q * eq.inverse() * q.transpose();
      // Delete-one-group jackknife over the groups that hold samples.
      std::vector<V4> deltas;
      for (int g = 0; g < 8; ++g) {
        if (!used[g]) continue;
        const M4 hgs = sm * hg[g] * sm;
        const V4 bgs = sm * bg[g];
        const Eigen::MatrixXd rest = q.transpose() * (hs - hgs) * q;
        deltas.push_back(q * rest.ldlt().solve(q.transpose() * (bgs - bs)));
      }
      V4 mean = V4::Zero();
      for (const V4& d : deltas) mean += d;
      mean /= double(deltas.size());
      for (const V4& d : deltas) jack += (d - mean) * (d - mean).transpose();
      jack *= double(deltas.size() - 1) / double(deltas.size());
    }
    for (int i = 0; i < 4; ++i) {
      // theta = theta_scaled / lever = theta_scaled * sc(3).
      out.step[i] = step(i) * sc(i);
      const double unscale = sc(i) * sc(i);
      out.sigma_model[i] = std::sqrt(cov(i, i) * unscale);
      out.sigma_jack[i] = std::sqrt(jack(i, i) * unscale);
      const double sd = std::max(out.sigma_model[i], out.sigma_jack[i]);
      out.observable[i] = share(i) >= 0.99 && sd <= (i == 3 ? max_sigma / lever : max_sigma);
    }
    out.ok = true;
    return out;
  }

 private:
  struct Sample {
    double x, y, z, ray_var;
    int layer;
  };
  struct Plane {
    double h, gx, gy, var, vgx, vgy, cgxy, lx, ly;
    bool evidence;
  };

  bool surface(double x, double y, int layer, Plane* out) const {
    int first = layer;
    if constexpr (S::kHasFine) {
      if (layer <= 0) {
        if (fine(x, y, out)) return true;
        first = 1;
      }
    }
    const int first_ccm = S::kHasFine ? 1 : 0;
    first = std::clamp(first, first_ccm, S::kLayerCount - 1);
    for (int l = first; l < S::kLayerCount; ++l)
      if (ccm(l, x, y, out)) return true;
    for (int l = first - 1; l >= first_ccm; --l)
      if (ccm(l, x, y, out)) return true;
    return false;
  }

  bool fine(double x, double y, Plane* out) const {
    const double w = stack_.layer_cell_width(0);
    const double u = x / w - 0.5, v = y / w - 0.5;
    const double i0 = std::floor(u), j0 = std::floor(v);
    const double fu = u - i0, fv = v - j0;
    double h[4], p[4], n[4];
    for (int k = 0; k < 4; ++k) {
      const CellIndex idx{std::int32_t(i0) + (k & 1), std::int32_t(j0) + (k >> 1)};
      const auto* cell = stack_.fine_layer().cell(idx);
      if (cell == nullptr || !(cell->weight >= stack_.params().min_weight) || !(cell->weight > 0)) return false;
      h[k] = cell->height;
      p[k] = cell->variance;
      n[k] = cell->weight;
    }
    const double wt[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
    const double ddx[4] = {-(1 - fv), 1 - fv, -fv, fv};
    const double ddy[4] = {-(1 - fu), -fu, 1 - fu, fu};
    out->h = out->gx = out->gy = 0;
    for (int k = 0; k < 4; ++k) {
      out->h += wt[k] * h[k];
      out->gx += ddx[k] * h[k] / w;
      out->gy += ddy[k] * h[k] / w;
    }
    const double g2 = out->gx * out->gx + out->gy * out->gy;
    out->var = out->vgx = out->vgy = out->cgxy = 0;
    for (int k = 0; k < 4; ++k) {
      const double pk = p[k] + g2 * w * w / (12.0 * n[k]);
      out->var += wt[k] * wt[k] * pk;
      out->vgx += ddx[k] * ddx[k] * pk / (w * w);
      out->vgy += ddy[k] * ddy[k] * pk / (w * w);
      out->cgxy += ddx[k] * ddy[k] * pk / (w * w);
    }
    const double twist = h[0] - h[1] - h[2] + h[3];
    out->vgx += twist * twist / (w * w) / 12.0;
    out->vgy += twist * twist / (w * w) / 12.0;
    out->lx = (i0 + 1) * w;
    out->ly = (j0 + 1) * w;
    out->evidence = false;
    return true;
  }

  bool ccm(int layer, double x, double y, Plane* out) const {
    const auto& grid = stack_.ccm_layer(layer - (S::kHasFine ? 1 : 0));
    CellIndex idx{};
    if (!grid.locate(float(x), float(y), &idx)) return false;
    const auto& c = grid.cell_unchecked(idx);
    const double w = stack_.layer_cell_width(layer);
    const double W = c.weight;
    if (!(W >= stack_.params().min_weight) || !(W > 0)) return false;
    const double sxx = c.s_xx / W, syy = c.s_yy / W, sxy = c.s_xy / W, sxz = c.s_xz / W, syz = c.s_yz / W, szz = c.s_zz / W;
    // Covered: the smaller eigenvalue of the lateral covariance at least tau^2 w^2 / 12.
    const double tau = stack_.params().coverage_tau;
    const double mean_l = 0.5 * (sxx + syy);
    const double rad = std::sqrt(0.25 * (sxx - syy) * (sxx - syy) + sxy * sxy);
    if (mean_l - rad < tau * tau * w * w / 12.0 * (1 - 1e-5)) return false;
    // Least-squares plane: [a b] = Sigma^-1 [sxz syz] (pseudo-inverse of a line: Sigma / trace^2).
    const double trace = sxx + syy, det = sxx * syy - sxy * sxy;
    double ixx, iyy, ixy;
    if (det > 1e-4 * trace * trace) {
      ixx = syy / det;
      iyy = sxx / det;
      ixy = -sxy / det;
    } else {
      ixx = sxx / (trace * trace);
      iyy = syy / (trace * trace);
      ixy = sxy / (trace * trace);
    }
    const double a = ixx * sxz + ixy * syz, bb = ixy * sxz + iyy * syz;
    const double ss = std::max(0.0, szz - a * sxz - bb * syz);
    const double cx = (idx.x + 0.5) * w, cy = (idx.y + 0.5) * w;
    const double dx = x - cx - c.mean_x, dy = y - cy - c.mean_y;
    out->h = c.mean_z + a * dx + bb * dy;
    out->gx = a;
    out->gy = bb;
    out->var = ss * (1.0 + (1.0 + dx * (ixx * dx + ixy * dy) + dy * (ixy * dx + iyy * dy)) / W);
    out->vgx = ss / W * ixx;
    out->vgy = ss / W * iyy;
    out->cgxy = ss / W * ixy;
    out->lx = cx + c.mean_x;
    out->ly = cy + c.mean_y;
    out->evidence = true;
    return true;
  }

  const S& stack_;
  RegistrationParams params_;
  double ox_, oy_, oz_;
  std::vector<Sample> samples_;
};

}  // namespace ccmap::test
