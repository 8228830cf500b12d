// Bare-metal implementation of the ccmap platform interface.
//
// The integrator supplies these C functions (for example from the flight software's
// time service, telemetry log and FDIR); the link fails if one is missing:
//   uint64_t ccmap_bm_monotonic_ns(void);
//   void     ccmap_bm_log_write(int level, const char* message);
//   void     ccmap_bm_fault(const char* file, int line, const char* expression);
#include "ccmap/platform/platform.hpp"

extern "C" {
std::uint64_t ccmap_bm_monotonic_ns(void);
void ccmap_bm_log_write(int level, const char* message);
void ccmap_bm_fault(const char* file, int line, const char* expression);
}

namespace ccmap::platform {

std::uint64_t monotonic_ns() noexcept { return ccmap_bm_monotonic_ns(); }

// One thread of execution, no CPU-time clock: the monotonic clock (interrupts included).
std::uint64_t thread_cpu_ns() noexcept { return ccmap_bm_monotonic_ns(); }

void log_write(LogLevel level, const char* message) noexcept {
  ccmap_bm_log_write(static_cast<int>(level), message);
}

void fault(const char* file, int line, const char* expression) noexcept {
  ccmap_bm_fault(file, line, expression);
}

const char* name() noexcept { return "baremetal"; }

}  // namespace ccmap::platform
