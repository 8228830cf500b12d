// Non-template pieces of the stack: parameter validation, routing, thresholds, classes.
#pragma once

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/types.hpp"

namespace ccmap {

/// kOk if the parameters describe a usable stack of `layer_count` layers: finite, positive
/// width (0.19 mm = kMaxAbsCoordinateM / 2^29 <= width, coarsest <= 100 m), W_l > 0, tau in (0, 1], min_weight >= 0, obstacle_fraction in (0, 4],
/// max_inclination > 0, kalman_min_variance > 0, finite thresholds, the outlier gate 0 (off) or
/// in [1, 100], change_min_points in [1, 65535], change_share in (0, 0.5], free_space_rays a whole
/// number in [0, 65535], free_space_clear_frames a whole number in [1, 255], a finite
/// sensor_view_axis, a valid noise model. Otherwise kInvalidArgument or kNonFiniteInput.
[[nodiscard]] Status validate_stack_params(const StackParams& params, int layer_count) noexcept;

/// kOk for a finite position within kMaxAbsCoordinateM of the origin.
[[nodiscard]] Status check_position(float x, float y) noexcept;

/// Normal-variance threshold of a layer: the configured one if > 0, else calibrated for a
/// step of obstacle_fraction * width at 50 % coverage (Section IV-E).
[[nodiscard]] float layer_threshold(const StackParams& params, int layer, float width) noexcept;

/// Class of a (pooled) CCM cell: unknown below min_weight; obstacle if sigma_s^2 > threshold
/// (even when partly covered: the seen points already prove the step); unknown if not covered
/// (ccm_is_covered: eq. 12 per axis for the paper cell, the smaller eigenvalue for the full
/// cell); steep if the inclination exceeds the maximum; else traversable.
[[nodiscard]] CellClass classify_ccm(const CcmCell& cell, float width, const StackParams& params,
                                     float threshold) noexcept;
[[nodiscard]] CellClass classify_ccm(const CcmPaperCell& cell, float width, const StackParams& params,
                                     float threshold) noexcept;
/// The same with the cell's surface already computed (`surface` must be ccm_surface(cell)): a
/// query needs the surface for its answer anyway, and computes it once.
[[nodiscard]] CellClass classify_ccm(const CcmCell& cell, const CcmSurface& surface, float width,
                                     const StackParams& params, float threshold) noexcept;
[[nodiscard]] CellClass classify_ccm(const CcmPaperCell& cell, const CcmSurface& surface, float width,
                                     const StackParams& params, float threshold) noexcept;

}  // namespace ccmap
