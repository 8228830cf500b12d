// Figs. 6 and 7 of the paper (Section V-B): Monte-Carlo obstacle detection against obstacle
// size, CCM versus the piece-wise constant OMG map with the roughness filter, on simulated
// CADRE stereo (tools/sim StereoCamera) over generated lunar terrain.
//
// One trial (one seed) and one obstacle size s (a share of the cell width w):
//  - Terrain: sim::lunar_terrain_params (3 % / 2 % slope, rolling ground, 2 cm fractal
//    roughness) without its random rocks and craters, so that the placed obstacle is the only
//    discrete hazard; rasterised at raster_resolution_m for the ray caster.
//  - Obstacle: an axis-aligned box (cube) of edge s and height s standing on the ground
//    (size = height = width, as in the paper's calibration "obstacles sized at 75 % of a cell",
//    a step height). On the raster its faces are ramps one raster cell wide whose half-height
//    lines are exactly the box edges (edges on raster-cell midpoints, s rounded to whole raster
//    steps: exact for every default size on the 1 cm raster), so the footprint below is exactly
//    what the camera sees at half height. The smallest default box (1 cm, 0.25 x 4 cm) is one
//    raster step: a pyramid with a 1 cm footprint at half height.
//    Lateral offset uniform in +-lateral_offset_max_m, along-track position jittered, so its
//    alignment with the map cells is random.
//  - Camera: sim::StereoCamera with the CADRE parameters (850 x 650 px, f 600 px, 5 cm baseline,
//    17.5 cm high, 25 deg pitch, 0.1 px disparity noise, 1/16 px quantisation), rays through
//    every pixel_stride-th pixel (ray casting is ~90 % of the run time; stride 2 = a quarter of
//    the frame), cut at 1.1 x the largest IV-G range (farther points are refused by every map).
//  - Rover: drives straight along +x towards the obstacle, a frame every frame_spacing_m, from
//    start_margin_m beyond the largest IV-G range of the resolutions to end_distance_m in front
//    of the obstacle's near face. The same frames (same seed, same size in metres) feed every
//    map of every resolution whose size list contains s.
//  - Maps (decision): single-layer stacks at the resolution, Stack<SingleCcmConfig> and
//    Stack<SingleOmgConfig>, default_stack_params(w) with the CADRE stereo model. Each takes
//    only points within its IV-G range (sensor/noise_model.hpp; the OMG layer's default limit
//    is the same bound): both maps see exactly the same points, and the CCM layer always
//    satisfies IV-G. Classes are the library's: CCM by normal variance (threshold calibrated
//    for a step of 75 % of w at 50 % coverage) and inclination, OMG by the stack's built-in
//    3 x 3 roughness filter (obstacle if a known neighbour differs by more than
//    tan(20 deg) x distance; the "lowest effective" threshold of Section V-B).
//
// Ground truth per map cell (global index (i, j) covering [i w, (i+1) w) x [j w, (j+1) w)):
//  - coverage c = share of the cell's area inside the obstacle footprint (exact, analytic);
//  - steep = sim::evaluate_cell_hazard slope of the ground plane > 20 deg (rare here);
//  - truth obstacle: truth_min_coverage <= c < 1 (the cell holds part of the obstacle's
//    border), or steep;
//  - don't care (excluded from every class): 0 < c < truth_min_coverage (a grazed corner,
//    below what any cell-level detector resolves; a planner inflates obstacles anyway), and
//    c = 1 (the flat top of a box larger than the cell: flat ground at the box's height, which a
//    2.5-D map cannot and need not call an obstacle: the planner meets the marked border first);
//  - free: c = 0 and not steep.
// Map hazard = class obstacle or steep (the roughness filter cannot tell them apart).
//
// Classes per frame (the paper's naming, Section V-B), over the cells *observed by that
// frame*: cell centre inside the camera's horizontal field of view, beyond the nearest ground
// the image sees, and within the layer's IV-G range of the camera:
//  - correct: truth obstacle marked hazard, or free marked traversable;
//  - false positive = missed obstacle: truth obstacle marked traversable;
//  - false negative = incorrectly marked obstacle, yet passable: free marked hazard; split into
//    "adjacent" (one of its 8 neighbours holds part of the obstacle, c > 0) and "far";
//  - unknown: the map does not know the cell (too few points, the coverage test of eq. 12,
//    the obstacle's shadow).
// Counts are cell-frames (integers; area = count x w^2, "time-summed area" in m^2 x frames):
// shards merge exactly. A resolution's frames are tallied from where the obstacle comes within
// its IV-G range plus start_margin_m, so every size of a resolution is scored over the same
// stretch of the drive. Per trial, the obstacle is "detected" if in at least one tallied frame
// a cell holding part of it (c > 0) is marked hazard (a planner that has seen it avoids it;
// far false obstacles are rare enough, see fn_far, for this not to reward noise).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "experiments/common.hpp"
#include "sim/stereo.hpp"
#include "sim/terrain.hpp"
#include "sim/types.hpp"

