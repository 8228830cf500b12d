// The front of the frame update, in integer arithmetic: validation, the sensor -> map transform
// of sensor-frame input, the squared range, routing (paper Section IV-G) and the finest-layer
// cell index. Used by Stack's update path (map/update/update_path.hpp); integrators need not
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
// The front works on chunks of points, structure of arrays, in plain loops of integer operations
// that the compiler vectorises (src/map/front.cpp). No heap, no exceptions, no float instruction;
// O(1) per point.
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

/// floor(v) as int64 for 1 <= v < 2^63, from the bit pattern in integer operations only. A
/// static_cast calls libgcc's __aeabi_f2lz on 32-bit Arm, which converts through double
/// (__aeabi_f2d, __aeabi_dmul) when the FPU is single precision (Cortex-M7 FPv5-SP): no double
/// may enter the core's image (tests/baremetal, link.no_soft_double). Per-frame and init-time
/// constants only.
[[nodiscard]] inline std::int64_t floor_to_int64(float v) noexcept {
  const std::uint32_t bits = bits_of(v);
  const std::int32_t exponent = static_cast<std::int32_t>((bits >> 23) & 0xFFU) - 150;  // v = significand * 2^exponent
  const std::uint64_t significand = (bits & 0x7FFFFFU) | 0x800000U;  // v >= 1: normal
  return static_cast<std::int64_t>(exponent >= 0 ? significand << exponent : significand >> -exponent);
}

/// floor(v * 2^18) for the float with bit pattern `bits`, exact, in integer operations of type
/// Int, for |v| < 2^kMagnitudeBits m: v = s * 2^(e - 150) with s the 24-bit significand and e the
/// biased exponent, so v * 2^18 = (s * 2^L) * 2^(e - 150 + 18 - L) with L = kMagnitudeBits - 6:
/// a left shift by L (the largest |v| fills the type), then an arithmetic right shift by
/// 126 + kMagnitudeBits - e >= 0 of the signed value, which floors negative values. For other bit
/// patterns the result is some value (the shift is clamped: no undefined behaviour, so vectorised
/// lanes of refused points are harmless).
template <typename Int, int kMagnitudeBits>
[[nodiscard]] inline Int q18_floor_bits(std::uint32_t bits) noexcept {
  static_assert(kMagnitudeBits - 6 + 24 < static_cast<int>(sizeof(Int) * 8), "the shifted significand must fit");
  constexpr int kLeft = kMagnitudeBits - 6;
  constexpr Int kMaxShift = static_cast<Int>(sizeof(Int) * 8 - 1);
  const auto biased = static_cast<Int>((bits >> 23) & 0xFFU);
  const Int significand = static_cast<Int>(bits & 0x7FFFFFU) | (biased != 0 ? Int{0x800000} : Int{0});
  const Int exponent = biased + (biased == 0 ? Int{1} : Int{0});
  Int shift = static_cast<Int>(126 + kMagnitudeBits) - exponent;
  shift = shift < 0 ? Int{0} : (shift > kMaxShift ? kMaxShift : shift);
  const Int sign = -static_cast<Int>(bits >> 31);  // 0 or -1
  const Int value = ((significand << kLeft) ^ sign) - sign;
  return value >> shift;  // arithmetic shift: gcc/clang, standard in C++20
}

/// floor(v * 2^18) of a map-frame coordinate (|v| <= kMaxAbsCoordinateM = 1e5 m < 2^17), int64.
[[nodiscard]] inline std::int64_t q18_floor(std::uint32_t bits) noexcept {
  return q18_floor_bits<std::int64_t, 17>(bits);
}

/// floor(v * 2^18) of a sensor-frame coordinate (|v| < 2^11 m), int32: the same value as
/// q18_floor, in 32-bit operations (4 lanes per NEON vector).
[[nodiscard]] inline std::int32_t q18_floor_small(std::uint32_t bits) noexcept {
  return q18_floor_bits<std::int32_t, 11>(bits);
}

/// Constants of the front, derived at init from the finest cell width and the routing table.
struct FrontConfig {
  std::int32_t index_mult;   ///< 24-bit significand of fl(1 / w_0)
  std::int32_t index_shift;  ///< index_0 = (q18 * index_mult) >> index_shift = floor(q * fl(1/w_0))
  std::uint32_t layers;      ///< routed layers
  /// Squared IV-G range bound of each layer (units of 2^-32 m^2), non-decreasing;
  /// INT64_MAX for an unbounded layer (and for unused slots).
  std::int64_t max_range_sq[kFrontMaxLayers];
  /// The same bounds as routing keys (route_key_of): routing compares keys, 32-bit lanes.
  std::uint32_t max_range_key[kFrontMaxLayers];
};

