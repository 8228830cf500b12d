// The free-space experiments of issue 21 (docs/evaluation.md, "Ghosts and drop-offs"): each runs
// the same simulated CADRE frames into two Stack<CadreConfig>, one without free space
// (free_space_rays = 0: BEFORE, the map as it was) and one with the library's default (AFTER).
//
//  - team:   three rovers drive together over lunar ground (tools/traverse/scene.hpp's terrain);
//            each maps with its own camera and sees the others, rover boxes stamped into the
//            terrain it ray-casts against. Rover 2 waits ahead of rover 1, follows, then turns off
//            and drives away; rover 3 crosses in front. Ghosts: stack-query points (2 cm raster)
//            that a rover occupied earlier, that no rover occupies now, whose ground is free, and
//            that the map calls obstacle or steep; per frame, and how many frames each lived on
//            after its rover left. Every cell a frame empties is judged: inside a rover's past
//            footprint (a ghost cleared) or not (real ground or rock lost).
//  - dropoff: a rover drives straight at a negative obstacle (a ditch 30 cm or 15 cm deep, a
//            crater 2 m across) at 0.1 m per frame; the range from the camera to the near rim at
//            which a drop-off is first marked in the rover's 0.6 m wide swath beyond the rim, and
//            where the planner's path query (1.5 m ahead, the 0.6 m x 0.4 m body) first finds a
//            hazard, against the stopping distance.
//  - shadows: a rover drives 8 m over lunar ground with rocks and no negative obstacle: every
//            drop-off the map shows is false; their share of the queried area near rocks (the
//            shadows) and on open ground.
// Host tool code: heap, double. Deterministic by seed; CPU times are not reported.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "experiments/common.hpp"
#include "sim/terrain.hpp"
#include "traverse/dropoff_truth.hpp"
#include "traverse/ghost_truth.hpp"

