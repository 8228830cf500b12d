// The frame budget (StackParams::frame_point_budget, frame_time_budget_us; docs/integration.md,
// "The frame budget"): a frame cut short processes whole chunks only, counts the rest, and,
// taking the chunks in bit-reversed order, still covers the whole field of view. References: the
// chunk arithmetic written out here (which chunks a budget takes), and the cells a full frame
// knows.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/flight_cycle.hpp"

namespace ccmap {
namespace {

using S = Stack<CadreConfig>;

std::unique_ptr<S> make(std::uint32_t points, std::uint32_t time_us) {
  auto s = std::make_unique<S>();
  StackParams p = default_stack_params(0.04F);
  p.frame_point_budget = points;
  p.frame_time_budget_us = time_us;
  EXPECT_EQ(s->init(p), Status::kOk);
  return s;
}

/// Cells of every layer that a query at their centre calls known (status kOk).
int known_cells(const S& s) {
  int known = 0;
  for (int k = 0; k < S::kLayerCount; ++k) {
    const float w = s.layer_cell_width(k);
    const CellIndex c = s.layer_centre(k);
    const std::int32_t half = S::layer_side(k) / 2;
    for (std::int32_t y = c.y - half; y < c.y + half; ++y) {
      for (std::int32_t x = c.x - half; x < c.x + half; ++x) {
        const QueryResult q = s.query_layer(k, grid::cell_centre(x, w), grid::cell_centre(y, w));
        known += q.status == Status::kOk ? 1 : 0;
      }
    }
  }
  return known;
}

std::uint32_t partition(const FrameCounters& c) {
  return c.used + c.rejected_non_finite + c.rejected_out_of_range + c.rejected_weight + c.outside_map + c.too_noisy +
         c.gated_finer + c.gated_occluded + c.gated_held + c.gated_pool_full + c.skipped_budget;
}

TEST(FrameBudget, ReverseBitsIsAPermutationOfItsRange) {
  for (std::uint32_t bits = 0U; bits <= 12U; ++bits) {
    std::vector<int> seen(std::size_t{1} << bits, 0);
    for (std::uint32_t j = 0U; j < (1U << bits); ++j) {
      ++seen[detail::reverse_bits(j, bits)];
    }
    for (const int s : seen) ASSERT_EQ(s, 1) << bits << " bits";
  }
  EXPECT_EQ(detail::reverse_bits(1U, 4U), 8U);
  EXPECT_EQ(detail::reverse_bits(6U, 4U), 6U);
}

// The chunk of the frame budget (StackParams: "no chunk of kFrontChunkPoints points"), 256 points.
constexpr std::uint32_t kChunk = 256U;
static_assert(detail::kFrontChunkPoints == kChunk, "the budget tests model 256-point chunks");

TEST(FrameBudget, APointBudgetTakesWholeChunksInBitReversedOrderAndCountsTheRest) {
  const test::CadreFrame frame = test::cycle_frame(0, 400, 250);  // 100,000 points: 391 chunks
  const auto n = static_cast<std::uint32_t>(frame.sensor_points.size());
  const std::uint32_t chunks = (n + kChunk - 1U) / kChunk;
  for (const std::uint32_t budget :
       {1U, kChunk - 1U, kChunk, kChunk + 1U, 5000U, n / 2U, n - 1U, n, n + 1000U}) {
    // Reference: chunks in bit-reversed order of [0, 512) while the next still fits.
    std::uint32_t taken = 0U;
    for (std::uint32_t j = 0U; j < 512U; ++j) {
      const std::uint32_t c = detail::reverse_bits(j, 9U);
      if (c >= chunks) continue;
      const std::uint32_t count = c + 1U == chunks ? n - c * kChunk : kChunk;
      if (taken + count > budget) break;
      taken += count;
    }
    auto s = make(budget, 0U);
    FrameCounters c{};
    ASSERT_EQ(s->update_frame_sensor(frame.sensor_points.data(), n, frame.pose, &c), Status::kOk);
    EXPECT_EQ(c.skipped_budget, n - taken) << "budget " << budget;
    EXPECT_EQ(partition(c), c.received) << "budget " << budget << ": every point counted once";
    EXPECT_LE(n - c.skipped_budget, budget) << "the budget is never exceeded";
  }
}

TEST(FrameBudget, HalfTheBudgetStillCoversTheFieldOfView) {
  const test::CadreFrame frame = test::cycle_frame(0);
  const auto n = static_cast<std::uint32_t>(frame.sensor_points.size());
  auto full = make(0U, 0U);
  auto half = make(n / 2U, 0U);
  auto first_half = make(0U, 0U);  // the same number of points, taken in order: a cut frame without interleaving
  FrameCounters cf{}, ch{}, co{};
  ASSERT_EQ(full->update_frame_sensor(frame.sensor_points.data(), n, frame.pose, &cf), Status::kOk);
  ASSERT_EQ(half->update_frame_sensor(frame.sensor_points.data(), n, frame.pose, &ch), Status::kOk);
  ASSERT_EQ(first_half->update_frame_sensor(frame.sensor_points.data(), n / 2U, frame.pose, &co), Status::kOk);
  const int known_full = known_cells(*full);
  const int known_half = known_cells(*half);
  const int known_first = known_cells(*first_half);
  std::printf("[ budget   ] CADRE frame of %u points: known cells %d full, %d with half the budget (interleaved), "
              "%d with its first half\n",
              n, known_full, known_half, known_first);
  EXPECT_GE(ch.skipped_budget, n / 2U - kChunk);
  EXPECT_GE(known_half, known_full * 85 / 100) << "an interleaved half frame must still see most of what a full one sees";
  EXPECT_GT(known_half, known_first) << "interleaving must cover more than the first half of the rows";
}

TEST(FrameBudget, ATimeBudgetStopsAtAChunkBoundaryAfterTheFirstChunk) {
  // 1 us: spent by the first chunk on any machine; the frame ends at the next chunk boundary, so
  // the overrun is that one chunk.
  const test::CadreFrame frame = test::cycle_frame(0, 400, 250);
  const auto n = static_cast<std::uint32_t>(frame.sensor_points.size());
  auto s = make(0U, 1U);
  FrameCounters c{};
  ASSERT_EQ(s->update_frame_sensor(frame.sensor_points.data(), n, frame.pose, &c), Status::kOk);
  EXPECT_EQ(c.skipped_budget, n - kChunk) << "exactly the first chunk (chunk 0 of the interleaved order)";
  EXPECT_EQ(partition(c), c.received);
  // A generous budget skips nothing.
  auto relaxed = make(0U, 60U * 1000U * 1000U);
  ASSERT_EQ(relaxed->update_frame_sensor(frame.sensor_points.data(), n, frame.pose, &c), Status::kOk);
  EXPECT_EQ(c.skipped_budget, 0U);
}

TEST(FrameBudget, ABudgetNeverReachedSkipsNothing) {
  // A budget that is never reached changes the order (interleaved) but no point is skipped; no
  // budget at all is the update in order. Both map every point.
  const test::CadreFrame frame = test::cycle_frame(1, 400, 250);
  const auto n = static_cast<std::uint32_t>(frame.sensor_points.size());
  auto a = make(0U, 0U);
  auto b = make(n, 0U);
  FrameCounters ca{}, cb{};
  ASSERT_EQ(a->update_frame_sensor(frame.sensor_points.data(), n, frame.pose, &ca), Status::kOk);
  ASSERT_EQ(b->update_frame_sensor(frame.sensor_points.data(), n, frame.pose, &cb), Status::kOk);
  EXPECT_EQ(ca.skipped_budget, 0U);
  EXPECT_EQ(cb.skipped_budget, 0U);
  EXPECT_EQ(ca.used + ca.gated_held, cb.used + cb.gated_held) << "the same points are taken, in another order";
}

}  // namespace
}  // namespace ccmap
