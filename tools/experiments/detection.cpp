#include "experiments/detection.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <unordered_map>

#include "ccmap/map/stack.hpp"
#include "ccmap/sensor/noise_model.hpp"
#include "experiments/common.hpp"
#include "experiments/svg_plot.hpp"
#include "sim/hazard.hpp"
#include "sim/path.hpp"
#include "sim/rng.hpp"

namespace ccmap::experiments {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kMaxSlopeDeg = 20.0;

/// Sizes and widths are matched in micrometres (exact integers for keys and CSV rows).
std::int64_t to_um(double metres) { return static_cast<std::int64_t>(std::llround(metres * 1e6)); }

bool same_ratio(double a, double b) { return std::fabs(a - b) < 1e-6; }

/// Share of the square [x0, x0 + w) x [y0, y0 + w) inside the rectangle r.
double rect_coverage(const sim::Rect& r, double x0, double y0, double w) {
  const double ox = std::max(0.0, std::min(r.x1, x0 + w) - std::max(r.x0, x0));
  const double oy = std::max(0.0, std::min(r.y1, y0 + w) - std::max(r.y0, y0));
  return ox * oy / (w * w);
}

/// The two single-layer maps of one resolution (heap: a few MB each). CcmConfig: SingleCcmConfig
/// (full cells) or PaperCell<SingleCcmConfig>.
template <typename CcmConfig>
struct MapPair {
  double width_m = 0.0;
  GateSetting gate;
  std::unique_ptr<Stack<CcmConfig>> ccm = std::make_unique<Stack<CcmConfig>>();
  std::unique_ptr<Stack<SingleOmgConfig>> omg = std::make_unique<Stack<SingleOmgConfig>>();
  bool reset() {
    StackParams params = default_stack_params(static_cast<float>(width_m));
    gate.apply(&params);
    return ccm->init(params) == Status::kOk && omg->init(params) == Status::kOk;
  }
};

bool is_hazard(CellClass c) { return c == CellClass::kObstacle || c == CellClass::kSteep; }

template <typename StackT>
CellClass class_at(const StackT& stack, std::int32_t i, std::int32_t j, float w) {
  const QueryResult q = stack.query_layer(0, grid::cell_centre(i, w), grid::cell_centre(j, w));
  return q.status == Status::kOk ? q.cell_class : CellClass::kUnknown;
}

/// Ground truth of one seed at one resolution: the steep flag of the ground plane per cell
/// (cached: the terrain is the same for every size of the seed).
class SteepCache {
 public:
  SteepCache(const sim::Terrain* ground, double w) : ground_(ground), w_(w) {}
  bool steep(std::int32_t i, std::int32_t j) {
    const std::int64_t key = (static_cast<std::int64_t>(i) << 32) ^ static_cast<std::int64_t>(static_cast<std::uint32_t>(j));
    const auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;
    sim::HazardParams hp;
    hp.min_obstacle_height_m = 1e9;  // obstacles come from the footprint, not from relief
    hp.max_slope_deg = kMaxSlopeDeg;
    const sim::Rect cell{i * w_, j * w_, (i + 1) * w_, (j + 1) * w_};
    const bool s = sim::evaluate_cell_hazard(*ground_, cell, hp).steep;
    cache_.emplace(key, s);
    return s;
  }

