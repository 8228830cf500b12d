// The deterministic budget of the flight cycle: the aarch64 instructions one cycle executes,
// counted under QEMU by the project's plugin (tools/qemu-icount) between markers around the cycle
// alone (frame generation is outside them). The same binary counts the same instructions: the
// ctest cannot flake. Registered in tests/map/CMakeLists.txt with the limits (label timing):
//   region 1: every cycle (move_to + update_frame_sensor + corridor footprint + 2 m path)
//   region 2: the update_frame_sensor calls alone (for the per-point figures)
//   region 3: the update_frame calls of the same points in the map frame (the 1.25x ratio)
//   region 4: the cycle's corridor footprint query, on the sensor-frame stack after its update
//   region 5: the cycle's 2 m path query, likewise (regions 4 and 5 are the queries of region 1:
//             the sensor-frame stack holds the same map as the cycle's)
// On other targets the markers are empty and the program only checks the cycles.
//
//   ccmap_cycle_icount [cycles [full|paper]]   default 3 (full 850 x 650 frames), full CCM cells;
//   `paper` counts the same cycles with Stack<PaperCell<CadreConfig>> (the paper's 9-float cell)
// The same cycles with free space from the viewshed table: ccmap_cycle_table_icount
// (cycle_table_icount.cpp; a program of its own, so that this one's code stays as it is).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "ccmap/platform/platform.hpp"
#include "support/flight_cycle.hpp"
#include "support/icount_marker.hpp"

namespace {

template <std::uint32_t kRegion, typename Fn>
auto counted(Fn&& fn) {
  ccmap::test::icount_begin<kRegion>();
  auto result = fn();
  ccmap::test::icount_end<kRegion>();
  return result;
}

#ifdef CCMAP_CYCLE_TABLE
int table_stride = 8;  ///< one point in table_stride feeds the viewshed table (cycle_table_icount.cpp)
#endif

template <typename Config>
int run(int cycles) {
  // Heap, as the timing test: a count is of a binary, and the stack's placement changes code.
  const auto stack = std::make_unique<ccmap::Stack<Config>>();
  const auto sensor_only = std::make_unique<ccmap::Stack<Config>>();
  const auto map_only = std::make_unique<ccmap::Stack<Config>>();
  ccmap::StackParams params = ccmap::default_stack_params(0.04F);
#ifdef CCMAP_CYCLE_TABLE
  params.free_space_rays = ccmap::detail::free_space_table_rays(table_stride);
#endif
  for (auto* s : {stack.get(), sensor_only.get(), map_only.get()}) {
    if (s->init(params) != ccmap::Status::kOk) {
      std::fprintf(stderr, "ccmap_cycle_icount: init failed\n");
      return 1;
    }
  }
  std::uint64_t cycle_cpu_ns = 0U;
  for (int k = 0; k < cycles; ++k) {
    const ccmap::test::CadreFrame frame = ccmap::test::cycle_frame(k);
    const ccmap::test::CyclePose pose = ccmap::test::cycle_pose(k);
    const std::uint64_t cpu0 = ccmap::platform::thread_cpu_ns();
    const ccmap::test::CycleOutcome outcome =
        counted<1>([&] { return ccmap::test::run_cycle(*stack, pose, frame); });
    cycle_cpu_ns += ccmap::platform::thread_cpu_ns() - cpu0;
    if (!ccmap::test::cycle_ok(outcome, frame.sensor_points.size())) {
      std::fprintf(stderr, "ccmap_cycle_icount: cycle %d did not do its work\n", k);
      return 1;
    }
    // The update alone, sensor frame and map frame, on stacks that follow the same drive.
    (void)sensor_only->move_to(pose.x, pose.y);
    (void)map_only->move_to(pose.x, pose.y);
    const ccmap::Status sensor_status = counted<2>([&] {
      return sensor_only->update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose,
                                              nullptr);
    });
    const ccmap::Status map_status = counted<3>([&] {
      return map_only->update_frame(frame.map_points.data(), frame.map_points.size(), frame.sensor_origin, nullptr);
    });
    const ccmap::FootprintResult corridor =
        counted<4>([&] { return ccmap::query_footprint(*sensor_only, ccmap::test::corridor_footprint(pose)); });
    const ccmap::PathResult path = counted<5>([&] { return ccmap::test::cycle_path(*sensor_only, pose); });
    if (corridor.status != outcome.corridor.status || corridor.unknown_share != outcome.corridor.unknown_share ||
        path.samples != outcome.path.samples || path.first_hazard_m != outcome.path.first_hazard_m) {
      std::fprintf(stderr, "ccmap_cycle_icount: the queries' stack differs from the cycle's in cycle %d\n", k);
      return 1;
    }
    if (sensor_status != ccmap::Status::kOk || map_status != ccmap::Status::kOk) {
      std::fprintf(stderr, "ccmap_cycle_icount: update refused in cycle %d\n", k);
      return 1;
    }
  }
  // The cycles' thread CPU time (with the counting plugin under QEMU: the emulator's time), for
  // the icount runner's time per instruction (cmake/ccmap_icount_run.cmake).
  std::printf("[ icount-time ] region=1 cpu_ns=%llu\n", static_cast<unsigned long long>(cycle_cpu_ns));
  std::printf("ccmap_cycle_icount: %d cycles of %d x %d points, %s CCM cells\n", cycles, ccmap::test::kCycleWidthPx,
              ccmap::test::kCycleHeightPx,
              ccmap::Stack<Config>::kCcmCellKind == ccmap::CcmCellKind::kFull ? "full" : "paper");
  return 0;
}

}  // namespace

#ifndef CCMAP_CYCLE_TABLE
int main(int argc, char** argv) {
  const int cycles = argc > 1 ? std::atoi(argv[1]) : 3;
  const bool paper = argc > 2 && std::strcmp(argv[2], "paper") == 0;
  if (cycles < 1 || cycles > 100 || argc > 3 || (argc == 3 && !paper && std::strcmp(argv[2], "full") != 0)) {
    std::fprintf(stderr, "usage: ccmap_cycle_icount [cycles 1..100 [full|paper]]\n");
    return 2;
  }
  return paper ? run<ccmap::PaperCell<ccmap::CadreConfig>>(cycles) : run<ccmap::CadreConfig>(cycles);
}
#endif
