// Free space in map exchange (persistence/exchange.hpp, delta format 3; docs/design.md 8.6): the
// free-space entries' bytes and checks, drop-offs learned from a team mate, team mates' clears
// under the receiver's rule, damaged entries refused alone. References: the CRC standard's check
// value, every record state round-tripped, the sender's own query answers (its records) cell by
// cell, and the scenes' geometry (tests/support/ray_scene.hpp), not the merge code.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "ccmap/persistence/exchange.hpp"
#include "support/calibrated_params.hpp"
#include "support/ray_scene.hpp"
#include "support/wire_bytes.hpp"

namespace ccmap {
namespace {

using Bytes = std::vector<std::uint8_t>;
using Map = Stack<CadreConfig>;
using Exchange = MapExchange<CadreConfig>;
using detail::FreeSpaceCell;
using detail::FreeSpaceEntry;
using detail::FreeSpaceEntryKind;
using test::AnalyticScene;
using test::SceneBox;
using test::SceneCamera;
using test::SceneDitch;
using test::SceneFrame;

constexpr std::size_t kEntryBytes = detail::kFreeSpaceEntryBytes;

// ---- the entries' bytes ----

TEST(FreeSpaceEntry, TheCheckIsTheStandardCrc16CcittFalse) {
  const std::uint8_t text[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(detail::free_space_entry_crc(text, sizeof text), 0x29B1U) << "CRC-16/CCITT-FALSE check value";
}

TEST(FreeSpaceEntry, EveryDropOffRecordStateAndAClearRoundTrip) {
  // Every bound code with both drop counts a drop-off can have, through encode, decode and the
  // merge into an empty record (no height offset): the receiver's record is the sender's.
  std::uint8_t bytes[kEntryBytes] = {};
  for (std::uint32_t code = 0; code <= 0xFFFFU; ++code) {
    for (const std::uint8_t rays : {std::uint8_t{2}, std::uint8_t{3}}) {
      FreeSpaceCell sent{static_cast<std::uint16_t>(code), 0U, static_cast<std::uint8_t>(rays << 6U)};
      ASSERT_TRUE(detail::is_drop(sent));
      const std::uint32_t position = (code * 2654435761U) % detail::kFreeSpaceEntryPositions;
      const int layer = static_cast<int>(code % 5U);
      detail::encode_free_space_entry(detail::drop_entry_of(sent, layer, position), bytes);
      FreeSpaceEntry e{};
      ASSERT_TRUE(detail::decode_free_space_entry(bytes, &e)) << "code " << code;
      ASSERT_EQ(e.kind, FreeSpaceEntryKind::kDropOff);
      ASSERT_EQ(e.layer, layer);
      ASSERT_EQ(e.position, position);
      FreeSpaceCell received{};
      detail::merge_drop(received, e.bound_code != 0U ? detail::bound_m(FreeSpaceCell{e.bound_code, 0U, 0U})
                                                       : std::numeric_limits<float>::quiet_NaN(),
                         e.drop_rays);
      // Code 0 (no bound) stays none; 1 and 65535 are the bounds -+127.996 m themselves.
      ASSERT_EQ(received.bound_code, code) << "code " << code;
      ASSERT_EQ(detail::drop_rays(received), rays);
    }
  }
  const FreeSpaceEntry clear{FreeSpaceEntryKind::kCleared, 4U, detail::kFreeSpaceEntryPositions - 1U, 0U, 0U};
  detail::encode_free_space_entry(clear, bytes);
  FreeSpaceEntry e{};
  ASSERT_TRUE(detail::decode_free_space_entry(bytes, &e));
  EXPECT_EQ(e.kind, FreeSpaceEntryKind::kCleared);
  EXPECT_EQ(e.layer, 4U);
  EXPECT_EQ(e.position, detail::kFreeSpaceEntryPositions - 1U);
}

TEST(FreeSpaceEntry, EveryFlipOfOneTwoOrThreeBitsAndEveryForgedFieldIsRefused) {
  const FreeSpaceEntry entries[] = {
      {FreeSpaceEntryKind::kDropOff, 0U, 0U, 0x8000U, 2U},
      {FreeSpaceEntryKind::kDropOff, 3U, 4095U, 0x7A31U, 3U},
      {FreeSpaceEntryKind::kCleared, 1U, 77U, 0U, 0U},
  };
  for (const FreeSpaceEntry& entry : entries) {
    std::uint8_t good[kEntryBytes] = {};
    detail::encode_free_space_entry(entry, good);
    constexpr int kBits = static_cast<int>(kEntryBytes) * 8;
    auto flipped = [&](int a, int b, int c) {
      std::uint8_t bad[kEntryBytes];
      std::memcpy(bad, good, kEntryBytes);
      for (const int bit : {a, b, c}) {
        if (bit >= 0) {
          bad[bit / 8] = static_cast<std::uint8_t>(bad[bit / 8] ^ (1U << (bit % 8)));
        }
      }
      FreeSpaceEntry e{};
      return detail::decode_free_space_entry(bad, &e);
    };
    for (int a = 0; a < kBits; ++a) {
      ASSERT_FALSE(flipped(a, -1, -1)) << "flip of bit " << a;
      for (int b = a + 1; b < kBits; ++b) {
        ASSERT_FALSE(flipped(a, b, -1)) << "flips of bits " << a << ", " << b;
        for (int c = b + 1; c < kBits; ++c) {
          ASSERT_FALSE(flipped(a, b, c)) << "flips of bits " << a << ", " << b << ", " << c;
        }
      }
    }
  }
  // Fields no export writes, their check recomputed: refused by the field checks.
  auto forged = [](std::uint32_t where, std::uint16_t bound, std::uint8_t rays, std::uint8_t reserved) {
    std::uint8_t b[kEntryBytes] = {static_cast<std::uint8_t>(where), static_cast<std::uint8_t>(where >> 8U),
                                   static_cast<std::uint8_t>(where >> 16U), static_cast<std::uint8_t>(where >> 24U),
                                   static_cast<std::uint8_t>(bound), static_cast<std::uint8_t>(bound >> 8U), rays,
                                   reserved, 0U, 0U};
    const std::uint16_t crc = detail::free_space_entry_crc(b, 8U);
    b[8] = static_cast<std::uint8_t>(crc);
    b[9] = static_cast<std::uint8_t>(crc >> 8U);
    FreeSpaceEntry e{};
    return detail::decode_free_space_entry(b, &e);
  };
  EXPECT_TRUE(forged(0x10000005U, 0x8000U, 2U, 0U)) << "a drop-off entry as an export writes it";
  EXPECT_TRUE(forged(0x20000005U, 0U, 0U, 0U)) << "a clear as an export writes it";
  for (const std::uint32_t kind : {0U, 3U, 7U, 15U}) {
    EXPECT_FALSE(forged((kind << 28U) | 5U, 0x8000U, 2U, 0U)) << "kind " << kind;
  }
  for (const std::uint8_t rays : {0U, 1U, 4U, 255U}) {
    EXPECT_FALSE(forged(0x10000005U, 0x8000U, rays, 0U)) << "a drop-off of " << int{rays} << " rays";
  }
  EXPECT_FALSE(forged(0x20000005U, 0x8000U, 0U, 0U)) << "a clear with a bound";
  EXPECT_FALSE(forged(0x20000005U, 0U, 2U, 0U)) << "a clear with drop rays";
  EXPECT_FALSE(forged(0x10000005U, 0x8000U, 2U, 1U)) << "a non-zero reserved byte";
}

// ---- scenes ----

/// The rovers' parameters, the thresholds written out once (support/calibrated_params.hpp): the
/// tests make many rovers, and init()'s calibration is not their subject.
StackParams scene_params() {
  static const StackParams params = [] {
    StackParams p = default_stack_params(0.04F);
    p.free_space_rays = 1024.0F;
    p.outlier_gate_sigma = 0.0F;  // the paper's update: a ghost stays unless lines of sight clear it
    p.weight_limit = kNoWeightLimit;
    p.kalman_min_variance = 1e-30F;
    return test::with_calibrated_thresholds<CadreConfig>(p);
  }();
  return params;
}

struct Rover {
  std::unique_ptr<Map> map = std::make_unique<Map>();
  std::unique_ptr<Exchange> exchange = std::make_unique<Exchange>();
  Rover(std::uint32_t id, CellIndex origin = CellIndex{0, 0}, float origin_z = 0.0F) {
    EXPECT_EQ(map->init(scene_params()), Status::kOk);
    EXPECT_EQ(exchange->init(*map, ExchangeParams{id, 1U, origin, origin_z}), Status::kOk);
  }
  FrameCounters see(const AnalyticScene& scene, std::uint64_t seed, double x = 0.0) {
    SceneCamera cam;
    cam.x = x;
    cam.seed = seed;
    const SceneFrame f = test::render_scene(scene, cam);
    FrameCounters c{};
    EXPECT_EQ(map->move_to(f.origin.x, f.origin.y), Status::kOk);
    EXPECT_EQ(map->update_frame(f.points.data(), f.points.size(), f.origin, &c), Status::kOk);
    return c;
  }
  Bytes export_delta(ExportReport* report = nullptr) {
    Bytes out(Exchange::max_delta_size());
    std::size_t n = 0;
    EXPECT_EQ(exchange->export_delta(out.data(), out.size(), ExportOptions{0.0F, 0}, &n, report), Status::kOk);
    out.resize(n);
    return out;
  }
  MergeReport merge(const Bytes& delta, Status expected = Status::kOk) {
    MergeReport r{};
    EXPECT_EQ(exchange->merge_delta(delta.data(), delta.size(), &r), expected);
    return r;
  }
};

AnalyticScene ditch_scene() {
  AnalyticScene s;
  s.ditches.push_back(SceneDitch{1.2, -1.5, 2.2, 1.5, 0.40});
  return s;
}

/// A rover that saw the ditch from 17.5 cm for three frames (docs/design.md 12).
void see_ditch(Rover& r) {
  for (int k = 0; k < 3; ++k) {
    r.see(ditch_scene(), static_cast<std::uint64_t>(k) + 1U);
  }
}

/// Drop-off cells of every layer over the rectangle, as `map` answers query_layer at the cell
/// centres (x, y shifted by `shift_m` in the map's frame).
int count_drop_agreement(const Map& a, const Map& b, float shift_m, float dz_m, int* mismatches) {
  int drops = 0;
  for (int layer = 0; layer < Map::kLayerCount; ++layer) {
    const float w = a.layer_cell_width(layer);
    for (float x = -1.0F + 0.5F * w; x < 4.0F; x += w) {
      for (float y = -2.0F + 0.5F * w; y < 2.0F; y += w) {
        const QueryResult qa = a.query_layer(layer, x, y);
        const QueryResult qb = b.query_layer(layer, x - shift_m, y);
        const bool da = qa.cell_class == CellClass::kDropOff;
        const bool db = qb.cell_class == CellClass::kDropOff;
        drops += da ? 1 : 0;
        // The bound moves by the origins' height offset, rounded up to 2^-8 m.
        const bool same = da == db && (!da || std::fabs(qb.height_m - (qa.height_m + dz_m)) <= 0.00390625F);
        *mismatches += same ? 0 : 1;
      }
    }
  }
  return drops;
}

/// A rover that saw the ditch, and its first delta.
struct DitchDelta {
  Rover a{1U};
  ExportReport sent{};
  Bytes delta;
  DeltaInfo info{};
  DitchDelta() {
    see_ditch(a);
    delta = a.export_delta(&sent);
    EXPECT_EQ(Exchange::peek_delta(delta.data(), delta.size(), &info), Status::kOk);
  }
};

TEST(ExchangeFreeSpace, ATeamMateThatNeverLookedThereLearnsTheDitchCellByCell) {
  DitchDelta d;
  Rover& a = d.a;
  const Bytes& delta = d.delta;
  EXPECT_GT(d.sent.drops_written, 0U);
  EXPECT_EQ(d.info.free_space_entries, d.sent.drops_written + d.sent.clears_written);
  // B shares the origin; B2's origin lies 16 finest cells (0.64 m, one coarsest cell) east and
  // 0.25 m lower in the team frame: the same drop-offs, 0.64 m west and 0.25 m higher in its map.
  for (const bool offset : {false, true}) {
    Rover b(2U, CellIndex{offset ? 16 : 0, 0}, offset ? -0.25F : 0.0F);
    const MergeReport r = b.merge(delta);
    EXPECT_EQ(r.free_space_status, Status::kOk);
    EXPECT_EQ(r.entries_refused, 0U);
    EXPECT_GT(r.drops_merged, 0U);
    int mismatches = 0;
    const int drops = count_drop_agreement(*a.map, *b.map, offset ? 0.64F : 0.0F, offset ? 0.25F : 0.0F, &mismatches);
    EXPECT_GT(drops, 0);
    EXPECT_EQ(mismatches, 0) << "B's drop-offs differ from A's own records (offset " << offset << ")";
    // The stack query, which the planner reads: B answers drop inside the ditch.
    bool found = false;
    for (float x = 1.7F; x <= 2.1F && !found; x += 0.02F) {
      found = b.map->query(x - (offset ? 0.64F : 0.0F), 0.0F).cell_class == CellClass::kDropOff;
    }
    EXPECT_TRUE(found) << "B's stack query shows no drop-off in the ditch";
    // Not sent on: B's own delta carries none of A's drop-offs.
    ExportReport back{};
    (void)b.export_delta(&back);
    EXPECT_EQ(back.drops_written, 0U);
  }
  // Sent once: A's next delta (nothing new seen) carries no drop-off again.
  ExportReport again{};
  (void)a.export_delta(&again);
  EXPECT_EQ(again.drops_written, 0U);
}

TEST(ExchangeFreeSpace, ADropOffNeverReplacesAReceiversOwnObservation) {
  // B mapped flat ground where A saw the ditch (as after a pose error of one of them): B's
  // observed cells answer with B's points, never with A's drop-off.
  Rover a(1U);
  see_ditch(a);
  Rover b(2U);
  for (int k = 0; k < 3; ++k) {
    b.see(AnalyticScene{}, static_cast<std::uint64_t>(k) + 40U);
  }
  std::vector<QueryResult> before;
  for (float x = 1.2F; x < 2.2F; x += 0.04F) {
    before.push_back(b.map->query_layer(0, x + 0.02F, 0.02F));
  }
  const MergeReport r = b.merge(a.export_delta());
  EXPECT_EQ(r.free_space_status, Status::kOk);
  std::size_t i = 0;
  for (float x = 1.2F; x < 2.2F; x += 0.04F, ++i) {
    const QueryResult q = b.map->query_layer(0, x + 0.02F, 0.02F);
    if (before[i].weight > 0.0F) {
      EXPECT_NE(q.cell_class, CellClass::kDropOff) << "an observed 4 cm cell at x = " << x << " became a drop-off";
      EXPECT_GT(q.weight, 0.0F);
    }
  }
}

AnalyticScene box_scene() {
  AnalyticScene s;
  s.boxes.push_back(SceneBox{1.40, -0.15, 1.70, 0.15, 0.15});
  return s;
}

bool any_obstacle(const Map& map) {
  for (double x = 1.38; x <= 1.72; x += 0.02) {
    for (double y = -0.17; y <= 0.17; y += 0.02) {
      if (map.query(static_cast<float>(x), static_cast<float>(y)).cell_class == CellClass::kObstacle) {
        return true;
      }
    }
  }
  return false;
}

/// Weight of every CCM and fine cell over the box (all layers), in a fixed order.
std::vector<float> weights_over_box(const Map& map) {
  std::vector<float> out;
  for (int layer = 0; layer < Map::kLayerCount; ++layer) {
    const float w = map.layer_cell_width(layer);
    for (float x = 1.40F + 0.5F * w; x < 1.70F; x += w) {
      for (float y = -0.15F + 0.5F * w; y < 0.15F; y += w) {
        out.push_back(map.query_layer(layer, x, y).weight);
      }
    }
  }
  return out;
}

TEST(ExchangeFreeSpace, AGhostATeamMateClearedIsClearedWhereOnlyTeamMatesHadSeenIt) {
  // A sees a box for four frames and sends it; B (never looking there) holds A's box. The box
  // goes; A's lines of sight clear its cells and A's deltas carry the clears: B's copy goes too.
  Rover a(1U);
  Rover b(2U);
  const AnalyticScene empty;
  for (int k = 0; k < 4; ++k) {
    a.see(box_scene(), static_cast<std::uint64_t>(k) + 1U);
  }
  b.merge(a.export_delta());
  ASSERT_TRUE(any_obstacle(*b.map)) << "B holds A's box";
  std::uint32_t sent_clears = 0, cleared = 0, deferred = 0;
  for (int k = 0; k < 8; ++k) {
    a.see(empty, static_cast<std::uint64_t>(k) + 100U);
    ExportReport e{};
    const MergeReport m = b.merge(a.export_delta(&e));
    sent_clears += e.clears_written;
    cleared += m.cells_cleared;
    deferred += m.clears_deferred;
  }
  ASSERT_FALSE(any_obstacle(*a.map)) << "A's lines of sight did not clear the box (the scene tests nothing)";
  EXPECT_GT(sent_clears, 0U);
  EXPECT_GT(cleared, 0U);
  EXPECT_LE(cleared, sent_clears);
  EXPECT_EQ(deferred, 0U) << "B holds no point of its own there: no clear waits";
  EXPECT_FALSE(any_obstacle(*b.map)) << "B keeps the ghost A cleared";
  // Cell by cell over the box: B holds what A holds (A's points since the clears; no limiter).
  const std::vector<float> wa = weights_over_box(*a.map), wb = weights_over_box(*b.map);
  ASSERT_EQ(wa.size(), wb.size());
  for (std::size_t i = 0; i < wa.size(); ++i) {
    EXPECT_NEAR(wb[i], wa[i], 1e-3F * (1.0F + wa[i])) << "cell " << i << " over the box";
  }
}

TEST(ExchangeFreeSpace, AClearWithoutRoomWaitsWithItsCellAndGoesInALaterDelta) {
  Rover a(1U);
  Rover b(2U);
  for (int k = 0; k < 4; ++k) {
    a.see(box_scene(), static_cast<std::uint64_t>(k) + 1U);
  }
  b.merge(a.export_delta());
  std::uint32_t cleared_by_a = 0;
  for (int k = 0; k < 8; ++k) {
    cleared_by_a += a.see(AnalyticScene{}, static_cast<std::uint64_t>(k) + 100U).cleared_cells;
  }
  ASSERT_GT(cleared_by_a, 0U);
  // Room for the header and the layer headers only: no clear fits, every cleared cell waits.
  Bytes small(Exchange::min_delta_size() + kEntryBytes - 1U);
  std::size_t n = 0;
  ExportReport tight{};
  ASSERT_EQ(a.exchange->export_delta(small.data(), small.size(), ExportOptions{0.0F, 0}, &n, &tight), Status::kOk);
  small.resize(n);
  EXPECT_EQ(tight.clears_written, 0U);
  EXPECT_EQ(tight.cells_written, 0U);
  EXPECT_GT(tight.cells_pending, 0U);
  EXPECT_EQ(b.merge(small).cells_cleared, 0U);
  EXPECT_TRUE(any_obstacle(*b.map));
  // The next delta with room carries every clear, and B's copy of the box goes.
  ExportReport full{};
  const MergeReport m = b.merge(a.export_delta(&full));
  EXPECT_GT(full.clears_written, 0U);
  EXPECT_LE(full.clears_written, cleared_by_a) << "a clear for a cell A never emptied (one mark per cell)";
  EXPECT_GT(m.cells_cleared, 0U);
  EXPECT_FALSE(any_obstacle(*b.map));
}

/// A and B both saw the box (B's twin the same frames as B, and no delta); B merged A's delta.
/// Then the box goes for A alone: A sees the empty place for 8 frames, and B merges A's delta
/// after each (the weights of B's cells over the box are checked never to drop).
struct BoxSeenByBoth {
  Rover a{1U}, b{2U}, twin{3U};
  std::uint32_t sent_clears = 0, cleared = 0, deferred = 0;
  BoxSeenByBoth() {
    for (int k = 0; k < 4; ++k) {
      a.see(box_scene(), static_cast<std::uint64_t>(k) + 1U);
      b.see(box_scene(), static_cast<std::uint64_t>(k) + 11U);
      twin.see(box_scene(), static_cast<std::uint64_t>(k) + 11U);
    }
    b.merge(a.export_delta());
    for (int k = 0; k < 8; ++k) {
      a.see(AnalyticScene{}, static_cast<std::uint64_t>(k) + 100U);
      ExportReport e{};
      const std::vector<float> before = weights_over_box(*b.map);
      const MergeReport m = b.merge(a.export_delta(&e));
      sent_clears += e.clears_written;
      cleared += m.cells_cleared;
      deferred += m.clears_deferred;
      const std::vector<float> after = weights_over_box(*b.map);
      for (std::size_t i = 0; i < before.size(); ++i) {
        EXPECT_GE(after[i], before[i]) << "a team mate's clear took points of B's own (cell " << i << ")";
      }
    }
  }
  /// B and its twin see the empty place for one frame: the cells each cleared.
  std::pair<std::uint32_t, std::uint32_t> one_empty_frame() {
    return {b.see(AnalyticScene{}, 300U).cleared_cells, twin.see(AnalyticScene{}, 300U).cleared_cells};
  }
};

TEST(ExchangeFreeSpace, AReceiversOwnObservationsSurviveATeamMatesClearWithoutItsOwnEvidence) {
  // B still holds points of its own over the box: A's clears do not empty B's cells (B's weights
  // only grow, by A's new ground), they raise B's evidence; B's box stays while B sees it, and its
  // confirmations then forget A's clears (one empty frame clears nothing, as for its twin).
  BoxSeenByBoth t;
  ASSERT_GT(t.sent_clears, 0U);
  EXPECT_EQ(t.cleared, 0U) << "B's own observations were emptied by a team mate's record alone";
  EXPECT_GT(t.deferred, 0U);
  EXPECT_TRUE(any_obstacle(*t.b.map)) << "B lost its own box to a team mate's clears";
  for (int k = 0; k < 3; ++k) {
    t.b.see(box_scene(), static_cast<std::uint64_t>(k) + 200U);
    t.twin.see(box_scene(), static_cast<std::uint64_t>(k) + 200U);
  }
  EXPECT_TRUE(any_obstacle(*t.b.map)) << "B's box vanished while B saw it";
  const auto [b_cleared, twin_cleared] = t.one_empty_frame();
  EXPECT_EQ(twin_cleared, 0U) << "one frame cleared the twin's box: the evidence rule asks for more";
  EXPECT_EQ(b_cleared, 0U) << "A's clears outlived B's own confirmations of the box";
}

TEST(ExchangeFreeSpace, ATeamMatesClearPlusOneFrameOfTheReceiversOwnRaysEmptiesTheCell) {
  // The first frame in which B's own lines of sight pass through the empty place clears cells,
  // where its twin without A's deltas needs the whole rule (three frames).
  BoxSeenByBoth t;
  ASSERT_GT(t.deferred, 0U);
  const auto [b_cleared, twin_cleared] = t.one_empty_frame();
  EXPECT_EQ(twin_cleared, 0U) << "one frame of its own cleared the twin's box";
  EXPECT_GT(b_cleared, 0U) << "B's first frame of its own evidence, after A's clears, cleared nothing";
}

// ---- damaged sections ----

TEST(ExchangeFreeSpace, AFlippedBitInAnEntryIsRefusedAloneAndTheRestMerges) {
  DitchDelta d;
  const Bytes& delta = d.delta;
  const ExportReport& sent = d.sent;
  ASSERT_GE(sent.drops_written, 3U);
  const std::size_t section = delta.size() - d.info.free_space_entries * kEntryBytes;
  // The reference: every drop-off merged from the intact delta.
  Rover clean(2U);
  const MergeReport all = clean.merge(delta);
  ASSERT_EQ(all.drops_merged, sent.drops_written);
  const std::size_t damaged = 1;  // the second entry
  for (std::size_t bit = 0; bit < kEntryBytes * 8U; ++bit) {
    Bytes b = delta;
    const std::size_t at = section + damaged * kEntryBytes + bit / 8U;
    b[at] = static_cast<std::uint8_t>(b[at] ^ (1U << (bit % 8U)));
    Rover rx(2U);
    const MergeReport r = rx.merge(b);
    ASSERT_EQ(r.free_space_status, Status::kCorrupt) << "bit " << bit;
    ASSERT_EQ(r.entries_refused, 1U) << "bit " << bit;
    ASSERT_EQ(r.drops_merged, all.drops_merged - 1U) << "bit " << bit;
    ASSERT_EQ(r.cells_merged, all.cells_merged) << "the cells beside a damaged entry were lost";
    ASSERT_EQ(rx.exchange->counters().entries_refused, 1U);
    ASSERT_EQ(rx.exchange->counters().sections_damaged, 1U);
  }
  // Truncated inside the last entry: it is refused, the others and the cells merge.
  Bytes cut(delta.begin(), delta.end() - 3);
  Rover rx(2U);
  const MergeReport r = rx.merge(cut);
  EXPECT_EQ(r.free_space_status, Status::kCorrupt);
  EXPECT_EQ(r.entries_refused, 1U);
  EXPECT_EQ(r.drops_merged, all.drops_merged - 1U);
  EXPECT_EQ(r.cells_merged, all.cells_merged);
  // A flip in the core (its CRC) refuses the whole delta, as before.
  Bytes core = delta;
  core[100] = static_cast<std::uint8_t>(core[100] ^ 1U);
  Rover rc(2U);
  EXPECT_EQ(rc.merge(core, Status::kCorrupt).drops_merged, 0U);
}

TEST(ExchangeFreeSpace, AVersion2DeltaStillMergesAndOneWithBytesBeyondItsSizeIsRefused) {
  Rover a(1U);
  for (int k = 0; k < 2; ++k) {
    a.see(AnalyticScene{}, static_cast<std::uint64_t>(k) + 1U);
  }
  ExportReport sent{};
  Bytes delta = a.export_delta(&sent);
  ASSERT_EQ(sent.drops_written + sent.clears_written, 0U) << "flat ground: no entry";
  // Version 2 is version 3 without a section: the same core, version 2.
  delta[4] = 2U;
  test::reseal(delta);
  Rover b(2U);
  const MergeReport r = b.merge(delta);
  EXPECT_GT(r.cells_merged, 0U);
  EXPECT_EQ(r.free_space_status, Status::kOk);
  // A version-2 delta's size field is the whole delta: a byte more is refused whole.
  Bytes longer = delta;
  longer.push_back(0U);
  Rover c(3U);
  EXPECT_EQ(c.merge(longer, Status::kCorrupt).cells_merged, 0U);
  // Version 1 and versions after 3 are refused by version.
  for (const std::uint8_t v : {std::uint8_t{1}, std::uint8_t{4}}) {
    Bytes other = delta;
    other[4] = v;
    test::reseal(other);
    Rover d(4U);
    (void)d.merge(other, Status::kVersionMismatch);
  }
}

}  // namespace
}  // namespace ccmap