/// Routing key of a squared range (2^-32 m^2 units): floor(r^2 / 2^-12 m^2), saturated at
/// 2^32 - 1 (r^2 >= 2^20 m^2, a range of 1024 m or more). A layer holds a point iff the point's
/// key <= the layer's bound key: bounds act as if rounded up to the next 2^-12 m^2
/// (2.4e-4 m^2; at the CADRE 4 cm bound of 1.32 m that is 0.09 mm of range), and ranges beyond
/// 1024 m compare as 1024 m (only a layer whose own bound is beyond 1024 m is affected).
[[nodiscard]] inline std::uint32_t route_key_of(std::int64_t range_sq) noexcept {
  const std::uint64_t key = static_cast<std::uint64_t>(range_sq) >> 20;
  return key > 0xFFFFFFFFULL ? 0xFFFFFFFFU : static_cast<std::uint32_t>(key);
}

/// The sensor pose of one frame in fixed point.
struct FramePose {
  std::int64_t origin_q18[3];       ///< sensor position, map frame (Q18, floor)
  std::int32_t rotation_q30[9];     ///< sensor -> map, row-major (Q30, rounded); sensor frame only
  std::int64_t rotation_bias_q48[3];///< added before the Q48 -> Q18 rounding (see make_frame_pose)
  std::int64_t translation_q18[3];  ///< sensor position, map frame (Q18, rounded); sensor frame only
};

/// Points per front chunk: a FrontChunk (64 B per point) fits a 32 KB L1 data cache beside the cells.
inline constexpr std::size_t kFrontChunkPoints = 128U;

/// The front's answer for a chunk of points, structure of arrays (vectorisable), owned by the
/// stack's update path. Entry i is valid for i < the count passed to the chunk function.
struct FrontChunk {
  std::int32_t code[kFrontChunkPoints];        ///< routed layer, or kFrontNonFinite/OutOfRange/TooNoisy
  std::int32_t ix0[kFrontChunkPoints];         ///< finest-layer global index (valid if routed)
  std::int32_t iy0[kFrontChunkPoints];
  std::int32_t height_q14[kFrontChunkPoints];  ///< floor(z * 2^14), map frame (valid if routed)
  std::int64_t range_sq[kFrontChunkPoints];    ///< 2^-32 m^2; INT64_MAX beyond kMaxSensorOffsetM
  std::uint32_t range_key[kFrontChunkPoints];  ///< route_key_of(range_sq)
  std::int64_t q18[3][kFrontChunkPoints];      ///< map-frame position, Q18 (valid if routed)
  // Scratch of the chunk functions (not results).
  std::int32_t scratch_i32[3][kFrontChunkPoints];
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

/// The front of n <= kFrontChunkPoints map-frame points: validation on the bit patterns (one
/// compare of the largest |bits| with bits(1e5) catches NaN, Inf and out-of-range), exact Q18
/// conversion, the squared range from the sensor (the frame pose's origin, saturated beyond
/// kMaxSensorOffsetM), routing (the first layer whose squared bound holds the range; the sensor
/// itself is too noisy), the finest index floor(q * fl(1/w_0)) and the Q14 height. Integer
/// operations only, in loops the compiler vectorises (NEON on aarch64; AVX2 on x86-64 where the
/// CPU has it, chosen at load time).
void front_map_chunk(const PointXYZ* points, std::size_t n, const FramePose& pose, const FrontConfig& config,
                     FrontChunk& out) noexcept;

/// The front of n <= kFrontChunkPoints sensor-frame points: validation (|s| < 2^11 m on every
/// axis), exact Q18 conversion, the squared range from the sensor-frame coordinates themselves
/// (no rotation error), the rotation and translation in integers
/// (m = (R_q30 s_q18 + bias + 2^29) >> 30 + t_q18), the map-frame range check (|m| <= 1e5 m),
/// routing, index and height. Position error against the double-precision transform of the same
/// float inputs: below 8 um per axis within 10 m of the sensor (docs/design.md, "The
/// sensor-frame transform"; tests/map/front_test.cpp). Integer operations only, vectorised.
void front_sensor_chunk(const PointXYZ* points, std::size_t n, const FramePose& pose, const FrontConfig& config,
                        FrontChunk& out) noexcept;

}  // namespace ccmap::detail
