// Soak: a 10^4-frame moving traverse with no state corruption.
//
// What "rebuild" means here. A cell that leaves a window is cleared, so the map after a
// traverse is not a function of all frames: each cell in the final windows holds exactly the
// points routed to it since it last entered its window. Routing itself depends on the windows
// at the time of each frame (a point goes to the finest layer whose window holds it), so
// replaying the frames into a stack sitting at the final pose would route differently. The
// rebuild is therefore a brute-force model, replayed frame by frame alongside the stack:
//  - per layer, a hash map from global cell index to that cell's state, with its own window
//    (snapped centre recomputed from the documented rule and checked against the stack's),
//    entries erased when they leave;
//  - routing re-derived per point (IV-G range bound from the stack's table, finest window that
//    holds the point);
//  - each cell kept twice: in float through the public cell API (ccm_update; Kalman cells by
//    the documented frame batch, kalman_update_batch_unchecked), and in double (CCM cells: the
//    float cell must stay within a small relative error of it).
// The generated points keep 10 % of the finest cell width away from every cell edge and 0.1 %
// away from every IV-G range bound, so routing is unambiguous: any correct float arithmetic of
// the update path puts each point in the same cell. Then every cell's presence and weight must
// match the model exactly (an aliased, lost, stale or wrongly cleared cell, or cross-talk in
// the ring buffers over 10^4 moves, changes them) and its statistics within float rounding
// (the update path may order its float operations differently from the cell API).
// Compared at checkpoints over the whole storage of every layer, not by queries.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <unordered_map>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/ccm_double.hpp"
#include "support/hash_unit.hpp"
#include "support/map_state.hpp"

namespace ccmap {
namespace {

using S = Stack<CadreConfig>;

using ccmap::test::hash_unit;

std::uint64_t key(CellIndex i) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i.x)) << 32) | static_cast<std::uint32_t>(i.y);
}

struct ModelCell {
  CellIndex index{};
  CcmCell ccm{};
  KalmanCell kalman{};
  test::CcmCellDouble twin;
};

/// The brute-force model of one layer.
struct ModelLayer {
  float width = 0.0F;
  float inv_width = 0.0F;
  std::int32_t side = 0;
  CellIndex centre{0, 0};
  std::unordered_map<std::uint64_t, ModelCell> cells;

  bool contains(CellIndex i) const {
    const std::int32_t half = side / 2;
    return i.x >= centre.x - half && i.x < centre.x + half && i.y >= centre.y - half && i.y < centre.y + half;
  }
  /// The documented rule: the nearest even index (multiple of twice the width).
  void move_to(float x, float y) {
    const float inv_double = 0.5F / width;
    const CellIndex c{2 * static_cast<std::int32_t>(std::floor(x * inv_double + 0.5F)),
                      2 * static_cast<std::int32_t>(std::floor(y * inv_double + 0.5F))};
    if (c == centre) return;
    centre = c;
    for (auto it = cells.begin(); it != cells.end();) {
      it = contains(it->second.index) ? std::next(it) : cells.erase(it);
    }
  }
};

/// Equal within `relative` (default 1e-4), or within `absolute` (units of the field).
bool close(float a, float b, double absolute, double relative = 1e-4) {
  const double d = std::fabs(static_cast<double>(a) - static_cast<double>(b));
  return d <= absolute || d <= relative * std::max(std::fabs(static_cast<double>(a)), std::fabs(static_cast<double>(b)));
}

struct Model {
  const S& stack;
  ModelLayer layers[S::kLayerCount];

  explicit Model(const S& s) : stack(s) {
    for (int k = 0; k < S::kLayerCount; ++k) {
      layers[k].width = s.layer_cell_width(k);
      layers[k].inv_width = 1.0F / layers[k].width;
      layers[k].side = S::layer_side(k);
    }
  }

  void move_to(float x, float y) {
    for (ModelLayer& l : layers) l.move_to(x, y);
  }

  struct Batch {
    std::uint32_t count = 0;
    std::int64_t z_ref = 0;
    std::int64_t sum_dz = 0;
    std::uint64_t sum_range = 0;
  };
  std::unordered_map<std::uint64_t, Batch> batches;  // this frame's Kalman batches (layer 0)

