// Inputs of the cell-math cases (cell_cases.cpp) and of their reference generator
// (make_cell_reference.cpp): deterministic float points from an integer hash, built with
// + - * only (correctly rounded on every IEEE target, -ffp-contract=off), so the host that
// computes the double-precision references and the target under test see the same bits.
// Nothing here calls the library.
#pragma once

#include <cstddef>
#include <cstdint>

#include "support/hash_unit.hpp"

namespace ccmap::test::cells {

struct Input {
  float x;  ///< m, relative to the cell centre
  float y;
  float z;  ///< m, map frame
  float w;  ///< measurement weight
};

/// The CCM cases. Each is one cell of width kCellWidthM fed point after point (no limiter),
/// except kPooled: four child cells of width kCellWidthM / 2 pooled into their parent.
enum CcmCase : int {
  kCloud = 0,      ///< uniform over the cell, a tilted plane plus +-5 mm noise, unit weights
  kWeighted = 1,   ///< a 12 cm step across the cell, weights 0.25 .. 4
  kPlane20 = 2,    ///< a noise-free plane inclined 20 deg (azimuth 30 deg)
  kFarOffset = 3,  ///< the cloud 250 m above the stack origin (cancellation in the z moments)
  kPooled = 4,     ///< a 16 x 16 grid over the parent, 8 x 8 per child, on a tilted plane
  kCcmCaseCount = 5,
};

inline constexpr float kCellWidthM = 0.16F;
/// tan(20 deg) cos(30 deg), tan(20 deg) sin(30 deg): the kPlane20 gradient, the double values
/// 0.31520746909590464 and 0.18198511713310117 rounded to float (make_cell_reference checks
/// them against tan/cos in double).
inline constexpr float kPlane20SlopeX = 0.315207481F;
inline constexpr float kPlane20SlopeY = 0.18198511F;
/// tan(20 deg), the kPlane20 inclination.
inline constexpr float kTan20 = 0.36397022F;

inline constexpr std::uint32_t ccm_point_count(int c) noexcept {
  return c == kCloud ? 400U : c == kWeighted ? 300U : c == kPlane20 ? 256U : c == kFarOffset ? 400U : 256U;
}

/// Query point (relative to the cell centre) at which the sub-cell height is checked.
inline constexpr float kQueryX = 0.05F;
inline constexpr float kQueryY = -0.03F;

/// Point i of case c. For kPooled: the point in the *parent* frame; pooled_child() says which
/// child it belongs to and child_offset() where that child's centre is.
inline Input ccm_point(int c, std::uint32_t i) noexcept {
  const std::uint32_t id = static_cast<std::uint32_t>(c) * 100000U + i;
  const float u = hash_unit(id, 11U) - 0.5F;  // [-0.5, 0.5)
  const float v = hash_unit(id, 12U) - 0.5F;
  const float noise = 0.01F * (hash_unit(id, 13U) - 0.5F);
  switch (c) {
    case kCloud: {
      const float x = kCellWidthM * u, y = kCellWidthM * v;
      return Input{x, y, 0.05F + 0.3F * x - 0.2F * y + noise, 1.0F};
    }
    case kWeighted: {
      const float x = kCellWidthM * u, y = kCellWidthM * v;
      return Input{x, y, (x > 0.02F ? 0.12F : 0.0F) + noise, 0.25F + 3.75F * hash_unit(id, 14U)};
    }
    case kPlane20: {
      // A 16 x 16 grid (exact in float), z from the inclined plane.
      const float x = kCellWidthM * (static_cast<float>(i % 16U) + 0.5F) * (1.0F / 16.0F) - 0.5F * kCellWidthM;
      const float y = kCellWidthM * (static_cast<float>(i / 16U) + 0.5F) * (1.0F / 16.0F) - 0.5F * kCellWidthM;
      return Input{x, y, -0.4F + kPlane20SlopeX * x + kPlane20SlopeY * y, 1.0F};
    }
    case kFarOffset: {
      const float x = kCellWidthM * u, y = kCellWidthM * v;
      return Input{x, y, 250.0F + 0.3F * x - 0.2F * y + noise, 1.0F};
    }
    default: {  // kPooled: a grid over the parent cell (width kCellWidthM; children kCellWidthM / 2)
      const float x = kCellWidthM * (static_cast<float>(i % 16U) + 0.5F) * (1.0F / 16.0F) - 0.5F * kCellWidthM;
      const float y = kCellWidthM * (static_cast<float>(i / 16U) + 0.5F) * (1.0F / 16.0F) - 0.5F * kCellWidthM;
      return Input{x, y, 0.02F + 0.25F * x - 0.1F * y + 0.5F * noise, 1.0F};
    }
  }
}

/// kPooled: child index ix + 2 iy of a parent-frame point (the quadrant).
inline int pooled_child(const Input& p) noexcept { return (p.x >= 0.0F ? 1 : 0) + (p.y >= 0.0F ? 2 : 0); }
/// kPooled: centre offset of child k from the parent centre, ((ix - 1/2) w_c, (iy - 1/2) w_c).
inline float child_offset_x(int k) noexcept { return ((k & 1) != 0 ? 0.5F : -0.5F) * (0.5F * kCellWidthM); }
inline float child_offset_y(int k) noexcept { return ((k & 2) != 0 ? 0.5F : -0.5F) * (0.5F * kCellWidthM); }

/// The weight-limiter case: kLimiterSettle points at z = 0, then kLimiterSteps at z = 1, all
/// of weight 1, at the cell centre's neighbourhood, W_l = kLimiterWeightLimit.
inline constexpr float kLimiterWeightLimit = 100.0F;
inline constexpr std::uint32_t kLimiterSettle = 1000U;
inline constexpr std::uint32_t kLimiterSteps = 50U;

/// Double-precision references rounded to float, as IEEE-754 bits (cell_reference.inc).
/// References of the full CCM cell (CcmCell): moments, and the least-squares plane's slopes,
/// residual, inclination and height.
struct CcmReference {
  std::uint32_t weight, mean_x, mean_y, mean_z, var_xx, var_yy, var_zz, cov_xz, cov_yz, cov_xy;
  std::uint32_t slope_x, slope_y, normal_variance, inclination, height_at_query;
};
struct LimiterReference {
  std::uint32_t weight, mean_z;
};
struct ConstantReference {
  std::uint32_t kalman_height, kalman_variance, omg_weight, omg_height, omg_variance;
};

/// The piece-wise constant cases: n height measurements with their variances.
inline constexpr std::uint32_t kConstantCount = 200U;
inline Input constant_measurement(std::uint32_t i) noexcept {
  const float z = 0.3F + 0.02F * (hash_unit(i, 21U) - 0.5F);
  const float variance = 1.0e-4F * (0.5F + hash_unit(i, 22U));  // (7 .. 12 mm)^2
  const float w = 0.5F + hash_unit(i, 23U);
  return Input{0.0F, variance, z, w};  // y carries the measurement variance
}

}  // namespace ccmap::test::cells
