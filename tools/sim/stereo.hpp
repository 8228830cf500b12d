// CADRE-like stereo camera simulator: ray casting onto a height raster, disparity noise and
// quantisation, optional border streaks.
//
// Model
//  - Pinhole camera width_px x height_px, focal focal_px, principal point at the image centre,
//    rays through pixel centres (u + 0.5, v + 0.5). Every pixel_stride-th pixel in u and v is
//    cast (1 = full frame).
//  - Mounting: the camera centre is camera_height_m above the terrain under the rover
//    (terrain.height(pose.x, pose.y)), looking along the rover heading, pitched down by
//    pitch_deg; no roll and no rover pitch/roll (the rover is assumed level).
//  - Sensor frame = camera optical frame: x right, y down, z forward; z is the depth Z.
//  - Ray casting: march along the ray over the raster's block-maximum grid (whole blocks the
//    ray stays above are skipped), clearance-based steps assuming slopes up to
//    max_assumed_slope inside a block, then bisection to max(0.5 mm, 1e-4 x range). Occlusion shadows follow
//    from taking the first crossing. Rays that leave the raster or exceed max_depth_m miss.
//  - Noise: d = f b / Z, d' = d + N(0, disparity_sigma_px), quantised to disparity_step_px
//    (0 = off), Z' = f b / d' (d' <= 0 is dropped). The depth error is thus
//    sigma_Z ~= Z^2 / (f b) * sqrt(sigma_d^2 + step^2 / 12)  (depth_sigma()).
//  - Border streaks (paper Section V-E): where a pixel's window (radius border_streak_radius_px)
//    holds a foreground depth Z_fg < (1 - border_streak_jump_ratio) * Z (or the pixel sees
//    nothing), with probability border_streak_probability the pixel takes the foreground depth
//    (or, with border_streak_interpolate, a depth uniform between Z_fg and Z): the obstacle's
//    top rim smears over the background behind it. Applied before the disparity noise.
//  - Mismatches (a block matcher's wrong matches): with probability mismatch_probability a pixel
//    that sees a surface gets a disparity uniform in [mismatch_disparity_min_px,
//    mismatch_disparity_max_px] instead of its own (no noise, no quantisation): a point anywhere
//    along its ray, most of them near the camera (uniform in disparity, not in depth). Off by
//    default; when off, no random number is drawn for it (frames stay as they were).
// Determinism: one Rng(seed) stream in pixel order; identical inputs give identical frames.
// Performance: a full 850 x 650 frame on a 1 cm raster of lunar-like terrain (horizon in view)
// takes ~0.45 s CPU on one core of the team's x86-64 build host; pixel_stride 2 about a
// quarter of that (measured with ccmap_sim_demo, which prints the CPU time).
#pragma once

#include <cstdint>
#include <vector>

#include "sim/terrain.hpp"
#include "sim/types.hpp"

namespace ccmap::sim {

struct StereoParams {
  int width_px = 850;
  int height_px = 650;
  double focal_px = 600.0;
  double baseline_m = 0.05;
  double camera_height_m = 0.175;
  double pitch_deg = 25.0;
  double disparity_sigma_px = 0.1;
  double disparity_step_px = 1.0 / 16.0;
  int pixel_stride = 1;
  double min_depth_m = 0.05;
  double max_depth_m = 20.0;
  double max_assumed_slope = 1.0;
  double border_streak_probability = 0.0;
  int border_streak_radius_px = 3;
  double border_streak_jump_ratio = 0.15;
  bool border_streak_interpolate = false;
  double mismatch_probability = 0.0;
  double mismatch_disparity_min_px = 1.0;    ///< 30 m depth with f b = 30 px m (CADRE)
  double mismatch_disparity_max_px = 100.0;  ///< 0.3 m
};

/// Per-point pixel record (parallel to the point vectors).
struct PixelSample {
  float u = 0.0F, v = 0.0F;       ///< pixel centre coordinates
  float true_depth_m = 0.0F;      ///< ray-cast depth before streaks and noise (NaN for a streak into sky)
  float depth_m = 0.0F;           ///< measured depth
  bool streak = false;            ///< depth replaced by a border streak
  bool mismatch = false;          ///< disparity replaced by a mismatch
};

struct StereoFrame {
  Pose2 true_pose;                    ///< pose used for ray casting
  Pose2 map_pose;                     ///< pose used to put points into the map frame (drift)
  Point3 sensor_position_map;         ///< camera centre, map frame (map_pose; z from the true ground)
  Point3 sensor_position_true;        ///< camera centre, world frame (true_pose)
  std::vector<Point3> points_sensor;  ///< optical frame: x right, y down, z forward (m)
  std::vector<Point3> points_map;     ///< points_sensor transformed with map_pose (m)
  std::vector<PixelSample> pixels;
  std::size_t rays_cast = 0;
  std::size_t rays_hit = 0;
  std::size_t streak_pixels = 0;
  std::size_t mismatch_pixels = 0;
};

/// Depth image on the strided pixel grid (cols x rows), NaN = no surface within range.
struct DepthImage {
  int cols = 0, rows = 0, stride = 1;
  std::vector<float> depth_m;
  float at(int c, int r) const { return depth_m[static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c)]; }
};

class StereoCamera {
 public:
  explicit StereoCamera(const StereoParams& params);

  const StereoParams& params() const { return p_; }

  /// One frame: rays from the camera at true_pose against `terrain`, points reported in the
  /// optical frame and in the map frame of map_pose (pass the same pose twice for no drift).
  StereoFrame capture(const HeightRaster& terrain, const Pose2& true_pose, const Pose2& map_pose,
                      std::uint64_t seed) const;
  StereoFrame capture(const HeightRaster& terrain, const Pose2& pose, std::uint64_t seed) const {
    return capture(terrain, pose, pose, seed);
  }

  /// Noise-free depth image seen from `pose`.
  DepthImage render_depth(const HeightRaster& terrain, const Pose2& pose) const;

  /// Camera centre (world frame) for a rover pose; z NaN if the pose is off the terrain.
  Point3 camera_position(const HeightRaster& terrain, const Pose2& pose) const;

  /// Optical frame -> world frame for a camera at `camera` with heading yaw.
  Point3 sensor_to_world(const Point3& p_sensor, const Point3& camera, double yaw) const;

  /// First crossing of origin + t * dir with the terrain for t in (0, t_max]; dir is any
  /// non-zero vector (t is in units of |dir|). NaN if none.
  double cast_ray(const HeightRaster& terrain, const Point3& origin, const Point3& dir, double t_max) const;

  /// Analytic depth standard deviation at depth Z (m): Z^2/(f b) sqrt(sigma_d^2 + step^2/12).
  double depth_sigma(double depth_m) const;

 private:
  void axes(double yaw, Point3* x_axis, Point3* y_axis, Point3* z_axis) const;
  StereoParams p_;
};

}  // namespace ccmap::sim
