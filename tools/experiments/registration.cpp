#include "experiments/registration.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "ccmap/registration/registration.hpp"
#include "cloud_reader.hpp"
#include "experiments/common.hpp"
#include "experiments/svg_plot.hpp"
#include "sim/data_dir.hpp"
#include "sim/rng.hpp"
#include "sim/terrain.hpp"

namespace ccmap::experiments {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct P3 {
  double x, y, z;
};

/// A terrain as two independent samples (the map's and the frame's) over a valid area, and the
/// ground height under a point (for the sensor's height).
struct Source {
  RegistrationTerrainInfo info;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;      ///< where disk centres may lie
  double sigma_m = 0.005;                     ///< the map's lidar noise model
  double sensor_height_m = 1.5;
  double yaw_lever_m = 4.0;
  std::function<void(double cx, double cy, double r, int which, std::uint64_t seed, std::vector<P3>*)> sample;
  std::function<double(double x, double y)> ground;  ///< NaN where unknown
};

/// Points of a cloud (local metres) in a coarse grid of buckets, for disk queries.
struct Buckets {
  double x0 = 0, y0 = 0, size = 1.0;
  int nx = 0, ny = 0;
  std::vector<std::vector<P3>> cells;
  void build(const std::vector<P3>& pts, double bucket) {
    size = bucket;
    double mx = pts.empty() ? 0 : pts[0].x, my = pts.empty() ? 0 : pts[0].y, Mx = mx, My = my;
    for (const P3& p : pts) {
      mx = std::min(mx, p.x);
      my = std::min(my, p.y);
      Mx = std::max(Mx, p.x);
      My = std::max(My, p.y);
    }
    x0 = mx;
    y0 = my;
    nx = static_cast<int>((Mx - mx) / size) + 1;
    ny = static_cast<int>((My - my) / size) + 1;
    cells.assign(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny), {});
    for (const P3& p : pts) cells[index(p.x, p.y)].push_back(p);
  }
  std::size_t index(double x, double y) const {
    const int i = std::clamp(static_cast<int>((x - x0) / size), 0, nx - 1);
    const int j = std::clamp(static_cast<int>((y - y0) / size), 0, ny - 1);
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i);
  }
  void disk(double cx, double cy, double r, std::vector<P3>* out) const {
    out->clear();
    const int i0 = std::max(0, static_cast<int>((cx - r - x0) / size)), i1 = std::min(nx - 1, static_cast<int>((cx + r - x0) / size));
    const int j0 = std::max(0, static_cast<int>((cy - r - y0) / size)), j1 = std::min(ny - 1, static_cast<int>((cy + r - y0) / size));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        for (const P3& p : cells[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i)])
          if ((p.x - cx) * (p.x - cx) + (p.y - cy) * (p.y - cy) <= r * r) out->push_back(p);
  }
  /// Median height of the points within r of (x, y); NaN without any.
  double ground(double x, double y, double r) const {
    std::vector<P3> near;
    disk(x, y, r, &near);
    if (near.empty()) return kNaN;
    std::vector<double> z;
    for (const P3& p : near) z.push_back(p.z);
    std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
    return z[z.size() / 2];
  }
};

