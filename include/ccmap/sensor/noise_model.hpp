// Sensor noise models (stereo, lidar) and the routing of a point to the layer of a
// multi-size, multi-resolution stack that can take it (paper Sections IV-G and VI).
//
// Units and conventions
//  - range_m is the distance from the sensor's optical centre to the point (m); range_sq_m2 its
//    square. sigma_m (m) is the standard deviation of the range error along the ray.
//  - Stereo: the textbook depth error sigma_Z = Z^2 * sigma_d / (f * b) holds for the depth Z
//    along the optical axis. It is applied here to the Euclidean range r >= Z, which
//    over-estimates the error off-axis: conservative (a point is never routed to a finer layer
//    than its true noise allows).
//  - IV-G (the paper's size rule): a CCM cell of width w converges to the terrain only if the
//    standard deviation of a uniform distribution over the cell, sigma_r = w / sqrt(12), is at
//    least twice the measurement standard deviation sigma_m:  w / sqrt(12) >= 2 * sigma_m,
//    i.e. sigma_m <= w / (4 * sqrt(3)) ~= 0.1443 * w.
//
// Everything is float-only, allocation-free and exception-free. Bad parameters are reported by
// NoiseModel::validate() and make every query answer its conservative value (documented per
// function); bad ranges give sigma +inf, which no layer accepts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include "ccmap/core/status.hpp"

namespace ccmap::sensor {

/// Stereo: range error sigma(r) = r^2 * disparity_sigma_px / (focal_px * baseline_m)
/// (grows with range squared).
struct StereoParams {
  float focal_px;            ///< f: focal length in pixels, > 0
  float baseline_m;          ///< b: stereo baseline (m), > 0
  float disparity_sigma_px;  ///< sigma_d: disparity noise (px), >= 0
};

/// Lidar: sigma(r) = sigma0_m + sigma_per_m * r (constant when sigma_per_m = 0).
struct LidarParams {
  float sigma0_m;     ///< range-independent error (m), >= 0
  float sigma_per_m;  ///< error growth per metre of range (m/m), >= 0
};

/// How a point is weighted in the cell update (the w_t of eq. (1)).
enum class WeightMode : std::uint8_t {
  kConstant,         ///< every point weighs 1: the paper's configuration ("a constant value
                     ///< proving sufficient", Section IV-C)
  kInverseVariance,  ///< sigma_ref^2 / sigma(r)^2, normalised to 1 at the reference range
};

enum class SensorKind : std::uint8_t { kStereo, kLidar };

/// Inverse-variance weights are clamped to [kMinInverseVarianceWeight, kMaxInverseVarianceWeight]
/// so that one very close point cannot freeze a cell and far points still count (both bounds
/// are valid CCM measurement weights, see ccm_check_weight).
inline constexpr float kMinInverseVarianceWeight = 1.0e-3F;
inline constexpr float kMaxInverseVarianceWeight = 1.0e3F;

/// 1 / (2 * sqrt(12)) = 1 / (4 * sqrt(3)): the largest sigma_m per metre of cell width that
/// IV-G allows (sigma_m <= kIvgSigmaPerCellWidth * w).
inline constexpr float kIvgSigmaPerCellWidth = 0.14433756729740644F;
/// 2 * sqrt(12) = 4 * sqrt(3): the smallest cell width per metre of sigma_m (w >= 6.93 sigma_m).
inline constexpr float kIvgCellWidthPerSigma = 6.9282032302755092F;

/// A sensor's range-noise model. A value type (no virtuals, a few floats, trivially copyable).
/// A default-constructed model is not initialised: validate() answers kNotInitialised.
class NoiseModel {
 public:
  constexpr NoiseModel() noexcept = default;

  /// Stereo model. Never fails here: bad parameters are reported by validate().
  [[nodiscard]] static NoiseModel stereo(const StereoParams& params) noexcept;
  /// Lidar model. Never fails here: bad parameters are reported by validate().
  [[nodiscard]] static NoiseModel lidar(const LidarParams& params) noexcept;

  /// kOk, or why the model is unusable:
  ///  - kNotInitialised: default-constructed;
  ///  - kNonFiniteInput: a NaN/Inf parameter or reference range;
  ///  - kInvalidArgument: focal/baseline <= 0, a negative noise term, sigma_d / (f * b) not
  ///    finite, an unknown weight mode, a reference range <= 0, or kInverseVariance with a
  ///    zero sigma at the reference range (nothing to normalise by).
  /// Parameter errors are reported before weight-mode errors.
  [[nodiscard]] Status validate() const noexcept;

