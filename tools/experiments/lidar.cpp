#include "experiments/lidar.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <unordered_map>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/map/stack.hpp"
#include "cloud_reader.hpp"
#include "experiments/canvas.hpp"
#include "experiments/common.hpp"
#include "png.hpp"
#include "sim/data_dir.hpp"
#include "sim/rng.hpp"

namespace ccmap::experiments {

namespace {

struct LocalPoint {
  double x, y, z;  ///< local frame (origin subtracted in double)
};

/// Fixed grid of the three cell kinds over [x0, x0 + nx w) x [y0, y0 + ny w); CcmCellT is
/// CcmCell or CcmPaperCell (LidarConfig::paper_cell).
template <typename CcmCellT>
struct Maps {
  double x0 = 0.0, y0 = 0.0, w = 1.0;
  int nx = 0, ny = 0;
  std::vector<CcmCellT> ccm;
  std::vector<KalmanCell> kalman;
  std::vector<OmgCell> omg;
  std::vector<CcmSurface> surface;
  int index(double x, double y) const {
    const int ix = static_cast<int>(std::floor((x - x0) / w)), iy = static_cast<int>(std::floor((y - y0) / w));
    if (ix < 0 || iy < 0 || ix >= nx || iy >= ny) return -1;
    return ix + nx * iy;
  }
  double cx(int k) const { return x0 + (k % nx + 0.5) * w; }
  double cy(int k) const { return y0 + (k / nx + 0.5) * w; }
};

template <typename CcmCellT>
Maps<CcmCellT> build_maps(const std::vector<LocalPoint>& train, double x0, double y0, double ex, double ey, double w,
                          double sigma_m) {
  Maps<CcmCellT> m;
  m.x0 = x0;
  m.y0 = y0;
  m.w = w;
  m.nx = std::max(1, static_cast<int>(std::ceil(ex / w + 1e-9)));
  m.ny = std::max(1, static_cast<int>(std::ceil(ey / w + 1e-9)));
  const std::size_t n = static_cast<std::size_t>(m.nx) * static_cast<std::size_t>(m.ny);
  m.ccm.assign(n, CcmCellT{});
  m.kalman.assign(n, KalmanCell{});
  m.omg.assign(n, OmgCell{});
  const float var = static_cast<float>(sigma_m * sigma_m);
  for (const LocalPoint& p : train) {
    const int k = m.index(p.x, p.y);
    if (k < 0) continue;
    const std::size_t u = static_cast<std::size_t>(k);
    const float z = static_cast<float>(p.z);
    // Local coordinates of a few tens of metres: never refused.
    (void)ccm_update(m.ccm[u], static_cast<float>(p.x - m.cx(k)), static_cast<float>(p.y - m.cy(k)), z, 1.0F,
                     kNoWeightLimit);
    (void)kalman_update(m.kalman[u], z, var);
    (void)omg_update(m.omg[u], z, var, 1.0F);
  }
  m.surface.resize(n);
  for (std::size_t k = 0; k < n; ++k) m.surface[k] = ccm_surface(m.ccm[k]);
  return m;
}

struct Errors {
  std::vector<double> abs;
  double sum_sq = 0.0;
  void add(double e) {
    abs.push_back(std::fabs(e));
    sum_sq += e * e;
  }
  void finish(LidarMethodStats* s, std::size_t skipped) {
    s->evaluated = abs.size();
    s->skipped = skipped;
    if (abs.empty()) return;
    std::sort(abs.begin(), abs.end());
    const std::size_t n = abs.size();
    s->rms_m = std::sqrt(sum_sq / static_cast<double>(n));
    s->median_abs_m = abs[n / 2];
    s->p95_abs_m = abs[std::min(n - 1, static_cast<std::size_t>(0.95 * static_cast<double>(n)))];
    s->max_abs_m = abs.back();
  }
};

/// Indices of points more than cut_m above the median z of their block (block_m square).
std::vector<bool> outlier_mask(const std::vector<LocalPoint>& pts, double block_m, double cut_m) {
  std::unordered_map<long long, std::vector<double>> blocks;
  auto key = [block_m](const LocalPoint& p) {
    return static_cast<long long>(std::floor(p.x / block_m)) * 1000003LL + static_cast<long long>(std::floor(p.y / block_m));
  };
  for (const LocalPoint& p : pts) blocks[key(p)].push_back(p.z);
  std::unordered_map<long long, double> med;
  for (auto& [k, v] : blocks) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    med[k] = v[v.size() / 2];
  }
  std::vector<bool> mask(pts.size(), false);
  for (std::size_t i = 0; i < pts.size(); ++i) mask[i] = pts[i].z > med[key(pts[i])] + cut_m;
  return mask;
}

template <typename CcmCellT>
bool ccm_known(const Maps<CcmCellT>& m, std::size_t k, const LidarConfig& cfg) {
  return ccm_is_covered(m.ccm[k], static_cast<float>(m.w), static_cast<float>(cfg.coverage_tau),
                        static_cast<float>(cfg.min_points));
}
template <typename CcmCellT>
bool constant_known(const Maps<CcmCellT>& m, std::size_t k, const LidarConfig& cfg) {
  return m.omg[k].weight >= static_cast<float>(cfg.min_points);
}

template <typename CcmCellT>
void evaluate(const Maps<CcmCellT>& m, const std::vector<LocalPoint>& held, const LidarConfig& cfg, LidarVariant* v) {
  Errors common[3], own_const[2];
  std::size_t skip_common = 0, skip_own = 0;
  for (const LocalPoint& p : held) {
    const int k = m.index(p.x, p.y);
    if (k < 0) {
      ++skip_common;
      ++skip_own;
      continue;
    }
    const std::size_t u = static_cast<std::size_t>(k);
    const bool cst = constant_known(m, u, cfg);
    if (cst) {
      own_const[0].add(m.omg[u].height - p.z);
      own_const[1].add(m.kalman[u].height - p.z);
    } else {
      ++skip_own;
    }
    if (!cst || !ccm_known(m, u, cfg)) {
      ++skip_common;
      continue;
    }
    const float qx = static_cast<float>(p.x - m.cx(k)), qy = static_cast<float>(p.y - m.cy(k));
    common[0].add(ccm_height_at(m.ccm[u], m.surface[u], qx, qy) - p.z);
    common[1].add(m.omg[u].height - p.z);
    common[2].add(m.kalman[u].height - p.z);
  }
  const char* names[3] = {"CCM", "OMG", "Kalman"};
  for (int i = 0; i < 3; ++i) {
    LidarMethodStats s;
    s.method = names[i];
    s.point_set = "common";
    s.cell_width_m = m.w;
    common[i].finish(&s, skip_common);
    v->stats.push_back(s);
  }
  for (int i = 0; i < 2; ++i) {
    LidarMethodStats s;
    s.method = names[i + 1];
    s.point_set = "own";
    s.cell_width_m = m.w;
    own_const[i].finish(&s, skip_own);
    v->stats.push_back(s);
  }
}

/// One row of three panels: held-in points (last z per 2.5 cm pixel), CCM sub-cell height,
/// constant height; viridis over the 2nd..98th percentile of the points, hill-shaded from the
/// maps' own gradients; black = no data / unknown cell.
template <typename CcmCellT>
bool write_picture(const std::string& file, const Maps<CcmCellT>& m, const std::vector<LocalPoint>& train, const LidarConfig& cfg,
                   double ex, double ey, const std::string& title, std::string* error) {
  const double step = std::max(cfg.image_step_m, std::max(ex, ey) / 400.0);  // panels <= ~400 px
  const int w = static_cast<int>(std::ceil(ex / step)), h = static_cast<int>(std::ceil(ey / step));
  std::vector<double> zs;
  for (const LocalPoint& p : train) zs.push_back(p.z);
  std::sort(zs.begin(), zs.end());
  const double lo = zs[zs.size() / 50], hi = zs[zs.size() * 49 / 50];
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> grid[3];
  for (auto& g : grid) g.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), nan);
  auto at = [w](int i, int j) { return static_cast<std::size_t>(i) + static_cast<std::size_t>(w) * static_cast<std::size_t>(j); };
  for (const LocalPoint& p : train) {
    const int i = static_cast<int>((p.x - m.x0) / step), j = static_cast<int>((p.y - m.y0) / step);
    // Each point drawn as 2 x 2 pixels (the scan's ~5 cm spacing is 2 pixels).
    for (int dj = 0; dj < 2; ++dj)
      for (int di = 0; di < 2; ++di)
        if (i + di >= 0 && j + dj >= 0 && i + di < w && j + dj < h) grid[0][at(i + di, j + dj)] = p.z;
  }
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const double x = m.x0 + (i + 0.5) * step, y = m.y0 + (j + 0.5) * step;
      const int k = m.index(x, y);
      if (k < 0) continue;
      const std::size_t u = static_cast<std::size_t>(k);
      if (ccm_known(m, u, cfg)) {
        grid[1][at(i, j)] = ccm_height_at(m.ccm[u], m.surface[u], static_cast<float>(x - m.cx(k)),
                                          static_cast<float>(y - m.cy(k)));
      }
      if (constant_known(m, u, cfg)) grid[2][at(i, j)] = m.omg[u].height;
    }
  }
  const int gap = 20, top = 40, legend = 46;
  tools::RgbImage img(3 * w + 4 * gap, top + h + legend, 255);
  const char* names[3] = {"SCAN POINTS (TRAINING, CUT)", "CCM SUB-CELL HEIGHT (EQ. 10)", "OMG/KALMAN CELL HEIGHT"};
  for (int p = 0; p < 3; ++p) {
    const int left = gap + p * (w + gap);
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < w; ++i) {
        const double z = grid[p][at(i, j)];
        Rgb c = kBlack;
        if (std::isfinite(z) && p == 0) {
          c = viridis(std::floor(40.0 * (z - lo) / (hi - lo)) / 40.0);  // points: unshaded
        } else if (std::isfinite(z)) {
          // Colours quantised (40 heights x 12 shades) so that the PNGs stay commit-sized.
          c = viridis(std::floor(40.0 * (z - lo) / (hi - lo)) / 40.0);
          // Shade by the gradient of this panel's surface (central differences).
          auto get = [&](int ii, int jj) {
            if (ii < 0 || jj < 0 || ii >= w || jj >= h) return z;
            const double v = grid[p][at(ii, jj)];
            return std::isfinite(v) ? v : z;
          };
          const double gx = (get(i + 1, j) - get(i - 1, j)) / (2 * step), gy = (get(i, j + 1) - get(i, j - 1)) / (2 * step);
          const double s = 0.45 + 0.55 * std::floor(12.0 * tools::hillshade(gx, gy)) / 12.0;
          c = Rgb{static_cast<std::uint8_t>(c.r * s), static_cast<std::uint8_t>(c.g * s), static_cast<std::uint8_t>(c.b * s)};
        }
        fill_rect(img, left + i, top + h - 1 - j, 1, 1, c);
      }
    }
    draw_text(img, left, top - 12, names[p], kBlack);
    draw_rect(img, left - 1, top - 1, w + 2, h + 2, kBlack);
    const double bar_m = ex > 20.0 ? 5.0 : 2.0;
    fill_rect(img, left + 4, top + h - 26, static_cast<int>(bar_m / step) + 16, 22, kWhite);
    scale_bar(img, left + 12, top + h - 20, 1.0 / step, bar_m, kBlack);
    fill_rect(img, left + w - 24, top + 3, 18, 38, kWhite);
    north_arrow(img, left + w - 15, top + 6, kBlack);
  }
  draw_text(img, gap, 8, title, kBlack);
  colour_bar(img, gap, top + h + 18, 220, 10, viridis, format("%.2f M", lo + 0.0), format("%.2f M", hi + 0.0),
             "HEIGHT (LOCAL), HILL-SHADED FROM NW");
  draw_text(img, gap + 260, top + h + 20, "BLACK: NO POINTS / UNKNOWN CELL (EQ. 12 FOR CCM, < 3 POINTS)", kBlack);
  return tools::write_png(file, img, error);
}

