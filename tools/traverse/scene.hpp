// The scene of the simulated CADRE traverses (tools/traverse: one rover, ccmap_traverse; a team,
// ccmap_team): the terrain with its placed obstacles, the camera pose in the form the stack takes,
// and the judging of map classes against the terrain's hazard ground truth (traverse.hpp states
// the definitions). Host tool code: heap, double.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "sim/hazard.hpp"
#include "sim/path.hpp"
#include "sim/stereo.hpp"
#include "sim/terrain.hpp"
#include "traverse/traverse.hpp"

namespace ccmap::traverse {

using Map = Stack<CadreConfig>;
/// The traverse's map with the paper's 9-float CCM cell (TraverseConfig::paper_cell). The
/// templates below over the map type are instantiated for Map and PaperMap (scene.cpp).
using PaperMap = Stack<PaperCell<CadreConfig>>;

inline constexpr double kMaxSlopeDeg = 20.0;       ///< steeper ground is a hazard
inline constexpr double kObstacleFraction = 0.75;  ///< a layer's minimum obstacle: 0.75 x its cell width

/// Lunar-like ground (tools/sim lunar_terrain_params) over [0, 30] m^2, its generated rocks
/// cleared from a 0.45 m corridor around every path (rovers do not drive over rocks; their
/// camera height follows the ground), plus placed rocks and a box beside the traverse path,
/// some above the 5 m-range minimum size of 48 cm.
std::unique_ptr<sim::ProceduralTerrain> make_terrain(std::uint64_t seed,
                                                     const std::vector<std::vector<sim::PathPose>>& paths);

/// Rotation sensor (optical) -> map of the camera at heading yaw: columns = the optical axes in
/// the map frame; translation: the camera position.
Pose camera_pose(const sim::StereoCamera& camera, const sim::Point3& position, double yaw);

[[nodiscard]] inline bool is_hazard(CellClass c) { return c == CellClass::kObstacle || c == CellClass::kSteep; }

/// Adds `area` (m^2) to the category of a cell of truth `truth_hazard` that the map calls `map_class`
/// (a drop-off, unobserved, to the drop-off areas: not judged as a known cell).
void count(DetectionAreas& a, bool truth_hazard, CellClass map_class, double area);

/// The ground truth of one layer's window: a hazard grid of the layer's cells (minimum
/// obstacle 0.75 w, maximum slope 20 deg).
struct LayerTruth {
  sim::HazardGrid grid;
  CellIndex min{0, 0};
  int side = 0;
  double width = 0.0;
  /// The truth of the cell holding (x, y); nullptr outside the window.
  const sim::CellHazard* at(double x, double y) const;
};
template <typename M>
LayerTruth layer_truth(const M& map, const sim::Terrain& terrain, int layer);

/// The layer whose cell gave the class of a stack answer (query() takes the class of a
/// constant-layer answer from the first CCM layer when that one knows the point).
template <typename M>
int classifying_layer(const M& map, const QueryResult& q, float x, float y);

/// The stack query on a raster of `step` m over the coarsest layer's window (x0, y0: its lower
/// corner), each point judged against the truth of the layer that classified it.
struct QueryRaster {
  double x0 = 0.0, y0 = 0.0, step = 0.04;
  int n = 0;
  std::vector<CellClass> map_class;
  std::vector<signed char> truth;  ///< -1 invalid, 0 free, 1 obstacle, 2 steep
};
template <typename M>
QueryRaster query_raster(const M& map, const std::vector<LayerTruth>& truths, double step, DetectionAreas* areas);

}  // namespace ccmap::traverse
