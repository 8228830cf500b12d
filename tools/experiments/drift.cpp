#include "experiments/drift.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "ccmap/registration/registration.hpp"
#include "ccmap/registration/types.hpp"
#include "experiments/common.hpp"
#include "experiments/detection.hpp"
#include "experiments/svg_plot.hpp"
#include "sim/path.hpp"
#include "sim/rng.hpp"
#include "sim/stereo.hpp"
#include "sim/terrain.hpp"

namespace ccmap::experiments {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool near(double a, double b) { return std::fabs(a - b) <= 1e-9 * std::max(1.0, std::fabs(a)); }

template <typename CcmConfig>
struct DriftMap {
  std::size_t row = 0;  ///< index into DriftResult::rows
  std::unique_ptr<Stack<CcmConfig>> stack = std::make_unique<Stack<CcmConfig>>();
  // Registered maps: the corrections so far, q = R p + t (R about z), applied to the drifted pose.
  double cos_yaw = 1.0, sin_yaw = 0.0, tx = 0.0, ty = 0.0, tz = 0.0;
};

template <typename CcmConfig>
DriftResult drift_runs(const DriftConfig& cfg);

/// A registered map's frame: the drifted frame moved by the corrections so far, registered
/// against the map (except the first), the correction composed in, the frame moved by the new
/// total into *out and the corrected camera into *origin.
template <typename CcmConfig>
void register_frame_into(const Stack<CcmConfig>& s, DriftMap<CcmConfig>& m, const std::vector<PointXYZ>& points,
                         const sim::Point3& cam, bool register_it, DriftRow* row, std::vector<PointXYZ>* out,
                         PointXYZ* origin) {
  auto move = [&m](double x, double y, double z, PointXYZ* q) {
    *q = PointXYZ{static_cast<float>(m.cos_yaw * x - m.sin_yaw * y + m.tx),
                  static_cast<float>(m.sin_yaw * x + m.cos_yaw * y + m.ty), static_cast<float>(z + m.tz)};
  };
  out->resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) move(points[i].x, points[i].y, points[i].z, &(*out)[i]);
  move(cam.x, cam.y, cam.z, origin);
  if (!register_it) return;
  const RegistrationResult r = ccmap::register_frame(s, out->data(), out->size(), *origin, default_registration_params());
  if (r.status != Status::kOk) return;
  ++row->registrations;
  if (r.observable[kAxisX]) ++row->x_observable;
  // q' = Rz(a)(q - o) + o + d after q = R p + t.
  const double ca = std::cos(double(r.dyaw)), sa = std::sin(double(r.dyaw));
  const double ox = origin->x, oy = origin->y;
  const double tx = ca * (m.tx - ox) - sa * (m.ty - oy) + ox + r.dx;
  const double ty = sa * (m.tx - ox) + ca * (m.ty - oy) + oy + r.dy;
  const double c = ca * m.cos_yaw - sa * m.sin_yaw, sn = sa * m.cos_yaw + ca * m.sin_yaw;
  m.tx = tx;
  m.ty = ty;
  m.tz += r.dz;
  m.cos_yaw = c;
  m.sin_yaw = sn;
  for (std::size_t i = 0; i < points.size(); ++i) move(points[i].x, points[i].y, points[i].z, &(*out)[i]);
  move(cam.x, cam.y, cam.z, origin);
}

}  // namespace

const DriftRow* DriftResult::find(double w, double wl, double drift, bool uncertain, bool registered) const {
  for (const DriftRow& r : rows)
    if (near(r.cell_width_m, w) && near(r.weight_limit, wl) && near(r.drift_fraction, drift) &&
        r.uncertain_moves == uncertain && r.registered == registered)
      return &r;
  return nullptr;
}

DriftResult run_drift(const DriftConfig& cfg) {
  return cfg.paper_cell ? drift_runs<PaperCell<SingleCcmConfig>>(cfg) : drift_runs<SingleCcmConfig>(cfg);
}

