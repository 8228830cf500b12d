// Whole-map state of a Stack for tests: the raw storage of every layer plus every window, as
// bytes (to prove "the map is unchanged" bitwise) and as a 64-bit FNV-1a hash over a fixed byte
// order (to compare maps across targets).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "ccmap/map/stack.hpp"

namespace ccmap::test {

/// Bytes of every layer's raw storage (finest first, buffer order) followed by every layer's
/// window centre. Two stacks of the same type hold the same map iff these are equal.
template <typename Config>
std::vector<unsigned char> raw_map_state(const Stack<Config>& stack) {
  using S = Stack<Config>;
  std::vector<unsigned char> out;
  auto append = [&out](const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    out.insert(out.end(), b, b + n);
  };
  if constexpr (S::kHasFine) {
    append(stack.fine_layer().storage(), stack.fine_layer().cell_count() * sizeof(typename S::FineCell));
  }
  for (int c = 0; c < S::kCcmLayerCount; ++c) {
    append(stack.ccm_layer(c).storage(), stack.ccm_layer(c).cell_count() * sizeof(typename S::CcmCellType));
  }
  for (int k = 0; k < S::kLayerCount; ++k) {
    const CellIndex centre = stack.layer_centre(k);
    append(&centre, sizeof centre);
  }
  return out;
}

/// Byte offset of the first byte of `layer`'s storage inside raw_map_state().
template <typename Config>
std::size_t layer_byte_offset(const Stack<Config>& stack, int layer) {
  using S = Stack<Config>;
  std::size_t offset = 0;
  for (int k = 0; k < layer; ++k) {
    offset += S::layer_capacity(k) * (S::layer_is_ccm(k) ? sizeof(typename S::CcmCellType) : sizeof(typename S::FineCell));
  }
  (void)stack;
  return offset;
}

/// Calls fn(float) for every float of every cell of every layer (all cell types are packed
/// floats: static_asserts in cell/*.hpp).
template <typename Config, typename Fn>
void for_each_stored_float(const Stack<Config>& stack, Fn&& fn) {
  using S = Stack<Config>;
  static_assert(sizeof(typename S::FineCell) % sizeof(float) == 0, "cells are packed floats");
  auto visit = [&fn](const void* p, std::size_t bytes) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i + sizeof(float) <= bytes; i += sizeof(float)) {
      float v;
      std::memcpy(&v, b + i, sizeof v);
      fn(v);
    }
  };
  if constexpr (S::kHasFine) {
    visit(stack.fine_layer().storage(), stack.fine_layer().cell_count() * sizeof(typename S::FineCell));
  }
  for (int c = 0; c < S::kCcmLayerCount; ++c) {
    visit(stack.ccm_layer(c).storage(), stack.ccm_layer(c).cell_count() * sizeof(typename S::CcmCellType));
  }
}

/// True if no stored float is NaN or infinite.
template <typename Config>
bool all_stored_finite(const Stack<Config>& stack) {
  bool finite = true;
  for_each_stored_float(stack, [&finite](float v) { finite = finite && std::isfinite(v); });
  return finite;
}

/// 64-bit FNV-1a.
struct Fnv1a64 {
  std::uint64_t hash = 0xCBF29CE484222325ULL;
  void byte(std::uint8_t b) {
    hash ^= b;
    hash *= 0x100000001B3ULL;
  }
  /// Little-endian, whatever the host byte order.
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) byte(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f32(float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    u32(bits);
  }
};

/// FNV-1a over every stored float's IEEE-754 bits (little-endian) and every window centre: the
/// same map gives the same hash on every target.
template <typename Config>
std::uint64_t map_hash(const Stack<Config>& stack) {
  Fnv1a64 h;
  for_each_stored_float(stack, [&h](float v) { h.f32(v); });
  for (int k = 0; k < Stack<Config>::kLayerCount; ++k) {
    const CellIndex centre = stack.layer_centre(k);
    h.i32(centre.x);
    h.i32(centre.y);
  }
  return h.hash;
}

}  // namespace ccmap::test
