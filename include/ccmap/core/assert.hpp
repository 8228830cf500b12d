// One assert macro, one hook.
//
// A violated contract inside the core is reported to a replaceable hook and then the
// function returns a safe value (the _OR_RETURN form): a release build whose hook returns
// stays safe. The default hook forwards to ccmap::platform::fault(). Tests install a
// recording hook and check that the assert fired.
#pragma once

#include <cstdint>

namespace ccmap {

/// Called with the source location and the failed expression. Must return.
using AssertHook = void (*)(const char* file, int line, const char* expression);

/// Installs `hook`; nullptr restores the default (platform::fault). Returns the previous hook.
AssertHook set_assert_hook(AssertHook hook) noexcept;

/// Number of contract violations reported since start (saturates at UINT32_MAX).
[[nodiscard]] std::uint32_t assert_failure_count() noexcept;

namespace detail {
void report_assert_failure(const char* file, int line, const char* expression) noexcept;
}  // namespace detail

}  // namespace ccmap

/// Reports the failure and continues.
#define CCMAP_ASSERT(condition)                                                   \
  do {                                                                            \
    if (!(condition)) {                                                           \
      ::ccmap::detail::report_assert_failure(__FILE__, __LINE__, #condition);     \
    }                                                                             \
  } while (false)

/// Reports the failure and returns `safe_value` from the enclosing function.
#define CCMAP_ASSERT_OR_RETURN(condition, safe_value)                             \
  do {                                                                            \
    if (!(condition)) {                                                           \
      ::ccmap::detail::report_assert_failure(__FILE__, __LINE__, #condition);     \
      return safe_value;                                                          \
    }                                                                             \
  } while (false)
