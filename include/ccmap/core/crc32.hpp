// CRC-32 (IEEE 802.3, as zlib's crc32; reflected polynomial 0xEDB88320), header-only: the one
// implementation behind snapshots, exchange deltas and patches (crc32_update,
// persistence/snapshot.hpp) and the map product (product_crc32, product/product_format.hpp), whose
// decoder must stay usable with no library linked. No heap; the table is built at compile time.
#pragma once

#include <cstddef>
#include <cstdint>

namespace ccmap {
namespace detail {

struct Crc32Table {
  std::uint32_t entry[256];
};

[[nodiscard]] constexpr Crc32Table make_crc32_table() noexcept {
  Crc32Table t{};
  for (std::uint32_t i = 0; i < 256U; ++i) {
    std::uint32_t c = i;
    for (int bit = 0; bit < 8; ++bit) {
      c = (c & 1U) != 0U ? (0xEDB88320U ^ (c >> 1U)) : (c >> 1U);
    }
    t.entry[i] = c;
  }
  return t;
}
inline constexpr Crc32Table kCrc32Table = make_crc32_table();

/// Continues a CRC-32: pass 0 as `crc` for the first block, the previous result to continue.
/// crc32_continue(0, "123456789", 9) == 0xCBF43926. data[0, size) must be readable.
[[nodiscard]] inline std::uint32_t crc32_continue(std::uint32_t crc, const std::uint8_t* data,
                                                  std::size_t size) noexcept {
  std::uint32_t c = ~crc;
  for (std::size_t i = 0; i < size; ++i) {
    c = kCrc32Table.entry[(c ^ data[i]) & 0xFFU] ^ (c >> 8U);
  }
  return ~c;
}

}  // namespace detail
}  // namespace ccmap
