// Value types of registration (docs/design.md, "Registration"): what a caller asks
// (RegistrationParams) and what it gets back (RegistrationResult). No matrix library here: the
// 4 x 4 algebra lives in src/registration/ (Eigen, fixed-size float), behind detail functions.
//
// The correction. For map-frame points p of a frame (or the cell means of another map) and a
// rotation centre o (the sensor origin of the frame; the other map's window centre), the
// correction (dx, dy, dz, dyaw) is the rigid motion
//     p' = Rz(dyaw) (p - o) + o + (dx, dy, dz)
// (rotation about the vertical axis through o first, then the translation) that best aligns
// p' with the map. The caller applies it to its pose (a sensor pose (R, t) becomes
// (Rz(dyaw) R, Rz(dyaw) (t - o) + o + d) = (Rz(dyaw) R, t + d) since o = t) and then updates.
// Registration changes nothing in the map.
//
// Observability. Terrain fixes only what its shape constrains: flat ground fixes dz and nothing
// else, a single straight slope or a ditch the direction across it and dz, a sinusoid along x
// nothing along y. A direction of (dx, dy, dz, lever * dyaw) is observable when its standard
// deviation is at most RegistrationParams::max_sigma_m (lever: the weighted RMS horizontal
// distance of the matched points from o, which makes the yaw a length). The correction has no
// component along an unobservable direction (the minimum-norm solution: nothing is invented
// there). A parameter is flagged observable when its axis lies in the observable subspace (to
// within 1 % of its squared length); its sigma is then the standard deviation of its estimate,
// else +infinity. Axis-aligned degeneracies (flat ground; a ditch along x) give exactly 0 for
// the unobservable parameters; a diagonal ditch moves (dx, dy) across it only, and flags both
// unobservable (neither is known alone).
#pragma once

#include <cstdint>

#include "ccmap/core/status.hpp"

namespace ccmap {

/// Indices of the four parameters in RegistrationResult::observable and the sigmas.
enum RegistrationAxis : std::uint8_t { kAxisX = 0, kAxisY = 1, kAxisZ = 2, kAxisYaw = 3 };

/// Largest sample count a call may use (RegistrationParams::max_points): bounds the time of a
/// call, not its memory (samples are read from the caller's points; nothing is stored per point).
inline constexpr std::uint32_t kMaxRegistrationPoints = 65536U;
/// Largest iteration count of a call (all passes together).
inline constexpr std::uint32_t kMaxRegistrationIterations = 64U;

struct RegistrationParams {
  /// Points used, at most: every k-th point of the frame (k = ceil(n / max_points)), so a
  /// camera frame is sampled over the whole image. 1 .. kMaxRegistrationPoints.
  std::uint32_t max_points;
  /// Gauss-Newton iterations, all passes together: 1 .. kMaxRegistrationIterations.
  std::uint32_t max_iterations;
  /// Fewest points that must lie on known cells (else kInsufficientOverlap), >= 3.
  std::uint32_t min_matches;
  /// Largest horizontal correction |(dx, dy)| and |dz| searched (m, > 0): a solution beyond it
  /// is refused (kNotConverged: the pose is farther off than registration can tell).
  float max_translation_m;
  /// Largest |dyaw| searched (rad, in (0, 0.5]).
  float max_yaw_rad;
  /// A direction is observable when its standard deviation (m; yaw times the lever) is at most
  /// this (> 0).
  float max_sigma_m;
  /// Cauchy weight scale in standard deviations (> 0): a point k sigmas off weighs
  /// 1 / (1 + (k / robust_sigmas)^2) of an inlier: changed ground and outliers fade out.
  float robust_sigmas;
  /// Variance added to every residual (m^2, >= 0): what the plane model of a cell cannot say
  /// about the ground inside it beyond its own normal variance (curvature, float rounding).
  float model_variance_m2;
  /// Iterations stop when no parameter's step moves a point by more than this (m, > 0; yaw
  /// times the lever) or, once the residuals fit their model, by more than a quarter of that
  /// parameter's standard deviation.
  float convergence_m;
};

/// Defaults: 1,024 points, 10 iterations, 30 matches, a 0.5 m / 0.2 rad
/// search, observable below 3 cm, Cauchy at 3 sigma, (1 mm)^2 model variance, 0.3 mm steps.
[[nodiscard]] RegistrationParams default_registration_params() noexcept;

/// kOk or why the parameters are unusable (kNonFiniteInput, kInvalidArgument).
[[nodiscard]] Status validate_registration_params(const RegistrationParams& params) noexcept;

/// The answer. On status != kOk nothing is claimed: the correction is 0, every sigma +infinity,
/// every observable flag false (the counts still say what was seen).
struct RegistrationResult {
  Status status;
  float dx;    ///< m, map frame
  float dy;    ///< m
  float dz;    ///< m
  float dyaw;  ///< rad, counter-clockwise about the vertical through the rotation centre
  float sigma_dx;    ///< m, 1-sigma; +infinity if not observable
  float sigma_dy;    ///< m
  float sigma_dz;    ///< m
  float sigma_dyaw;  ///< rad
  bool observable[4];            ///< dx, dy, dz, dyaw (RegistrationAxis order)
  std::uint8_t rank;             ///< observable directions, 0..4
  std::uint32_t iterations;      ///< Gauss-Newton iterations used, all passes
  std::uint32_t points_sampled;  ///< samples with finite coordinates considered
  std::uint32_t points_rejected; ///< samples refused: non-finite, out of range, or too noisy for every layer
  std::uint32_t points_matched;  ///< samples on a known cell at the solution
  float lever_m;                 ///< the yaw's lever arm (m): weighted RMS horizontal distance from the centre
  float residual_sigma;          ///< RMS of the matched residuals in their own standard deviations (~1 if the model fits)
};

}  // namespace ccmap
