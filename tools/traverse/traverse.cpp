#include "traverse/traverse.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <memory>

#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/registration/registration.hpp"
#include "experiments/canvas.hpp"
#include "experiments/common.hpp"
#include "layer_images.hpp"
#include "png.hpp"
#include "sim/hazard.hpp"
#include "sim/path.hpp"
#include "sim/stereo.hpp"
#include "sim/terrain.hpp"
#include "traverse/scene.hpp"

namespace ccmap::traverse {

namespace {

using experiments::format;
using experiments::Rgb;

constexpr double kFootprintStepM = 0.02;

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

/// The next `ahead` metres of the route from distance d, as a polyline: the rover's pose, the
/// fine route's points after it, the point at d + ahead (interpolated).
std::vector<PathPoint> route_ahead(const std::vector<sim::PathPose>& fine, double d, double ahead) {
  std::vector<PathPoint> pts;
  const double end = d + ahead;
  for (std::size_t k = 0; k < fine.size(); ++k) {
    const double t = fine[k].distance_m;
    if (t < d - 1e-9) continue;
    if (t <= end + 1e-9) {
      pts.push_back(PathPoint{static_cast<float>(fine[k].pose.x), static_cast<float>(fine[k].pose.y)});
      continue;
    }
    const sim::Pose2& a = fine[k - 1].pose;
    const sim::Pose2& b = fine[k].pose;
    const double f = (end - fine[k - 1].distance_m) / (t - fine[k - 1].distance_m);
    pts.push_back(PathPoint{static_cast<float>(a.x + f * (b.x - a.x)), static_cast<float>(a.y + f * (b.y - a.y))});
    break;
  }
  return pts;
}

/// Colours of the cost raster: cost white (0) .. dark grey (252), inscribed lilac, lethal red,
/// unknown dark blue-grey.
Rgb cost_rgb(std::uint8_t c) {
  if (c == kCostLethal) return Rgb{215, 35, 35};
  if (c == kCostInscribed) return Rgb{205, 165, 245};
  if (c == kCostUnknown) return Rgb{45, 45, 70};
  const auto v = static_cast<std::uint8_t>(255 - (170 * c) / 252);
  return Rgb{v, v, v};
}

/// The cost raster around the final pose, the route, and where the look-ahead saw hazards.
template <typename Map>
bool write_costmap_picture(const std::string& path, const Map& map, const std::vector<sim::PathPose>& route,
                           std::size_t driven, const TraverseResult& result, std::string* error) {
  const std::vector<FrameRecord>& frames = result.frames;
  const int stop_frame = result.stop_frame;
  constexpr int kSide = 256;
  constexpr float kRes = 0.04F;
  constexpr float kInflation = 0.3F;
  const sim::Pose2& rover = route[driven - 1].pose;
  std::vector<std::uint8_t> cost(static_cast<std::size_t>(kSide) * kSide);
  CostmapStats stats{};
  const Status status = fill_costmap(map, CostmapSpec{static_cast<float>(rover.x), static_cast<float>(rover.y), kRes, kSide,
                                                      kInflation},
                                     cost.data(), cost.size(), &stats);
  if (status != Status::kOk) {
    *error = std::string("fill_costmap: ") + to_string(status);
    return false;
  }
  const int scale = 2, pix = kSide * scale, gap = 24, top = 44, legend = 74;
  tools::RgbImage img(pix + 2 * gap, top + pix + legend, 255);
  PanelFrame f;
  f.x0 = rover.x - 0.5 * kSide * kRes;
  f.y0 = rover.y - 0.5 * kSide * kRes;
  f.extent = kSide * kRes;
  f.left = gap;
  f.top = top;
  f.pixels = pix;
  for (int iy = 0; iy < kSide; ++iy) {
    for (int ix = 0; ix < kSide; ++ix) {
      const Rgb c = cost_rgb(cost[static_cast<std::size_t>(ix + kSide * iy)]);
      experiments::fill_rect(img, f.left + ix * scale, f.top + (kSide - 1 - iy) * scale, scale, scale, c);
    }
  }
  draw_path(img, f, route, driven);
  // Every look-ahead hazard (the body's centre there), and the first one: where the rover stops.
  for (const FrameRecord& r : frames) {
    if (r.ahead_hazard) experiments::fill_disc(img, f.px(r.ahead_hazard_pose.x), f.py(r.ahead_hazard_pose.y), 3.0, Rgb{255, 150, 0});
  }
  if (stop_frame >= 0) {
    const FrameRecord& r = frames[static_cast<std::size_t>(stop_frame)];
    experiments::draw_rect(img, static_cast<int>(f.px(r.pose.x)) - 6, static_cast<int>(f.py(r.pose.y)) - 6, 13, 13,
                           Rgb{255, 0, 255}, 2);
  }
  panel_decorations(img, f, format("%.2f M AROUND THE ROVER AT %.0f CM, %.1f M INFLATION", kSide * kRes, 100.0 * kRes,
                                   kInflation));
  experiments::draw_text(img, gap, 8, "CADRE TRAVERSE: THE PLANNER'S COST RASTER (COSTMAP_2D VALUES)", experiments::kBlack);
  const int ly = top + pix + 14;
  int x = gap;
  x = experiments::legend_entry(img, x, ly, cost_rgb(0), "FREE");
  x = experiments::legend_entry(img, x, ly, cost_rgb(200), "COST 200");
  x = experiments::legend_entry(img, x, ly, cost_rgb(kCostInscribed), "INSCRIBED");
  x = experiments::legend_entry(img, x, ly, cost_rgb(kCostLethal), "LETHAL");
  experiments::legend_entry(img, x, ly, cost_rgb(kCostUnknown), "UNKNOWN");
  experiments::draw_text(img, gap, ly + 18,
                         format("LOOK-AHEAD: THE %.1f X %.1f M BODY ALONG THE NEXT %.1f M AFTER EACH FRAME", result.body_length_m,
                                result.body_width_m, result.lookahead_m),
                         experiments::kBlack);
  experiments::draw_text(img, gap, ly + 32, "ORANGE: BODY WHERE IT SAW A HAZARD; MAGENTA: WHERE THE ROVER STOPS",
                         experiments::kBlack);
  return tools::write_png(path, img, error);
}

/// The traverse with map type Map: Stack<CadreConfig> (full CCM cells) or PaperMap
/// (TraverseConfig::paper_cell, the paper's 9-float cell).
template <typename Map>
TraverseResult traverse_with(const TraverseConfig& cfg) {
  TraverseResult result;
  std::FILE* log = cfg.log;
  // Path: 6 m east, a 90 deg left turn over 3.5 m, 4 m north (13.5 m).
  const sim::Pose2 start{6.0, 8.0, 0.0};
  const std::vector<sim::PathSegment> segments{{6.0, 0.0}, {3.5, 0.5 * sim::kPi}, {4.0, 0.0}};
  const std::vector<sim::PathPose> route = sim::generate_path(start, segments, cfg.frame_spacing_m);
  const std::vector<sim::PathPose> fine_route = sim::generate_path(start, segments, 0.05);  // the look-ahead's polylines
  result.lookahead_m = cfg.lookahead_m;
  result.lookahead_step_m = cfg.lookahead_step_m;
  result.body_length_m = cfg.body_length_m;
  result.body_width_m = cfg.body_width_m;
  result.path_length_m = route.back().distance_m;
  const std::unique_ptr<sim::ProceduralTerrain> terrain = make_terrain(cfg.seed, {route});
  result.rocks = terrain->rocks().size();
  result.boxes = terrain->boxes().size();
  const clock_t r0 = std::clock();
  const sim::HeightRaster raster = sim::rasterize(*terrain, terrain->params().area, cfg.raster_resolution_m);
  const double raster_ms = 1000.0 * static_cast<double>(std::clock() - r0) / CLOCKS_PER_SEC;

  sim::StereoParams sp;  // CADRE: 850 x 650, f 600 px, b 5 cm, 17.5 cm above ground
  sp.pixel_stride = cfg.pixel_stride;
  sp.mismatch_probability = cfg.mismatch_share;
  const sim::StereoCamera camera(sp);

  auto map = std::make_unique<Map>();
  StackParams params = default_stack_params(CadreConfig::kDefaultFinestCellWidthM);
  cfg.gate.apply(&params);
  if (map->init(params) != Status::kOk) {
    result.error = "stack init failed";
    return result;
  }
  const std::size_t frames = cfg.max_frames > 0 ? std::min<std::size_t>(route.size(), static_cast<std::size_t>(cfg.max_frames))
                                                : route.size();
  if (log != nullptr) {
    std::fprintf(log,
                 "ccmap traverse: seed %llu, terrain 30 x 30 m (%zu rocks, %zu box, raster %.0f cm in %.0f ms CPU), "
                 "path %.1f m, %zu frames every %.2f m, camera %d x %d px stride %d, %s CCM cell, %.1f %% mismatched pixels; %s\n",
                 static_cast<unsigned long long>(cfg.seed), result.rocks, result.boxes, 100.0 * cfg.raster_resolution_m,
                 raster_ms, result.path_length_m, frames, cfg.frame_spacing_m, sp.width_px, sp.height_px, sp.pixel_stride,
                 cfg.paper_cell ? "paper (9-float)" : "full (10-float)", 100.0 * cfg.mismatch_share,
                 cfg.gate.describe(params).c_str());
  }
  std::vector<PointXYZ> points;
  sim::DriftParams drift;
  drift.fraction_of_distance = cfg.drift_fraction;
  drift.direction_rad = cfg.drift_direction_rad;
  drift.heading_rad_per_m = cfg.yaw_drift_rad_per_m;
  const std::vector<sim::Pose2> drifted = sim::apply_drift(route, drift);
  // Registration's corrections so far: q = Rz(c_yaw) p + (c_x, c_y), heights + c_z.
  double c_yaw = 0.0, c_x = 0.0, c_y = 0.0, c_z = 0.0;
  for (std::size_t i = 0; i < frames; ++i) {
    const sim::Pose2& pose = route[i].pose;
    FrameRecord rec;
    rec.index = static_cast<int>(i);
    rec.pose = pose;
    sim::Pose2 est = drifted[i];
    {
      const double cs = std::cos(c_yaw), sn = std::sin(c_yaw);
      est = sim::Pose2{cs * est.x - sn * est.y + c_x, sn * est.x + cs * est.y + c_y, est.yaw + c_yaw};
    }
    const clock_t c0 = std::clock();
    const sim::StereoFrame frame = camera.capture(raster, pose, est, cfg.seed * 1000003ULL + i);
    rec.capture_ms = 1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
    points.clear();
    for (const sim::Point3& p : frame.points_sensor) {
      points.push_back(PointXYZ{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
    }
    rec.points = points.size();
    rec.mismatches = frame.mismatch_pixels;
    sim::Point3 position = frame.sensor_position_map;
    position.z += c_z;
    Pose sensor = camera_pose(camera, position, est.yaw);
    if (cfg.register_frames && i > 0 && map->move_to(static_cast<float>(est.x), static_cast<float>(est.y)) == Status::kOk) {
      const RegistrationResult r = ccmap::register_frame_sensor(*map, points.data(), points.size(), sensor, default_registration_params());
      rec.registration = to_string(r.status);
      if (r.status == Status::kOk) {
        const double corr[4] = {r.dx, r.dy, r.dz, r.dyaw};
        for (int k = 0; k < 4; ++k) {
          rec.correction[k] = corr[k];
          rec.observable[k] = r.observable[k];
        }
        // About the camera o: q' = Rz(a)(q - o) + o + d, composed after the corrections so far.
        const double ca = std::cos(double(r.dyaw)), sa = std::sin(double(r.dyaw));
        const double ox = sensor.translation.x, oy = sensor.translation.y;
        auto turn = [&](double x, double y, double* qx, double* qy) {
          *qx = ca * (x - ox) - sa * (y - oy) + ox + r.dx;
          *qy = sa * (x - ox) + ca * (y - oy) + oy + r.dy;
        };
        double nx = 0.0, ny = 0.0;
        turn(c_x, c_y, &nx, &ny);
        c_x = nx;
        c_y = ny;
        c_yaw += r.dyaw;
        c_z += r.dz;
        turn(est.x, est.y, &est.x, &est.y);
        est.yaw += r.dyaw;
        position.x += r.dx;
        position.y += r.dy;
        position.z += r.dz;
        sensor = camera_pose(camera, position, est.yaw);
      }
    }
    rec.estimate = est;
    const Status moved = map->move_to(static_cast<float>(est.x), static_cast<float>(est.y));
    const Status updated =
        moved == Status::kOk ? map->update_frame_sensor(points.data(), points.size(), sensor, &rec.counters) : moved;
    rec.updated = updated == Status::kOk;
    rec.update_ms = static_cast<double>(map->last_update_ns()) * 1e-6;
    // The planner's look-ahead: the body swept along the next lookahead_m of the route.
    // At the end of the route nothing lies ahead (a single point is no path): no query.
    const std::vector<PathPoint> ahead = route_ahead(fine_route, route[i].distance_m, cfg.lookahead_m);
    rec.route_end = ahead.size() < 2;
    const clock_t a0 = std::clock();
    const PathResult look =
        rec.route_end ? detail::refused_path(Status::kOk)
                      : query_path(*map, ahead.data(), ahead.size(),
                                   PathSweep{static_cast<float>(cfg.body_length_m), static_cast<float>(cfg.body_width_m),
                                             static_cast<float>(cfg.lookahead_step_m), kDefaultMaxUnknownShare});
    rec.ahead_ms = 1000.0 * static_cast<double>(std::clock() - a0) / CLOCKS_PER_SEC;
    rec.ahead_ok = look.status == Status::kOk;
    rec.ahead_hazard = look.hazard_found;
    rec.ahead_hazard_m = look.first_hazard_m;
    rec.ahead_hazard_pose = sim::Pose2{look.hazard_pose.x, look.hazard_pose.y, std::atan2(look.hazard_pose.heading_y, look.hazard_pose.heading_x)};
    rec.ahead_hazard_class = to_string(look.hazard.worst_class);
    rec.ahead_unknown = look.unknown_found;
    rec.ahead_unknown_m = look.first_unknown_m;
    rec.ahead_poses = look.samples;
    result.frames.push_back(rec);
    if (log != nullptr) {
      const std::string hazard = rec.route_end      ? std::string("end of the route")
                                 : !rec.ahead_ok    ? std::string("REFUSED")
                                 : rec.ahead_hazard ? format("%s at %.2f m", rec.ahead_hazard_class, rec.ahead_hazard_m)
                                                    : std::string("clear");
      const std::string unknown = rec.ahead_unknown ? format("from %.2f m", rec.ahead_unknown_m) : std::string("none");
      std::fprintf(log,
                   "frame %2zu/%zu  x %5.2f y %5.2f yaw %4.0f deg  points %6zu  used %6u  too noisy %6u  outside %5u  "
                   "held %5u (dropped %5u, admitted %5u, pool full %5u, slots %4u)  update %6.2f ms%s  (capture %4.0f ms)  "
                   "ahead %.1f m: %s, unknown %s\n",
                   i + 1, frames, pose.x, pose.y, pose.yaw * 180.0 / sim::kPi, rec.points, rec.counters.used,
                   rec.counters.too_noisy, rec.counters.outside_map, rec.counters.gated_held, rec.counters.gated_dropped,
                   rec.counters.gated_admitted, rec.counters.gated_pool_full, map->last_frame_held_cells(), rec.update_ms,
                   rec.updated ? "" : " REFUSED", rec.capture_ms, cfg.lookahead_m, hazard.c_str(), unknown.c_str());
      std::fflush(log);
    }
  }
  std::vector<double> ahead_ms;
  for (std::size_t k = 0; k < result.frames.size(); ++k) {
    const FrameRecord& f = result.frames[k];
    if (!f.route_end) ahead_ms.push_back(f.ahead_ms);
    result.frames_with_hazard_ahead += f.ahead_hazard ? 1 : 0;
    result.frames_with_unknown_ahead += f.ahead_unknown ? 1 : 0;
    if (f.ahead_hazard && result.stop_frame < 0) result.stop_frame = static_cast<int>(k);
  }
  result.ahead_ms_median = median(ahead_ms);
  result.ahead_ms_max = ahead_ms.empty() ? 0.0 : *std::max_element(ahead_ms.begin(), ahead_ms.end());
  std::vector<double> ms;
  for (const FrameRecord& f : result.frames) {
    ms.push_back(f.update_ms);
    result.capture_ms_total += f.capture_ms;
  }
  result.update_ms_median = median(ms);
  result.update_ms_max = ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end());
  for (double m : ms) result.update_ms_mean += m / static_cast<double>(ms.size());

  // ---- per-layer ground truth and evaluation ----
  std::vector<LayerTruth> truths;
  for (int layer = 0; layer < Map::kLayerCount; ++layer) {
    truths.push_back(layer_truth(*map, *terrain, layer));
    const LayerTruth& t = truths.back();
    LayerReport rep;
    rep.layer = layer;
    rep.cell_width_m = t.width;
    rep.min_obstacle_m = kObstacleFraction * t.width;
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
  const QueryRaster qr = query_raster(*map, truths, cfg.query_step_m, &result.stack);
  // The map error: the stack's height against the terrain's surface where it knows the ground. A
  // drop-off answers kOk with weight 0 and its height an upper bound of the hidden floor, not a
  // measured height: it is not counted here (its area is counted apart, scene.cpp).
  {
    double sum = 0.0;
    std::size_t known = 0, beyond = 0;
    for (int iy = 0; iy < qr.n; ++iy) {
      for (int ix = 0; ix < qr.n; ++ix) {
        const double x = qr.x0 + (ix + 0.5) * qr.step, y = qr.y0 + (iy + 0.5) * qr.step;
        const QueryResult q = map->query(static_cast<float>(x), static_cast<float>(y));
        if (q.status != Status::kOk || q.cell_class == CellClass::kDropOff) continue;
        const double e = static_cast<double>(q.height_m) - terrain->height(x, y);
        sum += e * e;
        ++known;
        beyond += std::fabs(e) > 0.05 ? 1U : 0U;
      }
    }
    result.height_rms_m = known > 0 ? std::sqrt(sum / static_cast<double>(known)) : 0.0;
    result.height_beyond_5cm = known > 0 ? static_cast<double>(beyond) / static_cast<double>(known) : 0.0;
  }
  if (!result.frames.empty()) {
    const FrameRecord& last = result.frames.back();
    result.final_pose_error_m = std::hypot(last.estimate.x - last.pose.x, last.estimate.y - last.pose.y);
    result.final_yaw_error_rad = last.estimate.yaw - last.pose.yaw;
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
    const std::string costmap = cfg.out_dir + "/costmap.png";
    if (!write_costmap_picture(costmap, *map, route, frames, result, &error)) {
      result.error = error;
      return result;
    }
    result.pictures.push_back(costmap);
  }
  return result;
}

}  // namespace

TraverseResult run_traverse(const TraverseConfig& cfg) {
  return cfg.paper_cell ? traverse_with<PaperMap>(cfg) : traverse_with<Map>(cfg);
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
  out += format("simulator ray casting: %.1f s CPU in total (not part of the map)\n", 1e-3 * r.capture_ms_total);
  {
    std::size_t registered = 0, ok = 0, x = 0, y = 0, z = 0, yaw = 0;
    for (const FrameRecord& f : r.frames) {
      if (f.registration == "-") continue;
      ++registered;
      if (f.registration != "ok") continue;
      ++ok;
      x += f.observable[0] ? 1U : 0U;
      y += f.observable[1] ? 1U : 0U;
      z += f.observable[2] ? 1U : 0U;
      yaw += f.observable[3] ? 1U : 0U;
    }
    out += format("pose estimate: final error %.1f mm, %.2f deg; map height against the terrain: RMS %.1f mm, %.2f %% "
                  "of the known points more than 5 cm off\n",
                  1000.0 * r.final_pose_error_m, r.final_yaw_error_rad * 180.0 / sim::kPi, 1000.0 * r.height_rms_m,
                  100.0 * r.height_beyond_5cm);
    if (registered > 0) {
      out += format("registration: %zu frames, %zu ok; observable dx %zu, dy %zu, dz %zu, dyaw %zu\n", registered, ok, x,
                    y, z, yaw);
    }
  }
  out += format("look-ahead (query_path, the body along the next %.1f m, a pose every %.0f cm): median %.2f ms, max %.2f ms "
                "CPU; a hazard ahead after %d of %zu frames, an unknown footprint ahead after %d\n",
                r.lookahead_m, 100.0 * r.lookahead_step_m, r.ahead_ms_median, r.ahead_ms_max, r.frames_with_hazard_ahead,
                r.frames.size(), r.frames_with_unknown_ahead);
  if (r.stop_frame >= 0) {
    const FrameRecord& f = r.frames[static_cast<std::size_t>(r.stop_frame)];
    out += format("the rover would have stopped after frame %d at (%.2f, %.2f): %s %.2f m ahead, body at (%.2f, %.2f)\n\n",
                  f.index + 1, f.pose.x, f.pose.y, f.ahead_hazard_class, f.ahead_hazard_m, f.ahead_hazard_pose.x,
                  f.ahead_hazard_pose.y);
  } else {
    out += "the rover would not have stopped: no hazard within the look-ahead after any frame\n\n";
  }
  auto pct = [](double part, double whole) { return whole > 0.0 ? format("%.1f %%", 100.0 * part / whole) : std::string("-"); };
  Table t({"layer", "cell", "kind", "min obstacle", "correct", "missed obstacle", "false obstacle", "unknown",
           "drop-off (truth hazard / free)", "hazard hit", "false share of free", "exported", "non-finite"});
  auto row = [&](const std::string& name, const std::string& cell, const std::string& kind, const std::string& min_obs,
                 const DetectionAreas& a, const std::string& exported, const std::string& nf) {
    const double total = a.known() + a.unknown + a.drop_truth_hazard + a.drop_truth_free;
    t.add_row({name, cell, kind, min_obs, format("%.2f m2 (%s)", a.correct, pct(a.correct, total).c_str()),
               format("%.2f m2", a.missed), format("%.2f m2", a.false_obstacle),
               format("%.1f m2 (%s)", a.unknown, pct(a.unknown, total).c_str()),
               format("%.2f / %.2f m2", a.drop_truth_hazard, a.drop_truth_free),
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
