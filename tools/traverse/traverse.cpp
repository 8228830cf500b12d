#include "traverse/traverse.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "experiments/canvas.hpp"
#include "experiments/common.hpp"
#include "layer_images.hpp"
#include "png.hpp"
#include "sim/hazard.hpp"
#include "sim/path.hpp"
#include "sim/stereo.hpp"
#include "sim/terrain.hpp"

namespace ccmap::traverse {

namespace {

using experiments::format;
using experiments::Rgb;
// Map: Stack<CadreConfig> (full CCM cells) or Stack<PaperCell<CadreConfig>> (TraverseConfig::paper_cell).

constexpr double kMaxSlopeDeg = 20.0;
constexpr double kObstacleFraction = 0.75;
constexpr double kFootprintStepM = 0.02;

/// The terrain of the traverse: lunar-like ground (tools/sim lunar_terrain_params) over
/// [0, 30] m^2, its rocks cleared from a 0.45 m corridor around the path (the rover does not
/// drive over rocks; its camera height follows the ground), plus placed rocks and a box
/// beside the path, some above the 5 m-range minimum size of 48 cm.
std::unique_ptr<sim::ProceduralTerrain> make_terrain(std::uint64_t seed, const std::vector<sim::PathPose>& path) {
  const sim::Rect area{0.0, 0.0, 30.0, 30.0};
  const sim::TerrainParams params = sim::lunar_terrain_params(area, seed);
  const sim::ProceduralTerrain generated(params);
  sim::TerrainParams no_rocks = params;
  no_rocks.rocks.density_per_m2 = 0.0;  // independent streams: waves and craters stay the same
  auto terrain = std::make_unique<sim::ProceduralTerrain>(no_rocks);
  auto path_distance = [&](double x, double y) {
    double best = 1e300;
    for (const sim::PathPose& p : path) best = std::min(best, std::hypot(p.pose.x - x, p.pose.y - y));
    return best;
  };
  for (const sim::Rock& r : generated.rocks()) {
    if (path_distance(r.x, r.y) - 0.5 * r.diameter_m > 0.45) terrain->add_rock(r);
  }
  // Placed obstacles (x, y, diameter, height): beside the first straight, in the turn and
  // beside/after the last straight.
  const sim::Rock placed[] = {
      {9.5, 9.3, 1.0, 0.50},   {11.0, 6.3, 0.7, 0.35}, {16.0, 12.5, 1.1, 0.55}, {13.0, 16.6, 1.2, 0.60},
      {8.0, 8.95, 0.25, 0.12}, {10.2, 7.2, 0.16, 0.08}, {15.0, 11.4, 0.3, 0.15}, {13.4, 13.2, 0.22, 0.10},
      {12.2, 4.8, 1.0, 0.50},
  };
  for (const sim::Rock& r : placed) terrain->add_rock(r);
  terrain->add_box(sim::Box{7.8, 6.6, 8.2, 7.0, 0.20});
  return terrain;
}

/// Rotation sensor (optical) -> map of the camera at heading yaw: columns = the optical axes
/// in the map frame.
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

bool is_hazard(CellClass c) { return c == CellClass::kObstacle || c == CellClass::kSteep; }

void count(DetectionAreas& a, bool truth_hazard, CellClass map_class, double area) {
  if (map_class == CellClass::kUnknown) {
    a.unknown += area;
    return;
  }
  const bool map_hazard = is_hazard(map_class);
  (truth_hazard ? a.truth_hazard_known : a.truth_free_known) += area;
  if (map_hazard == truth_hazard) a.correct += area;
  else if (truth_hazard) a.missed += area;
  else a.false_obstacle += area;
}

struct LayerTruth {
  sim::HazardGrid grid;
  CellIndex min{0, 0};
  int side = 0;
  double width = 0.0;
  const sim::CellHazard* at(double x, double y) const {
    const int ix = static_cast<int>(std::floor((x - grid.origin_x) / width));
    const int iy = static_cast<int>(std::floor((y - grid.origin_y) / width));
    if (ix < 0 || iy < 0 || ix >= grid.nx || iy >= grid.ny) return nullptr;
    return &grid.at(ix, iy);
  }
};

/// The layer whose cell gave the class of a stack answer (query() takes the class of a
/// constant-layer answer from the first CCM layer when that one knows the point).
template <typename Map>
int classifying_layer(const Map& map, const QueryResult& q, float x, float y) {
  if (q.status == Status::kOk && !Map::layer_is_ccm(q.layer) && Map::kCcmLayerCount > 0 &&
      map.query_layer(Map::kFineLayerCount, x, y).status == Status::kOk) {
    return Map::kFineLayerCount;
  }
  return q.layer;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bool record_finite(const CellRecord& r) {
  return std::isfinite(r.centre_x) && std::isfinite(r.centre_y) && std::isfinite(r.weight) && std::isfinite(r.height_m) &&
         std::isfinite(r.slope_x) && std::isfinite(r.slope_y) && std::isfinite(r.normal_variance) &&
         std::isfinite(r.elevation_variance);
}

// ---------------------------------------------------------------------------------------------
// Pictures
// ---------------------------------------------------------------------------------------------

Rgb class_rgb(CellClass c) {
  std::uint8_t v[3];
  tools::class_colour(to_string(c), v);
  return Rgb{v[0], v[1], v[2]};
}

const Rgb kPathColour{255, 255, 255};
const Rgb kPathEdge{20, 20, 160};
const Rgb kPanelBg{235, 235, 235};

/// World (m) -> pixel of a panel showing [x0, x0 + extent] x [y0, y0 + extent] in `pixels`.
struct PanelFrame {
  double x0 = 0.0, y0 = 0.0, extent = 1.0;
  int left = 0, top = 0, pixels = 1;
  double px(double x) const { return left + (x - x0) / extent * pixels; }
  double py(double y) const { return top + (1.0 - (y - y0) / extent) * pixels; }
  double ppm() const { return pixels / extent; }
};

void draw_path(tools::RgbImage& img, const PanelFrame& f, const std::vector<sim::PathPose>& path, std::size_t driven) {
  auto inside = [&](double x, double y) {
    return x >= f.x0 && y >= f.y0 && x <= f.x0 + f.extent && y <= f.y0 + f.extent;
  };
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 1; i < path.size(); ++i) {
      const sim::Pose2& a = path[i - 1].pose;
      const sim::Pose2& b = path[i].pose;
      if (!inside(a.x, a.y) || !inside(b.x, b.y)) continue;
      const bool done = i < driven;
      const Rgb c = pass == 0 ? kPathEdge : (done ? kPathColour : Rgb{160, 160, 255});
      experiments::draw_line(img, f.px(a.x), f.py(a.y), f.px(b.x), f.py(b.y), c, pass == 0 ? 5 : 2);
    }
  }
  if (driven > 0 && driven <= path.size()) {
    const sim::Pose2& r = path[driven - 1].pose;
    if (inside(r.x, r.y)) {
      experiments::fill_disc(img, f.px(r.x), f.py(r.y), 6.0, kPathEdge);
      experiments::fill_disc(img, f.px(r.x), f.py(r.y), 4.0, kPathColour);
      experiments::draw_line(img, f.px(r.x), f.py(r.y), f.px(r.x + 0.6 * std::cos(r.yaw)),
                             f.py(r.y + 0.6 * std::sin(r.yaw)), kPathEdge, 3);
    }
  }
  const sim::Pose2& s = path.front().pose;
  if (inside(s.x, s.y)) {
    experiments::draw_rect(img, static_cast<int>(f.px(s.x)) - 4, static_cast<int>(f.py(s.y)) - 4, 9, 9, kPathEdge, 2);
  }
}

void panel_decorations(tools::RgbImage& img, const PanelFrame& f, const std::string& title) {
  experiments::draw_text(img, f.left, f.top - 12, title, experiments::kBlack);
  experiments::draw_rect(img, f.left - 1, f.top - 1, f.pixels + 2, f.pixels + 2, experiments::kBlack);
  const double metres = f.extent > 12.0 ? 2.0 : (f.extent > 4.0 ? 1.0 : 0.5);
  // Scale bar and north arrow on a light box in the lower-left / upper-right corners.
  const int bar = static_cast<int>(std::lround(f.ppm() * metres));
  experiments::fill_rect(img, f.left + 6, f.top + f.pixels - 30, bar + 20, 25, Rgb{255, 255, 255});
  experiments::scale_bar(img, f.left + 16, f.top + f.pixels - 24, f.ppm(), metres, experiments::kBlack);
  experiments::fill_rect(img, f.left + f.pixels - 26, f.top + 4, 20, 40, Rgb{255, 255, 255});
  experiments::north_arrow(img, f.left + f.pixels - 16, f.top + 8, experiments::kBlack);
}

/// Height, normal variance and class of one layer, side by side, with the path and legends.
template <typename Map>
bool write_layer_picture(const std::string& path, const Map& map, int layer, const std::vector<sim::PathPose>& route,
                         std::size_t driven, std::string* error) {
  std::vector<CellRecord> records(Map::layer_capacity(layer));
  std::size_t written = 0;
  if (map.export_layer(layer, records.data(), records.size(), &written) != Status::kOk) {
    *error = "export_layer failed";
    return false;
  }
  const double w = map.layer_cell_width(layer);
  std::vector<tools::LayerCellRow> rows;
  std::vector<double> heights;
  for (std::size_t i = 0; i < written; ++i) {
    const CellRecord& r = records[i];
    tools::LayerCellRow row;
    row.layer = layer;
    row.ix = r.index.x;
    row.iy = r.index.y;
    row.cx = r.centre_x;
    row.cy = r.centre_y;
    row.res = w;
    row.weight = r.weight;
    row.height = r.height_m;
    row.slope_x = r.slope_x;
    row.slope_y = r.slope_y;
    row.normal_var = r.normal_variance;
    row.elev_var = r.elevation_variance;
    row.cell_class = to_string(r.cell_class);
    rows.push_back(row);
    if (std::isfinite(r.height_m)) heights.push_back(r.height_m);
  }
  const int side = Map::layer_side(layer);
  const CellIndex c = map.layer_centre(layer);
  const tools::LayerWindow window{c.x - side / 2, c.y - side / 2, side, side};
  tools::RgbImage images[4];
  if (!tools::render_layer_images(rows, window, images, error)) return false;
  // The same colour range as render_layer_images: 2nd..98th height percentile.
  double h_lo = 0.0, h_hi = 1.0;
  if (!heights.empty()) {
    std::sort(heights.begin(), heights.end());
    h_lo = heights[static_cast<std::size_t>(0.02 * static_cast<double>(heights.size() - 1))];
    h_hi = heights[static_cast<std::size_t>(0.98 * static_cast<double>(heights.size() - 1))];
  }
  const int pix = images[0].width;
  const int gap = 24, top = 44, legend = 78;
  tools::RgbImage img(3 * pix + 4 * gap, top + pix + legend, 255);
  const char* names[3] = {"HEIGHT (SHADED)", "NORMAL VARIANCE", "CLASS"};
  const int which[3] = {0, 2, 3};
  experiments::draw_text(img, gap, 8,
                         format("LAYER %d: %.0f CM %s, %dX%d CELLS, %.2f M WIDE; MIN OBSTACLE %.0f CM; PATH WHITE, ROVER DOT",
                                layer, 100.0 * w, Map::layer_is_ccm(layer) ? "CCM" : "KALMAN", side, side, side * w,
                                100.0 * kObstacleFraction * w),
                         experiments::kBlack);
  for (int k = 0; k < 3; ++k) {
    PanelFrame f;
    f.x0 = static_cast<double>(window.ix_min) * w;
    f.y0 = static_cast<double>(window.iy_min) * w;
    f.extent = side * w;
    f.left = gap + k * (pix + gap);
    f.top = top;
    f.pixels = pix;
    experiments::blit(img, images[which[k]], f.left, f.top);
    draw_path(img, f, route, driven);
    panel_decorations(img, f, names[k]);
  }
  const int ly = top + pix + 26;
  experiments::colour_bar(img, gap, ly, 200, 12, experiments::viridis, format("%.2f M", h_lo + 0.0), format("%.2f M", h_hi + 0.0),
                          "HEIGHT, SHADED FROM NW; BLACK = NO DATA");
  experiments::colour_bar(img, gap + pix + gap, ly, 200, 12, experiments::viridis, "0.1 MM", "10 CM",
                          "SQRT(NORMAL VARIANCE), LOG SCALE");
  int x = gap + 2 * (pix + gap);
  for (CellClass cc : {CellClass::kTraversable, CellClass::kObstacle, CellClass::kSteep, CellClass::kUnknown}) {
    x = experiments::legend_entry(img, x, ly, class_rgb(cc), to_string(cc));
  }
  experiments::draw_text(img, gap + 2 * (pix + gap), ly + 18, "BLACK: NEVER OBSERVED", experiments::kBlack);
  return tools::write_png(path, img, error);
}

struct QueryRaster {
  double x0 = 0.0, y0 = 0.0, step = 0.04;
  int n = 0;
  std::vector<CellClass> map_class;
  std::vector<signed char> truth;  ///< -1 invalid, 0 free, 1 obstacle, 2 steep
};

Rgb truth_rgb(signed char t) {
  if (t == 1) return class_rgb(CellClass::kObstacle);
  if (t == 2) return class_rgb(CellClass::kSteep);
  if (t == 0) return class_rgb(CellClass::kTraversable);
  return experiments::kBlack;
}

template <typename Map>
bool write_hazard_picture(const std::string& path, const QueryRaster& q, const Map& map,
                          const std::vector<sim::PathPose>& route, std::size_t driven,
                          const std::vector<std::pair<sim::Rock, bool>>& large, std::string* error) {
  const int pix = q.n;
  const int gap = 24, top = 44, legend = 70;
  tools::RgbImage img(2 * pix + 3 * gap, top + pix + legend, 255);
  PanelFrame frames[2];
  for (int k = 0; k < 2; ++k) {
    frames[k].x0 = q.x0;
    frames[k].y0 = q.y0;
    frames[k].extent = q.n * q.step;
    frames[k].left = gap + k * (pix + gap);
    frames[k].top = top;
    frames[k].pixels = pix;
  }
  for (int j = 0; j < q.n; ++j) {
    for (int i = 0; i < q.n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i) + static_cast<std::size_t>(q.n) * static_cast<std::size_t>(j);
      const int py = top + q.n - 1 - j;
      Rgb t = truth_rgb(q.truth[k]);
      if (q.map_class[k] == CellClass::kUnknown && q.truth[k] >= 0) {
        t = Rgb{static_cast<std::uint8_t>(t.r / 2 + 64), static_cast<std::uint8_t>(t.g / 2 + 64),
                static_cast<std::uint8_t>(t.b / 2 + 64)};  // faded where the map does not know
      }
      experiments::fill_rect(img, frames[0].left + i, py, 1, 1, t);
      experiments::fill_rect(img, frames[1].left + i, py, 1, 1, class_rgb(q.map_class[k]));
    }
  }
  // Layer windows on the map panel.
  for (int layer = 0; layer < Map::kLayerCount; ++layer) {
    const double w = map.layer_cell_width(layer);
    const int side = Map::layer_side(layer);
    const CellIndex c = map.layer_centre(layer);
    const double x0 = (c.x - side / 2) * w, y0 = (c.y - side / 2) * w, e = side * w;
    const PanelFrame& f = frames[1];
    experiments::draw_rect(img, static_cast<int>(f.px(x0)), static_cast<int>(f.py(y0 + e)),
                           static_cast<int>(std::lround(e * f.ppm())), static_cast<int>(std::lround(e * f.ppm())),
                           Rgb{60, 60, 60}, 1);
    // Labels inside the top-left corner; the 32 cm window nearly coincides with the 16 cm one
    // (both 10.24 m wide), so its label goes to the top-right corner.
    const std::string label = format("%.0f CM", 100.0 * w);
    const int lx = layer == 3 ? static_cast<int>(f.px(x0 + e)) - 3 - experiments::text_width(label)
                              : static_cast<int>(f.px(x0)) + 3;
    experiments::draw_text(img, lx, static_cast<int>(f.py(y0 + e)) + 3, label, Rgb{30, 30, 30});
  }
  for (const PanelFrame& f : frames) {
    draw_path(img, f, route, driven);
    for (const auto& [rock, detected] : large) {
      const double r = 0.5 * rock.diameter_m * f.ppm() + 4.0;
      const Rgb c = detected ? Rgb{255, 255, 255} : Rgb{255, 0, 255};
      for (int a = 0; a < 48; ++a) {
        const double t0 = a * 2.0 * 3.141592653589793 / 48, t1 = (a + 1) * 2.0 * 3.141592653589793 / 48;
        experiments::draw_line(img, f.px(rock.x) + r * std::cos(t0), f.py(rock.y) - r * std::sin(t0),
                               f.px(rock.x) + r * std::cos(t1), f.py(rock.y) - r * std::sin(t1), c, 2);
      }
    }
  }
  panel_decorations(img, frames[0], "GROUND TRUTH PER CLASSIFYING CELL (FADED: MAP UNKNOWN)");
  panel_decorations(img, frames[1], format("STACK QUERY EVERY %.0f CM, LAYER WINDOWS", 100.0 * q.step));
  experiments::draw_text(img, gap, 8,
                         "CADRE TRAVERSE: HAZARDS. TRUTH: OBSTACLE = RELIEF > 0.75 X CELL WIDTH, STEEP > 20 DEG",
                         experiments::kBlack);
  const int ly = top + pix + 16;
  int x = gap;
  x = experiments::legend_entry(img, x, ly, class_rgb(CellClass::kTraversable), "TRAVERSABLE / FREE");
  x = experiments::legend_entry(img, x, ly, class_rgb(CellClass::kObstacle), "OBSTACLE");
  x = experiments::legend_entry(img, x, ly, class_rgb(CellClass::kSteep), "STEEP");
  x = experiments::legend_entry(img, x, ly, class_rgb(CellClass::kUnknown), "UNKNOWN");
  experiments::legend_entry(img, x, ly, experiments::kBlack, "OUTSIDE TERRAIN");
  experiments::draw_text(img, gap, ly + 18,
                         "CIRCLES: ROCKS >= 48 CM (WHITE DETECTED, MAGENTA MISSED OR UNSEEN). PATH: WHITE DRIVEN, "
                         "SQUARE START, DOT ROVER",
                         experiments::kBlack);
  experiments::draw_text(img, gap, ly + 32, format("%.0f X %.0f M AROUND THE ROVER, NORTH UP", q.n * q.step, q.n * q.step),
                         experiments::kBlack);
  return tools::write_png(path, img, error);
}

