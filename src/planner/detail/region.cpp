#include "ccmap/planner/detail/region.hpp"

#include <cmath>

namespace ccmap::detail {

bool make_oriented_rect(float x, float y, float heading_x, float heading_y, float length_m, float width_m,
                        OrientedRect* out) noexcept {
  if (out == nullptr || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(heading_x) ||
      !std::isfinite(heading_y) || !std::isfinite(length_m) || !std::isfinite(width_m)) {
    return false;
  }
  if (!(length_m > 0.0F) || !(width_m > 0.0F)) {
    return false;
  }
  // |heading| <= sqrt(2) * 3.4e38 overflows the square: scale the larger component to 1 first.
  const float scale = std::fabs(heading_x) > std::fabs(heading_y) ? std::fabs(heading_x) : std::fabs(heading_y);
  if (!(scale > 0.0F)) {
    return false;
  }
  const float hx = heading_x / scale;
  const float hy = heading_y / scale;
  const float norm = std::sqrt(hx * hx + hy * hy);  // in [1, sqrt 2]
  if (!(norm * scale >= 1.0e-6F)) {
    return false;
  }
  OrientedRect r{};
  r.cx = x;
  r.cy = y;
  r.ux = hx / norm;
  r.uy = hy / norm;
  r.half_length = 0.5F * length_m;
  r.half_width = 0.5F * width_m;
  const float ax = std::fabs(r.ux);
  const float ay = std::fabs(r.uy);
  r.half_extent_x = r.half_length * ax + r.half_width * ay;
  r.half_extent_y = r.half_length * ay + r.half_width * ax;
  r.corner_reach = ax + ay;
  *out = r;
  return true;
}

namespace {

/// Keeps the part of polygon (xi, yi, n) where nx * x + ny * y <= d; returns the new count.
/// The signed distance of every vertex is computed once, so both edges of a vertex see the same
/// side. At most Polygon::kMaxVertices are written (a convex input of n vertices gives <= n + 1).
int clip_half_plane(const float* xi, const float* yi, int n, float nx, float ny, float d, float* xo, float* yo) noexcept {
  float f[Polygon::kMaxVertices];
  bool all_in = true;
  for (int i = 0; i < n; ++i) {
    f[i] = d - (nx * xi[i] + ny * yi[i]);
    all_in = all_in && f[i] >= 0.0F;
  }
  if (all_in) {
    // The side does not cut the polygon (most sides of a boundary cell): the loop below would
    // copy every vertex and add none.
    for (int i = 0; i < n; ++i) {
      xo[i] = xi[i];
      yo[i] = yi[i];
    }
    return n;
  }
  int m = 0;
  for (int i = 0; i < n && m < Polygon::kMaxVertices; ++i) {
    const int j = i + 1 == n ? 0 : i + 1;
    const bool in_i = f[i] >= 0.0F;
    const bool in_j = f[j] >= 0.0F;
    if (in_i) {
      xo[m] = xi[i];
      yo[m] = yi[i];
      ++m;
    }
    if (in_i != in_j && m < Polygon::kMaxVertices) {
      const float t = f[i] / (f[i] - f[j]);  // f[i] and f[j] differ in sign: denominator != 0
      xo[m] = xi[i] + t * (xi[j] - xi[i]);
      yo[m] = yi[i] + t * (yi[j] - yi[i]);
      ++m;
    }
  }
  return m;
}

}  // namespace

float clip_square(const OrientedRect& r, float dx, float dy, float half, Polygon* out) noexcept {
  float ax[Polygon::kMaxVertices] = {dx - half, dx + half, dx + half, dx - half};
  float ay[Polygon::kMaxVertices] = {dy - half, dy - half, dy + half, dy + half};
  float bx[Polygon::kMaxVertices];
  float by[Polygon::kMaxVertices];
  int n = 4;
  // The four sides: s <= L/2, -s <= L/2, t <= W/2, -t <= W/2 with s = p.u, t = p.(-uy, ux).
  n = clip_half_plane(ax, ay, n, r.ux, r.uy, r.half_length, bx, by);
  n = clip_half_plane(bx, by, n, -r.ux, -r.uy, r.half_length, ax, ay);
  n = clip_half_plane(ax, ay, n, -r.uy, r.ux, r.half_width, bx, by);
  n = clip_half_plane(bx, by, n, r.uy, -r.ux, r.half_width, out->x, out->y);
  out->count = n;
  if (n < 3) {
    return 0.0F;
  }
  // Shoelace about the first vertex (small products: the piece is at most a cell wide).
  float twice_area = 0.0F;
  for (int i = 1; i + 1 < n; ++i) {
    const float ux = out->x[i] - out->x[0];
    const float uy = out->y[i] - out->y[0];
    const float vx = out->x[i + 1] - out->x[0];
    const float vy = out->y[i + 1] - out->y[0];
    twice_area += ux * vy - uy * vx;
  }
  return twice_area > 0.0F ? 0.5F * twice_area : 0.0F;
}

}  // namespace ccmap::detail
