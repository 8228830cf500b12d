// The cells a line of sight crosses, layer by layer, in integer arithmetic (docs/design.md, "Free
// space from lines of sight"). Used by map/visibility/free_space.hpp; pure, testable alone
// (tests/map/ray_walk_test.cpp holds it to a dense double-precision sampling of the ray).
//
// Units: a ray is given in "U units", finest-layer cells in fixed point with kRayFracBits = 8
// fraction bits: U = 256 i + floor(256 f) for a point the front placed in finest cell i at
// fraction f of it (ray_u), so that the cell of layer k holding a U coordinate is U >> (8 + k),
// exactly the index the front computes for the point (index_0 >> k, map/update/front.hpp): the
// walk and the update name the same cells.
//
// What the walk reports: for every layer whose window holds the ray's origin, every cell of that
// layer the segment crosses while it stays inside the layer's window (a window is convex and holds
// the origin, so the ray is inside it on one interval [0, t_out]), once, with its crossing
// interval [t_in, t_out] of the ray parameter t in [0, 1] (t = 0 at the origin, 1 at the end).
// Visits are emitted in the order the ray leaves the cells (increasing t_out; at a shared
// boundary finer layers first). A visit is flagged `walk_layer` when its layer is the finest
// whose window holds the ray where the crossing ends: the layer a query there would ask first.
// (A cell whose layer became the finest on the way, because the finer window ended inside it,
// keeps its whole crossing: walk-layer visits cover the ray in order and overlap only there.)
//   - Cells the segment only touches (a corner, or the origin or end lying on a boundary) are
//     not reported: their crossing has zero length. At an exact corner the walk steps diagonally.
//   - Layers finer than the finest holding the origin, and layers whose window does not hold
//     the origin, are not walked even where the ray enters their window later (for the robot's
//     own camera every window holds it).
// How: an Amanatides-Woo walk in the current walk layer with exact integer decisions: the next
// boundary on each axis is a distance a_x, a_y (U units) from the origin, and x comes first iff
// a_x |D_y| < a_y |D_x| (int64 products: |D| <= kMaxRayDeltaU = 2^27, a <= |D| + 2^15, so every
// product is below 2^55). t is only computed for the visits: a / |D| in float (relative error
// ~1e-7). Coarser layers follow the walk layer's index (index_k >> (j - k)); when the walk layer's
// next cell leaves its window the walk continues in the finest active coarser layer from the same
// point. Cost: O(cells of the walk layers crossed + cells of coarser layers crossed), a few
// integer operations per step and four float operations per visit. No heap, no recursion.
#pragma once

#include <cstdint>

#include "ccmap/grid/ring_index.hpp"
#include "ccmap/map/config.hpp"

