// Piece-wise constant elevation cells: the baselines and the finest layer of a stack.
//
//  - Kalman height update (robot-centric elevation mapping, paper ref. [13]): a 1-D Kalman
//    filter on the cell height with measurement variance sigma_m^2 from the sensor model.
//    Its variance is the uncertainty of the height estimate; it ignores the spread of the
//    samples (the paper's criticism of it for large cells).
//  - OMG update (Optimal Mixture of Gaussians, paper ref. [14]): weighted mean of the
//    measurements with a variance of the Gaussian mixture, i.e. the weighted mean of
//    (sigma_m,i^2 + (z_i - mean)^2): it includes the sample spread.
//
// Units: metres (height relative to the stack origin), m^2 for variances. Float only,
// allocation-free, O(1). Refused input (Status != kOk) leaves the cell unchanged.
#pragma once

#include <cmath>
#include <cstdint>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/core/assert.hpp"
#include "ccmap/core/status.hpp"

namespace ccmap {

/// Smallest variance a Kalman cell keeps (m^2). Without a floor the variance of a static cell
/// decays towards 0 and new data stops counting; the floor plays the role of the CCM weight
/// limiter. 1e-8 m^2 = (0.1 mm)^2.
inline constexpr float kKalmanDefaultMinVariance = 1.0e-8F;

struct KalmanCell {
  float height;    ///< m, map frame; meaningless while weight == 0
  float variance;  ///< m^2, variance of the height estimate
  float weight;    ///< number of fused measurements (for coverage and export); 0 = never observed
};
static_assert(sizeof(KalmanCell) == 3U * sizeof(float), "KalmanCell must stay 3 packed floats");

struct OmgCell {
  float weight;    ///< W = sum of measurement weights; 0 = never observed
  float height;    ///< m, weighted mean of the measured heights
  float s;         ///< W * mixture variance (m^2)
};
static_assert(sizeof(OmgCell) == 3U * sizeof(float), "OmgCell must stay 3 packed floats");

/// kOk if z is finite and |z| <= kMaxAbsCoordinateM and 0 < variance (finite), else the reason.
[[nodiscard]] inline Status constant_check_measurement(float z, float measurement_variance) noexcept {
  if (!std::isfinite(z) || !std::isfinite(measurement_variance)) {
    return Status::kNonFiniteInput;
  }
  if (std::fabs(z) > kMaxAbsCoordinateM) {
    return Status::kOutOfRange;
  }
  return measurement_variance > 0.0F ? Status::kOk : Status::kInvalidArgument;
}

namespace detail {
/// The one Kalman update of the library: fuses a measurement of height z (m) with variance
/// `variance` (m^2) worth `count` measurements into the cell: h += K (z - h), K = P / (P + R),
/// P = K R (= P R / (P + R)), P >= min_variance; weight += count. An empty cell becomes the
/// measurement (P = R, floored). The single update (count 1), the frame batch (the mean of n
/// measurements with R / n, count n) and the merge of two cells (the other cell's height and
/// variance, its weight) are this function. Precondition: variance > 0 and finite, min_variance
/// > 0 (callers validate; asserted: the cell is left unchanged if not).
inline void kalman_fuse(KalmanCell& cell, float z, float variance, float count, float min_variance) noexcept {
  CCMAP_ASSERT_OR_RETURN(variance > 0.0F && variance <= 3.4e38F && min_variance > 0.0F, );
  if (!(cell.weight > 0.0F)) {
    cell.height = z;
    cell.variance = variance > min_variance ? variance : min_variance;
    cell.weight = count;
    return;
  }
  const float sum = cell.variance + variance;                    // > 0
  const float gain = cell.variance / sum;                        // Kalman gain K = P / (P + R)
  cell.height += gain * (z - cell.height);
  const float fused = gain * variance;                           // P R / (P + R) = K R
  cell.variance = fused > min_variance ? fused : min_variance;
  cell.weight += count;
}

inline void kalman_update_unchecked(KalmanCell& cell, float z, float measurement_variance,
                                    float min_variance) noexcept {
  kalman_fuse(cell, z, measurement_variance, 1.0F, min_variance);
}

/// n measurements of one frame with the same variance R fused at once: the Kalman update with
/// their mean and variance R / n, which equals n sequential updates with variance R in real
/// arithmetic while the floor does not engage (the floor then acts once per batch, not per
/// measurement). n == 1 is kalman_update_unchecked exactly.
inline void kalman_update_batch_unchecked(KalmanCell& cell, float mean_z, float measurement_variance,
                                          std::uint32_t n, float min_variance) noexcept {
  const float count = static_cast<float>(n);
  kalman_fuse(cell, mean_z, n == 1U ? measurement_variance : measurement_variance / count, count, min_variance);
}

inline void omg_update_unchecked(OmgCell& cell, float z, float measurement_variance, float w,
                                 float weight_limit) noexcept {
  const float weight = cell.weight + w;
  const float d = z - cell.height;
  const float gain = w / weight;
  cell.height += gain * d;
  // Mixture second moment about the new mean (Welford form):
  // s += w * sigma_m^2 + w * (z - mean_old) * (z - mean_new)
  cell.s += w * measurement_variance + w * d * (z - cell.height);
  cell.weight = weight;
  if (cell.weight > weight_limit) {
    cell.s *= weight_limit / cell.weight;
    cell.weight = weight_limit;
  }
}
}  // namespace detail

/// Kalman height update: h += K (z - h), K = P / (P + R), P = P R / (P + R), P >= min_variance.
/// The first measurement initialises h = z, P = R. Refused: non-finite/out-of-range z,
/// non-positive or non-finite measurement variance or min_variance (kInvalidArgument).
[[nodiscard]] inline Status kalman_update(KalmanCell& cell, float z, float measurement_variance,
                                          float min_variance = kKalmanDefaultMinVariance) noexcept {
  const Status status = constant_check_measurement(z, measurement_variance);
  if (status != Status::kOk) {
    return status;
  }
  if (!(min_variance > 0.0F) || !std::isfinite(min_variance)) {
    return Status::kInvalidArgument;
  }
  detail::kalman_update_unchecked(cell, z, measurement_variance, min_variance);
  return Status::kOk;
}

/// OMG update with measurement weight w (constant, or 1/sigma_m^2 for inverse-variance
/// weighting) and the same weight limiter as CCM (W <= W_l, variance unchanged by the limit).
[[nodiscard]] inline Status omg_update(OmgCell& cell, float z, float measurement_variance, float w,
                                       float weight_limit = kNoWeightLimit) noexcept {
  const Status status = constant_check_measurement(z, measurement_variance);
  if (status != Status::kOk) {
    return status;
  }
  if (ccm_check_weight(w) != Status::kOk) {
    return Status::kBadWeight;
  }
  if (ccm_check_weight_limit(weight_limit) != Status::kOk) {
    return Status::kInvalidArgument;
  }
  detail::omg_update_unchecked(cell, z, measurement_variance, w, weight_limit);
  return Status::kOk;
}

// ---------------------------------------------------------------------------------------------
// Merging two cells of the same ground (map exchange, persistence/exchange.hpp)
// ---------------------------------------------------------------------------------------------

/// Merges `other` into `cell` in information form: the Kalman update with `other`'s height as
/// the measurement and its variance as the measurement variance,
///   P = P_a P_b / (P_a + P_b),  h = h_a + (h_b - h_a) P_a / (P_a + P_b)
/// (1/P = 1/P_a + 1/P_b, h/P = h_a/P_a + h_b/P_b), then the floor P >= min_variance; the
/// weights (measurement counts) add. Two cells fed disjoint measurements merge to the cell fed
/// all of them, in real arithmetic and while the floor does not engage: the sequential Kalman
/// update is this information sum. An empty `other` leaves `cell` unchanged; an empty `cell`
/// becomes `other` (floored). Refused (cell unchanged): a non-finite or negative weight, a
/// non-finite height, or a non-positive or non-finite variance in a non-empty `other`, or a
/// non-positive min_variance (kInvalidArgument).
[[nodiscard]] inline Status kalman_merge(KalmanCell& cell, const KalmanCell& other, float min_variance) noexcept {
  if (!(min_variance > 0.0F) || !std::isfinite(min_variance) || !std::isfinite(other.weight) || other.weight < 0.0F) {
    return Status::kInvalidArgument;
  }
  if (!(other.weight > 0.0F)) {
    return Status::kOk;
  }
  if (!std::isfinite(other.height) || !std::isfinite(other.variance) || !(other.variance > 0.0F)) {
    return Status::kInvalidArgument;
  }
  detail::kalman_fuse(cell, other.height, other.variance, other.weight, min_variance);
  return Status::kOk;
}

/// The inverse of kalman_merge without the floor: given total = part (+) rest, writes rest,
///   P_r = P_p P_t / (P_p - P_t),  h_r = h_p + (h_t - h_p) P_p / (P_p - P_t),  n_r = n_t - n_p.
/// An empty `part` gives rest = total. Exact in real arithmetic while the floor has not acted on
/// `total`; the error grows like P_p / (P_p - P_t) (little new information: a cancellation).
/// Refused (*rest untouched): rest == nullptr (kInvalidArgument); a negative or non-finite
/// weight, n_t <= n_p or P_t >= P_p with a non-empty part: nothing is left (kBadWeight).
[[nodiscard]] inline Status kalman_unmerge(const KalmanCell& total, const KalmanCell& part, KalmanCell* rest) noexcept {
  bool done = false;
  const Status start = detail::unmerge_start(total, part, rest, &done);
  if (start != Status::kOk || done) {
    return start;
  }
  const float gained = part.variance - total.variance;  // P_p - P_t > 0: total knows more
  if (!(total.weight > part.weight) || !(gained > 0.0F) || !(total.variance > 0.0F)) {
    return Status::kBadWeight;
  }
  const float share = part.variance / gained;  // P_p / (P_p - P_t)
  *rest = KalmanCell{part.height + (total.height - part.height) * share, total.variance * share,
                     total.weight - part.weight};
  return Status::kOk;
}

/// Merges `other` into `cell` (Chan's pairwise merge in one dimension): W = W_a + W_b,
/// h = h_a + (h_b - h_a) W_b / W, s = s_a + s_b + (h_b - h_a)^2 W_a W_b / W, then the limiter
/// (s *= W_l / W, W = W_l). A single OMG measurement is the cell (w, z, w sigma_m^2), so cells
/// fed disjoint measurements merge to the cell fed all of them (real arithmetic, no limiter).
/// An empty `other` leaves `cell` unchanged. Refused (unchanged): a non-finite or negative
/// weight or non-finite height or s in `other` (kBadWeight), a bad limit (kInvalidArgument).
[[nodiscard]] inline Status omg_merge(OmgCell& cell, const OmgCell& other, float weight_limit) noexcept {
  if (ccm_check_weight_limit(weight_limit) != Status::kOk) {
    return Status::kInvalidArgument;
  }
  if (!std::isfinite(other.weight) || other.weight < 0.0F) {
    return Status::kBadWeight;
  }
  if (!(other.weight > 0.0F)) {
    return Status::kOk;
  }
  if (!std::isfinite(other.height) || !std::isfinite(other.s)) {
    return Status::kBadWeight;
  }
  const float weight = cell.weight + other.weight;
  const float share = other.weight / weight;
  const float d = other.height - cell.height;
  cell.height += d * share;
  cell.s += other.s + cell.weight * share * d * d;
  cell.weight = weight;
  if (cell.weight > weight_limit) {
    cell.s *= weight_limit / cell.weight;
    cell.weight = weight_limit;
  }
  return Status::kOk;
}

/// The inverse of omg_merge without the limiter (as ccm_unmerge, one dimension); s clamped at 0.
/// Refused (*rest untouched): rest == nullptr (kInvalidArgument); a negative or non-finite
/// weight, or W_t <= W_p with a non-empty part (kBadWeight).
[[nodiscard]] inline Status omg_unmerge(const OmgCell& total, const OmgCell& part, OmgCell* rest) noexcept {
  bool done = false;
  const Status start = detail::unmerge_start(total, part, rest, &done);
  if (start != Status::kOk || done) {
    return start;
  }
  const float weight = total.weight - part.weight;
  if (!(weight > 0.0F)) {
    return Status::kBadWeight;
  }
  const float height = total.height + (total.height - part.height) * (part.weight / weight);
  const float d = height - part.height;
  const float s = total.s - part.s - part.weight * (weight / total.weight) * d * d;
  *rest = OmgCell{weight, height, s > 0.0F ? s : 0.0F};
  return Status::kOk;
}

/// Mixture variance of an OMG cell (m^2); 0 for a never-observed cell.
[[nodiscard]] inline float omg_variance(const OmgCell& cell) noexcept {
  return ccm_variance(cell.s, cell.weight);
}

}  // namespace ccmap
