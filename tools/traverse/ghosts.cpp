#include "traverse/ghosts.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "ccmap/persistence/exchange.hpp"
#include "ccmap/map/visibility/sight_table.hpp"
#include "ccmap/planner/path_query.hpp"
#include "experiments/canvas.hpp"
#include "layer_images.hpp"
#include "png.hpp"
#include "sim/hazard.hpp"
#include "sim/stereo.hpp"
#include "sim/terrain.hpp"
#include "traverse/scene.hpp"

namespace ccmap::traverse {

/// The ghost experiment's maps carry the viewshed table, so that `--rays 65535` casts every line
/// of sight and `--stride K` those of one point in K (docs/design.md 12); at any other count they
/// are the CADRE stack (the table unused).
using GhostMap = Stack<WithEveryLineOfSight<CadreConfig>>;

namespace {

using experiments::format;
using experiments::Rgb;

struct Body {
  double x = 0.0, y = 0.0, yaw = 0.0;
};

/// True if (x, y) lies inside body b's footprint grown by `margin` on every side.
bool inside_body(const Body& b, double x, double y, double margin) {
  const double dx = x - b.x, dy = y - b.y;
  const double c = std::cos(b.yaw), s = std::sin(b.yaw);
  const double along = dx * c + dy * s, across = -dx * s + dy * c;
  return std::fabs(along) <= 0.5 * kRoverLengthM + margin && std::fabs(across) <= 0.5 * kRoverWidthM + margin;
}

/// Raises the raster's vertices under the bodies to the ground + kRoverHeightM (a box), keeping
/// what it replaced; restore() puts it back.
class BodyStamp {
 public:
  BodyStamp(sim::HeightRaster& raster, const std::vector<Body>& bodies) : raster_(raster) {
    const double res = raster.resolution();
    const double reach = 0.5 * std::hypot(kRoverLengthM, kRoverWidthM) + res;
    for (const Body& b : bodies) {
      const int i0 = std::max(0, static_cast<int>(std::floor((b.x - reach - raster.origin_x()) / res)));
      const int i1 = std::min(raster.nx() - 1, static_cast<int>(std::ceil((b.x + reach - raster.origin_x()) / res)));
      const int j0 = std::max(0, static_cast<int>(std::floor((b.y - reach - raster.origin_y()) / res)));
      const int j1 = std::min(raster.ny() - 1, static_cast<int>(std::ceil((b.y + reach - raster.origin_y()) / res)));
      const float ground = static_cast<float>(raster.height(b.x, b.y));
      for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
          if (!inside_body(b, raster.origin_x() + i * res, raster.origin_y() + j * res, 0.0)) continue;
          saved_.push_back(Saved{i, j, raster.at(i, j)});
          raster.at(i, j) = std::max(raster.at(i, j), ground + static_cast<float>(kRoverHeightM));
        }
      }
      area_.push_back(sim::Rect{b.x - reach, b.y - reach, b.x + reach, b.y + reach});
    }
    for (const sim::Rect& a : area_) raster.rebuild_blocks(a);
  }
  ~BodyStamp() {
    for (auto it = saved_.rbegin(); it != saved_.rend(); ++it) raster_.at(it->i, it->j) = it->h;
    for (const sim::Rect& a : area_) raster_.rebuild_blocks(a);
  }
  BodyStamp(const BodyStamp&) = delete;
  BodyStamp& operator=(const BodyStamp&) = delete;

 private:
  struct Saved {
    int i, j;
    float h;
  };
  sim::HeightRaster& raster_;
  std::vector<Saved> saved_;
  std::vector<sim::Rect> area_;
};

StackParams map_params(const GhostConfig& config, bool free_space) {
  StackParams p = default_stack_params(0.04F);
  config.gate.apply(&p);
  p.sensor_view_axis = {0.0F, 0.0F, 1.0F};  // the simulator's optical frame looks along +z
  if (config.free_space_rays > 0) p.free_space_rays = static_cast<float>(config.free_space_rays);
  if (!free_space) p.free_space_rays = 0.0F;
  return p;
}

/// What AFTER casts per frame, in words: "256 lines of sight walked", "every line of sight",
/// "one line of sight in 4" (the viewshed table fed by one point in 4).
std::string rays_description(const GhostConfig& config) {
  const float rays = map_params(config, true).free_space_rays;
  const int stride = detail::sight_stride_of_rays(rays);
  if (stride == 1) return "every line of sight";
  if (stride > 1) return format("one line of sight in %d", stride);
  return format("%d lines of sight walked", static_cast<int>(rays));
}

std::unique_ptr<GhostMap> make_map(const StackParams& p, std::string* error) {
  auto m = std::make_unique<GhostMap>();
  if (m->init(p) != Status::kOk) {
    *error = "the map refused its parameters";
    return nullptr;
  }
  return m;
}

/// The camera's frame as the stack takes it (sensor frame and pose).
struct CameraFrame {
  std::vector<PointXYZ> points;
  Pose pose{};
  double x = 0.0, y = 0.0;
};

