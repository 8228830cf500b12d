// The 80 ms budget of the flight cycle (paper: 850 x 650 px stereo at 80 ms on a Snapdragon 820),
// measured as a rover runs it: per frame move_to the new pose, update_frame_sensor with a CADRE
// frame in the sensor frame (2 % NaN, 6 % beyond every IV-G range), and the planner's questions:
// the corridor footprint and the 2 m path (tests/support/flight_cycle.hpp). Ten cycles, one attempt.
//
// What is asserted: the median thread CPU time of the ten cycles (platform::thread_cpu_ns: time
// the other core's load and preemption do not inflate), wall time printed beside it.
//  - Native (host, or an aarch64 board): median CPU < 80 ms, the budget itself.
//  - Under an emulator (ctest sets CCMAP_EMULATOR for the cross build, tests/map/CMakeLists.txt):
//    the time is the emulator's on its x86-64 host, not the target's, and it follows the
//    emulator's cost model (a float instruction is a soft-float call of several ns, an integer
//    one a fraction of a ns), so no allowance turns it into the target's time: it is printed,
//    not asserted. The 80 ms budget is asserted there in its deterministic form, the aarch64
//    instruction count of the same cycle (ctest ccmap_timing_flight_cycle_instructions,
//    tests/map/cycle_icount.cpp, label timing too), which also prints the emulator's CPU time
//    per instruction measured in that run.
// Label `timing`: tools/test runs it alone after every other test (RUN_SERIAL), once.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "ccmap/platform/platform.hpp"
#include "support/flight_cycle.hpp"

namespace ccmap {
namespace {

constexpr int kCycles = 10;
constexpr double kBudgetMs = 80.0;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

TEST(Timing, FlightCycleMedianUnderTheEightyMillisecondBudget) {
  const char* const emulator = std::getenv("CCMAP_EMULATOR");
  const bool emulated = emulator != nullptr && emulator[0] != '\0';
  auto stack = std::make_unique<Stack<CadreConfig>>();
  ASSERT_EQ(stack->init(default_stack_params(0.04F)), Status::kOk);
  std::vector<double> cpu_ms;
  std::vector<double> wall_ms;
  for (int k = 0; k < kCycles; ++k) {
    // Frames are generated outside the timed region (one at a time: 13 MB each).
    const test::CadreFrame frame = test::cycle_frame(k);
    const test::CyclePose pose = test::cycle_pose(k);
    const std::uint64_t cpu0 = platform::thread_cpu_ns();
    const std::uint64_t wall0 = platform::monotonic_ns();
    const test::CycleOutcome outcome = test::run_cycle(*stack, pose, frame);
    const std::uint64_t wall1 = platform::monotonic_ns();
    const std::uint64_t cpu1 = platform::thread_cpu_ns();
    ASSERT_TRUE(test::cycle_ok(outcome, frame.sensor_points.size()))
        << "cycle " << k << ": used " << outcome.counters.used << ", non-finite " << outcome.counters.rejected_non_finite
        << ", too noisy " << outcome.counters.too_noisy << ", corridor unknown share " << outcome.corridor.unknown_share
        << ", path poses " << outcome.path.samples;
    cpu_ms.push_back(static_cast<double>(cpu1 - cpu0) * 1e-6);
    wall_ms.push_back(static_cast<double>(wall1 - wall0) * 1e-6);
  }
  const double cpu = median(cpu_ms);
  const double wall = median(wall_ms);
  std::printf("[ timing ] flight cycle (move, sensor-frame update of 552,500 points, corridor footprint, 2 m path), %s%s%s: "
              "median CPU %.2f ms (max %.2f), median wall %.2f ms (max %.2f) over %d cycles (budget %.0f ms)\n",
              platform::name(), emulated ? ", under " : "", emulated ? emulator : "", cpu,
              *std::max_element(cpu_ms.begin(), cpu_ms.end()), wall, *std::max_element(wall_ms.begin(), wall_ms.end()),
              kCycles, kBudgetMs);
  if (emulated) {
    std::printf("[ timing ] emulated: the emulator's time, printed only; the budget is asserted as the cycle's "
                "aarch64 instruction count (ctest ccmap_timing_flight_cycle_instructions)\n");
    return;
  }
  EXPECT_LT(cpu, kBudgetMs) << "median flight cycle " << cpu << " ms of CPU exceeds the 80 ms budget";
}

}  // namespace
}  // namespace ccmap
