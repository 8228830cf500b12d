// Maps for the planner-query tests (footprint, path, cost raster): deterministic terrains mapped
// into a stack from dense map-frame points, and the brute-force reference that evaluates a
// rectangle by point queries (Stack::query) at samples inside it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"

namespace ccmap::test {

/// The test terrain (map frame, m): a tilted plane (6 % in x, -3 % in y), a 15 cm high box on
/// [0.6, 0.9] x [-0.5, -0.2], a 30 deg ramp on x in [1.8, 2.4] (y > 0.8), and a hole that no
/// point reaches (unknown) in the disc of 0.25 m around (-0.7, 0.6).
inline double terrain_height(double x, double y) {
  double z = 0.06 * x - 0.03 * y;
  if (x >= 0.6 && x <= 0.9 && y >= -0.5 && y <= -0.2) z += 0.15;
  if (y > 0.8 && x > 1.8) z += 0.577 * (std::min(x, 2.4) - 1.8);
  return z;
}
inline bool terrain_hole(double x, double y) { return (x + 0.7) * (x + 0.7) + (y - 0.6) * (y - 0.6) < 0.0625; }

/// Precise lidar (0.5 mm, no range term): every layer accepts every point, so a point goes to
/// the finest layer whose window holds it.
inline StackParams precise_lidar_params(float finest_width_m) {
  StackParams p = default_stack_params(finest_width_m);
  p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.0005F, 0.0F});
  p.finest_max_sigma_m = 0.01F;
  return p;
}

/// Points of the test terrain every `spacing` m over [-extent, extent]^2 (hole left out),
/// slightly jittered (deterministic) so that no point sits on a cell edge.
inline std::vector<PointXYZ> terrain_points(double extent, double spacing) {
  std::vector<PointXYZ> pts;
  const int n = static_cast<int>(std::floor(2.0 * extent / spacing));
  std::uint32_t h = 12345U;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      h = h * 1664525U + 1013904223U;
      const double jx = 0.3 * spacing * (static_cast<double>(h >> 8) / 16777216.0 - 0.5);
      h = h * 1664525U + 1013904223U;
      const double jy = 0.3 * spacing * (static_cast<double>(h >> 8) / 16777216.0 - 0.5);
      const double x = -extent + (i + 0.5) * spacing + jx;
      const double y = -extent + (j + 0.5) * spacing + jy;
      if (terrain_hole(x, y)) continue;
      pts.push_back(PointXYZ{static_cast<float>(x), static_cast<float>(y), static_cast<float>(terrain_height(x, y))});
    }
  }
  return pts;
}

/// A stack of `Config` centred on the origin with the test terrain mapped in (one frame).
template <typename Config>
std::unique_ptr<Stack<Config>> terrain_stack(float finest_width_m, const StackParams& params, double extent,
                                             double spacing) {
  auto stack = std::make_unique<Stack<Config>>();
  if (stack->init(params) != Status::kOk) return nullptr;
  const std::vector<PointXYZ> pts = terrain_points(extent, spacing);
  if (stack->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr) != Status::kOk) return nullptr;
  (void)finest_width_m;
  return stack;
}

/// A sample of a rectangle: the point and the stack's point answer there.
struct RectSample {
  float x, y;
  QueryResult q;
};

/// Samples of the rectangle centred (cx, cy), unit heading (ux, uy), full extents L x W, in
/// double: a regular grid of `grid` spacing in the rectangle's own axes (cell midpoints), points
/// along the four sides every `edge` m inset by `inset` m, and the four corners inset likewise.
/// Samples closer than `edge_margin` m to a cell edge of width `finest` (hence of every layer) are
/// skipped: float and double may place those in either neighbour.
template <typename Config>
std::vector<RectSample> rect_samples(const Stack<Config>& stack, double cx, double cy, double ux, double uy, double L,
                                     double W, double grid, double edge, double inset, double finest,
                                     double edge_margin) {
  std::vector<RectSample> out;
  const double vx = -uy, vy = ux;
  auto add = [&](double s, double t) {
    const double x = cx + s * ux + t * vx, y = cy + s * uy + t * vy;
    for (const double v : {x, y}) {
      const double f = v / finest - std::floor(v / finest);
      if (f * finest < edge_margin || (1.0 - f) * finest < edge_margin) return;
    }
    const float fx = static_cast<float>(x), fy = static_cast<float>(y);
    out.push_back(RectSample{fx, fy, stack.query(fx, fy)});
  };
  const int ns = std::max(1, static_cast<int>(std::ceil(L / grid)));
  const int nt = std::max(1, static_cast<int>(std::ceil(W / grid)));
  for (int j = 0; j < nt; ++j)
    for (int i = 0; i < ns; ++i) add(-0.5 * L + (i + 0.5) * L / ns, -0.5 * W + (j + 0.5) * W / nt);
  const double hl = 0.5 * L - inset, hw = 0.5 * W - inset;
  for (double s = -hl; s <= hl; s += edge) {
    add(s, -hw);
    add(s, hw);
  }
  for (double t = -hw; t <= hw; t += edge) {
    add(-hl, t);
    add(hl, t);
  }
  add(hl, hw);
  add(-hl, hw);
  add(hl, -hw);
  add(-hl, -hw);
  return out;
}

}  // namespace ccmap::test
