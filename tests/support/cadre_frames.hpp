// Deterministic CADRE-like stereo frames for the update-path tests, the timing test and the
// benchmarks (host and aarch64/QEMU alike: no host tools, no files).
//
// The scene: gently undulating ground with a dozen rocks (3..20 cm high). The camera: the
// CADRE stereo head 17.5 cm above the ground, looking forward along the robot's heading. Each
// pixel (u, v) of a width x height image is one point:
//  - rows are spaced linearly in the tangent of the depression angle (a pinhole's rows)
//    between the far row (forward distance far_m) and the near row (near_m): dense near the
//    robot, sparse far away, as a camera;
//  - columns spread laterally like a pinhole of focal 600 px over 850 px (+-35 deg);
//  - the ray meets the terrain, then the range is perturbed along the ray by the CADRE stereo
//    noise sigma(r) = r^2 / 300 (clipped at 2.5 sigma).
// With the defaults (0.3 .. 4.0 m forward) every point lies within 5.1 m of the sensor, i.e.
// inside the IV-G range of the 64 cm layer (5.26 m) and inside every window of the CADRE stack
// centred on the sensor: all 552,500 points of an 850 x 650 frame are used.
//
// The random numbers are integer (xorshift) and the geometry uses only +, -, *, /, sqrt
// (correctly rounded on every IEEE target), so a frame is bitwise identical on x86-64 and
// aarch64 when both build with -ffp-contract=off.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "ccmap/map/types.hpp"
#include "support/poses.hpp"

