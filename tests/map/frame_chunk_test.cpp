// detail::floor_to_int64 (map/frame_chunk.hpp), the integer-only float -> int64 conversion of
// the routing bounds, against the compiler's own conversion (static_cast truncates, which is
// floor for v >= 1), over every exponent it accepts.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include "ccmap/map/frame_chunk.hpp"

namespace {

float from_bits(std::uint32_t bits) {
  float v = 0.0F;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

TEST(FrameChunk, FloorToInt64EqualsTheCompilersConversion) {
  // 1 <= v < 2^63: biased exponents 127 .. 189, with mantissas from the edges and between.
  const std::uint32_t mantissas[] = {0x000000U, 0x000001U, 0x2AAAAAU, 0x400000U, 0x555555U, 0x7FFFFEU, 0x7FFFFFU};
  int checked = 0;
  for (std::uint32_t exponent = 127U; exponent <= 189U; ++exponent) {
    for (const std::uint32_t mantissa : mantissas) {
      const float v = from_bits((exponent << 23) | mantissa);
      ASSERT_EQ(ccmap::detail::floor_to_int64(v), static_cast<std::int64_t>(v)) << "v = " << v;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 63 * 7);
  EXPECT_EQ(ccmap::detail::floor_to_int64(1.0F), 1);
  EXPECT_EQ(ccmap::detail::floor_to_int64(2.75F), 2);
  EXPECT_EQ(ccmap::detail::floor_to_int64(8388607.5F), 8388607);  // 2^23 - 0.5: exact in float
  EXPECT_EQ(ccmap::detail::floor_to_int64(9.0e18F), static_cast<std::int64_t>(9.0e18F));
}

}  // namespace
