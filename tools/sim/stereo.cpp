#include "sim/stereo.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/rng.hpp"

namespace ccmap::sim {

StereoCamera::StereoCamera(const StereoParams& params) : p_(params) {
  p_.pixel_stride = std::max(1, p_.pixel_stride);
  p_.border_streak_radius_px = std::max(1, p_.border_streak_radius_px);
}

double StereoCamera::depth_sigma(double depth_m) const {
  const double q = p_.disparity_step_px;
  return depth_m * depth_m / (p_.focal_px * p_.baseline_m) *
         std::sqrt(p_.disparity_sigma_px * p_.disparity_sigma_px + q * q / 12.0);
}

void StereoCamera::axes(double yaw, Point3* x_axis, Point3* y_axis, Point3* z_axis) const {
  const double pitch = p_.pitch_deg * kPi / 180.0;
  const double cp = std::cos(pitch), sp = std::sin(pitch), cy = std::cos(yaw), sy = std::sin(yaw);
  *x_axis = Point3{sy, -cy, 0.0};             // image right
  *z_axis = Point3{cp * cy, cp * sy, -sp};    // optical axis, pitched down
  *y_axis = Point3{-sp * cy, -sp * sy, -cp};  // image down = z x x
}

Point3 StereoCamera::camera_position(const HeightRaster& terrain, const Pose2& pose) const {
  return Point3{pose.x, pose.y, terrain.height(pose.x, pose.y) + p_.camera_height_m};
}

Point3 StereoCamera::sensor_to_world(const Point3& s, const Point3& camera, double yaw) const {
  Point3 ax, ay, az;
  axes(yaw, &ax, &ay, &az);
  return Point3{camera.x + s.x * ax.x + s.y * ay.x + s.z * az.x, camera.y + s.x * ax.y + s.y * ay.y + s.z * az.y,
                camera.z + s.x * ax.z + s.y * ay.z + s.z * az.z};
}

double StereoCamera::cast_ray(const HeightRaster& terrain, const Point3& o, const Point3& d, double t_max) const {
  if (terrain.empty() || terrain.blocks_x() == 0) return kNaN;
  const double len = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  if (!(len > 0.0)) return kNaN;
  const double horizontal = std::sqrt(d.x * d.x + d.y * d.y) / len;  // |horizontal| per metre of ray
  const double descent = std::max(0.0, -d.z / len);                  // drop per metre of ray
  const double slope = p_.max_assumed_slope;
  const double res = terrain.resolution();
  const double block_m = res * terrain.block_size();
  const double ox = terrain.origin_x(), oy = terrain.origin_y();
  const double global_max = terrain.blocks_max();
  auto height_at = [&](double t, double* clear) {
    const double x = o.x + t * d.x, y = o.y + t * d.y, z = o.z + t * d.z;
    const double h = terrain.height(x, y);
    *clear = z - h;
    return std::isfinite(h);
  };
  double clear = 0.0;
  if (!height_at(0.0, &clear) || !(clear > 0.0)) return kNaN;
  double t = 0.0;
  const double tiny = 1e-9;
  while (t < t_max) {
    const double px = o.x + t * d.x, py = o.y + t * d.y, pz = o.z + t * d.z;
    if (d.z >= 0.0 && pz > global_max) return kNaN;  // climbing above everything
    // Block containing p (clamped: p may sit exactly on the far edge).
    int bi = static_cast<int>(std::floor((px - ox) / block_m));
    int bj = static_cast<int>(std::floor((py - oy) / block_m));
    if (bi < 0 || bj < 0 || bi >= terrain.blocks_x() || bj >= terrain.blocks_y()) return kNaN;
    // Parametric exit of the ray from the block (in t units).
    double t_exit = t_max;
    if (d.x > 0.0) t_exit = std::min(t_exit, t + (ox + (bi + 1) * block_m - px) / d.x);
    if (d.x < 0.0) t_exit = std::min(t_exit, t + (ox + bi * block_m - px) / d.x);
    if (d.y > 0.0) t_exit = std::min(t_exit, t + (oy + (bj + 1) * block_m - py) / d.y);
    if (d.y < 0.0) t_exit = std::min(t_exit, t + (oy + bj * block_m - py) / d.y);
    t_exit = std::max(t_exit, t);
    const double z_exit = o.z + t_exit * d.z;
    const double bmax = terrain.block_max(bi, bj);
    if (std::min(pz, z_exit) > bmax) {
      t = t_exit + tiny * (1.0 + t_exit);  // nothing in this block can be hit
      continue;
    }
    if (pz > bmax && d.z < 0.0) {
      // Descending ray above the block's top: nothing can be hit before it sinks to bmax.
      t = std::min(t_exit, t + (pz - bmax) / -d.z);
    }
    if (!height_at(t, &clear)) return kNaN;
    const double depth_m = t * len;
    const double step_min = std::max(0.25 * res, 0.001 * depth_m);
    const double step_max = std::max(4.0 * res, 0.05 * depth_m);
    double step_m = clear / (descent + slope * horizontal + 1e-12);
    step_m = std::min(std::max(step_m, step_min), step_max);
    double t_next = std::min(t + step_m / len, t_exit + tiny * (1.0 + t_exit));
    if (t_next > t_max) t_next = t_max;
    double clear_next = 0.0;
    if (!height_at(t_next, &clear_next)) return kNaN;
    if (clear_next <= 0.0) {
      double lo = t, hi = t_next;  // clear(lo) > 0 >= clear(hi)
      // Bisect to 0.5 mm or 1e-4 of the range (far below the stereo depth noise there).
      const double tolerance_m = std::max(5e-4, 1e-4 * depth_m);
      for (int k = 0; k < 40 && (hi - lo) * len > tolerance_m; ++k) {
        const double mid = 0.5 * (lo + hi);
        double c = 0.0;
        if (!height_at(mid, &c)) return kNaN;
        if (c > 0.0) lo = mid; else hi = mid;
      }
      return 0.5 * (lo + hi);
    }
    if (t_next >= t_max) return kNaN;
    t = t_next;
  }
  return kNaN;
}

DepthImage StereoCamera::render_depth(const HeightRaster& terrain, const Pose2& pose) const {
  DepthImage img;
  img.stride = p_.pixel_stride;
  img.cols = (p_.width_px + img.stride - 1) / img.stride;
  img.rows = (p_.height_px + img.stride - 1) / img.stride;
  img.depth_m.assign(static_cast<std::size_t>(img.cols) * static_cast<std::size_t>(img.rows),
                     std::numeric_limits<float>::quiet_NaN());
  const Point3 cam = camera_position(terrain, pose);
  if (!std::isfinite(cam.z)) return img;
  Point3 ax, ay, az;
  axes(pose.yaw, &ax, &ay, &az);
  const double cx = 0.5 * p_.width_px, cy = 0.5 * p_.height_px;
  for (int r = 0; r < img.rows; ++r) {
    const double yn = (r * img.stride + 0.5 - cy) / p_.focal_px;
    for (int c = 0; c < img.cols; ++c) {
      const double xn = (c * img.stride + 0.5 - cx) / p_.focal_px;
      // Direction with unit depth: t is then the depth Z along the optical axis.
      const Point3 dir{xn * ax.x + yn * ay.x + az.x, xn * ax.y + yn * ay.y + az.y, xn * ax.z + yn * ay.z + az.z};
      const double z = cast_ray(terrain, cam, dir, p_.max_depth_m);
      if (std::isfinite(z) && z >= p_.min_depth_m) {
        img.depth_m[static_cast<std::size_t>(r) * static_cast<std::size_t>(img.cols) + static_cast<std::size_t>(c)] =
            static_cast<float>(z);
      }
    }
  }
  return img;
}

StereoFrame StereoCamera::capture(const HeightRaster& terrain, const Pose2& true_pose, const Pose2& map_pose,
                                  std::uint64_t seed) const {
  StereoFrame frame;
  frame.true_pose = true_pose;
  frame.map_pose = map_pose;
  frame.sensor_position_true = camera_position(terrain, true_pose);
  frame.sensor_position_map = Point3{map_pose.x, map_pose.y, frame.sensor_position_true.z};
  const DepthImage img = render_depth(terrain, true_pose);
  frame.rays_cast = img.depth_m.size();
  if (!std::isfinite(frame.sensor_position_true.z)) return frame;
  Rng rng(seed);
  const double fb = p_.focal_px * p_.baseline_m;
  const double cx = 0.5 * p_.width_px, cy = 0.5 * p_.height_px;
  const int radius = (p_.border_streak_radius_px + img.stride - 1) / img.stride;
  const bool streaks = p_.border_streak_probability > 0.0;
  Point3 ax, ay, az;
  axes(map_pose.yaw, &ax, &ay, &az);
  const Point3& cam = frame.sensor_position_map;
  frame.points_sensor.reserve(img.depth_m.size());
  frame.points_map.reserve(img.depth_m.size());
  frame.pixels.reserve(img.depth_m.size());
  for (int r = 0; r < img.rows; ++r) {
    for (int c = 0; c < img.cols; ++c) {
      const float true_depth = img.at(c, r);
      double depth = true_depth;
      bool streak = false;
      if (std::isfinite(true_depth)) ++frame.rays_hit;
      if (streaks) {
        // Foreground in the window: the nearest depth around the pixel.
        double fg = std::numeric_limits<double>::infinity();
        for (int dr = -radius; dr <= radius; ++dr) {
          const int rr = r + dr;
          if (rr < 0 || rr >= img.rows) continue;
          for (int dc = -radius; dc <= radius; ++dc) {
            const int cc = c + dc;
            if (cc < 0 || cc >= img.cols) continue;
            const float v = img.at(cc, rr);
            if (std::isfinite(v) && v < fg) fg = v;
          }
        }
        const bool background = std::isfinite(fg) && (!std::isfinite(depth) || fg < (1.0 - p_.border_streak_jump_ratio) * depth);
        if (background && rng.uniform() < p_.border_streak_probability) {
          const double far_depth = std::isfinite(depth) ? depth : p_.max_depth_m;
          depth = p_.border_streak_interpolate ? fg + rng.uniform() * (far_depth - fg) : fg;
          streak = true;
          ++frame.streak_pixels;
        }
      }
      if (!std::isfinite(depth)) continue;
      double disparity = fb / depth + rng.normal(0.0, p_.disparity_sigma_px);
      if (p_.disparity_step_px > 0.0) disparity = std::round(disparity / p_.disparity_step_px) * p_.disparity_step_px;
      const bool mismatch = p_.mismatch_probability > 0.0 && rng.uniform() < p_.mismatch_probability;
      if (mismatch) {
        disparity = rng.uniform(p_.mismatch_disparity_min_px, p_.mismatch_disparity_max_px);
        ++frame.mismatch_pixels;
      }
      if (!(disparity > 0.0)) continue;
      const double z = fb / disparity;
      const double xn = (c * img.stride + 0.5 - cx) / p_.focal_px;
      const double yn = (r * img.stride + 0.5 - cy) / p_.focal_px;
      const Point3 ps{xn * z, yn * z, z};
      frame.points_sensor.push_back(ps);
      frame.points_map.push_back(Point3{cam.x + ps.x * ax.x + ps.y * ay.x + ps.z * az.x,
                                        cam.y + ps.x * ax.y + ps.y * ay.y + ps.z * az.y,
                                        cam.z + ps.x * ax.z + ps.y * ay.z + ps.z * az.z});
      PixelSample px;
      px.u = static_cast<float>(c * img.stride + 0.5);
      px.v = static_cast<float>(r * img.stride + 0.5);
      px.true_depth_m = true_depth;
      px.depth_m = static_cast<float>(z);
      px.streak = streak;
      px.mismatch = mismatch;
      frame.pixels.push_back(px);
    }
  }
  return frame;
}

}  // namespace ccmap::sim