  /// Fuses this frame's Kalman batches: n measurements of the variance at the mean squared
  /// range, as one update with their mean and R / n.
  void finish_frame() {
    const StackParams& params = stack.params();
    const float w0 = stack.layer_cell_width(0);
    const float unit = w0 * (1.0F / 256.0F);
    const float unit_sq = unit * unit;
    for (const auto& [k, b] : batches) {
      ModelCell& cell = layers[0].cells[k];
      const float count = static_cast<float>(b.count);
      const float mean_z = (static_cast<float>(b.z_ref) + static_cast<float>(b.sum_dz) / count + 0.5F) * unit;
      const float r2 = static_cast<float>(static_cast<std::int64_t>(b.sum_range / b.count)) * unit_sq;
      const float sigma = params.noise.sigma_at_range_sq(r2);
      float variance = sigma * sigma;
      if (!(variance >= params.kalman_min_variance)) variance = params.kalman_min_variance;
      detail::kalman_update_batch_unchecked(cell.kalman, mean_z, variance, b.count, params.kalman_min_variance);
    }
    batches.clear();
  }

  /// Returns true if the point was used.
  bool insert(const PointXYZ& p, const PointXYZ& origin) {
    const StackParams& params = stack.params();
    if (ccm_check_point(p.x, p.y, p.z) != Status::kOk) return false;
    // The documented range rule (map/frame_chunk.hpp): coordinates in fixed-point units of
    // w_0 / 256, floor(v * fl(256 / w_0)), squared in integers, back to m^2 in float.
    const float w0 = stack.layer_cell_width(0);
    const float scale = 256.0F / w0;
    const float unit = w0 * (1.0F / 256.0F);
    const float unit_sq = unit * unit;
    const auto units = [scale](float v) { return static_cast<std::int64_t>(std::floor(static_cast<double>(v) * scale)); };
    const std::int64_t dx = units(p.x) - units(origin.x), dy = units(p.y) - units(origin.y),
                       dz = units(p.z) - units(origin.z);
    const std::int64_t range_units_sq = dx * dx + dy * dy + dz * dz;
    const float range_sq = static_cast<float>(range_units_sq) * unit_sq;
    int first = -1;
    for (int k = 0; k < S::kLayerCount && first < 0 && range_units_sq > 0; ++k) {
      const float bound = stack.layer_max_range_sq(k) / unit_sq;
      if (!(bound < 9.0e18F) || range_units_sq <= static_cast<std::int64_t>(bound)) first = k;
    }
    if (first < 0) return false;
    const float weight = params.noise.weight_at_range_sq(range_sq);
    for (int k = first; k < S::kLayerCount; ++k) {
      ModelLayer& l = layers[k];
      CellIndex i{};
      if (!grid::index_of_position(p.x, p.y, l.inv_width, &i) || !l.contains(i)) continue;
      ModelCell& cell = l.cells[key(i)];
      cell.index = i;
      if (S::layer_is_ccm(k)) {
        const float rx = p.x - grid::cell_centre(i.x, l.width);
        const float ry = p.y - grid::cell_centre(i.y, l.width);
        EXPECT_EQ(ccm_update(cell.ccm, rx, ry, p.z, weight, params.weight_limit), Status::kOk);
        cell.twin.update(rx, ry, p.z, weight, params.weight_limit);
      } else {
        // The documented frame batch (docs/design.md 4.3): count, heights floored to the range
        // unit, squared ranges; fused by finish_frame().
        Batch& b = batches[key(i)];
        const auto z_units = static_cast<std::int64_t>(std::floor(static_cast<double>(p.z) * scale));
        if (b.count == 0U) b.z_ref = z_units;
        ++b.count;
        b.sum_dz += z_units - b.z_ref;
        b.sum_range += static_cast<std::uint64_t>(range_units_sq);
        (void)range_sq;
      }
      return true;
    }
    return false;
  }

