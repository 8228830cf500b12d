// An independent reference for issue 31 item 2 ("a cell whose surface the frame's lines of sight
// pass clearly below is emptied within 3 frames anywhere the camera sees it"), on the ghost
// experiment (tools/traverse/ghosts.hpp, `ccmap_ghosts --ghost-truth`). Brute force from the
// simulator's true terrain and every pixel of the frame the map receives, not the library's walk
// or table:
//  - a line of sight is the segment from the camera to the true point its pixel sees (the noise-
//    free ray cast against the terrain with the team mates stamped in: sim::StereoCamera::
//    render_depth). A pixel that sees nothing gives none.
//  - a line passes a cell clearly below its surface when it crosses the cell's square (x, y)
//    with its highest point there (entry or exit: it is straight) below the cell's top less the
//    layer's clear margin, and its true point lies beyond the cell (it reaches ground past it).
//    The cell's top is the one the library's first test reads (docs/design.md section 12): a CCM
//    cell's mean + sqrt(3) sigma_zz, a constant cell's height; the margin obstacle_fraction x
//    the cell width (CADRE's clear margin in every layer).
//  - the camera sees a cell clearly below its surface in a frame when at least `min_rays` such
//    lines cross it (the evidence rule asks two contradicting rays a frame).
// A true line of sight lies above the true terrain up to its point, so only a cell whose top less
// the margin stands above the lowest true terrain in it can be passed below: those are the cells
// the reference judges (candidates), each frame, in the map as it stands before the frame's
// update (after the window's move). A candidate in a team mate's past footprint, with no rover on
// it now, is a ghost; one where no rover ever was is real (ground or rock: the reference's
// real-ground side). After the update the reference notes which tracked cells the map emptied. A
// tracked cell whose top later comes within the margin of the lowest true ground in it (its own
// new points pulled it down: a constant cell's height is their mean) can no longer be passed
// below: it is "sunk", not emptied, and its track ends.
// Host tool code: heap, double. Deterministic.
#pragma once

#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "sim/stereo.hpp"
#include "sim/terrain.hpp"