 private:
  const sim::Terrain* ground_;
  double w_;
  std::unordered_map<std::int64_t, bool> cache_;
};

/// CCM class with the obstacle test before the coverage test (DetectionMethod::kCcmObstacleFirst).
template <typename CcmConfig>
CellClass obstacle_first_class(const Stack<CcmConfig>& stack, std::int32_t i, std::int32_t j, float w) {
  const auto c = stack.pooled_cell(0, CellIndex{i, j});
  if (c.weight >= stack.params().min_weight && c.weight > 0.0F &&
      ccm_surface(c).normal_variance > stack.normal_variance_threshold(0)) {
    return CellClass::kObstacle;
  }
  return class_at(stack, i, j, w);
}

/// Classifies the cells one frame observes and tallies them (see detection.hpp).
template <typename CcmConfig>
void tally_frame(const MapPair<CcmConfig>& maps, const sim::StereoParams& sp, const sim::Point3& camera, double yaw,
                 const sim::HeightRaster& ground_raster, const sim::Rect& box, double min_coverage, SteepCache& steep,
                 DetectionCounts* counts /* [3], by DetectionMethod */) {
  const double w = maps.width_m;
  const float wf = static_cast<float>(w);
  const double range = ivg_max_range_m(w);
  const double half_fov = 0.5 * sp.width_px / sp.focal_px;
  const double reach = range * std::sqrt(1.0 + half_fov * half_fov);
  const auto i0 = static_cast<std::int32_t>(std::floor((camera.x - reach) / w));
  const auto i1 = static_cast<std::int32_t>(std::floor((camera.x + reach) / w));
  const auto j0 = static_cast<std::int32_t>(std::floor((camera.y - reach) / w));
  const auto j1 = static_cast<std::int32_t>(std::floor((camera.y + reach) / w));
  auto coverage = [&](std::int32_t i, std::int32_t j) { return rect_coverage(box, i * w, j * w, w); };
  for (std::int32_t j = j0; j <= j1; ++j) {
    for (std::int32_t i = i0; i <= i1; ++i) {
      if (!whole_cell_in_view(sp, camera, yaw, ground_raster, i * w, j * w, w, range)) continue;
      const double c = coverage(i, j);
      const bool partial = c > 0.0 && (c < min_coverage || c >= 1.0 - 1e-12);
      const bool truth_hazard = (c >= min_coverage && c < 1.0 - 1e-12) || steep.steep(i, j);
      bool adjacent = false;
      if (!truth_hazard && !partial) {
        for (int dj = -1; dj <= 1 && !adjacent; ++dj)
          for (int di = -1; di <= 1 && !adjacent; ++di) adjacent = (di != 0 || dj != 0) && coverage(i + di, j + dj) > 0.0;
      }
      const CellClass classes[3] = {class_at(*maps.ccm, i, j, wf), obstacle_first_class(*maps.ccm, i, j, wf),
                                    class_at(*maps.omg, i, j, wf)};
      for (int m = 0; m < 3; ++m) {
        DetectionCounts& t = counts[m];
        if (classes[m] == CellClass::kUnknown) {
          ++t.unknown;
          if (truth_hazard) ++t.unknown_obstacle;
        } else if (partial && !truth_hazard) {
          ++t.excluded;
        } else if (truth_hazard) {
          if (is_hazard(classes[m])) {
            ++t.correct;
            ++t.hit;
          } else {
            ++t.missed;
          }
        } else if (is_hazard(classes[m])) {
          ++(adjacent ? t.fn_adjacent : t.fn_far);
        } else {
          ++t.correct;
        }
      }
    }
  }
}

/// Whether a cell holding part of the box (c > 0) is marked hazard by `method`.
template <typename CcmConfig>
bool obstacle_marked(const MapPair<CcmConfig>& maps, DetectionMethod method, const sim::Rect& box) {
  const double w = maps.width_m;
  const float wf = static_cast<float>(w);
  const auto i0 = static_cast<std::int32_t>(std::floor(box.x0 / w)), i1 = static_cast<std::int32_t>(std::floor(box.x1 / w));
  const auto j0 = static_cast<std::int32_t>(std::floor(box.y0 / w)), j1 = static_cast<std::int32_t>(std::floor(box.y1 / w));
  for (std::int32_t j = j0; j <= j1; ++j)
    for (std::int32_t i = i0; i <= i1; ++i) {
      if (!(rect_coverage(box, i * w, j * w, w) > 0.0)) continue;
      const CellClass c = method == DetectionMethod::kCcm ? class_at(*maps.ccm, i, j, wf)
                          : method == DetectionMethod::kOmg ? class_at(*maps.omg, i, j, wf)
                                                            : obstacle_first_class(*maps.ccm, i, j, wf);
      if (is_hazard(c)) return true;
    }
  return false;
}

std::string ratio_label(double r) { return format("%.2f", r); }

}  // namespace

// ---------------------------------------------------------------------------------------------

const char* detection_method_name(DetectionMethod method) {
  switch (method) {
    case DetectionMethod::kCcm: return "CCM";
    case DetectionMethod::kCcmObstacleFirst: return "CCM-OF";
    case DetectionMethod::kOmg: return "OMG";
  }
  return "?";
}

