// The board's implementation of the three integrator hooks (platform/boards/<board>/hooks.cpp),
// through the core's platform interface, as the core calls them.
#include <cstdint>
#include <cstring>

#include "board.h"
#include "ccmap/core/assert.hpp"
#include "ccmap/platform/platform.hpp"
#include "harness.hpp"

BM_CASE(board, platform_is_baremetal) {
  BM_CHECK(std::strcmp(ccmap::platform::name(), "baremetal") == 0, "the image does not link platform/baremetal");
}

BM_CASE(board, clock_advances_with_instructions) {
  const std::uint64_t t0 = ccmap::platform::monotonic_ns();
  std::uint32_t counter = 100000U;  // 200,000 instructions: 200 us of virtual time
  __asm__ volatile(
      "1: subs %0, %0, #1\n"
      "   bne 1b\n"
      : "+r"(counter)
      :
      : "cc");
  const std::uint64_t t1 = ccmap::platform::monotonic_ns();
  BM_CHECK(t1 >= t0, "monotonic_ns went backwards");
  // 1 ns per instruction under -icount shift=0, 40 ns resolution, a few instructions around.
  BM_CHECK(t1 - t0 >= 200000U - 40U && t1 - t0 <= 200000U + 400U, "monotonic_ns does not count virtual nanoseconds");
}

BM_CASE(board, fault_hook_reports_and_returns) {
  const std::uint32_t board_faults = ccmap_board_fault_count();
  const std::uint32_t core_faults = ccmap::assert_failure_count();
  // What CCMAP_ASSERT_OR_RETURN does on a violated contract; the hook must return.
  ccmap::detail::report_assert_failure("board_cases.cpp", 42, "deliberate contract violation (expected in this log)");
  BM_CHECK_EQ(ccmap_board_fault_count(), board_faults + 1U, "ccmap_bm_fault was not called once");
  BM_CHECK_EQ(ccmap::assert_failure_count(), core_faults + 1U, "the core did not count the violation");
}

BM_CASE(board, log_hook_writes_a_line) {
  const std::uint32_t lines = ccmap_board_log_count();
  ccmap::platform::log_write(ccmap::platform::LogLevel::kInfo, "a log line from the core's platform interface");
  ccmap::platform::log_write(ccmap::platform::LogLevel::kError, nullptr);  // ignored, must not crash
  BM_CHECK_EQ(ccmap_board_log_count(), lines + 2U, "ccmap_bm_log_write was not called for each line");
}