namespace ccmap::experiments {

struct DetectionConfig {
  std::vector<double> cell_widths_m{0.04, 0.08, 0.16};
  std::vector<double> size_ratios{0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0};
  std::uint64_t first_seed = 1;  ///< trials use seeds [first_seed, first_seed + trials)
  std::uint64_t trials = 10;
  double frame_spacing_m = 0.1;
  int pixel_stride = 2;          ///< stereo rays every pixel_stride-th pixel (cost / stride^2)
  double raster_resolution_m = 0.01;
  double truth_min_coverage = 0.1;
  double end_distance_m = 0.35;  ///< camera to the obstacle's near face at the last frame
  double start_margin_m = 0.3;   ///< start this far beyond the largest IV-G range
  double lateral_offset_max_m = 0.2;
  double border_streak_probability = 0.0;  ///< sim streaks (Section V-E); 0 = off
  GateSetting gate;              ///< both maps' outlier gate (default: the library's)
  bool paper_cell = false;       ///< CCM map of the paper's 9-float cell (PaperCell<SingleCcmConfig>)
  bool progress = false;         ///< one line per trial on stderr
  static DetectionConfig quick() {
    DetectionConfig c;
    c.cell_widths_m = {0.08};
    c.size_ratios = {0.5, 1.0, 2.0};
    c.trials = 4;
    c.pixel_stride = 3;
    c.raster_resolution_m = 0.01;
    return c;
  }
};

/// The maps' classifications compared:
///  - kCcm: the library's CCM classes (Stack::query_layer, classify_ccm): a cell that fails the
///    coverage test of eq. (12) is unknown whatever its normal variance;
///  - kCcmObstacleFirst: the same CCM map, but a cell with at least min_weight whose normal
///    variance exceeds the threshold is an obstacle even when partly covered (the obstacle's
///    own shadow hides the ground behind it, so its border cells are rarely fully covered;
///    eq. (12) protects the sub-cell height and slope, which an obstacle flag does not use);
///    otherwise the library's class;
///  - kOmg: the OMG layer with the stack's 3 x 3 roughness filter.
enum class DetectionMethod { kCcm = 0, kCcmObstacleFirst = 1, kOmg = 2 };
inline constexpr DetectionMethod kDetectionMethods[] = {DetectionMethod::kCcm, DetectionMethod::kCcmObstacleFirst,
                                                        DetectionMethod::kOmg};
const char* detection_method_name(DetectionMethod method);  ///< "CCM", "CCM-OF", "OMG"

/// Integer tallies of one (method, resolution, size ratio); sums over trials.
struct DetectionCounts {
  std::uint64_t trials = 0;
  std::uint64_t detected = 0;       ///< trials whose obstacle was marked in some frame
  std::uint64_t correct = 0;        ///< cell-frames, all correct
  std::uint64_t hit = 0;            ///<   of which truth obstacle marked hazard
  std::uint64_t missed = 0;         ///< false positive: truth obstacle marked traversable
  std::uint64_t fn_adjacent = 0;    ///< false negative next to the obstacle
  std::uint64_t fn_far = 0;         ///< false negative elsewhere
  std::uint64_t unknown = 0;        ///< observed area the map does not know
  std::uint64_t unknown_obstacle = 0;  ///<   of which truth obstacle
  std::uint64_t excluded = 0;       ///< don't-care cells (grazed corner, box top)
  DetectionCounts& operator+=(const DetectionCounts& o);
  bool operator==(const DetectionCounts& o) const;
};

struct DetectionRow {
  DetectionMethod method = DetectionMethod::kCcm;
  double cell_width_m = 0.0;
  double size_ratio = 0.0;
  DetectionCounts counts;
  /// missed / (hit + missed): share of the known truth-obstacle area left traversable.
  double missed_share() const;
  /// unknown_obstacle / (hit + missed + unknown_obstacle): share of the observed truth-obstacle
  /// area the map does not know (shadow, partial coverage).
  double obstacle_unknown_share() const;
  /// (fn_adjacent + fn_far) / (hit + missed): false-obstacle area per true-obstacle area.
  double false_obstacle_ratio() const;
  double detection_rate() const;
  double area_m2(std::uint64_t cell_frames) const { return static_cast<double>(cell_frames) * cell_width_m * cell_width_m; }
};

struct DetectionResult {
  std::uint64_t first_seed = 0, end_seed = 0;  ///< seeds [first, end) (one shard)
  std::string maps;                            ///< the maps' gate (GateSetting::describe); shards of different maps do not merge
  bool paper_cell = false;                     ///< the CCM map's cell (CSV line "# ccm cell paper|full")
  std::vector<DetectionRow> rows;              ///< method-major, then width, then ratio
  const DetectionRow* find(DetectionMethod method, double cell_width_m, double size_ratio) const;
  DetectionRow* find(DetectionMethod method, double cell_width_m, double size_ratio);
};

/// Runs trials [config.first_seed, config.first_seed + config.trials).
DetectionResult run_detection(const DetectionConfig& config);

/// Shard file (CSV with a "# seeds A:B" line and a "# maps ..." line); false with a reason.
bool write_detection_csv(const std::string& path, const DetectionResult& result, std::string* error);
bool read_detection_csv(const std::string& path, DetectionResult* out, std::string* error);
/// Sums shards (rows matched by method, width, ratio). Refused: overlapping seed ranges, shards of
/// different CCM cells, shards of different maps (their "# maps" lines differ). A shard without
/// the "# ccm cell" line (written before the full cell) is read as the paper cell's.
bool merge_detection_results(const std::vector<DetectionResult>& shards, DetectionResult* out, std::string* error);

/// Table with areas (m^2 x frames), shares and the paper's expectation beside.
std::string detection_table(const DetectionResult& result);
/// fig6_ccm.svg (CCM-OF: missed share solid, unknown share of the obstacle area dashed),
/// fig7_omg.svg (OMG: missed share solid, false-obstacle ratio dashed), one colour per
/// resolution, and fig6_detection.svg (per-trial detection rate, CCM-OF solid, OMG dashed).
bool write_detection_plots(const DetectionResult& result, const std::string& out_dir, std::string* error);

/// Smallest size ratio from which, at it and every larger ratio run, the obstacle is detected in
/// at least min_detection_rate of the trials and the missed share stays <= max_missed_share
/// (NaN if not even at the largest): the "detects from" figure of the table.
double detection_limit_ratio(const DetectionResult& result, DetectionMethod method, double cell_width_m,
                             double max_missed_share, double min_detection_rate);

// ---------------------------------------------------------------------------------------------
// Scene helpers shared with the drift experiment (drift.hpp)
// ---------------------------------------------------------------------------------------------

/// CADRE stereo camera of the simulator, pitched 25 deg down, with rays cut at max_depth_m.
sim::StereoParams detection_stereo_params(int pixel_stride, double max_depth_m, double streak_probability);

/// IV-G range (m) of a CCM cell of width w for the CADRE stereo model: sqrt(w / (4 sqrt(3) k)).
double ivg_max_range_m(double cell_width_m);

/// Whether the cell centre (x, y) (ground z_ground) is seen by a camera at `camera` with
/// heading yaw: inside the horizontal field of view, beyond the nearest ground the image
/// shows, and within max_range_m (3-D) of the camera.
bool cell_in_view(const sim::StereoParams& camera_params, const sim::Point3& camera, double yaw, double x, double y,
                  double z_ground, double max_range_m);

/// Whether the whole cell [x0, x0 + w] x [y0, y0 + w] is seen: its four corners, on the ground
/// of `ground`, pass cell_in_view. False where the ground is unknown (NaN).
bool whole_cell_in_view(const sim::StereoParams& camera_params, const sim::Point3& camera, double yaw,
                        const sim::Terrain& ground, double x0, double y0, double w, double max_range_m);

}  // namespace ccmap::experiments
