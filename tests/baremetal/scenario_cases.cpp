// The board-sized determinism scenario (tests/support/board_scenario.hpp) on the bare-metal
// image, against the golden hash that the host and aarch64 builds check too
// (tests/golden/determinism.txt, line "board_scenario"; CMake passes it in as
// CCMAP_BOARD_SCENARIO_GOLDEN at configure time). The image is linked for 1 MiB of RAM: the
// link proves that the map, a 10,000-point frame with weights, an export buffer and the stack
// fit a 1 MiB controller. Also prints the deepest main-stack use of the run.
#include <cstdint>

#include "board.h"
#include "harness.hpp"
#include "support/board_scenario.hpp"

#ifndef CCMAP_BOARD_SCENARIO_GOLDEN
#error "CCMAP_BOARD_SCENARIO_GOLDEN (the board_scenario line of tests/golden/determinism.txt) is not defined"
#endif

namespace {

namespace scenario = ccmap::test::scenario;

// Static storage, zero-filled by start-up (.bss), as a flight image would hold them.
scenario::CadreStack g_stack;
ccmap::PointXYZ g_points[scenario::kBoardFramePoints];
float g_weights[scenario::kBoardFramePoints];
ccmap::CellRecord g_records[scenario::CadreStack::layer_capacity(0)];

}  // namespace

BM_CASE(board_scenario, hash_equals_golden) {
  const scenario::BoardResult r = scenario::run_board_scenario(g_stack, g_points, g_weights, g_records);
  BM_CHECK_EQ(r.failed_step, 0, "a call of the scenario did not answer kOk (step number)");
  ccmap::bmtest::Line().text("board_scenario ").hex64(r.hash).end();
  const struct {
    const char* name;
    std::uint32_t value;
  } counts[] = {{"  points received ", r.totals.received},          {", used ", r.totals.used},
                {", non-finite ", r.totals.rejected_non_finite},    {", out-of-range ", r.totals.rejected_out_of_range},
                {", bad weight ", r.totals.rejected_weight},        {", too noisy ", r.totals.too_noisy}};
  ccmap::bmtest::Line line;
  for (const auto& c : counts) {
    line.text(c.name).u64(c.value);
  }
  line.end();
  BM_CHECK_EQ(r.hash, CCMAP_BOARD_SCENARIO_GOLDEN,
              "board_scenario hash differs from tests/golden/determinism.txt: the Cortex-M7 arithmetic differs "
              "from the host's, or the map changed on purpose (regenerate: tests/map/determinism_dump.cpp)");
  BM_CHECK_EQ(ccmap_board_fault_count(), 0U, "the core reported a contract violation");
  const std::size_t used = ccmap_board_stack_used();
  ccmap::bmtest::Line().text("  main stack: ").u64(used).text(" of ").u64(ccmap_board_stack_size()).text(" bytes used").end();
  BM_CHECK(used + 256U < ccmap_board_stack_size(), "the main stack came within 256 bytes of its limit");
}