namespace ccmap::test {

struct CadreFrameSpec {
  int width_px = 850;
  int height_px = 650;
  float camera_height_m = 0.175F;
  float near_m = 0.3F;   ///< forward distance of the bottom row on flat ground
  float far_m = 4.0F;    ///< forward distance of the top row on flat ground
  float sensor_x = 0.0F; ///< sensor position in the map frame (m)
  float sensor_y = 0.0F;
  /// Heading as (cos, sin) so that no trigonometric function is evaluated (bitwise portable).
  float heading_cos = 1.0F;
  float heading_sin = 0.0F;
  std::uint32_t seed = 1U;  ///< noise seed; 0 -> no range noise
  /// Shares of pixels a stereo matcher does not deliver as usable ground points, chosen by an
  /// integer hash of the pixel (deterministic): `invalid_share` NaN (no disparity), `far_share`
  /// pushed along their ray to 6..15 m (sky, far hills, mismatches: beyond every IV-G range).
  float invalid_share = 0.0F;
  float far_share = 0.0F;
};

struct CadreFrame {
  std::vector<PointXYZ> map_points;     ///< map frame
  std::vector<PointXYZ> sensor_points;  ///< sensor frame: x forward, y left, z up
  PointXYZ sensor_origin{0.0F, 0.0F, 0.0F};
  Pose pose;                            ///< sensor -> map
};

namespace detail_frames {
struct Rock {
  float x, y, radius, height;
};
// Fixed rocks in the robot's surroundings (map frame, m).
inline constexpr Rock kRocks[] = {
    {0.55F, 0.10F, 0.06F, 0.04F}, {0.80F, -0.35F, 0.10F, 0.07F}, {1.10F, 0.40F, 0.08F, 0.03F},
    {1.40F, -0.05F, 0.15F, 0.12F}, {1.90F, 0.70F, 0.12F, 0.09F}, {2.30F, -0.80F, 0.20F, 0.20F},
    {2.80F, 0.20F, 0.18F, 0.15F}, {3.20F, -0.30F, 0.10F, 0.06F}, {3.60F, 1.10F, 0.25F, 0.18F},
    {0.45F, -0.60F, 0.07F, 0.05F}, {-0.40F, 0.30F, 0.10F, 0.08F}, {0.00F, 0.90F, 0.12F, 0.10F},
};

/// Terrain height (m) at map (x, y): a smooth polynomial swell (no trig: portable) plus rocks
/// (half ellipsoids).
inline float terrain_height(float x, float y) {
  const float u = 0.25F * x;
  const float v = 0.25F * y;
  float z = 0.03F * u * (1.0F - u) + 0.02F * v * v - 0.015F * u * v;
  for (const Rock& r : kRocks) {
    const float dx = x - r.x;
    const float dy = y - r.y;
    const float q = 1.0F - (dx * dx + dy * dy) / (r.radius * r.radius);
    if (q > 0.0F) {
      const float h = r.height * std::sqrt(q);
      z = h > z ? h : z;
    }
  }
  return z;
}

struct XorShift {
  std::uint64_t state;
  std::uint32_t next() {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return static_cast<std::uint32_t>(state >> 32);
  }
  /// Approximately standard normal: Irwin-Hall sum of 4 uniforms, scaled to unit variance.
  float normal() {
    float s = 0.0F;
    for (int i = 0; i < 4; ++i) {
      s += static_cast<float>(next() >> 8) * (1.0F / 16777216.0F);
    }
    return (s - 2.0F) * 1.7320508F;  // var of the sum = 4/12
  }
};
}  // namespace detail_frames

/// Writes one frame (image order: top row first, left to right) into the caller's buffers of
/// width_px * height_px points each, and its sensor origin and pose. No heap (the bare-metal
/// tests call it with static buffers).
inline void fill_cadre_frame(const CadreFrameSpec& spec, PointXYZ* map_points, PointXYZ* sensor_points,
                             PointXYZ* sensor_origin, Pose* pose) {
  using detail_frames::XorShift;
  const float h = spec.camera_height_m;
  const float c = spec.heading_cos;
  const float s = spec.heading_sin;
  *sensor_origin = PointXYZ{spec.sensor_x, spec.sensor_y, h};
  *pose = yaw_pose(c, s, PointXYZ{spec.sensor_x, spec.sensor_y, h});
  XorShift rng{0x9E3779B97F4A7C15ULL ^ (static_cast<std::uint64_t>(spec.seed) * 0x2545F4914F6CDD1DULL)};
  // Rows linear in t = h / d, the tangent of the depression angle (a pinhole's row spacing).
  const float t_far = h / spec.far_m;
  const float t_near = h / spec.near_m;
  const float half_width = 0.5F * static_cast<float>(spec.width_px - 1);
  const float lateral_scale = 425.0F / 600.0F / (half_width > 0.0F ? half_width : 1.0F);
  std::size_t i = 0;
  for (int v = 0; v < spec.height_px; ++v) {
    const float row = spec.height_px > 1 ? static_cast<float>(v) / static_cast<float>(spec.height_px - 1) : 0.0F;
    const float t = t_far + (t_near - t_far) * row;
    const float forward = h / t;
    for (int u = 0; u < spec.width_px; ++u, ++i) {
      const float lateral = -forward * (static_cast<float>(u) - half_width) * lateral_scale;  // +y = left
      // Flat-ground point in the sensor-heading frame, then its map position and the terrain.
      const float gx = spec.sensor_x + c * forward - s * lateral;
      const float gy = spec.sensor_y + s * forward + c * lateral;
      const float gz = detail_frames::terrain_height(gx, gy);
      // Sensor frame vector to the terrain point (x forward, y left, z up).
      float px = forward;
      float py = lateral;
      float pz = gz - h;
      if (spec.seed != 0U) {
        const float r = std::sqrt(px * px + py * py + pz * pz);
        float n_sigma = rng.normal();
        n_sigma = n_sigma > 2.5F ? 2.5F : (n_sigma < -2.5F ? -2.5F : n_sigma);
        const float scale = 1.0F + n_sigma * (r / 300.0F);  // r + n * r^2/300, along the ray
        px *= scale;
        py *= scale;
        pz *= scale;
      }
      // Unusable pixels (integer hash in [0, 1): portable).
      const std::uint32_t hashed = static_cast<std::uint32_t>(
          (static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ULL ^ (static_cast<std::uint64_t>(spec.seed) << 32)) >> 40);
      const float u01 = static_cast<float>(hashed & 0xFFFFFFU) * (1.0F / 16777216.0F);
      if (u01 < spec.invalid_share) {
        const float nan = std::numeric_limits<float>::quiet_NaN();
        px = nan;
        py = nan;
        pz = nan;
      } else if (u01 < spec.invalid_share + spec.far_share) {
        const float r = std::sqrt(px * px + py * py + pz * pz);
        const float far = 6.0F + 9.0F * (u01 - spec.invalid_share) / spec.far_share;
        px *= far / r;
        py *= far / r;
        pz *= far / r;
      }
      sensor_points[i] = PointXYZ{px, py, pz};
      map_points[i] = PointXYZ{spec.sensor_x + c * px - s * py, spec.sensor_y + s * px + c * py, h + pz};
    }
  }
}

/// Builds one frame (fill_cadre_frame into vectors). Allocates (test support).
inline CadreFrame make_cadre_frame(const CadreFrameSpec& spec) {
  CadreFrame frame;
  const std::size_t n = static_cast<std::size_t>(spec.width_px) * static_cast<std::size_t>(spec.height_px);
  frame.map_points.resize(n);
  frame.sensor_points.resize(n);
  fill_cadre_frame(spec, frame.map_points.data(), frame.sensor_points.data(), &frame.sensor_origin, &frame.pose);
  return frame;
}

/// The k-th frame of a deterministic sequence: the robot standing at the origin, turning by
/// ~0.1 rad per frame (heading from an integer rotation, no trig), a new noise seed each frame.
inline CadreFrameSpec cadre_sequence_spec(int k, int width_px = 850, int height_px = 650) {
  CadreFrameSpec spec;
  spec.width_px = width_px;
  spec.height_px = height_px;
  // Rotate (1, 0) k times by 0.1 rad with a fixed rotation (cos 0.1, sin 0.1), renormalised.
  float c = 1.0F;
  float s = 0.0F;
  for (int j = 0; j < k; ++j) {
    const float nc = c * 0.99500417F - s * 0.09983342F;
    const float ns = s * 0.99500417F + c * 0.09983342F;
    const float norm = std::sqrt(nc * nc + ns * ns);
    c = nc / norm;
    s = ns / norm;
  }
  spec.heading_cos = c;
  spec.heading_sin = s;
  spec.seed = static_cast<std::uint32_t>(k) + 1U;
  return spec;
}

}  // namespace ccmap::test
