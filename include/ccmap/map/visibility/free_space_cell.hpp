// What lines of sight have said about one map cell (docs/design.md, "Free space from lines of
// sight"): an upper bound on the terrain height where rays crossed the cell without meeting
// anything, the evidence that a surface stored in the cell is not there any more (rays passed
// clearly below it), and whether the rays proved a drop-off in it. Four bytes per cell, one
// record per cell of every layer (map/visibility/free_space.hpp keeps them beside the layers and
// moves them with the windows). Pure functions; integrators need not read it.
//
// Encoding (all zero is "nothing known", so a cleared cell and a static stack in .bss need no
// initialisation):
//   bound_code  uint16: 0 = no bound; else the bound is (bound_code - 32768) * 2^-8 m, i.e. heights
//               within +-128 m of the map origin in steps of 3.9 mm, rounded UP (an upper bound
//               stays an upper bound). A ray lower than -127.99 m or higher than +127.99 m
//               leaves the bound as it was (kMinBoundM, kMaxBoundM): such heights carry no bound.
//   evidence    frames in which the cell's surface was contradicted (kContradictionsPerFrame rays
//               or more passed clearly below it) since it was last confirmed; saturates at 255.
//   state       bits 0-2  frame stamp (the frame counter mod 8) of the per-frame bits below
//               bits 3-4  rays of that frame that contradicted the cell (0 .. 3, saturating)
//               bit  5    a ray of that frame ended on the cell's surface (confirmed)
//               bits 6-7  rays (of any frame) that proved a drop-off in the cell (0 .. 3,
//                         saturating); the cell is a drop-off from kDropRays on
// The per-frame bits are valid only while the stamp equals the current frame's; a record not
// touched for a multiple of 8 frames looks touched with stale bits, which at worst delays one
// frame's evidence (documented limit, tested).
#pragma once

#include <cmath>
#include <cstdint>

namespace ccmap::detail {

struct FreeSpaceCell {
  std::uint16_t bound_code;
  std::uint8_t evidence;
  std::uint8_t state;
};
static_assert(sizeof(FreeSpaceCell) == 4U, "the free-space record is 4 bytes per cell");

inline constexpr float kBoundUnitM = 0.00390625F;        ///< 2^-8 m
inline constexpr float kBoundUnitsPerM = 256.0F;
inline constexpr float kMinBoundM = -32767.0F * kBoundUnitM;  ///< -127.996 m
inline constexpr float kMaxBoundM = 32767.0F * kBoundUnitM;   ///< +127.996 m
inline constexpr std::uint8_t kStampMask = 0x07U;
inline constexpr int kContradictionShift = 3;
inline constexpr std::uint8_t kContradictionMask = 0x18U;
inline constexpr std::uint8_t kConfirmedBit = 0x20U;
inline constexpr int kDropShift = 6;
inline constexpr std::uint8_t kDropMask = 0xC0U;
inline constexpr std::uint32_t kNotDropMask = 0x3FU;
inline constexpr std::uint32_t kNotContradictionMask = 0xE7U;
/// Rays of one frame that must pass clearly below a cell's surface for the frame to count as
/// evidence against it: one ray is a stereo mismatch as often as it is a vanished rover.
inline constexpr std::uint32_t kContradictionsPerFrame = 2U;
/// Rays that must prove a drop-off in a cell before it is one: a single mismatched ray passing
/// under hidden ground would otherwise mark it.
inline constexpr std::uint32_t kDropRays = 2U;

/// True if the record holds an upper bound.
[[nodiscard]] inline bool has_bound(const FreeSpaceCell& c) noexcept { return c.bound_code != 0U; }

/// The bound (m) of a record that has one (has_bound); the value of code 0 otherwise.
[[nodiscard]] inline float bound_m(const FreeSpaceCell& c) noexcept {
  return static_cast<float>(static_cast<std::int32_t>(c.bound_code) - 32768) * kBoundUnitM;
}

/// Lowers the record's bound to z (m) if z is lower (rounded up to the 2^-8 m step: the stored
/// bound is never below z). z outside [kMinBoundM, kMaxBoundM] (or NaN) changes nothing.
inline void lower_bound(FreeSpaceCell& c, float z) noexcept {
  if (!(z >= kMinBoundM && z <= kMaxBoundM)) {
    return;
  }
  // ceil(z * 256): |z * 256| <= 32767, exact in float; the cast after ceil is exact.
  const auto units = static_cast<std::int32_t>(std::ceil(z * kBoundUnitsPerM));
  const auto code = static_cast<std::uint16_t>(units + 32768);
  if (c.bound_code == 0U || code < c.bound_code) {
    c.bound_code = code;
  }
}

/// Rays that proved a drop-off in the cell (0 .. 3).
[[nodiscard]] inline std::uint32_t drop_rays(const FreeSpaceCell& c) noexcept {
  return static_cast<std::uint32_t>(c.state & kDropMask) >> kDropShift;
}
/// True if at least kDropRays rays proved a drop-off in the cell.
[[nodiscard]] inline bool is_drop(const FreeSpaceCell& c) noexcept { return drop_rays(c) >= kDropRays; }

/// One more ray that proved a drop-off; true if the cell became a drop-off with it.
inline bool add_drop_ray(FreeSpaceCell& c) noexcept {
  const std::uint32_t n = drop_rays(c);
  if (n == 3U) {
    return false;
  }
  c.state = static_cast<std::uint8_t>((c.state & kNotDropMask) | ((n + 1U) << kDropShift));
  return n + 1U == kDropRays;
}

/// Makes the per-frame bits current for frame `stamp` (0 .. 7): a record last touched in another
/// frame starts the frame with no contradiction and no confirmation. True if it had to (the
/// first touch of this frame).
inline bool touch(FreeSpaceCell& c, std::uint8_t stamp) noexcept {
  if ((c.state & kStampMask) == stamp) {
    return false;
  }
  c.state = static_cast<std::uint8_t>((c.state & kDropMask) | stamp);
  return true;
}

/// Rays of the current frame that contradicted the cell (0 .. 3). Precondition: touch() this frame.
[[nodiscard]] inline std::uint32_t frame_contradictions(const FreeSpaceCell& c) noexcept {
  return static_cast<std::uint32_t>(c.state & kContradictionMask) >> kContradictionShift;
}
inline void add_contradiction(FreeSpaceCell& c) noexcept {
  const std::uint32_t n = frame_contradictions(c);
  if (n < 3U) {
    c.state = static_cast<std::uint8_t>((c.state & kNotContradictionMask) | ((n + 1U) << kContradictionShift));
  }
}
[[nodiscard]] inline bool frame_confirmed(const FreeSpaceCell& c) noexcept { return (c.state & kConfirmedBit) != 0U; }

/// A ray of this frame ended on the cell's surface: the surface is there. The evidence against
/// it is forgotten. Precondition: touch() this frame.
inline void confirm(FreeSpaceCell& c) noexcept {
  c.state = static_cast<std::uint8_t>(c.state | kConfirmedBit);
  c.evidence = 0U;
}

/// The end of a frame for a cell this frame touched: a frame with at least
/// kContradictionsPerFrame contradicting rays and no confirmation adds one frame of evidence.
/// Returns the evidence after it.
inline std::uint32_t settle_frame(FreeSpaceCell& c) noexcept {
  if (!frame_confirmed(c) && frame_contradictions(c) >= kContradictionsPerFrame && c.evidence < 255U) {
    ++c.evidence;
  }
  return c.evidence;
}

}  // namespace ccmap::detail
