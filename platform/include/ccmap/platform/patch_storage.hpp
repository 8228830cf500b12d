// Patch storage: where the global map (global/patch_keeper.hpp) keeps the patches of cells that
// left the map's windows. A function table, not a virtual interface: the flight software binds
// it once (a flash region, a file system, a downlink queue) and the core calls it through two
// plain function pointers.
//
// Implementations in this layer:
//  - RegionPatchStorage (this header, no OS): fixed-size slots in a caller-provided byte region;
//    for bare metal (RAM, memory-mapped flash written by the caller's driver, ...).
//  - posix_directory_storage (platform/posix/patch_directory.cpp): one file per patch in a
//    directory, written to a temporary name and renamed (a reader never sees half a patch).
//
// Contract for every implementation: bounded time per call, no exceptions, no allocation after
// setup; a read returns exactly the bytes of the last successful write of that key (the keeper
// checks each patch's CRC and format itself, so a storage that returns damaged bytes is caught).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

namespace ccmap::platform {

/// Which patch: a layer of the map and a tile of that layer's global cell indices
/// (tile (tx, ty) holds the cells [tx * T, (tx + 1) * T) x [ty * T, (ty + 1) * T), T the tile side).
struct PatchKey {
  std::int32_t layer;
  std::int32_t tile_x;
  std::int32_t tile_y;
};

[[nodiscard]] inline bool same_key(const PatchKey& a, const PatchKey& b) noexcept {
  return a.layer == b.layer && a.tile_x == b.tile_x && a.tile_y == b.tile_y;
}

enum class StorageResult : std::uint8_t {
  kOk = 0,
  kNotFound = 1,  ///< read: no patch of that key was ever written
  kFull = 2,      ///< write: no room (the patch is not stored; an older one of that key is kept)
  kError = 3,     ///< I/O error, buffer too small, bad arguments
};

/// The table the keeper calls. `context` is passed back unchanged.
struct PatchStorage {
  void* context;
  /// Stores size bytes under key, replacing any earlier patch of that key.
  StorageResult (*write)(void* context, const PatchKey& key, const std::uint8_t* data, std::size_t size);
  /// Copies the patch of key into buffer (capacity bytes) and sets *size.
  StorageResult (*read)(void* context, const PatchKey& key, std::uint8_t* buffer, std::size_t capacity,
                        std::size_t* size);
};

/// Patches in a caller-provided region: slots of slot_bytes, each [used u32][key 3 x i32][size u32]
/// [patch bytes]. A lookup scans the slots (O(slots), bounded); a full region answers kFull.
/// Place it and the region in static storage; init() binds them.
class RegionPatchStorage {
 public:
  static constexpr std::size_t kSlotHeaderBytes = 20U;

  /// false (nothing bound) for a null region or a slot too small for a header and one byte.
  [[nodiscard]] bool init(std::uint8_t* region, std::size_t region_bytes, std::size_t slot_bytes) noexcept {
    region_ = nullptr;
    slots_ = 0U;
    if (region == nullptr || slot_bytes <= kSlotHeaderBytes || region_bytes < slot_bytes) {
      return false;
    }
    region_ = region;
    slot_bytes_ = slot_bytes;
    slots_ = region_bytes / slot_bytes;
    for (std::size_t s = 0; s < slots_; ++s) {
      const std::uint32_t unused = 0U;
      std::memcpy(slot(s), &unused, sizeof unused);
    }
    return true;
  }
  [[nodiscard]] PatchStorage table() noexcept { return PatchStorage{this, &write_fn, &read_fn}; }
  [[nodiscard]] std::size_t slots() const noexcept { return slots_; }
  [[nodiscard]] std::size_t used_slots() const noexcept {
    std::size_t n = 0U;
    for (std::size_t s = 0; s < slots_; ++s) {
      n += used(s) ? 1U : 0U;
    }
    return n;
  }

 private:
  static constexpr std::uint32_t kUsed = 0x50415443U;  // "PATC"

  [[nodiscard]] std::uint8_t* slot(std::size_t s) const noexcept { return region_ + s * slot_bytes_; }
  [[nodiscard]] bool used(std::size_t s) const noexcept {
    std::uint32_t mark = 0U;
    std::memcpy(&mark, slot(s), sizeof mark);
    return mark == kUsed;
  }
  [[nodiscard]] PatchKey key_of(std::size_t s) const noexcept {
    PatchKey k{};
    std::memcpy(&k.layer, slot(s) + 4, 4);
    std::memcpy(&k.tile_x, slot(s) + 8, 4);
    std::memcpy(&k.tile_y, slot(s) + 12, 4);
    return k;
  }
  /// The slot holding key, or slots_.
  [[nodiscard]] std::size_t find(const PatchKey& key) const noexcept {
    for (std::size_t s = 0; s < slots_; ++s) {
      if (used(s) && same_key(key_of(s), key)) {
        return s;
      }
    }
    return slots_;
  }
  static StorageResult write_fn(void* context, const PatchKey& key, const std::uint8_t* data, std::size_t size) {
    auto* self = static_cast<RegionPatchStorage*>(context);
    if (self == nullptr || self->region_ == nullptr || data == nullptr) {
      return StorageResult::kError;
    }
    if (size > self->slot_bytes_ - kSlotHeaderBytes) {
      return StorageResult::kFull;
    }
    std::size_t s = self->find(key);
    for (std::size_t i = 0; s == self->slots_ && i < self->slots_; ++i) {
      s = self->used(i) ? s : i;
    }
    if (s == self->slots_) {
      return StorageResult::kFull;
    }
    std::uint8_t* p = self->slot(s);
    const auto size32 = static_cast<std::uint32_t>(size);
    std::memcpy(p + 4, &key.layer, 4);
    std::memcpy(p + 8, &key.tile_x, 4);
    std::memcpy(p + 12, &key.tile_y, 4);
    std::memcpy(p + 16, &size32, 4);
    std::memcpy(p + kSlotHeaderBytes, data, size);
    std::memcpy(p, &kUsed, 4);  // last: a slot is used only once it is whole
    return StorageResult::kOk;
  }
  static StorageResult read_fn(void* context, const PatchKey& key, std::uint8_t* buffer, std::size_t capacity,
                               std::size_t* size) {
    const auto* self = static_cast<const RegionPatchStorage*>(context);
    if (self == nullptr || buffer == nullptr || size == nullptr) {
      return StorageResult::kError;
    }
    const std::size_t s = self->find(key);
    if (s == self->slots_) {
      return StorageResult::kNotFound;
    }
    std::uint32_t stored = 0U;
    std::memcpy(&stored, self->slot(s) + 16, 4);
    if (stored > capacity || stored > self->slot_bytes_ - kSlotHeaderBytes) {
      return StorageResult::kError;
    }
    std::memcpy(buffer, self->slot(s) + kSlotHeaderBytes, stored);
    *size = stored;
    return StorageResult::kOk;
  }

  std::uint8_t* region_ = nullptr;
  std::size_t slot_bytes_ = 0U;
  std::size_t slots_ = 0U;
};

/// State of a directory storage (static storage; no allocation).
struct PosixDirectory {
  char path[200];
};

/// Binds `state` to an existing directory and fills *table; false if the path is null, too
/// long or not a directory (POSIX builds only: platform/posix/patch_directory.cpp). Patch files
/// are named L<layer>_<tile_x>_<tile_y>.ccp.
[[nodiscard]] bool posix_directory_storage(const char* directory, PosixDirectory* state, PatchStorage* table) noexcept;

}  // namespace ccmap::platform
