// Hazards under single-event upsets (issue 29, item 6; docs/integration.md section 12): no upset
// may turn a hazard into open ground with every status OK.
//
// The scene: a CADRE stack trained on four stereo frames of the rock field (tests/support/
// cadre_frames.hpp). The reference is the untouched map, independent of the integrity code: the
// places its point query answers lethal (obstacle, steep, drop-off), the rover footprints over
// them that footprint_class() calls lethal, the straight paths through them that find a hazard,
// and the lethal pixels of a cost raster over them. A trial restores the stack from a saved copy
// of its bytes (in place: its internal pointers stay valid), flips bits, asks every one of those
// questions, runs the scrub's frames (empty frames: kScrubFrames of them check every cell) and
// asks again. Four campaigns, deterministic (fixed seeds):
//   one bit anywhere in the stack's bytes;       eight bits within 32 adjacent bytes anywhere;
//   one bit of a live cell (weight > 0);          eight bits of one live cell.
// A hazard is lost when the trial answers it traversable (cost 0 .. 252 for a pixel; a path with
// neither hazard nor unknown found) with status kOk: asserted never. Printed per campaign:
// trials detected (a call answered kCorrupt, the scrub or the pool counted a corrupted cell or
// slot, or an answer said upset), undetected (of which some answer changed), hazards answered
// unknown, hazards lost. Trials per campaign: CCMAP_HAZARD_UPSET_TRIALS, else
// CCMAP_HAZARD_UPSET_DEFAULT_TRIALS (1000; tests/map/CMakeLists.txt sets 150 for the emulator).
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "support/cadre_frames.hpp"

namespace ccmap {
namespace {

using CadreStack = Stack<CadreConfig>;
using Layers = detail::LayerSet<CadreConfig>;

struct Rng {
  std::uint64_t s;
  std::uint32_t next() {
    s ^= s << 13U;
    s ^= s >> 7U;
    s ^= s << 17U;
    return static_cast<std::uint32_t>(s >> 32U);
  }
  std::size_t below(std::size_t n) { return static_cast<std::size_t>((std::uint64_t{next()} * n) >> 32U); }
};

constexpr PathSweep kSweep{0.6F, 0.4F, 0.05F, kDefaultMaxUnknownShare};
constexpr std::size_t kMaxHazardPoints = 192U;

/// What the questions answered in one evaluation.
struct Verdict {
  bool corrupt = false;  ///< a call answered kCorrupt
  bool upset = false;    ///< an answer said upset (point query flag, footprint upset_share)
  bool changed = false;  ///< an answer's class or verdict differs from the untouched map's
  std::uint32_t unknown = 0U;  ///< hazards answered unknown (or refused)
  std::uint32_t lost = 0U;     ///< hazards answered traversable with status kOk
  std::vector<const char*> lost_where;
};

struct Scene {
  std::unique_ptr<CadreStack> stack = std::make_unique<CadreStack>();
  std::vector<unsigned char> saved;
  std::vector<PointXYZ> points;            ///< lethal places (z unused) and their classes
  std::vector<CellClass> point_class;
  std::vector<Footprint> footprints;       ///< lethal footprints
  std::vector<std::array<PathPoint, 2>> paths;  ///< paths that find a hazard
  CostmapSpec raster{};
  std::vector<std::uint8_t> raster_ref;
  std::vector<std::size_t> lethal_pixels;
  std::vector<std::size_t> live_cells;     ///< byte offsets of observed cells in the stack
  std::vector<std::size_t> live_sizes;
  PointXYZ origin{0.0F, 0.0F, 0.175F};

  const Layers& layers() const { return detail::PlannerAccess<CadreConfig>::view(*stack).layers(); }

