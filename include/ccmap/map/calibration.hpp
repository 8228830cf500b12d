// Calibration of the surface-normal variance threshold (paper Section IV-E, Fig. 4).
//
// A ground-truth step of the minimum obstacle height h covers a share c of a CCM cell of
// width w (edge parallel to a cell side); the cell is filled with samples of that surface and
// its surface-normal variance sigma_s^2 (eq. 11) is read. The threshold is sigma_s^2 at one
// chosen coverage (the paper: 50%); obstacles of height >= h are then flagged over the
// coverage interval where sigma_s^2 >= threshold.
//
// Analytic curve (continuous uniform sampling, no noise): with u = c (1 - c), eq. (11) along
// the step axis gives sigma_s^2 = h^2 u (1 - 3u). It peaks at c ~ 21% and 79% and has a local
// minimum h^2/16 at 50%; a threshold at 50% flags c (1 - c) >= 1/12, i.e. 9.2% .. 90.8% (the
// paper reports 11% .. 91% for its 32 cm / 24 cm case, from its own simulation).
//
// This is set-up code (O(n^2) cell updates per curve point, a few hundred points per
// calibration), float-only, allocation-free, exception-free.
#pragma once

#include "ccmap/core/status.hpp"

namespace ccmap {

/// Default and largest number of samples per cell axis for the simulated step.
inline constexpr int kCalibrationDefaultSamplesPerAxis = 32;
inline constexpr int kCalibrationMaxSamplesPerAxis = 256;
/// Largest accepted cell width, obstacle height and noise sigma (m): terrain cells are not
/// kilometres wide, and the simulated coordinates must stay well inside kMaxAbsCoordinateM.
inline constexpr float kCalibrationMaxLengthM = 1000.0F;
/// Coarse sweep step of the detection interval (share of the cell); the interval ends are
/// then refined by bisection to ~1e-7 (kCalibrationBisectionSteps halvings of one step).
inline constexpr int kCalibrationSweepSteps = 100;
inline constexpr int kCalibrationBisectionSteps = 17;

struct ThresholdCalibration {
  float threshold;             ///< sigma_s^2 (m^2) at the calibration coverage
  float detect_from_coverage;  ///< smallest coverage share in [0, 1] with sigma_s^2 >= threshold
  float detect_to_coverage;    ///< largest coverage share in [0, 1] with sigma_s^2 >= threshold
  /// True if every swept coverage between from and to also reaches the threshold. False when
  /// the threshold sits above the 50% minimum of the curve (calibration coverage between
  /// ~9% and ~91% but not 50%): the detected set is then two intervals around the peaks,
  /// with a gap around 50%. With noise the noisy curve's minimum moves slightly off 50%, so
  /// even a 50% threshold can leave a narrow gap (32 cm cell, 24 cm step, 1 cm noise, n = 32:
  /// 50.1% .. 51.3%, where sigma_s^2 is 0.03% below the threshold).
  bool interval_is_contiguous;
};

/// One point of the Fig. 4 curve: sigma_s^2 (m^2, eq. 11) of a CCM cell of width
/// cell_width_m filled with a step of height obstacle_height_m covering the share `coverage`
/// of the cell (the step occupies x > w/2 - c w; its edge is parallel to the y side).
///
/// Sampling: an n x n grid (n = samples_per_axis) of column midpoints, weight 1 each. The
/// column that the edge cuts is split into its two parts, each sampled at its own midpoint with
/// weight equal to its share of the column, so the covered share is exactly c and the curve is
/// continuous in c (not a staircase in steps of 1/n). Without noise the midpoint rule makes the
/// means and every moment with z exact; only sigma_xx^2 is short by the within-column variance, about
/// (w/n)^2/12, which lowers the result by at most ~h^2/(4 n^2) against the analytic curve.
///
/// Noise: z of every sample gets noise_sigma_m * g, g a deterministic, approximately normal
/// variate (sum of 12 uniforms - 6: mean 0, variance 1, bounded by +-6) drawn from a hash of
/// the grid position (both parts of a split column share their column's value). The same
/// positions get the same noise at every coverage (common random numbers), so the noisy curve
/// is smooth in c and identical on every target. Noise is vertical only.
///
/// Refused input (returns -1, never NaN): cell width or height not finite or <= 0 or
/// > kCalibrationMaxLengthM; coverage not in [0, 1]; samples_per_axis not in
/// [2, kCalibrationMaxSamplesPerAxis]; noise sigma NaN, negative or > kCalibrationMaxLengthM.
[[nodiscard]] float step_normal_variance(float cell_width_m, float obstacle_height_m,
                                         float coverage, int samples_per_axis,
                                         float noise_sigma_m) noexcept;

/// Section IV-E: threshold = step_normal_variance at `coverage` (default 0.5, the paper's
/// choice); detect_from/to = the coverage interval where the variance reaches the threshold
/// (sigma_s^2 >= threshold, so the calibration coverage itself is inside).
///
/// Interval search: the curve is evaluated at c = k / kCalibrationSweepSteps (k = 0..100);
/// the first and last sweep points that reach the threshold are found and each end is refined
/// by bisection against its outer neighbour (assumes one crossing within 0.01 of coverage,
/// true for the smooth step curve). The calibration coverage is always included. With a zero
/// threshold (coverage 0 or 1 without noise) every coverage is flagged: [0, 1].
///
/// Refused (*out unchanged, checked in this order): NaN/Inf width, height, coverage or noise
/// (kNonFiniteInput); out == nullptr, width or height <= 0, coverage outside [0, 1], negative
/// noise, samples_per_axis outside [2, kCalibrationMaxSamplesPerAxis] (kInvalidArgument);
/// width, height or noise above kCalibrationMaxLengthM (kOutOfRange).
[[nodiscard]] Status calibrate_normal_variance_threshold(
    float cell_width_m, float obstacle_height_m, ThresholdCalibration* out,
    float coverage = 0.5F, int samples_per_axis = kCalibrationDefaultSamplesPerAxis,
    float noise_sigma_m = 0.0F) noexcept;

}  // namespace ccmap