/// A single-layer stack of the library folding one frame of local points.
template <typename Config>
class StackMap {
 public:
  /// gate nullptr: the gate off (the paper's update).
  bool build(const std::vector<LocalPoint>& train, double w, double sigma_m, const GateSetting* gate, double cx,
             double cy, double cz) {
    StackParams p = default_stack_params(static_cast<float>(w));
    p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{static_cast<float>(sigma_m), 0.0F});
    if (gate != nullptr) {
      gate->apply(&p);
    } else {
      p.outlier_gate_sigma = 0.0F;
    }
    if (stack_->init(p) != Status::kOk || stack_->move_to(static_cast<float>(cx), static_cast<float>(cy)) != Status::kOk) {
      return false;
    }
    std::vector<PointXYZ> pts;
    pts.reserve(train.size());
    for (const LocalPoint& q : train) pts.push_back(PointXYZ{static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z)});
    const PointXYZ origin{static_cast<float>(cx), static_cast<float>(cy), static_cast<float>(cz + 2.0)};
    FrameCounters c{};
    return stack_->update_frame(pts.data(), pts.size(), origin, &c) == Status::kOk && c.outside_map == 0U;
  }
  /// Height at (x, y) if the map knows it.
  bool height(double x, double y, double* h) const {
    const QueryResult q = stack_->query_layer(0, static_cast<float>(x), static_cast<float>(y));
    *h = q.height_m;
    return q.status == Status::kOk;
  }
  static double window_m(double w) { return w * Stack<Config>::layer_side(0); }

 private:
  std::unique_ptr<Stack<Config>> stack_ = std::make_unique<Stack<Config>>();
};

