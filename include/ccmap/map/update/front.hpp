// The front of the frame update: validation, the sensor -> map transform of sensor-frame input,
// the squared range, routing (paper Section IV-G), the finest-layer cell index and the point's
// position inside that cell, for a chunk of points at a time. Used by the update path
// (map/update/update_path.hpp); integrators need not read it.
//
// Float, in plain loops over structure-of-arrays that the compiler vectorises (four lanes of
// NEON on aarch64; SSE2, or the AVX2+FMA clone on x86-64 CPUs that have it); its aarch64
// instructions per point are counted in docs/performance.md section 2.
// Every operation is a single IEEE-754 float operation in a fixed order (the build forbids FMA
// contraction and fast-math; the one fused multiply-add is written out, std::fma, and rounds
// once on every target), so x86-64, aarch64 and the Cortex-M7 compute the same bits.
//
// Frames and units. Positions are in units of the finest cell, relative to the frame's anchor:
// the finest cell of the sensor's position, A = floor(o / w_0) (exact, per frame). A point's
// finest cell is A + floor(u), u its offset from the anchor's corner in cells, and its position
// inside that cell is the fraction u - floor(u) in [0, 1) (exact: the subtraction of a float's
// own floor). Heights are map-frame metres. Squared ranges are m^2 from the sensor.
//
// Map-frame input names its cell exactly as queries do: floor(x * fl(1/w_0)) of the exact
// product (grid::index_of_position), from a float product corrected by the sign of its exact
// remainder (std::fma); the fraction is that remainder. (Products of 2^23 cells or more, cells
// narrower than 12 mm far from the origin, take an exact integer path, point by point.) Sensor-frame input has no float map
// position to agree with: its offset u = R' s + f (R' the rotation's first two rows times
// fl(1/w_0), f the sensor's fraction inside its anchor cell), within 3 um of the
// double-precision transform at 10 m (tests/map/front_test.cpp; docs/design.md, "The
// sensor-frame transform").
//
// No heap, no exceptions; O(1) per point.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/core/status.hpp"
#include "ccmap/grid/ring_index.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/map/update/fixed_point.hpp"

