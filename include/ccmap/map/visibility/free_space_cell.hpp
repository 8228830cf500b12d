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
//
// Map exchange (persistence/exchange.hpp, delta format 3) carries what a team mate can use of
// these records as free-space entries (FreeSpaceEntry, below): a drop-off (its bound and drop
// rays) and a cleared cell (the sender's lines of sight emptied it). On the wire, 10 bytes,
// little-endian, each entry with its own check so that a damaged one is refused alone:
//   u32 where     bits 0-23 position in the layer's window, (y - min_y) side + (x - min_x) (the
//                 window of the delta's layer header), bits 24-27 stack layer (0 the finest),
//                 bits 28-31 kind (1 drop-off, 2 cleared; any other: refused)
//   u16 bound     drop-off: the record's bound_code (0 = no bound; heights above the sender's
//                 origin); cleared: 0
//   u8  rays      drop-off: drop rays, kDropRays .. 3; cleared: 0
//   u8  reserved  0
//   u16 check     CRC-16/CCITT-FALSE (polynomial 0x1021, initial 0xFFFF, no reflection) of the 8
//                 bytes before it: every error of up to 3 bits and every burst of up to 16 bits
//                 in an entry is detected
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
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

// ---- map exchange: free-space entries (the file comment gives the bytes) ----

/// What a free-space entry says.
enum class FreeSpaceEntryKind : std::uint8_t {
  kDropOff = 1U,  ///< the sender's rays proved a drop-off in the cell (unobserved there)
  kCleared = 2U,  ///< the sender's lines of sight emptied the cell (a ghost)
};

/// One decoded free-space entry of a delta.
struct FreeSpaceEntry {
  FreeSpaceEntryKind kind;
  std::uint8_t layer;       ///< stack layer (0 the finest)
  std::uint32_t position;   ///< in the layer's window, rows of increasing y (< 2^24)
  std::uint16_t bound_code; ///< drop-off: the record's bound_code; cleared: 0
  std::uint8_t drop_rays;   ///< drop-off: kDropRays .. 3; cleared: 0
};

inline constexpr std::size_t kFreeSpaceEntryBytes = 10U;
inline constexpr std::uint32_t kFreeSpaceEntryPositions = 1U << 24U;  ///< positions a layer may have
inline constexpr std::uint32_t kFreeSpaceEntryLayers = 16U;

/// CRC-16/CCITT-FALSE of n bytes (check("123456789") = 0x29B1).
[[nodiscard]] inline std::uint16_t free_space_entry_crc(const std::uint8_t* bytes, std::size_t n) noexcept {
  std::uint32_t crc = 0xFFFFU;
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= static_cast<std::uint32_t>(bytes[i]) << 8U;
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000U) != 0U ? ((crc << 1U) ^ 0x1021U) : (crc << 1U);
    }
    crc &= 0xFFFFU;
  }
  return static_cast<std::uint16_t>(crc);
}

/// The entry of a drop-off record (is_drop) at `position` of `layer`.
[[nodiscard]] inline FreeSpaceEntry drop_entry_of(const FreeSpaceCell& rec, int layer, std::uint32_t position) noexcept {
  return FreeSpaceEntry{FreeSpaceEntryKind::kDropOff, static_cast<std::uint8_t>(layer), position, rec.bound_code,
                        static_cast<std::uint8_t>(drop_rays(rec))};
}

/// Writes the 10 bytes of an entry (fields as the file comment; no validation: callers write
/// entries of their own records).
inline void encode_free_space_entry(const FreeSpaceEntry& e, std::uint8_t* out) noexcept {
  const std::uint32_t where = (e.position & (kFreeSpaceEntryPositions - 1U)) |
                              ((static_cast<std::uint32_t>(e.layer) & 0x0FU) << 24U) |
                              (static_cast<std::uint32_t>(e.kind) << 28U);
  for (unsigned b = 0U; b < 4U; ++b) {
    out[b] = static_cast<std::uint8_t>((where >> (8U * b)) & 0xFFU);
  }
  out[4] = static_cast<std::uint8_t>(e.bound_code & 0xFFU);
  out[5] = static_cast<std::uint8_t>(e.bound_code >> 8U);
  out[6] = e.drop_rays;
  out[7] = 0U;
  const std::uint16_t crc = free_space_entry_crc(out, 8U);
  out[8] = static_cast<std::uint8_t>(crc & 0xFFU);
  out[9] = static_cast<std::uint8_t>(crc >> 8U);
}

/// Reads 10 bytes into *e; false (e unchanged) for a check mismatch or anything an export does
/// not write: another kind, a non-zero reserved byte, a drop-off with fewer than kDropRays or
/// more than 3 rays, a cleared entry with a bound or rays. The layer and position are checked
/// against the receiver's stack by the caller.
[[nodiscard]] inline bool decode_free_space_entry(const std::uint8_t* in, FreeSpaceEntry* e) noexcept {
  const auto crc = static_cast<std::uint16_t>(in[8] | (in[9] << 8U));
  if (free_space_entry_crc(in, 8U) != crc || in[7] != 0U) {
    return false;
  }
  std::uint32_t where = 0U;
  for (unsigned b = 0U; b < 4U; ++b) {
    where |= static_cast<std::uint32_t>(in[b]) << (8U * b);
  }
  const std::uint32_t kind = where >> 28U;
  const auto bound = static_cast<std::uint16_t>(in[4] | (in[5] << 8U));
  const std::uint8_t rays = in[6];
  const bool drop = kind == static_cast<std::uint32_t>(FreeSpaceEntryKind::kDropOff) && rays >= kDropRays && rays <= 3U;
  const bool cleared = kind == static_cast<std::uint32_t>(FreeSpaceEntryKind::kCleared) && rays == 0U && bound == 0U;
  if (!drop && !cleared) {
    return false;
  }
  *e = FreeSpaceEntry{static_cast<FreeSpaceEntryKind>(kind), static_cast<std::uint8_t>((where >> 24U) & 0x0FU),
                      where & (kFreeSpaceEntryPositions - 1U), bound, rays};
  return true;
}

/// A team mate's drop-off folded into a record: the bound lowered to bound_z_m (this map's
/// frame, rounded up as lower_bound; NaN: the entry had no bound) and the drop rays raised to
/// `rays` (at most 3). Both are idempotent, so a drop-off merged twice is merged once.
inline void merge_drop(FreeSpaceCell& c, float bound_z_m, std::uint32_t rays) noexcept {
  lower_bound(c, bound_z_m);
  const std::uint32_t r = rays < 3U ? rays : 3U;
  const std::uint32_t kept = drop_rays(c);
  c.state = static_cast<std::uint8_t>((c.state & kNotDropMask) | (std::max(r, kept) << kDropShift));
}

}  // namespace ccmap::detail
