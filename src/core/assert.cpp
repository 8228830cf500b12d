#include "ccmap/core/assert.hpp"

#include <atomic>

#include "ccmap/platform/platform.hpp"

namespace ccmap {
namespace {
std::atomic<AssertHook> g_hook{nullptr};
std::atomic<std::uint32_t> g_failures{0U};
}  // namespace

AssertHook set_assert_hook(AssertHook hook) noexcept { return g_hook.exchange(hook); }

std::uint32_t assert_failure_count() noexcept { return g_failures.load(); }

namespace detail {
void report_assert_failure(const char* file, int line, const char* expression) noexcept {
  std::uint32_t count = g_failures.load();
  while (count != UINT32_MAX && !g_failures.compare_exchange_weak(count, count + 1U)) {
  }
  const AssertHook hook = g_hook.load();
  if (hook != nullptr) {
    hook(file, line, expression);
  } else {
    platform::fault(file, line, expression);
  }
}
}  // namespace detail

}  // namespace ccmap