DetectionCounts& DetectionCounts::operator+=(const DetectionCounts& o) {
  trials += o.trials;
  detected += o.detected;
  correct += o.correct;
  hit += o.hit;
  missed += o.missed;
  fn_adjacent += o.fn_adjacent;
  fn_far += o.fn_far;
  unknown += o.unknown;
  unknown_obstacle += o.unknown_obstacle;
  excluded += o.excluded;
  return *this;
}

bool DetectionCounts::operator==(const DetectionCounts& o) const {
  return trials == o.trials && detected == o.detected && correct == o.correct && hit == o.hit && missed == o.missed &&
         fn_adjacent == o.fn_adjacent && fn_far == o.fn_far && unknown == o.unknown &&
         unknown_obstacle == o.unknown_obstacle && excluded == o.excluded;
}

double DetectionRow::missed_share() const {
  const double known = static_cast<double>(counts.hit + counts.missed);
  return known > 0.0 ? static_cast<double>(counts.missed) / known : kNaN;
}

double DetectionRow::obstacle_unknown_share() const {
  const double observed = static_cast<double>(counts.hit + counts.missed + counts.unknown_obstacle);
  return observed > 0.0 ? static_cast<double>(counts.unknown_obstacle) / observed : kNaN;
}

double DetectionRow::false_obstacle_ratio() const {
  const double known = static_cast<double>(counts.hit + counts.missed);
  return known > 0.0 ? static_cast<double>(counts.fn_adjacent + counts.fn_far) / known : kNaN;
}

double DetectionRow::detection_rate() const {
  return counts.trials > 0 ? static_cast<double>(counts.detected) / static_cast<double>(counts.trials) : kNaN;
}

const DetectionRow* DetectionResult::find(DetectionMethod method, double w, double ratio) const {
  for (const DetectionRow& r : rows)
    if (r.method == method && to_um(r.cell_width_m) == to_um(w) && same_ratio(r.size_ratio, ratio)) return &r;
  return nullptr;
}

DetectionRow* DetectionResult::find(DetectionMethod method, double w, double ratio) {
  const DetectionResult& self = *this;
  return const_cast<DetectionRow*>(self.find(method, w, ratio));
}

sim::StereoParams detection_stereo_params(int pixel_stride, double max_depth_m, double streak_probability) {
  sim::StereoParams sp;  // CADRE defaults: 850 x 650 px, f 600 px, b 5 cm, 17.5 cm high
  sp.pixel_stride = pixel_stride;
  sp.max_depth_m = max_depth_m;
  sp.border_streak_probability = streak_probability;
  return sp;
}

double ivg_max_range_m(double cell_width_m) {
  const double k = sensor::cadre_stereo().stereo_sigma_per_range_sq();
  return std::sqrt(cell_width_m / (sensor::kIvgCellWidthPerSigma * k));
}

bool cell_in_view(const sim::StereoParams& sp, const sim::Point3& camera, double yaw, double x, double y,
                  double z_ground, double max_range_m) {
  const double px = x - camera.x, py = y - camera.y, pz = z_ground - camera.z;
  if (px * px + py * py + pz * pz > max_range_m * max_range_m) return false;
  // Optical frame of sim::StereoCamera (x right, y down, z forward, pitched down).
  const double pitch = sp.pitch_deg * sim::kPi / 180.0;
  const double cp = std::cos(pitch), spt = std::sin(pitch), cy = std::cos(yaw), sy = std::sin(yaw);
  const double zc = px * cp * cy + py * cp * sy - pz * spt;
  if (!(zc > 0.0)) return false;
  const double xc = px * sy - py * cy;
  const double yc = -px * spt * cy - py * spt * sy - pz * cp;
  return std::fabs(xc) <= zc * 0.5 * sp.width_px / sp.focal_px && std::fabs(yc) <= zc * 0.5 * sp.height_px / sp.focal_px;
}

bool whole_cell_in_view(const sim::StereoParams& sp, const sim::Point3& camera, double yaw, const sim::Terrain& ground,
                        double x0, double y0, double w, double range) {
  for (int c = 0; c < 4; ++c) {
    const double x = x0 + (c & 1) * w, y = y0 + (c >> 1) * w;
    const double z = ground.height(x, y);
    if (!std::isfinite(z) || !cell_in_view(sp, camera, yaw, x, y, z, range)) return false;
  }
  return true;
}