  /// sigma_m(r) (m). range_m negative or NaN -> +inf (no layer accepts the point); +inf ->
  /// +inf. An invalid model answers +inf for every range.
  [[nodiscard]] float sigma_at_range(float range_m) const noexcept;

  /// Same as sigma_at_range, from r^2 (m^2): stereo needs no sqrt (sigma = k * r^2), lidar
  /// takes one. range_sq negative or NaN -> +inf.
  [[nodiscard]] float sigma_at_range_sq(float range_sq_m2) const noexcept;

  /// Largest range (m) at which sigma_m(r) <= sigma_m: the inverse of sigma_at_range.
  /// +inf if sigma_m is never exceeded (lidar with sigma_per_m = 0 and sigma0 <= sigma_m, or a
  /// noise-free stereo model); 0 if no range satisfies it (sigma_m below the lidar floor
  /// sigma0, or sigma_m negative/NaN). An invalid model answers 0.
  [[nodiscard]] float max_range_for_sigma(float sigma_m) const noexcept;

  /// The square of max_range_for_sigma (m^2), computed without a sqrt (stereo: sigma_m / k).
  /// Same special values (+inf, 0). This is what the routing table stores.
  [[nodiscard]] float max_range_sq_for_sigma(float sigma_m) const noexcept;

  /// Measurement weight (the w_t of eq. (1)) for a point at range^2 (m^2):
  ///  - kConstant: 1 (the paper's default);
  ///  - kInverseVariance: sigma_ref^2 / sigma(r)^2 with sigma_ref = sigma at the reference
  ///    range, so a point at the reference range weighs 1; clamped to
  ///    [kMinInverseVarianceWeight, kMaxInverseVarianceWeight]. For stereo this is
  ///    (r_ref^2 / r^2)^2. A negative/NaN range (sigma +inf) gives the minimum weight; a zero
  ///    sigma (stereo at range 0) the maximum.
  /// An invalid model answers 1.
  [[nodiscard]] float weight_at_range_sq(float range_sq_m2) const noexcept;

  /// Selects the weighting. reference_range_m (m, > 0, finite) is used by kInverseVariance
  /// only; a bad value is reported by validate() and the weight then answers 1.
  void set_weight_mode(WeightMode mode, float reference_range_m = 1.0F) noexcept;

  [[nodiscard]] SensorKind kind() const noexcept { return kind_; }
  [[nodiscard]] WeightMode weight_mode() const noexcept { return weight_mode_; }
  [[nodiscard]] float reference_range_m() const noexcept { return reference_range_m_; }
  /// Stereo: k = sigma_d / (f * b) (1/m), so that sigma = k * r^2. 0 for lidar.
  [[nodiscard]] float stereo_sigma_per_range_sq() const noexcept { return stereo_k_; }
  /// Lidar: sigma0 (m) and growth per metre (m/m) as given to lidar(). 0 for stereo.
  [[nodiscard]] float lidar_sigma0_m() const noexcept { return lidar_sigma0_m_; }
  [[nodiscard]] float lidar_sigma_per_m() const noexcept { return lidar_sigma_per_m_; }

 private:
  // Every member starts at zero: a default model is all zero bytes, so a static map holding one
  // is zero-initialised (.bss) instead of being an image of initial values (.data, in flash).
  /// What the factory found in the parameters; kUnset: no factory made this model.
  enum class ParamState : std::uint8_t { kUnset = 0, kOk, kNonFinite, kInvalid };
  /// param_state_ as a Status (kUnset: kNotInitialised).
  [[nodiscard]] Status param_status() const noexcept;

