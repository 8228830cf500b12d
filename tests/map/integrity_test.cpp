// Single-event upsets (map/detail/integrity.hpp; docs/integration.md, "Radiation: single-event
// upsets") against independent references:
//  - the cell check against a bit-level model written from the documented formula (where each
//    bit of a cell lands in the 16-bit check), never against the library's word-level code;
//  - detection by brute force: every single-bit flip of every word of a cell of each kind (and of
//    its check) is seen; adjacent double flips are seen; the share of all double flips seen;
//  - every writer of a stack (per-point updates, Kalman batches, the change rule, moves, the
//    motion pass, snapshot load, exchange merges) keeps every check: the model's check of every
//    cell equals the stored one after each of them, for every preset and both CCM cells;
//  - a flipped cell contributes nothing to any answer (the answers equal those of the map with
//    that cell emptied by the test), is reset and counted within the stated scrub frames, and
//    stays visible after more writes to it;
//  - the scrub covers every cell within kScrubFrames frames, not sooner;
//  - a flipped bookkeeping bit (parameters, windows, storage bindings, derived constants) makes
//    every call answer kCorrupt until init; a flipped held-point slot is dropped and counted.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/map/update/held_pool.hpp"
#include "ccmap/map/update/kalman_batch.hpp"
#include "ccmap/persistence/exchange.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/planner/footprint.hpp"
#include "support/cadre_frames.hpp"
#include "support/hash_unit.hpp"

