// The integer ray walk (map/visibility/ray_walk.hpp) against an independent reference: the ray
// sampled densely in double precision, each sample's cell per layer found by floor division, the
// layer's window checked per sample. The reference shares nothing with the walk but the contract
// (docs/design.md, "Free space from lines of sight"): every layer whose window holds the origin,
// every cell crossed while inside the window, once, with its crossing interval, in order of
// leaving; the walk layer the finest window holding the stretch.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "ccmap/map/visibility/free_space_cell.hpp"
#include "ccmap/map/visibility/ray_walk.hpp"

namespace {

using ccmap::CellIndex;
using ccmap::detail::RayU;
using ccmap::detail::RayVisit;
using ccmap::detail::RayWindows;
using ccmap::detail::walk_ray;

constexpr int kFrac = 8;  // the walk's fraction bits (kRayFracBits), restated by the reference

struct Key {
  int layer;
  std::int32_t x, y;
  bool operator<(const Key& o) const { return std::tie(layer, x, y) < std::tie(o.layer, o.x, o.y); }
};
struct Extent {
  double t_min = 2.0, t_max = -1.0;
};

/// CADRE-like windows (sides 64, 64, 64, 32, 32) centred near `centre_u` (U units) with the
/// stack's even-index snapping per layer.
RayWindows cadre_windows(double cx_u, double cy_u) {
  RayWindows w;
  w.layers = 5;
  const std::int32_t sides[5] = {64, 64, 64, 32, 32};
  for (int k = 0; k < 5; ++k) {
    const double cell_u = std::ldexp(1.0, kFrac + k);
    const auto ix = static_cast<std::int32_t>(2.0 * std::floor(cx_u / cell_u / 2.0 + 0.5));
    const auto iy = static_cast<std::int32_t>(2.0 * std::floor(cy_u / cell_u / 2.0 + 0.5));
    w.side[k] = sides[k];
    w.min[k] = CellIndex{ix - sides[k] / 2, iy - sides[k] / 2};
  }
  return w;
}

bool in_window(const RayWindows& w, int k, std::int64_t x, std::int64_t y) {
  return x >= w.min[k].x && x < w.min[k].x + w.side[k] && y >= w.min[k].y && y < w.min[k].y + w.side[k];
}

/// The reference: every cell per layer the densely sampled ray passes through (inside the window,
/// for layers whose window holds the origin, until the ray first leaves the window).
std::map<Key, Extent> sampled_cells(const RayWindows& w, const RayU& ray, int samples) {
  std::map<Key, Extent> cells;
  int first = -1;
  for (int k = 0; k < w.layers; ++k) {
    const double scale = std::ldexp(1.0, kFrac + k);
    const auto x = static_cast<std::int64_t>(std::floor(static_cast<double>(ray.origin[0]) / scale));
    const auto y = static_cast<std::int64_t>(std::floor(static_cast<double>(ray.origin[1]) / scale));
    if (in_window(w, k, x, y) && first < 0) {
      first = k;
    }
  }
  if (first < 0) {
    return cells;
  }
  for (int k = first; k < w.layers; ++k) {
    const double scale = std::ldexp(1.0, kFrac + k);
    {
      const auto x = static_cast<std::int64_t>(std::floor(static_cast<double>(ray.origin[0]) / scale));
      const auto y = static_cast<std::int64_t>(std::floor(static_cast<double>(ray.origin[1]) / scale));
      if (!in_window(w, k, x, y)) {
        continue;  // not walked: its window does not hold the origin
      }
    }
    for (int i = 0; i <= samples; ++i) {
      const double t = static_cast<double>(i) / samples;
      const double ux = static_cast<double>(ray.origin[0]) + static_cast<double>(ray.delta[0]) * t;
      const double uy = static_cast<double>(ray.origin[1]) + static_cast<double>(ray.delta[1]) * t;
      const auto x = static_cast<std::int64_t>(std::floor(ux / scale));
      const auto y = static_cast<std::int64_t>(std::floor(uy / scale));
      if (!in_window(w, k, x, y)) {
        break;  // left the window: never re-entered (convex)
      }
      Extent& e = cells[Key{k, static_cast<std::int32_t>(x), static_cast<std::int32_t>(y)}];
      e.t_min = t < e.t_min ? t : e.t_min;
      e.t_max = t > e.t_max ? t : e.t_max;
    }
  }
  return cells;
}

std::vector<RayVisit> walked(const RayWindows& w, const RayU& ray) {
  std::vector<RayVisit> visits;
  walk_ray(w, ray, [&visits](const RayVisit& v) { visits.push_back(v); });
  return visits;
}

/// Checks the walk against the reference for one ray; returns the visits.
std::vector<RayVisit> check_ray(const RayWindows& w, const RayU& ray, const char* what) {
  constexpr int kSamples = 200000;
  const double tol = 2.0 / kSamples + 1e-6;
  const std::map<Key, Extent> reference = sampled_cells(w, ray, kSamples);
  const std::vector<RayVisit> visits = walked(w, ray);
  std::map<Key, const RayVisit*> by_cell;
  for (const RayVisit& v : visits) {
    const Key key{v.layer, v.index.x, v.index.y};
    EXPECT_EQ(by_cell.count(key), 0U) << what << ": layer " << v.layer << " cell (" << v.index.x << ", "
                                      << v.index.y << ") reported twice";
    by_cell[key] = &v;
    EXPECT_LT(v.t_in, v.t_out) << what << ": an empty crossing was reported";
    EXPECT_GE(v.t_in, 0.0F) << what;
    EXPECT_LE(v.t_out, 1.0F) << what;
  }
  for (const auto& [key, extent] : reference) {
    const auto it = by_cell.find(key);
    if (extent.t_max - extent.t_min <= tol) {
      continue;  // a corner or an end on a boundary: either answer is right
    }
    EXPECT_NE(it, by_cell.end()) << what << ": the ray crosses layer " << key.layer << " cell (" << key.x << ", "
                                 << key.y << ") over t in [" << extent.t_min << ", " << extent.t_max
                                 << "] but the walk does not report it";
    if (it == by_cell.end()) {
      continue;
    }
    EXPECT_NEAR(it->second->t_in, extent.t_min, tol) << what << ": entry of layer " << key.layer << " cell";
    EXPECT_NEAR(it->second->t_out, extent.t_max, tol) << what << ": exit of layer " << key.layer << " cell";
  }
  for (const RayVisit& v : visits) {
    const auto it = reference.find(Key{v.layer, v.index.x, v.index.y});
    if (v.t_out - v.t_in <= static_cast<float>(tol)) {
      continue;
    }
    EXPECT_NE(it, reference.end()) << what << ": the walk reports layer " << v.layer << " cell (" << v.index.x
                                   << ", " << v.index.y << ") over [" << v.t_in << ", " << v.t_out
                                   << "], which the ray does not cross";
  }
  // Emitted in order of leaving.
  for (std::size_t i = 1; i < visits.size(); ++i) {
    EXPECT_LE(visits[i - 1].t_out, visits[i].t_out) << what << ": visits out of order at " << i;
  }
  return visits;
}

RayU ray_of(double x0, double y0, double dx, double dy) {
  return RayU{{static_cast<std::int64_t>(std::floor(x0)), static_cast<std::int64_t>(std::floor(y0))},
              {static_cast<std::int64_t>(std::llround(dx)), static_cast<std::int64_t>(std::llround(dy))}};
}

TEST(RayWalk, VisitsEveryCellADenseDoubleSamplingFindsInEveryLayer) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> centre(-3000.0 * 256, 3000.0 * 256);
  std::uniform_real_distribution<double> offset(-20.0 * 256, 20.0 * 256);
  std::uniform_real_distribution<double> length(0.0, 260.0 * 256);  // up to 10 m at 4 cm
  std::uniform_real_distribution<double> angle(0.0, 6.283185307179586);
  for (int k = 0; k < 60; ++k) {
    const double cx = centre(rng);
    const double cy = centre(rng);
    const RayWindows w = cadre_windows(cx, cy);
    const double a = angle(rng);
    const double l = length(rng);
    const RayU ray = ray_of(cx + offset(rng), cy + offset(rng), l * std::cos(a), l * std::sin(a));
    const std::vector<RayVisit> visits = check_ray(w, ray, "random ray");
    ASSERT_FALSE(visits.empty()) << "a ray from inside the windows visits cells";
  }
}

