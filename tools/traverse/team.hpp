// A team of simulated CADRE rovers (the map-exchange experiment): two or three rovers
// drive different paths over the traverse terrain (tools/traverse/scene.hpp), each maps with
// its own Stack<CadreConfig> from a CADRE stereo frame every frame_spacing_m, and every
// exchange_every frames each broadcasts a delta of what it gained (MapExchange::export_delta)
// that every other rover merges. A twin of every rover maps the same frames alone. At the end
// each rover's final map, with and without the team, is judged by the stack query against the
// hazard ground truth over its coarsest window (traverse.hpp gives the categories; the same
// window for both, since a rover's windows follow only its own path).
//
// Frames: the terrain's world frame is the team frame and every rover's map frame (origins 0).
// Deterministic by seed; CPU times are measured.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "traverse/traverse.hpp"

namespace ccmap::traverse {

struct TeamConfig {
  std::uint64_t seed = 1;
  int rovers = 3;                 ///< 2 or 3 (rover 1 drives the traverse path)
  int pixel_stride = 2;           ///< every k-th pixel of the 850 x 650 frame
  double frame_spacing_m = 0.3;
  int exchange_every = 5;         ///< frames between exchanges (and one after the last frame)
  float weight_floor = 0.0F;      ///< ExportOptions::weight_floor
  std::int32_t finest_layer = 0;  ///< ExportOptions::finest_layer: finer layers are not sent
  std::size_t packet_bytes = 0;   ///< largest delta a rover sends (0: no limit); the rest waits
  double query_step_m = 0.04;     ///< raster of the stack-query evaluation and the picture
  std::string out_dir;            ///< the picture goes here; empty = none
  std::FILE* log = nullptr;       ///< a line per exchange and the report; nullptr = quiet
  /// false: every delta is merged as its core alone (cells; its free-space section dropped and
  /// the header's entry count set to 0), the team as it was before deltas carried free space.
  bool free_space_exchange = true;
  /// Two rovers, stride 8, a frame every 0.6 m: what the CI test runs.
  static TeamConfig quick() {
    TeamConfig c;
    c.rovers = 2;
    c.pixel_stride = 8;
    c.frame_spacing_m = 0.6;
    c.exchange_every = 3;
    return c;
  }
};

struct RoverResult {
  int id = 0;
  double path_length_m = 0.0;
  int frames = 0;
  DetectionAreas alone;           ///< its own map
  DetectionAreas team;            ///< its map with the team's deltas merged
  std::size_t deltas_sent = 0, bytes_sent = 0, cells_sent = 0, cells_saturated = 0, cells_pending_at_end = 0;
  std::size_t cells_merged = 0, cells_outside = 0, deltas_refused = 0;
  /// Free-space entries (delta format 3): sent, and of the team mates' merged here.
  std::size_t drops_sent = 0, clears_sent = 0, drops_merged = 0, cells_cleared = 0, clears_deferred = 0;
  /// The first exchange after which this rover's team map answers drop-off (stack query, 8 cm
  /// raster over its 64 cm window) where its own map alone does not: the frame, and the
  /// distance from the rover's camera position then to the nearest such point (m); 0 frames:
  /// never.
  std::size_t first_learned_drop_frame = 0;
  double first_learned_drop_range_m = 0.0;
  std::size_t first_learned_drop_points = 0;
  double export_ms = 0.0, merge_ms = 0.0;  ///< host CPU, all exchanges
};

struct TeamResult {
  std::vector<RoverResult> rovers;
  std::size_t snapshot_bytes = 0;  ///< one CADRE snapshot, for comparison
  std::vector<std::string> pictures;
  std::string error;
  bool ok() const { return error.empty(); }
};

TeamResult run_team(const TeamConfig& config);

/// The end-of-run tables, as printed by ccmap_team.
std::string team_report(const TeamResult& result, const TeamConfig& config);

}  // namespace ccmap::traverse