namespace ccmap::traverse {

/// How far above the true ground a ghost's top must stand to count as a raised surface within
/// the margin (GhostTruthResult::within_margin), m.
inline constexpr double kRaisedM = 0.05;

/// A line of sight: the camera centre and the true point its pixel sees (world frame, m).
struct SightLine {
  double ox = 0.0, oy = 0.0, oz = 0.0;
  double hx = 0.0, hy = 0.0, hz = 0.0;
};

/// A map cell as the reference judges it: its square [x0, x0 + w] x [y0, y0 + w] (m), the top of
/// its surface and the layer's clear margin (m).
struct TruthCell {
  double x0 = 0.0, y0 = 0.0, w = 0.0;
  double top = 0.0, margin = 0.0;
};

/// True if `line` crosses the cell's square with its highest point there below top - margin and
/// its true point beyond the cell (past its exit from the square).
bool passes_clearly_below(const TruthCell& cell, const SightLine& line);

/// How many of `lines` pass the cell clearly below its surface.
int lines_clearly_below(const TruthCell& cell, const std::vector<SightLine>& lines);

/// The lines of sight of every pixel of `depth` (the camera's noise-free depth image from the
/// camera centre `camera` with heading `yaw`).
std::vector<SightLine> sight_lines(const sim::StereoCamera& camera, const sim::DepthImage& depth,
                                   const sim::Point3& camera_centre, double yaw);

/// One map cell the reference judged (a ghost or a real candidate), over the run.
struct TruthTrack {
  int layer = 0;
  double cx = 0.0, cy = 0.0, w = 0.0;  ///< centre and width (m)
  bool ghost = false;                  ///< in a team mate's past footprint (else real ground)
  bool rock = false;                   ///< a rock in the cell (real side)
  int first_frame = -1;                ///< first frame it was a candidate
  int first_seen = -1;                 ///< first frame the camera saw it clearly below (-1: never)
  double seen_range_m = -1.0;          ///< camera to cell centre at first_seen (horizontal, m)
  int seen_frames = 0;                 ///< frames seen clearly below (up to its end)
  int emptied = -1;                    ///< frame the map emptied it (-1: never)
  int seen_until_emptied = 0;          ///< seen frames from first_seen to emptied, both included
  int ended = -1;                      ///< frame it left the window (or, real, a rover came over it)
  int sunk = -1;                       ///< frame its top came within the margin of the true ground (points)
  int max_rays = 0;                    ///< most lines clearly below it in one frame
};

struct GhostTruthResult {
  int min_rays = 2;
  int frames = 0;
  std::vector<TruthTrack> tracks;
  /// Ghost cells no line of sight can pass clearly below: in a team mate's past footprint, no rover
  /// on it, the top at least kRaisedM above the highest true ground in it, but less than the clear
  /// margin above the lowest (first_frame, and seen_range_m: the camera's range then).
  std::vector<TruthTrack> within_margin;
  std::uint64_t lines = 0;  ///< lines of sight over all frames
};

/// The map's non-empty cells as the reference reads them: layer, global index, width, top, weight.
struct MapCellView {
  int layer = 0;
  int ix = 0, iy = 0;
  double w = 0.0, top = 0.0;
};

/// Every non-empty cell of a Stack (fine layer then CCM layers, window order).
template <typename Map>
std::vector<MapCellView> map_cells(const Map& m) {
  std::vector<MapCellView> out;
  const double w0 = m.layer_cell_width(0);
  m.fine_layer().for_each([&](auto idx, const auto& c) {
    if (c.weight > 0.0F) out.push_back(MapCellView{0, idx.x, idx.y, w0, double{c.height}});
  });
  for (int k = 0; k < Map::kCcmLayerCount; ++k) {
    const double w = m.layer_cell_width(k + 1);
    m.ccm_layer(k).for_each([&](auto idx, const auto& c) {
      if (c.weight > 0.0F) {
        const double sd = std::sqrt(std::max(0.0, double{c.s_zz} / double{c.weight}));
        out.push_back(MapCellView{k + 1, idx.x, idx.y, w, double{c.mean_z} + std::sqrt(3.0) * sd});
      }
    });
  }
  return out;
}

/// The reference over a run of frames of one map (rover 1's in the ghost experiment).
class GhostTruth {
 public:
  /// `ground`: the true terrain without any rover (heights the lines of sight lie above);
  /// `rock_in`(cx, cy, w): a rock in that square; `mate_at`(x, y, f): a team mate's body covered
  /// (x, y) at frame f; `rover_at`(x, y, f): any rover's did (the map's own included).
  GhostTruth(const sim::HeightRaster& ground, double obstacle_fraction, int min_rays,
             std::function<bool(double, double, double)> rock_in, std::function<bool(double, double, int)> mate_at,
             std::function<bool(double, double, int)> rover_at);

  /// Before frame f's update: the map's cells `cells`, the frame's lines of sight, the camera's
  /// horizontal position.
  void before_update(int f, const std::vector<MapCellView>& cells, const std::vector<SightLine>& lines, double cam_x,
                     double cam_y);
  /// After frame f's update: the map's cells now.
  void after_update(int f, const std::vector<MapCellView>& cells);

  GhostTruthResult result() const { return result_; }

 private:
  using Key = std::tuple<int, int, int>;
  struct CellFacts {
    double ground_min = 0.0;
    double ground_max = 0.0;
    bool within_margin_noted = false;
    int first_mate = -1;  ///< first frame a team mate covered part of it (-1: none so far)
    int mate_checked = -1;
    int first_rover = -1;
    int rover_checked = -1;
    bool rock = false;
  };
  CellFacts& facts(const MapCellView& c);
  int first_cover(const MapCellView& c, int upto, const std::function<bool(double, double, int)>& at, int* checked,
                  int* first) const;
  bool covered_at(const MapCellView& c, int f, const std::function<bool(double, double, int)>& at) const;

  const sim::HeightRaster& ground_;
  double obstacle_fraction_;
  std::function<bool(double, double, double)> rock_in_;
  std::function<bool(double, double, int)> mate_at_, rover_at_;
  std::map<Key, CellFacts> facts_;
  std::map<Key, std::size_t> open_;  ///< tracked cells not yet ended -> index in tracks
  GhostTruthResult result_;
};

/// The reference's tables (docs/evaluation.md, "Ghosts and drop-offs", item 2).
std::string ghost_truth_report(const GhostTruthResult& r);

}  // namespace ccmap::traverse