TEST(RayWalk, AxisAlignedDiagonalAndNegativeRaysMatchTheReference) {
  const RayWindows w = cadre_windows(0.0, 0.0);
  check_ray(w, ray_of(0.0, 0.0, 100.0 * 256, 0.0), "along +x");
  check_ray(w, ray_of(0.0, 0.0, 0.0, -100.0 * 256), "along -y");
  check_ray(w, ray_of(-3.0 * 256, -5.0 * 256, 90.0 * 256, 90.0 * 256), "exact diagonal through corners");
  check_ray(w, ray_of(17.5 * 256, -1.25 * 256, -240.0 * 256, -37.0 * 256), "towards negative indices");
  check_ray(w, ray_of(5.0, 7.0, 3.0, 1.0), "inside one cell");
}

TEST(RayWalk, TheWalkLayerIsTheFinestWindowHoldingTheRayWhereItsCrossingEndsAndCoversTheRay) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> length(10.0 * 256, 300.0 * 256);
  std::uniform_real_distribution<double> angle(0.0, 6.283185307179586);
  const RayWindows w = cadre_windows(1000.0 * 256, -700.0 * 256);
  for (int k = 0; k < 40; ++k) {
    const double a = angle(rng);
    const double l = length(rng);
    const RayU ray = ray_of(1000.3 * 256, -700.6 * 256, l * std::cos(a), l * std::sin(a));
    const std::vector<RayVisit> visits = walked(w, ray);
    float covered = 0.0F;
    for (const RayVisit& v : visits) {
      if (!v.walk_layer) {
        continue;
      }
      // In order, without gaps; an overlap only where a finer window ended inside the cell.
      EXPECT_LE(v.t_in, covered + 1e-6F) << "a gap between walk-layer visits";
      EXPECT_GT(v.t_out, covered) << "walk-layer visits out of order";
      covered = v.t_out;
      // No finer window holds the ray just before the crossing ends.
      const double t = static_cast<double>(v.t_out) - 1e-5;
      const double ux = static_cast<double>(ray.origin[0]) + static_cast<double>(ray.delta[0]) * t;
      const double uy = static_cast<double>(ray.origin[1]) + static_cast<double>(ray.delta[1]) * t;
      for (int j = 0; j < v.layer; ++j) {
        const double scale = std::ldexp(1.0, kFrac + j);
        EXPECT_FALSE(in_window(w, j, static_cast<std::int64_t>(std::floor(ux / scale)),
                               static_cast<std::int64_t>(std::floor(uy / scale))))
            << "layer " << j << " holds a stretch walked in coarser layer " << v.layer;
      }
    }
  }
}