namespace {

template <typename CcmConfig>
DetectionResult run_trials(const DetectionConfig& cfg) {
  DetectionResult result;
  result.paper_cell = cfg.paper_cell;
  result.first_seed = cfg.first_seed;
  result.maps = cfg.gate.describe(default_stack_params(0.08F));
  result.end_seed = cfg.first_seed + cfg.trials;
  for (DetectionMethod m : kDetectionMethods)
    for (double w : cfg.cell_widths_m)
      for (double r : cfg.size_ratios) {
        DetectionRow row;
        row.method = m;
        row.cell_width_m = w;
        row.size_ratio = r;
        result.rows.push_back(row);
      }
  if (cfg.cell_widths_m.empty() || cfg.size_ratios.empty()) return result;

  // Distinct obstacle sizes (m), each with the resolutions whose ratio list holds it.
  std::map<std::int64_t, std::vector<std::pair<std::size_t, double>>> sizes;  // um -> (width index, ratio)
  for (std::size_t k = 0; k < cfg.cell_widths_m.size(); ++k)
    for (double r : cfg.size_ratios) sizes[to_um(r * cfg.cell_widths_m[k])].emplace_back(k, r);
  double max_range = 0.0;
  for (double w : cfg.cell_widths_m) max_range = std::max(max_range, ivg_max_range_m(w));
  const double res = cfg.raster_resolution_m;
  const sim::StereoParams sp = detection_stereo_params(cfg.pixel_stride, max_range * 1.1, cfg.border_streak_probability);
  const sim::StereoCamera camera(sp);
  const double start_distance = max_range + cfg.start_margin_m;
  const double drive = std::max(0.0, start_distance - cfg.end_distance_m);
  const std::vector<sim::PathPose> path =
      sim::generate_path(sim::Pose2{0.0, 0.0, 0.0}, {sim::PathSegment{drive, 0.0}}, cfg.frame_spacing_m);
  const double half_width = max_range * 0.5 * sp.width_px / sp.focal_px + 0.2;

  std::vector<MapPair<CcmConfig>> maps(cfg.cell_widths_m.size());
  for (std::size_t k = 0; k < maps.size(); ++k) {
    maps[k].width_m = cfg.cell_widths_m[k];
    maps[k].gate = cfg.gate;
  }

  const auto t_start = std::chrono::steady_clock::now();
  double capture_s = 0.0;
  for (std::uint64_t trial = 0; trial < cfg.trials; ++trial) {
    const std::uint64_t seed = cfg.first_seed + trial;
    sim::Rng placement(sim::hash_combine(seed, 0xD7));
    // The obstacle's near face lies start_distance ahead of the start plus up to 0.2 m.
    const double face_x = start_distance + placement.uniform(0.0, 0.2);
    const double centre_y = placement.uniform(-cfg.lateral_offset_max_m, cfg.lateral_offset_max_m);
    const double x_end = face_x - cfg.end_distance_m + max_range + 0.1;
    // Raster origin on whole raster steps; box edges go on raster-cell midpoints.
    const sim::Rect area{-0.3, std::floor((-half_width - 0.3) / res) * res, x_end, half_width + 0.3};
    sim::TerrainParams tp = sim::lunar_terrain_params(area, seed);
    tp.rocks.density_per_m2 = 0.0;
    tp.craters.count = 0;
    const sim::ProceduralTerrain ground(tp);
    const sim::HeightRaster base = sim::rasterize(ground, area, res);
    std::vector<SteepCache> steep;
    for (const MapPair<CcmConfig>& mp : maps) steep.emplace_back(&ground, mp.width_m);

    for (const auto& [size_um, users] : sizes) {
      const double size_wanted = static_cast<double>(size_um) * 1e-6;
      const int n = std::max(1, static_cast<int>(std::lround(size_wanted / res)));
      const double size = n * res;  // exact on the raster (documented: rounded to it)
      sim::Rng jitter(sim::hash_combine(seed, static_cast<std::uint64_t>(size_um), 0xB0));
      const int i0 = static_cast<int>(std::floor((face_x + jitter.uniform(0.0, res * 8.0) - base.origin_x()) / res));
      const int j0 = static_cast<int>(std::floor((centre_y - 0.5 * size - base.origin_y()) / res + jitter.uniform(0.0, 1.0)));
      const sim::Rect box{base.origin_x() + (i0 + 0.5) * res, base.origin_y() + (j0 + 0.5) * res,
                          base.origin_x() + (i0 + 0.5 + n) * res, base.origin_y() + (j0 + 0.5 + n) * res};
      sim::HeightRaster scene = base;
      for (int j = j0 + 1; j <= j0 + n && j < scene.ny(); ++j)
        for (int i = i0 + 1; i <= i0 + n && i < scene.nx(); ++i) scene.at(i, j) += static_cast<float>(size);
      scene.build_blocks();

      for (const auto& [k, ratio] : users) {
        (void)ratio;
        if (!maps[k].reset()) {
          std::fprintf(stderr, "detection: map init failed at %.2f m cells\n", maps[k].width_m);
          return result;
        }
      }
      std::vector<std::array<DetectionCounts, 3>> counts(users.size());
      // Frames from where the obstacle comes within reach of the coarsest resolution using it.
      double reach = 0.0;
      for (const auto& [k, ratio] : users) reach = std::max(reach, ivg_max_range_m(maps[k].width_m) + cfg.start_margin_m);
      std::vector<PointXYZ> points;
      for (std::size_t f = 0; f < path.size(); ++f) {
        const sim::Pose2& pose = path[f].pose;
        if (box.x0 - pose.x > reach) continue;
        const auto t_capture = std::chrono::steady_clock::now();
        const sim::StereoFrame frame = camera.capture(scene, pose, sim::hash_combine(seed, static_cast<std::uint64_t>(size_um), f));
        capture_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t_capture).count();
        points.clear();
        for (const sim::Point3& p : frame.points_map)
          points.push_back(PointXYZ{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
        const sim::Point3& cam = frame.sensor_position_map;
        const PointXYZ origin{static_cast<float>(cam.x), static_cast<float>(cam.y), static_cast<float>(cam.z)};
        for (std::size_t u = 0; u < users.size(); ++u) {
          MapPair<CcmConfig>& mp = maps[users[u].first];
          const float fx = static_cast<float>(pose.x), fy = static_cast<float>(pose.y);
          if (mp.ccm->move_to(fx, fy) != Status::kOk || mp.omg->move_to(fx, fy) != Status::kOk ||
              mp.ccm->update_frame(points.data(), points.size(), origin, nullptr) != Status::kOk ||
              mp.omg->update_frame(points.data(), points.size(), origin, nullptr) != Status::kOk) {
            std::fprintf(stderr, "detection: map update refused\n");
            continue;
          }
          // Tallied while the obstacle is within this resolution's own reach, so that every size
          // of a resolution is scored over the same stretch of the drive.
          if (box.x0 - pose.x > ivg_max_range_m(mp.width_m) + cfg.start_margin_m) continue;
          tally_frame(mp, sp, cam, pose.yaw, base, box, cfg.truth_min_coverage, steep[users[u].first], counts[u].data());
          for (DetectionMethod m : kDetectionMethods)
            if (obstacle_marked(mp, m, box)) counts[u][static_cast<std::size_t>(m)].detected = 1;
        }
      }
      for (std::size_t u = 0; u < users.size(); ++u) {
        const MapPair<CcmConfig>& mp = maps[users[u].first];
        for (DetectionMethod m : kDetectionMethods) {
          DetectionCounts& c = counts[u][static_cast<std::size_t>(m)];
          c.trials = 1;
          result.find(m, mp.width_m, users[u].second)->counts += c;
        }
      }
    }
    if (cfg.progress) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      const double eta = elapsed / static_cast<double>(trial + 1) * static_cast<double>(cfg.trials - trial - 1);
      std::fprintf(stderr, "fig6: trial %llu/%llu (seed %llu) done, %.0f s elapsed (%.0f s ray casting), ~%.0f s left\n",
                   static_cast<unsigned long long>(trial + 1), static_cast<unsigned long long>(cfg.trials),
                   static_cast<unsigned long long>(seed), elapsed, capture_s, eta);
    }
  }
  return result;
}

}  // namespace

