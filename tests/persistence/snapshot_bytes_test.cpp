// The snapshot byte layer at its edges (persistence/snapshot.hpp): the writer never writes past
// its capacity, the reader never reads past its size (both say so), and a map holding a value a
// load would refuse is not saved. References: the capacity and size given, and the documented
// statuses.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "ccmap/persistence/snapshot.hpp"

namespace ccmap {
namespace {

TEST(SnapshotBytes, WriterStopsAtItsCapacityAndSaysSo) {
  std::uint8_t bytes[6] = {0xEE, 0xEE, 0xEE, 0xEE, 0xEE, 0xEE};
  detail::SnapshotWriter w(bytes, 5U);
  w.u32(0x04030201U);
  EXPECT_FALSE(w.overflowed());
  w.u8(0x05U);
  EXPECT_FALSE(w.overflowed()) << "five bytes fit a capacity of five";
  w.u8(0x06U);
  EXPECT_TRUE(w.overflowed()) << "a sixth byte does not";
  w.u64(1U);
  EXPECT_EQ(w.position(), 5U) << "the writer must not advance past its capacity";
  EXPECT_EQ(bytes[4], 0x05U);
  EXPECT_EQ(bytes[5], 0xEEU) << "the byte after the capacity must stay untouched";
}

TEST(SnapshotBytes, ReaderPastTheEndGivesZeroAndIsNotOk) {
  const std::uint8_t bytes[3] = {0x11, 0x22, 0x33};
  detail::SnapshotReader r(bytes, 3U);
  EXPECT_EQ(r.u16(), 0x2211U);
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(r.u16(), 0x0033U) << "the missing high byte reads as 0";
  EXPECT_FALSE(r.ok()) << "reading past the end must mark the reader";
  detail::SnapshotReader s(bytes, 3U);
  s.seek(3U);
  EXPECT_TRUE(s.ok()) << "seeking to the end is allowed";
  s.seek(4U);
  EXPECT_FALSE(s.ok()) << "seeking beyond the end is not";
  EXPECT_EQ(s.position(), 3U);
}

TEST(SnapshotBytes, AMapHoldingANaNIsNotSaved) {
  auto stack = std::make_unique<Stack<CadreConfig>>();
  ASSERT_EQ(stack->init(default_stack_params(0.04F)), Status::kOk);
  std::vector<std::uint8_t> buffer(snapshot_size<CadreConfig>());
  std::size_t written = 0U;
  ASSERT_EQ(save_snapshot(*stack, buffer.data(), buffer.size(), &written), Status::kOk);
  // No update writes a NaN; a memory fault could. The stack is not const: write through the view.
  auto& grid = const_cast<RingGrid<CcmCell>&>(stack->ccm_layer(0));
  CcmCell* cell = grid.cell(CellIndex{0, 0});
  ASSERT_NE(cell, nullptr);
  cell->weight = 1.0F;
  cell->mean_z = std::numeric_limits<float>::quiet_NaN();
  written = 99U;
  EXPECT_EQ(save_snapshot(*stack, buffer.data(), buffer.size(), &written), Status::kNonFiniteInput)
      << "a snapshot that load_snapshot would refuse must not be written as a success";
  EXPECT_EQ(written, 0U);
}

}  // namespace
}  // namespace ccmap
