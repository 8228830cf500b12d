// Index math of the ring-buffer grid layer: pure free functions, exhaustively tested
// (tests/grid/ring_index_test.cpp).
//
// Two kinds of index, never mixed up
//  - A *global* cell index (CellIndex) names a cell of a layer for the life of the map: cell
//    (x, y) covers [x*w, (x+1)*w) x [y*w, (y+1)*w) metres of the map frame (relative to the
//    stack origin), w the cell width. It does not change when the window moves.
//  - A *ring position* / *buffer offset* is where that cell lives in a side x side buffer. It is
//    a pure function of the global index (wrap, buffer_offset) and never leaves the grid layer:
//    callers hold global indices only.
//
// Global indices used by the grid stay within +-kMaxCellIndex (plus half a window), so every
// sum and difference the grid forms fits int32 or is computed in int64.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <cstring>

#include "ccmap/core/assert.hpp"

namespace ccmap {

/// Global cell index of a layer (stable across moves): cell (x, y) covers
/// [x*w, (x+1)*w) x [y*w, (y+1)*w) metres of the map frame (relative to the stack origin).
struct CellIndex {
  std::int32_t x;
  std::int32_t y;
};

[[nodiscard]] constexpr bool operator==(CellIndex a, CellIndex b) noexcept {
  return a.x == b.x && a.y == b.y;
}
[[nodiscard]] constexpr bool operator!=(CellIndex a, CellIndex b) noexcept { return !(a == b); }

namespace grid {

/// Largest magnitude of a global cell index produced from a position (index_of_position) and
/// accepted as a window centre (RingGrid::init, RingGrid::move_to): 2^30. With the largest
/// side (kMaxSide) a window then spans at most [-2^30 - 2^14, 2^30 + 2^14), well inside int32.
inline constexpr std::int32_t kMaxCellIndex = std::int32_t{1} << 30;

/// Largest side of a ring buffer (cells per axis): 2^15, so side*side = 2^30 cells fits int32
/// and a 32-bit size_t. (Memory runs out long before: 2^30 cells of one byte are 1 GiB.)
inline constexpr std::int32_t kMaxSide = std::int32_t{1} << 15;
static_assert(std::int64_t{kMaxSide} * kMaxSide == std::int64_t{1} << 30, "kMaxSide^2 is 2^30 cells");

/// True if n is a positive power of two (1, 2, 4, ..., 2^30). False for 0, negatives and
/// INT32_MIN.
[[nodiscard]] constexpr bool is_power_of_two(std::int32_t n) noexcept {
  return n > 0 && (n & (n - 1)) == 0;
}

namespace detail {
/// wrap() without the check of its precondition: for RingGrid, whose side is checked once by
/// RingGrid::init (its invariant). Never undefined behaviour, whatever the arguments.
[[nodiscard]] constexpr std::int32_t wrap_unchecked(std::int32_t global_index, std::int32_t side_pow2) noexcept {
  // Unsigned arithmetic: int32 -> uint32 is defined modulo 2^32, so the mask is the remainder
  // for negative indices too, and side_pow2 - 1 cannot overflow in uint32.
  const std::uint32_t mask = static_cast<std::uint32_t>(side_pow2) - 1U;
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(global_index) & mask);
}
/// buffer_offset() without the check of its precondition (for RingGrid, as wrap_unchecked).
[[nodiscard]] constexpr std::size_t buffer_offset_unchecked(CellIndex index, std::int32_t side_pow2) noexcept {
  return static_cast<std::size_t>(wrap_unchecked(index.y, side_pow2)) * static_cast<std::size_t>(side_pow2) +
         static_cast<std::size_t>(wrap_unchecked(index.x, side_pow2));
}
}  // namespace detail

/// Ring position of a global index on a power-of-two side: in [0, side) for any int32, negative
/// included (the mask of the two's complement bit pattern, i.e. the mathematical
/// global_index mod side_pow2). wrap(-1, 8) == 7, wrap(INT32_MIN, s) == 0,
/// wrap(INT32_MAX, s) == s - 1.
/// Precondition: is_power_of_two(side_pow2); a violation is reported to the assert hook and
/// answered 0. Never undefined behaviour, whatever the arguments.
[[nodiscard]] constexpr std::int32_t wrap(std::int32_t global_index,
                                          std::int32_t side_pow2) noexcept {
  CCMAP_ASSERT_OR_RETURN(is_power_of_two(side_pow2), 0);
  return detail::wrap_unchecked(global_index, side_pow2);
}

/// Offset of a global cell in a side x side buffer (row-major by ring position):
/// wrap(y)*side + wrap(x), in [0, side*side). Any side consecutive global indices on each axis
/// (any window) map onto every offset exactly once.
/// Precondition: is_power_of_two(side_pow2) and side_pow2 <= kMaxSide; a violation is reported
/// to the assert hook and answered 0.
[[nodiscard]] constexpr std::size_t buffer_offset(CellIndex index,
                                                  std::int32_t side_pow2) noexcept {
  CCMAP_ASSERT_OR_RETURN(is_power_of_two(side_pow2) && side_pow2 <= kMaxSide, 0U);
  return detail::buffer_offset_unchecked(index, side_pow2);
}

namespace detail {
/// floor(v * mult * 2^-q) for the float v with bit pattern `bits`, in integer operations only,
/// exact: the product of the 24-bit significand and mult (< 2^39) is formed in 64 bits, signed,
/// and shifted arithmetically (which floors negative values). Precondition: v finite and
/// 150 + q - exponent(v) >= 0, i.e. |v * mult * 2^-q| below 2^(63-24) or so (callers check the
/// magnitude first); a violation (a negative shift would be undefined behaviour) is reported to
/// the assert hook and answered 0. Shifts beyond 63 saturate (tiny v: 0 or -1).
[[nodiscard]] inline std::int64_t floor_scaled_bits(std::uint32_t bits, std::uint64_t mult, std::int32_t q) noexcept {
  const std::uint32_t biased = (bits >> 23) & 0xFFU;
  const std::uint64_t significand =
      (bits & 0x7FFFFFU) | (static_cast<std::uint64_t>(biased != 0U) << 23);  // subnormal: no implicit bit
  const std::int32_t exponent = static_cast<std::int32_t>(biased) + static_cast<std::int32_t>(biased == 0U);
  const std::int32_t shift = 150 + q - exponent;  // v = significand * 2^(exponent - 150)
  CCMAP_ASSERT_OR_RETURN(biased != 0xFFU && shift >= 0, 0);
  const auto product = static_cast<std::int64_t>(significand * mult);
  const std::int64_t sign = -static_cast<std::int64_t>(bits >> 31);  // 0 or -1
  const std::int64_t signed_product = (product ^ sign) - sign;
  // Arithmetic shift: floor (gcc/clang; standard since C++20); beyond 63 the result is 0 or -1.
  return signed_product >> (shift > 63 ? 63 : shift);
}

[[nodiscard]] inline std::uint32_t float_bits(float v) noexcept {
  std::uint32_t u = 0U;
  std::memcpy(&u, &v, sizeof u);
  return u;
}
}  // namespace detail

/// floor(x * c) of the exact (unrounded) product, for finite x and a positive normal c with
/// |x * c| < 2^40: integer operations only. The float expression std::floor(x * c) rounds the
/// product first and may land one cell up within ~2^-24 |x c| below an integer; this does not.
[[nodiscard]] inline std::int64_t exact_floor_mul(float x, float c) noexcept {
  const std::uint32_t c_bits = detail::float_bits(c);
  const auto c_exponent = static_cast<std::int32_t>((c_bits >> 23) & 0xFFU);
  const std::uint64_t c_significand = (c_bits & 0x7FFFFFU) | 0x800000U;
  return detail::floor_scaled_bits(detail::float_bits(x), c_significand, 150 - c_exponent);
}

/// Global index of the cell holding the map-frame position (x, y) metres:
/// floor(x * inv_cell_width), floor(y * inv_cell_width) of the exact (unrounded) product.
///
/// Returns false, and leaves *out untouched, if out is nullptr, if x or y is NaN or infinite,
/// if inv_cell_width is not a positive normal float (NaN included), or if an index would leave
/// [-kMaxCellIndex, kMaxCellIndex].
///
/// Precision limit: inv_cell_width is the rounded 1/w (0.1 m, 0.2 m, ... are not floats), a
/// relative error below 2^-24, so a position within about 2^-24 * |x| of a cell boundary (6 um
/// at 100 m) may be put into the neighbouring cell of the true 1/w: off by one, never more. The
/// product itself is not rounded (exact_floor_mul), and the map update computes the same exact
/// floor (map/update/front.hpp), so an update and every query name the same cell for a
/// map-frame position, edges included.
/// Beyond |x / w| = 2^23 consecutive floats are a cell or more apart, so not every cell can be
/// named by a position (the map frame is local: see kMaxAbsCoordinateM in cell/ccm_cell.hpp).
/// Tested in tests/grid/ring_index_test.cpp (IndexOfPosition.FloatRoundingLimitNearEdges) and,
/// against the update path, in tests/map/front_test.cpp.
[[nodiscard]] inline bool index_of_position(float x, float y, float inv_cell_width,
                                            CellIndex* out) noexcept {
  if (out == nullptr || !(inv_cell_width >= std::numeric_limits<float>::min()) ||
      !(inv_cell_width <= std::numeric_limits<float>::max())) {
    return false;
  }
  // Gate in float (NaN fails every comparison, +-Inf one of them); 2^30 + 2 leaves room for
  // the exact floor below to be checked against the limit itself.
  constexpr float kGate = static_cast<float>(kMaxCellIndex) + 2.0F;
  const float fx = x * inv_cell_width;
  const float fy = y * inv_cell_width;
  if (!(fx >= -kGate && fx <= kGate && fy >= -kGate && fy <= kGate)) {
    return false;
  }
  const std::int64_t ix = exact_floor_mul(x, inv_cell_width);
  const std::int64_t iy = exact_floor_mul(y, inv_cell_width);
  if (ix < -kMaxCellIndex || ix > kMaxCellIndex || iy < -kMaxCellIndex || iy > kMaxCellIndex) {
    return false;
  }
  out->x = static_cast<std::int32_t>(ix);
  out->y = static_cast<std::int32_t>(iy);
  return true;
}

/// Centre (metres, map frame) of global cell i along one axis: (i + 0.5) * cell_width.
/// Float precision: i + 0.5 is exact up to |i| = 2^23 and the product carries one rounding
/// (relative 2^-24). Mapping the centre back through index_of_position adds two more, so the
/// round trip is off by at most 3 * 2^-24 * |i + 0.5| cells: for |i| <= 2^21 (2.1e6 cells,
/// 210 km of 0.1 m cells) index_of_position(cell_centre(i, w), ..., 1/w) == i.
[[nodiscard]] constexpr float cell_centre(std::int32_t i, float cell_width) noexcept {
  return (static_cast<float>(i) + 0.5F) * cell_width;
}

}  // namespace grid
}  // namespace ccmap
