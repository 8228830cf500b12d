// Non-template parts of registration/types.hpp: the default parameters and their validation.
#include <cmath>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/registration/detail/solver.hpp"
#include "ccmap/registration/types.hpp"

namespace ccmap {

RegistrationParams default_registration_params() noexcept {
  RegistrationParams p{};
  p.max_points = 1024U;
  p.max_iterations = 10U;
  p.min_matches = 30U;
  p.max_translation_m = 0.5F;
  p.max_yaw_rad = 0.2F;
  p.max_sigma_m = 0.03F;
  p.robust_sigmas = 3.0F;
  p.model_variance_m2 = 1.0e-6F;
  p.convergence_m = 3.0e-4F;
  return p;
}

Status validate_registration_params(const RegistrationParams& p) noexcept {
  const float values[] = {p.max_translation_m, p.max_yaw_rad, p.max_sigma_m, p.robust_sigmas, p.model_variance_m2,
                          p.convergence_m};
  for (const float v : values) {
    if (!std::isfinite(v)) {
      return Status::kNonFiniteInput;
    }
  }
  const bool counts = p.max_points >= 1U && p.max_points <= kMaxRegistrationPoints && p.max_iterations >= 1U &&
                      p.max_iterations <= kMaxRegistrationIterations &&
                      p.min_matches >= 3U;
  const bool bounds = p.max_translation_m > 0.0F && p.max_translation_m <= kMaxAbsCoordinateM && p.max_yaw_rad > 0.0F &&
                      p.max_yaw_rad <= 0.5F && p.max_sigma_m > 0.0F && p.robust_sigmas > 0.0F &&
                      p.model_variance_m2 >= 0.0F && p.convergence_m > 0.0F;
  return counts && bounds ? Status::kOk : Status::kInvalidArgument;
}

}  // namespace ccmap
