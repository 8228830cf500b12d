// Outliers and real change (issue 12): what the outlier gate and the change rule of the stack
// (docs/design.md, "Outlier gate and change") do on controlled synthetic ground, gate off (the
// paper's update) against gate on.
//
// 1. Outliers on a slope. A plane of slope `slope` (dz/dx) over an area_m x area_m square,
//    points uniform in it with Gaussian height noise noise_m, seen by a lidar of range noise
//    noise_m from sensor_height_m above the centre (every point within every layer's range);
//    outlier_share of them thrown uniformly 0.2 .. 1.0 m above the ground. `frames` frames of
//    points_per_frame each. Single-layer stacks (CCM, Kalman, OMG) at each cell width. Metric:
//    RMS of the map height (query_layer: CCM with its sub-cell plane) minus the true plane on a
//    query_step_m raster over the known cells one cell away from the area's edge, and the
//    share of the raster known.
// 2. Real change, per cell width and gate setting, counted in frames after the change (dense:
//    the frames of case 1 without outliers; sparse: about one point per cell and frame):
//      box       a box box_height_m high over a box_size_m square appears on mapped ground:
//                frames until the cells wholly on the box are within 1 cm of its top
//      seeded    a cell first seeded by 5 outliers (0.5 m up, 1 cm apart), then ground:
//                frames until its height is within 1 cm of the ground
//      jump      the ground seen 10 cm higher after a pose jump: frames until the cells of the
//                area are within 1 cm of the new ground
//    "within" meaning a height at the cell's centre within 1 cm, known or not (a sparsely seen
//    cell may lack the points or the coverage to be known), for at least 90 % of the cells
//    concerned; "never" if not within change_frames frames.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "experiments/common.hpp"

namespace ccmap::experiments {

struct OutlierConfig {
  std::vector<double> cell_widths_m{0.08, 0.16, 0.32};
  double slope = 0.05;
  double area_m = 8.0;
  double noise_m = 0.005;
  double sensor_height_m = 2.0;
  double outlier_share = 0.01;
  int frames = 8;
  int points_per_frame = 100000;
  double query_step_m = 0.02;
  double box_size_m = 1.0;
  double box_height_m = 0.3;
  int change_frames = 16;
  std::uint64_t seed = 1;
  GateSetting gate;  ///< the "gate on" runs (the library's gate unless overridden)
  static OutlierConfig quick() {
    OutlierConfig c;
    c.cell_widths_m = {0.16};
    c.area_m = 4.0;
    c.points_per_frame = 25000;
    c.frames = 6;
    c.change_frames = 16;
    return c;
  }
};

struct SlopeRow {
  double cell_width_m = 0.0;
  std::string map;       ///< "CCM", "Kalman", "OMG"
  std::string variant;   ///< "clean", "outliers"
  bool gate = false;
  double rms_m = 0.0;
  double known_share = 0.0;
  std::uint64_t held = 0, admitted = 0, dropped = 0;  ///< the gate's counters over the run
};

struct ChangeRow {
  double cell_width_m = 0.0;
  std::string change;    ///< "box", "seeded", "jump"
  bool sparse = false;
  bool gate = false;
  int frames = -1;       ///< frames after the change until it is in the map; -1: never
};

struct OutlierResult {
  std::vector<SlopeRow> slope;
  std::vector<ChangeRow> change;
  const SlopeRow* find(double cell_width_m, const std::string& map, const std::string& variant, bool gate) const;
  const ChangeRow* find_change(double cell_width_m, const std::string& name, bool sparse, bool gate) const;
};

OutlierResult run_outliers(const OutlierConfig& config);
std::string outlier_tables(const OutlierConfig& config, const OutlierResult& result);

}  // namespace ccmap::experiments
