// Cost on the Cortex-M7, in guest instructions counted by QEMU (-icount shift=0: 1 instruction
// = 1 ns of virtual time; timer 0 ticks at 25 MHz, 40 instructions a tick; board.h). The counts
// are deterministic: the same work gives the same count run after run, which the cases assert,
// so the figures printed as "[ figure ]" lines (docs/performance.md) are exact, not sampled.
// A first case checks the conversion itself against a loop of known length.
//
// The measured code is the code of this image: the update path is templates inlined into the
// caller, and another call site compiles to a slightly different instruction sequence (two call
// sites of the same frame update differed by 0.4 %). So each figure is measured in one
// non-inlined function, and the reproducibility check calls that same function again.
#include <cstdint>

#include "board.h"
#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "harness.hpp"
#include "shared_maps.hpp"
#include "support/cadre_frames.hpp"

namespace {

using ccmap::Status;
using ccmap::bmtest::CadreStack;

/// Waits for the timer to tick and returns the new count: a measurement that starts on a tick
/// edge is quantised at its end only (one tick, 40 instructions).
std::uint32_t start_on_tick() {
  const std::uint32_t now = ccmap_board_ticks();
  std::uint32_t next = now;
  while (next == now) {
    next = ccmap_board_ticks();
  }
  return next;
}

std::uint64_t instructions_since(std::uint32_t start_ticks) {
  return static_cast<std::uint64_t>(ccmap_board_ticks() - start_ticks) * CCMAP_BOARD_INSTRUCTIONS_PER_TICK;
}

void figure(const char* name, std::uint64_t instructions, std::uint64_t count, const char* per) {
  ccmap::bmtest::Line()
      .text("[ figure ] ")
      .text(name)
      .text(": ")
      .u64(instructions)
      .text(" instructions, ")
      .fixed(instructions, count, 1)
      .text(" per ")
      .text(per)
      .end();
}

constexpr int kFrameWidth = 125;  // 125 x 80 = 10,000 points (the bench's small frame)
constexpr int kFrameHeight = 80;
constexpr std::uint32_t kPoints = static_cast<std::uint32_t>(kFrameWidth * kFrameHeight);
static_assert(kPoints == ccmap::bmtest::kFramePoints, "the frame buffers hold one 125 x 80 frame");

/// Initialises stack 0 and folds CADRE frames 0..2 (the map then holds data, as in flight).
/// Frame 3 is left in the frame buffers, with its pose and origin.
void prepare(ccmap::Pose* pose, ccmap::PointXYZ* origin) {
  CadreStack& s = ccmap::bmtest::cadre_stack(0);
  BM_CHECK(s.init(ccmap::default_stack_params(0.04F)) == Status::kOk, "init refused the CADRE defaults");
  for (int k = 0; k < 4; ++k) {
    ccmap::test::fill_cadre_frame(ccmap::test::cadre_sequence_spec(k, kFrameWidth, kFrameHeight),
                                  ccmap::bmtest::frame_map_points(), ccmap::bmtest::frame_sensor_points(), origin, pose);
    if (k < 3) {
      BM_CHECK(s.update_frame(ccmap::bmtest::frame_map_points(), kPoints, *origin, nullptr) == Status::kOk,
               "update_frame refused a CADRE frame");
    }
  }
}

/// Instructions of one map-frame update of frame 3 on a freshly prepared stack.
__attribute__((noinline)) std::uint64_t map_frame_instructions(ccmap::FrameCounters* counters) {
  ccmap::Pose pose;
  ccmap::PointXYZ origin{};
  prepare(&pose, &origin);
  const std::uint32_t start = start_on_tick();
  const Status st = ccmap::bmtest::cadre_stack(0).update_frame(ccmap::bmtest::frame_map_points(), kPoints, origin, counters);
  const std::uint64_t n = instructions_since(start);
  BM_CHECK(st == Status::kOk, "update_frame refused a CADRE frame");
  return n;
}

// Cell updates on 64 cells in turn (as in a map: each update loads and stores its cell).
ccmap::CcmCell g_ccm_cells[64];
ccmap::KalmanCell g_kalman_cells[64];

__attribute__((noinline)) std::uint64_t ccm_updates(std::uint32_t n) {
  const std::uint32_t start = start_on_tick();
  for (std::uint32_t i = 0; i < n; ++i) {
    const float u = static_cast<float>(i & 255U) * (1.0F / 256.0F) - 0.5F;
    ccmap::detail::ccm_update_unchecked(g_ccm_cells[i & 63U], 0.08F * u, -0.05F * u, 0.1F * u, 1.0F, 1000.0F);
  }
  return instructions_since(start);
}

__attribute__((noinline)) std::uint64_t kalman_updates(std::uint32_t n) {
  const std::uint32_t start = start_on_tick();
  for (std::uint32_t i = 0; i < n; ++i) {
    ccmap::detail::kalman_update_unchecked(g_kalman_cells[i & 63U], 0.1F * static_cast<float>(i & 7U), 1e-4F, 1e-8F);
  }
  return instructions_since(start);
}

}  // namespace

