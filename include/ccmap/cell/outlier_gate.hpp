// Outlier gate of one cell and the change rule of one frame (docs/design.md, "Outlier gate and
// change"). Real sensors return mismatches, dust, steam, vegetation, multipath: a point far
// from the surface tilts a CCM cell's plane through its covariance lever arm. The gate holds a
// point back when it lies farther from its cell than k standard deviations of what the cell and
// the sensor model predict; at the end of the frame the change rule decides from all the
// frame's points of the cell whether the held points were outliers (dropped), part of a second
// surface in the cell (merged: a rock or box covering part of it) or the cell's new content
// (re-seed: the ground after a pose jump, a cell first seeded by outliers, a rock covering it).
//
// The gate is a comparison of squared quantities, no division or square root: for a CCM cell
// with weight W, mean height mu_z and co-moment S_zz = W sigma_zz^2, a point at height z is
// outside iff
//     (z - mu_z)^2 W  >  k^2 (S_zz + W V)              (i.e. (z - mu_z)^2 > k^2 (sigma_zz^2 + V))
// 6 float operations per point. V is the layer's floor variance (gate_floor_variance): the
// largest range variance the layer receives plus the height spread of the steepest traversable
// plane over the cell, so that a cell holding a few points (sigma_zz^2 not yet informative) or
// a perfectly flat one still admits what the sensor and the terrain can do. The residual is
// taken from the cell's mean height, not its plane: sigma_zz^2 contains the plane's own slope
// spread, so the gate is wider than a plane residual on slopes by at most that spread, and
// needs neither the slopes (two divisions) nor the normal variance.
//
// Units: metres, m^2. Float only, allocation-free, O(1).
#pragma once

#include <cmath>
#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"

namespace ccmap {

/// Squared constants of one layer's gate: k^2 and k^2 V (m^2). k = 0 is not a gate (every
/// point would be outside): callers switch the gate off instead of calling these.
struct GateConstants {
  float sigma_sq;  ///< k^2
  float floor_sq;  ///< k^2 V, m^2
};

/// The floor variance V (m^2) of a layer: max_sigma_m^2 (the largest range noise the layer
/// receives, m) + (max_inclination * cell_width_m)^2 / 12 (the height variance of a plane of
/// the steepest traversable gradient over a square cell of that width).
[[nodiscard]] inline float gate_floor_variance(float max_sigma_m, float cell_width_m, float max_inclination) noexcept {
  const float spread = max_inclination * cell_width_m;
  return max_sigma_m * max_sigma_m + spread * spread * (1.0F / 12.0F);
}

/// The gate constants for k standard deviations and floor variance V (m^2).
[[nodiscard]] inline GateConstants make_gate_constants(float sigma, float floor_variance) noexcept {
  return GateConstants{sigma * sigma, sigma * sigma * floor_variance};
}

/// True if a point at height z (m, map frame) lies outside the gate of a CCM cell:
/// (z - mu_z)^2 W > k^2 (S_zz + W V). A never-observed cell (W = 0) gives 0 > 0: inside (its
/// first point is always taken). Any CCM cell type with weight, mean_z and s_zz.
template <typename Cell>
[[nodiscard]] inline bool ccm_outside_gate(const Cell& cell, float z, const GateConstants& gate) noexcept {
  const float dz = z - cell.mean_z;
  return dz * dz * cell.weight > gate.sigma_sq * cell.s_zz + cell.weight * gate.floor_sq;
}

/// The same for an OMG cell: (z - h)^2 W > k^2 (s + W V), s = W x mixture variance (which holds
/// the accepted points' own range variances). W = 0: inside.
[[nodiscard]] inline bool omg_outside_gate(const OmgCell& cell, float z, const GateConstants& gate) noexcept {
  const float dz = z - cell.height;
  return dz * dz * cell.weight > gate.sigma_sq * cell.s + cell.weight * gate.floor_sq;
}

/// The same for a Kalman cell in float, for points that only consult it (the finer-layer check
/// of a coarser layer's point): (z - h)^2 > k^2 (P + V) while W > 0; a never-observed cell: inside.
[[nodiscard]] inline bool kalman_outside_gate(const KalmanCell& cell, float z, const GateConstants& gate) noexcept {
  const float dz = z - cell.height;
  return cell.weight > 0.0F && dz * dz > gate.sigma_sq * cell.variance + gate.floor_sq;
}

/// Half-width (m) of a Kalman cell's gate: a point is outside iff |z - h| exceeds
/// sqrt(k^2 (P + V)), P the cell's height variance (0 for a never-observed cell). The Kalman
/// layer's frame batch compares in integers against this, once per cell and frame.
[[nodiscard]] inline float kalman_gate_half_width(const KalmanCell& cell, const GateConstants& gate) noexcept {
  const float variance = cell.weight > 0.0F ? cell.variance : 0.0F;
  return std::sqrt(gate.sigma_sq * variance + gate.floor_sq);
}

/// What the change rule does with a cell's held points.
enum class ChangeVerdict : std::uint8_t {
  kDrop = 0,     ///< outliers: too small a share of the cell's points, or too few in time
  kMerge = 1,    ///< a second surface in the cell: folded in beside what it holds
  kReseed = 2,   ///< the cell's new content: it is replaced by them
  kPending = 3,  ///< not enough points yet: keep them for the next frame
};

/// The change rule (StackParams change_min_points, change_share).
struct ChangeRule {
  float min_points;
  float share;
};

/// True if held points whose heights have variance spread_variance (m^2) are tight enough to be
/// a surface while a minority: spread_variance <= k^2 V, the gate's own floor (the spread a
/// single point may have about a cell). Compared as spread_sum <= weight * k^2 V, no division.
[[nodiscard]] inline bool held_is_tight(float spread_sum, float weight, const GateConstants& gate) noexcept {
  return spread_sum <= weight * gate.floor_sq;
}

/// Verdict for a cell that took `accepted` points inside its gate and `held` outside since its
/// first held point, at the end of a frame. `tight`: the held heights' spread is within the
/// gate's floor (held_is_tight); `may_wait`: whether the held points may wait for another
/// frame. A side of the cell's points is a surface of its own when it holds at least
/// min_points points and at least `share` of all n = accepted + held, and, for the held side,
/// is tight or a majority (scattered outliers are neither; a rock's face seen from the front is
/// most of its cell). Evaluated in float exactly as written (counts below 2^24 are exact):
///   held < share n                                -> kDrop     (outliers)
///   held < min_points                             -> kPending if may_wait, else kDrop
///   not tight and held < n / 2                    -> kDrop     (a scattered minority)
///   accepted < min_points or accepted < share n   -> kReseed   (only the held points are a surface)
///   otherwise                                     -> kMerge    (both are: a step inside the cell)
[[nodiscard]] inline ChangeVerdict change_verdict(std::uint32_t accepted, std::uint32_t held, bool tight,
                                                  bool may_wait, const ChangeRule& rule) noexcept {
  const float a = static_cast<float>(accepted);
  const float h = static_cast<float>(held);
  const float n = a + h;
  const float least = rule.share * n;
  if (!(h >= least)) {
    return ChangeVerdict::kDrop;
  }
  if (!(h >= rule.min_points)) {
    return may_wait ? ChangeVerdict::kPending : ChangeVerdict::kDrop;
  }
  if (!tight && !(h >= 0.5F * n)) {
    return ChangeVerdict::kDrop;
  }
  return (a >= rule.min_points && a >= least) ? ChangeVerdict::kMerge : ChangeVerdict::kReseed;
}

}  // namespace ccmap
