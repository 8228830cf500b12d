#include "experiments/fig4.hpp"

#include <cmath>
#include <fstream>
#include <limits>

#include "ccmap/cell/ccm_cell.hpp"
#include "experiments/common.hpp"
#include "experiments/svg_plot.hpp"
#include "sim/rng.hpp"

namespace ccmap::experiments {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

template <typename Cell>
double normal_variance_of(const Cell& cell) { return static_cast<double>(ccm_surface(cell).normal_variance); }

template <typename Cell>
void feed(Cell& cell, double x, double y, double z) {
  // Points are finite and small: ccm_update cannot refuse them; a refusal would be a bug.
  if (ccm_update(cell, static_cast<float>(x), static_cast<float>(y), static_cast<float>(z), 1.0F, kNoWeightLimit) !=
      Status::kOk) {
    cell.weight = std::numeric_limits<float>::quiet_NaN();
  }
}

}  // namespace

double fig4_analytic_normal_variance(double coverage, double step_height_m) {
  const double u = coverage * (1.0 - coverage);
  return step_height_m * step_height_m * u * (1.0 - 3.0 * u);
}

CoverageInterval coverage_interval(const Fig4Curve& curve, double threshold) {
  CoverageInterval out{kNaN, kNaN};
  const std::vector<double>& c = curve.coverage;
  const std::vector<double>& v = curve.normal_variance;
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (v[k] >= threshold) {
      out.lo = (k == 0) ? c[0] : c[k - 1] + (threshold - v[k - 1]) / (v[k] - v[k - 1]) * (c[k] - c[k - 1]);
      break;
    }
  }
  for (std::size_t k = v.size(); k-- > 0;) {
    if (v[k] >= threshold) {
      out.hi = (k + 1 == v.size()) ? c[k] : c[k] + (v[k] - threshold) / (v[k] - v[k + 1]) * (c[k + 1] - c[k]);
      break;
    }
  }
  return out;
}

namespace {

template <typename Cell>
Fig4Result fig4_curves(const Fig4Config& cfg) {
  Fig4Result r;
  const double w = cfg.cell_width_m, h = cfg.step_height_m;
  const int n = cfg.grid_n + (cfg.grid_n % 2);  // even, so that c = 0.5 is on the grid
  // Noiseless regular grid.
  for (int k = 0; k <= n; ++k) {
    Cell cell{};
    for (int j = 0; j < n; ++j) {
      const double y = -0.5 * w + (j + 0.5) * w / n;
      for (int i = 0; i < n; ++i) {
        const double x = -0.5 * w + (i + 0.5) * w / n;
        feed(cell, x, y, i >= n - k ? h : 0.0);  // the far k columns are covered
      }
    }
    const double c = static_cast<double>(k) / n;
    r.noiseless.coverage.push_back(c);
    r.noiseless.normal_variance.push_back(normal_variance_of(cell));
  }
  r.threshold = r.noiseless.normal_variance[static_cast<std::size_t>(n / 2)];
  r.interval = coverage_interval(r.noiseless, r.threshold);
  for (int k = 0; k <= 400; ++k) {
    const double c = k / 400.0;
    r.analytic.coverage.push_back(c);
    r.analytic.normal_variance.push_back(fig4_analytic_normal_variance(c, h));
  }
  r.analytic_threshold = h * h / 16.0;
  const double c_lo = 0.5 * (1.0 - std::sqrt(1.0 - 4.0 / 12.0));
  r.analytic_interval = CoverageInterval{c_lo, 1.0 - c_lo};

  // Stereo-like noise along the line of sight.
  const int levels = cfg.noisy_levels + (cfg.noisy_levels % 2);
  const double fb = cfg.focal_px * cfg.baseline_m;
  const double sigma_d = std::sqrt(cfg.disparity_sigma_px * cfg.disparity_sigma_px +
                                   cfg.disparity_step_px * cfg.disparity_step_px / 12.0);
  for (std::size_t ri = 0; ri < cfg.noisy_ranges_m.size(); ++ri) {
    Fig4NoisyCurve nc;
    nc.range_m = cfg.noisy_ranges_m[ri];
    nc.depth_sigma_m = nc.range_m * nc.range_m / fb * sigma_d;
    sim::Rng rng(sim::hash_combine(cfg.seed, 4, ri));
    const double cam_x = -nc.range_m, cam_z = cfg.camera_height_m;  // camera on the -x side
    for (int k = 0; k <= levels; ++k) {
      const double c = static_cast<double>(k) / levels;
      double sum = 0.0;
      for (int t = 0; t < cfg.noisy_trials; ++t) {
        Cell cell{};
        for (int p = 0; p < cfg.noisy_points; ++p) {
          const double x = rng.uniform(-0.5 * w, 0.5 * w), y = rng.uniform(-0.5 * w, 0.5 * w);
          const double z = x >= 0.5 * w - c * w ? h : 0.0;
          const double lx = x - cam_x, ly = y, lz = z - cam_z;
          const double range = std::sqrt(lx * lx + ly * ly + lz * lz);
          const double e = rng.normal(0.0, range * range / fb * sigma_d) / range;
          feed(cell, x + e * lx, y + e * ly, z + e * lz);
        }
        sum += normal_variance_of(cell);
      }
      nc.curve.coverage.push_back(c);
      nc.curve.normal_variance.push_back(sum / cfg.noisy_trials);
    }
    nc.threshold = nc.curve.normal_variance[static_cast<std::size_t>(levels / 2)];
    nc.interval = coverage_interval(nc.curve, nc.threshold);
    nc.interval_noiseless_threshold = coverage_interval(nc.curve, r.threshold);
    r.noisy.push_back(nc);
  }
  return r;
}

}  // namespace

