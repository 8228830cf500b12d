// What registration matches against in a stack: the cells' own statistics (docs/design.md,
// "Registration"). Reads the stack through its public interface only (ccm_layer, fine_layer,
// params, layer_cell_width); no state of its own, so every call is const, allocation-free and
// bounded (at most one cell read per layer, four on the finest layer, per sample).
//
// Which cell. A sample carries the layer its range routes it to (Section IV-G: the layer whose
// cells its noise suits). It is matched against
//  - a piece-wise constant finest layer (Kalman, OMG): the bilinear surface through the centres
//    of the four known cells around it (height variance from their estimate variances, its
//    gradient from their differences); when one of the four is unknown, the next layer;
//  - a CCM layer: the layer's own cell there, not the pooled one, if it is known (covered,
//    eq. 12, and min_weight): its plane (eq. 10), its elevation variance at the point, and its
//    gradient's standard error, sigma_s^2 / W Sigma^+ (the least-squares plane's slope
//    covariance). Pooled cells are not used: a pooled cell's W counts the points of its
//    children, but a constant child enters as one sample, so W / n would overstate the plane's
//    precision many times (a 4 cm Kalman cell of 100 measurements is one height sample).
//  - If that layer does not know the point, the coarser layers in turn, then the finer ones.
//
// With the plane comes its gradient's covariance C_g (what the cell's statistics say about the
// slope's own error), which the solver takes off the information (registration/detail/solver.hpp),
// and the lever point the gradient belongs to (a CCM cell's mean; the centre of the four cell
// centres on the bilinear finest layer).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/grid/ring_index.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/registration/detail/solver.hpp"

namespace ccmap {
template <typename Config>
class Stack;
}  // namespace ccmap

namespace ccmap::detail {

/// Variance (m^2) of a constant cell's height estimate: the Kalman variance; an OMG cell's
/// mixture variance over its weight (the variance of a weighted mean).
[[nodiscard]] inline float constant_height_variance(const KalmanCell& cell) noexcept { return cell.variance; }
[[nodiscard]] inline float constant_height_variance(const OmgCell& cell) noexcept {
  return cell.weight > 0.0F ? omg_variance(cell) / cell.weight : 0.0F;
}

/// A stack's surface for registration (see the file comment).
template <typename Config>
class StackSurface {
 public:
  using StackType = Stack<Config>;
  using CcmCell = typename StackType::CcmCellType;
  static constexpr int kFirstCcm = StackType::kFineLayerCount;
  static constexpr int kLayers = StackType::kLayerCount;

  explicit StackSurface(const StackType& stack) noexcept : stack_(stack) {}

  [[nodiscard]] SurfaceAnswer at(float x, float y, int layer, SurfacePlane* out) const noexcept {
    bool inside = false;
    int first = layer;
    if constexpr (StackType::kHasFine) {
      if (layer <= 0) {
        if (fine_at(x, y, out, &inside)) {
          return SurfaceAnswer::kKnown;
        }
        first = kFirstCcm;
      }
    }
    first = first < kFirstCcm ? kFirstCcm : (first >= kLayers ? kLayers - 1 : first);
    for (int l = first; l < kLayers; ++l) {
      if (ccm_at(l, x, y, out, &inside)) {
        return SurfaceAnswer::kKnown;
      }
    }
    for (int l = first - 1; l >= kFirstCcm; --l) {
      if (ccm_at(l, x, y, out, &inside)) {
        return SurfaceAnswer::kKnown;
      }
    }
    return inside ? SurfaceAnswer::kUnknown : SurfaceAnswer::kOutside;
  }

