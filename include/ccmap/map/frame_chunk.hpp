// The front half of the frame update, one fixed-size chunk at a time: validation, the optional
// sensor-to-map transform, the squared range, routing (Section IV-G) and the finest-layer cell
// index, for every point of the chunk, into structure-of-arrays scratch owned by the stack.
//
// Why a separate pass: these steps touch no cell, have no dependency between points and no
// data-dependent branch, so the compiler vectorises the loop (SSE2 on x86-64, NEON on aarch64;
// check with -fopt-info-vec). The back half (Stack::apply_chunk) then only walks layers with
// integer compares and updates cells.
//
// Equality with the per-point path (Stack::update_frame_sequential): every float operation
// here is the one the per-point path performs, in the same order (the sensor transform, the
// range as (dx*dx + dy*dy) + dz*dz, floor(x * (1/w))), and -ffp-contract=off forbids the
// compiler to fuse them; comparisons that the per-point path makes on floats are made here on
// their bit patterns, which order non-negative floats (and +inf, NaN) the same way. So a chunk
// routes and indexes every point bitwise as the per-point path does.
//
// Float only, no heap, no exceptions; O(n) in the chunk.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <cmath>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/grid/ring_index.hpp"
#include "ccmap/map/types.hpp"

namespace ccmap::detail {

/// Points per chunk: the scratch is ~14 KB (fits L1 with the cells it feeds), and the chunk
/// loop costs nothing measurable at this size (docs/performance.md).
inline constexpr std::size_t kFrameChunkPoints = 512U;

/// What the front half says about a point: a routed layer (0 .. layers-1), or why it is refused.
enum : std::uint8_t {
  kChunkNonFinite = 0xFDU,   ///< a NaN/Inf coordinate (after the transform)
  kChunkOutOfRange = 0xFEU,  ///< |coordinate| > kMaxAbsCoordinateM
  kChunkTooNoisy = 0xFFU,    ///< no layer's IV-G range holds it (or range 0, NaN)
};

/// Structure-of-arrays scratch for one chunk (a member of the stack: capacity in the type).
struct FrameChunk {
  float x[kFrameChunkPoints];         ///< map frame (m)
  float y[kFrameChunkPoints];
  float z[kFrameChunkPoints];
  std::int64_t range_units_sq[kFrameChunkPoints];  ///< squared range, FixedFront range units
  std::int64_t z_units[kFrameChunkPoints];         ///< floor(z / range unit)
  std::int32_t ix[kFrameChunkPoints]; ///< global index at the finest layer; valid if routed
  std::int32_t iy[kFrameChunkPoints];
  std::uint8_t code[kFrameChunkPoints];
};

/// Bit pattern of a float (no aliasing UB: memcpy compiles to a move).
[[nodiscard]] inline std::uint32_t chunk_float_bits(float v) noexcept {
  std::uint32_t u = 0U;
  std::memcpy(&u, &v, sizeof u);
  return u;
}

[[nodiscard]] inline float chunk_float_from_bits(std::uint32_t u) noexcept {
  float v = 0.0F;
  std::memcpy(&v, &u, sizeof v);
  return v;
}

/// Routing and indexing run in integer arithmetic on each float's bit pattern. Why: under
/// QEMU user mode every float instruction is a call into a soft-float helper (~4-9 ns each on
/// the build host) while integer instructions are translated to native ones, and the front
/// half was ~40 % of a CADRE frame; on real cores both forms cost about the same
/// (docs/performance.md).
///  - The cell index is floor(fl(x * (1/w_0))) computed exactly as grid::index_of_position
///    computes it in float (the product rounded to nearest-even, then floored), so a point
///    lands in the cell that locate() names, edges included; layer k's index is that >> k
///    (1/w_k = (1/w_0) 2^-k exactly).
///  - The squared range is formed in int64 from fixed-point coordinates in units of
///    w_0 / 2^kRangeShift (0.16 mm for 4 cm cells): routing is exact for that quantisation.
/// Both update paths share this front (update_point_front), so they route and index every
/// point identically.
inline constexpr int kRangeShift = 8;
/// A point farther than 2^30 range units from the sensor on an axis (167 km for 4 cm cells,
/// 800 m for the smallest accepted 0.19 mm cells) is refused as out of range: beyond every
/// routing bound of a real sensor model, and it keeps the squares within int64.
inline constexpr std::int64_t kMaxRangeUnits = std::int64_t{1} << 30;

/// The stack's integer front: scales, routing bounds in squared range units, and the sensor
/// origin of the current frame in range units. Derived at init and per frame.
inline constexpr int kChunkMaxLayers = 8;
struct FixedFront {
  std::uint64_t mult;                          ///< significand of fl(1 / w_0) (24 bits)
  std::int32_t q;                              ///< range unit = 1 / (mult * 2^-q): floor(v * 2^kRangeShift / w_0)
  std::int64_t max_range_units_sq[kChunkMaxLayers];  ///< unused layers: INT64_MAX
  std::uint32_t layers;
  float range_unit_m;                          ///< w_0 / 2^kRangeShift
  float range_unit_sq_m2;                      ///< (w_0 / 2^kRangeShift)^2
  std::int64_t origin_units[3];                ///< sensor origin (range units), per frame
};

/// Routing of one point by the fixed front: code (layer or refusal), finest index, range^2.
struct PointFront {
  std::uint32_t code;
  std::int32_t ix0;
  std::int32_t iy0;
  std::int64_t range_units_sq;  ///< (range / (w_0 / 2^kRangeShift))^2; to_range_sq_m2() for m^2
  std::int64_t z_units;         ///< floor(z / (w_0 / 2^kRangeShift)): heights of constant cells
};

/// A squared range in FixedFront units as m^2 (two float operations: only the cells that need
/// it pay for it).
[[nodiscard]] inline float to_range_sq_m2(std::int64_t range_units_sq, const FixedFront& front) noexcept {
  return static_cast<float>(range_units_sq) * front.range_unit_sq_m2;
}

/// One point through validation, range, routing and finest index, in integer operations.
[[nodiscard]] inline PointFront update_point_front(float x, float y, float z, const FixedFront& front) noexcept {
  constexpr std::uint32_t kAbsMask = 0x7FFFFFFFU;
  constexpr std::uint32_t kInfBits = 0x7F800000U;
  const std::uint32_t limit_bits = chunk_float_bits(kMaxAbsCoordinateM);
  const std::uint32_t bx = chunk_float_bits(x);
  const std::uint32_t by = chunk_float_bits(y);
  const std::uint32_t bz = chunk_float_bits(z);
  const std::uint32_t ax = bx & kAbsMask;
  const std::uint32_t ay = by & kAbsMask;
  const std::uint32_t az = bz & kAbsMask;
  PointFront out{kChunkTooNoisy, 0, 0, 0, 0};
  const std::uint32_t largest = ax > ay ? (ax > az ? ax : az) : (ay > az ? ay : az);
  if (largest > limit_bits) {  // one compare on the common path
    out.code = largest >= kInfBits ? kChunkNonFinite : kChunkOutOfRange;
    return out;
  }
  // One exact conversion per axis: units = floor(v * 2^kRangeShift * fl(1/w_0)); the finest
  // index floor(v * fl(1/w_0)) is units >> kRangeShift (grid::index_of_position's value).
  const std::int64_t ux = grid::detail::floor_scaled_bits(bx, front.mult, front.q);
  const std::int64_t uy = grid::detail::floor_scaled_bits(by, front.mult, front.q);
  const std::int64_t uz = grid::detail::floor_scaled_bits(bz, front.mult, front.q);
  const std::int64_t dx = ux - front.origin_units[0];
  const std::int64_t dy = uy - front.origin_units[1];
  const std::int64_t dz = uz - front.origin_units[2];
  constexpr std::uint64_t kSpan = 2U * static_cast<std::uint64_t>(kMaxRangeUnits);
  if ((static_cast<std::uint64_t>(dx + kMaxRangeUnits) | static_cast<std::uint64_t>(dy + kMaxRangeUnits) |
       static_cast<std::uint64_t>(dz + kMaxRangeUnits)) > kSpan) {  // some |d| > kMaxRangeUnits
    out.code = kChunkOutOfRange;
    return out;
  }
  const std::int64_t range_units_sq = dx * dx + dy * dy + dz * dz;
  std::uint32_t layer = 0U;  // bounds are non-decreasing: the first that holds the range
  while (layer < front.layers && range_units_sq > front.max_range_units_sq[layer]) {
    ++layer;
  }
  if (range_units_sq == 0 || layer >= front.layers) {
    return out;  // at the sensor itself, or too noisy for every layer (RoutingTable::select: -1)
  }
  out.code = layer;
  out.ix0 = static_cast<std::int32_t>(ux >> kRangeShift);
  out.iy0 = static_cast<std::int32_t>(uy >> kRangeShift);
  out.range_units_sq = range_units_sq;
  out.z_units = uz;
  return out;
}

/// floor(v) as int64 for 1 <= v < 2^63, from the bit pattern in integer operations only. A
/// static_cast calls libgcc's __aeabi_f2lz on 32-bit Arm, which converts through double
/// (__aeabi_f2d, __aeabi_dmul) when the FPU is single precision (Cortex-M7 FPv5-SP): no double
/// may enter the core's image (tests/baremetal, link.no_soft_double).
[[nodiscard]] inline std::int64_t floor_to_int64(float v) noexcept {
  const std::uint32_t bits = chunk_float_bits(v);
  const std::int32_t exponent = static_cast<std::int32_t>((bits >> 23) & 0xFFU) - 150;  // v = significand * 2^exponent
  const std::uint64_t significand = (bits & 0x7FFFFFU) | 0x800000U;  // v >= 1: normal
  return static_cast<std::int64_t>(exponent >= 0 ? significand << exponent : significand >> -exponent);
}

/// Derives the scale and routing bounds for finest width w_0 and the routing table's squared
/// ranges (m^2, non-decreasing). kInvalidArgument if w_0 is outside what validate_stack_params
/// accepts (the scale would not fit). Evaluated once at init.
[[nodiscard]] inline Status make_fixed_front(float finest_width_m, const float* max_range_sq_m2, int layers,
                                             FixedFront* out) noexcept {
  if (out == nullptr || max_range_sq_m2 == nullptr || layers < 1 || layers > kChunkMaxLayers ||
      !(finest_width_m > 0.0F) || !std::isfinite(finest_width_m)) {
    return Status::kInvalidArgument;
  }
  FixedFront f{};
  const float inv_w0 = 1.0F / finest_width_m;  // the value RingGrid::init computes
  // |x| <= kMaxAbsCoordinateM must keep the index within +-2^30 and the shift in
  // floor_scaled_bits positive: 1/w_0 in [1e-3, 2^22).
  if (!(inv_w0 >= 1.0e-3F) || !(inv_w0 * kMaxAbsCoordinateM < 1073741824.0F)) {
    return Status::kInvalidArgument;  // a width validate_stack_params refuses
  }
  const std::uint32_t inv_bits = chunk_float_bits(inv_w0);
  f.mult = (inv_bits & 0x7FFFFFU) | 0x800000U;
  f.q = 150 - static_cast<std::int32_t>((inv_bits >> 23) & 0xFFU) - kRangeShift;
  for (int k = 0; k < kChunkMaxLayers; ++k) {
    f.max_range_units_sq[k] = INT64_MAX;
  }
  const float range_unit = 1.0F / (inv_w0 * static_cast<float>(1 << kRangeShift));
  f.range_unit_m = range_unit;
  f.range_unit_sq_m2 = range_unit * range_unit;
  for (int k = 0; k < layers; ++k) {
    const float units = max_range_sq_m2[k] / f.range_unit_sq_m2;
    // A bound below one unit takes only points at the sensor (refused anyway); a bound beyond
    // int64 (including the +inf/FLT_MAX of a noise-free model) never refuses.
    f.max_range_units_sq[k] = !(units < 9.0e18F) ? INT64_MAX : (units < 1.0F ? 0 : floor_to_int64(units));
  }
  f.layers = static_cast<std::uint32_t>(layers);
  *out = f;
  return Status::kOk;
}

/// Sets the frame's sensor origin in range units (the origin passed check_frame: finite and
/// within kMaxAbsCoordinateM).
inline void set_front_origin(FixedFront& front, const PointXYZ& origin) noexcept {
  front.origin_units[0] = grid::detail::floor_scaled_bits(chunk_float_bits(origin.x), front.mult, front.q);
  front.origin_units[1] = grid::detail::floor_scaled_bits(chunk_float_bits(origin.y), front.mult, front.q);
  front.origin_units[2] = grid::detail::floor_scaled_bits(chunk_float_bits(origin.z), front.mult, front.q);
}

/// Rotation sensor -> map (row-major) and translation.
struct ChunkTransform {
  float r[9];
  float t[3];
};

/// Fills chunk[0..n) from points[0..n) (n <= kFrameChunkPoints): the optional sensor -> map
/// transform (float), then update_point_front for every point.
inline void prepare_chunk(const PointXYZ* points, std::size_t n, const ChunkTransform* transform,
                          const FixedFront& front, FrameChunk& chunk) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    float x = points[i].x;
    float y = points[i].y;
    float z = points[i].z;
    if (transform != nullptr) {
      const float* r = transform->r;
      const float mx = r[0] * x + r[1] * y + r[2] * z + transform->t[0];
      const float my = r[3] * x + r[4] * y + r[5] * z + transform->t[1];
      const float mz = r[6] * x + r[7] * y + r[8] * z + transform->t[2];
      x = mx;
      y = my;
      z = mz;
    }
    chunk.x[i] = x;
    chunk.y[i] = y;
    chunk.z[i] = z;
    const PointFront p = update_point_front(x, y, z, front);
    chunk.code[i] = static_cast<std::uint8_t>(p.code);
    chunk.ix[i] = p.ix0;
    chunk.iy[i] = p.iy0;
    chunk.range_units_sq[i] = p.range_units_sq;
    chunk.z_units[i] = p.z_units;
  }
}

}  // namespace ccmap::detail