Fig4Result run_fig4(const Fig4Config& cfg) {
  return cfg.paper_cell ? fig4_curves<CcmPaperCell>(cfg) : fig4_curves<CcmCell>(cfg);
}

bool write_fig4_outputs(const Fig4Config& cfg, const Fig4Result& r, const std::string& out_dir, std::string* error) {
  if (!ensure_directory(out_dir, error)) return false;
  SvgPlot plot;
  plot.title = format("Fig. 4: CCM normal variance vs obstacle coverage (%.0f cm cell, %.0f cm step)",
                      cfg.cell_width_m * 100, cfg.step_height_m * 100);
  plot.x_label = "obstacle coverage of the cell [%]";
  plot.y_label = "surface-normal variance sigma_s^2 [cm^2]";
  plot.x_scale = 100.0;
  plot.y_scale = 1.0e4;
  plot.x_min = 0.0;
  plot.x_max = 1.0;
  plot.y_min = 0.0;
  SvgSeries analytic{"analytic h^2 u(1-3u), u=c(1-c)", r.analytic.coverage, r.analytic.normal_variance, "#999999", true, false, 2.0};
  SvgSeries grid{"CCM cell, noiseless grid", r.noiseless.coverage, r.noiseless.normal_variance, "#1f77b4", false, false, 2.5};
  plot.series.push_back(grid);
  plot.series.push_back(analytic);
  for (std::size_t i = 0; i < r.noisy.size(); ++i) {
    const Fig4NoisyCurve& nc = r.noisy[i];
    plot.series.push_back(SvgSeries{format("stereo noise at %.0f m (sigma_Z %.1f cm)", nc.range_m, nc.depth_sigma_m * 100),
                                    nc.curve.coverage, nc.curve.normal_variance, palette_color(static_cast<int>(i) + 1),
                                    false, true, 1.5});
  }
  plot.ref_lines.push_back(SvgRefLine{r.threshold, false, format("threshold = sigma_s^2(50%%) = %.1f cm^2", r.threshold * 1e4), "#d62728"});
  plot.ref_lines.push_back(SvgRefLine{r.interval.lo, true, format("%.1f%%", r.interval.lo * 100), "#d62728"});
  plot.ref_lines.push_back(SvgRefLine{r.interval.hi, true, format("%.1f%%", r.interval.hi * 100), "#d62728"});
  if (!write_svg(out_dir + "/fig4.svg", plot, error)) return false;
  std::ofstream csv(out_dir + "/fig4.csv");
  if (!csv) {
    if (error != nullptr) *error = "cannot write " + out_dir + "/fig4.csv";
    return false;
  }
  csv << "coverage,normal_variance_noiseless_m2,normal_variance_analytic_m2\n";
  for (std::size_t k = 0; k < r.noiseless.coverage.size(); ++k) {
    const double c = r.noiseless.coverage[k];
    csv << c << ',' << r.noiseless.normal_variance[k] << ',' << fig4_analytic_normal_variance(c, cfg.step_height_m) << '\n';
  }
  return static_cast<bool>(csv);
}

std::string fig4_table(const Fig4Config& cfg, const Fig4Result& r) {
  Table t({"case", "threshold sigma_s^2 [cm^2]", "detected coverage", "paper"});
  t.add_row({"analytic (h^2/16; c(1-c) >= 1/12)", format("%.3f", r.analytic_threshold * 1e4),
             format("%.1f%% - %.1f%%", r.analytic_interval.lo * 100, r.analytic_interval.hi * 100), "11% - 91%"});
  t.add_row({format("CCM cell, noiseless %dx%d grid", cfg.grid_n + cfg.grid_n % 2, cfg.grid_n + cfg.grid_n % 2),
             format("%.3f (%+.2f%% vs h^2/16)", r.threshold * 1e4, 100.0 * (r.threshold / r.analytic_threshold - 1.0)),
             format("%.1f%% - %.1f%%", r.interval.lo * 100, r.interval.hi * 100), "11% - 91%"});
  for (const Fig4NoisyCurve& nc : r.noisy) {
    t.add_row({format("stereo noise at %.0f m, own 50%% threshold", nc.range_m), format("%.3f", nc.threshold * 1e4),
               format("%.1f%% - %.1f%%", nc.interval.lo * 100, nc.interval.hi * 100), ""});
    t.add_row({format("stereo noise at %.0f m, noiseless threshold", nc.range_m), format("%.3f", r.threshold * 1e4),
               std::isfinite(nc.interval_noiseless_threshold.lo)
                   ? format("%.1f%% - %.1f%%", nc.interval_noiseless_threshold.lo * 100, nc.interval_noiseless_threshold.hi * 100)
                   : std::string("never"),
               ""});
  }
  return t.str();
}

}  // namespace ccmap::experiments
