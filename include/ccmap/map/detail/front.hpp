// The front of the frame update, in integer arithmetic: validation, the sensor -> map transform
// of sensor-frame input, the squared range, routing (paper Section IV-G) and the finest-layer
// cell index. Used by Stack's update path (map/detail/update_path.hpp); integrators need not
// read it.
//
// Why integers: under QEMU user mode every float instruction is a call into a soft-float helper
// (~4-9 ns each on the build host) while integer instructions are translated to one or two host
// instructions; on a real Cortex-A/Kryo core both forms cost about the same
// (docs/performance.md). Integer arithmetic is also exact, so the x86-64 and aarch64 builds route
// and index every point identically.
//
// Fixed-point formats (all two's complement, all exact conversions from float bits):
//   position  Q18 metres (1 unit = 2^-18 m = 3.8 um), int64 in the map frame; sensor-frame
//             coordinates and offsets from the sensor fit int32 (|v| < 2^11 m)
//   range     Q16 metres (15 um); squared ranges in units of 2^-32 m^2, int64
//   height    Q14 metres (61 um), for the frame batches of the piece-wise constant layer
//   rotation  Q30 (one unit = 2^-30), int32, entries of a rotation matrix (|r| <= ~1)
//
// A point's cell is floor(q / w) with q its Q18 position: grid::index_of_position defines the
// same quantisation for queries, so a point lands in the cell that locate() names, edges
// included (tests/map/front_test.cpp).
//
// No heap, no exceptions, no float instruction on the map-frame path; O(1) per point.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/core/status.hpp"
#include "ccmap/map/types.hpp"

