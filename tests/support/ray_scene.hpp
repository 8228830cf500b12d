// Physically consistent stereo frames of analytic scenes for the free-space tests
// (tests/map/free_space_test.cpp): a sloped plane with axis-aligned boxes (rocks, rovers) standing
// on it and rectangular ditches cut into it, seen by a pinhole camera whose lines of sight are
// cast in double precision (first crossing of the surface: a march, then bisection), so every
// point is what the camera can see: nothing behind a box, the inside of a ditch only where a line
// of sight reaches it. Independent of the library (it shares only PointXYZ). Test support:
// allocates, uses double.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "ccmap/map/types.hpp"

namespace ccmap::test {

struct SceneBox {
  double x0, y0, x1, y1;
  double height;  ///< above the plane
};
struct SceneDitch {
  double x0, y0, x1, y1;
  double depth;  ///< below the plane
};

struct AnalyticScene {
  double slope_x = 0.0;  ///< plane z = slope_x * x
  std::vector<SceneBox> boxes;
  std::vector<SceneDitch> ditches;

  [[nodiscard]] double plane(double x) const { return slope_x * x; }
  /// The surface a camera sees at (x, y).
  [[nodiscard]] double height(double x, double y) const {
    double z = plane(x);
    for (const SceneDitch& d : ditches) {
      if (x >= d.x0 && x <= d.x1 && y >= d.y0 && y <= d.y1) {
        z = plane(x) - d.depth;
      }
    }
    for (const SceneBox& b : boxes) {
      if (x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1) {
        z = z > plane(x) + b.height ? z : plane(x) + b.height;
      }
    }
    return z;
  }
  [[nodiscard]] double max_height() const {
    double h = 0.0;
    for (const SceneBox& b : boxes) {
      h = b.height > h ? b.height : h;
    }
    return h;
  }
};

/// A CADRE-like camera: `height_m` above the plane at (x, y), looking along yaw (cos, sin), rows
/// spaced like a pinhole's between the depression angles of flat ground at near_m and far_m,
/// columns over +-half_fov_tan (tangent of the half field of view).
struct SceneCamera {
  double x = 0.0, y = 0.0;
  double height_m = 0.175;
  double heading_cos = 1.0, heading_sin = 0.0;
  int cols = 120, rows = 90;
  double near_m = 0.3, far_m = 5.0;
  double half_fov_tan = 0.7;
  double max_range_m = 8.0;
  /// Range noise along the ray: sigma = noise_per_range_sq * r^2 (CADRE: 1/300), Gaussian
  /// (Box-Muller from a 64-bit LCG: deterministic, unclipped); 0 = none.
  double noise_per_range_sq = 0.0;
  std::uint64_t seed = 1;
};

struct SceneFrame {
  std::vector<PointXYZ> points;  ///< map frame
  PointXYZ origin{0.0F, 0.0F, 0.0F};
};

namespace detail_scene {
inline double uniform(std::uint64_t& s) {
  s = s * 6364136223846793005ULL + 1442695040888963407ULL;
  return (static_cast<double>(s >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}
inline double gaussian(std::uint64_t& s) {
  const double u1 = uniform(s);
  const double u2 = uniform(s);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}
}  // namespace detail_scene

/// First crossing of origin + t * dir (dir unit) with the scene surface for t in (0, t_max]; -1 if none.
inline double cast_scene_ray(const AnalyticScene& scene, const double* o, const double* d, double t_max) {
  auto above = [&](double tt) {
    const double x = o[0] + d[0] * tt;
    const double y = o[1] + d[1] * tt;
    return o[2] + d[2] * tt > scene.height(x, y);
  };
  if (!above(0.0)) {
    return -1.0;
  }
  // Nothing stands higher than max_height() above the plane: the march starts where the ray
  // comes down to that height above it (the ray's height above the plane falls at rate `sink`).
  double t = 0.0;
  const double clearance = o[2] - scene.plane(o[0]) - scene.max_height();
  const double sink = scene.slope_x * d[0] - d[2];
  if (clearance > 0.0 && sink > 0.0) {
    t = clearance / sink;
  }
  const double step = 0.01;
  while (t < t_max) {
    const double next = t + step < t_max ? t + step : t_max;
    if (!above(next)) {
      double lo = t;
      double hi = next;
      for (int i = 0; i < 40; ++i) {
        const double mid = 0.5 * (lo + hi);
        (above(mid) ? lo : hi) = mid;
      }
      return hi;
    }
    t = next;
  }
  return -1.0;
}

namespace detail_scene {
/// One pixel's line of sight: its unit direction and where it meets the scene (-1: a miss).
struct PixelCast {
  double d[3];
  double t;
};
/// The casts of one scene seen from one pose: everything of a frame but its range noise.
struct SceneCasts {
  AnalyticScene scene;
  SceneCamera camera;  ///< its seed and noise are not part of the casts
  std::vector<PixelCast> pixels;
};
inline bool same_rects(const SceneBox& a, const SceneBox& b) {
  return a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1 && a.height == b.height;
}
inline bool same_rects(const SceneDitch& a, const SceneDitch& b) {
  return a.x0 == b.x0 && a.y0 == b.y0 && a.x1 == b.x1 && a.y1 == b.y1 && a.depth == b.depth;
}
template <typename Rect>
bool same_rect_lists(const std::vector<Rect>& a, const std::vector<Rect>& b) {
  if (a.size() != b.size()) {
    return false;
  }
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!same_rects(a[i], b[i])) {
      return false;
    }
  }
  return true;
}
/// True if the casts of `c` are those of `scene` from `cam` (every field but seed and noise).
inline bool casts_match(const SceneCasts& c, const AnalyticScene& scene, const SceneCamera& cam) {
  const SceneCamera& k = c.camera;
  return c.scene.slope_x == scene.slope_x && same_rect_lists(c.scene.boxes, scene.boxes) &&
         same_rect_lists(c.scene.ditches, scene.ditches) && k.x == cam.x && k.y == cam.y &&
         k.height_m == cam.height_m && k.heading_cos == cam.heading_cos && k.heading_sin == cam.heading_sin &&
         k.cols == cam.cols && k.rows == cam.rows && k.near_m == cam.near_m && k.far_m == cam.far_m &&
         k.half_fov_tan == cam.half_fov_tan && k.max_range_m == cam.max_range_m;
}
/// The camera's centre, map frame (m): `height_m` above the scene's plane at (x, y), where every
/// line of sight of a frame starts and the frame's origin.
inline std::array<double, 3> camera_origin(const AnalyticScene& scene, const SceneCamera& cam) {
  return {cam.x, cam.y, scene.plane(cam.x) + cam.height_m};
}
/// Every pixel's cast of `scene` from `cam`, in row-major order.
inline void cast_pixels(const AnalyticScene& scene, const SceneCamera& cam, std::vector<PixelCast>& out) {
  out.clear();
  const std::array<double, 3> o = camera_origin(scene, cam);
  const double t_far = cam.height_m / cam.far_m;
  const double t_near = cam.height_m / cam.near_m;
  for (int r = 0; r < cam.rows; ++r) {
    const double tan_down = t_far + (t_near - t_far) * (cam.rows > 1 ? static_cast<double>(r) / (cam.rows - 1) : 0.0);
    for (int c = 0; c < cam.cols; ++c) {
      const double lateral = cam.half_fov_tan * (cam.cols > 1 ? 2.0 * c / (cam.cols - 1) - 1.0 : 0.0);
      // Direction in the camera's heading frame (forward 1, left `lateral`, down tan_down).
      PixelCast p{{cam.heading_cos - cam.heading_sin * lateral, cam.heading_sin + cam.heading_cos * lateral, -tan_down},
                  -1.0};
      const double norm = std::sqrt(p.d[0] * p.d[0] + p.d[1] * p.d[1] + p.d[2] * p.d[2]);
      for (double& v : p.d) {
        v /= norm;
      }
      p.t = cast_scene_ray(scene, o.data(), p.d, cam.max_range_m);
      out.push_back(p);
    }
  }
}
}  // namespace detail_scene

/// One frame: every pixel's line of sight cast against the scene, then its range noise; misses
/// give no point. The casts do not depend on the seed: those of the last scene and pose are kept
/// (per thread) and reused when the next frame is of the same scene from the same pose, so a
/// test folding many noisy frames of one view casts once (the frames are the same bit for bit).
inline SceneFrame render_scene(const AnalyticScene& scene, const SceneCamera& cam) {
  thread_local detail_scene::SceneCasts casts;
  if (casts.pixels.empty() || !detail_scene::casts_match(casts, scene, cam)) {
    casts.scene = scene;
    casts.camera = cam;
    detail_scene::cast_pixels(scene, cam, casts.pixels);
  }
  SceneFrame frame;
  const std::array<double, 3> o = detail_scene::camera_origin(scene, cam);
  frame.origin = PointXYZ{static_cast<float>(o[0]), static_cast<float>(o[1]), static_cast<float>(o[2])};
  std::uint64_t rng = cam.seed * 0x9E3779B97F4A7C15ULL + 1U;
  for (const detail_scene::PixelCast& p : casts.pixels) {
    double t = p.t;
    if (t < 0.0) {
      continue;
    }
    if (cam.noise_per_range_sq > 0.0) {
      t += detail_scene::gaussian(rng) * cam.noise_per_range_sq * t * t;
    }
    frame.points.push_back(PointXYZ{static_cast<float>(o[0] + p.d[0] * t), static_cast<float>(o[1] + p.d[1] * t),
                                    static_cast<float>(o[2] + p.d[2] * t)});
  }
  return frame;
}

}  // namespace ccmap::test
