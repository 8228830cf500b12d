// A brute-force, double-precision model of a Stack<Config>, independent of the library's update
// path: the documented rules re-implemented from the docs, not from the code.
//  - per layer a hash map from global cell index to the cell's state, with its own window (the
//    documented snapping rule: nearest even index), entries erased when they leave;
//  - validation (map frame: finite, |coordinate| <= 1e5 m; sensor frame: finite, |s| < 2^11 m,
//    and the transformed point within 1e5 m), the sensor -> map transform in double, the range
//    in double, routing by the stack's IV-G table (first layer whose squared bound holds the
//    range; the sensor itself is too noisy), the cell floor(x / w) in double, the walk to the
//    first coarser layer whose window holds the point;
//  - cells in double: CCM by the Welford update with the limiter (support/ccm_double.hpp), the
//    lateral covariance s_xy compared for full cells (CcmCell), not kept by paper cells;
//    Kalman by the documented frame batch (n points of a cell fused once per frame with their
//    mean height and the variance at their mean squared range over n); OMG per point.
// Generators must keep points away from cell edges and routing bounds (safe_point below), where
// any correct float/fixed-point arithmetic may legitimately decide either way; then the stack
// must agree with the model exactly in counters, windows, cell presence and weights, and within
// float rounding (plus the fixed-point front's documented position error) in statistics.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/ccm_double.hpp"

namespace ccmap::test {

inline std::uint64_t cell_key(CellIndex i) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i.x)) << 32) | static_cast<std::uint32_t>(i.y);
}

/// Equal within `absolute`, or within `relative` of the larger magnitude.
inline bool near_value(double a, double b, double absolute, double relative = 1e-4) {
  const double d = std::fabs(a - b);
  return d <= absolute || d <= relative * std::max(std::fabs(a), std::fabs(b));
}

template <typename Config>
class ModelStack {
 public:
  using S = Stack<Config>;

  struct Cell {
    CellIndex index{};
    CcmCellDouble ccm;
    double height = 0.0, variance = 0.0, weight = 0.0, omg_s = 0.0;  // Kalman / OMG
  };
  struct Layer {
    double width = 0.0;
    std::int32_t side = 0;
    CellIndex centre{0, 0};
    std::unordered_map<std::uint64_t, Cell> cells;
    bool contains(CellIndex i) const {
      const std::int32_t half = side / 2;
      return i.x >= centre.x - half && i.x < centre.x + half && i.y >= centre.y - half && i.y < centre.y + half;
    }
  };
  struct Counts {
    std::uint32_t received = 0, used = 0, non_finite = 0, out_of_range = 0, bad_weight = 0, outside = 0,
                  too_noisy = 0;
  };

  explicit ModelStack(const S& stack) : stack_(stack) {
    for (int k = 0; k < S::kLayerCount; ++k) {
      layers_[k].width = stack.layer_cell_width(k);
      layers_[k].side = S::layer_side(k);
    }
  }

  /// The documented window rule: the nearest even index (a multiple of twice the width).
  void move_to(float x, float y) {
    for (Layer& l : layers_) {
      const float inv_double = 0.5F / static_cast<float>(l.width);
      const CellIndex c{2 * static_cast<std::int32_t>(std::floor(x * inv_double + 0.5F)),
                        2 * static_cast<std::int32_t>(std::floor(y * inv_double + 0.5F))};
      l.centre = c;
      for (auto it = l.cells.begin(); it != l.cells.end();) {
        it = l.contains(it->second.index) ? std::next(it) : l.cells.erase(it);
      }
    }
  }