  SensorKind kind_ = SensorKind::kStereo;
  WeightMode weight_mode_ = WeightMode::kConstant;
  ParamState param_state_ = ParamState::kUnset;
  Status weight_status_ = Status::kOk;
  float stereo_k_ = 0.0F;           ///< sigma_d / (f * b), 1/m (stereo)
  float lidar_sigma0_m_ = 0.0F;     ///< m (lidar)
  float lidar_sigma_per_m_ = 0.0F;  ///< m/m (lidar)
  float reference_range_m_ = 0.0F;  ///< m (set_weight_mode, which both factories call)
  float reference_sigma_m_ = 0.0F;  ///< sigma at the reference range (m)
};

/// The IV-G bound, inverted: the largest sigma_m (m) a CCM cell of width w (m) tolerates,
/// w / (2 * sqrt(12)). NaN or negative width -> 0 (nothing is tolerated); +inf -> +inf.
[[nodiscard]] float max_sigma_for_cell_width(float cell_width_m) noexcept;

/// Section IV-G: smallest CCM cell width (m) whose uniform-distribution sigma_r = w/sqrt(12)
/// is at least 2*sigma_m: w >= 2*sqrt(12)*sigma_m ~= 6.93 * sigma_m. NaN or negative sigma ->
/// +inf (no finite width is known to be safe).
[[nodiscard]] float min_cell_width_for_sigma(float sigma_m) noexcept;

// ---------------------------------------------------------------------------------------------
// Routing
// ---------------------------------------------------------------------------------------------
//
// A point goes to the finest layer that can take it; coarser layers receive it through pooling
// (Section IV-F). For a CCM layer "can take it" is IV-G. The finest layer of a CADRE-type stack
// is piece-wise constant (Kalman/OMG), which IV-G does not constrain: it has no slope or
// roughness whose covariance shape range noise could distort. It still must not be dominated
// by range noise, for a different reason: a constant cell is the mean of the points binned into
// it, and range noise moves points across cell borders. For a point uniformly placed in a cell
// of width w and a Gaussian displacement sigma_m along one axis, the expected share that lands
// in a neighbouring cell is 2 * (sigma_m / w) / sqrt(2*pi) ~= 0.8 * sigma_m / w.
//
// Rule (default): the constant finest layer takes a point while sigma_m <= w_0 / (4*sqrt(3)),
// i.e. the IV-G bound of its own width. Reasons:
//  1. Its cells then keep about 88% of their points (0.8 * 0.144 ~= 12% mis-binned); at the
//     looser w_0/sqrt(12) it would be 23%, and the height of a 4 cm cell would describe a
//     ~6 cm neighbourhood.
//  2. Constant cells are pooled into the first CCM layer by ccm_from_constant as samples of
//     the surface at their centres: a cell whose points come from its neighbours' ground
//     (range noise across borders) no longer samples its own centre.
//  3. With widths doubling per layer, any looser limit of 2x or more (in sigma) equals or
//     exceeds the first CCM layer's own IV-G limit (w_1/(4 sqrt 3) = w_0/(2 sqrt 3)), so that
//     layer would never receive a point directly, although the paper shows (Fig. 9) that an
//     8 cm CCM layer resolves obstacles a 4 cm constant layer misses.
// A caller who wants a different trade-off passes its own finest_max_sigma_m to the overload
// of build_routing_table; values at or above layer 1's IV-G limit are refused (rule 3).

/// Default limit (m) for a piece-wise constant finest layer of width w_0: its IV-G bound.
[[nodiscard]] inline float constant_layer_max_sigma(float finest_cell_width_m) noexcept {
  return max_sigma_for_cell_width(finest_cell_width_m);
}

/// Routing table for a stack whose layers have cell widths w_0 < w_1 < ... (finest first).
/// max_range_sq[k] (m^2) is the largest squared range at which layer k may take a point
/// (IV-G for CCM layers, the caller's limit for an exempt constant finest layer). 0 means the
/// layer never takes a point (a lidar floor above its limit); ranges beyond float are stored
/// as the largest finite float, so a non-finite range is never routed. The table is
/// non-decreasing in k.
template <int kLayers>
struct RoutingTable {
  static_assert(kLayers >= 1, "a stack has at least one layer");
  float max_range_sq[static_cast<std::size_t>(kLayers)];