namespace ccmap::traverse {

/// A rover's body: a box over its pose (length along the heading, width across, height above the
/// ground); the camera sits at its centre, 17.5 cm above the ground.
inline constexpr double kRoverLengthM = 0.6;
inline constexpr double kRoverWidthM = 0.4;
inline constexpr double kRoverHeightM = 0.25;
/// The distance from the camera within which a hazard must be known before the rover reaches it:
/// a frame's drive (0.3 m in the traverse) plus the body's front ahead of the camera (0.3 m).
inline constexpr double kStoppingDistanceM = 0.6;

struct GhostConfig {
  std::uint64_t seed = 1;
  int pixel_stride = 2;               ///< every k-th pixel of the 850 x 650 frame
  int team_frames = 44;
  double raster_resolution_m = 0.01;  ///< terrain raster the cameras ray-cast against
  double query_step_m = 0.02;         ///< raster of the stack-query evaluation
  experiments::GateSetting gate;      ///< the maps' outlier gate (default: the library's)
  int free_space_rays = 0;            ///< AFTER's lines of sight per frame; 0 = the library's default
  bool dropoff_truth = false;         ///< the drop-off cases also against DropoffTruth (dropoff_truth.hpp)
  std::string out_dir;                ///< pictures; empty = none
  /// > 0: the reference of issue 31 item 2 on rover 1's AFTER map (ghost_truth.hpp), a cell seen
  /// in a frame when at least this many true lines of sight pass clearly below it; 0 = off.
  int ghost_truth_rays = 0;
  std::FILE* log = nullptr;
  static GhostConfig quick() {
    GhostConfig c;
    c.pixel_stride = 8;
    c.team_frames = 30;
    return c;
  }
};

/// One map's ghosts (per rover, BEFORE or AFTER).
struct GhostStats {
  double peak_area_m2 = 0.0;        ///< largest ghost area of a frame
  double end_area_m2 = 0.0;         ///< at the last frame
  double area_frames_m2 = 0.0;      ///< sum over frames (m^2 x frames)
  int points_ever = 0;              ///< raster points that were a ghost in some frame
  double mean_life_frames = 0.0;    ///< frames a ghost point lived on after its rover left (mean)
  int max_life_frames = 0;
  int still_at_end = 0;             ///< ghost points at the last frame
  std::uint64_t cleared_cells = 0;  ///< cells the frames emptied
  std::uint64_t cleared_ghost = 0;  ///< of which inside a rover's past footprint
  std::uint64_t lost_ground = 0;    ///< of which real ground (no rover ever there, ground free)
  std::uint64_t lost_rock = 0;      ///< of which real rock (no rover ever there, a rock in the cell)
  std::vector<double> area_per_frame;
};

struct TeamResult {
  GhostStats before[3], after[3];
  std::uint64_t rays = 0, refused = 0, drops_after = 0;
  /// Rover 1's final map (after): drop-off answers on the raster whose answering cell holds a
  /// crater bowl deeper than the cell's obstacle height (true) or not (false); of the latter, those
  /// on a crater's inner wall (DropPlace::kInnerWall) and those elsewhere (false drop-offs).
  int drop_points_true = 0, drop_points_false = 0;
  int drop_points_wall = 0, drop_points_elsewhere = 0;
  std::vector<std::string> pictures;
  GhostTruthResult truth;  ///< GhostConfig::ghost_truth_rays > 0 only
};

/// Where a drop-off answer lies on the true terrain, judged over the answering cell: the square
/// [i w, (i + 1) w) x [j w, (j + 1) w) of width w (m) holding (x, y), obstacle step
/// obstacle_fraction w.
///  - kBowl: a crater bowl or ditch deeper than the step in the cell (sim::ProceduralTerrain::
///    negative_depth at 5 x 5 points of the cell);
///  - kInnerWall: not that, but the cell's centre lies inside a crater's rim circle (closer to its
///    centre than half its diameter) and the true cell is a hazard of the traverse's truth
///    (sim::compute_hazard_grid, 1 cm samples: relief over the step or slope over 20 deg, scene.hpp's
///    kMaxSlopeDeg): the crater's upper inner wall, a hazard whichever class the map gives it;
///  - kElsewhere: anything else (open ground, a rock's shadow, a rim's outer flank, a gentle
///    slope): a false drop-off.
enum class DropPlace { kBowl, kInnerWall, kElsewhere };
DropPlace drop_place(const sim::ProceduralTerrain& terrain, double x, double y, double w, double obstacle_fraction);

struct DropCase {
  std::string name;
  double rim_x = 0.0;                 ///< near rim on the path (m)
  double depth_m = 0.0;
  // Per map (0 before, 1 after):
  double first_drop_range_m[2] = {-1.0, -1.0};    ///< camera-to-rim range at the first drop in the swath
  double first_hazard_range_m[2] = {-1.0, -1.0};  ///< camera-to-rim range when the path query first finds a hazard
  double hazard_at_m[2] = {0.0, 0.0};             ///< where that hazard's footprint front lay, from the rim (m, + beyond)
  std::string hazard_class[2] = {"none", "none"};
  /// Camera-to-rim range when the path query's first hazard first lies at the rim (its footprint's
  /// front within 0.1 m beyond it): where the planner stops before the rover rolls in.
  double rim_hazard_range_m[2] = {-1.0, -1.0};
  std::string rim_hazard_class[2] = {"none", "none"};
  double first_unknown_range_m[2] = {-1.0, -1.0}; ///< the same for the first footprint over 10 % unknown
  /// Team mates that never look at it: stacks parked kTeamMateRangeM metres before the near rim
  /// on the rover's line (their windows centred there), merging the AFTER rover's delta (map
  /// exchange, persistence/exchange.hpp) after every frame. The rover's camera-to-rim range when
  /// a team mate's stack query first answers drop-off in the swath (-1: never), and the
  /// drop-off entries the rover sent.
  double team_drop_range_m[3] = {-1.0, -1.0, -1.0};
  std::uint64_t drops_sent = 0;
  /// With GhostConfig::dropoff_truth: AFTER against the reference after every frame.
  std::vector<DropTruthRow> truth;
};

/// Where the team mates of a drop-off case are parked: their range to the near rim (m).
inline constexpr double kTeamMateRangeM[3] = {1.0, 2.0, 4.0};

struct ShadowResult {
  double area_near_rocks_m2 = 0.0, area_open_m2 = 0.0;
  double unknown_near_rocks_m2 = 0.0, unknown_open_m2 = 0.0;
  double drop_near_rocks_m2[2] = {0.0, 0.0}, drop_open_m2[2] = {0.0, 0.0};  ///< before, after
  int rocks = 0;
};

struct GhostResult {
  TeamResult team;
  std::vector<DropCase> drops;
  ShadowResult shadows;
  std::vector<std::string> pictures;
  std::string error;
  bool ok() const { return error.empty(); }
};

GhostResult run_ghosts(const GhostConfig& config);

/// The tables of docs/evaluation.md, "Ghosts and drop-offs".
std::string ghost_report(const GhostResult& result, const GhostConfig& config);

}  // namespace ccmap::traverse
