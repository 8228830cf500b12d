// aarch64 instructions of the planner queries (docs/performance.md): a Stack<CadreConfig> mapped
// from synthetic CADRE frames (tests/support/cadre_frames.hpp), then each query bracketed by its
// own icount region (tests/support/icount_marker.hpp), `calls` times:
//   region 1  query_footprint, the 0.6 m x 0.4 m rover body 0.9 m ahead
//   region 2  query_footprint, a 2 m x 1 m body at 37 deg (the flight-cycle timing test's size)
//   region 3  query_path, 2 m ahead, the body every 5 cm (41 footprints)
//   region 4  fill_costmap, 5 m x 5 m at 4 cm around the rover
//   region 5  fill_costmap, the same with 0.3 m inflation
//   region 6  move_to(x, y) of one finest cell and back (two calls per interval)
//   region 7  move_to(x, y, sigma) of one finest cell and back (two calls per interval)
// Under qemu-aarch64 with the plugin (tests/icount/CMakeLists.txt) the ctest prints instructions
// and float instructions per call; elsewhere the markers are empty and this only checks results.
//
//   icount_planner_example [calls frames width_px height_px]   default: 3 calls, 3 frames of 400 x 250
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/map/stack.hpp"
#include "support/cadre_frames.hpp"
#include "support/count_arg.hpp"
#include "support/icount_marker.hpp"

namespace {
int fail(const char* what) {
  std::fprintf(stderr, "icount_planner_example: %s\n", what);
  return 1;
}
}  // namespace

int main(int argc, char** argv) {
  using namespace ccmap;
  using test::parse_count;
  int calls = 3, frames = 3, width_px = 400, height_px = 250;
  if (argc != 1 && (argc != 5 || !parse_count(argv[1], 1000, &calls) || !parse_count(argv[2], 100, &frames) ||
                    !parse_count(argv[3], 4000, &width_px) || !parse_count(argv[4], 4000, &height_px))) {
    std::fprintf(stderr, "usage: icount_planner_example [calls (1..1000) frames (1..100) width_px height_px]\n");
    return 2;
  }
  const auto stack = std::make_unique<Stack<CadreConfig>>();  // on the heap, as the timing test's
  if (stack->init(default_stack_params(0.04F)) != Status::kOk) return fail("init failed");
  for (int k = 0; k < frames; ++k) {
    const test::CadreFrame frame = test::make_cadre_frame(test::cadre_sequence_spec(k, width_px, height_px));
    if (stack->update_frame(frame.map_points.data(), frame.map_points.size(), frame.sensor_origin, nullptr) != Status::kOk) {
      return fail("update refused");
    }
  }
  const Footprint body{0.9F, 0.05F, 1.0F, 0.0F, 0.6F, 0.4F};
  const Footprint large{1.0F, 0.05F, 0.8F, 0.6F, 2.0F, 1.0F};
  const PathPoint route[] = {{0.3F, 0.0F}, {2.3F, 0.0F}};
  // max_unknown_share 1: no footprint counts as unknown, so all 41 poses are evaluated (the sweep
  // stops once both a hazard and an unknown footprint are found).
  const PathSweep sweep{0.6F, 0.4F, 0.05F, 1.0F};
  std::vector<std::uint8_t> cost(125U * 125U);
  std::uint32_t read = 0U;
  for (int c = 0; c < calls; ++c) {
    test::icount_begin<1>();
    const FootprintResult a = query_footprint(*stack, body);
    test::icount_end<1>();
    test::icount_begin<2>();
    const FootprintResult b = query_footprint(*stack, large);
    test::icount_end<2>();
    test::icount_begin<3>();
    const PathResult p = query_path(*stack, route, 2, sweep);
    test::icount_end<3>();
    CostmapStats plain{}, inflated{};
    test::icount_begin<4>();
    const Status s1 = fill_costmap(*stack, CostmapSpec{0.0F, 0.0F, 0.04F, 125U, 0.0F}, cost.data(), cost.size(), &plain);
    test::icount_end<4>();
    test::icount_begin<5>();
    const Status s2 = fill_costmap(*stack, CostmapSpec{0.0F, 0.0F, 0.04F, 125U, 0.3F}, cost.data(), cost.size(), &inflated);
    test::icount_end<5>();
    if (a.status != Status::kOk || b.status != Status::kOk || p.status != Status::kOk || s1 != Status::kOk ||
        s2 != Status::kOk || p.samples != 41U) {
      return fail("a planner query failed");
    }
    read += a.cells_visited;
  }
  for (int c = 0; c < calls; ++c) {
    test::icount_begin<6>();
    const Status m1 = stack->move_to(0.04F, 0.0F);
    const Status m2 = stack->move_to(0.0F, 0.0F);
    test::icount_end<6>();
    test::icount_begin<7>();
    const Status u1 = stack->move_to(0.04F, 0.0F, 0.005F);
    const Status u2 = stack->move_to(0.0F, 0.0F, 0.005F);
    test::icount_end<7>();
    if (m1 != Status::kOk || m2 != Status::kOk || u1 != Status::kOk || u2 != Status::kOk) return fail("move refused");
  }
  std::printf("icount_planner_example: %d calls of each query (footprint reads %u cells per call)\n", calls,
              read / static_cast<std::uint32_t>(calls));
  return 0;
}
