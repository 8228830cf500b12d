// Single-event upsets in the free-space records (map/visibility/free_space.hpp, "integrity of the
// records"; docs/integration.md section 12): every bit of sampled live records, and of their
// checks, flipped one at a time in a trained map. Each flip must be detected (by the scrub within
// its frames, or when the record is read for a decision), the record reset to no evidence and
// counted once (FrameCounters::corrupted_cells), and no flip may make a drop-off or clear a cell
// that the untouched map (the reference: the same snapshot, the same frames, no flip) would not.
// The checks are compared with an independent model of the record's check: bound_code XOR
// (evidence | state << 8), what both signature forms give for one 32-bit word.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <type_traits>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "ccmap/map/visibility/sight_table.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/planner/detail/region_walk.hpp"
#include "support/calibrated_params.hpp"
#include "support/ray_scene.hpp"

#ifndef CCMAP_FREE_SPACE_UPSET_RECORDS
#define CCMAP_FREE_SPACE_UPSET_RECORDS 6  // live records flipped per campaign (every bit of each)
#endif

namespace {

using ccmap::CadreConfig;
using ccmap::CellClass;
using ccmap::FrameCounters;
using ccmap::PointXYZ;
using ccmap::Stack;
using ccmap::StackParams;
using ccmap::Status;
using ccmap::detail::FreeSpaceCell;
using ccmap::test::AnalyticScene;
using ccmap::test::SceneBox;
using ccmap::test::SceneCamera;
using ccmap::test::SceneDitch;
using ccmap::test::SceneFrame;

/// The model of a record's check (independent of the library's signature code).
std::uint16_t model_check(const FreeSpaceCell& r) {
  return static_cast<std::uint16_t>(r.bound_code ^ (std::uint32_t{r.evidence} | (std::uint32_t{r.state} << 8U)));
}

/// A record of the stack's storage, addressed by layer and buffer slot.
struct RecordAt {
  int layer;
  std::size_t slot;
};

template <typename Config>
struct Fixture {
  using Map = Stack<Config>;
  static const ccmap::detail::DropRecords& drops(const Map& map) {
    return *ccmap::detail::PlannerAccess<Config>::view(map).drops();
  }
  static FreeSpaceCell& record(Map& map, RecordAt at) {
    auto* grid = const_cast<ccmap::RingGrid<FreeSpaceCell>*>(drops(map).layer[at.layer]);
    return grid->storage()[at.slot];
  }
  static std::uint16_t& check(Map& map, RecordAt at) {
    return const_cast<std::uint16_t*>(drops(map).checks[at.layer])[at.slot];
  }
  /// Flips bit `bit` of the record (0 .. 31) or of its check (32 .. 47).
  static void flip(Map& map, RecordAt at, int bit) {
    if (bit < 32) {
      auto* bytes = reinterpret_cast<unsigned char*>(&record(map, at));
      bytes[bit / 8] = static_cast<unsigned char>(bytes[bit / 8] ^ (1U << (bit % 8)));
    } else {
      check(map, at) = static_cast<std::uint16_t>(check(map, at) ^ (1U << (bit - 32)));
    }
  }
  /// Records whose check differs from the model's (0: every writer kept every check).
  static std::size_t inconsistent(Map& map) {
    std::size_t bad = 0U;
    for (int layer = 0; layer < Map::kLayerCount; ++layer) {
      const std::size_t count = drops(map).layer[layer]->cell_count();
      for (std::size_t slot = 0; slot < count; ++slot) {
        bad += model_check(record(map, {layer, slot})) != check(map, {layer, slot}) ? 1U : 0U;
      }
    }
    return bad;
  }
  /// Up to `want` records that pass `pick`, spread evenly over all of them (deterministic).
  template <typename Pick>
  static std::vector<RecordAt> sample(Map& map, std::size_t want, Pick pick) {
    std::vector<RecordAt> all;
    for (int layer = 0; layer < Map::kLayerCount; ++layer) {
      const std::size_t count = drops(map).layer[layer]->cell_count();
      for (std::size_t slot = 0; slot < count; ++slot) {
        if (pick(record(map, {layer, slot}))) {
          all.push_back({layer, slot});
        }
      }
    }
    std::vector<RecordAt> out;
    for (std::size_t k = 0; k < want && !all.empty(); ++k) {
      out.push_back(all[(k * all.size()) / want]);
    }
    return out;
  }
  /// Every raw cell of every layer, as bytes.
  static std::vector<unsigned char> cells(const Map& map) {
    std::vector<unsigned char> out;
    for (int c = 0; c < Map::kCcmLayerCount; ++c) {
      const auto& g = map.ccm_layer(c);
      const auto* b = reinterpret_cast<const unsigned char*>(g.storage());
      out.insert(out.end(), b, b + g.cell_count() * sizeof(*g.storage()));
    }
    if constexpr (Map::kHasFine) {
      const auto& f = map.fine_layer();
      const auto* b = reinterpret_cast<const unsigned char*>(f.storage());
      out.insert(out.end(), b, b + f.cell_count() * sizeof(*f.storage()));
    }
    return out;
  }
};

/// The campaigns' parameters, the thresholds written out: every trial loads the snapshot, and
/// init()'s calibration is not the subject (support/calibrated_params.hpp).
template <typename Config>
StackParams params(float rays) {
  StackParams p = ccmap::default_stack_params(0.04F);
  p.free_space_rays = rays;
  return ccmap::test::with_calibrated_thresholds<Config>(p);
}

template <typename Map>
void fold(Map& map, const SceneFrame& f, FrameCounters* total) {
  FrameCounters c{};
  ASSERT_EQ(map.move_to(f.origin.x, f.origin.y), Status::kOk);
  ASSERT_EQ(map.update_frame(f.points.data(), f.points.size(), f.origin, &c), Status::kOk);
  if (total != nullptr) {
    total->cleared_cells += c.cleared_cells;
    total->corrupted_cells += c.corrupted_cells;
  }
}

/// Frames with no points: the scrub's slices alone. Returns the records and cells it reset.
template <typename Map>
std::uint32_t scrub_frames(Map& map, std::uint32_t frames) {
  std::uint32_t reset = 0U;
  const PointXYZ origin{0.0F, 0.0F, 0.175F};
  for (std::uint32_t f = 0; f < frames; ++f) {
    FrameCounters c{};
    EXPECT_EQ(map.update_frame(nullptr, 0U, origin, &c), Status::kOk);
    reset += c.corrupted_cells;
  }
  return reset;
}

template <typename Config>
std::vector<std::uint8_t> save(const Stack<Config>& map) {
  std::vector<std::uint8_t> buffer(ccmap::snapshot_size<Config>());
  std::size_t written = 0;
  EXPECT_EQ(ccmap::save_snapshot(map, buffer.data(), buffer.size(), &written), Status::kOk);
  buffer.resize(written);
  return buffer;
}

template <typename Map>
std::unique_ptr<Map> load(const std::vector<std::uint8_t>& snapshot) {
  auto m = std::make_unique<Map>();
  EXPECT_EQ(ccmap::load_snapshot(*m, snapshot.data(), snapshot.size()), Status::kOk);
  return m;
}

/// The trials' map: loaded from the snapshot once, then put back to that state before each trial
/// by copying the loaded bytes over it in place. A Stack is trivially copyable and its pointers
/// point into itself, so the bytes are those of a fresh load at the same address; copying them
/// costs a fraction of a load's checks (the snapshot's CRC, every cell read).
template <typename Map>
class LoadedOnce {
  static_assert(std::is_trivially_copyable<Map>::value, "a Stack is restored from its bytes");