DetectionResult run_detection(const DetectionConfig& cfg) {
  return cfg.paper_cell ? run_trials<PaperCell<SingleCcmConfig>>(cfg) : run_trials<SingleCcmConfig>(cfg);
}

// ---------------------------------------------------------------------------------------------
// Shards
// ---------------------------------------------------------------------------------------------

namespace {
constexpr const char* kCsvHeader =
    "method,cell_um,size_ratio,trials,detected,correct,hit,missed,fn_adjacent,fn_far,unknown,unknown_obstacle,excluded";
}

bool write_detection_csv(const std::string& path, const DetectionResult& result, std::string* error) {
  std::ofstream out(path);
  out << "# ccmap fig6/fig7 detection shard: integer cell-frame counts (see tools/experiments/detection.hpp)\n";
  out << "# seeds " << result.first_seed << ":" << result.end_seed << "\n";
  out << "# ccm cell " << (result.paper_cell ? "paper" : "full") << "\n";
  out << "# maps " << result.maps << "\n" << kCsvHeader << "\n";
  for (const DetectionRow& r : result.rows) {
    const DetectionCounts& c = r.counts;
    out << detection_method_name(r.method) << ',' << to_um(r.cell_width_m) << ',' << format("%.4f", r.size_ratio) << ','
        << c.trials << ',' << c.detected << ',' << c.correct << ',' << c.hit << ',' << c.missed << ',' << c.fn_adjacent
        << ',' << c.fn_far << ',' << c.unknown << ',' << c.unknown_obstacle << ',' << c.excluded << '\n';
  }
  if (!out) {
    if (error != nullptr) *error = "cannot write " + path;
    return false;
  }
  return true;
}