namespace ccmap::detail {

inline constexpr int kRayFracBits = 8;
/// Largest |D| on either axis (U units): 2^19 finest cells (21 km at 4 cm). Longer rays are
/// shortened to it by the caller (free_space.hpp); nothing of a window lies beyond for the
/// presets, and the products of the walk stay below 2^55.
inline constexpr std::int64_t kMaxRayDeltaU = std::int64_t{1} << 27;

/// The layers' windows the walk may enter: [min, min + side) per axis, per layer (0 = finest).
struct RayWindows {
  int layers = 0;
  CellIndex min[kMaxLayers]{};
  std::int32_t side[kMaxLayers]{};
  [[nodiscard]] bool contains(int layer, CellIndex c) const noexcept {
    const std::int64_t rx = std::int64_t{c.x} - std::int64_t{min[layer].x};
    const std::int64_t ry = std::int64_t{c.y} - std::int64_t{min[layer].y};
    const auto s = static_cast<std::uint64_t>(side[layer]);
    return static_cast<std::uint64_t>(rx) < s && static_cast<std::uint64_t>(ry) < s;
  }
};

/// A horizontal ray segment in U units: from origin to origin + delta. |delta| <= kMaxRayDeltaU
/// per axis (precondition; a longer ray is halved by the walk until it holds).
struct RayU {
  std::int64_t origin[2];
  std::int64_t delta[2];
};

/// One cell a ray crosses: its layer, global index and crossing interval (t_in < t_out).
struct RayVisit {
  int layer;
  CellIndex index;
  float t_in;
  float t_out;
  bool walk_layer;  ///< its layer is the finest whose window holds the ray at t_out
};

/// U coordinate of a position in finest cell `index` at `fraction` of it (the front's fx, fy or
/// a pose's anchor fraction, in [0, 1]; a fraction of 1 or more, NaN or below 0 is clamped into
/// the cell): 256 index + floor(256 fraction). |index| <= 2^30 + 2^14: fits int64.
[[nodiscard]] inline std::int64_t ray_u(std::int32_t index, float fraction) noexcept {
  const float scaled = fraction * 256.0F;
  const std::int32_t sub = scaled >= 255.0F ? 255 : (scaled >= 0.0F ? static_cast<std::int32_t>(scaled) : 0);
  return std::int64_t{index} * 256 + sub;
}

/// Calls sink(const RayVisit&) for every visit of the ray (see the header comment).
template <typename Sink>
void walk_ray(const RayWindows& windows, const RayU& ray, Sink&& sink) noexcept {
  const int layers = windows.layers < kMaxLayers ? windows.layers : kMaxLayers;
  const std::int64_t ux = ray.origin[0];
  const std::int64_t uy = ray.origin[1];
  std::int64_t dx = ray.delta[0];
  std::int64_t dy = ray.delta[1];
  // Precondition |D| <= kMaxRayDeltaU; a longer ray is halved until it holds (its direction kept
  // to the rounding of the halving: a safe value, not a contract).
  while (dx > kMaxRayDeltaU || dx < -kMaxRayDeltaU || dy > kMaxRayDeltaU || dy < -kMaxRayDeltaU) {
    dx /= 2;
    dy /= 2;
  }
  if (layers <= 0 || (dx == 0 && dy == 0)) {
    return;
  }
  CellIndex cur[kMaxLayers]{};
  float t_in[kMaxLayers]{};
  bool active[kMaxLayers]{};
  int walk = -1;
  for (int j = 0; j < layers; ++j) {
    const int shift = kRayFracBits + j;
    cur[j] = CellIndex{static_cast<std::int32_t>(ux >> shift), static_cast<std::int32_t>(uy >> shift)};
    active[j] = windows.contains(j, cur[j]);
    if (active[j] && walk < 0) {
      walk = j;
    }
  }
  if (walk < 0) {
    return;
  }
  for (int j = 0; j < walk; ++j) {
    active[j] = false;  // finer than the finest window holding the origin: not walked
  }
  const std::int32_t sx = dx > 0 ? 1 : (dx < 0 ? -1 : 0);
  const std::int32_t sy = dy > 0 ? 1 : (dy < 0 ? -1 : 0);
  const std::int64_t adx = dx < 0 ? -dx : dx;
  const std::int64_t ady = dy < 0 ? -dy : dy;
  const float inv_x = adx > 0 ? 1.0F / static_cast<float>(adx) : 0.0F;
  const float inv_y = ady > 0 ? 1.0F / static_cast<float>(ady) : 0.0F;
  // Distance (U) from the origin to the next boundary of cell c of `layer` along an axis. The
  // boundary c 2^shift is a product, not a left shift: c is negative left of the origin cell, and
  // a left shift of a negative value is undefined behaviour (|c| < 2^31, shift <= 15: no overflow).
  auto ahead = [](int layer, std::int32_t c, std::int64_t u, std::int32_t s) -> std::int64_t {
    const std::int64_t cell_u = std::int64_t{1} << (kRayFracBits + layer);
    return s > 0 ? ((std::int64_t{c} + 1) * cell_u - u) : (u - std::int64_t{c} * cell_u);
  };
  std::int64_t ax = ahead(walk, cur[walk].x, ux, sx);
  std::int64_t ay = ahead(walk, cur[walk].y, uy, sy);
  for (;;) {
    // Which boundary comes first (exact); both at once at a corner.
    bool step_x = false;
    bool step_y = false;
    if (adx == 0) {
      step_y = true;
    } else if (ady == 0) {
      step_x = true;
    } else {
      const std::int64_t lhs = ax * ady;
      const std::int64_t rhs = ay * adx;
      step_x = lhs <= rhs;
      step_y = rhs <= lhs;
    }
    const std::int64_t a = step_x ? ax : ay;
    const std::int64_t ad = step_x ? adx : ady;
    if (a >= ad) {
      break;  // the next boundary lies at or beyond the end of the segment
    }
    const float t = static_cast<float>(a) * (step_x ? inv_x : inv_y);
    const std::int64_t cell_u = std::int64_t{1} << (kRayFracBits + walk);
    CellIndex next = cur[walk];
    if (step_x) {
      next.x += sx;
      ax += cell_u;
    }
    if (step_y) {
      next.y += sy;
      ay += cell_u;
    }
    for (int j = walk; j < layers; ++j) {
      if (!active[j]) {
        continue;
      }
      const int down = j - walk;
      const CellIndex nj{next.x >> down, next.y >> down};
      if (nj.x == cur[j].x && nj.y == cur[j].y) {
        break;  // cells nest: an unchanged cell of layer j leaves every coarser one unchanged
      }
      if (t > t_in[j]) {
        sink(RayVisit{j, cur[j], t_in[j], t, j == walk});
      }
      cur[j] = nj;
      t_in[j] = t;
      active[j] = windows.contains(j, nj);
    }
    if (!active[walk]) {
      int next_walk = -1;
      for (int j = walk + 1; j < layers; ++j) {
        if (active[j]) {
          next_walk = j;
          break;
        }
      }
      if (next_walk < 0) {
        return;  // the ray left every window; each layer's last cell was reported on leaving
      }
      walk = next_walk;
      ax = ahead(walk, cur[walk].x, ux, sx);
      ay = ahead(walk, cur[walk].y, uy, sy);
    }
  }
  for (int j = walk; j < layers; ++j) {
    if (active[j] && 1.0F > t_in[j]) {
      sink(RayVisit{j, cur[j], t_in[j], 1.0F, j == walk});
    }
  }
}

}  // namespace ccmap::detail
