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
//  - the outlier gate and the change rule (docs/design.md, "Outlier gate and change"): the gate
//    of every cell kind in double from its documented inequality (CCM and OMG against the cell's
//    current state, Kalman against its state before the frame, in Q14 integers), held points
//    per cell in slots of a pool of the documented capacity (in the order of their first held
//    point, kept over frames while the verdict is pending, dropped when their cell leaves its
//    window), the verdict from the documented counts, re-seed and merge in double.
// Generators must keep points away from cell edges and routing bounds (safe_point below), where
// any correct float/fixed-point arithmetic may legitimately decide either way, and out of the
// gate's margin (without_gate_ambiguity: a point whose gate statistic lies within 1 % of the
// gate, or within 3 Q14 units for a Kalman cell, is left out); then the stack must agree with
// the model exactly in counters, windows, cell presence and weights, and within float rounding
// (plus the fixed-point front's documented position error) in statistics.
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
                  too_noisy = 0, finer = 0, occluded = 0, held = 0, pool_full = 0, admitted = 0, dropped = 0, reseeded = 0, merged = 0;
  };
  /// Held points of one cell (a slot).
  struct Slot {
    int layer = 0;
    CellIndex index{};
    CcmCellDouble ccm;                                 // CCM layers: the held points folded in
    double omg_weight = 0.0, omg_height = 0.0, omg_s = 0.0;  // OMG
    double kalman_sum_z = 0.0, kalman_sum_r2 = 0.0;   // Kalman: Q14 heights, 2^-12 m^2 keys
    double kalman_sum_zz = 0.0;                       // and the squares of the Q14 heights
    std::uint32_t accepted = 0, count = 0, frames = 0;
  };

  explicit ModelStack(const S& stack) : stack_(stack) {
    const StackParams& p = stack.params();
    for (int k = 0; k < S::kLayerCount; ++k) {
      layers_[k].width = stack.layer_cell_width(k);
      layers_[k].side = S::layer_side(k);
      // The documented floor variance: the largest range variance the layer receives (sigma_m at
      // its routing bound, capped by its IV-G bound or finest_max_sigma_m) plus the height
      // variance of the steepest traversable plane over the cell.
      const double width = layers_[k].width;
      double sigma = p.noise.sigma_at_range_sq(stack.layer_max_range_sq(k));
      const double admitted = S::layer_is_ccm(k) ? width / (4.0 * std::sqrt(3.0)) : double{p.finest_max_sigma_m};
      if (!(sigma <= admitted)) sigma = admitted;
      const double spread = double{p.max_inclination} * width;
      floor_variance_[k] = sigma * sigma + spread * spread / 12.0;
    }
  }

  /// The frame without the points whose gate decision the model finds within its margin, found
  /// by running the frame on copies of the model until none is (weights, if given, follow).
  std::vector<PointXYZ> without_gate_ambiguity(std::vector<PointXYZ> pts, std::vector<float>* weights,
                                               PointXYZ origin) const {
    return drop_ambiguous(std::move(pts), weights, [&](ModelStack& m, const std::vector<PointXYZ>& p,
                                                       const std::vector<float>* w) {
      m.frame_map(p, w != nullptr && !w->empty() ? w->data() : nullptr, origin);
    });
  }
  std::vector<PointXYZ> without_gate_ambiguity(std::vector<PointXYZ> pts, const Pose& pose) const {
    return drop_ambiguous(std::move(pts), nullptr,
                          [&](ModelStack& m, const std::vector<PointXYZ>& p, const std::vector<float>*) {
                            m.frame_sensor(p, pose);
                          });
  }

  /// Cells with held points awaiting the change rule (both pools).
  [[nodiscard]] std::size_t pending_cells() const { return ccm_slots_.size() + fine_slots_.size(); }

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
          c.scale_to(w);
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
    begin_frame(c);
    sight_origin_[0] = origin.x;
    sight_origin_[1] = origin.y;
    sight_origin_[2] = origin.z;
    c.received = static_cast<std::uint32_t>(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      point_ = i;
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
    finish_frame(c);
    return c;
  }

  /// One sensor-frame frame: the transform in double.
  Counts frame_sensor(const std::vector<PointXYZ>& pts, const Pose& pose) {
    Counts c;
    begin_frame(c);
    sight_origin_[0] = pose.translation.x;
    sight_origin_[1] = pose.translation.y;
    sight_origin_[2] = pose.translation.z;
    c.received = static_cast<std::uint32_t>(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      point_ = i;
      const PointXYZ& s = pts[i];
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
    finish_frame(c);
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
    EXPECT_EQ(c.gated_finer, m.finer) << what << ": dropped by the finer layer's gate";
    EXPECT_EQ(c.gated_occluded, m.occluded) << what << ": dropped by the line of sight";
    EXPECT_EQ(c.gated_held, m.held) << what << ": held by the gate";
    EXPECT_EQ(c.gated_pool_full, m.pool_full) << what << ": gated, pool full";
    EXPECT_EQ(c.gated_admitted, m.admitted) << what << ": admitted";
    EXPECT_EQ(c.gated_dropped, m.dropped) << what << ": dropped";
    EXPECT_EQ(c.reseeded_cells, m.reseeded) << what << ": re-seeded cells";
    EXPECT_EQ(c.merged_cells, m.merged) << what << ": merged cells";
    EXPECT_EQ(stack_.held_cells(), pending_cells()) << what << ": cells with held points";
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
          if (it == l.cells.end() || !(it->second.ccm.weight > 0.0)) {  // never took a point
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
          // height across a Q14 step (2^-14 m = 61 um) in the model and not in the stack. And a
          // point's squared range may fall on the other side of a 2^-12 m^2 routing key in the
          // front's fixed point than in the model's double: that moves a batch's gain by up to
          // 2^-12 m^2 / (n r^2) relative, which across two batches of a cell far apart (held
          // points merged or re-seeding beside the points inside the gate, up to a metre) moves
          // the height by tens of micrometres.
          const double height_tol = pos_tol + (position_tolerance_m > 1e-6 ? 6.2e-5 : 0.0) + 5e-5;
          check(near_value(a.height, e.height, height_tol), i, "height");
          if constexpr (std::is_same_v<typename S::FineCell, KalmanCell>) {
            // The range variance comes from squared ranges quantised to 2^-12 m^2 (routing keys,
            // half a key of bias removed): at most 2^-13 / r^2 relative, 4.9e-4 at r = 0.5 m, twice
            // that in a variance ~ r^4. Cells of few points average little of it out.
            check(near_value(a.variance, e.variance, 1e-12, 2e-3), i, "variance");
          } else {
            check(near_value(a.s / a.weight, e.omg_s / e.weight, 1e-9, 2e-3), i, "omg variance");
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

  bool gate_on() const { return stack_.params().outlier_gate_sigma > 0.0F; }
  double gate_sigma_sq() const {
    const double k = stack_.params().outlier_gate_sigma;
    return k * k;
  }

  /// Records point_ as ambiguous when `statistic` lies within the margin of `limit`.
  void check_margin(double statistic, double limit, double margin) {
    if (std::fabs(statistic - limit) <= margin) ambiguous_.push_back(point_);
  }

  template <typename Run>
  std::vector<PointXYZ> drop_ambiguous(std::vector<PointXYZ> pts, std::vector<float>* weights, Run run) const {
    for (int pass = 0; pass < 20; ++pass) {
      ModelStack copy = *this;
      copy.ambiguous_.clear();
      run(copy, pts, weights);
      if (copy.ambiguous_.empty()) return pts;
      std::vector<bool> drop(pts.size(), false);
      for (std::size_t i : copy.ambiguous_) drop[i] = true;
      std::vector<PointXYZ> kept;
      std::vector<float> kept_weights;
      for (std::size_t i = 0; i < pts.size(); ++i) {
        if (drop[i]) continue;
        kept.push_back(pts[i]);
        if (weights != nullptr && !weights->empty()) kept_weights.push_back((*weights)[i]);
      }
      pts.swap(kept);
      if (weights != nullptr && !weights->empty()) weights->swap(kept_weights);
    }
    ADD_FAILURE() << "the gate margin filter did not converge";
    return pts;
  }

  /// Slot of a cell in `slots`, or nullptr.
  static Slot* find_slot(std::vector<Slot>& slots, int layer, CellIndex i) {
    for (Slot& s : slots) {
      if (s.layer == layer && s.index == i) return &s;
    }
    return nullptr;
  }

  /// A point outside its cell's gate: its slot (taken now with the cell's accepted points of
  /// this frame if it has none), or nullptr when the pool is full (counted).
  Slot* hold(Counts& c, std::vector<Slot>& slots, int layer, CellIndex i) {
    if (Slot* s = find_slot(slots, layer, i)) {
      ++s->count;
      ++c.held;
      return s;
    }
    if (slots.size() >= (&slots == &ccm_slots_ ? S::kCcmHeldSlots : S::kFineHeldSlots)) {
      ++c.pool_full;
      return nullptr;
    }
    Slot s;
    s.layer = layer;
    s.index = i;
    s.accepted = accepted_in_frame_[layer_key(layer, i)];
    s.count = 1;
    slots.push_back(s);
    ++c.held;
    return &slots.back();
  }

  /// A point inside its cell's gate: counted in its slot, or in the frame's count (saturating
  /// at 32767 as the documented tag).
  void accept(std::vector<Slot>& slots, int layer, CellIndex i) {
    if (Slot* s = find_slot(slots, layer, i)) {
      ++s->accepted;
      return;
    }
    std::uint32_t& n = accepted_in_frame_[layer_key(layer, i)];
    if (n < 32767U) ++n;
  }

  static std::uint64_t layer_key(int layer, CellIndex i) { return cell_key(i) ^ (static_cast<std::uint64_t>(layer) << 61); }

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
      frame_points_[layer_key(k, i)].push_back(point_);
      const double kv = gate_sigma_sq() * floor_variance_[k];
      if (S::layer_is_ccm(k)) {
        const double rx = x - (i.x + 0.5) * l.width, ry = y - (i.y + 0.5) * l.width;
        if (gate_on()) {
          // (z - mu_z)^2 W > k^2 (S_zz + W V)
          const double dz = z - cell.ccm.mean_z;
          const double lhs = dz * dz * cell.ccm.weight;
          const double rhs = gate_sigma_sq() * cell.ccm.s_zz + cell.ccm.weight * kv;
          if (cell.ccm.weight > 0.0) check_margin(lhs, rhs, 1e-2 * rhs);  // W = 0: 0 > 0, exact
          // The range-error checks judge points outside the gate and every point of a cell
          // below min_weight (not yet known).
          const double mature = std::max(double{params.min_weight}, 1e-30);
          // Float and double weights may round apart near the threshold (not when equal: integer
          // weights are exact in both).
          if (cell.ccm.weight != mature) check_margin(cell.ccm.weight, mature, 1e-4 * mature);
          if (lhs > rhs || !(cell.ccm.weight >= mature)) {
            if (contradicted_by_finer(k, x, y, z, kv)) {
              ++c.finer;
              return;
            }
            if (params.noise.kind() == sensor::SensorKind::kStereo && occluded(k, x, y, z)) {
              ++c.occluded;
              return;
            }
          }
          if (lhs > rhs) {
            if (Slot* s = hold(c, ccm_slots_, k, i)) s->ccm.update(rx, ry, z, w, params.weight_limit);
            return;
          }
          accept(ccm_slots_, k, i);
        }
        cell.ccm.update(rx, ry, z, w, params.weight_limit);
      } else if constexpr (Config::kFineKind == FineKind::kKalman) {
        // The documented quantisation of the batch (docs/design.md 4.3): heights floored to Q14
        // metres and squared ranges to 2^-12 m^2, the bias removed by half a unit at the mean.
        Batch& b = batches_[cell_key(i)];
        const double h = std::floor(std::ldexp(z, 14));
        const double key = std::floor(std::ldexp(r2, 12));
        if (b.points == 0 && gate_on()) {
          // The gate of the frame: the cell's height before it (or this point's), half-width
          // sqrt(k^2 (P + V)), both floored to Q14.
          b.reference = cell.weight > 0.0 ? std::floor(std::ldexp(cell.height, 14)) : h;
          const double variance = cell.weight > 0.0 ? cell.variance : 0.0;
          b.half_width = std::floor(std::ldexp(std::sqrt(gate_sigma_sq() * variance + kv), 14));
        }
        ++b.points;
        if (gate_on()) {
          const double d = std::fabs(h - b.reference);
          check_margin(d, b.half_width, 3.0);
          if (d > b.half_width) {
            if (Slot* s = hold(c, fine_slots_, 0, i)) {
              s->kalman_sum_z += h;
              s->kalman_sum_r2 += key;
              s->kalman_sum_zz += h * h;
            }
            return;
          }
        }
        ++b.n;
        b.sum_z += h;
        b.sum_r2 += key;
      } else {
        double variance = sigma_at_range_sq(r2);
        variance *= variance;
        if (!(variance >= params.kalman_min_variance)) variance = params.kalman_min_variance;
        if (gate_on()) {
          // (z - h)^2 W > k^2 (s + W V)
          const double dz = z - cell.height;
          const double lhs = dz * dz * cell.weight;
          const double rhs = gate_sigma_sq() * cell.omg_s + cell.weight * kv;
          if (cell.weight > 0.0) check_margin(lhs, rhs, 1e-2 * rhs);  // W = 0: 0 > 0, exact
          if (lhs > rhs) {
            if (Slot* s = hold(c, fine_slots_, 0, i)) omg_update(s->omg_weight, s->omg_height, s->omg_s, z, variance, w);
            return;
          }
          accept(fine_slots_, 0, i);
        }
        omg_update(cell.weight, cell.height, cell.omg_s, z, variance, w);
      }
      ++c.used;
      return;
    }
    ++c.outside;
  }

  /// The documented finer-layer check: the next finer layer's cell at (x, y), if its window holds
  /// it and it has points, judges z with the gate constants of layer k (kv = k^2 V_k).
  bool contradicted_by_finer(int k, double x, double y, double z, double kv) {
    if (k == 0) return false;
    const Layer& f = layers_[k - 1];
    const CellIndex i{static_cast<std::int32_t>(std::floor(x / f.width)), static_cast<std::int32_t>(std::floor(y / f.width))};
    if (!f.contains(i)) return false;
    const auto it = f.cells.find(cell_key(i));
    if (it == f.cells.end()) return false;
    const Cell& cell = it->second;
    double lhs = 0.0, rhs = 0.0;
    if (S::layer_is_ccm(k - 1)) {
      const double dz = z - cell.ccm.mean_z;
      lhs = dz * dz * cell.ccm.weight;
      rhs = gate_sigma_sq() * cell.ccm.s_zz + cell.ccm.weight * kv;
      if (!(cell.ccm.weight > 0.0)) return false;
    } else if constexpr (Config::kFineKind == FineKind::kKalman) {
      if (!(cell.weight > 0.0)) return false;
      const double dz = z - cell.height;
      lhs = dz * dz;
      rhs = gate_sigma_sq() * cell.variance + kv;
    } else {
      if (!(cell.weight > 0.0)) return false;
      const double dz = z - cell.height;
      lhs = dz * dz * cell.weight;
      rhs = gate_sigma_sq() * cell.omg_s + cell.weight * kv;
    }
    check_margin(lhs, rhs, 1e-2 * rhs);
    return lhs > rhs;
  }

  /// The documented line-of-sight test: at the midpoint of sensor and point, the finest layer
  /// (up to k) whose window holds it and whose cell there holds points; occluded if that cell's
  /// height (CCM: mean) exceeds the line's height by more than k sqrt(V_k).
  bool occluded(int k, double x, double y, double z) {
    const double mx = 0.5 * (x + sight_origin_[0]), my = 0.5 * (y + sight_origin_[1]);
    const double line = 0.5 * (z + sight_origin_[2]);
    // The midpoint's cell: ambiguous within 10 um of a finest-layer edge (the stack forms it in
    // float cells from the anchor: map/update/line_of_sight.hpp).
    const double w0 = layers_[0].width;
    for (const double v : {mx, my}) {
      const double f = v / w0 - std::floor(v / w0);
      if (f * w0 < 1e-5 || (1.0 - f) * w0 < 1e-5) ambiguous_.push_back(point_);
    }
    const double margin = std::sqrt(gate_sigma_sq() * floor_variance_[k]);
    for (int j = 0; j <= k; ++j) {
      const Layer& l = layers_[j];
      const CellIndex i{static_cast<std::int32_t>(std::floor(mx / l.width)), static_cast<std::int32_t>(std::floor(my / l.width))};
      if (!l.contains(i)) continue;
      const auto it = l.cells.find(cell_key(i));
      if (it == l.cells.end()) continue;
      const Cell& cell = it->second;
      const bool known = S::layer_is_ccm(j) ? cell.ccm.weight > 0.0 : cell.weight > 0.0;
      if (!known) continue;
      const double ground = S::layer_is_ccm(j) ? cell.ccm.mean_z : cell.height;
      check_margin(ground - line, margin, 1e-2 * margin + 2e-5);
      return ground - line > margin;
    }
    return false;
  }

  void omg_update(double& weight, double& height, double& s, double z, double variance, double w) const {
    const double limit = stack_.params().weight_limit;
    const double total = weight + w;
    const double d = z - height;
    height += w / total * d;
    s += w * variance + w * d * (z - height);
    weight = total;
    if (weight > limit) {
      s *= limit / weight;
      weight = limit;
    }
  }

  /// The documented start of a frame: slots whose cell left its window are dropped.
  void begin_frame(Counts& c) {
    for (std::vector<Slot>* slots : {&ccm_slots_, &fine_slots_}) {
      std::vector<Slot> kept;
      for (const Slot& s : *slots) {
        if (layers_[s.layer].contains(s.index)) {
          kept.push_back(s);
        } else {
          c.dropped += s.count;
        }
      }
      slots->swap(kept);
    }
    accepted_in_frame_.clear();
    frame_points_.clear();
  }

  /// The Kalman batch of n points with these sums (heights in Q14 units, squared ranges in
  /// 2^-12 m^2 keys).
  void fuse_batch(Cell& cell, double sum_z, double sum_keys, std::uint32_t n) const {
    const StackParams& params = stack_.params();
    const double mean_z = std::ldexp(sum_z / n + 0.5, -14);
    double sigma = sigma_at_range_sq(std::ldexp(sum_keys / n + 0.5, -12));
    double r = sigma * sigma;
    if (!(r >= params.kalman_min_variance)) r = params.kalman_min_variance;
    const double batch = r / n;
    if (!(cell.weight > 0.0)) {
      cell.height = mean_z;
      cell.variance = std::max(batch, double{params.kalman_min_variance});
    } else {
      const double gain = cell.variance / (cell.variance + batch);
      cell.height += gain * (mean_z - cell.height);
      cell.variance = std::max(gain * batch, double{params.kalman_min_variance});
    }
    cell.weight += n;
  }

  /// The held heights' spread (sum of squared deviations, m^2) and weight of a slot.
  void spread_of(const Slot& s, double* spread, double* weight) const {
    if (S::layer_is_ccm(s.layer)) {
      *spread = s.ccm.s_zz;
      *weight = s.ccm.weight;
    } else if constexpr (Config::kFineKind == FineKind::kKalman) {
      const double n = s.count;
      *spread = std::ldexp(std::ldexp(s.kalman_sum_zz - s.kalman_sum_z * s.kalman_sum_z / n, -14), -14);
      *weight = n;
    } else {
      *spread = s.omg_s;
      *weight = s.omg_weight;
    }
  }

  /// The documented verdict, in float as written: 0 drop, 1 merge, 2 re-seed, 3 pending. A side
  /// (held, or inside the gate) is a surface with >= change_min_points points and >= change_share
  /// of all, the held side also tight (spread variance <= k^2 V) or a majority; held points that
  /// are no surface are dropped (or wait while they may and only lack points), held ones that
  /// are merge beside a surface inside the gate, else re-seed.
  int verdict(const Slot& s, Counts& c) {
    const StackParams& p = stack_.params();
    const float h = static_cast<float>(s.count);
    const float a = static_cast<float>(s.accepted);
    const float least = p.change_share * (a + h);
    double spread = 0.0, weight = 0.0;
    spread_of(s, &spread, &weight);
    const double limit = weight * gate_sigma_sq() * floor_variance_[s.layer];
    const bool tight = spread <= limit;
    int v = 0;
    if (h >= least) {
      if (h < p.change_min_points) {
        v = s.frames + 1 < detail::kMaxHeldFrames ? 3 : 0;
      } else if (!tight && h < 0.5F * (a + h)) {
        v = 0;
      } else {
        v = (a >= p.change_min_points && a >= least) ? 1 : 2;
      }
      if (h >= p.change_min_points && h < 0.5F * (a + h) && std::fabs(spread - limit) <= 1e-2 * limit) {
        // Tightness within the margin decides: leave this frame's points of the cell out.
        const auto it = frame_points_.find(layer_key(s.layer, s.index));
        if (it != frame_points_.end()) ambiguous_.insert(ambiguous_.end(), it->second.begin(), it->second.end());
      }
    }
    if (v == 0) c.dropped += s.count;
    if (v == 1 || v == 2) c.admitted += s.count;
    if (v == 1) ++c.merged;
    if (v == 2) ++c.reseeded;
    return v;
  }

  /// Chan merge of two CCM cells in double, then the limiter.
  static void merge(CcmCellDouble& a, const CcmCellDouble& b, double limit) {
    const double total = a.weight + b.weight;
    const double dx = b.mean_x - a.mean_x, dy = b.mean_y - a.mean_y, dz = b.mean_z - a.mean_z;
    const double f = a.weight * b.weight / total;
    a.s_xx += b.s_xx + dx * dx * f;
    a.s_yy += b.s_yy + dy * dy * f;
    a.s_zz += b.s_zz + dz * dz * f;
    a.s_xz += b.s_xz + dx * dz * f;
    a.s_yz += b.s_yz + dy * dz * f;
    a.s_xy += b.s_xy + dx * dy * f;  // the lateral co-moment (compared for full cells only)
    a.mean_x += dx * b.weight / total;
    a.mean_y += dy * b.weight / total;
    a.mean_z += dz * b.weight / total;
    a.weight = total;
    if (a.weight > limit) a.scale_to(limit);
  }

  /// The documented end of a frame: Kalman batches of the points inside the gate, then the
  /// verdict of every slot in order (pending ones kept).
  void finish_frame(Counts& c) {
    const StackParams& params = stack_.params();
    for (const auto& [key, b] : batches_) {
      if (b.n > 0) fuse_batch(layers_[0].cells[key], b.sum_z, b.sum_r2, b.n);
    }
    std::vector<Slot> kept;
    for (Slot& s : ccm_slots_) {
      const int v = verdict(s, c);
      Cell& cell = layers_[s.layer].cells[cell_key(s.index)];
      if (v == 2) cell.ccm = s.ccm;
      if (v == 1) merge(cell.ccm, s.ccm, params.weight_limit);
      if (v == 3) {
        ++s.frames;
        kept.push_back(s);
      }
    }
    ccm_slots_.swap(kept);
    kept.clear();
    for (Slot& s : fine_slots_) {
      Cell& cell = layers_[0].cells[cell_key(s.index)];
      if constexpr (Config::kFineKind == FineKind::kKalman) {
        const auto it = batches_.find(cell_key(s.index));
        if (it != batches_.end()) s.accepted += it->second.n;
      }
      const int v = verdict(s, c);
      if (v == 1 || v == 2) {
        if (v == 2) {
          cell = Cell{};
          cell.index = s.index;
        }
        if constexpr (Config::kFineKind == FineKind::kKalman) {
          fuse_batch(cell, s.kalman_sum_z, s.kalman_sum_r2, s.count);
        } else {
          // OMG merge (Chan), then the limiter; into an emptied cell it is the held cell itself.
          const double total = cell.weight + s.omg_weight;
          const double d = s.omg_height - cell.height;
          cell.omg_s += s.omg_s + d * d * cell.weight * s.omg_weight / total;
          cell.height += d * s.omg_weight / total;
          cell.weight = total;
          if (cell.weight > params.weight_limit) {
            cell.omg_s *= params.weight_limit / cell.weight;
            cell.weight = params.weight_limit;
          }
        }
      }
      if (v == 3) {
        ++s.frames;
        kept.push_back(s);
      }
    }
    fine_slots_.swap(kept);
    batches_.clear();
  }

  struct Batch {
    std::uint32_t n = 0, points = 0;
    double sum_z = 0.0, sum_r2 = 0.0;
    double reference = 0.0, half_width = 0.0;
  };
  const S& stack_;
  bool faded_ = false;  ///< an uncertain move happened: weights are no longer counts
  Layer layers_[S::kLayerCount];
  double floor_variance_[S::kLayerCount] = {};
  std::unordered_map<std::uint64_t, Batch> batches_;
  std::vector<Slot> ccm_slots_, fine_slots_;
  std::unordered_map<std::uint64_t, std::uint32_t> accepted_in_frame_;
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> frame_points_;  ///< this frame's points per cell
  std::size_t point_ = 0;
  std::vector<std::size_t> ambiguous_;
  double sight_origin_[3] = {0.0, 0.0, 0.0};
};

}  // namespace ccmap::test