namespace {

template <typename CcmConfig>
DriftResult drift_runs(const DriftConfig& cfg) {
  DriftResult result;
  for (const int mode : {0, 1, 2}) {  // plain, uncertain moves, registered
    if (mode == 1 && !cfg.compare_uncertain_moves) continue;
    if (mode == 2 && !cfg.compare_registration) continue;
    for (double w : cfg.cell_widths_m)
      for (double wl : cfg.weight_limits)
        for (double d : cfg.drift_fractions) {
          DriftRow r;
          r.cell_width_m = w;
          r.weight_limit = wl;
          r.drift_fraction = d;
          r.uncertain_moves = mode == 1;
          r.registered = mode == 2;
          result.rows.push_back(r);
        }
  }
  if (result.rows.empty()) return result;
  const double k_wave = 2.0 * sim::kPi / cfg.wave_wavelength_m;
  result.max_slope_deg = std::atan(cfg.wave_amplitude_m * k_wave) * 180.0 / sim::kPi;

  double max_range = 0.0;
  for (double w : cfg.cell_widths_m) max_range = std::max(max_range, ivg_max_range_m(w));
  const sim::StereoParams sp = detection_stereo_params(cfg.pixel_stride, max_range * 1.1, 0.0);
  const sim::StereoCamera camera(sp);
  const sim::WaveTerrain wave(cfg.wave_amplitude_m, cfg.wave_wavelength_m, 0.0);
  const double half_width = max_range * 0.5 * sp.width_px / sp.focal_px + 0.3;
  const sim::Rect area{-0.5, -half_width, cfg.path_length_m + max_range + 0.3, half_width};
  const sim::HeightRaster raster = sim::rasterize(wave, area, cfg.raster_resolution_m);
  const std::vector<sim::PathPose> truth =
      sim::generate_path(sim::Pose2{0.0, 0.0, 0.0}, {sim::PathSegment{cfg.path_length_m, 0.0}}, cfg.frame_spacing_m);

  // One map per (width, W_l, drift).
  std::vector<DriftMap<CcmConfig>> maps(result.rows.size());
  std::vector<std::vector<sim::Pose2>> estimates(cfg.drift_fractions.size());
  for (std::size_t d = 0; d < cfg.drift_fractions.size(); ++d) {
    sim::DriftParams dp;
    dp.fraction_of_distance = cfg.drift_fractions[d];
    dp.direction_rad = cfg.drift_direction_rad;
    estimates[d] = sim::apply_drift(truth, dp);
  }
  for (std::size_t k = 0; k < maps.size(); ++k) {
    maps[k].row = k;
    StackParams params = default_stack_params(static_cast<float>(result.rows[k].cell_width_m));
    cfg.gate.apply(&params);
    params.weight_limit = static_cast<float>(result.rows[k].weight_limit);
    if (maps[k].stack->init(params) != Status::kOk) {
      std::fprintf(stderr, "drift: map init failed\n");
      return result;
    }
  }
  auto drift_index = [&](double d) {
    for (std::size_t i = 0; i < cfg.drift_fractions.size(); ++i)
      if (near(cfg.drift_fractions[i], d)) return i;
    return std::size_t{0};
  };

  std::vector<PointXYZ> points, registered_points;
  std::size_t total_points = 0;
  const auto t_start = std::chrono::steady_clock::now();
  for (std::size_t f = 0; f < truth.size(); ++f) {
    const sim::StereoFrame frame = camera.capture(raster, truth[f].pose, sim::hash_combine(cfg.seed, 0xF10, f));
    total_points += frame.points_sensor.size();
    const double cam_z = frame.sensor_position_true.z;  // the estimator's height is not drifted
    for (std::size_t d = 0; d < cfg.drift_fractions.size(); ++d) {
      const sim::Pose2& est = estimates[d][f];
      const sim::Point3 cam{est.x, est.y, cam_z};
      points.clear();
      for (const sim::Point3& ps : frame.points_sensor) {
        const sim::Point3 p = camera.sensor_to_world(ps, cam, est.yaw);
        points.push_back(PointXYZ{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
      }
      for (DriftMap<CcmConfig>& m : maps) {
        DriftRow& row = result.rows[m.row];
        if (drift_index(row.drift_fraction) != d) continue;
        Stack<CcmConfig>& s = *m.stack;
        sim::Point3 cam_used = cam;  // the camera as the map believes: corrected if registered
        double yaw_used = est.yaw;
        PointXYZ origin{static_cast<float>(cam.x), static_cast<float>(cam.y), static_cast<float>(cam.z)};
        const std::vector<PointXYZ>* frame_points = &points;
        if (row.registered) {
          register_frame_into(s, m, points, cam, f > 0, &row, &registered_points, &origin);
          cam_used = sim::Point3{origin.x, origin.y, origin.z};
          yaw_used = est.yaw + std::atan2(m.sin_yaw, m.cos_yaw);
          frame_points = &registered_points;
        }
        // The odometry's 1-sigma error of the move since the last frame (none before the first).
        const double moved = f == 0 ? 0.0 : std::hypot(est.x - estimates[d][f - 1].x, est.y - estimates[d][f - 1].y);
        const double fraction = cfg.odometry_sigma_fraction >= 0.0 ? cfg.odometry_sigma_fraction : row.drift_fraction;
        const Status moved_status =
            row.uncertain_moves
                ? s.move_to(static_cast<float>(est.x), static_cast<float>(est.y), static_cast<float>(fraction * moved))
                : s.move_to(origin.x, origin.y);
        if (moved_status != Status::kOk ||
            s.update_frame(frame_points->data(), frame_points->size(), origin, nullptr) != Status::kOk) {
          std::fprintf(stderr, "drift: map update refused\n");
          continue;
        }
        if (f + 1 == truth.size()) {
          row.final_pose_error_m = std::hypot(cam_used.x - frame.sensor_position_true.x, cam_used.y - frame.sensor_position_true.y);
        }
        // Cells this frame observes, as the map believes (drifted camera).
        const double w = row.cell_width_m;
        const float wf = static_cast<float>(w);
        const double range = ivg_max_range_m(w);
        const double reach = range * std::sqrt(1.0 + 0.25 * sp.width_px * sp.width_px / (sp.focal_px * sp.focal_px));
        const auto i0 = static_cast<std::int32_t>(std::floor((cam_used.x - reach) / w));
        const auto i1 = static_cast<std::int32_t>(std::floor((cam_used.x + reach) / w));
        const auto j0 = static_cast<std::int32_t>(std::floor((cam_used.y - reach) / w));
        const auto j1 = static_cast<std::int32_t>(std::floor((cam_used.y + reach) / w));
        for (std::int32_t jj = j0; jj <= j1; ++jj) {
          for (std::int32_t i = i0; i <= i1; ++i) {
            // The in-view test needs the ground height only roughly: the wave at the map position.
            if (!whole_cell_in_view(sp, cam_used, yaw_used, raster, i * w, jj * w, w, range)) continue;
            const QueryResult q = s.query_layer(0, grid::cell_centre(i, wf), grid::cell_centre(jj, wf));
            if (q.status != Status::kOk || q.cell_class == CellClass::kUnknown) {
              ++row.unknown;
              continue;
            }
            ++row.known;
            if (q.cell_class == CellClass::kObstacle || q.cell_class == CellClass::kSteep) ++row.false_obstacle;
          }
        }
      }
    }
    if (cfg.progress && (f + 1) % std::max<std::size_t>(1, truth.size() / 10) == 0) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      std::fprintf(stderr, "fig10: frame %zu/%zu, %.0f s elapsed\n", f + 1, truth.size(), elapsed);
    }
  }
  result.points_per_frame = truth.empty() ? 0.0 : static_cast<double>(total_points) / static_cast<double>(truth.size());
  return result;
}

}  // namespace

double drift_crossing(const DriftResult& result, double w, double wl, double tolerance, bool uncertain, bool registered) {
  std::vector<const DriftRow*> rows;
  for (const DriftRow& r : result.rows)
    if (near(r.cell_width_m, w) && near(r.weight_limit, wl) && r.uncertain_moves == uncertain && r.registered == registered)
      rows.push_back(&r);
  std::sort(rows.begin(), rows.end(), [](const DriftRow* a, const DriftRow* b) { return a->drift_fraction < b->drift_fraction; });
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i]->share() > tolerance) {
      if (i == 0) return 0.0;
      const double s0 = rows[i - 1]->share(), s1 = rows[i]->share();
      const double t = (tolerance - s0) / (s1 - s0);
      return rows[i - 1]->drift_fraction + t * (rows[i]->drift_fraction - rows[i - 1]->drift_fraction);
    }
  }
  return kNaN;
}

