// Floats compared by their bit patterns: where "the same value" must mean the same bits (a grid
// width two maps must share exactly, parameters a command must change or not), not ==, which
// calls -0 and +0 equal and a NaN unequal to itself.
#pragma once

#include <cstdint>
#include <cstring>

namespace ccmap::detail {

/// True if two floats have the same bit pattern.
[[nodiscard]] inline bool same_float_bits(float a, float b) noexcept {
  std::uint32_t ua = 0U;
  std::uint32_t ub = 0U;
  std::memcpy(&ua, &a, sizeof ua);
  std::memcpy(&ub, &b, sizeof ub);
  return ua == ub;
}

/// The same for arrays of n floats.
[[nodiscard]] inline bool same_float_bits(const float* a, const float* b, std::size_t n) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    if (!same_float_bits(a[i], b[i])) {
      return false;
    }
  }
  return true;
}

}  // namespace ccmap::detail
