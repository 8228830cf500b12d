// Simulated CADRE traverse: a rover drives a path over a generated lunar terrain, captures a
// CADRE stereo frame every frame_spacing_m, moves a Stack<CadreConfig> with it and updates the
// map with each frame in the sensor frame (update_frame_sensor with the camera pose, what
// flight software does). At the end the final map is compared with the terrain's hazard ground
// truth (tools/sim/hazard.hpp), per layer and for the stack query.
//
// Frames and units: the map frame is the terrain's world frame (metres, z up; the terrain spans
// [0, 30] m on both axes, so no origin needs subtracting). Camera optical frame: x right, y
// down, z forward (tools/sim/stereo.hpp).
//
// Ground truth (per layer of cell width w): a cell is a hazard if its relief or a rock/box in
// it exceeds the layer's minimum obstacle height 0.75 w (the size the layer's normal-variance
// threshold is calibrated for, paper Section IV-E) or its ground slope exceeds 20 deg. A map
// cell is a hazard if its class is obstacle or steep. Areas (m^2) are counted as
//   correct        known, map hazard == truth hazard
//   missed         truth hazard, map traversable           (paper: "false positive")
//   false obstacle truth free, map obstacle/steep           (paper: "false negative")
//   unknown        map unknown (not observed, too few points, partly covered)
// The stack query is evaluated on a query_step_m raster over the coarsest layer's window; each
// point is judged against the truth of the layer whose cell classified it (for an answer of
// the 4 cm constant layer refined by the 8 cm CCM layer: the 8 cm truth).
// Objects (rocks, boxes) are counted as detected when any stack query point on their
// footprint (2 cm raster) is obstacle/steep, and as observed when any such point is known.
//
// Look-ahead (the planner's check, planner/path_query.hpp): after each frame the rover sweeps its
// body (body_length_m x body_width_m) along the next lookahead_m of its route, a pose every
// lookahead_step_m, and notes the first hazardous footprint (obstacle or steep) and the first
// with more than 10 % unknown area. Where the first hazard is seen is where the rover would have
// stopped. The final pictures include the cost raster (planner/costmap.hpp) around the rover.
//
// Odometry drift (drift_fraction, yaw_drift_rad_per_m; sim::apply_drift): the map is fed with the
// drifted pose estimate, the camera still sees the terrain from the true pose. With
// register_frames every frame after the first is registered against the map first
// (register_frame_sensor(stack, ...), default parameters) and the correction composed into the pose
// estimate, which carries it to the later frames. height_rms_m: the stack query's height against
// the terrain's surface over the known points of the final window (the map error; a drop-off's
// answer, an upper bound of a hidden floor, is not a known point).
//
// Deterministic by seed (terrain, noise); timings are measured, not simulated.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "ccmap/map/types.hpp"
#include "experiments/common.hpp"
#include "sim/types.hpp"