std::string drift_table(const DriftConfig& cfg, const DriftResult& result) {
  std::string o = format("wave terrain A = %.0f mm, lambda = %.2f m (max slope %.1f deg), path %.1f m, a frame every %.2f m, "
                         "%.0f points per frame (stride %d)\n\n",
                         cfg.wave_amplitude_m * 1000, cfg.wave_wavelength_m, result.max_slope_deg, cfg.path_length_m,
                         cfg.frame_spacing_m, result.points_per_frame, cfg.pixel_stride);
  Table t({"moves", "cell", "W_l", "drift", "known cell-frames", "false obstacle", "share", "unknown cell-frames",
           "final pose error", "registered (x observable)"});
  for (const DriftRow& r : result.rows) {
    t.add_row({r.registered ? "registered" : (r.uncertain_moves ? "uncertain" : "plain"), format("%.0f cm", r.cell_width_m * 100), format("%.0f", r.weight_limit),
               format("%.0f%%", r.drift_fraction * 100),
               format("%llu", static_cast<unsigned long long>(r.known)),
               format("%llu", static_cast<unsigned long long>(r.false_obstacle)), format("%.2f%%", 100.0 * r.share()),
               format("%llu", static_cast<unsigned long long>(r.unknown)), format("%.1f mm", 1000.0 * r.final_pose_error_m),
               r.registered ? format("%llu (%llu)", static_cast<unsigned long long>(r.registrations),
                                     static_cast<unsigned long long>(r.x_observable))
                            : std::string("-")});
  }
  o += t.str();
  o += format("\ndrift at which the false-obstacle share exceeds %.0f %%:\n\n", cfg.tolerance * 100);
  std::vector<std::string> head{"cell", "W_l", "withstands drift up to"};
  if (cfg.compare_uncertain_moves) head.push_back("with uncertain moves");
  if (cfg.compare_registration) head.push_back("with registration");
  head.push_back("paper (chosen W_l)");
  Table c(head);
  auto crossing = [&](double w, double wl, bool uncertain, bool registered = false) {
    const double x = drift_crossing(result, w, wl, cfg.tolerance, uncertain, registered);
    return std::isfinite(x) ? format("%.1f %%", 100.0 * x)
                            : format("> %.0f %% (never crossed)", 100.0 * cfg.drift_fractions.back());
  };
  for (double w : cfg.cell_widths_m)
    for (double wl : cfg.weight_limits) {
      std::string paper;
      if (near(wl, cfg.chosen_weight_limit)) {
        if (near(w, 0.04)) paper = "8 %";
        if (near(w, 0.08)) paper = "16 %";
      }
      std::vector<std::string> row{format("%.0f cm", w * 100), format("%.0f", wl), crossing(w, wl, false)};
      if (cfg.compare_uncertain_moves) row.push_back(crossing(w, wl, true));
      if (cfg.compare_registration) row.push_back(crossing(w, wl, false, true));
      row.push_back(paper);
      c.add_row(row);
    }
  std::string sigma = cfg.odometry_sigma_fraction >= 0.0 ? format("%.0f %% of the distance moved", 100.0 * cfg.odometry_sigma_fraction)
                                                          : std::string("the run's drift fraction x the distance moved");
  if (cfg.compare_uncertain_moves) o += "uncertain moves: Stack::move_to(x, y, sigma), sigma = " + sigma + "\n\n";
  return o + c.str();
}

