#include "traverse/scene.hpp"

#include <algorithm>
#include <cmath>

namespace ccmap::traverse {

std::unique_ptr<sim::ProceduralTerrain> make_terrain(std::uint64_t seed,
                                                     const std::vector<std::vector<sim::PathPose>>& paths) {
  const sim::Rect area{0.0, 0.0, 30.0, 30.0};
  const sim::TerrainParams params = sim::lunar_terrain_params(area, seed);
  const sim::ProceduralTerrain generated(params);
  sim::TerrainParams no_rocks = params;
  no_rocks.rocks.density_per_m2 = 0.0;  // independent streams: waves and craters stay the same
  auto terrain = std::make_unique<sim::ProceduralTerrain>(no_rocks);
  auto path_distance = [&](double x, double y) {
    double best = 1e300;
    for (const std::vector<sim::PathPose>& path : paths) {
      for (const sim::PathPose& p : path) best = std::min(best, std::hypot(p.pose.x - x, p.pose.y - y));
    }
    return best;
  };
  for (const sim::Rock& r : generated.rocks()) {
    if (path_distance(r.x, r.y) - 0.5 * r.diameter_m > 0.45) terrain->add_rock(r);
  }
  // Placed obstacles (x, y, diameter, height): beside the traverse's first straight, in its turn
  // and beside/after its last straight.
  const sim::Rock placed[] = {
      {9.5, 9.3, 1.0, 0.50},   {11.0, 6.3, 0.7, 0.35}, {16.0, 12.5, 1.1, 0.55}, {13.0, 16.6, 1.2, 0.60},
      {8.0, 8.95, 0.25, 0.12}, {10.2, 7.2, 0.16, 0.08}, {15.0, 11.4, 0.3, 0.15}, {13.4, 13.2, 0.22, 0.10},
      {12.2, 4.8, 1.0, 0.50},
  };
  for (const sim::Rock& r : placed) terrain->add_rock(r);
  terrain->add_box(sim::Box{7.8, 6.6, 8.2, 7.0, 0.20});
  return terrain;
}

Pose camera_pose(const sim::StereoCamera& camera, const sim::Point3& position, double yaw) {
  Pose pose{};
  const sim::Point3 zero{0.0, 0.0, 0.0};
  const sim::Point3 axes[3] = {camera.sensor_to_world(sim::Point3{1.0, 0.0, 0.0}, zero, yaw),
                               camera.sensor_to_world(sim::Point3{0.0, 1.0, 0.0}, zero, yaw),
                               camera.sensor_to_world(sim::Point3{0.0, 0.0, 1.0}, zero, yaw)};
  for (int c = 0; c < 3; ++c) {
    pose.rotation[0][c] = static_cast<float>(axes[c].x);
    pose.rotation[1][c] = static_cast<float>(axes[c].y);
    pose.rotation[2][c] = static_cast<float>(axes[c].z);
  }
  pose.translation = PointXYZ{static_cast<float>(position.x), static_cast<float>(position.y),
                              static_cast<float>(position.z)};
  return pose;
}

void count(DetectionAreas& a, bool truth_hazard, CellClass map_class, double area) {
  if (map_class == CellClass::kUnknown) {
    a.unknown += area;
    return;
  }
  if (map_class == CellClass::kDropOff) {
    (truth_hazard ? a.drop_truth_hazard : a.drop_truth_free) += area;
    return;
  }
  const bool map_hazard = is_hazard(map_class);
  (truth_hazard ? a.truth_hazard_known : a.truth_free_known) += area;
  if (map_hazard == truth_hazard) a.correct += area;
  else if (truth_hazard) a.missed += area;
  else a.false_obstacle += area;
}

const sim::CellHazard* LayerTruth::at(double x, double y) const {
  const int ix = static_cast<int>(std::floor((x - grid.origin_x) / width));
  const int iy = static_cast<int>(std::floor((y - grid.origin_y) / width));
  if (ix < 0 || iy < 0 || ix >= grid.nx || iy >= grid.ny) return nullptr;
  return &grid.at(ix, iy);
}

template <typename M>
LayerTruth layer_truth(const M& map, const sim::Terrain& terrain, int layer) {
  LayerTruth t;
  t.width = map.layer_cell_width(layer);
  t.side = M::layer_side(layer);
  const CellIndex c = map.layer_centre(layer);
  t.min = CellIndex{c.x - t.side / 2, c.y - t.side / 2};
  sim::HazardParams hp;
  hp.min_obstacle_height_m = kObstacleFraction * t.width;
  hp.max_slope_deg = kMaxSlopeDeg;
  hp.sample_spacing_m = 0.01;
  t.grid = sim::compute_hazard_grid(terrain, t.min.x * t.width, t.min.y * t.width, t.width, t.side, t.side, hp);
  return t;
}

template <typename M>
int classifying_layer(const M& map, const QueryResult& q, float x, float y) {
  if (q.status == Status::kOk && !M::layer_is_ccm(q.layer) && M::kCcmLayerCount > 0 &&
      map.query_layer(M::kFineLayerCount, x, y).status == Status::kOk) {
    return M::kFineLayerCount;
  }
  return q.layer;
}

template <typename M>
QueryRaster query_raster(const M& map, const std::vector<LayerTruth>& truths, double step, DetectionAreas* areas) {
  const LayerTruth& coarse = truths.back();
  QueryRaster qr;
  qr.step = step;
  qr.x0 = coarse.min.x * coarse.width;
  qr.y0 = coarse.min.y * coarse.width;
  qr.n = static_cast<int>(std::lround(coarse.side * coarse.width / qr.step));
  qr.map_class.assign(static_cast<std::size_t>(qr.n) * static_cast<std::size_t>(qr.n), CellClass::kUnknown);
  qr.truth.assign(qr.map_class.size(), -1);
  const double area = qr.step * qr.step;
  for (int j = 0; j < qr.n; ++j) {
    for (int i = 0; i < qr.n; ++i) {
      const double x = qr.x0 + (i + 0.5) * qr.step, y = qr.y0 + (j + 0.5) * qr.step;
      const float fx = static_cast<float>(x), fy = static_cast<float>(y);
      const QueryResult q = map.query(fx, fy);
      const int layer = classifying_layer(map, q, fx, fy);
      const std::size_t k = static_cast<std::size_t>(i) + static_cast<std::size_t>(qr.n) * static_cast<std::size_t>(j);
      const CellClass cls = q.status == Status::kOk ? q.cell_class : CellClass::kUnknown;
      qr.map_class[k] = cls;
      if (layer < 0) continue;
      const sim::CellHazard* h = truths[static_cast<std::size_t>(layer)].at(x, y);
      if (h == nullptr || !h->valid) continue;
      qr.truth[k] = static_cast<signed char>(h->obstacle ? 1 : (h->steep ? 2 : 0));
      if (areas != nullptr) count(*areas, h->hazard(), cls, area);
    }
  }
  return qr;
}

template LayerTruth layer_truth<Map>(const Map&, const sim::Terrain&, int);
template LayerTruth layer_truth<PaperMap>(const PaperMap&, const sim::Terrain&, int);
template int classifying_layer<Map>(const Map&, const QueryResult&, float, float);
template int classifying_layer<PaperMap>(const PaperMap&, const QueryResult&, float, float);
template QueryRaster query_raster<Map>(const Map&, const std::vector<LayerTruth>&, double, DetectionAreas*);
template QueryRaster query_raster<PaperMap>(const PaperMap&, const std::vector<LayerTruth>&, double, DetectionAreas*);

}  // namespace ccmap::traverse
