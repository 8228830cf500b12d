// Uncertainty with motion (robot-centric mapping with pose uncertainty, the paper's ref. on
// robot-centric elevation mapping): after a move whose position change the odometry knows only
// to sigma (m, 1-sigma, isotropic in x and y), the old contents of the map sit up to ~sigma from
// where they belong. On ground of inclination i that is a height error of variance i^2 sigma^2.
// Stack::move_to(x, y, sigma) applies it to every observed cell of every layer, in one pass
// after the window move (docs/design.md, "Uncertainty with motion"). Integrators need not read it.
//
//  - CCM cell (own statistics, not pooled): the variance of its height estimate at its mean,
//    sigma_s^2 / W (the plane term of the elevation variance, Section 2.4 of design.md), grows by
//    i^2 sigma^2 with i the cell's own inclination: W' = W sigma_s^2 / (sigma_s^2 + W i^2 sigma^2).
//    W and the co-moments S are scaled by W' / W, as the weight limiter scales them (eq. 7): the
//    variances, the mean, the slopes and the class stay, and the next points weigh W / W' times
//    more (the limiter forgets faster where the pose is uncertain). W' never falls below
//    min(W, min_weight): a known cell stays known by weight (its elevation variance then grows by
//    less than i^2 sigma^2). A flat cell (i = 0) is untouched.
//  - Kalman and OMG cells (piece-wise constant, no slope of their own): the gradient from the
//    observed 4-neighbours (central difference, one-sided at an unobserved neighbour, 0 without
//    either), and the height variance grows by (g_x^2 + g_y^2) sigma^2 (the Kalman filter's
//    process noise: its next gain grows; OMG: the mixture variance). At most kMaxHeightVariance.
//
// Cost: one pass over every cell of every layer (CADRE: 4,096 constant cells with 4 neighbour
// reads, 10,240 CCM cells), ~30 float operations per observed cell, none for an empty one.
#pragma once

#include <cstdint>
#include <limits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/core/assert.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/detail/layers.hpp"

namespace ccmap::detail {

/// Ceiling of a constant cell's height variance after motion (m^2): a 100 m sigma.
inline constexpr float kMaxHeightVariance = 1.0e4F;

/// The CCM rule above for one cell; sigma_sq = sigma^2 (m^2) > 0.
void ccm_forget_for_motion(CcmCell& cell, float sigma_sq, float min_weight) noexcept;
void ccm_forget_for_motion(CcmPaperCell& cell, float sigma_sq, float min_weight) noexcept;

/// Grown height variance of a constant cell with gradient (gx, gy): variance + (gx^2 + gy^2) sigma^2,
/// at most kMaxHeightVariance.
[[nodiscard]] float grown_variance(float variance, float gx, float gy, float sigma_sq) noexcept;

/// One gradient component from the heights of the two neighbours (observed or not) of a cell of
/// height h, cell width w: central, one-sided, or 0.
[[nodiscard]] float neighbour_gradient(bool low_seen, float low, bool high_seen, float high, float h, float w) noexcept;

/// Applies the rule to every observed cell of every layer. Precondition: sigma_sq > 0, finite; a
/// violation is reported to the assert hook and changes no cell (returns 0).
/// Integrity (map/detail/integrity.hpp): the pass reads every cell, so it checks each one first:
/// a cell an upset changed is reset to the distrusted cell (and neither changed nor read as a
/// neighbour); returns how many it reset. The cells it changes keep their checks.
template <typename Config>
[[nodiscard]] std::uint32_t forget_for_motion(LayerSet<Config>& layers, const StackParams& params,
                                              float sigma_sq) noexcept {
  CCMAP_ASSERT_OR_RETURN(sigma_sq > 0.0F && sigma_sq <= std::numeric_limits<float>::max(), 0U);
  using Layers = LayerSet<Config>;
  std::uint32_t corrupted = 0U;
  for (int c = 0; c < Layers::kCcmLayerCount; ++c) {
    layers.ccm[c].for_each([&](CellIndex, typename Layers::CcmCellType& cell) {
      if (!cell_intact(layers, cell)) {
        reset_cell(layers, cell);
        ++corrupted;
        return;
      }
      if (cell.weight > 0.0F) {
        ccm_forget_for_motion(cell, sigma_sq, params.min_weight);
        check_of(layers, cell) = cell_signature(cell);  // it was intact: the new check is its own
      }
    });
  }
  if constexpr (Layers::kHasFine) {
    using FineCell = typename Layers::FineCell;
    RingGrid<FineCell>& fine = layers.fine;
    const float w = layers.widths[0];
    // Heights are read, variances written: a cell's gradient never sees a grown variance.
    // Corrupted cells are reset first, so that no gradient reads one.
    fine.for_each([&](CellIndex, FineCell& cell) {
      if (!cell_intact(layers, cell)) {
        reset_cell(layers, cell);
        ++corrupted;
      }
    });
    fine.for_each([&](CellIndex i, FineCell& cell) {
      if (!(cell.weight > 0.0F)) {
        return;
      }
      const FineCell* west = fine.cell(CellIndex{i.x - 1, i.y});
      const FineCell* east = fine.cell(CellIndex{i.x + 1, i.y});
      const FineCell* south = fine.cell(CellIndex{i.x, i.y - 1});
      const FineCell* north = fine.cell(CellIndex{i.x, i.y + 1});
      const auto seen = [](const FineCell* n) { return n != nullptr && n->weight > 0.0F; };
      const auto height = [](const FineCell* n) { return n != nullptr ? n->height : 0.0F; };
      const float gx = neighbour_gradient(seen(west), height(west), seen(east), height(east), cell.height, w);
      const float gy = neighbour_gradient(seen(south), height(south), seen(north), height(north), cell.height, w);
      write_cell(layers, cell, [&](FineCell& grown) {
        if constexpr (Config::kFineKind == FineKind::kOmg) {
          // Mixture variance s / W grows by g^2 sigma^2.
          const float variance = grown.s / grown.weight;
          grown.s = grown_variance(variance, gx, gy, sigma_sq) * grown.weight;
        } else {
          grown.variance = grown_variance(grown.variance, gx, gy, sigma_sq);
        }
      });
    });
  }
  return corrupted;
}

}  // namespace ccmap::detail