namespace ccmap::traverse {

struct TraverseConfig {
  std::uint64_t seed = 1;
  int pixel_stride = 1;             ///< every k-th pixel of the 850 x 650 frame (1 = full frame)
  double frame_spacing_m = 0.3;     ///< distance driven between frames
  int max_frames = 0;               ///< 0 = the whole path
  double raster_resolution_m = 0.01;///< terrain raster the camera ray-casts against
  double query_step_m = 0.04;       ///< raster of the stack query evaluation and picture
  double lookahead_m = 1.5;         ///< route checked ahead of the rover after each frame
  double lookahead_step_m = 0.05;   ///< between the body's poses along it
  double body_length_m = 0.6;       ///< the rover body swept along it
  double body_width_m = 0.4;
  std::string out_dir;              ///< pictures go here; empty = no pictures
  bool paper_cell = false;          ///< map with the paper's 9-float CCM cell (PaperCell<CadreConfig>)
  std::FILE* log = nullptr;         ///< progress lines (one per frame) and the report; nullptr = quiet
  double mismatch_share = 0.0;      ///< stereo mismatches: share of pixels at a random disparity (sim/stereo.hpp)
  experiments::GateSetting gate;    ///< the map's outlier gate (default: the library's)
  double drift_fraction = 0.0;      ///< odometry position drift, share of the distance driven
  double drift_direction_rad = 0.785398;  ///< its direction in the map frame (default: 45 deg)
  double yaw_drift_rad_per_m = 0.0; ///< odometry heading drift per metre driven
  bool register_frames = false;     ///< register every frame after the first before it is folded in
  /// A short run: 8 frames at pixel stride 4.
  static TraverseConfig quick() {
    TraverseConfig c;
    c.pixel_stride = 4;
    c.max_frames = 8;
    return c;
  }
};

struct FrameRecord {
  int index = 0;
  sim::Pose2 pose;
  std::size_t points = 0;          ///< points the camera delivered
  std::size_t mismatches = 0;      ///< of which stereo mismatches
  FrameCounters counters{};        ///< what the stack did with them
  double update_ms = 0.0;          ///< Stack::last_update_ns() of this frame
  double capture_ms = 0.0;         ///< simulator CPU time (ray casting), not part of the map
  bool updated = false;            ///< update_frame_sensor answered kOk
  sim::Pose2 estimate;             ///< the pose the map was given (drifted; corrected when registered)
  std::string registration = "-";  ///< the registration's status (- when none)
  bool observable[4] = {false, false, false, false};  ///< its observable axes
  double correction[4] = {0, 0, 0, 0};  ///< its correction (dx, dy, dz m, dyaw rad)
  // The look-ahead after this frame (query_path along the next lookahead_m of the route).
  bool route_end = false;          ///< nothing ahead: no look-ahead after the last frame
  bool ahead_ok = false;           ///< the path query answered kOk (or there was none to ask)
  bool ahead_hazard = false;       ///< a footprint ahead is obstacle or steep
  double ahead_hazard_m = 0.0;     ///< its distance ahead of the rover
  sim::Pose2 ahead_hazard_pose;    ///< the body's pose there
  const char* ahead_hazard_class = "unknown";
  bool ahead_unknown = false;      ///< a footprint ahead is more than 10 % unknown
  double ahead_unknown_m = 0.0;
  double ahead_ms = 0.0;           ///< CPU time of the path query
  std::uint32_t ahead_poses = 0;
};

/// Areas in m^2 (see the header comment for the categories).
struct DetectionAreas {
  double correct = 0.0, missed = 0.0, false_obstacle = 0.0, unknown = 0.0;
  /// Drop-off area (CellClass::kDropOff: unobserved, lines of sight passed far below the ground
  /// before it): neither known nor unknown, by its truth (hazard or free) in the cell itself.
  double drop_truth_hazard = 0.0, drop_truth_free = 0.0;
  double truth_hazard_known = 0.0;  ///< known area whose truth is a hazard
  double truth_free_known = 0.0;    ///< known area whose truth is free ("flat ground")
  double known() const { return correct + missed + false_obstacle; }
  /// Share of the known free area marked obstacle/steep.
  double false_share() const { return truth_free_known > 0.0 ? false_obstacle / truth_free_known : 0.0; }
  /// Share of the known hazard area marked obstacle/steep.
  double hit_share() const { return truth_hazard_known > 0.0 ? 1.0 - missed / truth_hazard_known : 0.0; }
};

struct LayerReport {
  int layer = 0;
  double cell_width_m = 0.0;
  double min_obstacle_m = 0.0;     ///< 0.75 w
  bool ccm = false;
  DetectionAreas areas;
  std::size_t exported = 0;        ///< cells with weight > 0
  std::size_t non_finite = 0;      ///< exported records with a NaN/Inf field
};

/// Objects of one height bin [min_height_m, max_height_m) inside the final window.
struct ObjectBin {
  double min_height_m = 0.0, max_height_m = 0.0;
  int in_window = 0, observed = 0, detected = 0;
  double rate() const { return observed > 0 ? static_cast<double>(detected) / observed : 0.0; }
};

struct TraverseResult {
  std::vector<FrameRecord> frames;
  std::vector<LayerReport> layers;
  DetectionAreas stack;                 ///< the stack query on the fine raster
  std::vector<ObjectBin> object_bins;   ///< by height; the last bin is >= 0.48 m
  /// Objects at least as tall as 0.75 x the width of the coarsest layer that answered on their
  /// footprint (the size that layer is calibrated for there).
  ObjectBin design_size;
  double min_size_5m_m = 0.48;          ///< 0.75 x 64 cm: the 5 m-range minimum (paper Sec. VI)
  double update_ms_median = 0.0, update_ms_max = 0.0, update_ms_mean = 0.0;
  double ahead_ms_median = 0.0, ahead_ms_max = 0.0;  ///< the look-ahead path queries
  double lookahead_m = 0.0, lookahead_step_m = 0.0, body_length_m = 0.0, body_width_m = 0.0;  ///< as configured
  int stop_frame = -1;                  ///< first frame whose look-ahead saw a hazard; -1: none
  int frames_with_hazard_ahead = 0, frames_with_unknown_ahead = 0;
  double capture_ms_total = 0.0;
  double path_length_m = 0.0;
  std::size_t rocks = 0, boxes = 0;
  std::vector<std::string> pictures;    ///< files written
  double height_rms_m = 0.0;            ///< stack query height against the terrain, known points of the final window (drop-offs not)
  double height_beyond_5cm = 0.0;       ///< share of those points more than 5 cm off
  double final_pose_error_m = 0.0;      ///< the last frame's estimate from the true pose (horizontal)
  double final_yaw_error_rad = 0.0;
  std::string error;                    ///< empty on success
  bool ok() const { return error.empty(); }
  /// The objects >= min_size_5m_m (the last bin).
  const ObjectBin& large_objects() const { return object_bins.back(); }
};

TraverseResult run_traverse(const TraverseConfig& config);

/// The end-of-run report (tables), as printed by ccmap_traverse.
std::string traverse_report(const TraverseResult& result);

}  // namespace ccmap::traverse