/// Distance between two disks' centres whose common area is `share` of one disk (radius r).
double centre_distance(double share, double r) {
  auto lens = [r](double d) {  // common area / disk area
    if (d >= 2 * r) return 0.0;
    const double a = 2 * r * r * std::acos(d / (2 * r)) - 0.5 * d * std::sqrt(4 * r * r - d * d);
    return a / (kPi * r * r);
  };
  double lo = 0.0, hi = 2 * r;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (lens(mid) > share ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

const char* terrain_name(RegistrationTerrain t) {
  switch (t) {
    case RegistrationTerrain::kLoneStar: return "lone_star";
    case RegistrationTerrain::kMarsDtm: return "mars_dtm";
    case RegistrationTerrain::kFlat: return "flat";
    case RegistrationTerrain::kSinusoid: return "sinusoid";
  }
  return "?";
}

/// The Lone Star scan: local metres (floor of the minimum x, y; the median z), even and odd points.
bool lone_star_source(const std::string& data_dir, Source* s, std::shared_ptr<Buckets> halves[2]) {
  const std::string path = data_dir + "/lone_star_tls/lone-star.las";
  if (!sim::data_file_available(path, &s->info.why)) return false;
  const tools::Cloud cloud = tools::read_cloud(path);
  if (!cloud.ok() || cloud.size() == 0) {
    s->info.why = "cannot read " + path;
    return false;
  }
  double mx = cloud.x[0], my = cloud.y[0];
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    mx = std::min(mx, cloud.x[i]);
    my = std::min(my, cloud.y[i]);
  }
  std::vector<double> zs(cloud.z);
  std::nth_element(zs.begin(), zs.begin() + static_cast<std::ptrdiff_t>(zs.size() / 2), zs.end());
  const double ox = std::floor(mx), oy = std::floor(my), oz = std::round(zs[zs.size() / 2]);
  std::vector<P3> pts[2];
  for (std::size_t i = 0; i < cloud.size(); ++i) pts[i % 2].push_back(P3{cloud.x[i] - ox, cloud.y[i] - oy, cloud.z[i] - oz});
  for (int h = 0; h < 2; ++h) {
    halves[h] = std::make_shared<Buckets>();
    halves[h]->build(pts[h], 0.5);
  }
  s->x0 = halves[0]->x0 + 6.0;
  s->y0 = halves[0]->y0 + 6.0;
  s->x1 = halves[0]->x0 + halves[0]->nx * 0.5 - 6.0;
  s->y1 = halves[0]->y0 + halves[0]->ny * 0.5 - 6.0;
  std::shared_ptr<Buckets> a = halves[0], b = halves[1];
  s->sample = [a, b](double cx, double cy, double r, int which, std::uint64_t, std::vector<P3>* out) {
    (which == 0 ? a : b)->disk(cx, cy, r, out);
  };
  s->ground = [a](double x, double y) { return a->ground(x, y, 0.5); };
  return true;
}

}  // namespace

