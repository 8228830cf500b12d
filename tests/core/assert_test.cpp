#include <gtest/gtest.h>

#include <cstring>

#include "ccmap/core/assert.hpp"
#include "ccmap/core/status.hpp"
#include "ccmap/platform/platform.hpp"

namespace ccmap {
namespace {

int g_recorded = 0;
const char* g_expression = nullptr;

void record(const char*, int, const char* expression) {
  ++g_recorded;
  g_expression = expression;
}

int guarded_divide(int a, int b) {
  CCMAP_ASSERT_OR_RETURN(b != 0, 0);
  return a / b;
}

TEST(Assert, HookRecordsAndOrReturnGivesSafeValue) {
  g_recorded = 0;
  const AssertHook previous = set_assert_hook(&record);
  const std::uint32_t before = assert_failure_count();
  EXPECT_EQ(guarded_divide(6, 3), 2);
  EXPECT_EQ(g_recorded, 0);
  EXPECT_EQ(guarded_divide(6, 0), 0) << "the _OR_RETURN form must return the safe value";
  EXPECT_EQ(g_recorded, 1) << "the installed hook must see the failure";
  EXPECT_STREQ(g_expression, "b != 0");
  EXPECT_EQ(assert_failure_count(), before + 1U);
  EXPECT_EQ(set_assert_hook(previous), &record);
}

TEST(Assert, DefaultHookGoesToPlatformFaultAndReturns) {
  set_assert_hook(nullptr);
  testing::internal::CaptureStderr();
  EXPECT_EQ(guarded_divide(1, 0), 0);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("b != 0"), std::string::npos) << "posix fault should log the expression: " << err;
}

TEST(Status, EveryStatusHasAName) {
  for (int i = 0; i <= static_cast<int>(Status::kMisaligned); ++i) {
    const char* name = to_string(static_cast<Status>(i));
    ASSERT_NE(name, nullptr);
    EXPECT_STRNE(name, "invalid_status") << "status " << i << " has no name";
  }
  EXPECT_STREQ(to_string(static_cast<Status>(200)), "invalid_status");
}

TEST(Platform, MonotonicClockNeverGoesBackwards) {
  std::uint64_t last = platform::monotonic_ns();
  for (int i = 0; i < 10000; ++i) {
    const std::uint64_t now = platform::monotonic_ns();
    ASSERT_GE(now, last);
    last = now;
  }
  EXPECT_STREQ(platform::name(), "posix");
}

}  // namespace
}  // namespace ccmap