BM_CASE(icount, timer_counts_forty_instructions_per_tick) {
  // 200,000 iterations of a two-instruction loop (subs, bne): 400,000 instructions.
  constexpr std::uint32_t kIterations = 200000U;
  std::uint32_t counter = kIterations;
  const std::uint32_t start = start_on_tick();
  __asm__ volatile(
      "1: subs %0, %0, #1\n"
      "   bne 1b\n"
      : "+r"(counter)
      :
      : "cc");
  const std::uint64_t measured = instructions_since(start);
  ccmap::bmtest::Line().text("  loop of ").u64(2U * kIterations).text(" instructions measured as ").u64(measured).end();
  // +- one tick of quantisation, plus the few instructions around the loop.
  BM_CHECK(measured + 80U >= 2U * kIterations && measured <= 2U * kIterations + 80U,
           "timer ticks do not count 40 guest instructions each: run under -icount shift=0");
}

BM_CASE(icount, cadre_frame_costs) {
  ccmap::FrameCounters counters{};
  const std::uint64_t map_frame = map_frame_instructions(&counters);
  // Every point folded in or judged by the outlier gate (a rock's edge in a cell): none refused.
  BM_CHECK_EQ(counters.used + counters.gated_finer + counters.gated_occluded + counters.gated_held +
                  counters.gated_pool_full,
              kPoints, "a CADRE frame point was neither used nor judged by the gate");
  figure("update_frame, CADRE frame of 10,000 points (map frame)", map_frame, kPoints, "point");
  // Deterministic: the same state, frame and code cost the same again, to the tick.
  const std::uint64_t again = map_frame_instructions(&counters);
  BM_CHECK(again + CCMAP_BOARD_INSTRUCTIONS_PER_TICK >= map_frame && again <= map_frame + CCMAP_BOARD_INSTRUCTIONS_PER_TICK,
           "the instruction count of one frame is not reproducible to one tick");
  BM_CHECK(map_frame > 20U * kPoints && map_frame < 5000U * kPoints, "implausible instructions per point");

  ccmap::Pose pose;
  ccmap::PointXYZ origin{};
  prepare(&pose, &origin);
  CadreStack& s = ccmap::bmtest::cadre_stack(0);
  std::uint32_t start = start_on_tick();
  BM_CHECK(s.update_frame_sensor(ccmap::bmtest::frame_sensor_points(), kPoints, pose, nullptr) == Status::kOk,
           "update_frame_sensor refused a CADRE frame");
  figure("update_frame_sensor, the same frame (sensor frame)", instructions_since(start), kPoints, "point");

  start = start_on_tick();
  const ccmap::QueryResult fine = s.query(0.5F, 0.1F);
  figure("query, finest cell (4 cm)", instructions_since(start), 1U, "query");
  BM_CHECK(fine.status == Status::kOk && fine.layer == 0, "the 4 cm cell at (0.5, 0.1) is not known");
  start = start_on_tick();
  const ccmap::QueryResult coarse = s.query_layer(4, 1.0F, 0.3F);
  figure("query_layer, 64 cm cell pooled from every layer", instructions_since(start), 1U, "query");
  BM_CHECK(coarse.status == Status::kOk, "the 64 cm cell at (1.0, 0.3) is not known");
  start = start_on_tick();
  BM_CHECK(s.move_to(1.0F, 0.0F) == Status::kOk, "move_to refused");
  figure("move_to, 1 m step", instructions_since(start), 1U, "move");
}

BM_CASE(icount, cell_update_costs) {
  constexpr std::uint32_t kUpdates = 10000U;
  const std::uint64_t ccm = ccm_updates(kUpdates);
  figure("CCM cell update (eqs. 1-7, with the limiter; loop included)", ccm, kUpdates, "update");
  BM_CHECK_NEAR(g_ccm_cells[0].weight, 157.0F, 0.0F, "a cell does not count its 157 updates");
  const std::uint64_t kalman = kalman_updates(kUpdates);
  figure("Kalman cell update (loop included)", kalman, kUpdates, "update");
  BM_CHECK_NEAR(g_kalman_cells[0].weight, 157.0F, 0.0F, "a Kalman cell does not count its 157 updates");
  BM_CHECK(ccm > 10U * kUpdates && kalman > 5U * kUpdates, "implausibly cheap cell updates: was the loop optimised away?");
}
