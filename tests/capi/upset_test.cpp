// Fault injection (issue 23, item 1; docs/integration.md, "Radiation: single-event upsets"): one
// random bit flipped anywhere in the C API's caller-provided storage of a mapped CADRE map, then
// what a rover does next through the C API: queries, a move, a sensor-frame update, queries, a
// footprint, a path, and the scrub's frames. Every trial starts from the same bytes (the storage
// is restored; it never moves, so its internal pointers stay valid).
//
// Asserted for every trial, beside what the sanitizers assert (the `asan` preset: no
// out-of-bounds access, no undefined behaviour):
//  - every status is a valid one, every number finite;
//  - once a call answers CCMAP_CORRUPT, no later call answers with map content;
//  - a flip in a cell or its check: no answer used the cell (the answers equal those of the same
//    map with that cell set by the test to the distrusted cell, map/detail/integrity.hpp: every
//    place it answers is unknown, upset; before and after the update, wherever the scrub had not
//    yet reset it), and the cell is reset and counted within the scrub's frames unless a move
//    cleared it first;
//  - a flip in a free-space record (4 B per cell, not checked: docs/integration.md section 12):
//    every class answered is the reference's, or unknown, or a drop-off, or the reference's was a
//    drop-off (a record can add or remove a drop-off, move its bound, or hasten the clearing of
//    a cell that rays contradict; never make a cell traversable, steep or an obstacle that the
//    map without the flip did not answer so, except where the flip removed a drop-off);
//  - any other flip: the answers are those of the map without the flip, or the flip was detected
//    (CCMAP_CORRUPT, a held-point slot dropped); a silent change is a failure.
// The share of each outcome is printed. The test finds the cells in the storage through the C++
// stack's own accessors (the C API places the stack after its header); the library does not.
//
// Two campaigns: flips anywhere (mostly cells: they are 62 % of the bytes), and flips outside the
// cells and their checks (the bookkeeping, pools, scratch and counters, where the sanitizers look
// for an access outside the storage). Trials: CCMAP_UPSET_TRIALS per campaign (default 200,
// deterministic: fixed seeds); the asan build registers 4000 each (tests/capi/CMakeLists.txt).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "ccmap/ccmap.h"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/planner/footprint.hpp"
#include "support/cadre_frames.hpp"

namespace ccmap {
namespace {

using CadreStack = Stack<CadreConfig>;
using Layers = detail::LayerSet<CadreConfig>;

ccmap_cadre_storage g_storage;  // the map
ccmap_cadre_storage g_backup;   // its bytes before each trial

bool valid_status(std::int32_t s) { return s >= CCMAP_OK && s <= CCMAP_MISALIGNED; }

/// Outputs of a trial, flattened (statuses, classes and numbers), and what they said.
struct Outputs {
  std::vector<double> values;
  std::vector<int> classes;  ///< every class answered, in call order
  bool corrupt = false;      ///< some call answered CCMAP_CORRUPT
  bool content_after_corrupt = false;
  bool invalid = false;      ///< an invalid status or a non-finite number
  std::string why;