/// `raw`, if given, receives the simulator's frame (its true depths: the drop-off reference).
CameraFrame capture(const sim::StereoCamera& camera, const sim::HeightRaster& raster, const Body& b, std::uint64_t seed,
                    sim::StereoFrame* raw = nullptr) {
  const sim::StereoFrame f = camera.capture(raster, sim::Pose2{b.x, b.y, b.yaw}, seed);
  if (raw != nullptr) *raw = f;
  CameraFrame out;
  out.points.reserve(f.points_sensor.size());
  for (const sim::Point3& p : f.points_sensor) {
    out.points.push_back(PointXYZ{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
  }
  out.pose = camera_pose(camera, f.sensor_position_map, b.yaw);
  out.x = b.x;
  out.y = b.y;
  return out;
}

/// Every cell's weight, layer by layer in window order (to find the cells a frame emptied).
std::vector<float> cell_weights(const GhostMap& m) {
  std::vector<float> w;
  m.fine_layer().for_each([&w](CellIndex, const GhostMap::FineCell& c) { w.push_back(c.weight); });
  for (int k = 0; k < GhostMap::kCcmLayerCount; ++k) {
    m.ccm_layer(k).for_each([&w](CellIndex, const GhostMap::CcmCellType& c) { w.push_back(c.weight); });
  }
  return w;
}

/// Calls fn(layer, centre_x, centre_y, width) for every cell with weight > 0 in `before` and 0 now.
template <typename Fn>
void for_each_emptied(const GhostMap& m, const std::vector<float>& before, Fn&& fn) {
  std::size_t i = 0;
  const float w0 = m.layer_cell_width(0);
  m.fine_layer().for_each([&](CellIndex idx, const GhostMap::FineCell& c) {
    if (before[i++] > 0.0F && !(c.weight > 0.0F)) fn(0, (idx.x + 0.5) * w0, (idx.y + 0.5) * w0, double{w0});
  });
  for (int k = 0; k < GhostMap::kCcmLayerCount; ++k) {
    const double w = m.layer_cell_width(k + 1);
    m.ccm_layer(k).for_each([&](CellIndex idx, const GhostMap::CcmCellType& c) {
      if (before[i++] > 0.0F && !(c.weight > 0.0F)) fn(k + 1, (idx.x + 0.5) * w, (idx.y + 0.5) * w, w);
    });
  }
}

bool rock_in_square(const sim::ProceduralTerrain& t, double cx, double cy, double w) {
  for (const sim::Rock& r : t.rocks()) {
    const double rad = 0.5 * r.diameter_m;
    if (std::fabs(r.x - cx) <= 0.5 * w + rad && std::fabs(r.y - cy) <= 0.5 * w + rad) return true;
  }
  return false;
}

/// Free ground at (x, y): no rock or box within 10 cm and the terrain within 4 cm of flat there.
bool free_ground(const sim::ProceduralTerrain& t, double x, double y) {
  double lo = 1e300, hi = -1e300;
  for (int j = -2; j <= 2; ++j) {
    for (int i = -2; i <= 2; ++i) {
      const double dx = 0.05 * i, dy = 0.05 * j;
      if (t.obstacle_height(x + dx, y + dy) > 0.0) return false;
      const double h = t.height(x + dx, y + dy);
      lo = std::min(lo, h);
      hi = std::max(hi, h);
    }
  }
  return hi - lo < 0.04;
}

}  // namespace

DropPlace drop_place(const sim::ProceduralTerrain& terrain, double x, double y, double w, double obstacle_fraction) {
  const double x0 = std::floor(x / w) * w, y0 = std::floor(y / w) * w;
  const double step = obstacle_fraction * w;
  double deepest = 0.0;
  for (int b = 0; b < 5; ++b) {
    for (int a = 0; a < 5; ++a) {
      deepest = std::max(deepest, terrain.negative_depth(x0 + (a + 0.5) * w / 5, y0 + (b + 0.5) * w / 5));
    }
  }
  if (deepest > step) return DropPlace::kBowl;
  const double cx = x0 + 0.5 * w, cy = y0 + 0.5 * w;
  bool inside_rim = false;
  for (const sim::Crater& c : terrain.craters()) {
    inside_rim = inside_rim || std::hypot(cx - c.x, cy - c.y) < 0.5 * c.diameter_m;
  }
  if (!inside_rim) return DropPlace::kElsewhere;
  sim::HazardParams hp;
  hp.min_obstacle_height_m = step;
  hp.max_slope_deg = kMaxSlopeDeg;
  hp.sample_spacing_m = 0.01;
  const sim::HazardGrid g = sim::compute_hazard_grid(terrain, x0, y0, w, 1, 1, hp);
  return g.at(0, 0).hazard() ? DropPlace::kInnerWall : DropPlace::kElsewhere;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Team
// ---------------------------------------------------------------------------------------------

/// The three rovers' poses at frame f (see the header comment).
std::vector<Body> team_bodies(int f) {
  constexpr double kHalfPi = 1.5707963267948966;
  Body r1{8.0 + 0.15 * f, 15.0, 0.0};
  Body r2;
  if (f < 10) {
    r2 = Body{10.2, 15.0, 0.0};
  } else if (f < 18) {
    r2 = Body{10.2 + 0.15 * (f - 10), 15.0, 0.0};
  } else {
    r2 = Body{10.2 + 0.15 * 8, 15.0 + 0.3 * (f - 18), kHalfPi};
  }
  const double y3 = f < 6 ? 13.2 : std::min(13.2 + 0.12 * (f - 6), 18.0);
  Body r3{12.8, y3, kHalfPi};
  return {r1, r2, r3};
}

struct TeamRaster {
  double x0 = 0.0, y0 = 0.0, step = 0.04;
  int nx = 0, ny = 0;
  std::vector<char> free;        ///< static truth: free ground
  std::vector<int> last_occupied;  ///< last frame a rover covered the point (-1: never)
  double x(int i) const { return x0 + (i + 0.5) * step; }
  double y(int j) const { return y0 + (j + 0.5) * step; }
};

struct GhostTrack {
  std::vector<int> life;  ///< per point: the longest a ghost lived there after vacancy (-1: never a ghost)
};

void draw_class_panel(tools::RgbImage& img, int left, int top, int scale, const TeamRaster& r, const GhostMap& map,
                      const std::vector<Body>& bodies, const std::vector<std::vector<Body>>& tracks,
                      const std::string& title) {
  for (int j = 0; j < r.ny; ++j) {
    for (int i = 0; i < r.nx; ++i) {
      const QueryResult q = map.query(static_cast<float>(r.x(i)), static_cast<float>(r.y(j)));
      std::uint8_t c[3];
      tools::class_colour(q.status == Status::kOk ? to_string(q.cell_class) : "unknown", c);
      if (q.status == Status::kOutsideMap) c[0] = c[1] = c[2] = 0;
      experiments::fill_rect(img, left + i * scale, top + (r.ny - 1 - j) * scale, scale, scale, Rgb{c[0], c[1], c[2]});
    }
  }
  auto px = [&](double x) { return left + (x - r.x0) / r.step * scale; };
  auto py = [&](double y) { return top + (r.ny - (y - r.y0) / r.step) * scale; };
  for (const std::vector<Body>& track : tracks) {
    for (std::size_t k = 1; k < track.size(); ++k) {
      experiments::draw_line(img, px(track[k - 1].x), py(track[k - 1].y), px(track[k].x), py(track[k].y),
                             Rgb{255, 255, 255}, 1);
    }
  }
  for (const Body& b : bodies) {
    const double c = std::cos(b.yaw), s = std::sin(b.yaw);
    const double hl = 0.5 * kRoverLengthM, hw = 0.5 * kRoverWidthM;
    const double cx[4] = {hl, hl, -hl, -hl}, cy[4] = {hw, -hw, -hw, hw};
    for (int k = 0; k < 4; ++k) {
      const int n = (k + 1) % 4;
      experiments::draw_line(img, px(b.x + cx[k] * c - cy[k] * s), py(b.y + cx[k] * s + cy[k] * c),
                             px(b.x + cx[n] * c - cy[n] * s), py(b.y + cx[n] * s + cy[n] * c), Rgb{30, 60, 230}, 2);
    }
  }
  experiments::draw_text(img, left, top - 12, title, experiments::kBlack);
  experiments::draw_rect(img, left - 1, top - 1, r.nx * scale + 2, r.ny * scale + 2, experiments::kBlack);
}

TeamResult run_team(const GhostConfig& cfg, std::string* error) {
  TeamResult out;
  // Terrain: lunar ground, rocks cleared from the rovers' corridors (as the traverse does).
  std::vector<std::vector<sim::PathPose>> corridors(3);
  std::vector<std::vector<Body>> tracks(3);
  for (int f = 0; f < cfg.team_frames; ++f) {
    const std::vector<Body> b = team_bodies(f);
    for (int r = 0; r < 3; ++r) {
      sim::PathPose p;
      p.pose = sim::Pose2{b[static_cast<std::size_t>(r)].x, b[static_cast<std::size_t>(r)].y, b[static_cast<std::size_t>(r)].yaw};
      corridors[static_cast<std::size_t>(r)].push_back(p);
      tracks[static_cast<std::size_t>(r)].push_back(b[static_cast<std::size_t>(r)]);
    }
  }
  // Lunar ground without the traverse's placed rocks, the generated ones cleared from the
  // rovers' corridors (0.45 m, as the traverse does): rovers do not drive through rocks.
  const sim::TerrainParams params = sim::lunar_terrain_params(sim::Rect{0.0, 0.0, 30.0, 30.0}, cfg.seed);
  sim::TerrainParams no_rocks = params;
  no_rocks.rocks.density_per_m2 = 0.0;
  const sim::ProceduralTerrain generated(params);
  auto terrain = std::make_unique<sim::ProceduralTerrain>(no_rocks);
  for (const sim::Rock& rock : generated.rocks()) {
    double nearest = 1e300;
    for (const auto& corridor : corridors) {
      for (const sim::PathPose& p : corridor) nearest = std::min(nearest, std::hypot(p.pose.x - rock.x, p.pose.y - rock.y));
    }
    if (nearest - 0.5 * rock.diameter_m > 0.45) terrain->add_rock(rock);
  }
  sim::HeightRaster raster = sim::rasterize(*terrain, sim::Rect{0.0, 0.0, 30.0, 30.0}, cfg.raster_resolution_m);
  sim::StereoParams sp;
  sp.pixel_stride = cfg.pixel_stride;
  const sim::StereoCamera camera(sp);
  std::unique_ptr<GhostMap> before[3], after[3];
  for (int r = 0; r < 3; ++r) {
    before[r] = make_map(map_params(cfg, false), error);
    after[r] = make_map(map_params(cfg, true), error);
    if (!before[r] || !after[r]) return out;
  }
  // The evaluation raster: the rovers' whole playground.
  TeamRaster ras;
  ras.step = cfg.query_step_m > 0.04 ? cfg.query_step_m : 0.04;
  ras.x0 = 7.0;
  ras.y0 = 12.0;
  ras.nx = static_cast<int>(8.5 / ras.step);
  ras.ny = static_cast<int>(7.5 / ras.step);
  const std::size_t points = static_cast<std::size_t>(ras.nx) * static_cast<std::size_t>(ras.ny);
  ras.free.resize(points);
  ras.last_occupied.assign(points, -1);
  for (int j = 0; j < ras.ny; ++j) {
    for (int i = 0; i < ras.nx; ++i) {
      ras.free[static_cast<std::size_t>(j * ras.nx + i)] = free_ground(*terrain, ras.x(i), ras.y(j)) ? 1 : 0;
    }
  }
  GhostTrack life_before[3], life_after[3];
  for (int r = 0; r < 3; ++r) {
    life_before[r].life.assign(points, -1);
    life_after[r].life.assign(points, -1);
  }
  std::unique_ptr<GhostTruth> truth;
  if (cfg.ghost_truth_rays > 0) {
    std::vector<std::vector<Body>> all(static_cast<std::size_t>(cfg.team_frames));
    for (int f = 0; f < cfg.team_frames; ++f) all[static_cast<std::size_t>(f)] = team_bodies(f);
    const auto covers = [all](double x, double y, int f, std::size_t from) {
      const std::vector<Body>& b = all[static_cast<std::size_t>(f)];
      for (std::size_t k = from; k < b.size(); ++k) {
        if (inside_body(b[k], x, y, 0.05)) return true;
      }
      return false;
    };
    truth = std::make_unique<GhostTruth>(
        raster, double{map_params(cfg, true).obstacle_fraction}, cfg.ghost_truth_rays,
        [&terrain](double cx, double cy, double w) { return rock_in_square(*terrain, cx, cy, w); },
        [covers](double x, double y, int f) { return covers(x, y, f, 1); },
        [covers](double x, double y, int f) { return covers(x, y, f, 0); });
  }
  // Every place a rover ever covered (to judge emptied cells), grown by 10 cm.
  auto ever_rover = [&](double cx, double cy, double w, int upto) {
    for (int f = 0; f <= upto; ++f) {
      for (const Body& b : team_bodies(f)) {
        for (double dx : {-0.5 * w, 0.0, 0.5 * w}) {
          for (double dy : {-0.5 * w, 0.0, 0.5 * w}) {
            if (inside_body(b, cx + dx, cy + dy, 0.1)) return true;
          }
        }
      }
    }
    return false;
  };
  for (int f = 0; f < cfg.team_frames; ++f) {
    const std::vector<Body> bodies = team_bodies(f);
    for (int r = 0; r < 3; ++r) {
      std::vector<Body> others;
      for (int o = 0; o < 3; ++o) {
        if (o != r) others.push_back(bodies[static_cast<std::size_t>(o)]);
      }
      CameraFrame frame;
      std::vector<SightLine> truth_lines;
      {
        const BodyStamp stamp(raster, others);
        frame = capture(camera, raster, bodies[static_cast<std::size_t>(r)], cfg.seed * 1000003ULL + static_cast<std::uint64_t>(f * 3 + r));
        if (truth && r == 0) {
          const Body& b = bodies[0];
          truth_lines = sight_lines(camera, camera.render_depth(raster, sim::Pose2{b.x, b.y, b.yaw}),
                                    camera.camera_position(raster, sim::Pose2{b.x, b.y, b.yaw}), b.yaw);
        }
      }
      for (GhostMap* m : {before[r].get(), after[r].get()}) {
        if (m->move_to(static_cast<float>(frame.x), static_cast<float>(frame.y)) != Status::kOk) {
          *error = "move refused";
          return out;
        }
        const std::vector<float> w = cell_weights(*m);
        const bool judged = truth && m == after[0].get();
        if (judged) truth->before_update(f, map_cells(*m), truth_lines, frame.x, frame.y);
        FrameCounters c{};
        if (m->update_frame_sensor(frame.points.data(), frame.points.size(), frame.pose, &c) != Status::kOk) {
          *error = "frame refused";
          return out;
        }
        if (judged) truth->after_update(f, map_cells(*m));
        GhostStats& st = m == before[r].get() ? out.before[r] : out.after[r];
        if (m == after[r].get()) {
          out.rays += c.free_rays;
          out.refused += c.free_rays_refused;
          out.drops_after += c.drop_cells;
        }
        for_each_emptied(*m, w, [&](int, double cx, double cy, double cw) {
          ++st.cleared_cells;
          if (ever_rover(cx, cy, cw, f)) {
            ++st.cleared_ghost;
          } else if (rock_in_square(*terrain, cx, cy, cw)) {
            ++st.lost_rock;
          } else {
            ++st.lost_ground;
          }
        });
      }
    }
    // Occupancy after this frame's poses, then the ghosts of every map.
    for (int j = 0; j < ras.ny; ++j) {
      for (int i = 0; i < ras.nx; ++i) {
        for (const Body& b : bodies) {
          if (inside_body(b, ras.x(i), ras.y(j), 0.05)) ras.last_occupied[static_cast<std::size_t>(j * ras.nx + i)] = f;
        }
      }
    }
    for (int r = 0; r < 3; ++r) {
      for (int pass = 0; pass < 2; ++pass) {
        const GhostMap& m = pass == 0 ? *before[r] : *after[r];
        GhostStats& st = pass == 0 ? out.before[r] : out.after[r];
        GhostTrack& tr = pass == 0 ? life_before[r] : life_after[r];
        double area = 0.0;
        for (int j = 0; j < ras.ny; ++j) {
          for (int i = 0; i < ras.nx; ++i) {
            const std::size_t k = static_cast<std::size_t>(j * ras.nx + i);
            const int last = ras.last_occupied[k];
            if (last < 0 || last == f || ras.free[k] == 0) continue;
            bool near_now = false;
            for (const Body& b : bodies) near_now = near_now || inside_body(b, ras.x(i), ras.y(j), 0.1);
            if (near_now) continue;
            const QueryResult q = m.query(static_cast<float>(ras.x(i)), static_cast<float>(ras.y(j)));
            if (q.status != Status::kOk || !is_hazard(q.cell_class)) continue;
            area += ras.step * ras.step;
            tr.life[k] = std::max(tr.life[k], f - last);
            if (f == cfg.team_frames - 1) ++st.still_at_end;
          }
        }
        st.area_per_frame.push_back(area);
        st.peak_area_m2 = std::max(st.peak_area_m2, area);
        st.area_frames_m2 += area;
        st.end_area_m2 = area;
      }
    }
    if (cfg.log != nullptr) {
      std::fprintf(cfg.log, "team frame %d: ghost area rover 1 %.3f m^2 (before) %.3f (after)\n", f,
                   out.before[0].area_per_frame.back(), out.after[0].area_per_frame.back());
    }
  }
  if (truth) out.truth = truth->result();
  for (int r = 0; r < 3; ++r) {
    for (int pass = 0; pass < 2; ++pass) {
      GhostStats& st = pass == 0 ? out.before[r] : out.after[r];
      const GhostTrack& tr = pass == 0 ? life_before[r] : life_after[r];
      double sum = 0.0;
      for (const int l : tr.life) {
        if (l < 0) continue;
        ++st.points_ever;
        sum += l;
        st.max_life_frames = std::max(st.max_life_frames, l);
      }
      st.mean_life_frames = st.points_ever > 0 ? sum / st.points_ever : 0.0;
    }
  }
  const double obstacle_fraction = double{map_params(cfg, true).obstacle_fraction};
  for (int j = 0; j < ras.ny; ++j) {
    for (int i = 0; i < ras.nx; ++i) {
      const QueryResult q = after[0]->query(static_cast<float>(ras.x(i)), static_cast<float>(ras.y(j)));
      if (q.cell_class != CellClass::kDropOff) continue;
      switch (drop_place(*terrain, ras.x(i), ras.y(j), double{q.cell_width_m}, obstacle_fraction)) {
        case DropPlace::kBowl:
          ++out.drop_points_true;
          break;
        case DropPlace::kInnerWall:
          ++out.drop_points_false;
          ++out.drop_points_wall;
          break;
        case DropPlace::kElsewhere:
          ++out.drop_points_false;
          ++out.drop_points_elsewhere;
          break;
      }
    }
  }
  if (!cfg.out_dir.empty()) {
    const int scale = 3;
    const int panel_w = ras.nx * scale, panel_h = ras.ny * scale;
    tools::RgbImage img(2 * panel_w + 60, panel_h + 60, 255);
    const std::vector<Body> final_bodies = team_bodies(cfg.team_frames - 1);
    draw_class_panel(img, 20, 30, scale, ras, *before[0], final_bodies, tracks,
                     format("ROVER 1 MAP, FRAME %d, WITHOUT FREE SPACE", cfg.team_frames - 1));
    draw_class_panel(img, 40 + panel_w, 30, scale, ras, *after[0], final_bodies, tracks,
                     "WITH FREE SPACE (" + rays_description(cfg) + " PER FRAME)");
    int x = 20;
    for (const char* c : {"traversable", "obstacle", "steep", "drop", "unknown"}) {
      std::uint8_t v[3];
      tools::class_colour(c, v);
      x = experiments::legend_entry(img, x, panel_h + 42, Rgb{v[0], v[1], v[2]}, c);
    }
    experiments::legend_entry(img, x, panel_h + 42, Rgb{30, 60, 230}, "rovers now (white: their tracks)");
    const std::string path = cfg.out_dir + "/ghosts_team.png";
    std::string err;
    if (tools::write_png(path, img, &err)) out.pictures.push_back(path);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// Drop-offs
// ---------------------------------------------------------------------------------------------

std::unique_ptr<sim::ProceduralTerrain> flat_corridor_terrain(std::uint64_t seed, bool craters, double corridor_y0,
                                                             double corridor_y1) {
  const sim::Rect area{0.0, 0.0, 30.0, 30.0};
  sim::TerrainParams p = sim::lunar_terrain_params(area, seed);
  if (!craters) p.craters.count = 0;
  sim::TerrainParams no_rocks = p;
  no_rocks.rocks.density_per_m2 = 0.0;
  const sim::ProceduralTerrain generated(p);
  auto t = std::make_unique<sim::ProceduralTerrain>(no_rocks);
  for (const sim::Rock& r : generated.rocks()) {
    if (r.y + 0.5 * r.diameter_m < corridor_y0 || r.y - 0.5 * r.diameter_m > corridor_y1) t->add_rock(r);
  }
  return t;
}

void run_drop_case(const GhostConfig& cfg, DropCase* dc, bool crater, double width_m, std::vector<std::string>* pictures,
                   std::string* error) {
  auto terrain = flat_corridor_terrain(cfg.seed, false, 13.0, 17.0);
  const double y = 15.0;
  if (crater) {
    const double d = 2.0;
    terrain->add_crater(sim::Crater{dc->rim_x + 0.5 * d, y, d, dc->depth_m, 0.02 * d});
  } else {
    terrain->add_ditch(sim::Ditch{dc->rim_x, 12.0, dc->rim_x + width_m, 18.0, dc->depth_m});
  }
  const sim::HeightRaster raster = sim::rasterize(*terrain, sim::Rect{0.0, 0.0, 30.0, 30.0}, cfg.raster_resolution_m);
  sim::StereoParams sp;
  sp.pixel_stride = cfg.pixel_stride;
  const sim::StereoCamera camera(sp);
  std::unique_ptr<GhostMap> maps[2] = {make_map(map_params(cfg, false), error), make_map(map_params(cfg, true), error)};
  if (!maps[0] || !maps[1]) return;
  // The team mates: never a frame of their own, the AFTER rover's delta after every frame.
  using GhostExchange = MapExchange<WithEveryLineOfSight<CadreConfig>>;
  auto sender = std::make_unique<GhostExchange>();
  std::unique_ptr<GhostMap> mates[3];
  std::unique_ptr<GhostExchange> mate_exchanges[3];
  if (sender->init(*maps[1], ExchangeParams{1U, 1U, CellIndex{0, 0}, 0.0F}) != Status::kOk) {
    *error = "drop-off case: the exchange refused the map";
    return;
  }
  for (int t = 0; t < 3; ++t) {
    mates[t] = make_map(map_params(cfg, true), error);
    mate_exchanges[t] = std::make_unique<GhostExchange>();
    if (!mates[t] || mate_exchanges[t]->init(*mates[t], ExchangeParams{static_cast<std::uint32_t>(t) + 2U, 1U,
                                                                          CellIndex{0, 0}, 0.0F}) != Status::kOk) {
      *error = "drop-off case: a team mate's map or exchange refused";
      return;
    }
  }
  std::vector<std::uint8_t> delta(GhostExchange::max_delta_size());
  auto drop_in_swath = [&](const GhostMap& m) {
    for (double qx = dc->rim_x; qx <= dc->rim_x + (crater ? 2.0 : width_m); qx += 0.02) {
      for (double qy = 14.7; qy <= 15.3; qy += 0.02) {
        if (m.query(static_cast<float>(qx), static_cast<float>(qy)).cell_class == CellClass::kDropOff) return true;
      }
    }
    return false;
  };
  const double far_edge = crater ? dc->rim_x + 2.0 : dc->rim_x + width_m;
  std::unique_ptr<DropoffTruth> truth;  // --dropoff-truth: the swath from 0.5 m before the rim to 0.5 m beyond
  if (cfg.dropoff_truth) truth = make_swath_truth(*maps[1], dc->rim_x - 0.5, far_edge + 0.5, y);
  int picture_frame = -1;
  for (int f = 0;; ++f) {
    const double x = dc->rim_x - 4.0 + 0.1 * f;
    const double range = dc->rim_x - x;
    if (range < 0.2) break;
    sim::StereoFrame raw;
    const CameraFrame frame =
        capture(camera, raster, Body{x, y, 0.0}, cfg.seed * 7919ULL + static_cast<std::uint64_t>(f), truth ? &raw : nullptr);
    for (int k = 0; k < 2; ++k) {
      GhostMap& m = *maps[k];
      if (m.move_to(static_cast<float>(x), static_cast<float>(y)) != Status::kOk ||
          m.update_frame_sensor(frame.points.data(), frame.points.size(), frame.pose, nullptr) != Status::kOk) {
        *error = "drop-off case: a frame was refused";
        return;
      }
      if (dc->first_drop_range_m[k] < 0.0) {
        bool drop = false;
        for (double qx = dc->rim_x; qx <= far_edge && !drop; qx += 0.02) {
          for (double qy = y - 0.3; qy <= y + 0.3 && !drop; qy += 0.02) {
            drop = m.query(static_cast<float>(qx), static_cast<float>(qy)).cell_class == CellClass::kDropOff;
          }
        }
        if (drop) {
          dc->first_drop_range_m[k] = range;
          if (k == 1) picture_frame = f;
        }
      }
      const float start = static_cast<float>(x + 0.5 * kRoverLengthM);
      const PathPoint route[2] = {{start, static_cast<float>(y)}, {start + 1.5F, static_cast<float>(y)}};
      const PathResult p = query_path(m, route, 2, PathSweep{static_cast<float>(kRoverLengthM),
                                                             static_cast<float>(kRoverWidthM), 0.05F, 0.1F});
      if (p.status == Status::kOk && p.hazard_found) {
        const double front = start + p.first_hazard_m + 0.5 * kRoverLengthM - dc->rim_x;
        if (dc->first_hazard_range_m[k] < 0.0) {
          dc->first_hazard_range_m[k] = range;
          dc->hazard_at_m[k] = front;
          dc->hazard_class[k] = to_string(p.hazard.worst_class);
        }
        if (dc->rim_hazard_range_m[k] < 0.0 && front <= 0.1) {
          dc->rim_hazard_range_m[k] = range;
          dc->rim_hazard_class[k] = to_string(p.hazard.worst_class);
        }
      }
      if (p.status == Status::kOk && p.unknown_found && dc->first_unknown_range_m[k] < 0.0) {
        dc->first_unknown_range_m[k] = range;
      }
    }
    if (truth) {
      add_frame(*truth, camera, raw, raster, dc->rim_x, 3.0,
                [&](double r) { return double{maps[1]->params().noise.sigma_at_range(static_cast<float>(r))}; });
      dc->truth.push_back(evaluate_drops(*truth, *maps[1], range, raster, dc->rim_x));
      if (cfg.log != nullptr) log_truth_row(cfg.log, dc->name, dc->truth.back());
    }
    std::size_t written = 0;
    ExportReport sent{};
    if (sender->export_delta(delta.data(), delta.size(), ExportOptions{0.0F, 0}, &written, &sent) != Status::kOk) {
      *error = "drop-off case: export failed";
      return;
    }
    dc->drops_sent += sent.drops_written;
    for (int t = 0; t < 3; ++t) {
      if (mates[t]->move_to(static_cast<float>(dc->rim_x - kTeamMateRangeM[t]), static_cast<float>(y)) != Status::kOk ||
          mate_exchanges[t]->merge_delta(delta.data(), written, nullptr) != Status::kOk) {
        *error = "drop-off case: a team mate refused the delta";
        return;
      }
      if (dc->team_drop_range_m[t] < 0.0 && drop_in_swath(*mates[t])) {
        dc->team_drop_range_m[t] = range;
      }
    }
    if (f == picture_frame && !cfg.out_dir.empty()) {
      TeamRaster ras;
      ras.step = 0.02;
      ras.x0 = x - 0.5;
      ras.y0 = y - 1.5;
      ras.nx = static_cast<int>((far_edge + 0.6 - ras.x0) / ras.step);
      ras.ny = static_cast<int>(3.0 / ras.step);
      const int scale = 2;
      tools::RgbImage img(2 * ras.nx * scale + 60, ras.ny * scale + 60, 255);
      const std::vector<Body> rover{Body{x, y, 0.0}};
      draw_class_panel(img, 20, 30, scale, ras, *maps[0], rover, {}, format("%s: WITHOUT FREE SPACE, RIM %.1f M AHEAD", dc->name.c_str(), range));
      draw_class_panel(img, 40 + ras.nx * scale, 30, scale, ras, *maps[1], rover, {}, "WITH FREE SPACE");
      int lx = 20;
      for (const char* c : {"traversable", "obstacle", "steep", "drop", "unknown"}) {
        std::uint8_t v[3];
        tools::class_colour(c, v);
        lx = experiments::legend_entry(img, lx, ras.ny * scale + 42, Rgb{v[0], v[1], v[2]}, c);
      }
      std::string name = dc->name;
      std::replace(name.begin(), name.end(), ' ', '_');
      const std::string path = cfg.out_dir + "/dropoff_" + name + ".png";
      std::string err;
      if (tools::write_png(path, img, &err)) pictures->push_back(path);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Shadows
// ---------------------------------------------------------------------------------------------

ShadowResult run_shadows(const GhostConfig& cfg, std::string* error) {
  ShadowResult out;
  auto terrain = flat_corridor_terrain(cfg.seed, false, 14.55, 15.45);
  // Rocks that cast long shadows beside the drive (x, y, diameter, height).
  const sim::Rock placed[] = {{9.0, 15.9, 0.30, 0.15}, {10.5, 14.0, 0.25, 0.12}, {11.5, 16.2, 0.40, 0.20},
                              {12.6, 13.7, 0.20, 0.10}, {13.5, 15.8, 0.35, 0.18}, {14.8, 14.2, 0.5, 0.25}};
  for (const sim::Rock& r : placed) terrain->add_rock(r);
  const sim::HeightRaster raster = sim::rasterize(*terrain, sim::Rect{0.0, 0.0, 30.0, 30.0}, cfg.raster_resolution_m);
  sim::StereoParams sp;
  sp.pixel_stride = cfg.pixel_stride;
  const sim::StereoCamera camera(sp);
  std::unique_ptr<GhostMap> maps[2] = {make_map(map_params(cfg, false), error), make_map(map_params(cfg, true), error)};
  if (!maps[0] || !maps[1]) return out;
  const double y = 15.0;
  double last_x = 6.0;
  for (int f = 0; f <= 26; ++f) {
    const double x = 6.0 + 0.3 * f;
    last_x = x;
    const CameraFrame frame = capture(camera, raster, Body{x, y, 0.0}, cfg.seed * 104729ULL + static_cast<std::uint64_t>(f));
    for (auto& m : maps) {
      if (m->move_to(static_cast<float>(x), static_cast<float>(y)) != Status::kOk ||
          m->update_frame_sensor(frame.points.data(), frame.points.size(), frame.pose, nullptr) != Status::kOk) {
        *error = "shadows: a frame was refused";
        return out;
      }
    }
  }
  std::vector<const sim::Rock*> tall;
  for (const sim::Rock& r : terrain->rocks()) {
    if (r.height_m >= 0.08) tall.push_back(&r);
  }
  out.rocks = static_cast<int>(tall.size());
  const double step = 0.04;
  const double a = step * step;
  for (double qx = last_x - 9.0; qx <= last_x + 9.0; qx += step) {
    for (double qy = y - 9.0; qy <= y + 9.0; qy += step) {
      bool near = false;
      for (const sim::Rock* r : tall) near = near || std::hypot(qx - r->x, qy - r->y) < 0.5 * r->diameter_m + 1.2;
      const QueryResult q0 = maps[0]->query(static_cast<float>(qx), static_cast<float>(qy));
      const QueryResult q1 = maps[1]->query(static_cast<float>(qx), static_cast<float>(qy));
      if (q0.status == Status::kOutsideMap) continue;
      (near ? out.area_near_rocks_m2 : out.area_open_m2) += a;
      if (q0.status != Status::kOk) (near ? out.unknown_near_rocks_m2 : out.unknown_open_m2) += a;
      if (q0.cell_class == CellClass::kDropOff) (near ? out.drop_near_rocks_m2[0] : out.drop_open_m2[0]) += a;
      if (q1.cell_class == CellClass::kDropOff) (near ? out.drop_near_rocks_m2[1] : out.drop_open_m2[1]) += a;
    }
  }
  return out;
}

std::string range_text(double r) { return r < 0.0 ? "never" : format("%.1f m", r); }

}  // namespace

GhostResult run_ghosts(const GhostConfig& config) {
  GhostResult r;
  if (!config.out_dir.empty() && !experiments::ensure_directory(config.out_dir, &r.error)) return r;
  r.team = run_team(config, &r.error);
  if (!r.ok()) return r;
  for (const std::string& p : r.team.pictures) r.pictures.push_back(p);
  struct Spec {
    const char* name;
    bool crater;
    double depth, width;
  };
  const Spec specs[] = {{"ditch 30 cm deep", false, 0.30, 0.6}, {"ditch 15 cm deep", false, 0.15, 0.6},
                        {"crater 2 m", true, 0.24, 2.0}};
  for (const Spec& s : specs) {
    DropCase dc;
    dc.name = s.name;
    dc.rim_x = 12.0;
    dc.depth_m = s.depth;
    run_drop_case(config, &dc, s.crater, s.width, &r.pictures, &r.error);
    if (!r.ok()) return r;
    r.drops.push_back(dc);
  }
  r.shadows = run_shadows(config, &r.error);
  return r;
}

std::string ghost_report(const GhostResult& r, const GhostConfig& c) {
  std::string s;
  s += "AFTER: " + rays_description(c) + " per frame\n\n";
  s += format("Team of three rovers, %d frames, pixel stride %d: ghosts (map obstacle or steep where a rover stood,\n"
              "no rover stands and the ground is free), per rover's map\n\n",
              c.team_frames, c.pixel_stride);
  experiments::Table t({"rover", "map", "peak m^2", "end m^2", "m^2 x frames", "points", "life mean", "life max",
                        "cleared", "of ghosts", "ground lost", "rock lost"});
  for (int k = 0; k < 3; ++k) {
    for (int pass = 0; pass < 2; ++pass) {
      const GhostStats& g = pass == 0 ? r.team.before[k] : r.team.after[k];
      t.add_row({format("%d", k + 1), pass == 0 ? "before" : "after", format("%.3f", g.peak_area_m2),
                 format("%.3f", g.end_area_m2), format("%.2f", g.area_frames_m2), format("%d", g.points_ever),
                 format("%.1f", g.mean_life_frames), format("%d", g.max_life_frames),
                 format("%llu", static_cast<unsigned long long>(g.cleared_cells)),
                 format("%llu", static_cast<unsigned long long>(g.cleared_ghost)),
                 format("%llu", static_cast<unsigned long long>(g.lost_ground)),
                 format("%llu", static_cast<unsigned long long>(g.lost_rock))});
    }
  }
  s += t.str();
  s += format("\nlines of sight walked %llu, refused %llu; drop-offs marked %llu; rover 1's final map: %d drop-off\n"
              "points (of the %.2f m raster) in cells holding a crater bowl deeper than the cell's obstacle height, %d not:\n"
              "%d on a crater's inner wall within its rim (a hazard in the terrain's truth: steeper than %.0f deg or a\n"
              "step of relief), %d elsewhere\n\n",
              static_cast<unsigned long long>(r.team.rays), static_cast<unsigned long long>(r.team.refused),
              static_cast<unsigned long long>(r.team.drops_after), r.team.drop_points_true,
              c.query_step_m > 0.04 ? c.query_step_m : 0.04, r.team.drop_points_false, r.team.drop_points_wall,
              kMaxSlopeDeg, r.team.drop_points_elsewhere);
  s += format("Negative obstacles approached at 0.1 m per frame (range: camera to the near rim; stopping distance %.1f m)\n\n",
              kStoppingDistanceM);
  experiments::Table d({"obstacle", "map", "drop-off in swath at", "first path hazard at", "its front", "class",
                        "hazard at the rim at", "class"});
  for (const DropCase& dc : r.drops) {
    for (int k = 0; k < 2; ++k) {
      d.add_row({dc.name, k == 0 ? "before" : "after", range_text(dc.first_drop_range_m[k]),
                 range_text(dc.first_hazard_range_m[k]),
                 dc.first_hazard_range_m[k] < 0.0 ? "-" : format("rim %+.2f m", dc.hazard_at_m[k]),
                 dc.hazard_class[k], range_text(dc.rim_hazard_range_m[k]), dc.rim_hazard_class[k]});
    }
  }
  s += d.str();
  s += "\nThe same drop-offs at team mates that never look at them (map exchange: the AFTER rover's delta after\n"
       "every frame; each mate parked on the rover's line at a range from the near rim): the rover's range to the\n"
       "rim when the mate's stack query first answers drop-off in the swath\n\n";
  experiments::Table m({"obstacle", "drop-off entries sent", "mate 1 m from the rim", "2 m", "4 m"});
  for (const DropCase& dc : r.drops) {
    m.add_row({dc.name, format("%llu", static_cast<unsigned long long>(dc.drops_sent)), range_text(dc.team_drop_range_m[0]),
               range_text(dc.team_drop_range_m[1]), range_text(dc.team_drop_range_m[2])});
  }
  s += m.str();
  if (c.dropoff_truth) s += drop_truth_report(r.drops);
  const ShadowResult& sh = r.shadows;
  s += format("\nFalse drop-offs over 8 m of lunar ground with %d rocks of 8 cm or more (no negative obstacle)\n\n",
              sh.rocks);
  experiments::Table f({"area", "queried m^2", "unknown m^2", "drop before m^2", "drop after m^2", "share after"});
  f.add_row({"within 1.2 m of a rock", format("%.2f", sh.area_near_rocks_m2), format("%.2f", sh.unknown_near_rocks_m2),
             format("%.3f", sh.drop_near_rocks_m2[0]), format("%.3f", sh.drop_near_rocks_m2[1]),
             format("%.3f %%", sh.area_near_rocks_m2 > 0.0 ? 100.0 * sh.drop_near_rocks_m2[1] / sh.area_near_rocks_m2 : 0.0)});
  f.add_row({"open ground", format("%.2f", sh.area_open_m2), format("%.2f", sh.unknown_open_m2),
             format("%.3f", sh.drop_open_m2[0]), format("%.3f", sh.drop_open_m2[1]),
             format("%.3f %%", sh.area_open_m2 > 0.0 ? 100.0 * sh.drop_open_m2[1] / sh.area_open_m2 : 0.0)});
  s += f.str();
  if (!r.pictures.empty()) {
    s += "\npictures:";
    for (const std::string& p : r.pictures) s += " " + p;
    s += "\n";
  }
  return s;
}

}  // namespace ccmap::traverse