TEST(RayWalk, DegenerateRaysVisitNothing) {
  const RayWindows w = cadre_windows(0.0, 0.0);
  EXPECT_TRUE(walked(w, ray_of(10.0, 10.0, 0.0, 0.0)).empty()) << "no horizontal extent";
  // An origin outside every window (the coarsest spans 32 x 64 cm around the origin).
  EXPECT_TRUE(walked(w, ray_of(1.0e6 * 256, 0.0, -1000.0, 0.0)).empty()) << "origin outside every window";
  RayWindows none;
  EXPECT_TRUE(walked(none, ray_of(0.0, 0.0, 500.0, 0.0)).empty()) << "no layers";
}

TEST(RayWalk, ALongerRayThanTheWalkTakesKeepsItsDirection) {
  const RayWindows w = cadre_windows(0.0, 0.0);
  const RayU ray{{100, 200}, {std::int64_t{3} << 40, std::int64_t{1} << 40}};
  const std::vector<RayVisit> visits = walked(w, ray);
  ASSERT_FALSE(visits.empty());
  // Every visited cell lies on the line through the origin with slope 1/3 (within a cell).
  for (const RayVisit& v : visits) {
    const double scale = std::ldexp(1.0, kFrac + v.layer);
    const double cx = (v.index.x + 0.5) * scale - 100.0;
    const double cy = (v.index.y + 0.5) * scale - 200.0;
    EXPECT_LT(std::fabs(cy - cx / 3.0), 1.5 * scale) << "a halved ray must keep its direction";
  }
}

