// Mapping a whole cloud with the robot-centric stack: the host tool sweeps the stack over the
// cloud in tiles. The library's windows stay as they are (fixed in the type); this is the
// tool's job.
//
// Tiles. A tile is a square of T x T finest cells of the map-frame grid anchored at the local
// origin (tile (tx, ty) holds the finest cells [tx T, (tx + 1) T) x [ty T, (ty + 1) T), indices
// relative to the origin). T is a multiple of the coarsest cell (in finest cells), so every cell
// of every layer lies in exactly one tile, and it is the largest such size for which, with the
// stack moved to the tile's centre, every layer's window holds the whole tile (and the finest
// window a margin around it, below). Each tile is mapped alone, in its own float frame (origin
// at its corner, so float precision is that of a few metres wherever the tile lies):
//   1. the stack is emptied (MapRunner::reset) and moved to the tile's centre;
//   2. for each cloud in order (one frame each, as without tiling), the points whose finest
//      cell is in the tile are folded in file order, then those of the margin;
//   3. every layer's cells inside the tile are exported (pooled answers, Section IV-F: a coarse
//      cell's children are in the tile, hence in the finer windows); margin cells are not.
// So every point's cell of every layer is exported exactly once, with all the points that fall
// in it, and every layer covers the cloud's extent; no point is outside the map.
//
// The margin. A piece-wise constant finest layer classifies a cell with the roughness filter,
// which reads its 8 neighbours; the ring of finest cells around the tile (margin 1, with all
// their points) gives border cells the neighbours they have in one big window. CCM classes
// depend on the cell alone: a CCM finest layer needs no margin.
//
// What a tiled map means for multi-layer presets (cadre): when its tile is mapped, every point
// lies inside every layer's window, so only its range noise routes it (Section IV-G): with the
// lidar model every point goes to the finest layer its noise allows (the 4 cm Kalman layer for
// sigma <= 5.8 mm) and the coarser layers answer by pooling their children, as the cells next
// to the robot do in a live map. Without --poses there is no sensor path: the sensor (for the
// stereo model's range noise) is taken to be at the local origin, as without tiling.
//
// Assignment in double. The tool decides each point's finest cell in double on the map-frame
// grid (floor((x - origin) / w)), then hands the library a float tile-frame coordinate inside
// that cell: the rounded value, or, when rounding puts it in a neighbour, the nearest position
// that the library's own
// index function (grid::index_of_position, what updates and queries use) puts in that cell,
// a few um away at most. The tool's bookkeeping and the library's cells never disagree.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "cloud_reader.hpp"
#include "csv_writer.hpp"
#include "map_runner.hpp"
#include "origin.hpp"

namespace ccmap::tools {

struct TilePlan {
  std::int32_t tile_cells = 0;    ///< T: tile side in finest cells, a multiple of the coarsest cell
  std::int32_t margin_cells = 0;  ///< finest cells mapped around the tile (0 or 1), never exported
  float centre_m = 0.0F;          ///< tile-frame position the stack moves to (x = y = centre_m)
  std::vector<double> widths;     ///< cell width per layer (m, finest * 2^k): the map-frame grid
};

/// The largest tile (at most max_tile_cells per side; <= 0: no limit) whose cells every layer's
/// window holds with the stack at the tile's centre, found by trying the runner's real windows.
/// Resets the runner. False with a reason if no tile fits (a window narrower than a coarse cell).
[[nodiscard]] bool plan_tiles(MapRunner& runner, const std::vector<double>& widths, std::int32_t max_tile_cells,
                              TilePlan* plan, std::string* error);

/// A float coordinate near `local_m` (tile frame, m) in the tile-frame finest cell `cell`, as
/// grid::index_of_position computes it with `inv_width` (= 1 / finest width, in float): the
/// nearest float, or, if that lies in a neighbouring cell, the position in `cell` nearest to
/// local_m (bisection towards the cell's centre). False if local_m is not in `cell` or a
/// neighbour of it (a caller error) or beyond the library's index range.
[[nodiscard]] bool float_in_cell(double local_m, std::int64_t cell, float inv_width, float* out);

/// One row of a layer CSV from a library cell: global index (map-frame grid), centre, height in
/// the map frame (z_origin added back in double).
[[nodiscard]] LayerCellRow make_row(int layer, std::int64_t ix, std::int64_t iy, double width, double z_origin,
                                    const LocalCell& cell);

struct TiledMap {
  std::vector<std::vector<LayerCellRow>> layers;  ///< per layer, finest first; rows sorted by (iy, ix)
  std::vector<FrameStats> frames;                 ///< per cloud: library counters + the tool's
  std::vector<double> frame_ms;                   ///< per cloud: time in update_frame (ms)
  std::size_t tiles = 0;                          ///< tiles mapped (those holding points)
};

/// Where the query point of `ccmap query` lies: its tile, and its tile-frame coordinates.
struct TileQuery {
  bool wanted = false;          ///< map only the tile holding (x, y)
  double x = 0.0, y = 0.0;      ///< map frame (m)
  bool mapped = false;          ///< out: that tile holds points and is the runner's state now
  float local_x = 0.0F, local_y = 0.0F;  ///< out: (x, y) in the tile's float frame
};

/// Sweeps the stack over `clouds` (the points classify_point maps; others are counted in
/// `frames`) tile by tile, as described above. `progress` (may be nullptr) gets a line per tenth
/// of the tiles (per tile when there are fewer than ten). With query->wanted, only the query point's tile is
/// mapped, nothing is exported, and the runner is left holding it. False with a reason if the
/// library refuses a call (a defect: the plan guarantees the windows).
[[nodiscard]] bool map_tiled(MapRunner& runner, const TilePlan& plan, const std::vector<Cloud>& clouds,
                             const LocalOrigin& origin, const AreaBounds& bounds, std::ostream* progress,
                             TileQuery* query, TiledMap* result, std::string* error);

}  // namespace ccmap::tools
