// Free space in map exchange on the single-layer presets of the C interface (one 8 cm layer of
// 256 x 256 cells: SingleCcmConfig, SingleKalmanConfig, SingleOmgConfig; include/ccmap/ccmap.h):
// drop-offs learned from a team mate, team mates' clears under the receiver's rule, a clear
// without room, damaged entries refused alone. persistence/exchange.hpp is one template per
// preset, so each preset's copy of these paths is its own code; exchange_free_space_test.cpp
// drives them on the CADRE stack. References: the scenes' geometry (tests/support/ray_scene.hpp:
// where the ditch is and how deep, where the box stood, the plane it left), the sender's own
// query answers cell by cell, and a twin map fed the same frames without the team mate's delta.
//
// The scenes are made for one 8 cm layer: it takes points only up to the range at which the
// stereo noise reaches its IV-G bound (w / (4 sqrt 3) = 11.5 mm: 1.86 m for CADRE's stereo), so
// the ditch and the box stand within 1.3 m and the ditch camera's rows end at 1.8 m; a constant
// cell (Kalman, OMG) is one surface, its height the mean of its points, so the box is seen from
// above (a camera 0.5 m up) long enough that its cells stand the layer's clear margin (0.06 m,
// its obstacle height) above the rays that pass over them once it is gone (kBoxFrames).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "ccmap/persistence/exchange.hpp"
#include "support/ray_scene.hpp"