bool read_detection_csv(const std::string& path, DetectionResult* out, std::string* error) {
  auto fail = [&](const std::string& m) {
    if (error != nullptr) *error = path + ": " + m;
    return false;
  };
  std::ifstream in(path);
  if (!in) return fail("cannot open");
  DetectionResult r;
  r.paper_cell = true;  // shards written before the cell kinds existed hold the paper's cell
  bool seeds = false, header = false;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    if (line[0] == '#') {
      unsigned long long a = 0, b = 0;
      if (std::sscanf(line.c_str(), "# seeds %llu:%llu", &a, &b) == 2) {
        r.first_seed = a;
        r.end_seed = b;
        seeds = true;
      } else if (line.rfind("# maps ", 0) == 0) {
        r.maps = line.substr(7);
      }
      if (line == "# ccm cell full") r.paper_cell = false;
      continue;
    }
    if (!header) {
      if (line != kCsvHeader) return fail("unexpected header (not a detection shard)");
      header = true;
      continue;
    }
    char method[8] = {0};
    long long cell_um = 0;
    double ratio = 0.0;
    unsigned long long v[10] = {0};
    if (std::sscanf(line.c_str(), "%7[^,],%lld,%lf,%llu,%llu,%llu,%llu,%llu,%llu,%llu,%llu,%llu,%llu", method, &cell_um,
                    &ratio, &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9]) != 13)
      return fail("bad row: " + line);
    DetectionRow row;
    const std::string m = method;
    if (m == "CCM") row.method = DetectionMethod::kCcm;
    else if (m == "CCM-OF") row.method = DetectionMethod::kCcmObstacleFirst;
    else if (m == "OMG") row.method = DetectionMethod::kOmg;
    else return fail("unknown method " + m);
    row.cell_width_m = static_cast<double>(cell_um) * 1e-6;
    row.size_ratio = ratio;
    DetectionCounts& c = row.counts;
    c.trials = v[0];
    c.detected = v[1];
    c.correct = v[2];
    c.hit = v[3];
    c.missed = v[4];
    c.fn_adjacent = v[5];
    c.fn_far = v[6];
    c.unknown = v[7];
    c.unknown_obstacle = v[8];
    c.excluded = v[9];
    r.rows.push_back(row);
  }
  if (!seeds || !header) return fail("missing '# seeds A:B' line or header");
  *out = r;
  return true;
}

