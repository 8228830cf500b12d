#include "layer_images.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ccmap::tools {

void class_colour(const std::string& cell_class, std::uint8_t out[3]) {
  std::uint8_t r = 128, g = 128, b = 128;  // unknown (and anything unexpected): grey
  if (cell_class == "traversable") { r = 40; g = 170; b = 60; }
  else if (cell_class == "obstacle") { r = 220; g = 30; b = 30; }
  else if (cell_class == "steep") { r = 255; g = 150; b = 0; }
  else if (cell_class == "drop") { r = 130; g = 30; b = 190; }
  out[0] = r;
  out[1] = g;
  out[2] = b;
}

LayerWindow layer_extent(const std::vector<LayerCellRow>& rows, LayerWindow window) {
  if (window.nx > 0 && window.ny > 0) return window;
  if (rows.empty()) return LayerWindow{0, 0, 1, 1};
  std::int64_t x0 = rows[0].ix, x1 = rows[0].ix, y0 = rows[0].iy, y1 = rows[0].iy;
  for (const LayerCellRow& r : rows) {
    x0 = std::min(x0, r.ix); x1 = std::max(x1, r.ix);
    y0 = std::min(y0, r.iy); y1 = std::max(y1, r.iy);
  }
  // Differences of indices the tools produce (|ix| < 2^43) cannot overflow.
  const std::int64_t limit = kMaxImageCells + 1;
  return LayerWindow{x0, y0, static_cast<int>(std::min(x1 - x0 + 1, limit)), static_cast<int>(std::min(y1 - y0 + 1, limit))};
}

bool render_layer_images(const std::vector<LayerCellRow>& rows, LayerWindow window, RgbImage images[4],
                         std::string* error) {
  window = layer_extent(rows, window);
  if (window.nx > kMaxImageCells || window.ny > kMaxImageCells) {
    if (error != nullptr) *error = "layer too large to draw";
    return false;
  }
  const int nx = window.nx, ny = window.ny;
  const int side = std::max(nx, ny);
  const int scale = std::max(1, (kMinImageSide + side - 1) / side);
  // Grid of row pointers; cells outside the window are not drawn.
  std::vector<const LayerCellRow*> grid(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny), nullptr);
  bool any_slope = false;
  std::vector<double> heights;
  for (const LayerCellRow& r : rows) {
    const std::int64_t gx = r.ix - window.ix_min, gy = r.iy - window.iy_min;
    if (gx < 0 || gy < 0 || gx >= nx || gy >= ny) continue;
    grid[static_cast<std::size_t>(gy) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(gx)] = &r;
    if (r.slope_x != 0.0 || r.slope_y != 0.0) any_slope = true;
    if (std::isfinite(r.height)) heights.push_back(r.height);
  }
  // Height colour range: 2nd..98th percentile (real scans have tall outliers).
  double h_lo = 0.0, h_hi = 1.0;
  if (!heights.empty()) {
    std::sort(heights.begin(), heights.end());
    h_lo = heights[static_cast<std::size_t>(0.02 * static_cast<double>(heights.size() - 1))];
    h_hi = heights[static_cast<std::size_t>(0.98 * static_cast<double>(heights.size() - 1))];
    if (!(h_hi > h_lo)) h_hi = h_lo + 1e-3;
  }
  auto at = [&](int gx, int gy) -> const LayerCellRow* {
    if (gx < 0 || gy < 0 || gx >= nx || gy >= ny) return nullptr;
    return grid[static_cast<std::size_t>(gy) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(gx)];
  };
  for (int i = 0; i < 4; ++i) images[i] = RgbImage(nx * scale, ny * scale, 0);
  const double kPi = 3.14159265358979323846;
  for (int gy = 0; gy < ny; ++gy) {
    for (int gx = 0; gx < nx; ++gx) {
      const LayerCellRow* r = at(gx, gy);
      if (r == nullptr) continue;
      std::uint8_t c[4][3];
      // Shading: the cell's own inclination (CCM layers) or, for piece-wise constant layers,
      // central differences of neighbouring heights.
      double dzdx = r->slope_x, dzdy = r->slope_y;
      if (!any_slope && r->res > 0.0) {
        const LayerCellRow* w = at(gx - 1, gy);
        const LayerCellRow* e = at(gx + 1, gy);
        const LayerCellRow* s = at(gx, gy - 1);
        const LayerCellRow* n = at(gx, gy + 1);
        const double hx0 = w ? w->height : r->height, hx1 = e ? e->height : r->height;
        const double hy0 = s ? s->height : r->height, hy1 = n ? n->height : r->height;
        const double sx = (w ? 1 : 0) + (e ? 1 : 0), sy = (s ? 1 : 0) + (n ? 1 : 0);
        dzdx = sx > 0 ? (hx1 - hx0) / (sx * r->res) : 0.0;
        dzdy = sy > 0 ? (hy1 - hy0) / (sy * r->res) : 0.0;
      }
      colormap_viridis((r->height - h_lo) / (h_hi - h_lo), c[0]);
      const double shade = 0.35 + 0.65 * hillshade(dzdx, dzdy);
      for (int k = 0; k < 3; ++k) c[0][k] = static_cast<std::uint8_t>(std::lround(c[0][k] * shade));
      // Inclination: 0..45 degrees.
      const double incl_deg = std::atan(std::hypot(r->slope_x, r->slope_y)) * 180.0 / kPi;
      colormap_viridis(incl_deg / 45.0, c[1]);
      // Normal variance: log10 of the standard deviation, 0.1 mm .. 10 cm.
      const double sd = std::sqrt(std::max(r->normal_var, 1e-12));
      colormap_viridis((std::log10(sd) + 4.0) / 3.0, c[2]);
      class_colour(r->cell_class, c[3]);
      const int py0 = (ny - 1 - gy) * scale, px0 = gx * scale;  // north up
      for (int i = 0; i < 4; ++i) {
        for (int py = py0; py < py0 + scale; ++py) {
          for (int px = px0; px < px0 + scale; ++px) images[i].set(px, py, c[i]);
        }
      }
    }
  }
  return true;
}

bool write_layer_images(const std::string& prefix, const std::vector<LayerCellRow>& rows, LayerWindow window,
                        std::string* error) {
  RgbImage images[4];
  if (!render_layer_images(rows, window, images, error)) return false;
  static const char* kSuffix[4] = {"_height.png", "_slope.png", "_normal_var.png", "_class.png"};
  for (int i = 0; i < 4; ++i) {
    if (!write_png(prefix + kSuffix[i], images[i], error)) return false;
  }
  return true;
}

}  // namespace ccmap::tools