namespace ccmap {
namespace {

using Bytes = std::vector<std::uint8_t>;
using test::AnalyticScene;
using test::SceneBox;
using test::SceneCamera;
using test::SceneDitch;
using test::SceneFrame;

constexpr std::size_t kEntryBytes = detail::kFreeSpaceEntryBytes;
constexpr float kWidth = 0.08F;  // the presets' default cell width

StackParams single_params() {
  StackParams p = default_stack_params(kWidth);
  p.free_space_rays = 1024.0F;
  p.outlier_gate_sigma = 0.0F;  // the paper's update: a ghost stays unless lines of sight clear it
  p.weight_limit = kNoWeightLimit;
  p.kalman_min_variance = 1e-30F;
  return p;
}

/// One rover of a single-layer preset: its map and exchange (heap: a test may hold several).
template <typename Config>
struct Rover {
  using Map = Stack<Config>;
  using Exchange = MapExchange<Config>;
  std::unique_ptr<Map> map = std::make_unique<Map>();
  std::unique_ptr<Exchange> exchange = std::make_unique<Exchange>();
  explicit Rover(std::uint32_t id, CellIndex origin = CellIndex{0, 0}, float origin_z = 0.0F) {
    EXPECT_EQ(map->init(single_params()), Status::kOk);
    EXPECT_EQ(exchange->init(*map, ExchangeParams{id, 1U, origin, origin_z}), Status::kOk);
  }
  FrameCounters see(const SceneFrame& f) {
    FrameCounters c{};
    EXPECT_EQ(map->move_to(f.origin.x, f.origin.y), Status::kOk);
    EXPECT_EQ(map->update_frame(f.points.data(), f.points.size(), f.origin, &c), Status::kOk);
    return c;
  }
  Bytes export_delta(ExportReport* report = nullptr, std::size_t capacity = Exchange::max_delta_size()) {
    Bytes out(capacity);
    std::size_t n = 0;
    EXPECT_EQ(exchange->export_delta(out.data(), out.size(), ExportOptions{0.0F, 0}, &n, report), Status::kOk);
    out.resize(n);
    return out;
  }
  MergeReport merge(const Bytes& delta) {
    MergeReport r{};
    EXPECT_EQ(exchange->merge_delta(delta.data(), delta.size(), &r), Status::kOk);
    return r;
  }
};

/// Drop-offs in the rover's next delta.
template <typename Config>
std::uint32_t drops_in_next_delta(Rover<Config>& r) {
  ExportReport e{};
  (void)r.export_delta(&e);
  return e.drops_written;
}

// ---- the ditch: drop-offs ----

/// A ditch 0.4 m deep across the view, its near edge 0.7 m ahead: from 0.175 m (CADRE's camera)
/// the near edge hides its floor; the lines of sight to its far wall pass over the hidden floor
/// well below the ground they crossed last (a drop-off).
constexpr SceneDitch kDitch{0.70, -0.50, 1.30, 0.50, 0.40};

/// The frames carry no range noise, so every frame of a scene is the same one (rendered once);
/// the free-space stage's ray subsample moves with the frame count all the same.
const SceneFrame& ditch_frame() {
  static const SceneFrame frame = [] {
    AnalyticScene s;
    s.ditches.push_back(kDitch);
    SceneCamera cam;
    cam.far_m = 1.8;
    return test::render_scene(s, cam);
  }();
  return frame;
}

/// Three frames of the ditch (docs/design.md 12: drop-offs need rays of more than one frame).
template <typename Config>
void see_ditch(Rover<Config>& r) {
  for (int k = 0; k < 3; ++k) {
    r.see(ditch_frame());
  }
}

/// The drop-off cells of `map` over the ground ahead (x in [0, 2.4) m, |y| < 1.6 m), in a fixed
/// order: (x, y of the centre in the sender's frame, bound).
struct DropCell {
  float x, y, bound_m;
};
template <typename Map>
std::vector<DropCell> drop_cells(const Map& map, float shift_m) {
  std::vector<DropCell> out;
  for (float x = 0.5F * kWidth; x < 2.4F; x += kWidth) {
    for (float y = -1.6F + 0.5F * kWidth; y < 1.6F; y += kWidth) {
      const QueryResult q = map.query_layer(0, x - shift_m, y);
      if (q.cell_class == CellClass::kDropOff) {
        out.push_back(DropCell{x, y, q.height_m});
      }
    }
  }
  return out;
}

/// A rover that saw the ditch, and its first delta.
template <typename Config>
struct DitchDelta {
  Rover<Config> a{1U};
  ExportReport sent{};
  Bytes delta;
  DitchDelta() {
    see_ditch(a);
    delta = a.export_delta(&sent);
  }
};

template <typename Config>
class ExchangeFreeSpaceSingle : public ::testing::Test {};

struct PresetName {
  template <typename Config>
  static std::string GetName(int) {
    if (std::is_same_v<Config, SingleCcmConfig>) return "SingleCcm";
    if (std::is_same_v<Config, SingleKalmanConfig>) return "SingleKalman";
    return "SingleOmg";
  }
};
using Presets = ::testing::Types<SingleCcmConfig, SingleKalmanConfig, SingleOmgConfig>;
TYPED_TEST_SUITE(ExchangeFreeSpaceSingle, Presets, PresetName);

TYPED_TEST(ExchangeFreeSpaceSingle, ATeamMateLearnsTheDitchCellByCellAndInsideTheDitch) {
  DitchDelta<TypeParam> ditch;
  Rover<TypeParam>& a = ditch.a;
  const ExportReport& sent = ditch.sent;
  const Bytes& delta = ditch.delta;
  DeltaInfo info{};
  ASSERT_EQ(MapExchange<TypeParam>::peek_delta(delta.data(), delta.size(), &info), Status::kOk);
  EXPECT_EQ(info.free_space_entries, sent.drops_written + sent.clears_written);
  const std::vector<DropCell> own = drop_cells(*a.map, 0.0F);
  ASSERT_GE(own.size(), 3U) << "the ditch made no drop-off on one 8 cm layer (the scene tests nothing)";
  EXPECT_EQ(sent.drops_written, own.size()) << "every drop-off of A, and only those, is sent";
  // The geometry: a drop-off lies over the ditch (its cell overlaps it), and its bound is an
  // upper bound of the terrain there: at or above the ditch's floor, below the plane around it.
  for (const DropCell& d : own) {
    EXPECT_GT(d.x + 0.5F * kWidth, kDitch.x0) << "a drop-off before the ditch at x = " << d.x;
    EXPECT_LT(d.x - 0.5F * kWidth, kDitch.x1) << "a drop-off beyond the ditch at x = " << d.x;
    EXPECT_GT(d.y + 0.5F * kWidth, kDitch.y0) << "a drop-off beside the ditch at y = " << d.y;
    EXPECT_LT(d.y - 0.5F * kWidth, kDitch.y1) << "a drop-off beside the ditch at y = " << d.y;
    EXPECT_GE(d.bound_m, -kDitch.depth - 1e-3) << "a bound below the ditch's floor at x = " << d.x;
    EXPECT_LT(d.bound_m, 0.0F) << "a drop-off bound above the ground at x = " << d.x;
  }
  // B shares the origin; B2's origin lies 7 cells (0.56 m) east and 0.25 m lower in the team
  // frame: the same drop-offs 0.56 m west in its map, their bounds 0.25 m higher.
  for (const bool offset : {false, true}) {
    Rover<TypeParam> b(2U, CellIndex{offset ? 7 : 0, 0}, offset ? -0.25F : 0.0F);
    const MergeReport r = b.merge(delta);
    EXPECT_EQ(r.free_space_status, Status::kOk);
    EXPECT_EQ(r.entries_refused, 0U);
    EXPECT_EQ(r.entries_outside, 0U);
    EXPECT_EQ(r.drops_merged, sent.drops_written);
    const float shift = offset ? 0.56F : 0.0F, dz = offset ? 0.25F : 0.0F;
    const std::vector<DropCell> learned = drop_cells(*b.map, shift);
    ASSERT_EQ(learned.size(), own.size()) << "offset " << offset;
    for (std::size_t i = 0; i < own.size(); ++i) {
      EXPECT_EQ(learned[i].x, own[i].x);
      EXPECT_EQ(learned[i].y, own[i].y);
      // The bound moves by the origins' height offset, rounded up to 2^-8 m.
      EXPECT_NEAR(learned[i].bound_m, own[i].bound_m + dz, 0.00390625F) << "drop-off at x = " << own[i].x;
    }
    EXPECT_EQ(drops_in_next_delta(b), 0U) << "B sent A's drop-offs on";
  }
  EXPECT_EQ(drops_in_next_delta(a), 0U) << "A sent its drop-offs twice (nothing new seen)";
}

TYPED_TEST(ExchangeFreeSpaceSingle, ATeamMateBeyondTheWindowDropsTheDitchAndCountsIt) {
  // B's origin lies 300 cells (24 m) east of A's: A's ditch, 1 m ahead of A, is 23 m west of B,
  // beyond B's window (+-128 cells, 10.24 m): every cell and entry is dropped and counted.
  DitchDelta<TypeParam> ditch;
  const ExportReport& sent = ditch.sent;
  const Bytes& delta = ditch.delta;
  ASSERT_GE(sent.drops_written, 3U);
  Rover<TypeParam> b(2U, CellIndex{300, 0});
  const MergeReport r = b.merge(delta);
  EXPECT_EQ(r.free_space_status, Status::kOk);
  EXPECT_EQ(r.entries_outside, sent.drops_written + sent.clears_written);
  EXPECT_EQ(r.drops_merged, 0U);
  EXPECT_EQ(r.cells_outside, sent.cells_written);
  EXPECT_EQ(r.cells_merged, 0U);
  int drops = 0;  // B's whole window
  for (float x = -10.24F + 0.5F * kWidth; x < 10.24F; x += kWidth) {
    for (float y = -10.24F + 0.5F * kWidth; y < 10.24F; y += kWidth) {
      drops += b.map->query_layer(0, x, y).cell_class == CellClass::kDropOff ? 1 : 0;
    }
  }
  EXPECT_EQ(drops, 0);
}

TYPED_TEST(ExchangeFreeSpaceSingle, DropOffsWithoutRoomWaitAndGoInTheNextDelta) {
  // A and its twin see the same frames; the twin's delta gives the sizes. A's delta with room for
  // the core and one entry carries one drop-off; the rest wait (counted) and go in the next one.
  Rover<TypeParam> a(1U), twin(3U);
  see_ditch(a);
  see_ditch(twin);
  ExportReport whole{};
  const Bytes full = twin.export_delta(&whole);
  ASSERT_GE(whole.drops_written, 3U);
  ASSERT_EQ(whole.clears_written, 0U);
  ExportReport first{}, second{};
  const Bytes cut = a.export_delta(&first, full.size() - (whole.drops_written - 1U) * kEntryBytes);
  EXPECT_EQ(first.cells_written, whole.cells_written);
  EXPECT_EQ(first.drops_written, 1U);
  EXPECT_EQ(first.drops_pending, whole.drops_written - 1U);
  const Bytes rest = a.export_delta(&second);
  EXPECT_EQ(second.cells_written, 0U);
  EXPECT_EQ(second.drops_written, whole.drops_written - 1U);
  EXPECT_EQ(second.drops_pending, 0U);
  // B merges both and holds every drop-off of the twin's single delta.
  Rover<TypeParam> b(2U), c(4U);
  EXPECT_EQ(b.merge(cut).drops_merged + b.merge(rest).drops_merged, whole.drops_written);
  (void)c.merge(full);
  const std::vector<DropCell> via_two = drop_cells(*b.map, 0.0F), via_one = drop_cells(*c.map, 0.0F);
  ASSERT_EQ(via_two.size(), via_one.size());
  for (std::size_t i = 0; i < via_one.size(); ++i) {
    EXPECT_EQ(via_two[i].x, via_one[i].x);
    EXPECT_EQ(via_two[i].y, via_one[i].y);
    EXPECT_EQ(via_two[i].bound_m, via_one[i].bound_m);
  }
}

TYPED_TEST(ExchangeFreeSpaceSingle, AFlippedBitInAnEntryIsRefusedAloneAndCounted) {
  DitchDelta<TypeParam> ditch;
  const ExportReport& sent = ditch.sent;
  const Bytes& delta = ditch.delta;
  ASSERT_GE(sent.drops_written, 3U);
  Rover<TypeParam> clean(2U);
  const MergeReport all = clean.merge(delta);
  ASSERT_EQ(all.drops_merged, sent.drops_written);
  const std::size_t section = delta.size() - (sent.drops_written + sent.clears_written) * kEntryBytes;
  // One bit of each byte of the second entry (position, layer and kind, bound, rays, reserved, CRC).
  for (std::size_t byte = 0; byte < kEntryBytes; ++byte) {
    Bytes bad = delta;
    const std::size_t at = section + kEntryBytes + byte;
    bad[at] = static_cast<std::uint8_t>(bad[at] ^ (1U << (byte % 8U)));
    Rover<TypeParam> rx(2U);
    const MergeReport r = rx.merge(bad);
    EXPECT_EQ(r.free_space_status, Status::kCorrupt) << "byte " << byte;
    EXPECT_EQ(r.entries_refused, 1U) << "byte " << byte;
    EXPECT_EQ(r.drops_merged, all.drops_merged - 1U) << "byte " << byte;
    EXPECT_EQ(r.cells_merged, all.cells_merged) << "the cells beside a damaged entry were lost (byte " << byte << ")";
    EXPECT_EQ(rx.exchange->counters().entries_refused, 1U);
    EXPECT_EQ(rx.exchange->counters().sections_damaged, 1U);
  }
}

// ---- the vanished box: clears ----

/// A box 0.3 m tall and 0.4 m square, 0.8 m ahead, seen from 0.5 m up (its top in view): after
/// it goes, the lines of sight to the ground behind its place pass over its cells below their
/// heights by more than the clear margin.
constexpr SceneBox kBox{0.80, -0.20, 1.20, 0.20, 0.30};

SceneFrame box_camera_frame(const AnalyticScene& scene) {
  SceneCamera cam;
  cam.height_m = 0.5;
  cam.far_m = 4.0;
  return test::render_scene(scene, cam);
}
const SceneFrame& box_frame() {
  static const SceneFrame frame = [] {
    AnalyticScene s;
    s.boxes.push_back(kBox);
    return box_camera_frame(s);
  }();
  return frame;
}
/// The same place after the box went.
const SceneFrame& empty_frame() {
  static const SceneFrame frame = box_camera_frame(AnalyticScene{});
  return frame;
}

/// Frames of the box before it goes. Its top, seen 0.2 m below the camera from 0.8-1.2 m, takes
/// about one camera row per 8 cm cell, the ground of its place after it two or three: each frame
/// of that ground pulls a constant cell's height (the mean of its points) down, and after four
/// frames of the box the Kalman and OMG cells sank within two empty frames to where the rays
/// over them no longer passed the clear margin below, before the evidence rule's three frames
/// (measured: 12 of 20 cells kept). After twelve they stand until cleared.
constexpr int kBoxFrames = 12;

/// A rover that saw the box for kBoxFrames frames.
template <typename Config>
void see_box(Rover<Config>& r) {
  for (int k = 0; k < kBoxFrames; ++k) {
    r.see(box_frame());
  }
}

/// Cells over the box's place standing above the plane by more than the layer's obstacle height
/// (0.75 w = 0.06 m): what is left of the box (the truth after it went: the plane, z = 0).
template <typename Map>
int ghost_cells(const Map& map) {
  int ghosts = 0;
  for (float x = kBox.x0 + 0.5F * kWidth; x < kBox.x1; x += kWidth) {
    for (float y = kBox.y0 + 0.5F * kWidth; y < kBox.y1; y += kWidth) {
      const QueryResult q = map.query_layer(0, x, y);
      ghosts += q.weight > 0.0F && q.height_m > 0.75F * kWidth ? 1 : 0;
    }
  }
  return ghosts;
}

/// Weight and height of every cell over the box's place, in a fixed order.
template <typename Map>
std::vector<float> cells_over_box(const Map& map) {
  std::vector<float> out;
  for (float x = kBox.x0 + 0.5F * kWidth; x < kBox.x1; x += kWidth) {
    for (float y = kBox.y0 + 0.5F * kWidth; y < kBox.y1; y += kWidth) {
      const QueryResult q = map.query_layer(0, x, y);
      out.push_back(q.weight);
      out.push_back(q.weight > 0.0F ? q.height_m : 0.0F);
    }
  }
  return out;
}

TYPED_TEST(ExchangeFreeSpaceSingle, AVanishedBoxATeamMateClearedIsClearedWhereOnlyTeamMatesHadSeenIt) {
  Rover<TypeParam> a(1U), b(2U);
  see_box(a);
  (void)b.merge(a.export_delta());
  ASSERT_GT(ghost_cells(*b.map), 0) << "B holds A's box";
  std::uint32_t sent_clears = 0, cleared = 0, deferred = 0, cleared_by_a = 0;
  for (int k = 0; k < 6; ++k) {
    cleared_by_a += a.see(empty_frame()).cleared_cells;
    ExportReport e{};
    const MergeReport m = b.merge(a.export_delta(&e));
    sent_clears += e.clears_written;
    cleared += m.cells_cleared;
    deferred += m.clears_deferred;
  }
  ASSERT_EQ(ghost_cells(*a.map), 0) << "A's lines of sight left the box (the scene tests nothing)";
  EXPECT_GT(cleared_by_a, 0U);
  EXPECT_GT(sent_clears, 0U);
  EXPECT_LE(sent_clears, cleared_by_a) << "a clear for a cell A never emptied";
  EXPECT_GT(cleared, 0U);
  EXPECT_LE(cleared, sent_clears);
  EXPECT_EQ(deferred, 0U) << "B holds no point of its own there: no clear waits";
  EXPECT_EQ(ghost_cells(*b.map), 0) << "B keeps the ghost A cleared";
  // Cell by cell over the box's place: B holds what A holds (A's points since the clears).
  const std::vector<float> ca = cells_over_box(*a.map), cb = cells_over_box(*b.map);
  ASSERT_EQ(ca.size(), cb.size());
  for (std::size_t i = 0; i < ca.size(); ++i) {
    EXPECT_NEAR(cb[i], ca[i], 1e-3F * (1.0F + std::fabs(ca[i]))) << "value " << i << " over the box";
  }
}

TYPED_TEST(ExchangeFreeSpaceSingle, AClearWithoutRoomWaitsWithItsCellAndGoesInALaterDelta) {
  Rover<TypeParam> a(1U), b(2U);
  see_box(a);
  (void)b.merge(a.export_delta());
  std::uint32_t cleared_by_a = 0;
  for (int k = 0; k < 6; ++k) {
    cleared_by_a += a.see(empty_frame()).cleared_cells;
  }
  ASSERT_GT(cleared_by_a, 0U);
  // Room for the header and the layer header only: no clear fits, every cleared cell waits.
  ExportReport tight{};
  const Bytes small = a.export_delta(&tight, MapExchange<TypeParam>::min_delta_size() + kEntryBytes - 1U);
  EXPECT_EQ(tight.clears_written, 0U);
  EXPECT_EQ(tight.cells_written, 0U);
  EXPECT_GT(tight.cells_pending, 0U);
  EXPECT_EQ(b.merge(small).cells_cleared, 0U);
  EXPECT_GT(ghost_cells(*b.map), 0);
  ExportReport full{};
  const MergeReport m = b.merge(a.export_delta(&full));
  EXPECT_GT(full.clears_written, 0U);
  EXPECT_LE(full.clears_written, cleared_by_a);
  EXPECT_GT(m.cells_cleared, 0U);
  EXPECT_EQ(ghost_cells(*b.map), 0);
}

TYPED_TEST(ExchangeFreeSpaceSingle, AReceiversOwnBoxWaitsForOneFrameOfItsOwnRays) {
  // B saw the box too (its twin the same frames, and no delta); A's clears do not empty B's
  // cells (B's weights only grow), they raise B's evidence: the first frame of B's own rays
  // through the empty place then clears cells, where the twin needs the whole rule.
  Rover<TypeParam> a(1U), b(2U), twin(3U);
  see_box(a);
  see_box(b);
  see_box(twin);
  (void)b.merge(a.export_delta());
  std::uint32_t sent_clears = 0, cleared = 0, deferred = 0;
  for (int k = 0; k < 6; ++k) {
    a.see(empty_frame());
    ExportReport e{};
    const std::vector<float> before = cells_over_box(*b.map);
    const MergeReport m = b.merge(a.export_delta(&e));
    sent_clears += e.clears_written;
    cleared += m.cells_cleared;
    deferred += m.clears_deferred;
    const std::vector<float> after = cells_over_box(*b.map);
    for (std::size_t i = 0; i < before.size(); i += 2) {
      EXPECT_GE(after[i], before[i]) << "a team mate's clear took points of B's own (cell " << i / 2 << ")";
    }
  }
  ASSERT_GT(sent_clears, 0U);
  EXPECT_EQ(cleared, 0U) << "B's own observations were emptied by a team mate's record alone";
  EXPECT_GT(deferred, 0U);
  EXPECT_GT(ghost_cells(*b.map), 0) << "B lost its own box to a team mate's clears";
  const std::uint32_t twin_cleared = twin.see(empty_frame()).cleared_cells;
  const std::uint32_t b_cleared = b.see(empty_frame()).cleared_cells;
  EXPECT_EQ(twin_cleared, 0U) << "one frame of its own cleared the twin's box";
  EXPECT_GT(b_cleared, 0U) << "B's first frame of its own evidence, after A's clears, cleared nothing";
}

}  // namespace
}  // namespace ccmap