/// Variant "stack" (lidar.hpp, item 6).
LidarVariant stack_variant(const LidarConfig& cfg, const std::vector<LocalPoint>& all, const std::vector<bool>& held,
                           const std::vector<bool>& outlier, double x0, double y0, double ex, double ey, double z50) {
  LidarVariant v;
  v.name = "stack";
  std::vector<LocalPoint> train, test;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (!held[i]) {
      train.push_back(all[i]);
    } else if (!outlier[i]) {
      test.push_back(all[i]);
    } else {
      ++v.removed_outliers;  // held-out outliers: not predicted
    }
  }
  v.train_points = train.size();
  v.held_out_points = test.size();
  const double cx = x0 + 0.5 * ex, cy = y0 + 0.5 * ey;
  for (const double w : cfg.cell_widths_m) {
    if (StackMap<SingleCcmConfig>::window_m(w) < std::max(ex, ey) + 2.0 * w) continue;  // the cloud must fit
    StackMap<SingleCcmConfig> ccm[2];
    StackMap<SingleKalmanConfig> kalman[2];
    StackMap<SingleOmgConfig> omg[2];
    for (int g = 0; g < 2; ++g) {
      const GateSetting* gate = g == 1 ? &cfg.gate : nullptr;
      if (!ccm[g].build(train, w, cfg.sigma_m, gate, cx, cy, z50) ||
          !kalman[g].build(train, w, cfg.sigma_m, gate, cx, cy, z50) ||
          !omg[g].build(train, w, cfg.sigma_m, gate, cx, cy, z50)) {
        continue;
      }
    }
    Errors errors[6];
    std::size_t skipped = 0;
    for (const LocalPoint& p : test) {
      double h[6];
      bool known = true;
      for (int g = 0; g < 2; ++g) {
        known = ccm[g].height(p.x, p.y, &h[3 * g]) && known;
        known = kalman[g].height(p.x, p.y, &h[3 * g + 1]) && known;
        known = omg[g].height(p.x, p.y, &h[3 * g + 2]) && known;
      }
      if (!known) {
        ++skipped;
        continue;
      }
      for (int k = 0; k < 6; ++k) errors[k].add(h[k] - p.z);
    }
    const char* names[6] = {"CCM, gate off", "Kalman, gate off", "OMG, gate off", "CCM, gate on", "Kalman, gate on",
                            "OMG, gate on"};
    for (int k = 0; k < 6; ++k) {
      LidarMethodStats s;
      s.method = names[k];
      s.point_set = "common";
      s.cell_width_m = w;
      errors[k].finish(&s, skipped);
      v.stats.push_back(s);
    }
  }
  return v;
}

}  // namespace

