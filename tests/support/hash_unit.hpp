// Deterministic test noise without libm or the standard library's distributions, so that the
// host and aarch64 builds generate bitwise-identical inputs.
#pragma once

#include <cstdint>

namespace ccmap::test {

/// Integer hash of (i, salt) -> [0, 1) with 24 bits: exact in float.
inline float hash_unit(std::uint32_t i, std::uint32_t salt) {
  std::uint32_t h = i * 0x9E3779B1U ^ salt * 0x85EBCA77U;
  h ^= h >> 15;
  h *= 0x2C1B3C6DU;
  h ^= h >> 12;
  h *= 0x297A2D39U;
  h ^= h >> 15;
  return static_cast<float>(h >> 8) * (1.0F / 16777216.0F);
}

}  // namespace ccmap::test
