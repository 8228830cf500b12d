// Instructions per registration call (docs/performance.md, "Registration: what it costs"): a
// CADRE stack fed the flight cycle's frames (tests/support/flight_cycle.hpp: 850 x 650 stereo
// frames, 552,500 points, 2 % NaN, 6 % beyond every IV-G range), each frame after the first
// registered before it is folded in, as a rover would. Regions (tests/support/icount_marker.hpp):
//   1  register_frame_sensor (sensor-frame points and the pose)
//   2  register_frame (the same frame's map-frame points and the sensor origin)
// On other targets the markers are empty and the program checks that every call answers kOk
// and that every correction claims the height (the flight cycle's ground fixes it).
//
//   icount_registration_example [frames [width_px height_px]]   default: 3 850 650
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "ccmap/registration/registration.hpp"
#include "support/count_arg.hpp"
#include "support/flight_cycle.hpp"
#include "support/icount_marker.hpp"

int main(int argc, char** argv) {
  int frames = 3, width_px = ccmap::test::kCycleWidthPx, height_px = ccmap::test::kCycleHeightPx;
  if ((argc != 1 && argc != 2 && argc != 4) || (argc >= 2 && !ccmap::test::parse_count(argv[1], 1000, &frames)) ||
      (argc == 4 && (!ccmap::test::parse_count(argv[2], 4000, &width_px) ||
                     !ccmap::test::parse_count(argv[3], 4000, &height_px)))) {
    std::fprintf(stderr, "usage: icount_registration_example [frames [width_px height_px]]\n");
    return 2;
  }
  // On the heap, as the timing test and icount_stack_example (the counts are of the same code).
  const auto map = std::make_unique<ccmap::Stack<ccmap::CadreConfig>>();
  if (map->init(ccmap::default_stack_params(0.04F)) != ccmap::Status::kOk) {
    std::fprintf(stderr, "icount_registration_example: init failed\n");
    return 1;
  }
  const ccmap::RegistrationParams params = ccmap::default_registration_params();
  unsigned iterations = 0U;
  double seconds = 0.0;  // wall time of the calls (printed on the host only)
  for (int k = 0; k <= frames; ++k) {
    const ccmap::test::CyclePose pose = ccmap::test::cycle_pose(k);
    const ccmap::test::CadreFrame f = ccmap::test::cycle_frame(k, width_px, height_px);
    if (map->move_to(pose.x, pose.y) != ccmap::Status::kOk) {
      std::fprintf(stderr, "icount_registration_example: move %d refused\n", k);
      return 1;
    }
    if (k > 0) {
      const auto t0 = std::chrono::steady_clock::now();
      ccmap::test::icount_begin<1>();
      const ccmap::RegistrationResult a = ccmap::register_frame_sensor(*map, f.sensor_points.data(), f.sensor_points.size(), f.pose, params);
      ccmap::test::icount_end<1>();
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      ccmap::test::icount_begin<2>();
      const ccmap::RegistrationResult b = ccmap::register_frame(*map, f.map_points.data(), f.map_points.size(), f.sensor_origin, params);
      ccmap::test::icount_end<2>();
      if (a.status != ccmap::Status::kOk || b.status != ccmap::Status::kOk || !a.observable[ccmap::kAxisZ] ||
          !b.observable[ccmap::kAxisZ]) {
        std::fprintf(stderr, "icount_registration_example: frame %d: %s / %s\n", k, ccmap::to_string(a.status),
                     ccmap::to_string(b.status));
        return 1;
      }
      iterations += a.iterations;
    }
    if (map->update_frame_sensor(f.sensor_points.data(), f.sensor_points.size(), f.pose, nullptr) != ccmap::Status::kOk) {
      std::fprintf(stderr, "icount_registration_example: update %d refused\n", k);
      return 1;
    }
  }
  std::printf("icount_registration_example: %d registrations of %d x %d points, %u iterations\n", frames, width_px,
              height_px, iterations);
#if !defined(__aarch64__)
  // Host only: a time varies from run to run, and so would the instructions that print it,
  // which the counting runs (aarch64 under QEMU) must see equal twice.
  std::printf("host: %.3f ms per register_frame_sensor\n", frames > 0 ? 1000.0 * seconds / frames : 0.0);
#endif
  return 0;
}
