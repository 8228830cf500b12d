// Instruction counts of the outlier gate (docs/performance.md, "Outlier gate: what it costs"): two CADRE stacks
// fed the same frames (tests/support/cadre_frames.hpp, 0.3 m apart), one with the gate at its
// CADRE default, one with it off (outlier_gate_sigma = 0: the paper's update). Each frame is
// given once in the sensor frame and once, from the next place, in the map frame. Regions
// (tests/support/icount_marker.hpp):
//   1  update_frame_sensor, gate on          2  update_frame_sensor, gate off
//   3  update_frame (map frame), gate on     4  update_frame (map frame), gate off
// On other targets the markers are empty and the program checks that every call succeeds and
// that every point is folded in or judged by the gate (none refused).
//
//   icount_gate_example [frames width_px height_px]   default: 2 80 50
//   (5 850 650: the figures of docs/performance.md)
#include <cstdint>
#include <cstdio>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "support/cadre_frames.hpp"
#include "support/count_arg.hpp"
#include "support/icount_marker.hpp"

namespace {

using Map = ccmap::Stack<ccmap::CadreConfig>;

/// Points folded in or judged by the gate: every point of a CADRE frame (all lie in the stack).
std::uint64_t accounted(const ccmap::FrameCounters& c) {
  return std::uint64_t{c.used} + c.gated_finer + c.gated_occluded + c.gated_held + c.gated_pool_full;
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 2, width_px = 80, height_px = 50;
  if (argc != 1 && (argc != 4 || !ccmap::test::parse_count(argv[1], 1000, &frames) ||
                    !ccmap::test::parse_count(argv[2], 4000, &width_px) ||
                    !ccmap::test::parse_count(argv[3], 4000, &height_px))) {
    std::fprintf(stderr, "usage: icount_gate_example [frames width_px height_px]\n");
    return 2;
  }
  // On the heap, as the timing test and icount_stack_example (the counts are of the same code).
  const auto on = std::make_unique<Map>();
  const auto off = std::make_unique<Map>();
  ccmap::StackParams params = ccmap::default_stack_params(0.04F);
  if (!(params.outlier_gate_sigma > 0.0F) || on->init(params) != ccmap::Status::kOk) {
    std::fprintf(stderr, "icount_gate_example: the CADRE default should have the gate on\n");
    return 1;
  }
  params.outlier_gate_sigma = 0.0F;
  if (off->init(params) != ccmap::Status::kOk) {
    std::fprintf(stderr, "icount_gate_example: init failed\n");
    return 1;
  }
  std::uint64_t gated = 0;
  for (int k = 0; k < frames; ++k) {
    for (const bool sensor_frame : {true, false}) {
      ccmap::test::CadreFrameSpec spec;
      spec.width_px = width_px;
      spec.height_px = height_px;
      spec.sensor_x = 0.3F * static_cast<float>(2 * k + (sensor_frame ? 0 : 1));
      spec.seed = static_cast<std::uint32_t>(2 * k + (sensor_frame ? 0 : 1)) + 1U;
      const ccmap::test::CadreFrame f = ccmap::test::make_cadre_frame(spec);
      const std::size_t n = f.map_points.size();
      if (on->move_to(spec.sensor_x, spec.sensor_y) != ccmap::Status::kOk ||
          off->move_to(spec.sensor_x, spec.sensor_y) != ccmap::Status::kOk) {
        std::fprintf(stderr, "icount_gate_example: move %d refused\n", k);
        return 1;
      }
      ccmap::FrameCounters a{}, b{};
      ccmap::Status sa = ccmap::Status::kOk, sb = ccmap::Status::kOk;
      if (sensor_frame) {
        ccmap::test::icount_begin<1>();
        sa = on->update_frame_sensor(f.sensor_points.data(), n, f.pose, &a);
        ccmap::test::icount_end<1>();
        ccmap::test::icount_begin<2>();
        sb = off->update_frame_sensor(f.sensor_points.data(), n, f.pose, &b);
        ccmap::test::icount_end<2>();
      } else {
        ccmap::test::icount_begin<3>();
        sa = on->update_frame(f.map_points.data(), n, f.sensor_origin, &a);
        ccmap::test::icount_end<3>();
        ccmap::test::icount_begin<4>();
        sb = off->update_frame(f.map_points.data(), n, f.sensor_origin, &b);
        ccmap::test::icount_end<4>();
      }
      if (sa != ccmap::Status::kOk || sb != ccmap::Status::kOk || accounted(a) != n || b.used != n) {
        std::fprintf(stderr, "icount_gate_example: frame %d: %llu (gate on) and %u (off) of %zu points\n", k,
                     static_cast<unsigned long long>(accounted(a)), b.used, n);
        return 1;
      }
      gated += accounted(a) - a.used;
    }
  }
  std::printf("icount_gate_example: %d sensor and %d map frames of %d x %d points, %llu judged by the gate\n", frames,
              frames, width_px, height_px, static_cast<unsigned long long>(gated));
  return 0;
}