  /// First layer k with range_sq <= max_range_sq[k]; -1 if the point is too noisy for every
  /// layer, or if range_sq is not > 0 (NaN, negative, or the sensor origin itself) or +inf.
  /// No sqrt, no division: at most kLayers + 1 compares. This is the routing rule; the stack's
  /// front routes a chunk of points at a time on the same squared bounds (map/update/front.hpp),
  /// and tests/map/front_test.cpp holds that against this function on double-precision ranges.
  [[nodiscard]] int select(float range_sq) const noexcept {
    if (!(range_sq > 0.0F)) {
      return -1;
    }
    for (int k = 0; k < kLayers; ++k) {
      if (range_sq <= max_range_sq[k]) {
        return k;
      }
    }
    return -1;
  }
};

namespace detail {
/// Size-erased body of build_routing_table (one copy for every kLayers). finest_exempt false:
/// IV-G for every layer (finest_max_sigma_m ignored); true: layer 0 uses finest_max_sigma_m.
/// Writes max_range_sq_out[0..layers) only on kOk.
[[nodiscard]] Status build_routing_table_impl(const NoiseModel& model, const float* cell_widths_m,
                                              int layers, bool finest_exempt,
                                              float finest_max_sigma_m,
                                              float* max_range_sq_out) noexcept;
}  // namespace detail

// The int template parameter (the stack's layer count type) must stay deducible from the
// width array's bound, so the bound is written as kLayers, which gcc's -Wsign-conversion flags
// (array bounds are size_t). kLayers >= 1 is asserted by RoutingTable, so the conversion is
// exact; the warning is silenced for these two declarations only.
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wsign-conversion"
#endif

/// Fills *out with every layer routed by IV-G (use it when every layer, including the finest,
/// is CCM, or to route a constant finest layer by the default rule above, which is the same
/// bound). Refused (*out unchanged): out == nullptr or a width <= 0 or not strictly increasing
/// (kInvalidArgument), a NaN/Inf width (kNonFiniteInput), an invalid model (its validate()).
template <int kLayers>
[[nodiscard]] Status build_routing_table(const NoiseModel& model,
                                         const float (&cell_widths_m)[kLayers],
                                         RoutingTable<kLayers>* out) noexcept {
  if (out == nullptr) {
    return Status::kInvalidArgument;
  }
  return detail::build_routing_table_impl(model, cell_widths_m, kLayers, false, 0.0F,
                                          out->max_range_sq);
}

/// As above, with layer 0 a piece-wise constant layer exempt from IV-G: it takes points while
/// sigma_m(r) <= finest_max_sigma_m (m), see constant_layer_max_sigma for the default and the
/// argument. Layers 1.. are routed by IV-G. Additionally refused: finest_max_sigma_m NaN
/// (kNonFiniteInput), <= 0, or (with 2+ layers) >= layer 1's IV-G limit w_1/(4 sqrt 3), which
/// would starve layer 1 (kInvalidArgument). +inf is allowed for a single-layer stack.
template <int kLayers>
[[nodiscard]] Status build_routing_table(const NoiseModel& model,
                                         const float (&cell_widths_m)[kLayers],
                                         float finest_max_sigma_m,
                                         RoutingTable<kLayers>* out) noexcept {
  if (out == nullptr) {
    return Status::kInvalidArgument;
  }
  return detail::build_routing_table_impl(model, cell_widths_m, kLayers, true, finest_max_sigma_m,
                                          out->max_range_sq);
}

#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

// ---------------------------------------------------------------------------------------------
// CADRE preset (paper Sections V-B and VI)
// ---------------------------------------------------------------------------------------------
//
// CADRE stereo: 850 x 650 px, baseline b = 5 cm, 17.5 cm above the ground. The paper gives
// neither focal length nor disparity noise; they are chosen here so that its Section VI claim
// holds ("obstacles over 48 cm [75% of a 64 cm cell] at a 5 m detection range"):
//   f = 600 px      -> horizontal field of view 2*atan(425/600) = 70.6 deg (vertical 56.9 deg)
//   sigma_d = 0.1 px (sub-pixel block matching)
//   k = sigma_d / (f*b) = 0.1 / (600 * 0.05) = 1/300 per metre, sigma_m(r) = r^2 / 300
//   IV-G: r_max(w)^2 = w / (4*sqrt(3) * k) = 43.30 * w   [m^2, w in m]
//     w = 0.04 m: r_max = 1.316 m  (sigma_m <= 5.77 mm)
//     w = 0.08 m: r_max = 1.861 m  (sigma_m <= 11.5 mm)
//     w = 0.16 m: r_max = 2.632 m  (sigma_m <= 23.1 mm)
//     w = 0.32 m: r_max = 3.722 m  (sigma_m <= 46.2 mm)
//     w = 0.64 m: r_max = 5.264 m  (sigma_m <= 92.4 mm)   -> the 64 cm layer covers 5 m.
//   At 5 m, sigma_m = 83 mm; the ray from 17.5 cm height meets the ground at 2.0 deg, so the
//   range noise is almost horizontal (vertical part ~3 mm).
// The IV-G limits grow by sqrt(2) per doubling of the width (sigma_m ~ r^2).
inline constexpr StereoParams kCadreStereoParams{600.0F, 0.05F, 0.1F};
inline constexpr int kCadreImageWidthPx = 850;
inline constexpr int kCadreImageHeightPx = 650;
inline constexpr float kCadreCameraHeightM = 0.175F;

/// NoiseModel::stereo(kCadreStereoParams), constant weights.
[[nodiscard]] NoiseModel cadre_stereo() noexcept;

}  // namespace ccmap::sensor