namespace ccmap {
namespace {

using test::hash_unit;

// ---- the bit-level models of the check (docs/integration.md, map/detail/integrity.hpp) ----------
// 64-bit form: bit b of 32-bit word k (little-endian) lies at position p = b + 32 (k mod 2) of
// 64-bit lane j = k / 2; the lane is rotated right by 3j (p -> p - 3j mod 64); the high half of
// the result is rotated right by 2 and XORed onto the low half (h -> h - 2 mod 32), and the 32
// bits are folded to 16 (f -> f mod 16).
// 32-bit form: word k is rotated right by 3k mod 32 (b -> b - 3k mod 32), folded to 16 bits.
// The check is the XOR of the check bits of the cell's set bits.
template <unsigned kLaneBits>
int model_check_bit(std::size_t word, std::size_t bit) {
  if constexpr (kLaneBits == 64U) {
    const std::size_t lane = word / 2U;
    const std::size_t p = bit + 32U * (word % 2U);
    const std::size_t q = (p + 64U * 4U - 3U * lane) % 64U;
    const std::size_t f = q < 32U ? q : (q - 32U + 32U - 2U) % 32U;
    return static_cast<int>(f % 16U);
  } else {
    const std::size_t f = (bit + 32U * 64U - (3U * word) % 32U) % 32U;
    return static_cast<int>(f % 16U);
  }
}

template <unsigned kLaneBits = detail::kCheckLaneBits>
std::uint16_t model_check(const void* data, std::size_t bytes) {
  const auto* b = static_cast<const unsigned char*>(data);
  std::uint32_t check = 0U;
  for (std::size_t i = 0; i < bytes * 8U; ++i) {
    if (((b[i / 8U] >> (i % 8U)) & 1U) != 0U) {
      check ^= 1U << model_check_bit<kLaneBits>(i / 32U, i % 32U);
    }
  }
  return static_cast<std::uint16_t>(check);
}

template <typename Cell>
Cell random_cell(std::uint32_t seed) {
  Cell cell{};
  unsigned char bytes[sizeof(Cell)];
  for (std::size_t i = 0; i < sizeof(Cell); ++i) {
    bytes[i] = static_cast<unsigned char>(hash_unit(seed * 131U + static_cast<std::uint32_t>(i), 7U) * 256.0F);
  }
  std::memcpy(&cell, bytes, sizeof cell);
  return cell;
}

template <typename Cell>
Cell flipped(const Cell& cell, std::size_t bit) {
  unsigned char bytes[sizeof(Cell)];
  std::memcpy(bytes, &cell, sizeof cell);
  bytes[bit / 8U] = static_cast<unsigned char>(bytes[bit / 8U] ^ (1U << (bit % 8U)));
  Cell out{};
  std::memcpy(&out, bytes, sizeof out);
  return out;
}

template <typename Cell, unsigned kLaneBits>
void signature_matches_the_model(const char* name) {
  EXPECT_EQ(detail::cell_signature<kLaneBits>(Cell{}), 0U) << name << ": the never-observed cell must have check 0";
  for (std::uint32_t seed = 1; seed <= 200; ++seed) {
    const Cell cell = random_cell<Cell>(seed);
    ASSERT_EQ(detail::cell_signature<kLaneBits>(cell), model_check<kLaneBits>(&cell, sizeof cell))
        << name << " (" << kLaneBits << "-bit form): check of random cell " << seed;
    // The incremental form a writer uses: fold(wide(a) ^ wide(b)) = check(a) ^ check(b).
    const Cell other = random_cell<Cell>(seed + 1000U);
    ASSERT_EQ(detail::fold_signature(detail::cell_signature_wide<kLaneBits>(cell) ^
                                     detail::cell_signature_wide<kLaneBits>(other)),
              static_cast<std::uint16_t>(model_check<kLaneBits>(&cell, sizeof cell) ^
                                         model_check<kLaneBits>(&other, sizeof other)))
        << name << " (" << kLaneBits << "-bit form): the writers' update of the check is not linear";
  }
}

TEST(Integrity, CheckMatchesTheBitLevelModel) {
  static_assert(detail::kCheckLaneBits == (sizeof(void*) == 8U ? 64U : 32U), "the form follows the register width");
  signature_matches_the_model<CcmCell, 64>("CcmCell");
  signature_matches_the_model<CcmPaperCell, 64>("CcmPaperCell");
  signature_matches_the_model<KalmanCell, 64>("KalmanCell");
  signature_matches_the_model<OmgCell, 64>("OmgCell");
  // The 32-bit targets' form, checked here too (the library suite does not run on them).
  signature_matches_the_model<CcmCell, 32>("CcmCell");
  signature_matches_the_model<CcmPaperCell, 32>("CcmPaperCell");
  signature_matches_the_model<KalmanCell, 32>("KalmanCell");
  signature_matches_the_model<OmgCell, 32>("OmgCell");
}

template <typename Cell, unsigned kLaneBits>
void every_single_flip_is_detected(const char* name) {
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    const Cell cell = random_cell<Cell>(seed);
    const std::uint16_t check = model_check<kLaneBits>(&cell, sizeof cell);
    for (std::size_t bit = 0; bit < sizeof(Cell) * 8U; ++bit) {
      const std::uint16_t now = detail::cell_signature<kLaneBits>(flipped(cell, bit));
      ASSERT_NE(now, check) << name << ": a flip of bit " << bit % 32U << " of word " << bit / 32U << " went unseen";
      const std::uint32_t changed = static_cast<std::uint32_t>(now ^ check);
      EXPECT_EQ(changed & (changed - 1U), 0U) << name << ": one flipped bit must change exactly one check bit";
    }
    for (int bit = 0; bit < 16; ++bit) {  // an upset in the check itself
      const auto stored = static_cast<std::uint16_t>(check ^ (1U << bit));
      EXPECT_NE(detail::cell_signature<kLaneBits>(cell), stored) << name << ": a flip of check bit " << bit << " went unseen";
    }
  }
}

TEST(Integrity, EverySingleBitFlipOfEveryCellKindIsDetected) {
  every_single_flip_is_detected<CcmCell, 64>("CcmCell");
  every_single_flip_is_detected<CcmPaperCell, 64>("CcmPaperCell");
  every_single_flip_is_detected<KalmanCell, 64>("KalmanCell");
  every_single_flip_is_detected<OmgCell, 64>("OmgCell");
  every_single_flip_is_detected<CcmCell, 32>("CcmCell");
  every_single_flip_is_detected<CcmPaperCell, 32>("CcmPaperCell");
  every_single_flip_is_detected<KalmanCell, 32>("KalmanCell");
  every_single_flip_is_detected<OmgCell, 32>("OmgCell");
}

template <typename Cell, unsigned kLaneBits>
double double_flips(const char* name) {
  const Cell cell = random_cell<Cell>(3U);
  const std::uint16_t check = detail::cell_signature<kLaneBits>(cell);
  constexpr std::size_t kBits = sizeof(Cell) * 8U;
  constexpr std::size_t kWords = sizeof(Cell) / 4U;
  // Adjacent bits (inside a word and across word boundaries) and the same bit of words up to
  // three apart: what a multiple-bit upset of neighbouring SRAM cells flips.
  for (std::size_t bit = 0; bit + 1U < kBits; ++bit) {
    EXPECT_NE(detail::cell_signature<kLaneBits>(flipped(flipped(cell, bit), bit + 1U)), check)
        << name << ": adjacent bits " << bit << ", " << bit + 1U << " cancel";
  }
  for (std::size_t distance = 1; distance <= 3; ++distance) {
    for (std::size_t word = 0; word + distance < kWords; ++word) {
      for (std::size_t b = 0; b < 32U; ++b) {
        EXPECT_NE(detail::cell_signature<kLaneBits>(flipped(flipped(cell, 32U * word + b), 32U * (word + distance) + b)), check)
            << name << ": bit " << b << " of words " << word << " and " << word + distance << " cancel";
      }
    }
  }
  std::size_t seen = 0U;
  std::size_t pairs = 0U;
  for (std::size_t a = 0; a < kBits; ++a) {
    for (std::size_t b = a + 1U; b < kBits; ++b) {
      ++pairs;
      seen += model_check_bit<kLaneBits>(a / 32U, a % 32U) != model_check_bit<kLaneBits>(b / 32U, b % 32U) ? 1U : 0U;
    }
  }
  return static_cast<double>(seen) / static_cast<double>(pairs);
}

template <unsigned kLaneBits>
void adjacent_double_flips_are_detected() {
  const double full = double_flips<CcmCell, kLaneBits>("CcmCell");
  const double paper = double_flips<CcmPaperCell, kLaneBits>("CcmPaperCell");
  const double kalman = double_flips<KalmanCell, kLaneBits>("KalmanCell");
  std::printf("[ integrity ] %u-bit form: double flips detected: CcmCell %.4f, CcmPaperCell %.4f, KalmanCell/OmgCell %.4f\n",
              kLaneBits, full, paper, kalman);
  // Each bit lands on one of 16 check bits, about evenly: about 1 - (n/16 - 1) / (n - 1) of the
  // pairs of n bits (0.941 for 320 bits, 0.947 for 96).
  EXPECT_GT(full, 0.94) << kLaneBits << "-bit form: share of double flips detected in a 10-float cell";
  EXPECT_GT(paper, 0.94);
  EXPECT_GT(kalman, 0.94);
}

TEST(Integrity, AdjacentDoubleFlipsAreDetected) {
  adjacent_double_flips_are_detected<64>();
  adjacent_double_flips_are_detected<32>();
}

/// Two CCM cells and their checks, the members the writer hooks use of a LayerSet.
struct TwoCells {
  using CcmCellType = CcmCell;
  using FineCell = KalmanCell;
  CcmCell ccm_storage[2]{};
  KalmanCell fine_storage[1]{};
  detail::CellChecks<1, 2> checks{};
};

TEST(Integrity, AnUpsetStaysVisibleAfterMoreWritesToTheCell) {
  // A CCM cell and its check, kept by the writer hook as the update path keeps them.
  TwoCells layers;
  CcmCell& cell = layers.ccm_storage[1];
  for (int i = 0; i < 20; ++i) {
    detail::write_cell(layers, cell, [i](CcmCell& written) {
      detail::ccm_update_unchecked(written, 0.01F * static_cast<float>(i % 5), -0.02F,
                                   0.3F + 0.001F * static_cast<float>(i), 1.0F, 1000.0F);
    });
  }
  ASSERT_TRUE(detail::cell_intact(layers, cell)) << "the writer hook lost the check of a cell it wrote";
  cell = flipped(cell, 6U * 32U + 3U);  // a low mantissa bit of s_zz: no invariant can see it
  const auto discrepancy = static_cast<std::uint16_t>(detail::cell_signature(cell) ^ layers.checks.ccm[1]);
  ASSERT_NE(discrepancy, 0U);
  // More writes, through runs as the back half makes them (interleaved with another cell).
  detail::CheckRun<CcmCell> run;
  for (int i = 0; i < 50; ++i) {
    CcmCell& target = layers.ccm_storage[i % 3 == 0 ? 0 : 1];
    run.write(layers, target, [i](CcmCell& written) {
      detail::ccm_update_unchecked(written, 0.02F, 0.01F * static_cast<float>(i % 7), 0.31F, 1.0F, 1000.0F);
    });
  }
  run.close(layers);
  EXPECT_TRUE(detail::cell_intact(layers, layers.ccm_storage[0])) << "runs lost the check of the intact cell";
  EXPECT_EQ(static_cast<std::uint16_t>(detail::cell_signature(cell) ^ layers.checks.ccm[1]), discrepancy)
      << "writes after an upset must keep it visible (the discrepancy is constant over writes)";
}

// ---- stacks -------------------------------------------------------------------------------------

template <typename Config>
const detail::LayerSet<Config>& layers_of(const Stack<Config>& stack) {
  return detail::PlannerAccess<Config>::view(stack).layers();
}
template <typename Config>
detail::LayerSet<Config>& mutable_layers(Stack<Config>& stack) {
  return const_cast<detail::LayerSet<Config>&>(layers_of(stack));
}

/// Cells whose stored check differs from the model's check of their bits (0: every writer kept
/// every check).
template <typename Config>
std::size_t inconsistent_cells(const Stack<Config>& stack) {
  const auto& layers = layers_of(stack);
  using Layers = detail::LayerSet<Config>;
  std::size_t bad = 0U;
  if constexpr (Layers::kHasFine) {
    for (std::size_t i = 0; i < Layers::kFineCellCount; ++i) {
      bad += model_check(&layers.fine_storage[i], sizeof layers.fine_storage[i]) != layers.checks.fine[i] ? 1U : 0U;
    }
  }
  if constexpr (Layers::kCcmLayerCount > 0) {
    for (std::size_t i = 0; i < Layers::kCcmCellCount; ++i) {
      bad += model_check(&layers.ccm_storage[i], sizeof layers.ccm_storage[i]) != layers.checks.ccm[i] ? 1U : 0U;
    }
  }
  return bad;
}

template <typename Config>
std::size_t observed_cells(const Stack<Config>& stack) {
  const auto& layers = layers_of(stack);
  using Layers = detail::LayerSet<Config>;
  std::size_t n = 0U;
  if constexpr (Layers::kHasFine) {
    for (const auto& c : layers.fine_storage) n += c.weight > 0.0F ? 1U : 0U;
  }
  if constexpr (Layers::kCcmLayerCount > 0) {
    for (const auto& c : layers.ccm_storage) n += c.weight > 0.0F ? 1U : 0U;
  }
  return n;
}

test::CadreFrame small_frame(int k, float x, float y) {
  test::CadreFrameSpec spec = test::cadre_sequence_spec(k, 200, 150);
  spec.sensor_x = x;
  spec.sensor_y = y;
  spec.invalid_share = 0.02F;
  spec.far_share = 0.03F;
  return test::make_cadre_frame(spec);
}

/// Drives a stack through every writer, checking every cell's check after each one.
template <typename Config>
void every_writer_keeps_the_checks(const char* name, bool gate) {
  StackParams params = default_stack_params(Config::kDefaultFinestCellWidthM);
  if (!gate) params.outlier_gate_sigma = 0.0F;
  auto a = std::make_unique<Stack<Config>>();
  auto b = std::make_unique<Stack<Config>>();
  ASSERT_EQ(a->init(params), Status::kOk);
  ASSERT_EQ(b->init(params), Status::kOk);
  auto consistent = [&](const char* step) {
    ASSERT_EQ(inconsistent_cells(*a), 0U) << name << (gate ? " (gate on)" : " (gate off)") << ": after " << step;
  };
  for (int k = 0; k < 6; ++k) {
    const float x = 0.15F * static_cast<float>(k);
    const float y = -0.05F * static_cast<float>(k);
    const test::CadreFrame frame = small_frame(k, x, y);
    if (k % 2 == 1) {
      ASSERT_EQ(a->move_to(x, y, 0.01F), Status::kOk);
      consistent("an uncertain move (the motion pass)");
    } else {
      ASSERT_EQ(a->move_to(x, y), Status::kOk);
      consistent("a move");
    }
    // A pose jump in frame 3: the change rule re-seeds and merges cells.
    Pose pose = frame.pose;
    if (k == 3) pose.translation.z += 0.2F;
    ASSERT_EQ(a->update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), pose, nullptr), Status::kOk);
    consistent("a sensor-frame update");
    ASSERT_EQ(a->update_frame(frame.map_points.data(), frame.map_points.size(), frame.sensor_origin, nullptr),
              Status::kOk);
    consistent("a map-frame update");
    ASSERT_EQ(b->move_to(x + 0.5F, y), Status::kOk);
    ASSERT_EQ(b->update_frame(frame.map_points.data(), frame.map_points.size(), frame.sensor_origin, nullptr),
              Status::kOk);
  }
  ASSERT_GT(observed_cells(*a), 100U) << name << ": the frames observed too little to test";
  // Exchange: a delta of b and a snapshot of b merged into a.
  MapExchange<Config> ea;
  MapExchange<Config> eb;
  ASSERT_EQ(ea.init(*a, ExchangeParams{1U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  ASSERT_EQ(eb.init(*b, ExchangeParams{2U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  std::vector<std::uint8_t> delta(MapExchange<Config>::max_delta_size());
  std::size_t written = 0U;
  ASSERT_EQ(eb.export_delta(delta.data(), delta.size(), ExportOptions{0.0F, 0}, &written, nullptr), Status::kOk);
  ASSERT_EQ(ea.merge_delta(delta.data(), written, nullptr), Status::kOk);
  consistent("an exchange delta merge");
  std::vector<std::uint8_t> snap(snapshot_size<Config>());
  ASSERT_EQ(save_snapshot(*b, snap.data(), snap.size(), &written), Status::kOk);
  ASSERT_EQ(merge_snapshot(*a, snap.data(), snap.size(), CellIndex{0, 0}, 0.0F, nullptr), Status::kOk);
  consistent("a snapshot merge");
  ASSERT_EQ(load_snapshot(*a, snap.data(), snap.size()), Status::kOk);
  consistent("a snapshot load");
  EXPECT_EQ(a->total_counters().corrupted_cells, 0U) << name << ": the scrub reset an intact cell";
  EXPECT_EQ(a->state_status(), Status::kOk);
}

TEST(Integrity, EveryWriterKeepsEveryCheck) {
  every_writer_keeps_the_checks<CadreConfig>("CADRE", true);
  every_writer_keeps_the_checks<CadreConfig>("CADRE", false);
  every_writer_keeps_the_checks<PaperCell<CadreConfig>>("CADRE, paper cell", true);
  every_writer_keeps_the_checks<SingleOmgConfig>("single OMG", true);
  every_writer_keeps_the_checks<SingleKalmanConfig>("single Kalman", true);
  every_writer_keeps_the_checks<SingleCcmConfig>("single CCM", true);
}

/// A CADRE stack after a few frames around the origin.
std::unique_ptr<Stack<CadreConfig>> mapped_cadre() {
  auto stack = std::make_unique<Stack<CadreConfig>>();
  EXPECT_EQ(stack->init(default_stack_params(0.04F)), Status::kOk);
  for (int k = 0; k < 4; ++k) {
    const test::CadreFrame frame = small_frame(k, 0.0F, 0.0F);
    EXPECT_EQ(stack->update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, nullptr),
              Status::kOk);
  }
  return stack;
}

/// Every answer a planner or an integrator can get about the ground around (x, y): the point
/// query, each layer's answer, the pooled CCM cells there and a footprint, field by field (the
/// structs have padding).
std::vector<double> answers_around(const Stack<CadreConfig>& stack, float x, float y) {
  std::vector<double> out;
  auto add = [&out](const QueryResult& q) {
    out.insert(out.end(), {static_cast<double>(q.status), static_cast<double>(q.layer), q.cell_width_m, q.height_m,
                           q.slope_x, q.slope_y, q.inclination, q.normal_variance, q.elevation_variance, q.weight,
                           static_cast<double>(q.cell_class)});
  };
  for (float dy = -0.3F; dy <= 0.31F; dy += 0.1F) {
    for (float dx = -0.3F; dx <= 0.31F; dx += 0.1F) {
      add(stack.query(x + dx, y + dy));
      for (int layer = 0; layer < Stack<CadreConfig>::kLayerCount; ++layer) {
        add(stack.query_layer(layer, x + dx, y + dy));
      }
    }
  }
  for (int layer = 1; layer < Stack<CadreConfig>::kLayerCount; ++layer) {
    CellIndex index{};
    if (layers_of(stack).locate(layer, x, y, &index)) {
      const CcmCell c = stack.pooled_cell(layer, index);
      out.insert(out.end(), {c.weight, c.mean_x, c.mean_y, c.mean_z, c.s_xx, c.s_yy, c.s_zz, c.s_xz, c.s_yz, c.s_xy});
    }
  }
  const FootprintResult f = query_footprint(stack, Footprint{x, y, 1.0F, 0.0F, 0.6F, 0.4F});
  out.insert(out.end(), {static_cast<double>(f.status), static_cast<double>(f.worst_class), f.unknown_share,
                         f.max_step_m, f.max_inclination, f.min_height_m, f.max_height_m});
  return out;
}

/// A known cell of `layer` (its storage and its centre), near the rover.
template <typename Cell>
Cell* known_cell(Stack<CadreConfig>& stack, int layer, float* cx, float* cy) {
  auto& layers = mutable_layers(stack);
  for (float r = 0.5F; r < 4.0F; r += 0.05F) {
    CellIndex index{};
    if (!layers.locate(layer, r, 0.1F, &index)) continue;
    const QueryResult q = stack.query_layer(layer, r, 0.1F);
    if (q.status != Status::kOk || q.cell_class != CellClass::kTraversable) continue;
    *cx = grid::cell_centre(index.x, layers.widths[layer]);
    *cy = grid::cell_centre(index.y, layers.widths[layer]);
    if constexpr (std::is_same_v<Cell, KalmanCell>) {
      return layers.fine.cell(index);
    } else {
      return layers.ccm_grid(layer).cell(index);
    }
  }
  return nullptr;
}

/// The answers at and around a cell of `layer` whose check failed (a flipped bit), before and
/// after the scrub reset it: every one equals the map's with the cell set to the distrusted cell
/// by the test (map/detail/integrity.hpp, "distrust"), and the place the cell answers is unknown
/// with upset set on its layer, in the point query and in a footprint over it (no coarser layer
/// answers it). The scrub leaves the distrusted cell (counted once), and a point folded into it
/// clears the mark.
template <typename Cell>
void a_flipped_cell_is_distrusted(int layer, std::size_t bit, const char* what) {
  auto stack = mapped_cadre();
  float cx = 0.0F;
  float cy = 0.0F;
  Cell* cell = known_cell<Cell>(*stack, layer, &cx, &cy);
  ASSERT_NE(cell, nullptr) << "no traversable cell on layer " << layer;
  auto& layers = mutable_layers(*stack);
  const Cell original = *cell;
  const detail::CellCheck original_check = detail::check_of(layers, *cell);
  const Cell distrusted = detail::distrusted_cell<Cell>();
  EXPECT_TRUE(std::signbit(distrusted.weight) && distrusted.weight == 0.0F);
  // The answers of the map with the cell distrusted (set by the test, its check consistent).
  *cell = distrusted;
  detail::check_of(layers, *cell) = detail::cell_signature(distrusted);
  const std::vector<double> reference = answers_around(*stack, cx, cy);
  // The map with the cell's bit flipped.
  *cell = flipped(original, bit);
  detail::check_of(layers, *cell) = original_check;
  auto expect_upset_place = [&](const char* when) {
    const QueryResult own = stack->query_layer(layer, cx, cy);
    EXPECT_EQ(own.status, Status::kUnknown) << what << " " << when << ": the distrusted cell answered";
    EXPECT_TRUE(own.upset) << what << " " << when << ": the answer does not say why";
    // The point query: a finer layer that knows the place answers it (the cell is not the
    // answering one); else the place is unknown, upset. Layers 0 and 1 (the constant layer's
    // hazards come from the first CCM layer) always answer upset.
    const QueryResult q = stack->query(cx, cy);
    if (layer <= 1 || q.status != Status::kOk || q.layer >= layer) {
      EXPECT_TRUE(q.status == Status::kUnknown && q.upset) << what << " " << when << ": another layer answered";
    }
    if (layer > 1) {
      return;  // finer layers know most of a coarse cell: no footprint stands on it alone
    }
    const FootprintResult f = query_footprint(*stack, Footprint{cx, cy, 1.0F, 0.0F, 0.3F, 0.3F});
    EXPECT_EQ(f.status, Status::kOk);
    EXPECT_GT(f.upset_share, 0.0F) << what << " " << when << ": the footprint does not count the upset part";
    EXPECT_NE(footprint_class(f, 1.0F), CellClass::kTraversable)
        << what << " " << when << ": a footprint with an upset part is traversable even at full tolerance";
  };
  expect_upset_place("before the scrub");
  EXPECT_EQ(answers_around(*stack, cx, cy), reference)
      << what << ": an answer differs from the map with the cell distrusted";
  // Reset and counted by the scrub within kScrubFrames frames (empty frames: nothing else writes).
  const std::uint32_t frames = detail::ConfigScrubFrames<CadreConfig>::value;
  std::uint32_t found_after = 0U;
  const PointXYZ origin{0.0F, 0.0F, 0.175F};
  for (std::uint32_t f = 1; f <= frames && found_after == 0U; ++f) {
    FrameCounters counters{};
    ASSERT_EQ(stack->update_frame(nullptr, 0U, origin, &counters), Status::kOk);
    if (counters.corrupted_cells > 0U) {
      EXPECT_EQ(counters.corrupted_cells, 1U) << what << ": the scrub reset intact cells too";
      found_after = f;
    }
  }
  EXPECT_GT(found_after, 0U) << what << ": not reset within " << frames << " frames";
  EXPECT_EQ(stack->total_counters().corrupted_cells, 1U);
  EXPECT_EQ(std::memcmp(cell, &distrusted, sizeof distrusted), 0) << what << ": the reset cell is not the distrusted cell";
  EXPECT_EQ(detail::check_of(layers, *cell), detail::cell_signature(distrusted));
  EXPECT_EQ(inconsistent_cells(*stack), 0U);
  expect_upset_place("after the scrub");
  EXPECT_EQ(answers_around(*stack, cx, cy), reference) << what << ": after the scrub, an answer differs";
  // Later scrub passes leave it alone (it agrees with its check): still distrusted.
  for (std::uint32_t f = 0; f < frames; ++f) {
    ASSERT_EQ(stack->update_frame(nullptr, 0U, origin, nullptr), Status::kOk);
  }
  EXPECT_EQ(stack->total_counters().corrupted_cells, 1U);
  expect_upset_place("a scrub pass later");
}

TEST(Integrity, AFlippedCellIsDistrustedUntilTheScrubResetsItAndAfter) {
  // Kalman: a low mantissa bit of the height; the weight's exponent (a known cell forgotten).
  a_flipped_cell_is_distrusted<KalmanCell>(0, 0U * 32U + 2U, "Kalman height mantissa");
  a_flipped_cell_is_distrusted<KalmanCell>(0, 2U * 32U + 28U, "Kalman weight exponent");
  // CCM: s_zz's sign (a negative normal variance), a low mantissa bit of s_xz, the weight.
  a_flipped_cell_is_distrusted<CcmCell>(1, 6U * 32U + 31U, "CCM s_zz sign");
  a_flipped_cell_is_distrusted<CcmCell>(1, 7U * 32U + 1U, "CCM s_xz mantissa");
  a_flipped_cell_is_distrusted<CcmCell>(2, 0U * 32U + 23U, "CCM weight exponent");
  a_flipped_cell_is_distrusted<CcmCell>(4, 9U * 32U + 30U, "CCM s_xy exponent, coarsest layer");
}

TEST(Integrity, APointFoldedIntoADistrustedCellClearsTheMark) {
  // The cell functions: every update of a distrusted cell gives a positive weight and the
  // statistics of an empty cell's first point (the mark is the weight's sign, nothing else).
  {
    CcmCell d = detail::distrusted_cell<CcmCell>();
    CcmCell e{};
    detail::ccm_update_unchecked(d, 0.01F, -0.02F, 0.3F, 1.0F, 1000.0F);
    detail::ccm_update_unchecked(e, 0.01F, -0.02F, 0.3F, 1.0F, 1000.0F);
    EXPECT_FALSE(detail::distrust_mark(d));
    EXPECT_EQ(d.weight, 1.0F);
    EXPECT_TRUE(d.mean_x == e.mean_x && d.mean_y == e.mean_y && d.mean_z == e.mean_z && d.s_zz == e.s_zz);
    CcmCell m = detail::distrusted_cell<CcmCell>();
    const CcmCell one{1.0F, 0.0F, 0.0F, 0.2F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F};
    ASSERT_EQ(ccm_merge(m, one, 1000.0F), Status::kOk);
    EXPECT_FALSE(detail::distrust_mark(m));
    EXPECT_EQ(m.weight, 1.0F);
    KalmanCell k = detail::distrusted_cell<KalmanCell>();
    detail::kalman_fuse(k, 0.3F, 1.0e-4F, 1.0F, 1.0e-6F);
    EXPECT_FALSE(detail::distrust_mark(k));
    EXPECT_EQ(k.weight, 1.0F);
    OmgCell o = detail::distrusted_cell<OmgCell>();
    detail::omg_update_unchecked(o, 0.3F, 1.0e-4F, 1.0F, 1000.0F);
    EXPECT_FALSE(detail::distrust_mark(o));
    EXPECT_EQ(o.weight, 1.0F);
  }
  // The stack: a finest cell the scrub reset answers upset until a frame's points land in it.
  auto stack = mapped_cadre();
  float cx = 0.0F;
  float cy = 0.0F;
  KalmanCell* cell = known_cell<KalmanCell>(*stack, 0, &cx, &cy);
  ASSERT_NE(cell, nullptr);
  *cell = flipped(*cell, 40U);
  const PointXYZ origin{cx - 0.3F, cy, 0.175F};
  for (std::uint32_t f = 0; f < detail::ConfigScrubFrames<CadreConfig>::value; ++f) {
    ASSERT_EQ(stack->update_frame(nullptr, 0U, origin, nullptr), Status::kOk);
  }
  ASSERT_EQ(stack->total_counters().corrupted_cells, 1U);
  EXPECT_TRUE(stack->query(cx, cy).upset);
  const float z = stack->query(cx + 0.04F, cy).height_m;
  std::vector<PointXYZ> points;
  for (int i = 0; i < 5; ++i) {
    points.push_back(PointXYZ{cx - 0.01F + 0.004F * static_cast<float>(i), cy + 0.005F, z});
  }
  FrameCounters counters{};
  ASSERT_EQ(stack->update_frame(points.data(), points.size(), origin, &counters), Status::kOk);
  EXPECT_EQ(counters.used, points.size());
  EXPECT_GT(cell->weight, 0.0F) << "the points did not land in the distrusted cell";
  EXPECT_FALSE(detail::distrust_mark(*cell));
  EXPECT_FALSE(stack->query(cx, cy).upset) << "new points observed the cell: the mark must be gone";
  EXPECT_EQ(inconsistent_cells(*stack), 0U);
}

TEST(Integrity, TheScrubChecksEveryCellWithinTheStatedFrames) {
  auto stack = mapped_cadre();
  auto& layers = mutable_layers(*stack);
  using Layers = detail::LayerSet<CadreConfig>;
  // One flipped bit in every cell of every layer, observed or not.
  for (std::size_t i = 0; i < Layers::kFineCellCount; ++i) {
    layers.fine_storage[i] = flipped(layers.fine_storage[i], i % 96U);
  }
  for (std::size_t i = 0; i < Layers::kCcmCellCount; ++i) {
    layers.ccm_storage[i] = flipped(layers.ccm_storage[i], i % 320U);
  }
  const std::size_t total = Layers::kFineCellCount + Layers::kCcmCellCount;
  const std::uint32_t frames = detail::ConfigScrubFrames<CadreConfig>::value;
  const PointXYZ origin{0.0F, 0.0F, 0.175F};
  for (std::uint32_t f = 1; f <= frames; ++f) {
    ASSERT_EQ(stack->update_frame(nullptr, 0U, origin, nullptr), Status::kOk);
    if (f < frames) {
      EXPECT_LT(stack->total_counters().corrupted_cells, total) << "the stated bound is not tight";
    }
  }
  EXPECT_EQ(stack->total_counters().corrupted_cells, total) << "a cell was not checked within " << frames << " frames";
  EXPECT_EQ(observed_cells(*stack), 0U);
  EXPECT_EQ(inconsistent_cells(*stack), 0U);
  std::printf("[ integrity ] CADRE: %zu cells, %u per frame, every cell within %u frames\n", total,
              detail::scrub_cells_per_frame<CadreConfig, Layers>(), frames);
}

TEST(Integrity, MotionPassResetsAndCountsCorruptedCells) {
  auto stack = mapped_cadre();
  auto& layers = mutable_layers(*stack);
  float cx = 0.0F;
  float cy = 0.0F;
  KalmanCell* fine = known_cell<KalmanCell>(*stack, 0, &cx, &cy);
  CcmCell* ccm = known_cell<CcmCell>(*stack, 1, &cx, &cy);
  ASSERT_NE(fine, nullptr);
  ASSERT_NE(ccm, nullptr);
  *fine = flipped(*fine, 40U);
  *ccm = flipped(*ccm, 200U);
  ASSERT_EQ(stack->move_to(0.0F, 0.0F, 0.02F), Status::kOk);
  EXPECT_EQ(stack->total_counters().corrupted_cells, 2U) << "the motion pass reads every cell: it must reset both";
  EXPECT_TRUE(detail::distrust_mark(*fine) && fine->weight == 0.0F) << "not reset to the distrusted cell";
  EXPECT_TRUE(detail::distrust_mark(*ccm) && ccm->weight == 0.0F) << "not reset to the distrusted cell";
  EXPECT_EQ(inconsistent_cells(*stack), 0U);
  (void)layers;
}

// ---- bookkeeping ------------------------------------------------------------------------------

/// Flips one bit of the stack's bytes at `address`, then checks that every call is refused with
/// kCorrupt and changes nothing, and that init() recovers.
void bookkeeping_flip_is_refused(Stack<CadreConfig>& stack, const void* address, std::size_t bit, const char* what) {
  void* const raw = &stack;
  std::vector<unsigned char> backup(static_cast<const unsigned char*>(raw),
                                    static_cast<const unsigned char*>(raw) + sizeof(Stack<CadreConfig>));
  auto* byte = static_cast<unsigned char*>(const_cast<void*>(address)) + bit / 8U;
  *byte = static_cast<unsigned char>(*byte ^ (1U << (bit % 8U)));
  EXPECT_EQ(stack.state_status(), Status::kCorrupt) << what << " bit " << bit;
  EXPECT_EQ(stack.query(0.5F, 0.0F).status, Status::kCorrupt) << what;
  EXPECT_EQ(stack.query_layer(1, 0.5F, 0.0F).status, Status::kCorrupt) << what;
  EXPECT_EQ(stack.move_to(0.1F, 0.0F), Status::kCorrupt) << what;
  static const test::CadreFrame frame = small_frame(0, 0.0F, 0.0F);  // made once: the same frame every flip
  EXPECT_EQ(stack.update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, nullptr),
            Status::kCorrupt)
      << what;
  EXPECT_EQ(query_footprint(stack, Footprint{0.5F, 0.0F, 1.0F, 0.0F, 0.6F, 0.4F}).status, Status::kCorrupt) << what;
  std::vector<std::uint8_t> snap(snapshot_size<CadreConfig>());
  std::size_t written = 0U;
  EXPECT_EQ(save_snapshot(stack, snap.data(), snap.size(), &written), Status::kCorrupt) << what;
  EXPECT_EQ(stack.query(0.5F, 0.0F).status, Status::kCorrupt) << what << ": the refusal must stay, queries included";
  std::memcpy(raw, backup.data(), backup.size());  // the stack as it was: intact again
  EXPECT_EQ(stack.state_status(), Status::kOk) << what;
}

TEST(Integrity, BookkeepingFlipsAreRefusedWithCorrupt) {
  auto stack = mapped_cadre();
  const auto& layers = layers_of(*stack);
  // Every bit of the parameters (all fields, no padding).
  const auto* params = reinterpret_cast<const unsigned char*>(&stack->params());
  for (std::size_t bit = 0; bit < sizeof(StackParams) * 8U; ++bit) {
    bookkeeping_flip_is_refused(*stack, params, bit, "StackParams");
  }
  // Every bit of each grid's binding: storage pointer, side, cell width, its inverse, window
  // centre and lowest index (the first 36 bytes of a RingGrid; then padding and the move
  // telemetry, which is not bookkeeping).
  static_assert(sizeof(RingGrid<CcmCell>) == 48U && sizeof(RingGrid<KalmanCell>) == 48U,
                "the binding bytes below assume RingGrid's layout: 36 bytes of fields first");
  const RingGrid<KalmanCell>* grids[] = {&layers.fine};
  for (std::size_t bit = 0; bit < 36U * 8U; ++bit) {
    bookkeeping_flip_is_refused(*stack, grids[0], bit, "finest grid binding");
    for (int c = 0; c < Stack<CadreConfig>::kCcmLayerCount; c += 3) {
      bookkeeping_flip_is_refused(*stack, &layers.ccm[c], bit, "CCM grid binding");
    }
  }
  for (std::size_t bit = 0; bit < sizeof layers.widths * 8U; ++bit) {
    bookkeeping_flip_is_refused(*stack, layers.widths, bit, "cell widths");
  }
  for (std::size_t bit = 0; bit < sizeof layers.kept * 8U; bit += 3U) {
    bookkeeping_flip_is_refused(*stack, layers.kept, bit, "kept windows");
  }
  // Recovery: init() after a refusal.
  auto* byte = const_cast<unsigned char*>(params);
  *byte = static_cast<unsigned char>(*byte ^ 1U);
  ASSERT_EQ(stack->state_status(), Status::kCorrupt);
  EXPECT_EQ(stack->init(default_stack_params(0.04F)), Status::kOk);
  EXPECT_EQ(stack->state_status(), Status::kOk);
  EXPECT_EQ(stack->query(0.5F, 0.0F).status, Status::kUnknown) << "init must start an empty map";
}

/// Every byte that init() sets in a value-initialised stack (every other byte stays 0: cells,
/// checks, counters, scratch, pools) is state a call trusts: parameters, routing, thresholds, the
/// grids' bindings, widths, kept windows, the initialised word, the seals and the update path's
/// derived constants (the front, the gate's constants and change rule, the budget, the weight
/// mode). Every bit of each such byte, flipped, must make the stack refuse with kCorrupt: the
/// seal covers whatever init() derives, without the test naming the members (so a constant added
/// to init() and left out of the seal fails here). Returns the bytes swept.
template <typename Config>
std::size_t every_byte_init_sets_is_sealed(const char* name, const StackParams& params) {
  auto stack = std::make_unique<Stack<Config>>();
  EXPECT_EQ(stack->init(params), Status::kOk) << name;
  auto* bytes = reinterpret_cast<unsigned char*>(stack.get());
  std::size_t swept = 0U;
  std::size_t unsealed = 0U;
  for (std::size_t at = 0; at < sizeof(Stack<Config>); ++at) {
    if (bytes[at] == 0U) {
      continue;
    }
    ++swept;
    for (unsigned bit = 0; bit < 8U; ++bit) {
      bytes[at] = static_cast<unsigned char>(bytes[at] ^ (1U << bit));
      const Status status = stack->state_status();
      bytes[at] = static_cast<unsigned char>(bytes[at] ^ (1U << bit));
      if (status != Status::kCorrupt && ++unsealed <= 5U) {
        ADD_FAILURE() << name << ": a flip of bit " << bit << " of byte " << at << " of " << sizeof(Stack<Config>)
                      << " (set by init) is not refused: " << to_string(status);
      }
    }
  }
  EXPECT_EQ(unsealed, 0U) << name << ": flips init's state takes without a refusal";
  EXPECT_EQ(stack->state_status(), Status::kOk) << name << ": the sweep must leave the stack as it was";
  return swept;
}

TEST(Integrity, EveryByteInitSetsIsSealed) {
  StackParams budget = default_stack_params(0.04F);
  budget.frame_point_budget = 300000U;  // non-zero: the update path's copies of the budget are set
  budget.frame_time_budget_us = 70000U;
  StackParams no_gate = default_stack_params(0.04F);
  no_gate.outlier_gate_sigma = 0.0F;
  StackParams lidar = default_stack_params(0.04F);
  lidar.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.01F, 0.002F});
  lidar.noise.set_weight_mode(sensor::WeightMode::kInverseVariance, 2.0F);
  const std::size_t cadre = every_byte_init_sets_is_sealed<CadreConfig>("CADRE, budget", budget);
  EXPECT_GT(cadre, 300U) << "too few bytes set by init: the sweep tests nothing";
  (void)every_byte_init_sets_is_sealed<CadreConfig>("CADRE, gate off", no_gate);
  (void)every_byte_init_sets_is_sealed<CadreConfig>("CADRE, lidar", lidar);
  (void)every_byte_init_sets_is_sealed<SingleOmgConfig>("single OMG", default_stack_params(0.04F));
  (void)every_byte_init_sets_is_sealed<WithoutOutlierGate<CadreConfig>>("CADRE without the gate compiled in", no_gate);
  std::printf("[ integrity ] CADRE: %zu bytes set by init, every bit of each refused when flipped\n", cadre);
}

TEST(Integrity, IndicesFromScratchStayInsideWhateverTheirBits) {
  // The Kalman frame records: a slot with any bits names a record of the batch (masked).
  auto batch = std::make_unique<detail::KalmanBatch<64U>>();
  batch->clear();
  const GateConstants gate{9.0F, 1e-4F};
  for (const std::int32_t slot : {63, 64, 65, 1 << 20, -2, INT32_MAX}) {
    detail::KalmanBatch<64U>::Run run{};
    batch->start(run, slot);
    EXPECT_GE(run.slot, 0) << "slot " << slot;
    EXPECT_LT(run.slot, 64) << "slot " << slot << " opened a record outside the batch";
    EXPECT_TRUE(batch->add<false>(run, 1000, 7, gate));
    batch->flush(run);
    EXPECT_EQ(batch->sum(static_cast<std::uint32_t>(slot)).count, 1U) << "slot " << slot;
    batch->template begin_frame<false>(nullptr, gate);
  }
  // A held-point pool: a slot whose cell number an upset put out of range is dropped at the end
  // of the frame (never handed to the change rule to index the cells) and counted.
  using Pool = detail::HeldPool<CcmCell, 100U, 8U>;
  auto pool = std::make_unique<Pool>();
  pool->clear();
  Pool::Slot* a = pool->hold(3U, CellIndex{3, 0}, 1);
  Pool::Slot* b = pool->hold(97U, CellIndex{97, 0}, 1);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  b->cell = 100U + (1U << 12);
  int kept_calls = 0;
  EXPECT_EQ(pool->end_frame([&](const Pool::Slot& slot) {
    ++kept_calls;
    EXPECT_LT(slot.cell, 100U) << "the change rule was handed a cell outside the layers";
    return true;
  }), 1U) << "the slot with a cell out of range must be counted";
  EXPECT_EQ(kept_calls, 1);
  EXPECT_EQ(pool->used(), 1U);
  pool->seal();
  // Between frames: a flip of the slot's bytes drops it; a slot count an upset raised past the
  // pool drops every slot (not trusted), never reads past them.
  auto* raw = reinterpret_cast<unsigned char*>(pool.get());
  const std::size_t slots_at = sizeof(std::uint16_t) * 100U;  // the tags come first
  raw[slots_at + 2U] = static_cast<unsigned char>(raw[slots_at + 2U] ^ 0x10U);
  EXPECT_EQ(pool->verify_seals(), 1U) << "a flipped slot must be dropped";
  EXPECT_EQ(pool->used(), 0U);
  ASSERT_NE(pool->hold(5U, CellIndex{5, 0}, 1), nullptr);
  ASSERT_NE(pool->hold(6U, CellIndex{6, 0}, 1), nullptr);
  EXPECT_EQ(pool->end_frame([](const Pool::Slot&) { return true; }), 0U);
  pool->seal();
  std::uint32_t used = 0U;
  const std::size_t used_at = slots_at + sizeof(Pool::Slot) * 8U;
  std::memcpy(&used, raw + used_at, sizeof used);
  ASSERT_EQ(used, 2U) << "the test's picture of HeldPool's layout is stale";
  used ^= 1U << 30;
  std::memcpy(raw + used_at, &used, sizeof used);
  EXPECT_EQ(pool->verify_seals(), 2U) << "a slot count out of range: every slot dropped, counted";
  EXPECT_EQ(pool->used(), 0U);
  EXPECT_EQ(pool->end_frame([](const Pool::Slot&) { return true; }), 0U);
}

TEST(Integrity, UninitialisedStackAnswersNotInitialisedAndAFlipInItsWordIsCorrupt) {
  auto stack = std::make_unique<Stack<CadreConfig>>();
  EXPECT_EQ(stack->state_status(), Status::kNotInitialised);
  EXPECT_EQ(stack->query(0.0F, 0.0F).status, Status::kNotInitialised);
  EXPECT_EQ(stack->move_to(0.0F, 0.0F), Status::kNotInitialised);
}

/// A CADRE stack whose held-point pools hold slots that wait for more evidence (a sparse frame
/// 25 cm above the ground: fewer than change_min_points outside the gate per cell), and the
/// sparse points.
std::unique_ptr<Stack<CadreConfig>> stack_with_held_slots(std::vector<PointXYZ>* sparse, PointXYZ* origin) {
  auto stack = mapped_cadre();
  const test::CadreFrame frame = small_frame(5, 0.0F, 0.0F);
  for (std::size_t i = 0; i < frame.map_points.size(); i += 40U) {
    PointXYZ p = frame.map_points[i];
    p.z += 0.25F;
    sparse->push_back(p);
  }
  *origin = frame.sensor_origin;
  EXPECT_EQ(stack->update_frame(sparse->data(), sparse->size(), *origin, nullptr), Status::kOk);
  return stack;
}

/// Flips bit `bit` of each byte in [from, to) (every `stride`-th), one at a time on a restored
/// copy, then runs a frame and a query: every status is kOk or kCorrupt, every answer finite,
/// no more slots dropped than live; returns the slots dropped over all flips.
std::size_t sweep_after_the_cells(Stack<CadreConfig>& stack, const std::vector<PointXYZ>& sparse, PointXYZ origin,
                                  std::size_t from, std::size_t to, std::size_t stride, unsigned bits) {
  void* const raw = &stack;
  const auto* begin = static_cast<const unsigned char*>(raw);
  const std::vector<unsigned char> backup(begin, begin + sizeof(Stack<CadreConfig>));
  const std::uint32_t held = stack.held_cells();
  std::size_t dropped = 0U;
  for (std::size_t at = from; at < to; at += stride) {
    for (unsigned bit = 0; bit < 8U; ++bit) {
      if (((bits >> bit) & 1U) == 0U) continue;
      std::memcpy(raw, backup.data(), backup.size());
      auto* byte = static_cast<unsigned char*>(raw) + at;
      *byte = static_cast<unsigned char>(*byte ^ (1U << bit));
      FrameCounters c{};
      const Status s = stack.update_frame(sparse.data(), 8U, origin, &c);
      const QueryResult q = stack.query(1.0F, 0.1F);
      const bool ok = (s == Status::kOk || s == Status::kCorrupt) &&
                      (q.status == Status::kOk || q.status == Status::kUnknown || q.status == Status::kCorrupt) &&
                      std::isfinite(q.height_m) && std::isfinite(q.normal_variance) && std::isfinite(q.weight) &&
                      c.corrupted_slots <= held;
      EXPECT_TRUE(ok) << "byte " << at << " bit " << bit << ": update " << to_string(s) << ", query "
                      << to_string(q.status) << ", height " << q.height_m << ", slots dropped " << c.corrupted_slots;
      if (!ok) {
        std::memcpy(raw, backup.data(), backup.size());
        return dropped;
      }
      dropped += c.corrupted_slots;
    }
  }
  std::memcpy(raw, backup.data(), backup.size());
  return dropped;
}

TEST(Integrity, EveryBitOfTheStateAfterTheCountersIsSafe) {
  // The counters, the initialised word, the seal, the scrub cursor and the front's constants
  // (index scale and shift, routing bounds: a shift an upset made 64 or more would be undefined
  // behaviour), every bit: refused or harmless, never an access outside (the asan preset).
  std::vector<PointXYZ> sparse;
  PointXYZ origin{};
  auto stack = stack_with_held_slots(&sparse, &origin);
  const auto* begin = reinterpret_cast<const unsigned char*>(stack.get());
  const auto from = static_cast<std::size_t>(reinterpret_cast<const unsigned char*>(&stack->total_counters()) - begin);
  const std::size_t to = from + 512U < sizeof(Stack<CadreConfig>) ? from + 512U : sizeof(Stack<CadreConfig>);
  (void)sweep_after_the_cells(*stack, sparse, origin, from, to, 1U, 0xFFU);
}

TEST(Integrity, AFlippedHeldSlotIsDroppedAndCounted) {
  // One bit of every 97th byte after the counters (the update path's scratch, batches, touched
  // list, held-point pools, gate constants): a live slot's flip is dropped at the next frame.
  std::vector<PointXYZ> sparse;
  PointXYZ origin{};
  auto stack = stack_with_held_slots(&sparse, &origin);
  ASSERT_GT(stack->held_cells(), 0U) << "no slot waits: nothing to flip";
  const auto* begin = reinterpret_cast<const unsigned char*>(stack.get());
  const auto from = static_cast<std::size_t>(reinterpret_cast<const unsigned char*>(&stack->total_counters()) - begin);
  const std::size_t dropped = sweep_after_the_cells(*stack, sparse, origin, from, sizeof(Stack<CadreConfig>), 97U, 0x10U);
  std::printf("[ integrity ] held slots: %u live, %zu flips dropped a slot\n", stack->held_cells(), dropped);
  EXPECT_GT(dropped, 0U) << "no flip reached a live slot's seal";
}

}  // namespace
}  // namespace ccmap
