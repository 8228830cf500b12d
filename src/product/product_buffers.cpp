#include "ccmap/product/product_buffers.hpp"

#include <cstring>

#include "ccmap/product/product_format.hpp"

namespace ccmap {
namespace {

[[nodiscard]] std::uint32_t load_relaxed(const std::uint32_t* p) noexcept { return __atomic_load_n(p, __ATOMIC_RELAXED); }
[[nodiscard]] std::uint32_t load_acquire(const std::uint32_t* p) noexcept { return __atomic_load_n(p, __ATOMIC_ACQUIRE); }
void store_relaxed(std::uint32_t* p, std::uint32_t v) noexcept { __atomic_store_n(p, v, __ATOMIC_RELAXED); }
void store_release(std::uint32_t* p, std::uint32_t v) noexcept { __atomic_store_n(p, v, __ATOMIC_RELEASE); }

/// Words of a slot.
[[nodiscard]] std::size_t slot_words(const ProductBuffers& b) noexcept { return b.slot_bytes / 4U; }
[[nodiscard]] std::uint32_t* slot(const ProductBuffers& b, std::uint32_t s) noexcept {
  return b.storage + slot_words(b) * s;
}

}  // namespace

Status product_buffers_init(ProductBuffers* buffers, void* storage, std::size_t storage_size) noexcept {
  if (buffers == nullptr || storage == nullptr || reinterpret_cast<std::uintptr_t>(storage) % 4U != 0U) {
    return Status::kInvalidArgument;
  }
  const std::size_t slot_bytes = storage_size / 12U * 4U;
  if (slot_bytes < product_size(1U, 1U) || slot_bytes > 0x80000000U) {
    return Status::kInvalidArgument;
  }
  *buffers = ProductBuffers{};
  buffers->slot_bytes = static_cast<std::uint32_t>(slot_bytes);
  buffers->storage = static_cast<std::uint32_t*>(storage);
  buffers->magic = kProductBuffersMagic ^ buffers->slot_bytes;
  return Status::kOk;
}

bool product_buffers_valid(const ProductBuffers& buffers) noexcept {
  return buffers.storage != nullptr && buffers.magic == (kProductBuffersMagic ^ buffers.slot_bytes) &&
         buffers.slot_bytes % 4U == 0U && buffers.slot_bytes >= product_size(1U, 1U);
}

std::uint8_t* product_staging(ProductBuffers& buffers) noexcept {
  // The staging area is the writer's alone: plain bytes.
  return product_buffers_valid(buffers) ? reinterpret_cast<std::uint8_t*>(slot(buffers, 2U)) : nullptr;
}

std::uint32_t product_next_sequence(const ProductBuffers& buffers) noexcept {
  return load_relaxed(&buffers.published) + 1U;  // the writer is the only one that stores it
}

Status product_commit(ProductBuffers& buffers, std::uint32_t bytes) noexcept {
  if (!product_buffers_valid(buffers) || bytes % 4U != 0U || bytes > buffers.slot_bytes) {
    return Status::kInvalidArgument;
  }
  const std::uint32_t n = load_relaxed(&buffers.published);
  const std::uint32_t s = (n + 1U) & 1U;
  std::uint32_t* sequence = &buffers.slot_sequence[s];
  const std::uint32_t v = load_relaxed(sequence);
  store_relaxed(sequence, v + 1U);  // odd: being written
  std::uint32_t* target = slot(buffers, s);
  const auto* staged = reinterpret_cast<const std::uint8_t*>(slot(buffers, 2U));
  for (std::uint32_t i = 0; i < bytes / 4U; ++i) {
    std::uint32_t word = 0U;
    std::memcpy(&word, staged + 4U * i, sizeof word);
    store_release(target + i, word);  // release: the odd sequence is visible before this word
  }
  store_release(sequence, v + 2U);  // even: whole
  store_release(&buffers.published, n + 1U);
  return Status::kOk;
}

Status product_read(const ProductBuffers& buffers, std::uint8_t* out, std::size_t capacity,
                    std::size_t* written) noexcept {
  if (written != nullptr) {
    *written = 0U;
  }
  if (out == nullptr || written == nullptr || !product_buffers_valid(buffers)) {
    return Status::kInvalidArgument;
  }
  for (std::uint32_t attempt = 0; attempt < kProductReadTries; ++attempt) {
    const std::uint32_t n = load_acquire(&buffers.published);
    if (n == 0U) {
      return Status::kNotInitialised;
    }
    const std::uint32_t s = n & 1U;
    const std::uint32_t* sequence = &buffers.slot_sequence[s];
    const std::uint32_t v1 = load_acquire(sequence);
    if ((v1 & 1U) != 0U) {
      continue;
    }
    const std::uint32_t* source = slot(buffers, s);
    // The size word (+8) first; clamped, since a torn copy may hold anything until v2 says.
    std::uint32_t size_word = load_acquire(source + 2U);
    std::uint8_t size_bytes[4];
    std::memcpy(size_bytes, &size_word, sizeof size_word);
    std::uint32_t total = product_detail::get_u32(size_bytes);
    const bool fits_slot = total >= product_size(1U, 1U) && total <= buffers.slot_bytes && total % 4U == 0U;
    const bool fits_out = total <= capacity;
    if (fits_slot && fits_out) {
      for (std::uint32_t i = 0; i < total / 4U; ++i) {
        const std::uint32_t word = load_acquire(source + i);  // acquire: v2 is read after this word
        std::memcpy(out + 4U * i, &word, sizeof word);
      }
    }
    const std::uint32_t v2 = load_relaxed(sequence);
    if (v1 != v2) {
      continue;  // the writer came by during the copy
    }
    if (!fits_slot) {
      return Status::kCorrupt;
    }
    if (!fits_out) {
      return Status::kBufferTooSmall;
    }
    ProductHeader header{};
    if (decode_product_header(out, total, &header) != Status::kOk || (header.product_sequence & 1U) != s) {
      return Status::kCorrupt;
    }
    *written = total;
    return Status::kOk;
  }
  return Status::kBusy;
}

}  // namespace ccmap