  /// The documented uncertain move (docs/design.md, "Uncertainty with motion"), in double: the
  /// window move, then for every observed CCM cell W' = W s2 / (s2 + W i^2 sigma^2) from its own
  /// slope and normal variance (eqs. 9, 11 for the paper cell; the least-squares plane of the full
  /// cell, CcmCellDouble::slopes), at least min(W, max(min_weight, 1e-3)), every co-moment (s_xy
  /// too) scaled by W' / W; for every observed constant cell the height variance grows by
  /// (gx^2 + gy^2) sigma^2 (gradient from the observed 4-neighbours' heights: central,
  /// one-sided, or 0), at most 1e4 m^2.
  void move_to(float x, float y, double sigma) {
    move_to(x, y);
    if (!(sigma > 0.0)) return;
    faded_ = true;
    const double s2 = sigma * sigma;
    const StackParams& params = stack_.params();
    for (int k = 0; k < S::kLayerCount; ++k) {
      Layer& l = layers_[k];
      if (S::layer_is_ccm(k)) {
        for (auto& [key, cell] : l.cells) {
          CcmCellDouble& c = cell.ccm;
          if (!(c.weight > 0.0)) continue;
          double a = 0.0, b = 0.0;
          c.slopes(kHasLateralCovariance<typename S::CcmCellType>, &a, &b);
          const double i2 = a * a + b * b;
          if (!(i2 > 0.0)) continue;
          const double residual = std::max(0.0, c.var_zz() - c.cov_xz() * a - c.cov_yz() * b);
          double w = residual > 0.0 ? c.weight * residual / (residual + c.weight * i2 * s2) : 0.0;
          const double floor = std::min(c.weight, std::max(double{params.min_weight}, 1e-3));
          w = std::max(w, floor);
          if (w >= c.weight) continue;
          const double scale = w / c.weight;
          c.s_xx *= scale;
          c.s_yy *= scale;
          c.s_zz *= scale;
          c.s_xz *= scale;
          c.s_yz *= scale;
          c.s_xy *= scale;
          c.weight = w;
        }
      } else {
        const double width = l.width;
        const auto seen = [&](CellIndex i, double* h) {
          const auto it = l.cells.find(cell_key(i));
          if (it == l.cells.end() || !(it->second.weight > 0.0)) return false;
          *h = it->second.height;
          return true;
        };
        const auto gradient = [&](CellIndex lo, CellIndex hi, double h) {
          double a = 0.0, b = 0.0;
          const bool sa = seen(lo, &a), sb = seen(hi, &b);
          if (sa && sb) return (b - a) / (2.0 * width);
          if (sb) return (b - h) / width;
          if (sa) return (h - a) / width;
          return 0.0;
        };
        std::vector<std::pair<std::uint64_t, double>> grown;
        for (const auto& [key, cell] : l.cells) {
          if (!(cell.weight > 0.0)) continue;
          const CellIndex i = cell.index;
          const double gx = gradient(CellIndex{i.x - 1, i.y}, CellIndex{i.x + 1, i.y}, cell.height);
          const double gy = gradient(CellIndex{i.x, i.y - 1}, CellIndex{i.x, i.y + 1}, cell.height);
          const double variance = Config::kFineKind == FineKind::kOmg ? cell.omg_s / cell.weight : cell.variance;
          grown.emplace_back(key, std::min(1e4, variance + (gx * gx + gy * gy) * s2));
        }
        for (const auto& [key, v] : grown) {
          Cell& cell = l.cells[key];
          if (Config::kFineKind == FineKind::kOmg) {
            cell.omg_s = v * cell.weight;
          } else {
            cell.variance = v;
          }
        }
      }
    }
  }

  /// One map-frame frame (weights may be nullptr).
  Counts frame_map(const std::vector<PointXYZ>& pts, const float* weights, PointXYZ origin) {
    Counts c;
    c.received = static_cast<std::uint32_t>(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const PointXYZ& p = pts[i];
      if (!finite(p)) {
        ++c.non_finite;
        continue;
      }
      if (std::fabs(p.x) > 1e5F || std::fabs(p.y) > 1e5F || std::fabs(p.z) > 1e5F) {
        ++c.out_of_range;
        continue;
      }
      const double d[3] = {double{p.x} - origin.x, double{p.y} - origin.y, double{p.z} - origin.z};
      insert(c, p.x, p.y, p.z, d[0] * d[0] + d[1] * d[1] + d[2] * d[2], weights != nullptr ? &weights[i] : nullptr);
    }
    finish_frame();
    return c;
  }

  /// One sensor-frame frame: the transform in double.
  Counts frame_sensor(const std::vector<PointXYZ>& pts, const Pose& pose) {
    Counts c;
    c.received = static_cast<std::uint32_t>(pts.size());
    for (const PointXYZ& s : pts) {
      if (!finite(s)) {
        ++c.non_finite;
        continue;
      }
      if (std::fabs(s.x) >= 2048.0F || std::fabs(s.y) >= 2048.0F || std::fabs(s.z) >= 2048.0F) {
        ++c.out_of_range;
        continue;
      }
      double m[3];
      transform(pose, s, m);
      if (std::fabs(m[0]) > 1e5 || std::fabs(m[1]) > 1e5 || std::fabs(m[2]) > 1e5) {
        ++c.out_of_range;
        continue;
      }
      insert(c, m[0], m[1], m[2], double{s.x} * s.x + double{s.y} * s.y + double{s.z} * s.z, nullptr);
    }
    finish_frame();
    return c;
  }

  static void transform(const Pose& pose, const PointXYZ& s, double m[3]) {
    const double t[3] = {pose.translation.x, pose.translation.y, pose.translation.z};
    for (int r = 0; r < 3; ++r) {
      m[r] = double{pose.rotation[r][0]} * s.x + double{pose.rotation[r][1]} * s.y + double{pose.rotation[r][2]} * s.z +
             t[r];
    }
  }

