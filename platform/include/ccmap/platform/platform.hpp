// ccmap platform interface: the only OS services the core uses.
//
// One interface, one implementation library per platform, chosen at link time by the build
// (CCMAP_PLATFORM=posix|baremetal). No virtual calls, no registration at run time.
//
// Contract for every implementation:
//  - every function is callable from any context the map is updated from (no allocation,
//    no exceptions, bounded time);
//  - monotonic_ns() never goes backwards;
//  - log_write() and fault() may drop messages, but must return.
#pragma once

#include <cstdint>

namespace ccmap::platform {

enum class LogLevel : std::uint8_t { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3 };

/// Monotonic time in nanoseconds since an arbitrary epoch.
[[nodiscard]] std::uint64_t monotonic_ns() noexcept;

/// CPU time consumed by the calling thread, nanoseconds since an arbitrary epoch; never goes
/// backwards within a thread. Unlike monotonic_ns() it does not count time the thread was
/// preempted or waiting, so a cycle budget measured with it is not charged for other load.
/// Without threads or a CPU-time clock (bare metal) it equals monotonic_ns().
[[nodiscard]] std::uint64_t thread_cpu_ns() noexcept;

/// Writes one log line (no trailing newline needed). `message` may be nullptr (ignored).
void log_write(LogLevel level, const char* message) noexcept;

/// Reports a violated contract inside the core. Must return: the core then returns a safe
/// value (see CCMAP_ASSERT_OR_RETURN). A flight integration forwards this to its FDIR.
void fault(const char* file, int line, const char* expression) noexcept;

/// Name of the linked implementation ("posix", "baremetal").
[[nodiscard]] const char* name() noexcept;

}  // namespace ccmap::platform