bool merge_detection_results(const std::vector<DetectionResult>& shards, DetectionResult* out, std::string* error) {
  DetectionResult merged;
  merged.paper_cell = !shards.empty() && shards.front().paper_cell;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;
  if (!shards.empty()) merged.maps = shards.front().maps;
  for (const DetectionResult& s : shards) {
    if (s.paper_cell != merged.paper_cell) {
      if (error != nullptr) *error = "shards of the paper cell and of the full cell cannot be merged";
      return false;
    }
    if (s.maps != merged.maps) {
      if (error != nullptr) *error = "shards of different maps: '" + merged.maps + "' and '" + s.maps + "'";
      return false;
    }
    for (const auto& [a, b] : ranges) {
      if (s.first_seed < b && a < s.end_seed) {
        if (error != nullptr)
          *error = format("seed ranges %llu:%llu and %llu:%llu overlap", static_cast<unsigned long long>(a),
                          static_cast<unsigned long long>(b), static_cast<unsigned long long>(s.first_seed),
                          static_cast<unsigned long long>(s.end_seed));
        return false;
      }
    }
    ranges.emplace_back(s.first_seed, s.end_seed);
    for (const DetectionRow& row : s.rows) {
      DetectionRow* target = merged.find(row.method, row.cell_width_m, row.size_ratio);
      if (target == nullptr) {
        merged.rows.push_back(row);
      } else {
        target->counts += row.counts;
      }
    }
  }
  std::sort(merged.rows.begin(), merged.rows.end(), [](const DetectionRow& a, const DetectionRow& b) {
    if (a.method != b.method) return a.method < b.method;
    if (to_um(a.cell_width_m) != to_um(b.cell_width_m)) return a.cell_width_m < b.cell_width_m;
    return a.size_ratio < b.size_ratio;
  });
  std::sort(ranges.begin(), ranges.end());
  merged.first_seed = ranges.empty() ? 0 : ranges.front().first;
  merged.end_seed = ranges.empty() ? 0 : ranges.back().second;
  *out = merged;
  return true;
}

// ---------------------------------------------------------------------------------------------
// Table and plots
// ---------------------------------------------------------------------------------------------

double detection_limit_ratio(const DetectionResult& result, DetectionMethod method, double w, double max_missed,
                             double min_detection) {
  std::vector<const DetectionRow*> rows;
  for (const DetectionRow& r : result.rows)
    if (r.method == method && to_um(r.cell_width_m) == to_um(w)) rows.push_back(&r);
  std::sort(rows.begin(), rows.end(), [](const DetectionRow* a, const DetectionRow* b) { return a->size_ratio < b->size_ratio; });
  double limit = kNaN;
  for (auto it = rows.rbegin(); it != rows.rend(); ++it) {
    const double s = (*it)->missed_share();
    if (!(s <= max_missed) || !((*it)->detection_rate() >= min_detection)) break;
    limit = (*it)->size_ratio;
  }
  return limit;
}

std::string detection_table(const DetectionResult& result) {
  Table t({"map", "cell", "size/cell", "trials", "detected", "correct m2f", "missed(FP) m2f", "FN adj m2f", "FN far m2f",
           "unknown m2f", "missed share", "obstacle unknown", "FN/obstacle"});
  for (const DetectionRow& r : result.rows) {
    const DetectionCounts& c = r.counts;
    t.add_row({detection_method_name(r.method), format("%.0f cm", r.cell_width_m * 100), ratio_label(r.size_ratio),
               format("%llu", static_cast<unsigned long long>(c.trials)),
               format("%.0f%%", 100.0 * r.detection_rate()), format("%.2f", r.area_m2(c.correct)),
               format("%.4f", r.area_m2(c.missed)), format("%.4f", r.area_m2(c.fn_adjacent)),
               format("%.4f", r.area_m2(c.fn_far)), format("%.3f", r.area_m2(c.unknown)),
               format("%.0f%%", 100.0 * r.missed_share()), format("%.0f%%", 100.0 * r.obstacle_unknown_share()),
               format("%.2f", r.false_obstacle_ratio())});
  }
  std::ostringstream o;
  o << "seeds " << result.first_seed << ":" << result.end_seed << ", " << (result.paper_cell ? "paper" : "full")
    << " CCM cell; m2f = time-summed area (m^2 x frames); missed share = missed / known obstacle area;\n"
       "obstacle unknown = unknown / observed obstacle area; FN/obstacle = false-obstacle area / known obstacle area;\n"
       "detected = trials with the obstacle marked in at least one frame\n\n"
    << t.str() << "\n";
  Table s({"map", "cell", "detects from (>= 80 % of trials, missed share <= 25 %)", "paper"});
  std::vector<double> widths;
  for (const DetectionRow& r : result.rows)
    if (std::find_if(widths.begin(), widths.end(), [&](double w) { return to_um(w) == to_um(r.cell_width_m); }) == widths.end())
      widths.push_back(r.cell_width_m);
  for (DetectionMethod m : kDetectionMethods)
    for (double w : widths) {
      const double lim = detection_limit_ratio(result, m, w, 0.25, 0.8);
      s.add_row({detection_method_name(m), format("%.0f cm", w * 100),
                 std::isfinite(lim) ? format("%.2f x cell", lim) : std::string("not within the sizes run"),
                 m == DetectionMethod::kOmg ? "~3 x cell" : "~0.75 x cell"});
    }
  o << s.str();
  return o.str();
}