  /// True if the map-frame point (x, y) with squared range r2 is at least `margin_m` from every
  /// cell edge of the finest layer (hence of every layer) and 0.1 % from every squared routing
  /// bound: there every correct arithmetic routes and indexes it as this model does.
  bool safe_point(double x, double y, double r2, double margin_m) const {
    const double w = layers_[0].width;
    for (const double v : {x, y}) {
      const double f = v / w - std::floor(v / w);
      if (f * w < margin_m || (1.0 - f) * w < margin_m) return false;
    }
    for (int k = 0; k < S::kLayerCount; ++k) {
      const double bound = stack_.layer_max_range_sq(k);
      if (std::isfinite(bound) && std::fabs(r2 - bound) < 1e-3 * bound) return false;
    }
    return true;
  }

  /// Compares counters, windows and the whole storage of every layer with the model. Positions
  /// may differ by `position_tolerance_m` (the sensor-frame front's fixed-point error).
  void expect_matches(const FrameCounters& c, const Counts& m, const std::string& what,
                      double position_tolerance_m = 1e-6) const {
    EXPECT_EQ(c.received, m.received) << what;
    EXPECT_EQ(c.used, m.used) << what << ": used";
    EXPECT_EQ(c.rejected_non_finite, m.non_finite) << what << ": non-finite";
    EXPECT_EQ(c.rejected_out_of_range, m.out_of_range) << what << ": out of range";
    EXPECT_EQ(c.rejected_weight, m.bad_weight) << what << ": bad weight";
    EXPECT_EQ(c.outside_map, m.outside) << what << ": outside map";
    EXPECT_EQ(c.too_noisy, m.too_noisy) << what << ": too noisy";
    for (int k = 0; k < S::kLayerCount; ++k) {
      const Layer& l = layers_[k];
      ASSERT_EQ(stack_.layer_centre(k), l.centre) << what << ": layer " << k << " window";
      int mismatches = 0;
      std::string first;
      const double pos_tol = position_tolerance_m + 2e-6;  // + float rounding of a mean
      // Weights count points exactly with the constant model; the inverse-variance model weighs
      // by range, which the front quantises (Q16): relative 1e-3.
      // After an uncertain move CCM weights follow from the statistics (W' of the fading rule):
      // compared like them, 1e-3.
      const bool counting = stack_.params().noise.weight_mode() == sensor::WeightMode::kConstant && !faded_;
      const double weight_tol = counting ? 1e-5 : 1e-3;
      const auto check = [&](bool ok, CellIndex i, const char* field) {
        if (!ok && mismatches++ == 0) {
          first = std::string(field) + " of cell (" + std::to_string(i.x) + ", " + std::to_string(i.y) + ")";
        }
      };
      if (S::layer_is_ccm(k)) {
        const auto& grid = stack_.ccm_layer(k - S::kFineLayerCount);
        grid.for_each([&](CellIndex i, const typename S::CcmCellType& a) {
          const auto it = l.cells.find(cell_key(i));
          if (it == l.cells.end()) {
            check(a.weight == 0.0F, i, "presence");
            return;
          }
          const CcmCellDouble& e = it->second.ccm;
          check(near_value(a.weight, e.weight, 0.0, weight_tol), i, "weight");
          check(near_value(a.mean_x, e.mean_x, pos_tol) && near_value(a.mean_y, e.mean_y, pos_tol) &&
                    near_value(a.mean_z, e.mean_z, pos_tol),
                i, "mean");
          // Variances (m^2): relative 1e-3, or 2 * pos_tol * cell width absolute (a position error
          // e moves a co-moment per weight by about 2 e times the spread).
          const double var_tol = 2.0 * pos_tol * l.width + 1e-9;
          const double w = a.weight;
          check(near_value(a.s_xx / w, e.var_xx(), var_tol, 1e-3) && near_value(a.s_yy / w, e.var_yy(), var_tol, 1e-3) &&
                    near_value(a.s_zz / w, e.var_zz(), var_tol, 1e-3) &&
                    near_value(a.s_xz / w, e.cov_xz(), var_tol, 1e-3) && near_value(a.s_yz / w, e.cov_yz(), var_tol, 1e-3),
                i, "co-moments");
          if constexpr (kHasLateralCovariance<typename S::CcmCellType>) {
            // The lateral covariance of the full cell (issue 11): the same Welford rule, in double.
            check(near_value(a.s_xy / w, e.cov_xy(), var_tol, 1e-3), i, "lateral covariance s_xy");
          }
        });
      } else {
        stack_.fine_layer().for_each([&](CellIndex i, const typename S::FineCell& a) {
          const auto it = l.cells.find(cell_key(i));
          if (it == l.cells.end()) {
            check(a.weight == 0.0F, i, "presence");
            return;
          }
          const Cell& e = it->second;
          check(near_value(a.weight, e.weight, 0.0, 1e-5), i, "weight");
          // Kalman: the model quantises as documented; a sensor-frame position error may move a
          // height across a Q14 step (2^-14 m = 61 um) in the model and not in the stack.
          const double height_tol = pos_tol + (position_tolerance_m > 1e-6 ? 6.2e-5 : 0.0);
          check(near_value(a.height, e.height, height_tol), i, "height");
          if constexpr (std::is_same_v<typename S::FineCell, KalmanCell>) {
            check(near_value(a.variance, e.variance, 1e-12, 1e-3), i, "variance");
          } else {
            check(near_value(a.s / a.weight, e.omg_s / e.weight, 1e-9, 1e-3), i, "omg variance");
          }
        });
      }
      EXPECT_EQ(mismatches, 0) << what << ": layer " << k << ": " << mismatches << " cells differ from the model, first: "
                               << first;
    }
  }