 private:
  /// Bilinear surface of the four finest cells around (x, y), all known.
  [[nodiscard]] bool fine_at(float x, float y, SurfacePlane* out, bool* inside) const noexcept {
    const auto& grid = stack_.fine_layer();
    const float w = stack_.layer_cell_width(0);
    const float min_weight = stack_.params().min_weight;
    // Cell centres at (i + 1/2) w: u = x / w - 1/2 lies between centres i0 and i0 + 1.
    const float u = x / w - 0.5F;
    const float v = y / w - 0.5F;
    if (!(std::fabs(u) < 1.0e9F) || !(std::fabs(v) < 1.0e9F)) {
      return false;
    }
    const float fu0 = std::floor(u);
    const float fv0 = std::floor(v);
    const auto i0 = static_cast<std::int32_t>(fu0);
    const auto j0 = static_cast<std::int32_t>(fv0);
    const float fu = u - fu0;
    const float fv = v - fv0;
    float h[4] = {};
    float p[4] = {};
    float n[4] = {};
    for (int k = 0; k < 4; ++k) {
      const CellIndex index{i0 + (k & 1), j0 + (k >> 1)};
      const auto* cell = grid.cell(index);
      if (cell == nullptr) {
        return false;
      }
      *inside = true;
      if (!(cell->weight >= min_weight) || !(cell->weight > 0.0F)) {
        return false;
      }
      h[k] = cell->height;
      p[k] = constant_height_variance(*cell);
      n[k] = cell->weight;
    }
    // h = (1-fu)(1-fv) h00 + fu (1-fv) h10 + (1-fu) fv h01 + fu fv h11 (k = ix + 2 iy).
    const float a0 = (1.0F - fu) * (1.0F - fv);
    const float a1 = fu * (1.0F - fv);
    const float a2 = (1.0F - fu) * fv;
    const float a3 = fu * fv;
    const float inv_w = 1.0F / w;
    out->height = a0 * h[0] + a1 * h[1] + a2 * h[2] + a3 * h[3];
    out->slope_x = ((h[1] - h[0]) * (1.0F - fv) + (h[3] - h[2]) * fv) * inv_w;
    out->slope_y = ((h[2] - h[0]) * (1.0F - fu) + (h[3] - h[1]) * fu) * inv_w;
    // A constant cell's height is the mean of its points, i.e. the surface at their centroid,
    // which lies off the centre by about w / sqrt(12 n) per axis (n points spread over the
    // cell): on a gradient g that is a height error of variance |g|^2 w^2 / (12 n) beyond the
    // estimate's own (the Kalman variance knows only the range noise).
    const float g2 = out->slope_x * out->slope_x + out->slope_y * out->slope_y;
    for (int k = 0; k < 4; ++k) {
      p[k] += g2 * w * w / (12.0F * n[k]);
    }
    out->variance = a0 * a0 * p[0] + a1 * a1 * p[1] + a2 * a2 * p[2] + a3 * a3 * p[3];
    // The gradient's covariance: d/dx of the weights are (-(1-fv), (1-fv), -fv, fv) / w, d/dy
    // (-(1-fu), -fu, (1-fu), fu) / w; the heights independent with variances p.
    const float dx[4] = {-(1.0F - fv), 1.0F - fv, -fv, fv};
    const float dy[4] = {-(1.0F - fu), -fu, 1.0F - fu, fu};
    float vxx = 0.0F;
    float vyy = 0.0F;
    float vxy = 0.0F;
    for (int k = 0; k < 4; ++k) {
      vxx += dx[k] * dx[k] * p[k];
      vyy += dy[k] * dy[k] * p[k];
      vxy += dx[k] * dy[k] * p[k];
    }
    const float inv_w2 = inv_w * inv_w;
    // Beyond the heights' own errors, a surface that is no plane at the patch's scale (a rock's
    // rim) has no one gradient: the twist h00 - h10 - h01 + h11 changes the x gradient by
    // twist / w across the patch (and the y gradient alike), a spread of (twist / w)^2 / 12.
    const float twist = h[0] - h[1] - h[2] + h[3];
    const float spread = twist * twist * inv_w2 * (1.0F / 12.0F);
    out->var_gx = vxx * inv_w2 + spread;
    out->var_gy = vyy * inv_w2 + spread;
    out->cov_gxy = vxy * inv_w2;
    // The bilinear gradient along x is the difference quotient between the two cell-centre
    // columns (exact at their mid-line, x = (i0 + 1) w, for a quadratic surface), along y between
    // the rows: it belongs to the patch centre, not to the point.
    out->lever_x = (fu0 + 1.0F) * w;
    out->lever_y = (fv0 + 1.0F) * w;
    out->gradient_is_evidence = false;
    return true;
  }

  /// The plane of CCM layer `layer`'s own cell at (x, y), if known.
  [[nodiscard]] bool ccm_at(int layer, float x, float y, SurfacePlane* out, bool* inside) const noexcept {
    const auto& grid = stack_.ccm_layer(layer - kFirstCcm);
    CellIndex index{};
    if (!grid.locate(x, y, &index)) {
      return false;
    }
    *inside = true;
    const CcmCell& cell = grid.cell_unchecked(index);
    const float width = stack_.layer_cell_width(layer);
    const StackParams& params = stack_.params();
    if (!ccm_is_covered(cell, width, params.coverage_tau, params.min_weight)) {
      return false;
    }
    const CcmSurface surface = ccm_surface(cell);
    const float qx = x - grid::cell_centre(index.x, width);
    const float qy = y - grid::cell_centre(index.y, width);
    out->height = ccm_height_at(cell, surface, qx, qy);
    out->slope_x = surface.slope_x;
    out->slope_y = surface.slope_y;
    out->variance = ccm_elevation_variance(cell, surface, qx, qy);
    // Slope covariance of the least-squares plane: sigma_s^2 / W Sigma^+ (the paper cell's
    // eq. (9) slopes: diag(1 / sigma_xx^2, 1 / sigma_yy^2)).
    const float inv_w = 1.0F / cell.weight;
    const float var_xx = cell.s_xx * inv_w;
    const float var_yy = cell.s_yy * inv_w;
    const float scale = surface.normal_variance * inv_w;
    if constexpr (kHasLateralCovariance<CcmCell>) {
      const LateralInverse inv = lateral_inverse(var_xx, var_yy, cell.s_xy * inv_w);
      out->var_gx = scale * inv.xx;
      out->var_gy = scale * inv.yy;
      out->cov_gxy = scale * inv.xy;
    } else {
      out->var_gx = var_xx > kMinLateralVariance ? scale / var_xx : 0.0F;
      out->var_gy = var_yy > kMinLateralVariance ? scale / var_yy : 0.0F;
      out->cov_gxy = 0.0F;
    }
    out->lever_x = grid::cell_centre(index.x, width) + cell.mean_x;
    out->lever_y = grid::cell_centre(index.y, width) + cell.mean_y;
    out->gradient_is_evidence = true;
    return true;
  }

  const StackType& stack_;
};

}  // namespace ccmap::detail