namespace ccmap::detail {

/// Largest layer count the front routes (the stack's kMaxLayers).
inline constexpr int kFrontMaxLayers = 8;

/// Sensor-frame coordinates must be below this magnitude (m) on every axis; beyond it a point
/// is refused as out of range (no terrain sensor of a local map measures 2 km away, and the
/// offset in cells then stays far inside int32 for every accepted cell width).
inline constexpr float kMaxSensorOffsetM = 2048.0F;

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

/// floor(v) as int32 for |v| < 2^31 (exact). On aarch64 one instruction (FCVTMS); elsewhere the
/// truncation corrected downwards, which every SIMD level of x86-64 vectorises.
[[nodiscard]] inline std::int32_t floor_to_int32(float v) noexcept {
#if defined(__aarch64__)
  return static_cast<std::int32_t>(__builtin_floorf(v));
#else
  const auto t = static_cast<std::int32_t>(v);
  return t - (static_cast<float>(t) > v ? 1 : 0);
#endif
}

/// Squared range bounds and the finest cell width of a stack, derived at init.
struct FrontConfig {
  float inv_width;  ///< fl(1 / w_0), the value RingGrid::init and queries use
  float width;      ///< w_0 (m)
  std::uint32_t layers;
  /// Squared IV-G range bound of each layer (m^2, non-decreasing, the routing table's own
  /// floats); +inf for an unbounded layer and for unused slots.
  float max_range_sq[kFrontMaxLayers];
};

/// The sensor pose of one frame, as the front uses it.
struct FramePose {
  float origin[3];           ///< sensor position, map frame (m)
  CellIndex anchor;          ///< A = floor(o_xy * fl(1/w_0)), exact
  float anchor_fraction[2];  ///< o_xy * fl(1/w_0) - A, in [0, 1) (cells)
  float rotation[9];         ///< sensor -> map, row-major; sensor frame only
  float rotation_cells[6];   ///< rows 0 and 1 times fl(1/w_0) (cells per m); sensor frame only
  /// The sensor is within 2^11 m * sqrt(3) of kMaxAbsCoordinateM on an axis: sensor-frame
  /// points are then checked against it in the map frame (a rare, scalar pass).
  bool near_limit;
};

/// The finest layer's window for the Kalman frame batch's slot (side 0: no such layer).
struct FineWindow {
  CellIndex min;
  std::int32_t side;       ///< power of two, or 0
  std::int32_t log2_side;
};

/// Points per front chunk: the chunk below is 10 KB (in L1 beside the cells it updates). Each
/// chunk pays the front's and the back half's set-up and the counters once.
inline constexpr std::size_t kFrontChunkPoints = 256U;

/// The front's answer for a chunk of points, structure of arrays (vectorisable), owned by the
/// stack's update path. Entry i is valid for i < the count passed to the chunk function;
/// entries other than `code` are meaningful only for routed points (code < layers).
struct FrontChunk {
  std::int32_t code[kFrontChunkPoints];        ///< routed layer, or kFrontNonFinite/OutOfRange/TooNoisy
  std::int32_t ix0[kFrontChunkPoints];         ///< finest-layer global index
  std::int32_t iy0[kFrontChunkPoints];
  float fx[kFrontChunkPoints];                 ///< position inside that cell, [0, 1] cells
  float fy[kFrontChunkPoints];
  float z[kFrontChunkPoints];                  ///< map-frame height (m)
  float range_sq[kFrontChunkPoints];           ///< squared range from the sensor (m^2)
  /// Slot of the finest cell in the finest layer's buffer when the point is routed to layer 0
  /// and that layer's window (FineWindow) holds it; -1 otherwise.
  std::int32_t fine_slot[kFrontChunkPoints];
  std::int32_t height_q14[kFrontChunkPoints];  ///< floor(z * 2^14) (61 um units)
  std::int32_t range_key[kFrontChunkPoints];   ///< floor(min(range_sq, 2^19 m^2) * 2^12) (2^-12 m^2 units)
};
static_assert(sizeof(FrontChunk) == std::size_t{40U} * kFrontChunkPoints, "ten 4-byte lanes per point, no padding");

/// Derives the front's constants for finest width w_0 and the routing table's squared ranges
/// (m^2, non-decreasing; +inf allowed). kInvalidArgument for a width outside what
/// validate_stack_params accepts (1/w_0 in [1e-3, 2^30 / 1e5]: every index of a position within
/// kMaxAbsCoordinateM stays within +-2^30), bad pointers or layer counts. Evaluated at init.
[[nodiscard]] Status make_front_config(float finest_width_m, const float* max_range_sq_m2, int layers,
                                       FrontConfig* out) noexcept;

/// The rotation check of every call that takes a sensor pose (update_frame_sensor,
/// register_frame_sensor): kOk for a row-major 3 x 3 rotation; kNonFiniteInput for a NaN/Inf
/// entry; kInvalidArgument for an entry beyond 1 + 1e-3, or R^T R further than 1e-3 from the
/// identity in any entry (a scaling or shear, not a rigid transform).
[[nodiscard]] Status check_rotation(const float* rotation_row_major) noexcept;

/// The frame's pose for the front. `rotation` may be nullptr (map-frame input: only the origin
/// is used). kNonFiniteInput for a NaN/Inf entry; kOutOfRange for an origin beyond
/// kMaxAbsCoordinateM; kInvalidArgument for a rotation that is not one (an entry beyond
/// 1 + 1e-3, or R^T R further than 1e-3 from the identity in any entry), for a null `out`, or
/// for a config that make_front_config did not fill.
[[nodiscard]] Status make_frame_pose(const PointXYZ& origin, const float* rotation_row_major, const FrontConfig& config,
                                     FramePose* out) noexcept;

/// The front of n <= kFrontChunkPoints map-frame points: validation on the bit patterns (NaN,
/// Inf, |x| > kMaxAbsCoordinateM), the squared range from the sensor, routing (the first layer
/// whose bound holds it; the sensor itself is too noisy), the finest index and fraction, the
/// Kalman slot, the Q14 height and the range key.
void front_map_chunk(const PointXYZ* points, std::size_t n, const FramePose& pose, const FrontConfig& config,
                     const FineWindow& fine, FrontChunk& out) noexcept;

/// The front of n <= kFrontChunkPoints sensor-frame points: validation (|s| < 2^11 m on every
/// axis), the squared range from the sensor-frame coordinates themselves (no rotation error),
/// the transform u = R' s + f, the map-frame range check (|m| <= 1e5 m, when the pose is near
/// the limit), routing, index, fraction, slot, height and key as front_map_chunk.
void front_sensor_chunk(const PointXYZ* points, std::size_t n, const FramePose& pose, const FrontConfig& config,
                        const FineWindow& fine, FrontChunk& out) noexcept;

}  // namespace ccmap::detail
