// Snapshots on the target: a saved CADRE map loads into another stack that then answers every
// query and holds every cell bitwise as the original (the original is the reference), keeps
// doing so after both take the same new frame, and damaged snapshots are refused with the stack
// left bitwise unchanged. The CRC itself is checked against the standard check value.
#include <cstdint>
#include <cstring>

#include "ccmap/persistence/snapshot.hpp"
#include "harness.hpp"
#include "shared_maps.hpp"
#include "support/map_state.hpp"

namespace {

using ccmap::Status;
using ccmap::bmtest::CadreStack;
using ccmap::bmtest::kCadreSnapshotBytes;

/// Stack 0 with three frames along a short path; the snapshot of it in snapshot_buffer().
bool prepare_saved_map() {
  CadreStack& a = ccmap::bmtest::cadre_stack(0);
  bool ok = BM_CHECK(a.init(ccmap::default_stack_params(0.04F)) == Status::kOk, "init refused the CADRE defaults");
  for (int f = 0; f < 3; ++f) {
    const float rx = 0.1F * static_cast<float>(f);
    ok = ok && BM_CHECK(a.move_to(rx, 0.0F) == Status::kOk, "move_to refused");
    ccmap::bmtest::terrain_frame(f, rx, 0.0F, ccmap::bmtest::kFramePoints);
    ok = ok && BM_CHECK(a.update_frame(ccmap::bmtest::frame_map_points(), ccmap::bmtest::kFramePoints,
                                       ccmap::PointXYZ{rx, 0.0F, 0.5F}, nullptr) == Status::kOk,
                        "update_frame refused a valid frame");
  }
  std::size_t written = 0;
  ok = ok && BM_CHECK_STATUS(ccmap::save_snapshot(a, ccmap::bmtest::snapshot_buffer(), kCadreSnapshotBytes, &written),
                             Status::kOk, "save_snapshot");
  ok = ok && BM_CHECK_EQ(written, kCadreSnapshotBytes, "snapshot size is not snapshot_size<CadreConfig>()");
  return ok;
}

/// Field by field, floats by their bits (QueryResult has padding bytes: no memcmp).
bool same(const ccmap::QueryResult& a, const ccmap::QueryResult& b) {
  using ccmap::bmtest::bits;
  return a.status == b.status && a.layer == b.layer && a.cell_class == b.cell_class &&
         bits(a.cell_width_m) == bits(b.cell_width_m) && bits(a.height_m) == bits(b.height_m) &&
         bits(a.slope_x) == bits(b.slope_x) && bits(a.slope_y) == bits(b.slope_y) &&
         bits(a.inclination) == bits(b.inclination) && bits(a.normal_variance) == bits(b.normal_variance) &&
         bits(a.elevation_variance) == bits(b.elevation_variance) && bits(a.weight) == bits(b.weight);
}

/// Every query on a 12 cm grid over the 64 cm layer's window answers bitwise alike on both
/// stacks, and the grid reaches known cells of every layer.
bool same_answers(const CadreStack& a, const CadreStack& b) {
  int known = 0;
  bool all_same = true;
  for (int j = -80; j <= 80; j += 3) {
    for (int i = -80; i <= 80; i += 3) {
      const float x = 0.04F * static_cast<float>(i);
      const float y = 0.04F * static_cast<float>(j);
      const ccmap::QueryResult qa = a.query(x, y);
      all_same = all_same && same(qa, b.query(x, y));
      known += qa.status == Status::kOk ? 1 : 0;
    }
  }
  BM_CHECK(known > 100, "fewer than 100 known cells on the query grid: the comparison would prove little");
  return all_same;
}

}  // namespace