template <typename Map>
TraverseResult traverse_with(const TraverseConfig& cfg) {
  TraverseResult result;
  std::FILE* log = cfg.log;
  // Path: 6 m east, a 90 deg left turn over 3.5 m, 4 m north (13.5 m).
  const sim::Pose2 start{6.0, 8.0, 0.0};
  const std::vector<sim::PathSegment> segments{{6.0, 0.0}, {3.5, 0.5 * sim::kPi}, {4.0, 0.0}};
  const std::vector<sim::PathPose> route = sim::generate_path(start, segments, cfg.frame_spacing_m);
  result.path_length_m = route.back().distance_m;
  const std::unique_ptr<sim::ProceduralTerrain> terrain = make_terrain(cfg.seed, route);
  result.rocks = terrain->rocks().size();
  result.boxes = terrain->boxes().size();
  const clock_t r0 = std::clock();
  const sim::HeightRaster raster = sim::rasterize(*terrain, terrain->params().area, cfg.raster_resolution_m);
  const double raster_ms = 1000.0 * static_cast<double>(std::clock() - r0) / CLOCKS_PER_SEC;

  sim::StereoParams sp;  // CADRE: 850 x 650, f 600 px, b 5 cm, 17.5 cm above ground
  sp.pixel_stride = cfg.pixel_stride;
  const sim::StereoCamera camera(sp);

  auto map = std::make_unique<Map>();
  if (map->init(default_stack_params(CadreConfig::kDefaultFinestCellWidthM)) != Status::kOk) {
    result.error = "stack init failed";
    return result;
  }
  const std::size_t frames = cfg.max_frames > 0 ? std::min<std::size_t>(route.size(), static_cast<std::size_t>(cfg.max_frames))
                                                : route.size();
  if (log != nullptr) {
    std::fprintf(log,
                 "ccmap traverse: seed %llu, terrain 30 x 30 m (%zu rocks, %zu box, raster %.0f cm in %.0f ms CPU), "
                 "path %.1f m, %zu frames every %.2f m, camera %d x %d px stride %d, %s CCM cell\n",
                 static_cast<unsigned long long>(cfg.seed), result.rocks, result.boxes, 100.0 * cfg.raster_resolution_m,
                 raster_ms, result.path_length_m, frames, cfg.frame_spacing_m, sp.width_px, sp.height_px, sp.pixel_stride,
                 cfg.paper_cell ? "paper (9-float)" : "full (10-float)");
  }
  std::vector<PointXYZ> points;
  for (std::size_t i = 0; i < frames; ++i) {
    const sim::Pose2& pose = route[i].pose;
    FrameRecord rec;
    rec.index = static_cast<int>(i);
    rec.pose = pose;
    const clock_t c0 = std::clock();
    const sim::StereoFrame frame = camera.capture(raster, pose, pose, cfg.seed * 1000003ULL + i);
    rec.capture_ms = 1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
    points.clear();
    for (const sim::Point3& p : frame.points_sensor) {
      points.push_back(PointXYZ{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
    }
    rec.points = points.size();
    const Status moved = map->move_to(static_cast<float>(pose.x), static_cast<float>(pose.y));
    const Pose sensor = camera_pose(camera, frame.sensor_position_map, pose.yaw);
    const Status updated =
        moved == Status::kOk ? map->update_frame_sensor(points.data(), points.size(), sensor, &rec.counters) : moved;
    rec.updated = updated == Status::kOk;
    rec.update_ms = static_cast<double>(map->last_update_ns()) * 1e-6;
    result.frames.push_back(rec);
    if (log != nullptr) {
      std::fprintf(log,
                   "frame %2zu/%zu  x %5.2f y %5.2f yaw %4.0f deg  points %6zu  used %6u  too noisy %6u  outside %5u  "
                   "update %6.2f ms%s  (capture %4.0f ms)\n",
                   i + 1, frames, pose.x, pose.y, pose.yaw * 180.0 / sim::kPi, rec.points, rec.counters.used,
                   rec.counters.too_noisy, rec.counters.outside_map, rec.update_ms, rec.updated ? "" : " REFUSED",
                   rec.capture_ms);
      std::fflush(log);
    }
  }
  std::vector<double> ms;
  for (const FrameRecord& f : result.frames) {
    ms.push_back(f.update_ms);
    result.capture_ms_total += f.capture_ms;
  }
  result.update_ms_median = median(ms);
  result.update_ms_max = ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end());
  for (double m : ms) result.update_ms_mean += m / static_cast<double>(ms.size());

  // ---- per-layer ground truth and evaluation ----
  std::vector<LayerTruth> truths(Map::kLayerCount);
  for (int layer = 0; layer < Map::kLayerCount; ++layer) {
    LayerTruth& t = truths[static_cast<std::size_t>(layer)];
    t.width = map->layer_cell_width(layer);
    t.side = Map::layer_side(layer);
    const CellIndex c = map->layer_centre(layer);
    t.min = CellIndex{c.x - t.side / 2, c.y - t.side / 2};
    sim::HazardParams hp;
    hp.min_obstacle_height_m = kObstacleFraction * t.width;
    hp.max_slope_deg = kMaxSlopeDeg;
    hp.sample_spacing_m = 0.01;
    t.grid = sim::compute_hazard_grid(*terrain, t.min.x * t.width, t.min.y * t.width, t.width, t.side, t.side, hp);
    LayerReport rep;
    rep.layer = layer;
    rep.cell_width_m = t.width;
    rep.min_obstacle_m = hp.min_obstacle_height_m;
    rep.ccm = Map::layer_is_ccm(layer);
    for (int iy = 0; iy < t.side; ++iy) {
      for (int ix = 0; ix < t.side; ++ix) {
        const sim::CellHazard& h = t.grid.at(ix, iy);
        if (!h.valid) continue;
        const float x = static_cast<float>((t.min.x + ix + 0.5) * t.width);
        const float y = static_cast<float>((t.min.y + iy + 0.5) * t.width);
        const QueryResult q = map->query_layer(layer, x, y);
        count(rep.areas, h.hazard(), q.status == Status::kOk ? q.cell_class : CellClass::kUnknown, t.width * t.width);
      }
    }
    std::vector<CellRecord> records(Map::layer_capacity(layer));
    if (map->export_layer(layer, records.data(), records.size(), &rep.exported) != Status::kOk) {
      result.error = format("export_layer(%d) failed", layer);
      return result;
    }
    for (std::size_t i = 0; i < rep.exported; ++i) rep.non_finite += record_finite(records[i]) ? 0U : 1U;
    result.layers.push_back(rep);
  }

  // ---- stack query on a fine raster over the coarsest window ----
  const LayerTruth& coarse = truths.back();
  QueryRaster qr;
  qr.step = cfg.query_step_m;
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
      const QueryResult q = map->query(fx, fy);
      const int layer = classifying_layer(*map, q, fx, fy);
      const std::size_t k = static_cast<std::size_t>(i) + static_cast<std::size_t>(qr.n) * static_cast<std::size_t>(j);
      const CellClass cls = q.status == Status::kOk ? q.cell_class : CellClass::kUnknown;
      qr.map_class[k] = cls;
      if (layer < 0) continue;
      const sim::CellHazard* h = truths[static_cast<std::size_t>(layer)].at(x, y);
      if (h == nullptr || !h->valid) continue;
      qr.truth[k] = static_cast<signed char>(h->obstacle ? 1 : (h->steep ? 2 : 0));
      count(result.stack, h->hazard(), cls, area);
    }
  }

  // ---- objects ----
  const double bin_edges[] = {0.04, 0.12, 0.24, result.min_size_5m_m, 1e9};
  for (int b = 0; b < 4; ++b) result.object_bins.push_back(ObjectBin{bin_edges[b], bin_edges[b + 1], 0, 0, 0});
  result.design_size.min_height_m = 0.0;
  result.design_size.max_height_m = 1e9;
  const double wx0 = qr.x0, wy0 = qr.y0, wx1 = qr.x0 + qr.n * qr.step, wy1 = qr.y0 + qr.n * qr.step;
  std::vector<std::pair<sim::Rock, bool>> large;
  auto judge = [&](double cx, double cy, double height, const sim::Rock* rock, auto&& covers, double x0, double y0,
                   double x1, double y1) {
    if (cx < wx0 || cy < wy0 || cx >= wx1 || cy >= wy1) return;
    bool observed = false, detected = false;
    double coarsest = 0.0;
    for (double y = y0 + 0.5 * kFootprintStepM; y < y1; y += kFootprintStepM) {
      for (double x = x0 + 0.5 * kFootprintStepM; x < x1; x += kFootprintStepM) {
        if (!covers(x, y)) continue;
        const float fx = static_cast<float>(x), fy = static_cast<float>(y);
        const QueryResult q = map->query(fx, fy);
        if (q.status != Status::kOk) continue;
        observed = true;
        detected = detected || is_hazard(q.cell_class);
        coarsest = std::max(coarsest, static_cast<double>(map->layer_cell_width(classifying_layer(*map, q, fx, fy))));
      }
    }
    for (ObjectBin& b : result.object_bins) {
      if (height >= b.min_height_m && height < b.max_height_m) {
        ++b.in_window;
        b.observed += observed ? 1 : 0;
        b.detected += detected ? 1 : 0;
      }
    }
    if (observed && height >= kObstacleFraction * coarsest) {
      ++result.design_size.in_window;
      ++result.design_size.observed;
      result.design_size.detected += detected ? 1 : 0;
    }
    if (rock != nullptr && height >= result.min_size_5m_m) large.emplace_back(*rock, detected);
  };
  for (const sim::Rock& r : terrain->rocks()) {
    const double rad = 0.5 * r.diameter_m;
    judge(r.x, r.y, r.height_m, &r, [&](double x, double y) { return std::hypot(x - r.x, y - r.y) <= rad; }, r.x - rad,
          r.y - rad, r.x + rad, r.y + rad);
  }
  for (const sim::Box& b : terrain->boxes()) {
    judge(0.5 * (b.x0 + b.x1), 0.5 * (b.y0 + b.y1), b.height_m, nullptr, [](double, double) { return true; }, b.x0, b.y0,
          b.x1, b.y1);
  }

  // ---- pictures ----
  if (!cfg.out_dir.empty()) {
    std::string error;
    if (!experiments::ensure_directory(cfg.out_dir, &error)) {
      result.error = error;
      return result;
    }
    for (int layer = 0; layer < Map::kLayerCount; ++layer) {
      const std::string file =
          cfg.out_dir + format("/layer%d_%02.0fcm.png", layer, 100.0 * map->layer_cell_width(layer));
      if (!write_layer_picture(file, *map, layer, route, frames, &error)) {
        result.error = error;
        return result;
      }
      result.pictures.push_back(file);
    }
    const std::string file = cfg.out_dir + "/hazards_truth_vs_map.png";
    if (!write_hazard_picture(file, qr, *map, route, frames, large, &error)) {
      result.error = error;
      return result;
    }
    result.pictures.push_back(file);
  }
  return result;
}

}  // namespace

