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
//    emulator's cost model (float instructions are soft-float calls of ~4-6 ns, 64-bit vector
//    lanes cost several times a 32-bit one). The cycle of 61 M instructions before the outlier
//    gate took 67 ms on the development machine and 95 ms on the CI machine (1.1 and 1.55 ns per
//    instruction); with the gate, 80.8 M instructions and more float, 118 ms on the development
//    machine (1.46 ns). The Snapdragon 820 at 2.15 GHz and one instruction per cycle, the
//    budget's own assumption, takes 0.47 ns: for the cycle as it flies the emulator is 3.1x
//    (development machine) to ~4.4x (CI, estimated) slower than the target. The assertion
//    divides by 3, less than that: median emulator CPU / 3 < 80 ms, i.e. the cycle would fit the
//    budget on a target only 3x faster than the emulator (docs/performance.md section 5).
//  The deterministic form of the budget is the instruction count of the same cycle
//  (tests/map/cycle_icount.cpp, label timing too): at most half of 80 ms x 2.15 GHz x 1 IPC.
//
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
/// Emulator time per target time assumed by the assertion under an emulator (see above).
constexpr double kEmulatorSlowdown = 3.0;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

TEST(Timing, FlightCycleMedianUnderTheEightyMillisecondBudget) {
  const char* const emulator = std::getenv("CCMAP_EMULATOR");
  const bool emulated = emulator != nullptr && emulator[0] != '\0';
  const double slowdown = emulated ? kEmulatorSlowdown : 1.0;
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
    std::printf("[ timing ] emulated: the assertion takes the target as %.0fx faster than the emulator: %.2f ms < %.0f ms\n",
                slowdown, cpu / slowdown, kBudgetMs);
  }
  EXPECT_LT(cpu / slowdown, kBudgetMs) << "median flight cycle " << cpu << " ms of CPU"
                                       << (emulated ? " (emulated, divided by the emulator allowance)" : "")
                                       << " exceeds the 80 ms budget";
}

}  // namespace
}  // namespace ccmap
