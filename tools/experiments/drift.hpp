// Fig. 10 of the paper (Section V-D): drift resilience of CCM. With a drifting pose estimate,
// the same ground is placed at different map positions by successive frames; on sloped ground
// the heights in a cell then spread, its sample (normal) variance grows and CCM marks safe
// terrain as obstacle. The weight limit W_l (eqs. 6-7) bounds how long a cell remembers.
//
// Setting
//  - Terrain: sim::WaveTerrain, waves of wave_amplitude_m / wave_wavelength_m crossing the
//    drive (crests along y, the rover drives along +x): the worst case of the paper, every
//    along-track position error turns into a height error, yet all of it is traversable. The
//    default 5 cm / 1 m wave has a maximum slope 2 pi A / lambda = 17.4 deg, close to the
//    20 deg limit (the steepest still clearly traversable ground: the height error per metre
//    of drift is the slope), and a curvature that leaves < 0.5 mm of residual in an 8 cm cell.
//  - Rover: straight along +x for path_length_m, a frame every frame_spacing_m. Stereo clouds
//    are ray-cast from the true pose (sim::StereoCamera) and placed in the map with the pose of
//    sim::apply_drift (position error = drift x distance driven, along drift_direction_rad;
//    no heading error), as the estimator would.
//  - Maps: single-layer CCM stacks (Stack<SingleCcmConfig>, default_stack_params(w), the CADRE
//    stereo model: only points within the layer's IV-G range) for each cell width and each
//    W_l. The cloud of a frame is the same for every drift value, width and W_l. Constant
//    point weights (1), so W_l counts points: how far a cell remembers is W_l divided by the
//    points it receives per metre driven (frame rate / speed x pixel density; here a frame
//    every frame_spacing_m with every pixel_stride-th pixel): W_l = 100 forgets within a few
//    frames near the rover, 10000 never limits in this setting.
//  - Metric per frame, over the cells that the frame observes *as the map believes*: camera at
//    the drifted pose, the whole cell in the field of view and within the IV-G range. Of the cells
//    the map knows (eq. 12 coverage, min weight), the share marked obstacle or steep; summed
//    over frames (cell-frames). The truth is all traversable, so every such mark is false.
//  - Crossing: the smallest drift at which the share exceeds `tolerance` (5 %: one false
//    obstacle cell in twenty observed; linear interpolation between the drifts run).
//  - Uncertain moves (compare_uncertain_moves): every map also runs a second time with
//    Stack::move_to(x, y, sigma), sigma = odometry_sigma_fraction x the distance moved since the
//    last frame (the odometry's 1-sigma position error; a negative fraction: the run's own drift
//    fraction, an estimator that knows its drift rate). Same clouds, same poses.
//  - Registration (compare_registration): every map also runs a third time with plain moves and
//    each frame after the first registered against the map before it is folded in
//    (register_frame(stack, ...), default parameters); the correction is composed into the map's pose
//    estimate (as a rover corrects its pose) and carried to the later frames, whose drifted poses
//    it corrects first. The metric's camera is then the corrected one. final_pose_error_m: the
//    horizontal distance of the last corrected (or drifted) camera from the true one.
// Paper: the chosen W_l withstands 8 % drift at 4 cm and 16 % at 8 cm.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "experiments/common.hpp"

namespace ccmap::experiments {

struct DriftConfig {
  std::vector<double> cell_widths_m{0.04, 0.08};
  std::vector<double> drift_fractions{0.0, 0.02, 0.04, 0.06, 0.08, 0.10, 0.12, 0.16, 0.20, 0.24, 0.32};
  std::vector<double> weight_limits{100.0, 1000.0, 10000.0};
  double chosen_weight_limit = 1000.0;  ///< the library default (default_stack_params)
  double wave_amplitude_m = 0.05;
  double wave_wavelength_m = 1.0;
  double path_length_m = 4.0;
  double frame_spacing_m = 0.1;
  double drift_direction_rad = 0.0;     ///< along track (across the crests)
  int pixel_stride = 2;
  double raster_resolution_m = 0.01;
  double tolerance = 0.05;
  std::uint64_t seed = 1;
  bool paper_cell = false;  ///< CCM maps of the paper's 9-float cell (PaperCell<SingleCcmConfig>)
  bool progress = false;
  GateSetting gate;                     ///< the maps' outlier gate (default: the library's)
  bool compare_uncertain_moves = true;  ///< also run every map with uncertain moves
  double odometry_sigma_fraction = -1.0;  ///< sigma per metre moved; < 0: the run's drift fraction
  bool compare_registration = true;     ///< also run every map with registration (plain moves)
  static DriftConfig quick() {
    DriftConfig c;
    c.cell_widths_m = {0.04};
    c.drift_fractions = {0.0, 0.08, 0.24};
    c.weight_limits = {1000.0};
    c.path_length_m = 2.0;
    c.pixel_stride = 3;
    return c;
  }
};

struct DriftRow {
  double cell_width_m = 0.0;
  double weight_limit = 0.0;
  double drift_fraction = 0.0;
  bool uncertain_moves = false;     ///< mapped with move_to(x, y, sigma)
  bool registered = false;          ///< every frame after the first registered before it was folded in
  std::uint64_t registrations = 0;  ///< registrations that answered kOk (registered rows)
  std::uint64_t x_observable = 0;   ///< of those, with dx observable
  double final_pose_error_m = 0.0;  ///< the last frame's camera (corrected if registered) from the truth (m)
  std::uint64_t known = 0;          ///< observed, known cell-frames
  std::uint64_t false_obstacle = 0; ///< of which marked obstacle or steep
  std::uint64_t unknown = 0;        ///< observed cell-frames the map does not know
  double share() const { return known > 0 ? static_cast<double>(false_obstacle) / static_cast<double>(known) : 0.0; }
};

struct DriftResult {
  std::vector<DriftRow> rows;  ///< moves (plain, uncertain, registered), width, W_l, drift (ascending)
  double points_per_frame = 0.0;
  double max_slope_deg = 0.0;
  const DriftRow* find(double cell_width_m, double weight_limit, double drift_fraction,
                       bool uncertain_moves = false, bool registered = false) const;
};

DriftResult run_drift(const DriftConfig& config);

/// Drift (fraction of distance) at which the share first exceeds the tolerance, linearly
/// interpolated; NaN if it never does within the drifts run, 0 if it does at the first one.
double drift_crossing(const DriftResult& result, double cell_width_m, double weight_limit, double tolerance,
                      bool uncertain_moves = false, bool registered = false);

std::string drift_table(const DriftConfig& config, const DriftResult& result);

/// fig10.svg (false-obstacle share vs drift, one line per width and W_l) and fig10.csv.
bool write_drift_outputs(const DriftConfig& config, const DriftResult& result, const std::string& out_dir,
                         std::string* error);

}  // namespace ccmap::experiments