TraverseResult run_traverse(const TraverseConfig& cfg) {
  return cfg.paper_cell ? traverse_with<Stack<PaperCell<CadreConfig>>>(cfg) : traverse_with<Stack<CadreConfig>>(cfg);
}

std::string traverse_report(const TraverseResult& r) {
  using experiments::Table;
  std::string out;
  std::size_t updated = 0, points = 0, used = 0;
  for (const FrameRecord& f : r.frames) {
    updated += f.updated ? 1U : 0U;
    points += f.points;
    used += f.counters.used;
  }
  out += format("frames: %zu updated of %zu; %zu points, %zu used (%.0f %%)\n", updated, r.frames.size(), points, used,
                points > 0 ? 100.0 * static_cast<double>(used) / static_cast<double>(points) : 0.0);
  out += format("update time per frame (Stack::last_update_ns): median %.2f ms, mean %.2f ms, max %.2f ms "
                "(paper: 80 ms on a Snapdragon 820 for 850 x 650 stereo)\n",
                r.update_ms_median, r.update_ms_mean, r.update_ms_max);
  out += format("simulator ray casting: %.1f s CPU in total (not part of the map)\n\n", 1e-3 * r.capture_ms_total);
  auto pct = [](double part, double whole) { return whole > 0.0 ? format("%.1f %%", 100.0 * part / whole) : std::string("-"); };
  Table t({"layer", "cell", "kind", "min obstacle", "correct", "missed obstacle", "false obstacle", "unknown",
           "hazard hit", "false share of free", "exported", "non-finite"});
  auto row = [&](const std::string& name, const std::string& cell, const std::string& kind, const std::string& min_obs,
                 const DetectionAreas& a, const std::string& exported, const std::string& nf) {
    const double total = a.known() + a.unknown;
    t.add_row({name, cell, kind, min_obs, format("%.2f m2 (%s)", a.correct, pct(a.correct, total).c_str()),
               format("%.2f m2", a.missed), format("%.2f m2", a.false_obstacle),
               format("%.1f m2 (%s)", a.unknown, pct(a.unknown, total).c_str()),
               a.truth_hazard_known > 0.0 ? format("%.1f %%", 100.0 * a.hit_share()) : "-",
               format("%.2f %%", 100.0 * a.false_share()), exported, nf});
  };
  for (const LayerReport& l : r.layers) {
    row(format("%d", l.layer), format("%.0f cm", 100.0 * l.cell_width_m), l.ccm ? "CCM" : "Kalman+roughness",
        format("%.0f cm", 100.0 * l.min_obstacle_m), l.areas, format("%zu", l.exported), format("%zu", l.non_finite));
  }
  row("stack", "query", "finest known", "0.75 x w", r.stack, "", "");
  out += "hazard detection over the final map window (areas; truth per layer: obstacle = relief > 0.75 x cell width, "
         "steep > 20 deg)\n" +
         t.str() + "\n";
  Table o({"objects (rocks, box)", "in window", "observed", "detected", "detection rate"});
  for (const ObjectBin& b : r.object_bins) {
    const std::string name = b.max_height_m > 100.0 ? format("height >= %.0f cm (5 m-range minimum)", 100.0 * b.min_height_m)
                                                    : format("height %.0f-%.0f cm", 100.0 * b.min_height_m, 100.0 * b.max_height_m);
    o.add_row({name, format("%d", b.in_window), format("%d", b.observed), format("%d", b.detected),
               b.observed > 0 ? format("%.0f %%", 100.0 * b.rate()) : "-"});
  }
  const ObjectBin& d = r.design_size;
  o.add_row({">= 0.75 x answering cell width", "", format("%d", d.observed), format("%d", d.detected),
             d.observed > 0 ? format("%.0f %%", 100.0 * d.rate()) : "-"});
  out += "object detection by the stack query (detected: any footprint point obstacle/steep)\n" + o.str();
  return out;
}

}  // namespace ccmap::traverse