  /// Compares the whole storage of every layer with the model (presence and weight exactly, the
  /// statistics within float rounding) and tracks the worst error of CCM cells against their
  /// double twins.
  void compare(int frame, double* worst_mean_m, double* worst_variance_rel) const {
    for (int k = 0; k < S::kLayerCount; ++k) {
      const ModelLayer& l = layers[k];
      ASSERT_EQ(stack.layer_centre(k), l.centre) << "layer " << k << " window differs at frame " << frame;
      const std::size_t n = S::layer_capacity(k);
      int mismatches = 0;
      if (S::layer_is_ccm(k)) {
        std::vector<CcmCell> expected(n, CcmCell{});
        for (const auto& [unused, c] : l.cells) {
          expected[grid::buffer_offset(c.index, l.side)] = c.ccm;
          const double w = c.ccm.weight;
          *worst_mean_m = std::max({*worst_mean_m, std::fabs(c.ccm.mean_x - c.twin.mean_x),
                                    std::fabs(c.ccm.mean_y - c.twin.mean_y), std::fabs(c.ccm.mean_z - c.twin.mean_z)});
          const double floor = 1e-8;  // m^2: below it a variance is rounding noise of a near-empty cell
          for (const auto& [f, d] : {std::pair<double, double>{c.ccm.s_xx / w, c.twin.var_xx()},
                                     std::pair<double, double>{c.ccm.s_yy / w, c.twin.var_yy()},
                                     std::pair<double, double>{c.ccm.s_zz / w, c.twin.var_zz()}}) {
            *worst_variance_rel = std::max(*worst_variance_rel, std::fabs(f - d) / std::max(d, floor));
          }
        }
        const CcmCell* stored = stack.ccm_layer(k - 1).storage();
        for (std::size_t i = 0; i < n; ++i) {
          const CcmCell& a = stored[i];
          const CcmCell& e = expected[i];
          const bool same = a.weight == e.weight && close(a.mean_x, e.mean_x, 1e-5) && close(a.mean_y, e.mean_y, 1e-5) &&
                            close(a.mean_z, e.mean_z, 1e-5) && close(a.s_xx, e.s_xx, 1e-9) && close(a.s_yy, e.s_yy, 1e-9) &&
                            close(a.s_zz, e.s_zz, 1e-9) && close(a.s_xz, e.s_xz, 1e-9) && close(a.s_yz, e.s_yz, 1e-9);
          mismatches += same ? 0 : 1;
        }
      } else {
        std::vector<KalmanCell> expected(n, KalmanCell{});
        for (const auto& [unused, c] : l.cells) expected[grid::buffer_offset(c.index, l.side)] = c.kalman;
        const KalmanCell* stored = stack.fine_layer().storage();
        for (std::size_t i = 0; i < n; ++i) {
          const KalmanCell& a = stored[i];
          const KalmanCell& e = expected[i];
          // The update path may derive sigma_m from a quantised range (relative 1e-4 or so): the
          // Kalman variance is compared at 1e-3, the height (through the gain) at 10 um.
          const bool same = a.weight == e.weight && close(a.height, e.height, 1e-5) &&
                            close(a.variance, e.variance, 1e-12, 1e-3);
          mismatches += same ? 0 : 1;
        }
      }
      EXPECT_EQ(mismatches, 0) << "layer " << k << ": " << mismatches << " cells differ from the rebuild at frame "
                               << frame;
    }
  }
};

