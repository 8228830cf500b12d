// Registration on real and synthetic terrain (issue 22; docs/evaluation.md, "Registration"): the
// error of register_frame(stack, ...) against an injected pose error, as a function of the overlap
// between the map and the frame and of the error's size, and where it fails.
//
// Procedure, per terrain and per (overlap, offset size), `trials` times:
//  1. Two disks of radius radius_m: the map's around a random centre A inside the terrain, the
//     frame's around B, B - A in a random direction at the distance that makes the disks' common
//     area the given share of one disk (overlap 1: the same disk).
//  2. The map: a single-layer CCM stack (Stack<SingleCcmConfig>, cell width cell_m, a lidar
//     noise of sigma_m, outlier gate off) fed the map disk's points of one sample of the
//     terrain, as one frame from A, sensor_height_m above the ground.
//  3. The frame: the frame disk's points of another, independent sample, moved by the inverse
//     of a correction C about the sensor above B: a horizontal shift of the offset size in a random
//     direction, a vertical shift of a third of it, a yaw of offset / yaw_lever_m (so that the
//     yaw moves a point yaw_lever_m away by as much as the shift).
//  4. register_frame from the sensor above B; its answer against C, axis by axis.
// Samples: the Lone Star scan's points (even indices for the map, odd for the frame; its tall
// returns and shadows kept), the Mars DTM's surface sampled bilinearly with sigma_z noise, and
// two synthetic failures: flat ground, and a sinusoid along x (period 0.8 m: an offset beyond
// half a period lands on the next crest).
// Reported per cell of the grid: registrations that answered kOk; of those, how often x and y
// were claimed; the median errors of what was claimed; and over-claims: claimed axes whose error
// exceeds 3 sigma + a floor (2 mm, 0.5 mrad): the measure of honesty.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ccmap::experiments {

enum class RegistrationTerrain { kLoneStar, kMarsDtm, kFlat, kSinusoid };

struct RegistrationExpConfig {
  std::vector<RegistrationTerrain> terrains{RegistrationTerrain::kLoneStar, RegistrationTerrain::kMarsDtm,
                                            RegistrationTerrain::kFlat, RegistrationTerrain::kSinusoid};
  std::vector<double> overlaps{1.0, 0.75, 0.5, 0.25};
  /// Offset sizes as a share of the terrain's scale (its `scale_m`: 1 m for the scan and the
  /// synthetic ground, 10 m for the DTM of 1 m pixels).
  std::vector<double> offsets{0.02, 0.05, 0.1, 0.2, 0.4};
  int trials = 12;
  std::uint64_t seed = 1;
  std::string data_dir;
  static RegistrationExpConfig quick() {
    RegistrationExpConfig c;
    c.overlaps = {1.0, 0.5};
    c.offsets = {0.02, 0.1, 0.4};
    c.trials = 4;
    return c;
  }
};

struct RegistrationCell {
  RegistrationTerrain terrain = RegistrationTerrain::kFlat;
  double overlap = 0.0;
  double offset_m = 0.0;
  int trials = 0;
  int ok = 0;            ///< answered kOk
  int claimed_x = 0;     ///< of those, x observable
  int claimed_y = 0;     ///< of those, y observable
  int claimed_yaw = 0;   ///< of those, yaw observable
  int claimed_z = 0;
  double median_xy_error_m = 0.0;   ///< horizontal error of the claimed components, where x or y was claimed (NaN: none)
  double median_z_error_m = 0.0;    ///< where z was claimed
  double median_yaw_error_rad = 0.0;
  double median_xy_sigma_m = 0.0;   ///< the claimed sigma of the same components, root sum of squares
  int axes_claimed = 0;  ///< claimed axes over all trials
  int over_claims = 0;   ///< claimed axes off by more than 3 sigma + the floor
  std::vector<std::string> statuses;  ///< the refusals' names, one per refused trial
};

struct RegistrationTerrainInfo {
  RegistrationTerrain terrain = RegistrationTerrain::kFlat;
  std::string name;
  double cell_m = 0.0, radius_m = 0.0, scale_m = 1.0;
  bool available = true;
  std::string why;  ///< why not (data absent)
};

struct RegistrationExpResult {
  std::vector<RegistrationTerrainInfo> terrains;
  std::vector<RegistrationCell> cells;
};

RegistrationExpResult run_registration_experiment(const RegistrationExpConfig& config);
std::string registration_table(const RegistrationExpResult& result);
/// registration.csv, and registration_<terrain>.svg: median horizontal error against the offset,
/// one line per overlap.
bool write_registration_outputs(const RegistrationExpResult& result, const std::string& out_dir, std::string* error);

}  // namespace ccmap::experiments
