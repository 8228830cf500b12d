// Value types of the map API: points, poses, query results, export records, counters.
//
// Frames: every position the core sees is in the *map frame* of its stack, in metres, relative
// to the stack's own origin (chosen by the integrator, e.g. the landing site or the start of a
// drive). Never pass absolute world coordinates (a UTM northing of 4.9e6 m has 0.5 m steps in
// float): subtract the origin in your own (double or fixed-point) precision first.
#pragma once

#include <cstdint>

#include "ccmap/core/status.hpp"
#include "ccmap/grid/ring_grid.hpp"

namespace ccmap {

/// One measured point, metres (map frame for update_frame, sensor frame for update_frame_sensor).
struct PointXYZ {
  float x;
  float y;
  float z;
};
static_assert(sizeof(PointXYZ) == 12U, "PointXYZ must stay 3 packed floats (caller buffers)");

/// Rigid transform sensor -> map: p_map = rotation * p_sensor + translation (metres), plain
/// floats (no matrix library in the interface). rotation[row][col], row-major: the map-frame x
/// of a point is rotation[0][0] * x_s + rotation[0][1] * y_s + rotation[0][2] * z_s + translation.x.
/// The caller builds the rotation (from its estimator's quaternion or matrix); the core does
/// not evaluate trigonometric functions, so results are bitwise reproducible across targets.
struct Pose {
  float rotation[3][3];
  PointXYZ translation;  ///< the sensor's position in the map frame (m)
};
static_assert(sizeof(Pose) == 48U, "Pose must stay 12 packed floats (C API: ccmap_pose)");

/// Hazard class of a cell (paper Section IV-E, IV-D).
enum class CellClass : std::uint8_t {
  kUnknown = 0,      ///< not observed, too few points, or partly covered (eq. 12)
  kTraversable = 1,  ///< covered, normal variance and inclination below their thresholds
  kObstacle = 2,     ///< surface-normal variance above the layer's threshold (sub-cell step)
  kSteep = 3,        ///< inclination above the maximum
  /// Not observed, but lines of sight passed over it far below the ground before it: the
  /// terrain drops there by more than the layer's obstacle height (a crater, a ditch, a ledge's
  /// far side). A hazard, like an obstacle (docs/design.md, "Free space from lines of sight").
  kDropOff = 4,
};

/// True for the classes a rover must not drive into (lethal in the cost raster): obstacle, steep,
/// drop-off.
[[nodiscard]] constexpr bool is_lethal(CellClass c) noexcept {
  return c == CellClass::kObstacle || c == CellClass::kSteep || c == CellClass::kDropOff;
}

/// "unknown", "traversable", "obstacle", "steep", "drop"; never nullptr.
[[nodiscard]] const char* to_string(CellClass cell_class) noexcept;

/// Answer of a point query. On status != kOk the numbers are 0 and the class is kUnknown;
/// `layer` is the finest layer that contains the point (-1 if no layer does). A drop-off answer
/// (kDropOff) is kOk with weight 0, height_m the upper bound the lines of sight proved (the
/// terrain lies at or below it) and every other number 0.
struct QueryResult {
  Status status;
  std::int32_t layer;          ///< layer that answered (0 = finest)
  float cell_width_m;          ///< cell width of that layer
  float height_m;              ///< height at the query point (sub-cell for CCM, eq. 10)
  float slope_x;               ///< a = dz/dx (ccm_surface); 0 for piece-wise constant cells
  float slope_y;               ///< b = dz/dy
  float inclination;           ///< sqrt(a^2 + b^2)
  float normal_variance;       ///< sigma_s^2 (eq. 11 / the plane's residual), m^2; constant cells: their own variance
  float elevation_variance;    ///< m^2, variance of the height at the point
  float weight;                ///< accumulated weight of the answering (pooled) cell
  CellClass cell_class;
  /// True with status kUnknown when the answering cell, or a cell pooled into it, failed its
  /// check or was reset by the scrub (a single-event upset: docs/integration.md section 12): the
  /// place is unknown until new points observe that cell again, and no other layer answers it.
  bool upset;
};

/// One cell of an exported layer (cells with weight > 0, and unobserved drop-off cells: weight 0,
/// height_m their upper bound, class kDropOff).
struct CellRecord {
  CellIndex index;             ///< global index in that layer (stable across moves)
  float centre_x;              ///< cell centre, map frame (m)
  float centre_y;
  float weight;
  float height_m;              ///< height at the cell centre
  float slope_x;
  float slope_y;
  float normal_variance;
  float elevation_variance;
  CellClass cell_class;
};

/// What happened to the points of one frame (also accumulated over the life of a stack).
/// Every received point is counted once, in the frame that received it: received = used +
/// rejected_non_finite + rejected_out_of_range + rejected_weight + outside_map + too_noisy +
/// gated_finer + gated_occluded + gated_held + gated_pool_full + skipped_budget. A held point is counted again when the change rule decides it
/// (gated_admitted or gated_dropped, in that frame or a later one: docs/design.md, "Outlier gate
/// and change"). The gate counters are 0 with the outlier gate off. The free-space counters
/// (free_rays .. drop_cells) count lines of sight and cells, not points, and are outside that
/// partition (docs/design.md, "Free space from lines of sight"); 0 with free space off.
struct FrameCounters {
  std::uint32_t received;
  std::uint32_t used;                   ///< folded into a cell
  std::uint32_t rejected_non_finite;    ///< NaN/Inf coordinate
  std::uint32_t rejected_out_of_range;  ///< |coordinate| > kMaxAbsCoordinateM
  std::uint32_t rejected_weight;        ///< weight from the model out of range
  std::uint32_t outside_map;            ///< no layer window holds the point
  std::uint32_t too_noisy;              ///< sigma_m too large for every layer (Section IV-G)
  std::uint32_t gated_finer;            ///< outside the gate of the next finer layer's cell there: dropped
  std::uint32_t gated_occluded;         ///< stereo: its line of sight passes under known ground: dropped
  std::uint32_t gated_held;             ///< outside its cell's outlier gate: held for the change rule
  std::uint32_t gated_pool_full;        ///< outside the gate while every held-point slot was taken: dropped
  std::uint32_t gated_admitted;         ///< held points the change rule admitted (re-seed or merge)
  std::uint32_t gated_dropped;          ///< held points it dropped as outliers (or whose cell left the map)
  std::uint32_t reseeded_cells;         ///< cells replaced by their held points
  std::uint32_t merged_cells;           ///< cells that took their held points in beside their own
  std::uint32_t skipped_budget;         ///< not processed: the frame budget was spent (StackParams)
  /// Single-event upsets (docs/integration.md, "Radiation: single-event upsets"); not points:
  std::uint32_t corrupted_cells;        ///< cells whose bits disagreed with their check: reset to never observed
  std::uint32_t corrupted_slots;        ///< held-point slots whose bits disagreed with their seal: dropped
  // ---- free space from lines of sight (issue 21): four counters of rays and cells, last ----
  std::uint32_t free_rays;              ///< lines of sight walked from the sensor to a sampled point
  /// Sampled points whose line of sight was refused: refused points (non-finite, out of range,
  /// too noisy, a bad weight), points behind the sensor, or all of them when no window holds the
  /// sensor. They change nothing.
  std::uint32_t free_rays_refused;
  std::uint32_t cleared_cells;          ///< cells emptied: rays passed clearly below their surface
  std::uint32_t drop_cells;             ///< unobserved cells that became drop-offs
};

}  // namespace ccmap
