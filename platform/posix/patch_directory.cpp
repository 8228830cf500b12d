// The POSIX patch storage: one file per patch in a directory (platform/include/ccmap/platform/patch_storage.hpp).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>

#include "ccmap/platform/patch_storage.hpp"

namespace ccmap::platform {
namespace {

bool patch_path(const PosixDirectory& dir, const PatchKey& key, const char* suffix, char (&out)[256]) noexcept {
  const int n = std::snprintf(out, sizeof out, "%s/L%d_%d_%d.ccp%s", dir.path, static_cast<int>(key.layer),
                              static_cast<int>(key.tile_x), static_cast<int>(key.tile_y), suffix);
  return n > 0 && static_cast<std::size_t>(n) < sizeof out;
}

StorageResult write_file(void* context, const PatchKey& key, const std::uint8_t* data, std::size_t size) {
  const auto* dir = static_cast<const PosixDirectory*>(context);
  char temporary[256];
  char final_path[256];
  if (dir == nullptr || data == nullptr || !patch_path(*dir, key, ".tmp", temporary) ||
      !patch_path(*dir, key, "", final_path)) {
    return StorageResult::kError;
  }
  const int fd = ::open(temporary, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) {
    return StorageResult::kError;
  }
  std::size_t done = 0U;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n <= 0) {
      (void)::close(fd);
      (void)::unlink(temporary);
      return StorageResult::kFull;
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0 || ::rename(temporary, final_path) != 0) {
    (void)::unlink(temporary);
    return StorageResult::kError;
  }
  return StorageResult::kOk;
}

StorageResult read_file(void* context, const PatchKey& key, std::uint8_t* buffer, std::size_t capacity,
                        std::size_t* size) {
  const auto* dir = static_cast<const PosixDirectory*>(context);
  char path[256];
  if (dir == nullptr || buffer == nullptr || size == nullptr || !patch_path(*dir, key, "", path)) {
    return StorageResult::kError;
  }
  const int fd = ::open(path, O_RDONLY);
  if (fd < 0) {
    return StorageResult::kNotFound;
  }
  std::size_t done = 0U;
  for (;;) {
    if (done == capacity) {
      std::uint8_t extra = 0U;
      const ssize_t more = ::read(fd, &extra, 1U);
      (void)::close(fd);
      return more == 0 ? (*size = done, StorageResult::kOk) : StorageResult::kError;
    }
    const ssize_t n = ::read(fd, buffer + done, capacity - done);
    if (n < 0) {
      (void)::close(fd);
      return StorageResult::kError;
    }
    if (n == 0) {
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  (void)::close(fd);
  *size = done;
  return StorageResult::kOk;
}

}  // namespace

bool posix_directory_storage(const char* directory, PosixDirectory* state, PatchStorage* table) noexcept {
  struct stat info {};
  if (directory == nullptr || state == nullptr || table == nullptr ||
      std::strlen(directory) >= sizeof state->path || ::stat(directory, &info) != 0 || !S_ISDIR(info.st_mode)) {
    return false;
  }
  std::memcpy(state->path, directory, std::strlen(directory) + 1U);
  *table = PatchStorage{state, &write_file, &read_file};
  return true;
}

}  // namespace ccmap::platform