 private:
  static bool finite(const PointXYZ& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

  double sigma_at_range_sq(double r2) const {
    return stack_.params().noise.sigma_at_range_sq(static_cast<float>(r2));
  }

  void insert(Counts& c, double x, double y, double z, double r2, const float* weight_in) {
    const StackParams& params = stack_.params();
    int first = -1;
    for (int k = 0; k < S::kLayerCount && first < 0 && r2 > 0.0; ++k) {
      if (r2 <= static_cast<double>(stack_.layer_max_range_sq(k))) first = k;
    }
    if (first < 0) {
      ++c.too_noisy;
      return;
    }
    const bool constant = params.noise.weight_mode() == sensor::WeightMode::kConstant;
    double w = weight_in != nullptr ? double{*weight_in}
                                    : (constant ? 1.0 : params.noise.weight_at_range_sq(static_cast<float>(r2)));
    if (!(w > 0.0 && w <= 1e6)) {
      ++c.bad_weight;
      return;
    }
    for (int k = first; k < S::kLayerCount; ++k) {
      Layer& l = layers_[k];
      const CellIndex i{static_cast<std::int32_t>(std::floor(x / l.width)), static_cast<std::int32_t>(std::floor(y / l.width))};
      if (!l.contains(i)) continue;
      Cell& cell = l.cells[cell_key(i)];
      cell.index = i;
      if (S::layer_is_ccm(k)) {
        cell.ccm.update(x - (i.x + 0.5) * l.width, y - (i.y + 0.5) * l.width, z, w, params.weight_limit);
      } else if constexpr (Config::kFineKind == FineKind::kKalman) {
        // The documented quantisation of the batch (docs/design.md 4.3): heights floored to Q14
        // metres, the bias removed by half a unit at the mean.
        Batch& b = batches_[cell_key(i)];
        ++b.n;
        b.sum_z += std::floor(std::ldexp(z, 14));
        b.sum_r2 += r2;
      } else {
        double variance = sigma_at_range_sq(r2);
        variance *= variance;
        if (!(variance >= params.kalman_min_variance)) variance = params.kalman_min_variance;
        const double total = cell.weight + w;
        const double d = z - cell.height;
        cell.height += w / total * d;
        cell.omg_s += w * variance + w * d * (z - cell.height);
        cell.weight = total;
        if (cell.weight > params.weight_limit) {
          cell.omg_s *= params.weight_limit / cell.weight;
          cell.weight = params.weight_limit;
        }
      }
      ++c.used;
      return;
    }
    ++c.outside;
  }

  void finish_frame() {
    const StackParams& params = stack_.params();
    for (const auto& [key, b] : batches_) {
      Cell& cell = layers_[0].cells[key];
      const double mean_z = std::ldexp(b.sum_z / b.n + 0.5, -14);
      double sigma = sigma_at_range_sq(b.sum_r2 / b.n);
      double r = sigma * sigma;
      if (!(r >= params.kalman_min_variance)) r = params.kalman_min_variance;
      const double batch = r / b.n;
      if (!(cell.weight > 0.0)) {
        cell.height = mean_z;
        cell.variance = std::max(batch, double{params.kalman_min_variance});
      } else {
        const double gain = cell.variance / (cell.variance + batch);
        cell.height += gain * (mean_z - cell.height);
        cell.variance = std::max(gain * batch, double{params.kalman_min_variance});
      }
      cell.weight += b.n;
    }
    batches_.clear();
  }

  struct Batch {
    std::uint32_t n = 0;
    double sum_z = 0.0, sum_r2 = 0.0;
  };
  const S& stack_;
  bool faded_ = false;  ///< an uncertain move happened: weights are no longer counts
  Layer layers_[S::kLayerCount];
  std::unordered_map<std::uint64_t, Batch> batches_;
};

}  // namespace ccmap::test