// ---- the record ----

TEST(FreeSpaceCell, BoundsRoundUpStayUpperBoundsAndOnlyDecrease) {
  using ccmap::detail::FreeSpaceCell;
  FreeSpaceCell c{};
  EXPECT_FALSE(ccmap::detail::has_bound(c)) << "an empty record has no bound";
  ccmap::detail::lower_bound(c, 0.1F);
  ASSERT_TRUE(ccmap::detail::has_bound(c));
  EXPECT_GE(ccmap::detail::bound_m(c), 0.1F) << "the stored bound is never below the ray";
  EXPECT_LT(ccmap::detail::bound_m(c), 0.1F + 0.00390625F) << "within one 2^-8 m step";
  ccmap::detail::lower_bound(c, 0.5F);
  EXPECT_LT(ccmap::detail::bound_m(c), 0.11F) << "a higher ray does not raise the bound";
  ccmap::detail::lower_bound(c, -2.30078125F);  // exact in 2^-8 m
  EXPECT_EQ(ccmap::detail::bound_m(c), -2.30078125F);
  const FreeSpaceCell before = c;
  ccmap::detail::lower_bound(c, -200.0F);
  ccmap::detail::lower_bound(c, std::nanf(""));
  EXPECT_EQ(c.bound_code, before.bound_code) << "heights beyond +-128 m and NaN carry no bound";
  FreeSpaceCell high{};
  ccmap::detail::lower_bound(high, 127.9F);
  EXPECT_GE(ccmap::detail::bound_m(high), 127.9F);
}

TEST(FreeSpaceCell, ADropNeedsTwoRaysAndFrameBitsResetWithTheStamp) {
  using ccmap::detail::FreeSpaceCell;
  FreeSpaceCell c{};
  EXPECT_FALSE(ccmap::detail::add_drop_ray(c));
  EXPECT_FALSE(ccmap::detail::is_drop(c)) << "one ray is not enough for a drop-off";
  EXPECT_TRUE(ccmap::detail::add_drop_ray(c)) << "the second ray makes it one";
  EXPECT_TRUE(ccmap::detail::is_drop(c));
  EXPECT_FALSE(ccmap::detail::add_drop_ray(c));
  EXPECT_FALSE(ccmap::detail::add_drop_ray(c));
  EXPECT_TRUE(ccmap::detail::is_drop(c)) << "saturates";
  // Per-frame contradictions: two rays make a contradicting frame, a confirmation cancels it.
  EXPECT_TRUE(ccmap::detail::touch(c, 3));
  ccmap::detail::add_contradiction(c);
  EXPECT_EQ(ccmap::detail::settle_frame(c), 0U) << "one contradicting ray in a frame is no evidence";
  EXPECT_TRUE(ccmap::detail::touch(c, 4)) << "a new frame";
  EXPECT_EQ(ccmap::detail::frame_contradictions(c), 0U) << "the new frame starts without contradictions";
  ccmap::detail::add_contradiction(c);
  ccmap::detail::add_contradiction(c);
  EXPECT_EQ(ccmap::detail::settle_frame(c), 1U);
  EXPECT_TRUE(ccmap::detail::touch(c, 5));
  ccmap::detail::add_contradiction(c);
  ccmap::detail::add_contradiction(c);
  ccmap::detail::add_contradiction(c);
  ccmap::detail::add_contradiction(c);
  EXPECT_EQ(ccmap::detail::frame_contradictions(c), 3U) << "saturates at 3";
  ccmap::detail::confirm(c);
  EXPECT_EQ(ccmap::detail::settle_frame(c), 0U) << "a ray ending on the surface forgets the evidence";
  EXPECT_TRUE(ccmap::detail::is_drop(c)) << "frame bits leave the drop-off count alone";
}

}  // namespace
