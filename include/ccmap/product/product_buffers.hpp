// The double buffer that carries map products from the writer (the map's thread) to readers in
// other threads, lock-free: the caller owns the memory (ccmap_product_buffers of ccmap/ccmap.h,
// used as is from C++), the writer never waits, a reader gets a whole product or a refusal.
//
// Memory ordering (a sequence lock per slot; H.-J. Boehm, "Can seqlocks get along with
// programming language memory models?", the variant without stand-alone fences):
//   writer (one thread): slot s = the one readers are not pointed at; seq[s] = odd (relaxed);
//     each word of the product stored with release (so no reader can see a new word without
//     then seeing the odd sequence); seq[s] = even (release); published = n + 1 (release):
//     readers now start at slot s.
//   reader (any thread): n = published (acquire); s = n & 1; v1 = seq[s] (acquire), odd: retry;
//     each word loaded with acquire (so the second sequence load cannot move before it);
//     v2 = seq[s] (relaxed); v1 != v2: retry; else the copy was taken while no writer wrote the
//     slot: check its CRC and sizes.
// Every shared word is touched only through 32-bit atomics (GCC/Clang __atomic builtins on
// plain uint32_t: lock-free on every target of this library), so the exchange is race-free in
// the C++ memory model, and ThreadSanitizer (which does not model stand-alone fences) checks the
// very code that flies (tests/capi/CMakeLists.txt, ProductBuffers.ThreadSanitizer). On x86-64
// release and acquire are plain moves; on aarch64 stlr/ldar; on Cortex-M7 a dmb beside each.
#pragma once

#include <cstddef>
#include <cstdint>

#include "ccmap/ccmap.h"
#include "ccmap/core/status.hpp"

namespace ccmap {

using ProductBuffers = ccmap_product_buffers;

inline constexpr std::uint32_t kProductBuffersMagic = 0x42504343U;  // "CCPB"
inline constexpr std::uint32_t kProductReadTries = 8U;

/// Binds storage[0, storage_size) (4-byte aligned) as two slots and a staging area of
/// floor(storage_size / 12) * 4 bytes each. kInvalidArgument: nullptr, misaligned, too small
/// for a product of one cell, or above 3 * 2^31 bytes.
[[nodiscard]] Status product_buffers_init(ProductBuffers* buffers, void* storage, std::size_t storage_size) noexcept;

/// True if `buffers` was set up by product_buffers_init (and not damaged since).
[[nodiscard]] bool product_buffers_valid(const ProductBuffers& buffers) noexcept;

/// The writer's staging area (slot_bytes bytes): compose the next product there, then commit it.
/// nullptr if the buffers are not set up.
[[nodiscard]] std::uint8_t* product_staging(ProductBuffers& buffers) noexcept;

/// The sequence number the next committed product must carry (1 for the first).
[[nodiscard]] std::uint32_t product_next_sequence(const ProductBuffers& buffers) noexcept;

/// Publishes the first `bytes` bytes of the staging area (a multiple of 4, at most slot_bytes)
/// into the slot readers are not pointed at, then points them at it. The writer only.
[[nodiscard]] Status product_commit(ProductBuffers& buffers, std::uint32_t bytes) noexcept;

/// Copies the latest whole product into out[0, *written): kOk; kNotInitialised (nothing
/// published); kBusy (the writer replaced the slot during each of kProductReadTries tries);
/// kCorrupt (a copy no writer disturbed fails its CRC or sizes); kBufferTooSmall; kInvalidArgument.
/// *written is 0 unless kOk. Any thread; never writes to `buffers`.
[[nodiscard]] Status product_read(const ProductBuffers& buffers, std::uint8_t* out, std::size_t capacity,
                                  std::size_t* written) noexcept;

}  // namespace ccmap
