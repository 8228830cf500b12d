#include "experiments/fig5.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "experiments/common.hpp"
#include "png.hpp"
#include "sim/cloud.hpp"
#include "sim/data_dir.hpp"
#include "sim/rng.hpp"

namespace ccmap::experiments {

namespace {

constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

/// A fixed grid of cells of one kind over `area`: cell (ix, iy) covers
/// [x0 + ix w, x0 + (ix+1) w) x [y0 + iy w, ...); the last row/column may stick out of the area.
template <typename Cell>
struct CellGrid {
  double x0 = 0.0, y0 = 0.0, w = 1.0;
  int nx = 0, ny = 0;
  std::vector<Cell> cells;
  CellGrid(const sim::Rect& area, double width) : x0(area.x0), y0(area.y0), w(width) {
    nx = std::max(1, static_cast<int>(std::ceil(area.width() / width - 1e-9)));
    ny = std::max(1, static_cast<int>(std::ceil(area.height() / width - 1e-9)));
    cells.assign(static_cast<std::size_t>(nx * ny), Cell{});
  }
  /// Index of the cell holding (x, y), or -1 outside; fills the cell centre.
  int index(double x, double y, double* cx, double* cy) const {
    const int ix = static_cast<int>(std::floor((x - x0) / w)), iy = static_cast<int>(std::floor((y - y0) / w));
    if (ix < 0 || iy < 0 || ix >= nx || iy >= ny) return -1;
    *cx = x0 + (ix + 0.5) * w;
    *cy = y0 + (iy + 0.5) * w;
    return ix + nx * iy;
  }
};

struct Accumulator {
  double sum_sq = 0.0;
  std::size_t n = 0, violations = 0;
  std::vector<float> sigmas;
  void add(double err, double sigma) {
    sum_sq += err * err;
    ++n;
    if (std::fabs(err) > 3.0 * sigma) ++violations;
    sigmas.push_back(static_cast<float>(sigma));
  }
  void finish(Fig5MethodStats* s) {
    s->samples = n;
    s->rms_m = n > 0 ? std::sqrt(sum_sq / static_cast<double>(n)) : 0.0;
    s->violation_share = n > 0 ? static_cast<double>(violations) / static_cast<double>(n) : 0.0;
    if (!sigmas.empty()) {
      std::nth_element(sigmas.begin(), sigmas.begin() + static_cast<std::ptrdiff_t>(sigmas.size() / 2), sigmas.end());
      s->median_sigma_m = sigmas[sigmas.size() / 2];
    }
  }
};

std::string method_slug(const Fig5MethodStats& m, double base_width) {
  std::string s = m.method;
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (m.cell_width_m > base_width * 1.5) s += "_2w";
  return s;
}

}  // namespace

sim::TerrainParams fig5_terrain_params(double size_m, std::uint64_t seed) {
  sim::TerrainParams p;
  p.area = sim::Rect{0.0, 0.0, size_m, size_m};
  p.seed = seed;
  p.slope_x = 0.04;
  p.slope_y = 0.02;
  p.rolling = sim::RollingParams{4, 0.45, 7.0, 20.0};
  p.roughness = sim::RoughnessParams{4, 0.03, 1.5, 0.5};
  p.rocks = sim::RockParams{0.08, 0.15, 1.0, 2.5, 0.5};
  p.craters = sim::CraterParams{2, 2.0, 5.0, 0.12, 0.02};
  return p;
}

const Fig5MethodStats* Fig5Run::find(const std::string& method, double cell_width_m) const {
  for (const Fig5MethodStats& m : methods) {
    if (m.method == method && std::fabs(m.cell_width_m - cell_width_m) < 1e-9) return &m;
  }
  return nullptr;
}

namespace {

template <typename CcmCellT>
Fig5Run evaluate_maps(const sim::Terrain& truth, const sim::Rect& area, const std::vector<sim::Point3>& cloud,
                      double cell_width_m, double sigma_z_m, double eval_step_m, bool keep_maps) {
  Fig5Run run;
  run.area = area;
  run.points = cloud.size();
  run.eval_step_m = eval_step_m;
  run.eval_nx = static_cast<int>(std::floor(area.width() / eval_step_m + 1e-9));
  run.eval_ny = static_cast<int>(std::floor(area.height() / eval_step_m + 1e-9));
  const float meas_var = static_cast<float>(sigma_z_m * sigma_z_m);

  CellGrid<CcmCellT> ccm(area, cell_width_m), ccm2(area, 2.0 * cell_width_m);
  CellGrid<KalmanCell> kalman(area, cell_width_m);
  CellGrid<OmgCell> omg(area, cell_width_m);
  std::size_t refused = 0;
  for (const sim::Point3& p : cloud) {
    double cx = 0.0, cy = 0.0;
    const int k = ccm.index(p.x, p.y, &cx, &cy);
    if (k < 0) continue;
    const float z = static_cast<float>(p.z);
    const std::size_t uk = static_cast<std::size_t>(k);
    if (ccm_update(ccm.cells[uk], static_cast<float>(p.x - cx), static_cast<float>(p.y - cy), z, 1.0F, kNoWeightLimit) != Status::kOk) ++refused;
    if (kalman_update(kalman.cells[uk], z, meas_var) != Status::kOk) ++refused;
    if (omg_update(omg.cells[uk], z, meas_var, 1.0F) != Status::kOk) ++refused;
    const int k2 = ccm2.index(p.x, p.y, &cx, &cy);
    if (ccm_update(ccm2.cells[static_cast<std::size_t>(k2)], static_cast<float>(p.x - cx), static_cast<float>(p.y - cy), z, 1.0F,
                   kNoWeightLimit) != Status::kOk) ++refused;
  }
  (void)refused;  // finite points of a few hundred metres are never refused

  // Surfaces once per CCM cell.
  std::vector<CcmSurface> surf(ccm.cells.size()), surf2(ccm2.cells.size());
  for (std::size_t k = 0; k < ccm.cells.size(); ++k) surf[k] = ccm_surface(ccm.cells[k]);
  for (std::size_t k = 0; k < ccm2.cells.size(); ++k) surf2[k] = ccm_surface(ccm2.cells[k]);

  const std::size_t ns = static_cast<std::size_t>(run.eval_nx) * static_cast<std::size_t>(run.eval_ny);
  Fig5MethodStats s_ccm, s_omg, s_kal, s_ccm2;
  s_ccm.method = "CCM";
  s_omg.method = "OMG";
  s_kal.method = "Kalman";
  s_ccm2.method = "CCM";
  s_ccm.cell_width_m = s_omg.cell_width_m = s_kal.cell_width_m = cell_width_m;
  s_ccm2.cell_width_m = 2.0 * cell_width_m;
  s_ccm.cells_x = s_omg.cells_x = s_kal.cells_x = ccm.nx;
  s_ccm.cells_y = s_omg.cells_y = s_kal.cells_y = ccm.ny;
  s_ccm2.cells_x = ccm2.nx;
  s_ccm2.cells_y = ccm2.ny;
  s_ccm.bytes = ccm.cells.size() * sizeof(CcmCellT);
  s_ccm2.bytes = ccm2.cells.size() * sizeof(CcmCellT);
  s_omg.bytes = omg.cells.size() * sizeof(OmgCell);
  s_kal.bytes = kalman.cells.size() * sizeof(KalmanCell);
  for (Fig5MethodStats* s : {&s_ccm, &s_omg, &s_kal, &s_ccm2}) {
    if (keep_maps) {
      s->error_m.assign(ns, kNaNf);
      s->sigma_m.assign(ns, kNaNf);
    }
  }
  Accumulator a_ccm, a_omg, a_kal, a_ccm2;
  for (int j = 0; j < run.eval_ny; ++j) {
    const double y = area.y0 + (j + 0.5) * eval_step_m;
    for (int i = 0; i < run.eval_nx; ++i) {
      const double x = area.x0 + (i + 0.5) * eval_step_m;
      const double h = truth.height(x, y);
      if (!std::isfinite(h)) continue;
      const std::size_t si = static_cast<std::size_t>(i) + static_cast<std::size_t>(run.eval_nx) * static_cast<std::size_t>(j);
      auto record = [&](Fig5MethodStats& s, Accumulator& a, double est, double var) {
        const double err = est - h, sigma = std::sqrt(std::max(0.0, var));
        a.add(err, sigma);
        if (keep_maps) {
          s.error_m[si] = static_cast<float>(err);
          s.sigma_m[si] = static_cast<float>(sigma);
        }
      };
      double cx = 0.0, cy = 0.0;
      const int k = ccm.index(x, y, &cx, &cy);
      if (k >= 0) {
        const std::size_t uk = static_cast<std::size_t>(k);
        const CcmCellT& c = ccm.cells[uk];
        if (c.weight > 0.0F) {
          const float qx = static_cast<float>(x - cx), qy = static_cast<float>(y - cy);
          record(s_ccm, a_ccm, ccm_height_at(c, surf[uk], qx, qy), ccm_elevation_variance(c, surf[uk], qx, qy));
        }
        if (omg.cells[uk].weight > 0.0F) record(s_omg, a_omg, omg.cells[uk].height, omg_variance(omg.cells[uk]));
        if (kalman.cells[uk].weight > 0.0F) record(s_kal, a_kal, kalman.cells[uk].height, kalman.cells[uk].variance);
      }
      const int k2 = ccm2.index(x, y, &cx, &cy);
      if (k2 >= 0 && ccm2.cells[static_cast<std::size_t>(k2)].weight > 0.0F) {
        const std::size_t uk = static_cast<std::size_t>(k2);
        const float qx = static_cast<float>(x - cx), qy = static_cast<float>(y - cy);
        record(s_ccm2, a_ccm2, ccm_height_at(ccm2.cells[uk], surf2[uk], qx, qy),
               ccm_elevation_variance(ccm2.cells[uk], surf2[uk], qx, qy));
      }
    }
  }
  a_ccm.finish(&s_ccm);
  a_omg.finish(&s_omg);
  a_kal.finish(&s_kal);
  a_ccm2.finish(&s_ccm2);
  run.methods = {s_ccm, s_omg, s_kal, s_ccm2};
  return run;
}

}  // namespace

Fig5Run evaluate_fig5_maps(const sim::Terrain& truth, const sim::Rect& area, const std::vector<sim::Point3>& cloud,
                           double cell_width_m, double sigma_z_m, double eval_step_m, bool keep_maps, bool paper_cell) {
  return paper_cell ? evaluate_maps<CcmPaperCell>(truth, area, cloud, cell_width_m, sigma_z_m, eval_step_m, keep_maps)
                    : evaluate_maps<CcmCell>(truth, area, cloud, cell_width_m, sigma_z_m, eval_step_m, keep_maps);
}

Fig5Run run_fig5_synthetic(const Fig5Config& cfg, bool keep_maps) {
  const sim::ProceduralTerrain terrain(fig5_terrain_params(cfg.size_m, cfg.seed));
  sim::CloudParams cp;
  cp.area = sim::Rect{0.0, 0.0, cfg.size_m, cfg.size_m};
  cp.count = static_cast<std::size_t>(std::llround(cfg.points_per_m2 * cp.area.area()));
  cp.sigma_z_m = cfg.sigma_z_m;
  cp.seed = sim::hash_combine(cfg.seed, 5);
  const std::vector<sim::Point3> cloud = sim::sample_noisy_cloud(terrain, cp);
  Fig5Run run = evaluate_fig5_maps(terrain, cp.area, cloud, cfg.cell_width_m, cfg.sigma_z_m, cfg.eval_step_m, keep_maps,
                                   cfg.paper_cell);
  run.terrain_name = format("simulated %.0f x %.0f m", cfg.size_m, cfg.size_m);
  return run;
}

bool run_fig5_mars(const Fig5Config& cfg, const std::string& data_dir, bool keep_maps, Fig5Run* out, std::string* why) {
  const std::string path = sim::mars_dtm_path(data_dir);
  if (!sim::data_file_available(path, why)) return false;
  sim::HeightRaster dtm;
  if (!sim::load_esri_ascii(path, &dtm, why)) return false;
  dtm.shift_heights(-dtm.mean_height());  // map z near 0 (float precision of the cells)
  sim::CloudParams cp;
  cp.area = dtm.extent();
  cp.count = static_cast<std::size_t>(std::llround(cfg.mars_points_per_m2 * cp.area.area()));
  cp.sigma_z_m = cfg.sigma_z_m;
  cp.seed = sim::hash_combine(cfg.seed, 6);
  const std::vector<sim::Point3> cloud = sim::sample_noisy_cloud(dtm, cp);
  *out = evaluate_fig5_maps(dtm, cp.area, cloud, cfg.mars_cell_width_m, cfg.sigma_z_m, cfg.mars_eval_step_m, keep_maps,
                            cfg.paper_cell);
  out->terrain_name = format("HiRISE Mars DTM %.0f x %.0f m", cp.area.width(), cp.area.height());
  return true;
}

bool write_fig5_images(const Fig5Run& run, const sim::Terrain& truth, const std::string& out_dir,
                       const std::string& prefix, std::string* error) {
  if (!ensure_directory(out_dir, error)) return false;
  const int nx = run.eval_nx, ny = run.eval_ny;
  if (nx <= 0 || ny <= 0 || run.methods.empty() || run.methods[0].error_m.empty()) {
    if (error != nullptr) *error = "no maps kept for the images";
    return false;
  }
  const double base_w = run.methods[0].cell_width_m;
  // Common colour scale: the 99th percentile of |error| over the constant maps.
  std::vector<float> all;
  for (const Fig5MethodStats& m : run.methods)
    for (float e : m.error_m)
      if (std::isfinite(e)) all.push_back(std::fabs(e));
  std::sort(all.begin(), all.end());
  const double scale = all.empty() ? 1.0 : std::max(1e-3, static_cast<double>(all[all.size() * 99 / 100]));
  auto pixel_row = [ny](int j) { return ny - 1 - j; };  // north up
  auto draw_cells = [&](ccmap::tools::RgbImage& img, double w) {
    const std::uint8_t grey[3] = {110, 110, 110};
    for (int i = 0; i < nx; ++i) {
      const double x = run.area.x0 + (i + 0.5) * run.eval_step_m;
      const double fx = (x - run.area.x0) / w;
      if (i > 0 && std::floor(fx) != std::floor((x - run.eval_step_m - run.area.x0) / w))
        for (int j = 0; j < ny; ++j) img.set(i, j, grey);
    }
    for (int j = 1; j < ny; ++j) {
      const double y = run.area.y0 + (j + 0.5) * run.eval_step_m;
      if (std::floor((y - run.area.y0) / w) != std::floor((y - run.eval_step_m - run.area.y0) / w))
        for (int i = 0; i < nx; ++i) img.set(i, pixel_row(j), grey);
    }
  };
  std::vector<std::string> names;
  for (const Fig5MethodStats& m : run.methods) {
    ccmap::tools::RgbImage err_img(nx, ny, 0), vio_img(nx, ny, 0);
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const std::size_t si = static_cast<std::size_t>(i) + static_cast<std::size_t>(nx) * static_cast<std::size_t>(j);
        const float e = m.error_m[si], s = m.sigma_m[si];
        std::uint8_t c[3] = {0, 0, 0};
        if (std::isfinite(e)) ccmap::tools::colormap_viridis(std::fabs(e) / scale, c);
        err_img.set(i, pixel_row(j), c);
        std::uint8_t v[3] = {255, 255, 255};
        if (!std::isfinite(e)) {
          v[0] = v[1] = v[2] = 0;
        } else if (std::fabs(e) > 3.0 * s) {
          ccmap::tools::colormap_viridis((std::fabs(e) - 3.0 * s) / scale, v);
        }
        vio_img.set(i, pixel_row(j), v);
      }
    }
    draw_cells(err_img, m.cell_width_m);
    draw_cells(vio_img, m.cell_width_m);
    const std::string slug = method_slug(m, base_w);
    names.push_back(slug);
    if (!ccmap::tools::write_png(out_dir + "/" + prefix + "_" + slug + "_error.png", err_img, error)) return false;
    if (!ccmap::tools::write_png(out_dir + "/" + prefix + "_" + slug + "_3sigma.png", vio_img, error)) return false;
  }
  // Terrain hillshade.
  ccmap::tools::RgbImage shade(nx, ny, 0);
  const double e = 0.5 * run.eval_step_m;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double x = run.area.x0 + (i + 0.5) * run.eval_step_m, y = run.area.y0 + (j + 0.5) * run.eval_step_m;
      const double gx = (truth.height(x + e, y) - truth.height(x - e, y)) / (2 * e);
      const double gy = (truth.height(x, y + e) - truth.height(x, y - e)) / (2 * e);
      const double s = ccmap::tools::hillshade(gx, gy);
      const std::uint8_t g = static_cast<std::uint8_t>(std::lround(std::isfinite(s) ? 255.0 * std::clamp(s, 0.0, 1.0) : 0.0));
      const std::uint8_t c[3] = {g, g, g};
      shade.set(i, pixel_row(j), c);
    }
  }
  if (!ccmap::tools::write_png(out_dir + "/" + prefix + "_terrain.png", shade, error)) return false;
  // SVG page laying the PNGs out like the paper's figure: one row per map, precision | variance.
  const double aspect = static_cast<double>(ny) / nx;
  const int pw = 300, ph = static_cast<int>(std::lround(pw * aspect));
  const int rows = static_cast<int>(run.methods.size()) + 1;
  std::ostringstream o;
  const int W = 2 * pw + 60, H = rows * (ph + 40) + 70;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" width=\"" << W << "\" height=\"" << H
    << "\" font-family=\"Helvetica, Arial, sans-serif\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << "<text x=\"20\" y=\"22\" font-size=\"15\">" << run.terrain_name << ": left |error| (viridis 0 - "
    << format("%.2f", scale) << " m), right: white = |error| &lt; 3 sigma, colour = excess</text>\n";
  auto image = [&](const std::string& file, int x, int y, const std::string& title) {
    o << "<text x=\"" << x << "\" y=\"" << y - 6 << "\" font-size=\"13\">" << title << "</text>\n";
    o << "<image x=\"" << x << "\" y=\"" << y << "\" width=\"" << pw << "\" height=\"" << ph << "\" href=\"" << file
      << "\" xlink:href=\"" << file << "\" style=\"image-rendering:pixelated\"/>\n";
  };
  image(prefix + "_terrain.png", 20, 56, "terrain (hillshade)");
  for (std::size_t r = 0; r < run.methods.size(); ++r) {
    const Fig5MethodStats& m = run.methods[r];
    const int y = 56 + static_cast<int>(r + 1) * (ph + 40);
    image(prefix + "_" + names[r] + "_error.png", 20, y,
          format("%s %.1f m: RMS %.3f m", m.method.c_str(), m.cell_width_m, m.rms_m));
    image(prefix + "_" + names[r] + "_3sigma.png", 40 + pw, y,
          format("%s %.1f m: %.1f%% outside 3 sigma", m.method.c_str(), m.cell_width_m, 100.0 * m.violation_share));
  }
  o << "</svg>\n";
  std::ofstream svg(out_dir + "/" + prefix + "_maps.svg");
  svg << o.str();
  if (!svg) {
    if (error != nullptr) *error = "cannot write " + out_dir + "/" + prefix + "_maps.svg";
    return false;
  }
  return true;
}

std::string fig5_table(const Fig5Run& run, bool with_paper) {
  Table t({"map", "cell [m]", "cells", "memory [B]", "RMS error [m]", "outside 3 sigma", "median sigma [m]", "paper"});
  const double base_w = run.methods.empty() ? 0.0 : run.methods[0].cell_width_m;
  for (const Fig5MethodStats& m : run.methods) {
    std::string paper;
    if (with_paper) {
      if (m.method == "CCM" && m.cell_width_m <= base_w * 1.5) paper = "RMS 0.07, within 3 sigma";
      if (m.method == "OMG") paper = "RMS 0.15, within 3 sigma";
      if (m.method == "Kalman") paper = "RMS 0.15, fails 3 sigma";
      if (m.method == "CCM" && m.cell_width_m > base_w * 1.5) paper = "similar to constant at 1x";
    }
    t.add_row({m.method, format("%.2f", m.cell_width_m), format("%dx%d", m.cells_x, m.cells_y), format("%zu", m.bytes),
               format("%.4f", m.rms_m), format("%.1f%%", 100.0 * m.violation_share), format("%.4f", m.median_sigma_m), paper});
  }
  return t.str();
}

}  // namespace ccmap::experiments