bool write_detection_plots(const DetectionResult& result, const std::string& out_dir, std::string* error) {
  if (!ensure_directory(out_dir, error)) return false;
  std::vector<double> widths;
  for (const DetectionRow& r : result.rows)
    if (std::find_if(widths.begin(), widths.end(), [&](double w) { return to_um(w) == to_um(r.cell_width_m); }) == widths.end())
      widths.push_back(r.cell_width_m);
  auto series_of = [&](DetectionMethod m, double w, double (DetectionRow::*value)() const) {
    std::vector<double> x, y;
    for (const DetectionRow& r : result.rows)
      if (r.method == m && to_um(r.cell_width_m) == to_um(w)) {
        x.push_back(r.size_ratio);
        y.push_back((r.*value)());
      }
    return std::make_pair(x, y);
  };
  const std::string seeds = format("%llu trials, %s CCM cell", static_cast<unsigned long long>(result.end_seed - result.first_seed),
                                   result.paper_cell ? "paper" : "full");
  auto colour = [](std::size_t k) { return std::string(palette_color(static_cast<int>(k))); };
  SvgPlot ccm;
  ccm.title = "Fig. 6: CCM (obstacle test before coverage) (" + seeds + ")";
  ccm.x_label = "obstacle size / cell width";
  ccm.y_label = "solid: missed / known obstacle area; dashed: unknown / observed";
  ccm.y_min = 0.0;
  ccm.y_max = 1.0;
  SvgPlot omg = ccm;
  omg.title = "Fig. 7: OMG + roughness filter (" + seeds + ")";
  omg.y_label = "solid: missed share; dashed: false-obstacle / obstacle area";
  omg.y_max = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < widths.size(); ++k) {
    const double w = widths[k];
    const auto [ax, ay] = series_of(DetectionMethod::kCcmObstacleFirst, w, &DetectionRow::missed_share);
    const auto [bx, by] = series_of(DetectionMethod::kCcmObstacleFirst, w, &DetectionRow::obstacle_unknown_share);
    ccm.series.push_back(SvgSeries{format("missed, %.0f cm", w * 100), ax, ay, colour(k), false, true});
    ccm.series.push_back(SvgSeries{format("unknown, %.0f cm", w * 100), bx, by, colour(k), true, true});
    const auto [mx, my] = series_of(DetectionMethod::kOmg, w, &DetectionRow::missed_share);
    const auto [fx, fy] = series_of(DetectionMethod::kOmg, w, &DetectionRow::false_obstacle_ratio);
    omg.series.push_back(SvgSeries{format("missed, %.0f cm", w * 100), mx, my, colour(k), false, true});
    omg.series.push_back(SvgSeries{format("false obstacle, %.0f cm", w * 100), fx, fy, colour(k), true, true});
  }
  ccm.ref_lines.push_back(SvgRefLine{0.75, true, "paper: from 0.75 x"});
  omg.ref_lines.push_back(SvgRefLine{3.0, true, "paper: ~3 x"});
  if (!write_svg(out_dir + "/fig6_ccm.svg", ccm, error) || !write_svg(out_dir + "/fig7_omg.svg", omg, error)) return false;
  SvgPlot d;
  d.title = "Per-trial detection (" + seeds + "): CCM-OF solid, OMG + roughness dashed";
  d.x_label = "obstacle size / cell width";
  d.y_label = "share of trials with the obstacle marked";
  d.y_min = 0.0;
  d.y_max = 1.0;
  for (std::size_t k = 0; k < widths.size(); ++k) {
    for (DetectionMethod m : {DetectionMethod::kCcmObstacleFirst, DetectionMethod::kOmg}) {
      const auto [x, y] = series_of(m, widths[k], &DetectionRow::detection_rate);
      d.series.push_back(SvgSeries{format("%s %.0f cm", detection_method_name(m), widths[k] * 100), x, y, colour(k),
                                   m == DetectionMethod::kOmg, true});
    }
  }
  return write_svg(out_dir + "/fig6_detection.svg", d, error);
}

}  // namespace ccmap::experiments
