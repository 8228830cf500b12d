// The integration pattern for instruction budgets: bracket the cycle, and nothing else, with
// icount markers (tests/support/icount_marker.hpp). CADRE frames (tests/support/cadre_frames.hpp,
// the sequence of the timing test) update a Stack<CadreConfig>; only the update_frame calls lie
// in region 1, frame generation does not. Under qemu-aarch64 with the plugin
// (ccmap_add_icount_test in tests/icount/CMakeLists.txt) the ctest prints instructions and
// float instructions per point; on other targets the markers are empty and this program just
// checks that the updates succeed.
//
//   icount_stack_example [frames width_px height_px [map|sensor [full|paper]]]
//   default: 3 frames of 80 x 50 points (10 850 650: the timing test's ten full frames,
//   docs/performance.md section 1.1); `sensor` folds the same frames in the sensor frame with
//   update_frame_sensor and their pose; `paper` maps into Stack<PaperCell<CadreConfig>> (the
//   paper's 9-float CCM cell) instead of Stack<CadreConfig>
//
// The markers bracket the call, so the call's argument set-up (a handful of instructions) may
// be counted too; against thousands of points per frame that is noise.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>

#include "ccmap/map/stack.hpp"
#include "support/cadre_frames.hpp"
#include "support/count_arg.hpp"
#include "support/icount_marker.hpp"

namespace {
template <typename Config>
int run(int frames, int width_px, int height_px, bool sensor_frame) {
  const std::size_t points = static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px);
  // On the heap (585 KB), as in tests/map/timing_test.cpp, so that both count the same code: a
  // count is of a binary, and where the stack lives can change the code emitted for it.
  const auto stack = std::make_unique<ccmap::Stack<Config>>();
  if (stack->init(ccmap::default_stack_params(0.04F)) != ccmap::Status::kOk) {
    std::fprintf(stderr, "icount_stack_example: Stack<CadreConfig> init failed\n");
    return 1;
  }
  for (int k = 0; k < frames; ++k) {
    const ccmap::test::CadreFrame frame =
        ccmap::test::make_cadre_frame(ccmap::test::cadre_sequence_spec(k, width_px, height_px));
    ccmap::FrameCounters counters{};
    ccmap::test::icount_begin<1>();
    const ccmap::Status status =
        sensor_frame
            ? stack->update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, &counters)
            : stack->update_frame(frame.map_points.data(), frame.map_points.size(), frame.sensor_origin, &counters);
    ccmap::test::icount_end<1>();
    // Every point folded in or judged by the outlier gate (a rock's edge in a cell): none refused.
    const std::uint32_t judged =
        counters.gated_finer + counters.gated_occluded + counters.gated_held + counters.gated_pool_full;
    if (status != ccmap::Status::kOk || counters.used + judged != points) {
      std::fprintf(stderr, "icount_stack_example: frame %d: status %d, %u of %zu points used, %u judged by the gate\n",
                   k, static_cast<int>(status), counters.used, points, judged);
      return 1;
    }
  }
  std::printf("icount_stack_example: %d %s-frame frames of %zu points updated (region 1), %s CCM cells\n", frames,
              sensor_frame ? "sensor" : "map", points,
              ccmap::Stack<Config>::kCcmCellKind == ccmap::CcmCellKind::kFull ? "full" : "paper");
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  using ccmap::test::parse_count;
  int frames = 3;
  int width_px = 80;
  int height_px = 50;
  const bool sensor_frame = argc >= 5 && std::strcmp(argv[4], "sensor") == 0;
  const bool paper_cell = argc >= 6 && std::strcmp(argv[5], "paper") == 0;
  const bool good_path = argc < 5 || sensor_frame || std::strcmp(argv[4], "map") == 0;
  const bool good_cell = argc < 6 || paper_cell || std::strcmp(argv[5], "full") == 0;
  if (argc != 1 && (argc < 4 || argc > 6 || !good_path || !good_cell || !parse_count(argv[1], 1000, &frames) ||
                    !parse_count(argv[2], 4000, &width_px) || !parse_count(argv[3], 4000, &height_px))) {
    std::fprintf(stderr,
                 "usage: icount_stack_example [frames (1..1000) width_px height_px (1..4000) [map|sensor [full|paper]]]\n");
    return 2;
  }
  return paper_cell ? run<ccmap::PaperCell<ccmap::CadreConfig>>(frames, width_px, height_px, sensor_frame)
                    : run<ccmap::CadreConfig>(frames, width_px, height_px, sensor_frame);
}
