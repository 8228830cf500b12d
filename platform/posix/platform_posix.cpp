// POSIX implementation of the ccmap platform interface.
#include "ccmap/platform/platform.hpp"

#include <cstdio>
#include <ctime>

namespace ccmap::platform {

namespace {
std::uint64_t clock_ns(clockid_t clock) noexcept {
  timespec ts{};
  if (clock_gettime(clock, &ts) != 0) {
    return 0U;
  }
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ULL + static_cast<std::uint64_t>(ts.tv_nsec);
}
}  // namespace

std::uint64_t monotonic_ns() noexcept { return clock_ns(CLOCK_MONOTONIC); }

std::uint64_t thread_cpu_ns() noexcept { return clock_ns(CLOCK_THREAD_CPUTIME_ID); }

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
