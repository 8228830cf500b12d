// Markers that bracket a region whose aarch64 instructions the QEMU plugin counts
// (tools/qemu-icount, docs/performance.md "Counting instructions under QEMU").
//
//   ccmap::test::icount_begin<1>();
//   stack.update_frame(...);          // counted in region 1
//   ccmap::test::icount_end<1>();
//
// Each marker is one architectural no-op instruction, MOVZ XZR, #id (begin) or
// MOVZ XZR, #id, LSL #16 (end) (tools/qemu-icount/icount_marker_encoding.h), emitted as a
// volatile asm statement with a memory clobber: the compiler neither removes it nor moves
// memory accesses across it. It can still schedule register-only arithmetic across a marker,
// so bracket whole calls (a non-inlined function, an update_frame) rather than a few
// statements. Region ids are 0 .. 65535; a region may be entered any number of times (the
// plugin sums the intervals and counts them); different regions may overlap, one region may
// not nest in itself. On targets other than aarch64 the markers compile to nothing.
#pragma once

#include <cstdint>

#include "../../tools/qemu-icount/icount_marker_encoding.h"

namespace ccmap::test {

namespace detail {
template <std::uint32_t Word>
inline void icount_marker() {
#if defined(__aarch64__)
  asm volatile(".inst %c0" : : "i"(Word) : "memory");
#endif
}
}  // namespace detail

/// Begins an interval of region RegionId (0 .. 65535).
template <std::uint32_t RegionId>
inline void icount_begin() {
  static_assert(RegionId <= CCMAP_ICOUNT_MAX_REGION_ID, "icount region ids are 0 .. 65535");
  detail::icount_marker<CCMAP_ICOUNT_MARKER_BEGIN | (RegionId << CCMAP_ICOUNT_MARKER_ID_SHIFT)>();
}

/// Ends the open interval of region RegionId.
template <std::uint32_t RegionId>
inline void icount_end() {
  static_assert(RegionId <= CCMAP_ICOUNT_MAX_REGION_ID, "icount region ids are 0 .. 65535");
  detail::icount_marker<CCMAP_ICOUNT_MARKER_END | (RegionId << CCMAP_ICOUNT_MARKER_ID_SHIFT)>();
}

}  // namespace ccmap::test