std::string lidar_crop_path(const std::string& data_dir) {
  return data_dir + "/lone_star_tls/lone_star_crop_10x10m_x515386.6_y4918368.4.xyz";
}
std::string lidar_full_path(const std::string& data_dir) { return data_dir + "/lone_star_tls/lone-star.las"; }

const LidarMethodStats* LidarVariant::find(const std::string& method, double cell_width_m,
                                           const std::string& point_set) const {
  for (const LidarMethodStats& s : stats) {
    if (s.method == method && s.point_set == point_set && std::fabs(s.cell_width_m - cell_width_m) < 1e-9) return &s;
  }
  return nullptr;
}

bool run_lidar(const LidarConfig& cfg, const std::string& path, const std::string& name, const std::string& out_dir,
               const std::string& prefix, LidarRun* out, std::string* why, std::vector<std::string>* pictures) {
  if (!sim::data_file_available(path, why)) return false;
  const tools::Cloud cloud = tools::read_cloud(path);
  if (!cloud.ok() || cloud.size() == 0) {
    *why = "cannot read " + path + ": " + (cloud.ok() ? std::string("no points") : cloud.error);
    return false;
  }
  LidarRun run;
  run.cloud_name = name;
  run.path = path;
  run.points = cloud.size();
  double min_x = cloud.x[0], min_y = cloud.y[0], max_x = cloud.x[0], max_y = cloud.y[0];
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    min_x = std::min(min_x, cloud.x[i]);
    max_x = std::max(max_x, cloud.x[i]);
    min_y = std::min(min_y, cloud.y[i]);
    max_y = std::max(max_y, cloud.y[i]);
  }
  std::vector<double> zs(cloud.z);
  std::nth_element(zs.begin(), zs.begin() + static_cast<std::ptrdiff_t>(zs.size() / 2), zs.end());
  run.origin_x = std::floor(min_x);
  run.origin_y = std::floor(min_y);
  run.origin_z = std::round(zs[zs.size() / 2]);
  std::vector<LocalPoint> all(cloud.size());
  double zmax = -1e300;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    all[i] = LocalPoint{cloud.x[i] - run.origin_x, cloud.y[i] - run.origin_y, cloud.z[i] - run.origin_z};
    zmax = std::max(zmax, all[i].z);
  }
  run.z_p50 = zs[zs.size() / 2] - run.origin_z;
  run.z_max_above_p50 = zmax - run.z_p50;
  const double x0 = min_x - run.origin_x, y0 = min_y - run.origin_y;
  run.extent_x = max_x - min_x;
  run.extent_y = max_y - min_y;
  // Hold-out split by seed.
  sim::Rng rng(sim::hash_combine(cfg.seed, 77));
  std::vector<bool> held(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) held[i] = rng.uniform() < cfg.holdout_share;
  const std::vector<bool> outlier = outlier_mask(all, cfg.outlier_block_m, cfg.robust_cut_m);
  for (int variant = 0; variant < 2; ++variant) {
    LidarVariant v;
    v.name = variant == 0 ? "raw" : "cut";
    std::vector<LocalPoint> train, test;
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (variant == 1 && outlier[i]) {
        ++v.removed_outliers;
        continue;
      }
      (held[i] ? test : train).push_back(all[i]);
    }
    v.train_points = train.size();
    v.held_out_points = test.size();
    for (double w : cfg.cell_widths_m) {
      const auto evaluate_and_draw = [&](const auto& m) {
        evaluate(m, test, cfg, &v);
        if (variant != 1 || out_dir.empty()) return true;
        if (!ensure_directory(out_dir, why)) return false;
        const std::string file = out_dir + "/" + prefix + format("_%02.0fcm.png", 100.0 * w);
        const LidarMethodStats* c = v.find("CCM", w, "common");
        const LidarMethodStats* o = v.find("OMG", w, "common");
        const std::string title =
            format("%s, %.0f CM CELLS, OUTLIER CUT: HELD-OUT RMS CCM %.1f MM, CONSTANT %.1f MM (SAME POINTS)",
                   name.c_str(), 100.0 * w, 1000.0 * c->rms_m, 1000.0 * o->rms_m);
        if (!write_picture(file, m, train, cfg, run.extent_x, run.extent_y, title, why)) return false;
        if (pictures != nullptr) pictures->push_back(file);
        return true;
      };
      const bool drawn =
          cfg.paper_cell
              ? evaluate_and_draw(build_maps<CcmPaperCell>(train, x0, y0, run.extent_x, run.extent_y, w, cfg.sigma_m))
              : evaluate_and_draw(build_maps<CcmCell>(train, x0, y0, run.extent_x, run.extent_y, w, cfg.sigma_m));
      if (!drawn) return false;
    }
    run.variants.push_back(v);
  }
  run.variants.push_back(stack_variant(cfg, all, held, outlier, x0, y0, run.extent_x, run.extent_y, run.z_p50));
  run.gate = cfg.gate.describe(default_stack_params(0.08F));
  *out = run;
  return true;
}