BM_CASE(snapshot, crc32_check_value) {
  const std::uint8_t digits[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  BM_CHECK_EQ(ccmap::crc32_update(0U, digits, sizeof digits), 0xCBF43926U, "CRC-32 of \"123456789\" is not 0xCBF43926");
}

BM_CASE(snapshot, round_trip_is_bitwise) {
  if (!prepare_saved_map()) {
    return;
  }
  CadreStack& a = ccmap::bmtest::cadre_stack(0);
  CadreStack& b = ccmap::bmtest::cadre_stack(1);
  BM_CHECK_STATUS(ccmap::load_snapshot(b, ccmap::bmtest::snapshot_buffer(), kCadreSnapshotBytes), Status::kOk,
                  "load_snapshot of an intact snapshot");
  BM_CHECK_EQ(ccmap::test::map_hash(b), ccmap::test::map_hash(a), "loaded cells or windows differ from the saved map");
  BM_CHECK(std::memcmp(&a.total_counters(), &b.total_counters(), sizeof(ccmap::FrameCounters)) == 0,
           "loaded counters differ");
  BM_CHECK(same_answers(a, b), "a query answers differently on the loaded map");
  // Both take the same next frame: the restored state includes parameters and routing.
  ccmap::bmtest::terrain_frame(7, 0.3F, 0.1F, ccmap::bmtest::kFramePoints);
  const ccmap::PointXYZ origin{0.3F, 0.1F, 0.5F};
  BM_CHECK(a.move_to(0.3F, 0.1F) == Status::kOk && b.move_to(0.3F, 0.1F) == Status::kOk, "move_to refused");
  BM_CHECK(a.update_frame(ccmap::bmtest::frame_map_points(), ccmap::bmtest::kFramePoints, origin, nullptr) == Status::kOk &&
               b.update_frame(ccmap::bmtest::frame_map_points(), ccmap::bmtest::kFramePoints, origin, nullptr) == Status::kOk,
           "update_frame refused a valid frame");
  BM_CHECK_EQ(ccmap::test::map_hash(b), ccmap::test::map_hash(a), "the maps diverge after the same frame");
}

BM_CASE(snapshot, damaged_snapshots_are_refused_and_change_nothing) {
  if (!prepare_saved_map()) {
    return;
  }
  CadreStack& b = ccmap::bmtest::cadre_stack(1);
  BM_CHECK(b.init(ccmap::default_stack_params(0.08F)) == Status::kOk, "init refused 8 cm defaults");
  ccmap::bmtest::terrain_frame(11, 0.0F, 0.0F, 2000U);
  BM_CHECK(b.update_frame(ccmap::bmtest::frame_map_points(), 2000U, ccmap::PointXYZ{0.0F, 0.0F, 0.5F}, nullptr) ==
               Status::kOk,
           "update_frame refused a valid frame");
  const std::uint64_t before = ccmap::test::map_hash(b);
  std::uint8_t* data = ccmap::bmtest::snapshot_buffer();
  const std::size_t size = kCadreSnapshotBytes;

  BM_CHECK_STATUS(ccmap::load_snapshot(b, data, size - 1U), Status::kCorrupt, "truncated by one byte");
  BM_CHECK_STATUS(ccmap::load_snapshot(b, data, 7U), Status::kCorrupt, "shorter than the header");
  // One flipped bit in the cells, the counters, the magic.
  for (const std::size_t offset : {std::size_t{2000}, size / 2U, size - 40U, std::size_t{0}}) {
    data[offset] ^= 0x08U;
    BM_CHECK_STATUS(ccmap::load_snapshot(b, data, size), Status::kCorrupt, "a flipped bit");
    data[offset] ^= 0x08U;
  }
  // Another format version (checked before the CRC).
  data[4] ^= 0x01U;
  BM_CHECK_STATUS(ccmap::load_snapshot(b, data, size), Status::kVersionMismatch, "another format version");
  data[4] ^= 0x01U;
  // An intact snapshot of another map shape: layer count changed, CRC re-sealed.
  const std::uint8_t layers = data[13];
  data[13] = 4U;
  const std::uint32_t crc = ccmap::crc32_update(0U, data, size - 4U);
  std::uint8_t sealed[4];
  for (int i = 0; i < 4; ++i) {
    sealed[i] = data[size - 4U + static_cast<std::size_t>(i)];
    data[size - 4U + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(crc >> (8 * i));
  }
  BM_CHECK_STATUS(ccmap::load_snapshot(b, data, size), Status::kVersionMismatch, "a snapshot of another configuration");
  data[13] = layers;
  std::memcpy(data + size - 4U, sealed, sizeof sealed);
  BM_CHECK_STATUS(ccmap::load_snapshot(b, nullptr, size), Status::kInvalidArgument, "null data");
  BM_CHECK_EQ(ccmap::test::map_hash(b), before, "a refused load changed the stack");
  BM_CHECK(b.layer_cell_width(0) > 0.079F, "a refused load changed the parameters");
  // The buffer is intact again: it loads.
  BM_CHECK_STATUS(ccmap::load_snapshot(b, data, size), Status::kOk, "the restored snapshot");
}

BM_CASE(snapshot, save_refusals) {
  CadreStack& b = ccmap::bmtest::cadre_stack(1);
  std::size_t written = 99U;
  // A stack that was never initialised (or whose init failed) has nothing to save.
  ccmap::StackParams bad = ccmap::default_stack_params(0.04F);
  bad.finest_cell_width_m = 0.0F;
  BM_CHECK_STATUS(b.init(bad), Status::kInvalidArgument, "init with a zero cell width");
  BM_CHECK_STATUS(ccmap::save_snapshot(b, ccmap::bmtest::snapshot_buffer(), kCadreSnapshotBytes, &written),
                  Status::kNotInitialised, "save of an uninitialised stack");
  BM_CHECK_EQ(written, 0U, "written is not 0 after a refused save");
  BM_CHECK(b.init(ccmap::default_stack_params(0.04F)) == Status::kOk, "init refused the CADRE defaults");
  BM_CHECK_STATUS(ccmap::save_snapshot(b, ccmap::bmtest::snapshot_buffer(), kCadreSnapshotBytes - 1U, &written),
                  Status::kBufferTooSmall, "save into a buffer one byte short");
  BM_CHECK_STATUS(ccmap::save_snapshot(b, nullptr, kCadreSnapshotBytes, &written), Status::kInvalidArgument,
                  "save into a null buffer");
  BM_CHECK_STATUS(ccmap::save_snapshot(b, ccmap::bmtest::snapshot_buffer(), kCadreSnapshotBytes, nullptr),
                  Status::kInvalidArgument, "save without a written pointer");
}