 public:
  explicit LoadedOnce(const std::vector<std::uint8_t>& snapshot)
      : map_(load<Map>(snapshot)), bytes_(sizeof(Map)) {
    std::memcpy(bytes_.data(), static_cast<const void*>(map_.get()), sizeof(Map));
  }
  /// The map as loaded: every change of the previous trial undone.
  Map* fresh() {
    std::memcpy(static_cast<void*>(map_.get()), bytes_.data(), sizeof(Map));
    return map_.get();
  }

 private:
  std::unique_ptr<Map> map_;
  std::vector<unsigned char> bytes_;
};

SceneFrame frame_of(const AnalyticScene& scene, std::uint64_t seed) {
  SceneCamera cam;
  cam.seed = seed;
  return ccmap::test::render_scene(scene, cam);
}

/// Drop-offs: a ditch seen for three frames. Every bit of sampled drop-off records and of their
/// checks: the cell never answers a drop-off the reference does not, and the scrub resets and
/// counts the record within its frames.
template <typename Config>
void drop_campaign(float rays) {
  using F = Fixture<Config>;
  using Map = typename F::Map;
  AnalyticScene ditch;
  ditch.ditches.push_back(SceneDitch{1.2, -1.5, 2.2, 1.5, 0.40});
  auto trained = std::make_unique<Map>();
  ASSERT_EQ(trained->init(params<Config>(rays)), Status::kOk);
  for (std::uint64_t k = 1; k <= 3; ++k) {
    fold(*trained, frame_of(ditch, k), nullptr);
  }
  ASSERT_EQ(F::inconsistent(*trained), 0U) << "a writer did not keep a record's check";
  const std::vector<std::uint8_t> snapshot = save(*trained);
  auto reference = load<Map>(snapshot);
  ASSERT_EQ(F::inconsistent(*reference), 0U) << "a load did not reseal the records";
  // Half drop-off records, half any other live record (bounds, stamps).
  const std::size_t half = CCMAP_FREE_SPACE_UPSET_RECORDS / 2;
  std::vector<RecordAt> picked = F::sample(*reference, half, [](const FreeSpaceCell& r) { return is_drop(r); });
  ASSERT_EQ(picked.size(), half) << "the ditch shows no drop-off records: this scene tests nothing";
  for (const RecordAt& other : F::sample(*reference, half, [](const FreeSpaceCell& r) { return !is_drop(r) && has_bound(r); })) {
    picked.push_back(other);
  }
  const std::uint32_t scrub = ccmap::detail::ConfigScrubFrames<Config>::value;
  LoadedOnce<Map> trials(snapshot);
  std::size_t trial_count = 0;
  for (const RecordAt at : picked) {
    const auto& grid = *F::drops(*reference).layer[at.layer];
    // The cell's centre: its global index from the slot within the window.
    const ccmap::CellIndex min = grid.window_min();
    const std::int32_t side = grid.side();
    ccmap::CellIndex index{};
    for (std::int32_t j = 0; j < side; ++j) {
      for (std::int32_t i = 0; i < side; ++i) {
        const ccmap::CellIndex g{min.x + i, min.y + j};
        if (ccmap::grid::detail::buffer_offset_unchecked(g, side) == at.slot) {
          index = g;
        }
      }
    }
    const float w = grid.cell_width();
    const float x = (static_cast<float>(index.x) + 0.5F) * w;
    const float y = (static_cast<float>(index.y) + 0.5F) * w;
    const ccmap::QueryResult want = reference->query(x, y);
    for (int bit = 0; bit < 48; ++bit) {
      Map* const map = trials.fresh();
      F::flip(*map, at, bit);
      const ccmap::QueryResult got = map->query(x, y);
      if (got.cell_class == CellClass::kDropOff) {
        EXPECT_EQ(want.cell_class, CellClass::kDropOff) << "bit " << bit << " of a record made a drop-off";
      }
      EXPECT_EQ(scrub_frames(*map, scrub), 1U) << "bit " << bit << " not detected and counted once in " << scrub << " frames";
      const FreeSpaceCell& after = F::record(*map, at);
      EXPECT_TRUE(after.bound_code == 0U && after.evidence == 0U && after.state == 0U) << "bit " << bit << ": not reset";
      EXPECT_EQ(F::inconsistent(*map), 0U);
      EXPECT_NE(map->query(x, y).cell_class, CellClass::kDropOff) << "a reset record still answers a drop-off";
      ++trial_count;
    }
  }
  std::printf("[ upset ] drop-off records: %zu flips, every one detected within %u frames\n", trial_count, scrub);
}

/// Clearing: a box seen for four frames, then gone for two (its cells hold evidence against their
/// surface); every bit of sampled records with evidence and of their checks, then the frames in
/// which the reference clears the ghost: no cell is emptied that the reference keeps, and the flip
/// is counted once (at the read of the evidence or by the scrub).
template <typename Config>
void clearing_campaign(float rays) {
  using F = Fixture<Config>;
  using Map = typename F::Map;
  AnalyticScene with_box;
  with_box.boxes.push_back(SceneBox{1.40, -0.15, 1.70, 0.15, 0.15});
  const AnalyticScene empty;
  auto trained = std::make_unique<Map>();
  ASSERT_EQ(trained->init(params<Config>(rays)), Status::kOk);
  for (std::uint64_t k = 1; k <= 4; ++k) {
    fold(*trained, frame_of(with_box, k), nullptr);
  }
  for (std::uint64_t k = 100; k < 102; ++k) {
    fold(*trained, frame_of(empty, k), nullptr);
  }
  ASSERT_EQ(F::inconsistent(*trained), 0U) << "a writer did not keep a record's check";
  const std::vector<std::uint8_t> snapshot = save(*trained);
  const std::vector<SceneFrame> next = {frame_of(empty, 102), frame_of(empty, 103)};
  auto reference = load<Map>(snapshot);
  std::vector<RecordAt> picked =
      F::sample(*reference, CCMAP_FREE_SPACE_UPSET_RECORDS, [](const FreeSpaceCell& r) { return r.evidence > 0U; });
  ASSERT_EQ(picked.size(), static_cast<std::size_t>(CCMAP_FREE_SPACE_UPSET_RECORDS))
      << "no record holds evidence: this scene tests no clearing";
  FrameCounters ref{};
  for (const SceneFrame& f : next) {
    fold(*reference, f, &ref);
  }
  ASSERT_GT(ref.cleared_cells, 0U) << "the reference clears nothing in these frames: no clearing decision is tested";
  ASSERT_EQ(ref.corrupted_cells, 0U);
  const std::vector<unsigned char> want = F::cells(*reference);
  const std::uint32_t scrub = ccmap::detail::ConfigScrubFrames<Config>::value;
  LoadedOnce<Map> trials(snapshot);
  std::size_t trial_count = 0;
  for (const RecordAt at : picked) {
    for (int bit = 0; bit < 48; ++bit) {
      Map* const map = trials.fresh();
      F::flip(*map, at, bit);
      FrameCounters got{};
      for (const SceneFrame& f : next) {
        fold(*map, f, &got);
      }
      EXPECT_LE(got.cleared_cells, ref.cleared_cells) << "bit " << bit;
      // Every cell the flipped map emptied (all zero) the reference emptied too. Cells are 4-byte
      // aligned words of whole floats: compare cell by cell through the raw bytes.
      const std::vector<unsigned char> have = F::cells(*map);
      ASSERT_EQ(have.size(), want.size());
      std::size_t extra = 0;
      std::size_t cell_bytes = 0;
      std::size_t offset = 0;
      for (int c = 0; c <= Map::kCcmLayerCount; ++c) {
        const bool fine = c == Map::kCcmLayerCount;
        if (fine && !Map::kHasFine) {
          break;
        }
        std::size_t count = 0;
        if (fine) {
          if constexpr (Map::kHasFine) {
            count = map->fine_layer().cell_count();
            cell_bytes = sizeof(*map->fine_layer().storage());
          }
        } else {
          count = map->ccm_layer(c).cell_count();
          cell_bytes = sizeof(*map->ccm_layer(c).storage());
        }
        for (std::size_t i = 0; i < count; ++i, offset += cell_bytes) {
          bool zero_here = true;
          bool zero_ref = true;
          for (std::size_t b = 0; b < cell_bytes; ++b) {
            zero_here = zero_here && have[offset + b] == 0U;
            zero_ref = zero_ref && want[offset + b] == 0U;
          }
          extra += zero_here && !zero_ref ? 1U : 0U;
        }
      }
      EXPECT_EQ(extra, 0U) << "bit " << bit << " of a record cleared " << extra << " cells the reference keeps";
      const std::uint32_t later = scrub_frames(*map, scrub);
      EXPECT_EQ(got.corrupted_cells + later, 1U) << "bit " << bit << " not counted exactly once";
      EXPECT_EQ(F::inconsistent(*map), 0U);
      ++trial_count;
    }
  }
  std::printf("[ upset ] evidence records: %zu flips, none cleared a cell the reference keeps\n", trial_count);
}

TEST(FreeSpaceUpset, DropOffRecordFlipsAreDetectedResetAndNeverADropOff) { drop_campaign<CadreConfig>(1024.0F); }

TEST(FreeSpaceUpset, EvidenceRecordFlipsAreDetectedAndNeverClearACell) { clearing_campaign<CadreConfig>(1024.0F); }

TEST(FreeSpaceUpset, EveryLineOfSightDropOffRecordFlips) {
  drop_campaign<ccmap::WithEveryLineOfSight<CadreConfig>>(ccmap::detail::kFreeSpaceEveryRay);
}

TEST(FreeSpaceUpset, EveryLineOfSightEvidenceRecordFlips) {
  clearing_campaign<ccmap::WithEveryLineOfSight<CadreConfig>>(ccmap::detail::kFreeSpaceEveryRay);
}

}  // namespace
