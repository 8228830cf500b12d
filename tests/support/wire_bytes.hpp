// Little-endian fields of serialised maps (snapshots, exchange deltas) read and forged by tests:
// the tests change a field, reseal the CRC-32 trailer, and check that validation, not the CRC,
// refuses the result.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "ccmap/persistence/snapshot.hpp"

namespace ccmap::test {

using Bytes = std::vector<std::uint8_t>;

inline std::uint32_t get_u32(const Bytes& b, std::size_t at) {
  return static_cast<std::uint32_t>(b[at]) | static_cast<std::uint32_t>(b[at + 1]) << 8 |
         static_cast<std::uint32_t>(b[at + 2]) << 16 | static_cast<std::uint32_t>(b[at + 3]) << 24;
}
inline void put_u32(Bytes& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline void put_f32(Bytes& b, std::size_t at, float v) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, 4);
  put_u32(b, at, bits);
}
/// Recomputes the trailer (CRC-32 of everything before the last 4 bytes).
inline void reseal(Bytes& b) { put_u32(b, b.size() - 4, crc32_update(0U, b.data(), b.size() - 4)); }

}  // namespace ccmap::test
