// POSIX implementation of the ccmap platform interface.
#include "ccmap/platform/platform.hpp"

#include <cstdio>
#include <ctime>

namespace ccmap::platform {

std::uint64_t monotonic_ns() noexcept {
  timespec ts{};
  if (clock_gettime(CLOCK_MONOTONIC, &ts) != 0) {
    return 0U;
  }
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ULL + static_cast<std::uint64_t>(ts.tv_nsec);
}

void log_write(LogLevel level, const char* message) noexcept {
  if (message == nullptr) {
    return;
  }
  static const char* const kNames[] = {"debug", "info", "warning", "error"};
  const auto index = static_cast<unsigned>(level);
  const char* level_name = index < 4U ? kNames[index] : "?";
  // Best effort: a failed write to stderr has nowhere else to be reported.
  (void)std::fprintf(stderr, "ccmap[%s] %s\n", level_name, message);
}

void fault(const char* file, int line, const char* expression) noexcept {
  (void)std::fprintf(stderr, "ccmap[fault] %s:%d: %s\n", file != nullptr ? file : "?", line,
               expression != nullptr ? expression : "?");
}

const char* name() noexcept { return "posix"; }

}  // namespace ccmap::platform