namespace ccmap::detail {

inline constexpr int kPositionFracBits = 18;  ///< Q18 metres
inline constexpr int kRangeFracBits = 16;     ///< Q16 metres
inline constexpr int kHeightFracBits = 14;    ///< Q14 metres
inline constexpr int kRotationFracBits = 30;  ///< Q30
/// Largest layer count the front routes (the stack's kMaxLayers).
inline constexpr int kFrontMaxLayers = 8;

/// Sensor-frame coordinates must be below this magnitude (m) on every axis: 2^11 m keeps a Q18
/// coordinate and its rotation within int32. Beyond it a point is refused as out of range (no
/// terrain sensor of a local map measures 2 km away). Map-frame points farther than this from
/// the sensor on an axis get a saturated squared range: only a layer with an unbounded range
/// (a constant-noise or noise-free model) takes them.
inline constexpr float kMaxSensorOffsetM = 2048.0F;
inline constexpr std::int64_t kMaxSensorOffsetQ18 = std::int64_t{1} << 29;  ///< 2^11 m in Q18

/// What the front says about a point: a routed layer (0 .. layers-1), or why it is refused.
enum : std::uint32_t {
  kFrontNonFinite = 0xFDU,   ///< a NaN/Inf coordinate
  kFrontOutOfRange = 0xFEU,  ///< |map coordinate| > kMaxAbsCoordinateM, |sensor coordinate| >= 2^11 m
  kFrontTooNoisy = 0xFFU,    ///< no layer's IV-G range holds it (or the point is the sensor itself)
};

/// Bit pattern of a float (no aliasing UB: memcpy compiles to a move).
[[nodiscard]] inline std::uint32_t bits_of(float v) noexcept {
  std::uint32_t u = 0U;
  std::memcpy(&u, &v, sizeof u);
  return u;
}

/// floor(v * 2^18) for the float with bit pattern `bits`, exact, in integer operations.
/// Precondition: v finite and |v| < 2^17 m (the caller compared |bits| with kMaxAbsCoordinateM
/// = 1e5 m first; a larger v would need a negative shift).
/// v = s * 2^(e - 150) with s the 24-bit significand and e the biased exponent, so
/// v * 2^18 = (s * 2^11) * 2^(e - 143): a left shift by 11 (at most 2^35), then an arithmetic
/// right shift by 143 - e >= 0 of the signed value, which floors negative values.
[[nodiscard]] inline std::int64_t q18_floor(std::uint32_t bits) noexcept {
  const std::uint32_t biased = (bits >> 23) & 0xFFU;
  const std::uint32_t significand = (bits & 0x7FFFFFU) | (biased != 0U ? 0x800000U : 0U);
  const std::int32_t exponent = static_cast<std::int32_t>(biased) + (biased == 0U ? 1 : 0);
  const std::int32_t shift = 143 - exponent;
  const std::int64_t sign = -static_cast<std::int64_t>(bits >> 31);  // 0 or -1
  const std::int64_t value = ((static_cast<std::int64_t>(significand) << 11) ^ sign) - sign;
  return value >> (shift > 63 ? 63 : shift);  // arithmetic shift: gcc/clang, standard in C++20
}

/// floor(v * 2^18) for |v| < 2^11 m as int32 (the sensor-frame conversion): the same value as
/// q18_floor, in 32-bit operations (v * 2^18 = (s * 2^5) * 2^(e - 137)).
/// Precondition: |bits| < bits_of(2048.0F) (checked by the caller).
[[nodiscard]] inline std::int32_t q18_floor_small(std::uint32_t bits) noexcept {
  const std::uint32_t biased = (bits >> 23) & 0xFFU;
  const std::uint32_t significand = (bits & 0x7FFFFFU) | (biased != 0U ? 0x800000U : 0U);
  const std::int32_t exponent = static_cast<std::int32_t>(biased) + (biased == 0U ? 1 : 0);
  const std::int32_t shift = 137 - exponent;
  const std::int32_t sign = -static_cast<std::int32_t>(bits >> 31);
  const std::int32_t value = (static_cast<std::int32_t>(significand << 5) ^ sign) - sign;
  return value >> (shift > 31 ? 31 : shift);
}

/// Constants of the front, derived at init from the finest cell width and the routing table.
struct FrontConfig {
  std::int64_t index_mult;   ///< 24-bit significand of fl(1 / w_0)
  std::int32_t index_shift;  ///< index_0 = (q18 * index_mult) >> index_shift = floor(q * fl(1/w_0))
  std::uint32_t layers;      ///< routed layers
  /// Squared IV-G range bound of each layer (units of 2^-32 m^2), non-decreasing;
  /// INT64_MAX for an unbounded layer (and for unused slots).
  std::int64_t max_range_sq[kFrontMaxLayers];
};

/// The sensor pose of one frame in fixed point.
struct FramePose {
  std::int64_t origin_q18[3];       ///< sensor position, map frame (Q18, floor)
  std::int32_t rotation_q30[9];     ///< sensor -> map, row-major (Q30, rounded); sensor frame only
  std::int64_t rotation_bias_q48[3];///< added before the Q48 -> Q18 rounding (see make_frame_pose)
  std::int64_t translation_q18[3];  ///< sensor position, map frame (Q18, rounded); sensor frame only
};

/// One point after the front: routed layer (or refusal code), finest index, squared range,
/// Q18 map position (for sensor-frame input, where no float position exists) and Q14 height.
struct PointFront {
  std::uint32_t code;
  std::int32_t ix0;
  std::int32_t iy0;
  std::int64_t range_sq;   ///< units of 2^-32 m^2; to_range_sq_m2() for m^2
  std::int64_t q18[3];     ///< map frame position (Q18)
  std::int64_t height_q14; ///< floor(z * 2^14)
};

/// A squared range of the front (2^-32 m^2 units) in m^2 (two float operations: only the cells
/// that need it pay for it).
[[nodiscard]] inline float to_range_sq_m2(std::int64_t range_sq) noexcept {
  return static_cast<float>(range_sq) * 2.3283064e-10F;  // 2^-32
}

/// Q18 position as the nearest float (m): one conversion, the power-of-two scale is exact.
[[nodiscard]] inline float q18_to_float(std::int64_t q) noexcept {
  return static_cast<float>(q) * 3.81469727e-6F;  // 2^-18
}

/// Derives the front's constants for finest width w_0 and the routing table's squared ranges
/// (m^2, non-decreasing). kInvalidArgument for a width outside what validate_stack_params
/// accepts (the index product would not fit), bad pointers or layer counts. Evaluated at init.
[[nodiscard]] Status make_front_config(float finest_width_m, const float* max_range_sq_m2, int layers,
                                       FrontConfig* out) noexcept;

/// The fixed-point form of a frame's pose. `rotation` may be nullptr (map-frame input: only the
/// origin is used). kNonFiniteInput for a NaN/Inf entry; kOutOfRange for an origin beyond
/// kMaxAbsCoordinateM; kInvalidArgument for a rotation that is not one (an entry beyond
/// 1 + 1e-3, or R^T R further than 1e-3 from the identity in any entry).
/// Rotation error: each Q30 entry is within 2^-31 of the float, i.e. < 1.5 nm per metre.
[[nodiscard]] Status make_frame_pose(const PointXYZ& origin, const float* rotation_row_major, FramePose* out) noexcept;

/// Squared range (2^-32 m^2) of a Q18 offset from the sensor; INT64_MAX when an axis is at or
/// beyond kMaxSensorOffsetM (saturated: only unbounded layers take the point).
[[nodiscard]] inline std::int64_t range_sq_of_offset(std::int64_t dx, std::int64_t dy, std::int64_t dz) noexcept {
  constexpr auto kSpan = static_cast<std::uint64_t>(2 * kMaxSensorOffsetQ18);
  if ((static_cast<std::uint64_t>(dx + kMaxSensorOffsetQ18) | static_cast<std::uint64_t>(dy + kMaxSensorOffsetQ18) |
       static_cast<std::uint64_t>(dz + kMaxSensorOffsetQ18)) >= kSpan) {
    return INT64_MAX;
  }
  const std::int64_t rx = dx >> 2;  // Q18 -> Q16 (floor); |r| < 2^27, so the sum stays < 2^56
  const std::int64_t ry = dy >> 2;
  const std::int64_t rz = dz >> 2;
  return rx * rx + ry * ry + rz * rz;
}

/// Routing and indexing of a Q18 map position with squared range `range_sq`; fills `out`.
inline void route_and_index(const std::int64_t q[3], std::int64_t range_sq, const FrontConfig& config,
                            PointFront& out) noexcept {
  std::uint32_t layer = 0U;  // bounds are non-decreasing: the first that holds the range
  while (layer < config.layers && range_sq > config.max_range_sq[layer]) {
    ++layer;
  }
  out.range_sq = range_sq;
  if (range_sq == 0 || layer >= config.layers) {
    out.code = kFrontTooNoisy;  // at the sensor itself, or too noisy for every layer
    return;
  }
  out.code = layer;
  // |q| < 2^35 and index_mult < 2^24: the product fits int64; >> floors.
  out.ix0 = static_cast<std::int32_t>((q[0] * config.index_mult) >> config.index_shift);
  out.iy0 = static_cast<std::int32_t>((q[1] * config.index_mult) >> config.index_shift);
  out.q18[0] = q[0];
  out.q18[1] = q[1];
  out.q18[2] = q[2];
  out.height_q14 = q[2] >> (kPositionFracBits - kHeightFracBits);
}

/// Front of a map-frame point: validation on the bit patterns (one compare of the largest |bits|
/// with bits(1e5) catches NaN, Inf and out-of-range), Q18 conversion, range from the sensor,
/// routing, index. Integer operations only.
[[nodiscard]] inline PointFront front_map_point(float x, float y, float z, const FramePose& pose,
                                                const FrontConfig& config) noexcept {
  constexpr std::uint32_t kAbsMask = 0x7FFFFFFFU;
  constexpr std::uint32_t kInfBits = 0x7F800000U;
  const std::uint32_t bx = bits_of(x);
  const std::uint32_t by = bits_of(y);
  const std::uint32_t bz = bits_of(z);
  const std::uint32_t ax = bx & kAbsMask;
  const std::uint32_t ay = by & kAbsMask;
  const std::uint32_t az = bz & kAbsMask;
  PointFront out{kFrontTooNoisy, 0, 0, 0, {0, 0, 0}, 0};
  const std::uint32_t largest = ax > ay ? (ax > az ? ax : az) : (ay > az ? ay : az);
  if (largest > bits_of(kMaxAbsCoordinateM)) {
    out.code = largest >= kInfBits ? kFrontNonFinite : kFrontOutOfRange;
    return out;
  }
  const std::int64_t q[3] = {q18_floor(bx), q18_floor(by), q18_floor(bz)};
  const std::int64_t range_sq =
      range_sq_of_offset(q[0] - pose.origin_q18[0], q[1] - pose.origin_q18[1], q[2] - pose.origin_q18[2]);
  route_and_index(q, range_sq, config, out);
  return out;
}

/// Front of a sensor-frame point: validation (|s| < 2^11 m on every axis), Q18 conversion,
/// the squared range from the sensor-frame coordinates themselves (exact: no rotation error),
/// the rotation and translation in integers (m = (R_q30 s_q18 + bias + 2^29) >> 30 + t_q18),
/// routing, index. Integer operations only. Position error against the double-precision
/// transform of the same float inputs: below 8 um per axis within 10 m of the sensor
/// (docs/design.md, "The sensor-frame transform"; tests/map/front_test.cpp asserts it).
[[nodiscard]] inline PointFront front_sensor_point(float x, float y, float z, const FramePose& pose,
                                                   const FrontConfig& config) noexcept {
  constexpr std::uint32_t kAbsMask = 0x7FFFFFFFU;
  constexpr std::uint32_t kInfBits = 0x7F800000U;
  constexpr std::uint32_t kLimitBits = 0x45000000U;  // bits_of(2048.0F)
  const std::uint32_t bx = bits_of(x);
  const std::uint32_t by = bits_of(y);
  const std::uint32_t bz = bits_of(z);
  const std::uint32_t ax = bx & kAbsMask;
  const std::uint32_t ay = by & kAbsMask;
  const std::uint32_t az = bz & kAbsMask;
  PointFront out{kFrontTooNoisy, 0, 0, 0, {0, 0, 0}, 0};
  const std::uint32_t largest = ax > ay ? (ax > az ? ax : az) : (ay > az ? ay : az);
  if (largest >= kLimitBits) {
    out.code = largest >= kInfBits ? kFrontNonFinite : kFrontOutOfRange;
    return out;
  }
  const std::int64_t sx = q18_floor_small(bx);
  const std::int64_t sy = q18_floor_small(by);
  const std::int64_t sz = q18_floor_small(bz);
  const std::int32_t* r = pose.rotation_q30;
  // |r| <= 2^30 * 1.001 and |s| < 2^29: each product < 2^59.01, the sum of three < 2^60.6.
  std::int64_t q[3];
  for (int row = 0; row < 3; ++row) {
    const std::int64_t acc = r[3 * row] * sx + r[3 * row + 1] * sy + r[3 * row + 2] * sz + pose.rotation_bias_q48[row];
    q[row] = (acc >> kRotationFracBits) + pose.translation_q18[row];
  }
  // The map position must stay inside the map frame's range, as for map-frame input.
  constexpr std::int64_t kMaxQ18 = std::int64_t{100000} << kPositionFracBits;
  if (q[0] > kMaxQ18 || q[0] < -kMaxQ18 || q[1] > kMaxQ18 || q[1] < -kMaxQ18 || q[2] > kMaxQ18 || q[2] < -kMaxQ18) {
    out.code = kFrontOutOfRange;
    return out;
  }
  const std::int64_t range_sq = range_sq_of_offset(sx, sy, sz);
  route_and_index(q, range_sq, config, out);
  return out;
}

}  // namespace ccmap::detail