TEST(StackSoak, TenThousandFrameTraverseMatchesABruteForceRebuild) {
  constexpr int kFrames = 10000;
  constexpr std::uint32_t kPointsPerFrame = 32;
  auto stack = std::make_unique<S>();
  ASSERT_EQ(stack->init(default_stack_params(0.04F)), Status::kOk);
  Model model(*stack);
  std::vector<PointXYZ> pts(kPointsPerFrame);
  FrameCounters totals{};
  std::uint32_t model_used = 0;
  double worst_mean_m = 0.0, worst_variance_rel = 0.0;
  for (int f = 0; f < kFrames; ++f) {
    // A figure-of-eight loop of +-12 m, ~1.5 cm per frame: windows move on every layer, cells
    // leave and re-enter, the loop crosses itself.
    const double t = 2.0 * 3.141592653589793 * f / 5000.0;
    const float rx = static_cast<float>(12.0 * std::sin(t));
    const float ry = static_cast<float>(6.0 * std::sin(2.0 * t));
    const float hx = static_cast<float>(std::cos(t)), hy = static_cast<float>(std::cos(2.0 * t));
    ASSERT_EQ(stack->move_to(rx, ry), Status::kOk);
    model.move_to(rx, ry);
    const PointXYZ origin{rx, ry, 0.5F};
    const float w0 = stack->layer_cell_width(0);
    std::size_t count = 0;
    for (std::uint32_t i = 0; i < kPointsPerFrame; ++i) {
      const std::uint32_t id = static_cast<std::uint32_t>(f) * kPointsPerFrame + i;
      // Ahead of the robot out to 6 m (some points beyond every IV-G bound), +-3 m sideways.
      const float ahead = 0.2F + 5.8F * hash_unit(id, 1U);
      const float side = 6.0F * hash_unit(id, 2U) - 3.0F;
      const float norm = 1.0F / std::sqrt(hx * hx + hy * hy + 1e-6F);
      const float x = rx + (hx * ahead - hy * side) * norm;
      const float y = ry + (hy * ahead + hx * side) * norm;
      // 10 % of the finest width away from every cell edge (coarser edges are finer edges).
      const float x_safe = (std::floor(x / w0) + 0.1F + 0.8F * hash_unit(id, 4U)) * w0;
      const float y_safe = (std::floor(y / w0) + 0.1F + 0.8F * hash_unit(id, 5U)) * w0;
      const float z = 0.05F * std::sin(0.7F * x_safe) + 0.03F * std::cos(1.3F * y_safe) + 0.004F * hash_unit(id, 3U);
      const float dx = x_safe - origin.x, dy = y_safe - origin.y, dz = z - origin.z;
      const float range_sq = dx * dx + dy * dy + dz * dz;
      bool near_bound = false;
      for (int k = 0; k < S::kLayerCount; ++k) {
        near_bound = near_bound || std::fabs(range_sq - stack->layer_max_range_sq(k)) < 1e-3F * stack->layer_max_range_sq(k);
      }
      if (!near_bound) pts[count++] = PointXYZ{x_safe, y_safe, z};
    }
    FrameCounters c{};
    ASSERT_EQ(stack->update_frame(pts.data(), count, origin, &c), Status::kOk);
    for (std::size_t i = 0; i < count; ++i) model_used += model.insert(pts[i], origin) ? 1U : 0U;
    model.finish_frame();
    ASSERT_EQ(c.used + c.rejected_non_finite + c.rejected_out_of_range + c.rejected_weight + c.outside_map +
                  c.too_noisy,
              c.received)
        << "frame counters do not add up at frame " << f;
    detail::accumulate(totals, c);
    if ((f + 1) % 1000 == 0) {
      model.compare(f, &worst_mean_m, &worst_variance_rel);
      ASSERT_FALSE(HasFailure()) << "state corrupted by frame " << f;
      ASSERT_TRUE(test::all_stored_finite(*stack)) << "NaN/Inf in the map at frame " << f;
    }
  }
  EXPECT_EQ(totals.used, model_used) << "the stack used a different number of points than the rebuild";
  EXPECT_EQ(std::memcmp(&totals, &stack->total_counters(), sizeof totals), 0) << "total counters drifted";
  EXPECT_GT(totals.used, kFrames * kPointsPerFrame / 2) << "most points should be mapped";
  EXPECT_GT(totals.too_noisy, 0U) << "the traverse should also exercise the IV-G refusal";
  std::printf("[ soak     ] traverse: %u points used; worst float vs double: mean %.2e m, variance %.2e rel\n",
              totals.used, worst_mean_m, worst_variance_rel);
  EXPECT_LT(worst_mean_m, 1e-5) << "a cell mean drifted from its double twin";
  EXPECT_LT(worst_variance_rel, 1e-3) << "a cell variance drifted from its double twin";
}

}  // namespace
}  // namespace ccmap
