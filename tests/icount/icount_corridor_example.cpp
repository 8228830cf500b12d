// The flight cycle's corridor question (tests/support/flight_cycle.hpp: the rover's 1 m x 2 m
// corridor 0.3 .. 2.3 m ahead) asked two ways, each in its own icount region, on the maps of the
// cycle's drive (move_to + update_frame_sensor of cycle_frame(k), not counted):
//   region 1  the 1,250 point queries, one per 4 cm cell (test::corridor_queries)
//   region 2  one query_footprint over the same rectangle (test::corridor_footprint), as
//             run_cycle asks it
// and checks that they agree: the footprint's unknown share within 0.05 of the cells' share, and
// a hazard whenever a cell centre is one (the footprint sees every part, centres or not).
//
//   icount_corridor_example [cycles]     default 3 (full 850 x 650 frames)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "ccmap/planner/footprint.hpp"
#include "ccmap/map/stack.hpp"
#include "support/flight_cycle.hpp"
#include "support/icount_marker.hpp"

int main(int argc, char** argv) {
  using namespace ccmap;
  const int cycles = argc > 1 ? std::atoi(argv[1]) : 3;
  if (cycles < 1 || cycles > 100) {
    std::fprintf(stderr, "usage: icount_corridor_example [cycles 1..100]\n");
    return 2;
  }
  const auto stack = std::make_unique<Stack<CadreConfig>>();
  if (stack->init(default_stack_params(0.04F)) != Status::kOk) return 1;
  for (int k = 0; k < cycles; ++k) {
    const test::CadreFrame frame = test::cycle_frame(k);
    const test::CyclePose pose = test::cycle_pose(k);
    if (stack->move_to(pose.x, pose.y) != Status::kOk ||
        stack->update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, nullptr) !=
            Status::kOk) {
      return 1;
    }
    int hazards = 0;
    test::icount_begin<1>();
    const int unknown = test::corridor_queries(*stack, pose, &hazards);
    test::icount_end<1>();
    const Footprint corridor = test::corridor_footprint(pose);
    test::icount_begin<2>();
    const FootprintResult f = query_footprint(*stack, corridor);
    test::icount_end<2>();
    const float cell_share = static_cast<float>(unknown) / 1250.0F;
    const bool hazard = f.worst_class == CellClass::kObstacle || f.worst_class == CellClass::kSteep;
    std::printf("cycle %d: cells unknown %.3f, hazard cells %d; footprint unknown %.3f, worst %s, %u cells read\n", k,
                static_cast<double>(cell_share), hazards, static_cast<double>(f.unknown_share), to_string(f.worst_class),
                f.cells_visited);
    if (f.status != Status::kOk || std::fabs(f.unknown_share - cell_share) > 0.05F || (hazards > 0 && !hazard)) {
      std::fprintf(stderr, "icount_corridor_example: cycle %d: the footprint disagrees with the cell queries\n", k);
      return 1;
    }
  }
  return 0;
}