RegistrationExpResult run_registration_experiment(const RegistrationExpConfig& cfg) {
  RegistrationExpResult result;
  for (const RegistrationTerrain t : cfg.terrains) {
    Source s;
    s.info.terrain = t;
    std::shared_ptr<Buckets> halves[2];
    auto dtm = std::make_shared<sim::HeightRaster>();
    if (t == RegistrationTerrain::kLoneStar) {
      s.info.name = "Lone Star scan (TLS: half of its points each, ~200 points/m^2; 20 cm cells, 4 m disks)";
      s.info.cell_m = 0.2;
      s.info.radius_m = 4.0;
      s.info.available = lone_star_source(sim::resolve_data_dir(cfg.data_dir), &s, halves);
    } else if (t == RegistrationTerrain::kMarsDtm) {
      s.info.name = "HiRISE Mars DTM (1 m pixels sampled at 25 points/m^2, sigma 5 cm; 1 m cells, 20 m disks)";
      s.info.cell_m = 1.0;
      s.info.radius_m = 20.0;
      s.info.scale_m = 10.0;
      s.sigma_m = 0.05;
      s.sensor_height_m = 2.0;
      s.yaw_lever_m = 20.0;
      const std::string path = sim::mars_dtm_path(sim::resolve_data_dir(cfg.data_dir));
      s.info.available = sim::data_file_available(path, &s.info.why) && sim::load_esri_ascii(path, dtm.get(), &s.info.why);
      if (s.info.available) {
        dtm->shift_heights(-dtm->mean_height());
        const sim::Rect e = dtm->extent();
        s.x0 = e.x0 + 21.0;
        s.y0 = e.y0 + 21.0;
        s.x1 = e.x1 - 21.0;
        s.y1 = e.y1 - 21.0;
        s.sample = [dtm](double cx, double cy, double r, int, std::uint64_t seed, std::vector<P3>* out) {
          out->clear();
          sim::Rng rng(seed);
          const auto n = static_cast<std::size_t>(25.0 * kPi * r * r);
          for (std::size_t i = 0; i < n; ++i) {
            const double rr = r * std::sqrt(rng.uniform()), a = rng.uniform(0.0, 2 * kPi);
            const double x = cx + rr * std::cos(a), y = cy + rr * std::sin(a);
            const double z = dtm->height(x, y);
            if (std::isfinite(z)) out->push_back(P3{x, y, z + 0.05 * rng.normal()});
          }
        };
        s.ground = [dtm](double x, double y) { return dtm->height(x, y); };
      }
    } else {
      const bool flat = t == RegistrationTerrain::kFlat;
      s.info.name = flat ? "flat ground (synthetic, 2000 points/m^2, 3 mm noise; 8 cm cells, 4 m disks)"
                         : "sinusoid along x, 5 cm / 0.8 m (synthetic as flat ground)";
      s.info.cell_m = 0.08;
      s.info.radius_m = 4.0;
      s.x0 = s.y0 = -5.0;
      s.x1 = s.y1 = 5.0;
      auto height = [flat](double x, double) { return flat ? 0.0 : 0.05 * std::sin(2 * kPi * x / 0.8); };
      s.sample = [height](double cx, double cy, double r, int, std::uint64_t seed, std::vector<P3>* out) {
        out->clear();
        sim::Rng rng(seed);
        const auto n = static_cast<std::size_t>(2000.0 * kPi * r * r);
        for (std::size_t i = 0; i < n; ++i) {
          const double rr = r * std::sqrt(rng.uniform()), a = rng.uniform(0.0, 2 * kPi);
          const double x = cx + rr * std::cos(a), y = cy + rr * std::sin(a);
          out->push_back(P3{x, y, height(x, y) + 0.003 * rng.normal()});
        }
      };
      s.ground = height;
    }
    result.terrains.push_back(s.info);
    if (!s.info.available) continue;

    auto map = std::make_unique<Stack<SingleCcmConfig>>();
    StackParams params = default_stack_params(static_cast<float>(s.info.cell_m));
    params.noise = sensor::NoiseModel::lidar(sensor::LidarParams{static_cast<float>(s.sigma_m), 0.0F});
    params.outlier_gate_sigma = 0.0F;
    RegistrationParams rp = default_registration_params();
    double largest = 0.0;
    for (double o : cfg.offsets) largest = std::max(largest, o * s.info.scale_m);
    rp.max_translation_m = static_cast<float>(std::max(0.5, 1.5 * largest));
    rp.max_iterations = 40U;
    std::vector<P3> map_pts, frame_pts;
    std::vector<PointXYZ> pts;
    for (const double overlap : cfg.overlaps) {
      const double d = centre_distance(overlap, s.info.radius_m);
      for (const double offset_share : cfg.offsets) {
        const double offset = offset_share * s.info.scale_m;
        RegistrationCell cell;
        cell.terrain = t;
        cell.overlap = overlap;
        cell.offset_m = offset;
        std::vector<double> exy, ez, eyaw, sxy;
        sim::Rng rng(sim::hash_combine(cfg.seed, static_cast<std::uint64_t>(t) * 1000003ULL +
                                                     static_cast<std::uint64_t>(overlap * 1000) * 1009ULL +
                                                     static_cast<std::uint64_t>(offset_share * 1e6)));
        for (int k = 0; k < cfg.trials; ++k) {
          // Centres inside the valid area, ground under both.
          double ax = 0, ay = 0, bx = 0, by = 0, az = kNaN, bz = kNaN;
          for (int tries = 0; tries < 50 && !(std::isfinite(az) && std::isfinite(bz)); ++tries) {
            ax = rng.uniform(s.x0, s.x1);
            ay = rng.uniform(s.y0, s.y1);
            const double dir = rng.uniform(0.0, 2 * kPi);
            bx = ax + d * std::cos(dir);
            by = ay + d * std::sin(dir);
            az = s.ground(ax, ay);
            bz = s.ground(bx, by);
          }
          const double shift_dir = rng.uniform(0.0, 2 * kPi);
          const double cdx = offset * std::cos(shift_dir), cdy = offset * std::sin(shift_dir);
          const double cdz = offset / 3.0 * (rng.uniform() < 0.5 ? -1.0 : 1.0);
          const double cyaw = offset / s.yaw_lever_m * (rng.uniform() < 0.5 ? -1.0 : 1.0);
          ++cell.trials;
          if (!(std::isfinite(az) && std::isfinite(bz))) {
            cell.statuses.push_back("no ground");
            continue;
          }
          const std::uint64_t seed = rng.next_u64();
          s.sample(ax, ay, s.info.radius_m, 0, seed, &map_pts);
          s.sample(bx, by, s.info.radius_m, 1, seed ^ 0x5555ULL, &frame_pts);
          // Map: one frame from above A, the stack centred there (local float frame around A).
          if (map->init(params) != Status::kOk || map->move_to(static_cast<float>(ax), static_cast<float>(ay)) != Status::kOk) {
            cell.statuses.push_back("init");
            continue;
          }
          pts.clear();
          for (const P3& p : map_pts) pts.push_back(PointXYZ{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
          (void)map->update_frame(pts.data(), pts.size(),
                                  PointXYZ{static_cast<float>(ax), static_cast<float>(ay), static_cast<float>(az + s.sensor_height_m)},
                                  nullptr);
          // Frame: moved by C^-1 about the sensor above B.
          const double ox = bx, oy = by, oz = bz + s.sensor_height_m;
          const double cs = std::cos(-cyaw), sn = std::sin(-cyaw);
          pts.clear();
          for (const P3& p : frame_pts) {
            const double x = p.x - ox - cdx, y = p.y - oy - cdy;
            pts.push_back(PointXYZ{static_cast<float>(ox + cs * x - sn * y), static_cast<float>(oy + sn * x + cs * y),
                                   static_cast<float>(p.z - cdz)});
          }
          const RegistrationResult r = ccmap::register_frame(*map, 
              pts.data(), pts.size(), PointXYZ{static_cast<float>(ox), static_cast<float>(oy), static_cast<float>(oz)}, rp);
          if (r.status != Status::kOk) {
            cell.statuses.push_back(to_string(r.status));
            continue;
          }
          ++cell.ok;
          const double err[4] = {r.dx - cdx, r.dy - cdy, r.dz - cdz, r.dyaw - cyaw};
          const double sig[4] = {r.sigma_dx, r.sigma_dy, r.sigma_dz, r.sigma_dyaw};
          const double floor_err[4] = {0.002, 0.002, 0.002, 0.0005};
          for (int a = 0; a < 4; ++a) {
            if (!r.observable[a]) continue;
            ++cell.axes_claimed;
            if (std::fabs(err[a]) > 3.0 * sig[a] + floor_err[a]) ++cell.over_claims;
          }
          cell.claimed_x += r.observable[kAxisX] ? 1 : 0;
          cell.claimed_y += r.observable[kAxisY] ? 1 : 0;
          if (r.observable[kAxisX] || r.observable[kAxisY]) {
            const double ex = r.observable[kAxisX] ? err[0] : 0.0, ey = r.observable[kAxisY] ? err[1] : 0.0;
            const double sx = r.observable[kAxisX] ? sig[0] : 0.0, sy = r.observable[kAxisY] ? sig[1] : 0.0;
            exy.push_back(std::hypot(ex, ey));
            sxy.push_back(std::hypot(sx, sy));
          }
          if (r.observable[kAxisZ]) {
            ++cell.claimed_z;
            ez.push_back(std::fabs(err[2]));
          }
          if (r.observable[kAxisYaw]) {
            ++cell.claimed_yaw;
            eyaw.push_back(std::fabs(err[3]));
          }
        }
        auto median = [](std::vector<double> v) {
          if (v.empty()) return kNaN;
          std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
          return v[v.size() / 2];
        };
        cell.median_xy_error_m = median(exy);
        cell.median_z_error_m = median(ez);
        cell.median_yaw_error_rad = median(eyaw);
        cell.median_xy_sigma_m = median(sxy);
        result.cells.push_back(cell);
      }
    }
  }
  return result;
}

std::string registration_table(const RegistrationExpResult& r) {
  std::string o;
  for (const RegistrationTerrainInfo& t : r.terrains) {
    o += format("%s: %s\n", terrain_name(t.terrain), t.available ? t.name.c_str() : ("skipped: " + t.why).c_str());
    if (!t.available) continue;
    Table table({"overlap", "offset", "ok", "x / y claimed", "xy error (median)", "xy sigma (median)", "z claimed",
                 "z error", "yaw claimed", "yaw error", "over-claims", "refusals"});
    for (const RegistrationCell& c : r.cells) {
      if (c.terrain != t.terrain) continue;
      std::string refusals;
      for (const std::string& st : c.statuses) {
        if (refusals.find(st) == std::string::npos) refusals += (refusals.empty() ? "" : ", ") + st;
      }
      auto mm = [](double v) { return std::isfinite(v) ? format("%.1f mm", 1000.0 * v) : std::string("-"); };
      table.add_row({format("%.0f %%", 100 * c.overlap), format("%.3f m", c.offset_m), format("%d/%d", c.ok, c.trials),
                     format("%d / %d", c.claimed_x, c.claimed_y), mm(c.median_xy_error_m), mm(c.median_xy_sigma_m), format("%d", c.claimed_z),
                     mm(c.median_z_error_m), format("%d", c.claimed_yaw),
                     std::isfinite(c.median_yaw_error_rad) ? format("%.2f mrad", 1000.0 * c.median_yaw_error_rad) : std::string("-"),
                     format("%d of %d", c.over_claims, c.axes_claimed), refusals.empty() ? std::string("-") : refusals});
    }
    o += table.str() + "\n";
  }
  return o;
}

bool write_registration_outputs(const RegistrationExpResult& r, const std::string& out_dir, std::string* error) {
  if (!ensure_directory(out_dir, error)) return false;
  std::ofstream csv(out_dir + "/registration.csv");
  csv << "terrain,overlap,offset_m,trials,ok,claimed_x,claimed_y,median_xy_error_m,median_xy_sigma_m,claimed_z,median_z_error_m,"
         "claimed_yaw,median_yaw_error_rad,axes_claimed,over_claims\n";
  for (const RegistrationCell& c : r.cells) {
    csv << terrain_name(c.terrain) << ',' << c.overlap << ',' << c.offset_m << ',' << c.trials << ',' << c.ok << ','
        << c.claimed_x << ',' << c.claimed_y << ',' << c.median_xy_error_m << ',' << c.median_xy_sigma_m << ',' << c.claimed_z << ','
        << c.median_z_error_m << ',' << c.claimed_yaw << ',' << c.median_yaw_error_rad << ',' << c.axes_claimed << ','
        << c.over_claims << '\n';
  }
  if (!csv) {
    *error = "cannot write " + out_dir + "/registration.csv";
    return false;
  }
  for (const RegistrationTerrainInfo& t : r.terrains) {
    if (!t.available) continue;
    SvgPlot p;
    p.title = format("Registration: %s", t.name.c_str());
    p.x_label = "injected horizontal offset [m] (and a third of it in z, offset / lever in yaw)";
    p.y_label = "horizontal error of what was claimed, median [mm]";
    p.y_scale = 1000.0;
    p.x_min = 0.0;
    p.y_min = 0.0;
    int colour = 0;
    std::vector<double> overlaps;
    for (const RegistrationCell& c : r.cells)
      if (c.terrain == t.terrain && std::find(overlaps.begin(), overlaps.end(), c.overlap) == overlaps.end())
        overlaps.push_back(c.overlap);
    for (const double ov : overlaps) {
      SvgSeries s;
      s.name = format("overlap %.0f %%", 100 * ov);
      for (const RegistrationCell& c : r.cells) {
        if (c.terrain != t.terrain || c.overlap != ov) continue;
        s.x.push_back(c.offset_m);
        s.y.push_back(c.median_xy_error_m);
      }
      s.color = palette_color(colour++);
      s.markers = true;
      p.series.push_back(s);
    }
    if (!write_svg(out_dir + "/registration_" + terrain_name(t.terrain) + ".svg", p, error)) return false;
  }
  return true;
}

}  // namespace ccmap::experiments