  void status(std::int32_t s, const char* what) {
    if (!valid_status(s)) {
      invalid = true;
      why = std::string("invalid status from ") + what;
    }
    if (corrupt && s == CCMAP_OK) {  // a refused map answers nothing until init
      content_after_corrupt = true;
      why = std::string("map content after CCMAP_CORRUPT from ") + what;
    }
    corrupt = corrupt || s == CCMAP_CORRUPT;
    values.push_back(static_cast<double>(s));
  }
  void number(double v, const char* what) {
    if (!std::isfinite(v)) {
      invalid = true;
      why = std::string("non-finite number from ") + what;
    }
    values.push_back(v);
  }
};

void query(ccmap_map* map, float x, float y, Outputs& out) {
  ccmap_query_result r{};
  out.status(ccmap_query(map, x, y, &r), "ccmap_query");
  for (const double v : {static_cast<double>(r.layer), static_cast<double>(r.cell_class)}) out.number(v, "ccmap_query");
  out.classes.push_back(static_cast<int>(r.cell_class));
  out.number(static_cast<double>(r.upset), "ccmap_query");
  for (const float v : {r.cell_width_m, r.height_m, r.slope_x, r.slope_y, r.inclination, r.normal_variance,
                        r.elevation_variance, r.weight}) {
    out.number(v, "ccmap_query");
  }
  for (std::int32_t layer = 0; layer < CadreStack::kLayerCount; ++layer) {
    ccmap_query_result q{};
    out.status(ccmap_query_layer(map, layer, x, y, &q), "ccmap_query_layer");
    out.number(static_cast<double>(q.cell_class), "ccmap_query_layer");
    out.classes.push_back(static_cast<int>(q.cell_class));
    for (const float v : {q.height_m, q.slope_x, q.slope_y, q.normal_variance, q.elevation_variance, q.weight}) {
      out.number(v, "ccmap_query_layer");
    }
  }
}

void footprint(ccmap_map* map, float x, float y, Outputs& out) {
  const ccmap_footprint f{x, y, 1.0F, 0.0F, 0.6F, 0.4F};
  ccmap_footprint_result r{};
  out.status(ccmap_query_footprint(map, &f, &r), "ccmap_query_footprint");
  out.number(static_cast<double>(r.worst_class), "footprint");
  out.classes.push_back(static_cast<int>(r.worst_class));
  for (const float v : {r.unknown_share, r.max_step_m, r.max_inclination, r.min_height_m, r.max_height_m,
                        r.upset_share}) {
    out.number(v, "footprint");
  }
}

/// The answers about the ground around (x, y) (cells of every layer there and beside it).
void answers_around(ccmap_map* map, float x, float y, Outputs& out) {
  for (const float d : {-0.3F, -0.05F, 0.0F, 0.05F, 0.3F}) {
    query(map, x + d, y, out);
    query(map, x, y + d, out);
  }
  footprint(map, x, y, out);
}

/// Fixed answers over the mapped ground.
void fixed_answers(ccmap_map* map, Outputs& out) {
  for (float y = -1.6F; y <= 1.61F; y += 0.8F) {
    for (float x = 0.4F; x <= 3.61F; x += 0.8F) {
      query(map, x, y, out);
    }
  }
  footprint(map, 1.5F, 0.0F, out);
  const float path[] = {0.5F, 0.0F, 3.0F, 0.4F};
  const ccmap_path_sweep sweep = {0.6F, 0.4F, 0.1F, CCMAP_DEFAULT_MAX_UNKNOWN_SHARE};
  ccmap_path_result p{};
  out.status(ccmap_query_path(map, path, 2U, &sweep, &p), "ccmap_query_path");
  for (const double v : {static_cast<double>(p.hazard_found), static_cast<double>(p.first_hazard_m),
                         static_cast<double>(p.unknown_found), static_cast<double>(p.first_unknown_m),
                         static_cast<double>(p.checked_m)}) {
    out.number(v, "ccmap_query_path");
  }
}

void frame_counters(const ccmap_frame_counters& c, Outputs& out) {
  // Every point counter (the frame's work); the upset counters are reported, not compared.
  for (const std::uint32_t v : {c.received, c.used, c.rejected_non_finite, c.rejected_out_of_range, c.outside_map,
                                c.too_noisy, c.gated_finer, c.gated_occluded, c.gated_held, c.gated_pool_full,
                                c.gated_admitted, c.gated_dropped, c.reseeded_cells, c.merged_cells}) {
    out.values.push_back(static_cast<double>(v));
  }
}

/// Where a flipped byte lies.
struct Location {
  enum Kind { kHeader, kCell, kCheck, kRecord, kOther } kind = kOther;
  bool fine = false;      ///< the finest layer's (else a CCM layer's)
  std::size_t cell = 0U;  ///< index in fine_storage / ccm_storage
};

const CadreStack& stack_in(const ccmap_cadre_storage& storage) {
  const std::size_t offset = ccmap_storage_size(CCMAP_PRESET_CADRE) - sizeof(CadreStack);
  return *reinterpret_cast<const CadreStack*>(storage.bytes + offset);
}
Layers& layers_in(ccmap_cadre_storage& storage) {
  return const_cast<Layers&>(detail::PlannerAccess<CadreConfig>::view(stack_in(storage)).layers());
}

Location locate(std::size_t byte) {
  Location l;
  const std::size_t stack_offset = ccmap_storage_size(CCMAP_PRESET_CADRE) - sizeof(CadreStack);
  if (byte < stack_offset) {
    l.kind = Location::kHeader;
    return l;
  }
  const Layers& layers = layers_in(g_storage);
  const auto* at = g_storage.bytes + byte;
  auto inside = [at](const void* begin, std::size_t size) {
    const auto* b = static_cast<const unsigned char*>(begin);
    return at >= b && at < b + size;
  };
  auto index = [at](const void* begin, std::size_t element) {
    return static_cast<std::size_t>(at - static_cast<const unsigned char*>(begin)) / element;
  };
  if (inside(layers.fine_storage, sizeof layers.fine_storage)) {
    l = Location{Location::kCell, true, index(layers.fine_storage, sizeof(KalmanCell))};
  } else if (inside(layers.ccm_storage, sizeof layers.ccm_storage)) {
    l = Location{Location::kCell, false, index(layers.ccm_storage, sizeof(CcmCell))};
  } else if (inside(layers.checks.fine, sizeof layers.checks.fine)) {
    l = Location{Location::kCheck, true, index(layers.checks.fine, sizeof(detail::CellCheck))};
  } else if (inside(layers.checks.ccm, sizeof layers.checks.ccm)) {
    l = Location{Location::kCheck, false, index(layers.checks.ccm, sizeof(detail::CellCheck))};
  } else {
    // The free-space records: one per cell of every layer, contiguous from the finest layer's.
    const detail::DropRecords* drops = detail::PlannerAccess<CadreConfig>::view(stack_in(g_storage)).drops();
    const std::size_t records = Layers::kFineCellCount + Layers::kCcmCellCount;
    if (drops != nullptr && drops->layer[0] != nullptr &&
        inside(drops->layer[0]->storage(), records * sizeof(detail::FreeSpaceCell))) {
      l = Location{Location::kRecord, true, index(drops->layer[0]->storage(), sizeof(detail::FreeSpaceCell))};
    }
  }
  return l;
}

/// Centre (map frame) of the cell in storage slot `cell` of the finest or the CCM storage.
void cell_centre(const Location& l, float* x, float* y) {
  const Layers& layers = layers_in(g_storage);
  int layer = 0;
  std::size_t slot = l.cell;
  if (!l.fine) {
    layer = 1;
    while (slot >= Layers::capacity(layer)) {
      slot -= Layers::capacity(layer);
      ++layer;
    }
  }
  const std::int32_t side = Layers::side(layer);
  const CellIndex min = layers.window_min(layer);
  const auto rx = static_cast<std::int32_t>(slot % static_cast<std::size_t>(side));
  const auto ry = static_cast<std::int32_t>(slot / static_cast<std::size_t>(side));
  const std::int32_t gx = min.x + grid::wrap(rx - min.x, side);
  const std::int32_t gy = min.y + grid::wrap(ry - min.y, side);
  *x = grid::cell_centre(gx, layers.widths[layer]);
  *y = grid::cell_centre(gy, layers.widths[layer]);
}

/// The cell's bytes and check, for the test's distrusted-cell reference.
struct CellBytes {
  unsigned char cell[sizeof(CcmCell)];
  detail::CellCheck check;
};
void* cell_address(const Location& l) {
  Layers& layers = layers_in(g_storage);
  return l.fine ? static_cast<void*>(&layers.fine_storage[l.cell]) : static_cast<void*>(&layers.ccm_storage[l.cell]);
}
detail::CellCheck& check_ref(const Location& l) {
  Layers& layers = layers_in(g_storage);
  return l.fine ? layers.checks.fine[l.cell] : layers.checks.ccm[l.cell];
}
std::size_t cell_size(const Location& l) { return l.fine ? sizeof(KalmanCell) : sizeof(CcmCell); }
bool cell_is_empty(const Location& l) {
  const auto* b = static_cast<const unsigned char*>(cell_address(l));
  for (std::size_t i = 0; i < cell_size(l); ++i) {
    if (b[i] != 0U) return false;
  }
  return check_ref(l) == 0U;
}

/// The answers with the flipped cell set to the distrusted cell, its check consistent (then put
/// back as it was).
template <typename Fn>
Outputs with_cell_emptied(const Location& l, Fn&& answers) {
  CellBytes saved{};
  std::memcpy(saved.cell, cell_address(l), cell_size(l));
  saved.check = check_ref(l);
  if (l.fine) {
    const KalmanCell distrusted = detail::distrusted_cell<KalmanCell>();
    std::memcpy(cell_address(l), &distrusted, sizeof distrusted);
    check_ref(l) = detail::cell_signature(distrusted);
  } else {
    const CcmCell distrusted = detail::distrusted_cell<CcmCell>();
    std::memcpy(cell_address(l), &distrusted, sizeof distrusted);
    check_ref(l) = detail::cell_signature(distrusted);
  }
  Outputs out;
  answers(out);
  std::memcpy(cell_address(l), saved.cell, cell_size(l));
  check_ref(l) = saved.check;
  return out;
}

struct Campaign {
  std::vector<PointXYZ> frame_points;
  ccmap_pose pose{};
  Outputs reference_before;
  Outputs reference_after;
  // Outcome counts: [location kind][outcome]
  enum Outcome { kMasked, kRefused, kResetCell, kDroppedSlot, kClearedByMove, kDropOnly, kOutcomes };
  std::size_t counts[5][kOutcomes] = {};
  std::size_t trials = 0U;
};

ccmap_map* handle() { return reinterpret_cast<ccmap_map*>(&g_storage); }

/// The trial's calls after the flip: answers, a move, the update, answers, the scrub's frames.
void run_after_flip(Campaign& c, const Location& l, float cx, float cy, Outputs& before, Outputs& after,
                    std::uint32_t* corrupted_cells, std::uint32_t* corrupted_slots, bool* reset_at_update, bool* cleared,
                    std::string* failure) {
  ccmap_map* map = handle();
  const bool cell_flip = l.kind == Location::kCell || l.kind == Location::kCheck;
  fixed_answers(map, before);
  if (cell_flip) {
    answers_around(map, cx, cy, before);
    const Outputs emptied = with_cell_emptied(l, [&](Outputs& o) {
      fixed_answers(map, o);
      answers_around(map, cx, cy, o);
    });
    if (!before.corrupt && emptied.values != before.values) {
      *failure = "an answer before the update used the flipped cell";
    }
  }
  before.status(ccmap_move_to(map, 0.2F, 0.0F), "ccmap_move_to");
  if (cell_flip) *cleared = cell_is_empty(l);
  ccmap_frame_counters fc{};
  after.status(ccmap_update_frame_sensor(map, &c.frame_points[0].x, c.frame_points.size(), &c.pose, &fc),
               "ccmap_update_frame_sensor");
  frame_counters(fc, after);
  *corrupted_cells += fc.corrupted_cells;
  *corrupted_slots += fc.corrupted_slots;
  *reset_at_update = fc.corrupted_cells > 0U;
  fixed_answers(map, after);
  if (cell_flip && !*reset_at_update && !*cleared) {
    answers_around(map, cx, cy, after);
    const Outputs emptied = with_cell_emptied(l, [&](Outputs& o) {
      fixed_answers(map, o);
      answers_around(map, cx, cy, o);
    });
    Outputs flipped_answers;
    fixed_answers(map, flipped_answers);
    answers_around(map, cx, cy, flipped_answers);
    if (!after.corrupt && emptied.values != flipped_answers.values && failure->empty()) {
      *failure = "an answer after the update used the flipped cell";
    }
  }
  const float origin[3] = {0.2F, 0.0F, 0.175F};
  for (std::uint32_t f = 0; f < detail::ConfigScrubFrames<CadreConfig>::value; ++f) {
    ccmap_frame_counters empty{};
    const ccmap_status s = ccmap_update_frame(map, nullptr, nullptr, 0U, origin, &empty);
    after.status(s, "ccmap_update_frame (scrub)");
    *corrupted_cells += empty.corrupted_cells;
    *corrupted_slots += empty.corrupted_slots;
  }
}

/// outside_cells: every flip lands outside the cells and their checks (the header, the
/// bookkeeping, the held-point pools, the scratch, the counters), where a random flip rarely goes.
/// The map mapped and saved in g_backup, the trial frame and the reference outputs.
void prepare(Campaign& c) {
  ccmap_map* map = nullptr;
  ASSERT_EQ(ccmap_place(&g_storage, sizeof g_storage, CCMAP_PRESET_CADRE, &map), CCMAP_OK);
  ccmap_params params{};
  ASSERT_EQ(ccmap_default_params(CCMAP_PRESET_CADRE, &params), CCMAP_OK);
  ASSERT_EQ(ccmap_init(map, &params), CCMAP_OK);
  // Map the ground ahead, as a rover does, then keep the next frame for the trials.
  for (int k = 0; k < 4; ++k) {
    test::CadreFrameSpec spec = test::cadre_sequence_spec(k % 2, 160, 120);
    spec.invalid_share = 0.02F;
    const test::CadreFrame frame = test::make_cadre_frame(spec);
    ccmap_pose pose{};
    std::memcpy(pose.rotation, &frame.pose.rotation[0][0], sizeof pose.rotation);
    std::memcpy(pose.translation, &frame.pose.translation, sizeof pose.translation);
    if (k < 3) {
      ASSERT_EQ(ccmap_update_frame_sensor(map, &frame.sensor_points[0].x, frame.sensor_points.size(), &pose, nullptr),
                CCMAP_OK);
    } else {
      c.frame_points = frame.sensor_points;
      c.pose = pose;
      c.pose.translation[0] += 0.2F;
    }
  }
  std::memcpy(&g_backup, &g_storage, ccmap_storage_size(CCMAP_PRESET_CADRE));
  std::uint32_t cells = 0U;
  std::uint32_t slots = 0U;
  bool reset = false;
  bool cleared = false;
  std::string failure;
  run_after_flip(c, Location{}, 0.0F, 0.0F, c.reference_before, c.reference_after, &cells, &slots, &reset, &cleared,
                 &failure);
  ASSERT_FALSE(c.reference_before.corrupt || c.reference_after.corrupt || c.reference_before.invalid ||
               c.reference_after.invalid)
      << "the reference run failed: " << c.reference_before.why << c.reference_after.why;
  ASSERT_EQ(cells + slots, 0U) << "the reference run found corrupted cells";
}

/// One trial: restore, flip bit `bit` of byte `byte`, run, judge. Returns the failure ("" if none).
std::string trial(Campaign& c, std::size_t byte, unsigned bit) {
  std::memcpy(&g_storage, &g_backup, ccmap_storage_size(CCMAP_PRESET_CADRE));
  const Location l = locate(byte);
  float cx = 0.0F;
  float cy = 0.0F;
  const bool cell_flip = l.kind == Location::kCell || l.kind == Location::kCheck;
  if (cell_flip) cell_centre(l, &cx, &cy);
  g_storage.bytes[byte] = static_cast<unsigned char>(g_storage.bytes[byte] ^ (1U << bit));
  Outputs before;
  Outputs after;
  std::uint32_t cells = 0U;
  std::uint32_t slots = 0U;
  bool reset = false;
  bool cleared = false;
  std::string failure;
  run_after_flip(c, l, cx, cy, before, after, &cells, &slots, &reset, &cleared, &failure);
  const bool refused = before.corrupt || after.corrupt;
  if (failure.empty() && (before.invalid || after.invalid || before.content_after_corrupt || after.content_after_corrupt)) {
    failure = before.why + after.why;
  }
  Campaign::Outcome outcome = Campaign::kMasked;
  if (refused) {
    outcome = Campaign::kRefused;
  } else if (cell_flip) {
    if (cleared) {
      outcome = Campaign::kClearedByMove;
    } else if (cells == 1U) {
      outcome = Campaign::kResetCell;
    } else if (failure.empty()) {
      failure = "a flipped cell was not reset within the scrub's frames (" + std::to_string(cells) + " reset)";
    }
  } else if (slots > 0U || cells > 0U) {
    outcome = cells > 0U ? Campaign::kResetCell : Campaign::kDroppedSlot;
  } else if (l.kind == Location::kRecord) {
    if (before.values != c.reference_before.values || after.values != c.reference_after.values) {
      outcome = Campaign::kDropOnly;
      const auto safe = [](const std::vector<int>& got, const std::vector<int>& want) {
        if (got.size() != want.size()) return false;
        for (std::size_t i = 0; i < got.size(); ++i) {
          if (got[i] != want[i] && got[i] != CCMAP_CLASS_UNKNOWN && got[i] != CCMAP_CLASS_DROP &&
              want[i] != CCMAP_CLASS_DROP) {
            return false;
          }
        }
        return true;
      };
      if (!(safe(before.classes, c.reference_before.classes) && safe(after.classes, c.reference_after.classes)) &&
          failure.empty()) {
        failure = "a flipped free-space record made a cell answer a class other than unknown or drop-off";
      }
    }
  } else if ((before.values != c.reference_before.values || after.values != c.reference_after.values) &&
             failure.empty()) {
    failure = "a silent change: answers differ from the map without the flip, and nothing was detected";
  }
  ++c.counts[l.kind][outcome];
  ++c.trials;
  if (!failure.empty()) {
    failure = "bit " + std::to_string(bit) + " of byte " + std::to_string(byte) + " (location kind " +
              std::to_string(static_cast<int>(l.kind)) + ", cell " + std::to_string(l.cell) + (l.fine ? " fine" : " ccm") +
              "): " + failure;
  }
  return failure;
}

void report(const Campaign& c, const char* what, std::size_t failures) {
  const char* kinds[] = {"header", "cells", "checks", "free-space records", "other (bookkeeping, pools, scratch, counters)"};
  std::printf("[ upsets ] %zu trials: %s\n", c.trials, what);
  std::printf("[ upsets ] %-46s %7s %8s %8s %8s %8s %8s %8s\n", "location", "trials", "masked", "refused", "reset",
              "slot", "cleared", "drop/unk");
  std::size_t total[Campaign::kOutcomes] = {};
  for (int k = 0; k < 5; ++k) {
    std::size_t n = 0U;
    for (int o = 0; o < Campaign::kOutcomes; ++o) {
      n += c.counts[k][o];
      total[o] += c.counts[k][o];
    }
    std::printf("[ upsets ] %-46s %7zu %8zu %8zu %8zu %8zu %8zu %8zu\n", kinds[k], n, c.counts[k][Campaign::kMasked],
                c.counts[k][Campaign::kRefused], c.counts[k][Campaign::kResetCell], c.counts[k][Campaign::kDroppedSlot],
                c.counts[k][Campaign::kClearedByMove], c.counts[k][Campaign::kDropOnly]);
  }
  const double n = c.trials > 0U ? static_cast<double>(c.trials) : 1.0;
  std::printf("[ upsets ] shares: masked %.1f %%, refused (CCMAP_CORRUPT) %.1f %%, cell reset %.1f %%, slot dropped "
              "%.1f %%, cleared by a move %.1f %%; failures %zu\n",
              100.0 * static_cast<double>(total[Campaign::kMasked]) / n,
              100.0 * static_cast<double>(total[Campaign::kRefused]) / n,
              100.0 * static_cast<double>(total[Campaign::kResetCell]) / n,
              100.0 * static_cast<double>(total[Campaign::kDroppedSlot]) / n,
              100.0 * static_cast<double>(total[Campaign::kClearedByMove]) / n, failures);
}

/// outside_cells: every flip lands outside the cells and their checks (the header, the
/// bookkeeping, the held-point pools, the scratch, the counters), where a random flip rarely goes.
void run_campaign(std::size_t trials, std::uint64_t seed, bool outside_cells) {
  Campaign c;
  prepare(c);
  if (::testing::Test::HasFatalFailure()) return;
  const std::size_t size = ccmap_storage_size(CCMAP_PRESET_CADRE);
  test::detail_frames::XorShift random{seed};
  std::size_t failures = 0U;
  for (std::size_t t = 0; t < trials && failures <= 20U; ++t) {
    std::size_t byte = 0U;
    Location l;
    do {
      byte = (static_cast<std::size_t>(random.next()) * 65536U + random.next() % 65536U) % size;
      l = locate(byte);
    } while (outside_cells && (l.kind == Location::kCell || l.kind == Location::kCheck));
    const std::string failure = trial(c, byte, random.next() % 8U);
    if (!failure.empty()) {
      ++failures;
      ADD_FAILURE() << "trial " << t << ": " << failure;
    }
  }
  std::memcpy(&g_storage, &g_backup, size);
  const std::string what = std::string("one random bit flipped in ") +
                           (outside_cells ? "the non-cell bytes of the " : "the ") + std::to_string(size) +
                           " bytes of CADRE storage (seed " + std::to_string(seed) + ")";
  report(c, what.c_str(), failures);
  EXPECT_EQ(failures, 0U);
}

std::size_t trials_from_environment(std::size_t fallback) {
  const char* text = std::getenv("CCMAP_UPSET_TRIALS");
  if (text == nullptr) return fallback;
  const long value = std::strtol(text, nullptr, 10);
  return value > 0 ? static_cast<std::size_t>(value) : fallback;
}

TEST(Upset, RandomFlipsInTheCApiStorage) { run_campaign(trials_from_environment(200U), 0x5EEDC0DEULL, false); }

TEST(Upset, RandomFlipsOutsideTheCells) { run_campaign(trials_from_environment(200U), 0xB00C4EE9ULL, true); }

// One bit in CCMAP_UPSET_BOOKKEEPING_BIT_STEP below: 1 (every bit) on the host; 3 under the
// emulator (tests/capi/CMakeLists.txt), where every byte still sees two or three of its bits.
#ifndef CCMAP_UPSET_BOOKKEEPING_BIT_STEP
#define CCMAP_UPSET_BOOKKEEPING_BIT_STEP 1
#endif

TEST(Upset, EveryBitOfTheBookkeeping) {
  // Every bit of the values that index memory or give the cells their meaning: the header, the
  // parameters, each grid's binding (storage pointer, side, widths, window), the widths and kept
  // windows, and the 512 bytes after the counters (initialised word, seal, scrub cursor, the
  // front's index scale and shift, routing bounds).
  constexpr std::size_t kBitStep = CCMAP_UPSET_BOOKKEEPING_BIT_STEP;
  static_assert(kBitStep >= 1U && kBitStep < 8U, "every byte must see at least one of its bits");
  Campaign c;
  prepare(c);
  if (::testing::Test::HasFatalFailure()) return;
  const std::size_t stack_offset = ccmap_storage_size(CCMAP_PRESET_CADRE) - sizeof(CadreStack);
  const CadreStack& stack = stack_in(g_storage);
  const Layers& layers = layers_in(g_storage);
  auto offset_of = [](const void* p) {
    return static_cast<std::size_t>(static_cast<const unsigned char*>(p) - g_storage.bytes);
  };
  struct Range {
    std::size_t from;
    std::size_t to;
  };
  const Range ranges[] = {
      {0U, stack_offset},
      {offset_of(&stack.params()), offset_of(&stack.params()) + sizeof(StackParams)},
      {offset_of(&layers.fine), offset_of(&layers.checks)},
      {offset_of(&stack.total_counters()), offset_of(&stack.total_counters()) + 512U},
  };
  std::size_t failures = 0U;
  for (const Range& r : ranges) {
    for (std::size_t at = r.from * 8U; at < r.to * 8U && failures <= 20U; at += kBitStep) {
      const std::string failure = trial(c, at / 8U, static_cast<unsigned>(at % 8U));
      if (!failure.empty()) {
        ++failures;
        ADD_FAILURE() << failure;
      }
    }
  }
  std::memcpy(&g_storage, &g_backup, ccmap_storage_size(CCMAP_PRESET_CADRE));
  const std::string which = kBitStep == 1U ? std::string("every bit") : "one bit in " + std::to_string(kBitStep);
  report(c, (which + " of the header, parameters, grid bindings, widths, kept windows and the 512 bytes after the counters").c_str(),
         failures);
  EXPECT_EQ(failures, 0U);
}

TEST(Upset, ACorruptMapStillGivesItsCountersAndRecoversWithInit) {
  ccmap_map* map = nullptr;
  ASSERT_EQ(ccmap_place(&g_storage, sizeof g_storage, CCMAP_PRESET_CADRE, &map), CCMAP_OK);
  ccmap_params params{};
  ASSERT_EQ(ccmap_default_params(CCMAP_PRESET_CADRE, &params), CCMAP_OK);
  ASSERT_EQ(ccmap_init(map, &params), CCMAP_OK);
  const float origin[3] = {0.0F, 0.0F, 0.175F};
  ASSERT_EQ(ccmap_update_frame(map, nullptr, nullptr, 0U, origin, nullptr), CCMAP_OK);
  // One bit of the coverage tau in the stack's parameters.
  const CadreStack& stack = stack_in(g_storage);
  auto* tau = reinterpret_cast<unsigned char*>(const_cast<float*>(&stack.params().coverage_tau));
  tau[1] = static_cast<unsigned char>(tau[1] ^ 0x04U);
  ccmap_query_result q{};
  EXPECT_EQ(ccmap_query(map, 1.0F, 0.0F, &q), CCMAP_CORRUPT);
  EXPECT_EQ(ccmap_update_frame(map, nullptr, nullptr, 0U, origin, nullptr), CCMAP_CORRUPT);
  ccmap_counters counters{};
  EXPECT_EQ(ccmap_get_counters(map, &counters), CCMAP_CORRUPT);
  EXPECT_EQ(counters.rejected_frames, 1U) << "the refused frame must be counted and the counters written";
  EXPECT_EQ(ccmap_init(map, &params), CCMAP_OK) << "init must recover a map whose state failed its check";
  EXPECT_EQ(ccmap_query(map, 1.0F, 0.0F, &q), CCMAP_UNKNOWN);
  EXPECT_EQ(ccmap_get_counters(map, &counters), CCMAP_OK);
}

TEST(Upset, EveryHeaderBitIsRefused) {
  ccmap_map* map = nullptr;
  ASSERT_EQ(ccmap_place(&g_storage, sizeof g_storage, CCMAP_PRESET_CADRE, &map), CCMAP_OK);
  ccmap_params params{};
  ASSERT_EQ(ccmap_default_params(CCMAP_PRESET_CADRE, &params), CCMAP_OK);
  ASSERT_EQ(ccmap_init(map, &params), CCMAP_OK);
  const std::size_t header = ccmap_storage_size(CCMAP_PRESET_CADRE) - sizeof(CadreStack);
  for (std::size_t bit = 0; bit < header * 8U; ++bit) {
    unsigned char& byte = g_storage.bytes[bit / 8U];
    byte = static_cast<unsigned char>(byte ^ (1U << (bit % 8U)));
    ccmap_query_result r{};
    const ccmap_status q = ccmap_query(map, 1.0F, 0.0F, &r);
    const ccmap_status m = ccmap_move_to(map, 0.0F, 0.0F);
    const bool in_use = bit < 96U;  // magic, preset, check; the last 4 bytes are padding
    if (in_use) {
      // CCMAP_CORRUPT; a flip that makes the map's magic the exchange's is a foreign handle.
      EXPECT_TRUE(q == CCMAP_CORRUPT || q == CCMAP_INVALID_ARGUMENT) << "header bit " << bit << ": " << ccmap_status_string(q);
      EXPECT_TRUE(m == CCMAP_CORRUPT || m == CCMAP_INVALID_ARGUMENT) << "header bit " << bit;
      EXPECT_EQ(ccmap_layer_count(map), 0) << "header bit " << bit << ": a damaged header was trusted";
    } else {
      EXPECT_EQ(m, CCMAP_OK) << "padding bit " << bit;
    }
    byte = static_cast<unsigned char>(byte ^ (1U << (bit % 8U)));
    ASSERT_EQ(ccmap_move_to(map, 0.0F, 0.0F), CCMAP_OK) << "header bit " << bit << " restored";
  }
}

}  // namespace
}  // namespace ccmap