  Verdict evaluate() const {
    Verdict v;
    const CadreStack& s = *stack;
    auto status = [&v](Status st) { v.corrupt = v.corrupt || st == Status::kCorrupt; };
    for (std::size_t i = 0; i < points.size(); ++i) {
      const QueryResult q = s.query(points[i].x, points[i].y);
      status(q.status);
      v.upset = v.upset || q.upset;
      v.changed = v.changed || q.status != Status::kOk || q.cell_class != point_class[i];
      if (q.status == Status::kOk && q.cell_class == CellClass::kTraversable) {
        ++v.lost;
        v.lost_where.push_back("point query");
      } else if (q.status != Status::kOk || q.cell_class == CellClass::kUnknown) {
        ++v.unknown;
      }
    }
    for (const Footprint& fp : footprints) {
      const FootprintResult f = query_footprint(s, fp);
      status(f.status);
      v.upset = v.upset || f.upset_share > 0.0F;
      const CellClass c = footprint_class(f, kDefaultMaxUnknownShare);
      v.changed = v.changed || !is_lethal(c);
      if (f.status == Status::kOk && c == CellClass::kTraversable) {
        ++v.lost;
        v.lost_where.push_back("footprint");
      } else if (!is_lethal(c)) {
        ++v.unknown;
      }
    }
    for (const auto& path : paths) {
      const PathResult p = query_path(s, path.data(), path.size(), kSweep);
      status(p.status);
      v.upset = v.upset || p.hazard.upset_share > 0.0F || p.unknown.upset_share > 0.0F;
      v.changed = v.changed || !p.hazard_found;
      if (p.status == Status::kOk && !p.hazard_found && !p.unknown_found) {
        ++v.lost;
        v.lost_where.push_back("path");
      } else if (!p.hazard_found) {
        ++v.unknown;
      }
    }
    std::vector<std::uint8_t> cost(raster_ref.size());
    const Status cs = fill_costmap(s, raster, cost.data(), cost.size(), nullptr);
    status(cs);
    for (const std::size_t px : lethal_pixels) {
      v.changed = v.changed || cs != Status::kOk || cost[px] != kCostLethal;
      if (cs == Status::kOk && cost[px] < kCostInscribed) {
        ++v.lost;
        v.lost_where.push_back("costmap pixel");
      } else if (cs != Status::kOk || cost[px] == kCostUnknown) {
        ++v.unknown;
      }
    }
    return v;
  }
};

/// Trains the stack, finds the hazards of the untouched map and saves its bytes.
Scene& scene() {
  static std::unique_ptr<Scene> built;  // the campaigns share it
  if (built != nullptr) {
    return *built;
  }
  built = std::make_unique<Scene>();
  Scene& sc = *built;
  CadreStack& s = *sc.stack;
  EXPECT_EQ(s.init(default_stack_params(0.04F)), Status::kOk);
  for (int k = 0; k < 4; ++k) {
    test::CadreFrameSpec spec = test::cadre_sequence_spec(k % 2, 240, 180);
    spec.invalid_share = 0.02F;
    spec.seed = 7U + static_cast<std::uint32_t>(k);
    const test::CadreFrame frame = test::make_cadre_frame(spec);
    EXPECT_EQ(s.update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, nullptr),
              Status::kOk);
  }
  // Lethal places: the point query over the mapped ground every 4 cm (cell centres of the finest
  // width: no point on an edge), thinned evenly to at most kMaxHazardPoints.
  std::vector<PointXYZ> lethal;
  std::vector<CellClass> classes;
  float min_x = 1e9F, max_x = -1e9F, min_y = 1e9F, max_y = -1e9F;
  for (int iy = -60; iy < 60; ++iy) {
    for (int ix = 5; ix < 110; ++ix) {
      const float x = 0.02F + 0.04F * static_cast<float>(ix);
      const float y = 0.02F + 0.04F * static_cast<float>(iy);
      const QueryResult q = s.query(x, y);
      if (q.status == Status::kOk && is_lethal(q.cell_class)) {
        lethal.push_back(PointXYZ{x, y, 0.0F});
        classes.push_back(q.cell_class);
        min_x = x < min_x ? x : min_x;
        max_x = x > max_x ? x : max_x;
        min_y = y < min_y ? y : min_y;
        max_y = y > max_y ? y : max_y;
      }
    }
  }
  const std::size_t stride = lethal.size() / kMaxHazardPoints + 1U;
  for (std::size_t i = 0; i < lethal.size(); i += stride) {
    sc.points.push_back(lethal[i]);
    sc.point_class.push_back(classes[i]);
  }
  // Footprints (the rover body, heading x) over 8 of them, and 1.4 m straight paths through 3.
  const std::size_t step = sc.points.size() / 8U + 1U;
  for (std::size_t i = 0; i < sc.points.size(); i += step) {
    const PointXYZ& p = sc.points[i];
    const Footprint fp{p.x, p.y, 1.0F, 0.0F, 0.6F, 0.4F};
    const FootprintResult f = query_footprint(s, fp);
    if (f.status == Status::kOk && is_lethal(footprint_class(f, kDefaultMaxUnknownShare))) {
      sc.footprints.push_back(fp);
    }
    if (sc.paths.size() < 3U && p.x > 1.3F) {
      const std::array<PathPoint, 2> path{{{p.x - 1.0F, p.y}, {p.x + 0.4F, p.y}}};
      const PathResult r = query_path(s, path.data(), path.size(), kSweep);
      if (r.status == Status::kOk && r.hazard_found) {
        sc.paths.push_back(path);
      }
    }
  }
  // The cost raster over the lethal places' bounding box (5 cm pixels, at most 32 x 32).
  const float span = (max_x - min_x) > (max_y - min_y) ? (max_x - min_x) : (max_y - min_y);
  const float res = 0.05F;
  std::uint32_t side = static_cast<std::uint32_t>(span / res) + 2U;
  side = side > 32U ? 32U : side;
  sc.raster = CostmapSpec{0.5F * (min_x + max_x), 0.5F * (min_y + max_y), res, side, 0.0F};
  sc.raster_ref.assign(static_cast<std::size_t>(side) * side, 0U);
  EXPECT_EQ(fill_costmap(s, sc.raster, sc.raster_ref.data(), sc.raster_ref.size(), nullptr), Status::kOk);
  for (std::size_t px = 0; px < sc.raster_ref.size(); ++px) {
    if (sc.raster_ref[px] == kCostLethal) {
      sc.lethal_pixels.push_back(px);
    }
  }
  // Live cells: every observed cell of every layer, as byte offsets in the stack.
  const Layers& layers = sc.layers();
  const auto* base = reinterpret_cast<const unsigned char*>(&s);
  for (const KalmanCell& c : layers.fine_storage) {
    if (c.weight > 0.0F) {
      sc.live_cells.push_back(static_cast<std::size_t>(reinterpret_cast<const unsigned char*>(&c) - base));
      sc.live_sizes.push_back(sizeof c);
    }
  }
  for (const CcmCell& c : layers.ccm_storage) {
    if (c.weight > 0.0F) {
      sc.live_cells.push_back(static_cast<std::size_t>(reinterpret_cast<const unsigned char*>(&c) - base));
      sc.live_sizes.push_back(sizeof c);
    }
  }
  sc.saved.assign(base, base + sizeof(CadreStack));
  // The untouched map answers every question as the reference says, before and after the scrub.
  const Verdict ref = sc.evaluate();
  EXPECT_FALSE(ref.changed || ref.corrupt || ref.upset || ref.lost > 0U) << "the reference is not reproducible";
  std::printf("[ hazards ] CADRE stack %zu bytes, %zu live cells; %zu lethal places (of %zu), %zu footprints, "
              "%zu paths, %zu lethal pixels of %u x %u\n",
              sizeof(CadreStack), sc.live_cells.size(), sc.points.size(), lethal.size(), sc.footprints.size(),
              sc.paths.size(), sc.lethal_pixels.size(), side, side);
  return sc;
}

#ifndef CCMAP_HAZARD_UPSET_DEFAULT_TRIALS
#define CCMAP_HAZARD_UPSET_DEFAULT_TRIALS 1000
#endif

std::size_t trials_per_campaign() {
  const char* env = std::getenv("CCMAP_HAZARD_UPSET_TRIALS");
  const long n = env != nullptr ? std::strtol(env, nullptr, 10) : 0L;
  return n > 0 ? static_cast<std::size_t>(n) : std::size_t{CCMAP_HAZARD_UPSET_DEFAULT_TRIALS};
}

enum class Target { kAnywhere, kLiveCell };

void campaign(Target target, unsigned bits, std::uint64_t seed, const char* name) {
  Scene& sc = scene();
  ASSERT_GE(sc.points.size(), 20U) << "the scene has too few hazards for the campaign to mean anything";
  ASSERT_GE(sc.footprints.size(), 4U);
  ASSERT_GE(sc.paths.size(), 2U);
  ASSERT_GE(sc.lethal_pixels.size(), 10U);
  CadreStack& s = *sc.stack;
  auto* bytes = reinterpret_cast<unsigned char*>(&s);
  const std::size_t size = sizeof(CadreStack);
  Rng rng{seed};
  const std::size_t trials = trials_per_campaign();
  std::size_t detected = 0U, undetected = 0U, undetected_changed = 0U, lost_trials = 0U;
  std::uint64_t unknown_answers = 0U, lost_answers = 0U;
  for (std::size_t t = 0; t < trials; ++t) {
    std::memcpy(bytes, sc.saved.data(), size);
    const std::uint32_t cells_before = s.total_counters().corrupted_cells + s.total_counters().corrupted_slots;
    // The flips: `bits` distinct bits of one span (32 adjacent bytes anywhere, or one live cell).
    std::size_t begin = 0U;
    std::size_t span = 0U;
    if (target == Target::kAnywhere) {
      span = bits == 1U ? 1U : 32U;
      begin = rng.below(size - span + 1U);
    } else {
      const std::size_t c = rng.below(sc.live_cells.size());
      begin = sc.live_cells[c];
      span = sc.live_sizes[c];
    }
    std::vector<std::size_t> chosen;
    while (chosen.size() < bits) {
      const std::size_t b = rng.below(span * 8U);
      bool seen = false;
      for (const std::size_t x : chosen) seen = seen || x == b;
      if (!seen) chosen.push_back(b);
    }
    for (const std::size_t b : chosen) {
      bytes[begin + b / 8U] = static_cast<unsigned char>(bytes[begin + b / 8U] ^ (1U << (b % 8U)));
    }
    const Verdict before = sc.evaluate();
    bool refused = false;
    for (std::uint32_t f = 0; f < detail::ConfigScrubFrames<CadreConfig>::value; ++f) {
      refused = s.update_frame(nullptr, 0U, sc.origin, nullptr) == Status::kCorrupt || refused;
    }
    const Verdict after = sc.evaluate();
    const std::uint32_t cells_after = s.total_counters().corrupted_cells + s.total_counters().corrupted_slots;
    const bool seen = before.corrupt || after.corrupt || refused || before.upset || after.upset ||
                      cells_after != cells_before;
    detected += seen ? 1U : 0U;
    undetected += seen ? 0U : 1U;
    undetected_changed += !seen && (before.changed || after.changed) ? 1U : 0U;
    unknown_answers += before.unknown + after.unknown;
    lost_answers += before.lost + after.lost;
    if (before.lost + after.lost > 0U) {
      ++lost_trials;
      ADD_FAILURE() << name << " trial " << t << ": a hazard answered traversable with status OK ("
                    << (before.lost > 0U ? before.lost_where[0] : after.lost_where[0])
                    << (before.lost > 0U ? ", before the scrub" : ", after the scrub") << "), flips at byte " << begin;
    }
  }
  std::memcpy(bytes, sc.saved.data(), size);
  std::printf("[ hazards ] %s: %zu trials: %zu detected, %zu undetected (%zu of them changed an answer), "
              "%llu hazard answers unknown, %zu trials lost a hazard (%llu answers)\n",
              name, trials, detected, undetected, undetected_changed, static_cast<unsigned long long>(unknown_answers),
              lost_trials, static_cast<unsigned long long>(lost_answers));
  EXPECT_EQ(lost_trials, 0U);
}

TEST(HazardUpsets, OneBitAnywhereNeverOpensAHazard) { campaign(Target::kAnywhere, 1U, 0x9E3779B97F4A7C15ULL, "one bit anywhere"); }
TEST(HazardUpsets, EightBitsAnywhereNeverOpenAHazard) { campaign(Target::kAnywhere, 8U, 0xD1B54A32D192ED03ULL, "eight bits anywhere"); }
TEST(HazardUpsets, OneBitOfALiveCellNeverOpensAHazard) { campaign(Target::kLiveCell, 1U, 0x8CB92BA72F3D8DD7ULL, "one bit of a live cell"); }
TEST(HazardUpsets, EightBitsOfALiveCellNeverOpenAHazard) { campaign(Target::kLiveCell, 8U, 0xA0761D6478BD642FULL, "eight bits of a live cell"); }

}  // namespace
}  // namespace ccmap