std::string lidar_table(const LidarRun& run) {
  std::string out = format("%s: %zu points, %.1f x %.1f m; origin (%.0f, %.0f, %.0f) subtracted in double; highest return "
                           "%.1f m above the median height\n",
                           run.cloud_name.c_str(), run.points, run.extent_x, run.extent_y, run.origin_x, run.origin_y,
                           run.origin_z, run.z_max_above_p50);
  for (const LidarVariant& v : run.variants) {
    const std::string what =
        v.name == "raw"   ? std::string("every point (outliers included in maps and held-out set)")
        : v.name == "cut" ? format("%zu points > 0.30 m above their 1 m block median removed from both",
                                   v.removed_outliers)
                          : format("the library's single-layer stacks from every raw training point (one frame), "
                                   "predicting the held-out ground (%zu held-out outliers by the cut left out); "
                                   "gate on: %s",
                                   v.removed_outliers, run.gate.c_str());
    out += format("\nvariant %s: %s; %zu training, %zu held-out points\n", v.name.c_str(), what.c_str(),
                  v.train_points, v.held_out_points);
    Table t({"cell", "map", "held-out set", "evaluated", "skipped (unknown)", "RMS [mm]", "median |e| [mm]",
             "p95 |e| [mm]", "max |e| [m]"});
    for (const LidarMethodStats& s : v.stats) {
      t.add_row({format("%.0f cm", 100.0 * s.cell_width_m), s.method,
                 s.point_set == "common" ? "all maps known" : "own known cells", format("%zu", s.evaluated),
                 format("%.1f %%", 100.0 * s.skipped_share()), format("%.1f", 1000.0 * s.rms_m),
                 format("%.1f", 1000.0 * s.median_abs_m), format("%.1f", 1000.0 * s.p95_abs_m),
                 format("%.2f", s.max_abs_m)});
    }
    out += t.str();
  }
  return out;
}

}  // namespace ccmap::experiments