bool write_drift_outputs(const DriftConfig& cfg, const DriftResult& result, const std::string& out_dir, std::string* error) {
  if (!ensure_directory(out_dir, error)) return false;
  SvgPlot p;
  p.title = format("Fig. 10: drift resilience, wave terrain A %.0f mm / %.1f m", cfg.wave_amplitude_m * 1000, cfg.wave_wavelength_m);
  p.x_label = "pose drift [% of distance travelled]";
  p.y_label = "observed traversable ground marked obstacle [%]";
  p.x_scale = 100.0;
  p.y_scale = 100.0;
  p.y_min = 0.0;
  p.x_min = 0.0;
  int colour = 0;
  for (std::size_t k = 0; k < cfg.cell_widths_m.size(); ++k) {
    for (double wl : cfg.weight_limits) {
      const std::string colour_name = palette_color(colour++);
      for (const int mode : {0, 1, 2}) {
        const bool uncertain = mode == 1, registered = mode == 2;
        if (uncertain && (!cfg.compare_uncertain_moves || !near(wl, cfg.chosen_weight_limit))) continue;
        if (registered && (!cfg.compare_registration || !near(wl, cfg.chosen_weight_limit))) continue;
        SvgSeries s;
        s.name = format("%.0f cm, W_l %.0f%s", cfg.cell_widths_m[k] * 100, wl,
                        uncertain ? ", uncertain moves" : (registered ? ", registration" : ""));
        for (const DriftRow& r : result.rows)
          if (near(r.cell_width_m, cfg.cell_widths_m[k]) && near(r.weight_limit, wl) && r.uncertain_moves == uncertain &&
              r.registered == registered) {
            s.x.push_back(r.drift_fraction);
            s.y.push_back(r.share());
          }
        s.color = colour_name;
        s.dashed = !near(wl, cfg.chosen_weight_limit) || uncertain;
        s.dotted = registered;
        s.markers = true;
        p.series.push_back(s);
      }
    }
  }
  p.ref_lines.push_back(SvgRefLine{cfg.tolerance, false, format("tolerance %.0f %%", cfg.tolerance * 100)});
  p.ref_lines.push_back(SvgRefLine{0.08, true, "paper 4 cm: 8 %"});
  p.ref_lines.push_back(SvgRefLine{0.16, true, "paper 8 cm: 16 %"});
  if (!write_svg(out_dir + "/fig10.svg", p, error)) return false;
  std::ofstream csv(out_dir + "/fig10.csv");
  csv << "cell_m,weight_limit,drift_fraction,uncertain_moves,known,false_obstacle,unknown,share,registered,"
         "registrations,x_observable,final_pose_error_m\n";
  for (const DriftRow& r : result.rows)
    csv << r.cell_width_m << ',' << r.weight_limit << ',' << r.drift_fraction << ',' << (r.uncertain_moves ? 1 : 0) << ','
        << r.known << ',' << r.false_obstacle << ',' << r.unknown << ',' << r.share() << ',' << (r.registered ? 1 : 0) << ','
        << r.registrations << ',' << r.x_observable << ',' << r.final_pose_error_m << '\n';
  if (!csv) {
    if (error != nullptr) *error = "cannot write " + out_dir + "/fig10.csv";
    return false;
  }
  return true;
}

}  // namespace ccmap::experiments
