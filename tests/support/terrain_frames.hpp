// Analytic terrains and frames of map-frame points over them, for the registration tests and
// examples (host and aarch64/QEMU alike; test support, allocates).
//
// A frame: points uniform in area over a fan in front of a sensor (forward along +x from the
// sensor's ground position, +-half_angle, near_m .. far_m), each on the terrain, then moved
// along its ray by the CADRE stereo noise sigma(r) = r^2 / 300 (clipped at 2.5 sigma). Geometry
// in double, points rounded to float. A pose error is applied by `displace`: the frame the rover
// would see with a pose that is off by the inverse of a correction C, so that registration of
// the displaced frame should answer C (registration/types.hpp: p_true = Rz(yaw)(p - o) + o + d).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "ccmap/map/types.hpp"

namespace ccmap::test {

enum class Terrain {
  kFlat,      ///< z = 0
  kPlane,     ///< z = 0.15 x + 0.05 y (one tilted plane)
  kRampX,     ///< flat, a ramp of 0.3 m/m for 1.2 <= x <= 2.2, flat again (invariant along y)
  kBowl,      ///< z = 0.12 ((x - 2)^2 + (y - 0.5)^2): rotationally symmetric about (2, 0.5)
  kSinusoidX, ///< z = 0.05 sin(2 pi x / 0.8): repetitive along x, invariant along y
  kRolling,   ///< smooth bumps of different wavelengths across x and y: everything observable
  kRocks,     ///< a gentle swell and a dozen rocks (6..25 cm): what a rover sees, x-y-yaw weakly tied
};

struct TerrainRock {
  double x, y, radius, height;
};
inline constexpr TerrainRock kTerrainRocks[] = {
    {0.9, 0.4, 0.12, 0.08},  {1.3, -0.5, 0.18, 0.12}, {1.8, 0.9, 0.15, 0.10}, {2.2, -0.2, 0.25, 0.18},
    {2.7, 1.2, 0.20, 0.15},  {3.1, -1.1, 0.30, 0.20}, {3.4, 0.3, 0.22, 0.12}, {3.9, -0.4, 0.35, 0.25},
    {0.6, -0.9, 0.10, 0.06}, {2.5, 0.4, 0.12, 0.07},  {3.6, 1.6, 0.30, 0.20}, {1.5, 1.4, 0.20, 0.10},
};

[[nodiscard]] inline double terrain_height(Terrain t, double x, double y) {
  constexpr double kPi = 3.14159265358979323846;
  switch (t) {
    case Terrain::kFlat:
      return 0.0;
    case Terrain::kPlane:
      return 0.15 * x + 0.05 * y;
    case Terrain::kRampX:
      return x < 1.2 ? 0.0 : (x < 2.2 ? 0.3 * (x - 1.2) : 0.3);
    case Terrain::kBowl:
      return 0.12 * ((x - 2.0) * (x - 2.0) + (y - 0.5) * (y - 0.5));
    case Terrain::kSinusoidX:
      return 0.05 * std::sin(2.0 * kPi * x / 0.8);
    case Terrain::kRolling:
      return 0.06 * std::sin(2.0 * kPi * x / 1.3) * std::cos(2.0 * kPi * y / 1.1) +
             0.04 * std::sin(2.0 * kPi * (x + 0.6 * y) / 2.3);
    case Terrain::kRocks: {
      double z = 0.04 * std::sin(1.3 * x + 0.4) * std::cos(0.9 * y) + 0.02 * ((x - 2.0) * (x - 2.0) + y * y) * 0.25;
      for (const TerrainRock& r : kTerrainRocks) {
        const double dx = x - r.x;
        const double dy = y - r.y;
        const double q = 1.0 - (dx * dx + dy * dy) / (r.radius * r.radius);
        if (q > 0.0) {
          z = std::max(z, r.height * std::sqrt(q));
        }
      }
      return z;
    }
  }
  return 0.0;
}

struct TerrainFrameSpec {
  Terrain terrain = Terrain::kRolling;
  double sensor_x = 0.0;  ///< sensor ground position (m); the sensor is camera_height_m above the terrain there
  double sensor_y = 0.0;
  double heading = 0.0;   ///< rad, the fan's centre direction
  double camera_height_m = 0.175;
  double near_m = 0.3;
  double far_m = 4.5;
  double half_angle = 1.0;  ///< rad
  int points = 40000;
  std::uint32_t seed = 1U;  ///< noise seed; 0: no range noise
};

struct TerrainFrame {
  std::vector<PointXYZ> points;  ///< map frame
  PointXYZ origin{0.0F, 0.0F, 0.0F};
};

[[nodiscard]] inline TerrainFrame make_terrain_frame(const TerrainFrameSpec& spec) {
  TerrainFrame f;
  const double ox = spec.sensor_x;
  const double oy = spec.sensor_y;
  const double oz = terrain_height(spec.terrain, ox, oy) + spec.camera_height_m;
  f.origin = PointXYZ{static_cast<float>(ox), static_cast<float>(oy), static_cast<float>(oz)};
  std::mt19937 rng(spec.seed == 0U ? 12345U : spec.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  f.points.reserve(static_cast<std::size_t>(spec.points));
  for (int i = 0; i < spec.points; ++i) {
    // Uniform in area over the annular sector: r^2 uniform.
    const double r2 = spec.near_m * spec.near_m + unit(rng) * (spec.far_m * spec.far_m - spec.near_m * spec.near_m);
    const double r = std::sqrt(r2);
    const double a = spec.heading + (2.0 * unit(rng) - 1.0) * spec.half_angle;
    const double gx = ox + r * std::cos(a);
    const double gy = oy + r * std::sin(a);
    const double gz = terrain_height(spec.terrain, gx, gy);
    double px = gx - ox;
    double py = gy - oy;
    double pz = gz - oz;
    if (spec.seed != 0U) {
      const double range = std::sqrt(px * px + py * py + pz * pz);
      double n = normal(rng);
      n = n > 2.5 ? 2.5 : (n < -2.5 ? -2.5 : n);
      const double scale = 1.0 + n * range / 300.0;
      px *= scale;
      py *= scale;
      pz *= scale;
    }
    f.points.push_back(PointXYZ{static_cast<float>(ox + px), static_cast<float>(oy + py), static_cast<float>(oz + pz)});
  }
  return f;
}

/// A correction (registration/types.hpp): p_true = Rz(yaw)(p - o) + o + d.
struct TestCorrection {
  double dx = 0.0, dy = 0.0, dz = 0.0, yaw = 0.0;
};

/// The frame as a rover with a pose error sees it: every point moved by the inverse of c about
/// the frame's origin, p = Rz(-yaw)(p_true - o - d) + o (the origin itself stays: it is where
/// the rover believes it is, and the correction rotates about it).
[[nodiscard]] inline TerrainFrame displace(const TerrainFrame& truth, const TestCorrection& c) {
  TerrainFrame f = truth;
  const double ox = truth.origin.x;
  const double oy = truth.origin.y;
  const double cs = std::cos(-c.yaw);
  const double sn = std::sin(-c.yaw);
  for (PointXYZ& p : f.points) {
    const double x = p.x - ox - c.dx;
    const double y = p.y - oy - c.dy;
    p.x = static_cast<float>(ox + cs * x - sn * y);
    p.y = static_cast<float>(oy + sn * x + cs * y);
    p.z = static_cast<float>(p.z - c.dz);
  }
  return f;
}

}  // namespace ccmap::test
