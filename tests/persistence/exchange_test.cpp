// Map exchange (include/ccmap/persistence/exchange.hpp): two rovers fed halves of a traverse and
// exchanging deltas end equal to one map fed everything (the independent reference: the single
// map's own updates); with the weight limit, within a stated bound of it; snapshots merge
// likewise, with origin offsets; every corrupted, truncated, forged, duplicated, misaligned or
// echoed delta is refused with the map bitwise unchanged; moves, floors and small buffers never
// lose or double an increment.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "ccmap/persistence/exchange.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "support/cadre_frames.hpp"
#include "support/exchange_seeds.hpp"
#include "support/map_state.hpp"
#include "support/reference.hpp"
#include "support/wire_bytes.hpp"

namespace ccmap {
namespace {

using Bytes = std::vector<std::uint8_t>;
using Cadre = Stack<CadreConfig>;
using CadreExchange = MapExchange<CadreConfig>;

// A small stack (4 x 4 Kalman, two 4 x 4 CCM layers, 0.5 m cells: the fuzz targets' shape) for
// exhaustive corruption.
using TinyConfig = test::SeedConfig;
using Tiny = Stack<TinyConfig>;
using TinyExchange = MapExchange<TinyConfig>;

// ---------------------------------------------------------------------------------------------
// A traverse: CADRE frames (tests/support/cadre_frames.hpp) along a path that drives 3 m out,
// turns, and comes back past the start, so that cells of the small layers leave their windows
// and re-enter them.
// ---------------------------------------------------------------------------------------------
struct TraverseFrame {
  float x, y;
  test::CadreFrame frame;
};

std::vector<TraverseFrame> make_traverse(int frames, int width_px, int height_px) {
  std::vector<TraverseFrame> out;
  float x = 0.0F;
  float y = 0.0F;
  for (int k = 0; k < frames; ++k) {
    test::CadreFrameSpec spec;
    spec.width_px = width_px;
    spec.height_px = height_px;
    const bool back = k >= frames / 2;
    spec.heading_cos = back ? -1.0F : 1.0F;
    spec.heading_sin = 0.0F;
    spec.sensor_x = x;
    spec.sensor_y = y;
    spec.seed = static_cast<std::uint32_t>(k) + 1U;
    out.push_back(TraverseFrame{x, y, test::make_cadre_frame(spec)});
    x += back ? -0.4F : 0.4F;
    y += 0.05F;
  }
  return out;
}

/// The defaults with the outlier gate and free space off (the paper's update). The exact-merge
/// claims tested here hold for it only: with the gate on, which points a cell takes depends on
/// what the cell held when they came (docs/design.md, "Outlier gate and change"), so a rover fed
/// half the points gates differently from one fed all of them; free space clears a cell from the
/// rays of its own frames, which a rover fed half the frames sees differently.
StackParams paper_params(float finest_cell_width_m) {
  StackParams p = default_stack_params(finest_cell_width_m);
  p.outlier_gate_sigma = 0.0F;
  p.free_space_rays = 0.0F;
  return p;
}

/// No limiter and a floor far below any reachable Kalman variance: every merge is exact in real
/// arithmetic.
StackParams exact_params() {
  StackParams p = paper_params(0.04F);
  p.weight_limit = kNoWeightLimit;
  p.kalman_min_variance = 1e-30F;
  return p;
}

Bytes export_all(CadreExchange& ex, ExportReport* report = nullptr, float floor = 0.0F, std::size_t capacity = 0) {
  Bytes out(capacity > 0 ? capacity : CadreExchange::max_delta_size());
  std::size_t written = 0;
  EXPECT_EQ(ex.export_delta(out.data(), out.size(), ExportOptions{floor, 0}, &written, report), Status::kOk);
  out.resize(written);
  return out;
}

struct Team {
  std::unique_ptr<Cadre> single = std::make_unique<Cadre>();
  std::unique_ptr<Cadre> a = std::make_unique<Cadre>();
  std::unique_ptr<Cadre> b = std::make_unique<Cadre>();
  std::unique_ptr<CadreExchange> ex_a = std::make_unique<CadreExchange>();
  std::unique_ptr<CadreExchange> ex_b = std::make_unique<CadreExchange>();
  std::size_t bytes = 0;

  explicit Team(const StackParams& p) {
    EXPECT_EQ(single->init(p), Status::kOk);
    EXPECT_EQ(a->init(p), Status::kOk);
    EXPECT_EQ(b->init(p), Status::kOk);
    EXPECT_EQ(ex_a->init(*a, ExchangeParams{1U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
    EXPECT_EQ(ex_b->init(*b, ExchangeParams{2U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  }

  /// Both directions: A's gains to B, then B's to A.
  void exchange(float floor = 0.0F, std::size_t capacity = 0) {
    const Bytes da = export_all(*ex_a, nullptr, floor, capacity);
    ASSERT_EQ(ex_b->merge_delta(da.data(), da.size(), nullptr), Status::kOk);
    const Bytes db = export_all(*ex_b, nullptr, floor, capacity);
    ASSERT_EQ(ex_a->merge_delta(db.data(), db.size(), nullptr), Status::kOk);
    bytes += da.size() + db.size();
  }

  /// Every map follows the whole path; frame k is fed to the single map and to A (k even) or B.
  void drive(const std::vector<TraverseFrame>& frames, int exchange_every, float floor = 0.0F,
             std::size_t capacity = 0) {
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const TraverseFrame& f = frames[k];
      for (Cadre* s : {single.get(), a.get(), b.get()}) {
        ASSERT_EQ(s->move_to(f.x, f.y), Status::kOk);
      }
      const auto& pts = f.frame.sensor_points;
      ASSERT_EQ(single->update_frame_sensor(pts.data(), pts.size(), f.frame.pose, nullptr), Status::kOk);
      Cadre* half = k % 2 == 0 ? a.get() : b.get();
      ASSERT_EQ(half->update_frame_sensor(pts.data(), pts.size(), f.frame.pose, nullptr), Status::kOk);
      if ((k + 1) % static_cast<std::size_t>(exchange_every) == 0) {
        exchange(floor, capacity);
      }
    }
    exchange();  // the last gains, without floor or size limit
  }
};

/// Largest differences between two maps of the same windows, over every observed cell.
struct Deviation {
  double mean_m = 0.0;        ///< CCM means, Kalman heights (m)
  double moment_rel = 0.0;    ///< CCM second moments per weight, relative to the cell's own
  double variance_rel = 0.0;  ///< Kalman variances, relative
  int weight_mismatches = 0;  ///< cells whose weights differ at all
  int presence_mismatches = 0;
  int cells = 0;
};

template <typename Config>
Deviation compare(const Stack<Config>& got, const Stack<Config>& want) {
  using S = Stack<Config>;
  Deviation d;
  for (int k = 0; k < S::kLayerCount; ++k) {
    EXPECT_EQ(got.layer_centre(k), want.layer_centre(k));
  }
  auto rel = [](double a, double b, double scale) { return std::fabs(a - b) / std::max(scale, 1e-30); };
  for (int c = 0; c < S::kCcmLayerCount; ++c) {
    const float w = got.layer_cell_width(c + S::kFineLayerCount);
    got.ccm_layer(c).for_each([&](CellIndex i, const CcmCell& g) {
      const CcmCell& e = *want.ccm_layer(c).cell(i);
      if ((g.weight > 0.0F) != (e.weight > 0.0F)) {
        ++d.presence_mismatches;
        return;
      }
      if (!(g.weight > 0.0F)) return;
      ++d.cells;
      d.weight_mismatches += g.weight == e.weight ? 0 : 1;
      d.mean_m = std::max({d.mean_m, std::fabs(double{g.mean_x} - e.mean_x), std::fabs(double{g.mean_y} - e.mean_y),
                           std::fabs(double{g.mean_z} - e.mean_z)});
      // Second moments per weight against the cell's own spread (w^2/12 laterally, and the
      // larger of its height variance and 1 mm^2): a relative measure that a flat cell's tiny
      // s_zz does not blow up.
      const double we = e.weight;
      const double lateral = double{w} * w / 12.0;
      const double vertical = std::max(double{e.s_zz} / we, 1e-6);
      const double cross = std::sqrt(lateral * vertical);
      d.moment_rel = std::max({d.moment_rel, rel(g.s_xx / we, e.s_xx / we, lateral), rel(g.s_yy / we, e.s_yy / we, lateral),
                               rel(g.s_zz / we, e.s_zz / we, vertical), rel(g.s_xz / we, e.s_xz / we, cross),
                               rel(g.s_yz / we, e.s_yz / we, cross)});
    });
  }
  if constexpr (S::kHasFine) {
    got.fine_layer().for_each([&](CellIndex i, const typename S::FineCell& g) {
      const typename S::FineCell& e = *want.fine_layer().cell(i);
      if ((g.weight > 0.0F) != (e.weight > 0.0F)) {
        ++d.presence_mismatches;
        return;
      }
      if (!(g.weight > 0.0F)) return;
      ++d.cells;
      d.weight_mismatches += g.weight == e.weight ? 0 : 1;
      d.mean_m = std::max(d.mean_m, std::fabs(double{g.height} - e.height));
      d.variance_rel = std::max(d.variance_rel, rel(g.variance, e.variance, e.variance));
    });
  }
  return d;
}

std::string describe(const Deviation& d) {
  return "cells " + std::to_string(d.cells) + ", presence mismatches " + std::to_string(d.presence_mismatches) +
         ", weight mismatches " + std::to_string(d.weight_mismatches) + ", mean " + std::to_string(d.mean_m * 1e6) +
         " um, moments " + std::to_string(d.moment_rel) + " rel, Kalman variance " + std::to_string(d.variance_rel) +
         " rel";
}

// The stated bound of the exact case (docs/design.md, "Map exchange"): weights and presence
// equal, means and heights within 2 um, second moments within 1e-3 of the cell's own spread,
// Kalman variances within 1e-4 relative. Measured: see the test's output line.
void expect_exact(const Deviation& d, const char* who, int min_cells) {
  EXPECT_GT(d.cells, min_cells) << who;
  EXPECT_EQ(d.presence_mismatches, 0) << who << ": " << describe(d);
  EXPECT_EQ(d.weight_mismatches, 0) << who << ": " << describe(d);
  EXPECT_LE(d.mean_m, 2e-6) << who << ": " << describe(d);
  EXPECT_LE(d.moment_rel, 1e-3) << who << ": " << describe(d);
  EXPECT_LE(d.variance_rel, 1e-4) << who << ": " << describe(d);
}

TEST(MapExchange, HalvesExchangingDeltasEqualOneMapFedEverything) {
  const auto frames = make_traverse(16, 212, 162);
  Team team(exact_params());
  team.drive(frames, 3);
  const Deviation da = compare(*team.a, *team.single);
  const Deviation db = compare(*team.b, *team.single);
  std::printf("[ exchange ] exact: A %s\n[ exchange ] exact: B %s\n[ exchange ] %zu bytes exchanged in %u + %u deltas\n",
              describe(da).c_str(), describe(db).c_str(), team.bytes, team.ex_a->sequence(), team.ex_b->sequence());
  expect_exact(da, "rover A", 4000);
  expect_exact(db, "rover B", 4000);
  // The windows moved back over the start: some cells left and re-entered between exports.
  EXPECT_GT(team.single->ccm_layer(0).cells_cleared_by_moves(), 0U);
}

TEST(MapExchange, FloorAndSmallBuffersDelayButNeverLoseOrDoubleAGain) {
  const auto frames = make_traverse(10, 160, 120);
  Team team(exact_params());
  // Gains below 20 points wait; deltas of at most 1,500 bytes (a radio packet) carry the rest later.
  team.drive(frames, 2, 20.0F, 1500U);
  expect_exact(compare(*team.a, *team.single), "rover A, floor 20, 1500-byte deltas", 3000);
  expect_exact(compare(*team.b, *team.single), "rover B, floor 20, 1500-byte deltas", 3000);
}

TEST(MapExchange, WithTheWeightLimitMergedMapsStayWithinTheStatedBoundOfTheSingleMap) {
  const auto frames = make_traverse(16, 212, 162);
  Team team(paper_params(0.04F));  // W_l = 1000, Kalman floor 1e-8 m^2: both engage
  team.drive(frames, 3);
  // Query answers at the centre of every cell the single map knows, every layer.
  double worst_height = 0.0;
  double worst_slope = 0.0;
  double sum_sq_height = 0.0;
  int compared = 0;
  int class_changes = 0;
  for (int layer = 0; layer < Cadre::kLayerCount; ++layer) {
    const float w = team.single->layer_cell_width(layer);
    const CellIndex c = team.single->layer_centre(layer);
    const int side = Cadre::layer_side(layer);
    for (int iy = c.y - side / 2; iy < c.y + side / 2; ++iy) {
      for (int ix = c.x - side / 2; ix < c.x + side / 2; ++ix) {
        const float x = (static_cast<float>(ix) + 0.5F) * w;
        const float y = (static_cast<float>(iy) + 0.5F) * w;
        const QueryResult want = team.single->query_layer(layer, x, y);
        if (want.status != Status::kOk) continue;
        for (const Cadre* got_map : {team.a.get(), team.b.get()}) {
          const QueryResult got = got_map->query_layer(layer, x, y);
          ASSERT_EQ(got.status, Status::kOk) << "layer " << layer << " cell (" << ix << ", " << iy << ")";
          const double dh = double{got.height_m} - want.height_m;
          worst_height = std::max(worst_height, std::fabs(dh));
          sum_sq_height += dh * dh;
          worst_slope = std::max({worst_slope, std::fabs(double{got.slope_x} - want.slope_x),
                                  std::fabs(double{got.slope_y} - want.slope_y)});
          class_changes += got.cell_class == want.cell_class ? 0 : 1;
          ++compared;
        }
      }
    }
  }
  std::printf("[ exchange ] limited: %d answers, height within %.3f mm (RMS %.3f mm), slope within %.4f, %d class "
              "changes\n",
              compared, worst_height * 1e3, std::sqrt(sum_sq_height / std::max(compared, 1)) * 1e3, worst_slope,
              class_changes);
  EXPECT_GT(compared, 5000);
  // The stated bound (docs/design.md, "Map exchange"): heights within 4 mm, slopes within 0.05,
  // classes equal for at least 99 % of the answers. Measured: 2.4 mm, 0.035, no class change.
  // The differences come from saturated cells: the Kalman floor (0.1 mm) makes a cell follow
  // its latest frames, and which rover saw the latest frame differs from the single map.
  EXPECT_LE(worst_height, 4e-3);
  EXPECT_LE(worst_slope, 0.05);
  EXPECT_LE(class_changes, compared / 100);
}

// ---------------------------------------------------------------------------------------------
// Snapshots: independent maps merged whole, with origin offsets.
// ---------------------------------------------------------------------------------------------
template <typename Config>
Bytes save(const Stack<Config>& s) {
  Bytes bytes(snapshot_size<Config>());
  std::size_t written = 0;
  EXPECT_EQ(save_snapshot(s, bytes.data(), bytes.size(), &written), Status::kOk);
  return bytes;
}

TEST(MapExchange, SnapshotOfAnIndependentHalfMergesToTheSingleMapAtAnAlignedOffset) {
  // 1/16 m cells (coarsest 1 m) and a 2 m offset: B's coordinates x - 2, y - 2 are exact in
  // float for x, y > 2 (the traverse runs around (10, 10)), and so are B's cell indices, windows
  // and ranges. B's map then holds the same statistics at indices shifted by 32 finest cells,
  // and the merge must reproduce the single map up to the merge's own rounding.
  StackParams p = paper_params(0.0625F);
  p.weight_limit = kNoWeightLimit;
  p.kalman_min_variance = 1e-30F;
  auto frames = make_traverse(8, 160, 120);
  auto single = std::make_unique<Cadre>();
  auto a = std::make_unique<Cadre>();
  auto b = std::make_unique<Cadre>();
  ASSERT_EQ(single->init(p), Status::kOk);
  ASSERT_EQ(a->init(p), Status::kOk);
  ASSERT_EQ(b->init(p), Status::kOk);
  const float shift = 2.0F;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    TraverseFrame& f = frames[k];
    std::vector<PointXYZ> pts(f.frame.map_points);
    for (PointXYZ& q : pts) q = PointXYZ{q.x + 10.0F, q.y + 10.0F, q.z};
    const PointXYZ o{f.frame.sensor_origin.x + 10.0F, f.frame.sensor_origin.y + 10.0F, f.frame.sensor_origin.z};
    const float x = f.x + 10.0F, y = f.y + 10.0F;
    ASSERT_EQ(single->move_to(x, y), Status::kOk);
    ASSERT_EQ(a->move_to(x, y), Status::kOk);
    ASSERT_EQ(b->move_to(x - shift, y - shift), Status::kOk);
    ASSERT_EQ(single->update_frame(pts.data(), pts.size(), o, nullptr), Status::kOk);
    if (k % 2 == 0) {
      ASSERT_EQ(a->update_frame(pts.data(), pts.size(), o, nullptr), Status::kOk);
    } else {
      std::vector<PointXYZ> shifted(pts);
      for (PointXYZ& q : shifted) {
        ASSERT_GT(q.x, shift);
        ASSERT_GT(q.y, shift);
        q = PointXYZ{q.x - shift, q.y - shift, q.z};
      }
      const PointXYZ ob{o.x - shift, o.y - shift, o.z};
      ASSERT_EQ(b->update_frame(shifted.data(), shifted.size(), ob, nullptr), Status::kOk);
    }
  }
  const Bytes snap = save(*b);
  const auto before = test::raw_map_state(*a);
  // Misaligned: 1 finest cell is not a whole coarsest cell; another width; not a snapshot.
  EXPECT_EQ(merge_snapshot(*a, snap.data(), snap.size(), CellIndex{32 + 1, 32}, 0.0F, nullptr), Status::kMisaligned);
  auto other_width = std::make_unique<Cadre>();
  ASSERT_EQ(other_width->init(paper_params(0.04F)), Status::kOk);
  const Bytes other = save(*other_width);
  EXPECT_EQ(merge_snapshot(*a, other.data(), other.size(), CellIndex{0, 0}, 0.0F, nullptr), Status::kMisaligned);
  Bytes corrupt = snap;
  corrupt[100] ^= 1U;
  EXPECT_EQ(merge_snapshot(*a, corrupt.data(), corrupt.size(), CellIndex{32, 32}, 0.0F, nullptr), Status::kCorrupt);
  EXPECT_EQ(test::raw_map_state(*a), before);
  MergeReport report{};
  ASSERT_EQ(merge_snapshot(*a, snap.data(), snap.size(), CellIndex{32, 32}, 0.0F, &report), Status::kOk);
  EXPECT_GT(report.cells_merged, 1000U);
  const Deviation d = compare(*a, *single);
  std::printf("[ exchange ] snapshot merge at an offset: %s\n", describe(d).c_str());
  expect_exact(d, "snapshot of B merged into A", 2000);
}

// ---------------------------------------------------------------------------------------------
// Moves: a cell that left and re-entered sends only what arrived after its return.
// ---------------------------------------------------------------------------------------------
TEST(MapExchange, ACellThatLeftAndReturnedSendsOnlyItsNewPoints) {
  StackParams p = paper_params(0.5F);
  p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.001F, 0.0F});
  p.weight_limit = kNoWeightLimit;
  p.kalman_min_variance = 1e-30F;
  auto sender = std::make_unique<Tiny>();
  auto fresh = std::make_unique<Tiny>();  // fed only the points after the return: the reference
  ASSERT_EQ(sender->init(p), Status::kOk);
  ASSERT_EQ(fresh->init(p), Status::kOk);
  TinyExchange ex;
  ASSERT_EQ(ex.init(*sender, ExchangeParams{7U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  const PointXYZ o{0.0F, 0.0F, 1.0F};
  const std::vector<PointXYZ> old_points{{0.3F, 0.2F, 0.10F}, {0.7F, 0.9F, 0.12F}, {1.6F, 1.2F, 0.3F}};
  const std::vector<PointXYZ> new_points{{0.35F, 0.15F, 0.20F}, {0.6F, 0.8F, 0.25F}, {1.55F, 1.3F, 0.4F}};
  ASSERT_EQ(sender->update_frame(old_points.data(), old_points.size(), o, nullptr), Status::kOk);
  Bytes first(TinyExchange::max_delta_size());
  std::size_t n = 0;
  ASSERT_EQ(ex.export_delta(first.data(), first.size(), ExportOptions{}, &n, nullptr), Status::kOk);
  // Away (every window moves by more than its side: all cells cleared), and back.
  ASSERT_EQ(sender->move_to(40.0F, 0.0F), Status::kOk);
  ASSERT_EQ(sender->move_to(0.0F, 0.0F), Status::kOk);
  ASSERT_EQ(sender->update_frame(new_points.data(), new_points.size(), o, nullptr), Status::kOk);
  ASSERT_EQ(fresh->update_frame(new_points.data(), new_points.size(), o, nullptr), Status::kOk);
  Bytes second(TinyExchange::max_delta_size());
  ASSERT_EQ(ex.export_delta(second.data(), second.size(), ExportOptions{}, &n, nullptr), Status::kOk);
  second.resize(n);
  // Merged into an empty map, the second delta must give exactly the fresh map.
  auto receiver = std::make_unique<Tiny>();
  ASSERT_EQ(receiver->init(p), Status::kOk);
  TinyExchange rx;
  ASSERT_EQ(rx.init(*receiver, ExchangeParams{8U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  ASSERT_EQ(rx.merge_delta(second.data(), second.size(), nullptr), Status::kOk);
  const Deviation d = compare(*receiver, *fresh);
  EXPECT_EQ(d.presence_mismatches, 0) << describe(d);
  EXPECT_EQ(d.weight_mismatches, 0) << describe(d);
  EXPECT_LE(d.mean_m, 1e-7) << describe(d);
}

TEST(KeptWindow, HoldsExactlyTheCellsNoMoveClearedSinceTheMark) {
  // Brute force: after a mark every cell of every layer is stamped; a move clears exactly the
  // leaving cells (RingGrid's tests), so a cell is kept iff it still holds its stamp. Random
  // walks with small and large steps (some beyond a window side), marks in between.
  auto layers = std::make_unique<detail::LayerSet<TinyConfig>>();
  test::Rng rng(77);
  auto stamp = [](CellIndex i) { return static_cast<float>(1 + (i.x + 1000) + 4096 * (i.y + 1000)); };
  for (int walk = 0; walk < 100; ++walk) {
    ASSERT_EQ(layers->init(0.5F), Status::kOk);
    float x = static_cast<float>(rng.uniform(-20.0, 20.0));
    float y = static_cast<float>(rng.uniform(-20.0, 20.0));
    for (int step = 0; step < 30; ++step) {
      if (step % 7 == 0) {
        for (int k = 0; k < Tiny::kLayerCount; ++k) layers->kept[k].mark(layers->window_min(k), Tiny::layer_side(k));
        layers->fine.for_each([&](CellIndex i, KalmanCell& c) { c.weight = stamp(i); });
        for (auto& grid : layers->ccm) grid.for_each([&](CellIndex i, CcmCell& c) { c.weight = stamp(i); });
      }
      const double reach = rng.uniform(0.0, 1.0) < 0.1 ? 12.0 : 1.5;
      x += static_cast<float>(rng.uniform(-reach, reach));
      y += static_cast<float>(rng.uniform(-reach, reach));
      for (int k = 0; k < Tiny::kLayerCount; ++k) {
        const float w2 = 2.0F * layers->widths[k];
        const CellIndex centre{2 * static_cast<std::int32_t>(std::floor(x / w2 + 0.5F)),
                               2 * static_cast<std::int32_t>(std::floor(y / w2 + 0.5F))};
        ASSERT_EQ(layers->move_layer(k, centre), Status::kOk);
      }
      int disagreements = 0;
      layers->fine.for_each([&](CellIndex i, const KalmanCell& c) {
        disagreements += layers->kept[0].contains(i) == (c.weight == stamp(i)) ? 0 : 1;
      });
      for (int c = 0; c < Tiny::kCcmLayerCount; ++c) {
        layers->ccm[c].for_each([&](CellIndex i, const CcmCell& cell) {
          disagreements += layers->kept[c + 1].contains(i) == (cell.weight == stamp(i)) ? 0 : 1;
        });
      }
      ASSERT_EQ(disagreements, 0) << "walk " << walk << " step " << step;
    }
  }
  detail::KeptWindow empty{};
  EXPECT_FALSE(empty.contains(CellIndex{0, 0})) << "a zero KeptWindow (a static stack) keeps nothing";
}

// ---------------------------------------------------------------------------------------------
// Refusals: the small map, exhaustively.
// ---------------------------------------------------------------------------------------------
StackParams tiny_params() {
  StackParams p = paper_params(0.5F);
  p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.001F, 0.0F});
  return p;
}

void feed(Tiny& s, float dz) {
  const std::vector<PointXYZ> pts{{0.3F, 0.2F, 0.1F + dz},  {0.7F, 0.9F, 0.12F + dz}, {1.6F, 1.2F, 0.3F + dz},
                                  {-0.6F, 0.4F, 0.2F + dz}, {2.2F, -1.1F, 0.5F + dz}, {-3.1F, 2.9F, 0.7F + dz}};
  ASSERT_EQ(s.update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
}

struct TinyPair {
  std::unique_ptr<Tiny> sender = std::make_unique<Tiny>();
  std::unique_ptr<Tiny> receiver = std::make_unique<Tiny>();
  TinyExchange tx, rx;
  Bytes delta;
  TinyPair() {
    EXPECT_EQ(sender->init(tiny_params()), Status::kOk);
    EXPECT_EQ(receiver->init(tiny_params()), Status::kOk);
    EXPECT_EQ(tx.init(*sender, ExchangeParams{1U, 5U, CellIndex{0, 0}, 0.0F}), Status::kOk);
    EXPECT_EQ(rx.init(*receiver, ExchangeParams{2U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
    feed(*sender, 0.0F);
    feed(*receiver, 0.01F);
    delta.resize(TinyExchange::max_delta_size());
    std::size_t n = 0;
    EXPECT_EQ(tx.export_delta(delta.data(), delta.size(), ExportOptions{}, &n, nullptr), Status::kOk);
    delta.resize(n);
  }
};

using test::get_u32;
using test::put_f32;
using test::put_u32;
using test::reseal;

// Offsets of the format (exchange.hpp).
constexpr std::size_t kVersionAt = 4, kSidesAt = 16, kWidthAt = 52, kSenderAt = 56, kSessionAt = 60,
                      kSequenceAt = 64, kOriginXAt = 76, kOriginZAt = 84, kFirstLayerAt = 88;

TEST(MapExchange, EverySingleBitFlipAndEveryTruncationIsRefusedAndTheMapIsUnchanged) {
  TinyPair pair;
  // A twin of the receiver (same map, same moves) that sees none of the refused deltas: at the
  // end both must export the same bytes, so the refusals left the sent copies alone too, even
  // though a move since the last export gave them something to settle.
  auto twin = std::make_unique<Tiny>();
  ASSERT_EQ(twin->init(tiny_params()), Status::kOk);
  TinyExchange twin_rx;
  ASSERT_EQ(twin_rx.init(*twin, ExchangeParams{2U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  feed(*twin, 0.01F);
  for (Tiny* s : {pair.receiver.get(), twin.get()}) ASSERT_EQ(s->move_to(2.1F, 0.0F), Status::kOk);
  const auto before = test::raw_map_state(*pair.receiver);
  ASSERT_GT(pair.delta.size(), 150U);
  int refused = 0;
  for (std::size_t byte = 0; byte < pair.delta.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      Bytes b = pair.delta;
      b[byte] = static_cast<std::uint8_t>(b[byte] ^ (1U << bit));
      const Status s = pair.rx.merge_delta(b.data(), b.size(), nullptr);
      ASSERT_NE(s, Status::kOk) << "flip of bit " << bit << " of byte " << byte << " was merged";
      ASSERT_EQ(test::raw_map_state(*pair.receiver), before) << "byte " << byte << " bit " << bit;
      ++refused;
    }
  }
  for (std::size_t len = 0; len < pair.delta.size(); ++len) {
    const Status s = pair.rx.merge_delta(pair.delta.data(), len, nullptr);
    ASSERT_NE(s, Status::kOk) << "truncation to " << len << " bytes was merged";
    ASSERT_EQ(test::raw_map_state(*pair.receiver), before);
    ++refused;
  }
  EXPECT_EQ(pair.rx.counters().refused, static_cast<std::uint32_t>(refused));
  EXPECT_EQ(pair.rx.counters().deltas_merged, 0U);
  Bytes mine(TinyExchange::max_delta_size()), theirs(TinyExchange::max_delta_size());
  std::size_t n_mine = 0, n_theirs = 0;
  ASSERT_EQ(pair.rx.export_delta(mine.data(), mine.size(), ExportOptions{}, &n_mine, nullptr), Status::kOk);
  ASSERT_EQ(twin_rx.export_delta(theirs.data(), theirs.size(), ExportOptions{}, &n_theirs, nullptr), Status::kOk);
  mine.resize(n_mine);
  theirs.resize(n_theirs);
  EXPECT_EQ(mine, theirs) << "a refused delta changed what the receiver sends";
  // The intact delta still merges (nothing above consumed its sequence number), here with a
  // byte more: bytes after the core are its free-space section, which this one (no entry
  // announced) does not fill whole: the cells merge, the section is reported damaged.
  Bytes longer = pair.delta;
  longer.push_back(0U);
  MergeReport report{};
  EXPECT_EQ(pair.rx.merge_delta(longer.data(), longer.size(), &report), Status::kOk);
  EXPECT_EQ(report.free_space_status, Status::kCorrupt);
  EXPECT_EQ(report.entries_refused, 0U);
  EXPECT_EQ(pair.rx.counters().sections_damaged, 1U);
  EXPECT_NE(test::raw_map_state(*pair.receiver), before);
}

TEST(MapExchange, ForgedButCrcValidDeltasAreRefusedWithTheirReason) {
  TinyPair pair;
  const auto before = test::raw_map_state(*pair.receiver);
  auto refuse = [&](Bytes b, Status expected, const char* what) {
    reseal(b);
    EXPECT_EQ(pair.rx.merge_delta(b.data(), b.size(), nullptr), expected) << what;
    EXPECT_EQ(test::raw_map_state(*pair.receiver), before) << what;
  };
  Bytes b = pair.delta;
  b[kVersionAt] = 1;
  refuse(b, Status::kVersionMismatch, "format version 1 (before the cell kinds)");
  b = pair.delta;
  b[kVersionAt] = 4;
  refuse(b, Status::kVersionMismatch, "another format version");
  b = pair.delta;
  put_u32(b, kSidesAt, 8U);
  refuse(b, Status::kVersionMismatch, "another preset (first layer 8 x 8)");
  b = pair.delta;
  put_f32(b, kWidthAt, 0.25F);
  refuse(b, Status::kMisaligned, "another finest cell width");
  b = pair.delta;
  put_u32(b, kOriginXAt, 1U);
  refuse(b, Status::kMisaligned, "an origin 1 finest cell off the coarsest grid");
  b = pair.delta;
  put_f32(b, kOriginZAt, std::numeric_limits<float>::quiet_NaN());
  refuse(b, Status::kCorrupt, "a NaN origin height");
  b = pair.delta;
  put_u32(b, kSequenceAt, 0U);
  refuse(b, Status::kCorrupt, "sequence 0");
  b = pair.delta;
  put_u32(b, kSenderAt, 2U);
  refuse(b, Status::kDuplicate, "the receiver's own id");
  b = pair.delta;
  put_u32(b, kFirstLayerAt, 1U);  // odd window centre of the coarsest layer
  refuse(b, Status::kCorrupt, "an odd window centre");
  b = pair.delta;
  put_u32(b, kFirstLayerAt + 8, 17U);  // 17 cells in a 4 x 4 layer
  refuse(b, Status::kCorrupt, "more cells than the layer holds");
  // The first cell of the coarsest layer: its varint, then weight, mean_x, ... (CCM codec).
  const std::size_t first_count = get_u32(pair.delta, kFirstLayerAt + 8);
  ASSERT_GT(first_count, 0U);
  const std::size_t cell = kFirstLayerAt + 12 + 1;
  b = pair.delta;
  b[cell - 1] = 16;  // position 16 of a 4 x 4 window
  refuse(b, Status::kCorrupt, "a cell position outside the window");
  b = pair.delta;
  put_f32(b, cell, 0.0F);
  refuse(b, Status::kCorrupt, "a zero weight");
  b = pair.delta;
  put_f32(b, cell, -1.0F);
  refuse(b, Status::kCorrupt, "a negative weight");
  b = pair.delta;
  put_f32(b, cell + 4, 2.5F);  // mean_x 2.5 m from the centre of a 2 m cell
  refuse(b, Status::kCorrupt, "a mean outside its cell");
  b = pair.delta;
  put_f32(b, cell + 16, -1.0F);  // s_xx
  refuse(b, Status::kCorrupt, "a negative second moment");
  b = pair.delta;
  put_f32(b, cell + 24, std::numeric_limits<float>::infinity());  // s_zz
  refuse(b, Status::kCorrupt, "an infinite second moment");
  b = pair.delta;
  put_f32(b, cell + 36, std::numeric_limits<float>::quiet_NaN());  // s_xy, the full cell's tenth float
  refuse(b, Status::kCorrupt, "a NaN lateral covariance");
  b = pair.delta;
  put_f32(b, kOriginZAt, 1.0e5F);  // heights pushed beyond kMaxAbsCoordinateM
  refuse(b, Status::kOutOfRange, "an origin height that moves cells out of range");
  EXPECT_EQ(pair.rx.counters().deltas_merged, 0U);
  EXPECT_EQ(pair.rx.merge_delta(pair.delta.data(), pair.delta.size(), nullptr), Status::kOk);
}

TEST(MapExchange, AMergeThatWouldOverflowIsRefused) {
  // Without a weight limit, a forged (CRC-valid) weight of 3e38 merges once; a second one would
  // make the weight infinite and is refused, the map unchanged.
  TinyPair pair;
  StackParams unlimited = tiny_params();
  unlimited.weight_limit = kNoWeightLimit;
  auto receiver = std::make_unique<Tiny>();
  ASSERT_EQ(receiver->init(unlimited), Status::kOk);
  TinyExchange rx;
  ASSERT_EQ(rx.init(*receiver, ExchangeParams{2U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  const std::size_t cell = kFirstLayerAt + 12 + 1;  // the coarsest layer's first cell: its weight
  Bytes b = pair.delta;
  put_f32(b, cell, 3e38F);
  reseal(b);
  ASSERT_EQ(rx.merge_delta(b.data(), b.size(), nullptr), Status::kOk);
  const auto before = test::raw_map_state(*receiver);
  put_u32(b, kSequenceAt, 2U);
  reseal(b);
  EXPECT_EQ(rx.merge_delta(b.data(), b.size(), nullptr), Status::kOutOfRange);
  EXPECT_EQ(test::raw_map_state(*receiver), before);
  EXPECT_TRUE(test::all_stored_finite(*receiver));
}

TEST(MapExchange, DuplicatesEchoesAndOldSessionsAreRefusedGapsAreCounted) {
  TinyPair pair;
  ASSERT_EQ(pair.rx.merge_delta(pair.delta.data(), pair.delta.size(), nullptr), Status::kOk);
  const auto merged = test::raw_map_state(*pair.receiver);
  EXPECT_EQ(pair.rx.merge_delta(pair.delta.data(), pair.delta.size(), nullptr), Status::kDuplicate);
  EXPECT_EQ(test::raw_map_state(*pair.receiver), merged) << "the same delta twice";
  // The receiver's own delta, sent back to it.
  Bytes own(TinyExchange::max_delta_size());
  std::size_t n = 0;
  ASSERT_EQ(pair.rx.export_delta(own.data(), own.size(), ExportOptions{}, &n, nullptr), Status::kOk);
  own.resize(n);
  const auto after_export = test::raw_map_state(*pair.receiver);
  EXPECT_EQ(pair.rx.merge_delta(own.data(), own.size(), nullptr), Status::kDuplicate);
  EXPECT_EQ(test::raw_map_state(*pair.receiver), after_export) << "its own delta";
  // Sequences 2 and 3 of the sender; 3 arrives first (2 is then old), a gap of 1 is counted.
  feed(*pair.sender, 0.02F);
  Bytes second(TinyExchange::max_delta_size());
  ASSERT_EQ(pair.tx.export_delta(second.data(), second.size(), ExportOptions{}, &n, nullptr), Status::kOk);
  second.resize(n);
  feed(*pair.sender, 0.03F);
  Bytes third(TinyExchange::max_delta_size());
  ASSERT_EQ(pair.tx.export_delta(third.data(), third.size(), ExportOptions{}, &n, nullptr), Status::kOk);
  third.resize(n);
  MergeReport report{};
  ASSERT_EQ(pair.rx.merge_delta(third.data(), third.size(), &report), Status::kOk);
  EXPECT_EQ(report.sequence, 3U);
  EXPECT_EQ(report.deltas_missed, 1U);
  const auto after_third = test::raw_map_state(*pair.receiver);
  EXPECT_EQ(pair.rx.merge_delta(second.data(), second.size(), nullptr), Status::kDuplicate);
  EXPECT_EQ(test::raw_map_state(*pair.receiver), after_third) << "an older sequence";
  // A restarted sender (a new session) is accepted from sequence 1; the old session no more.
  auto restarted = std::make_unique<Tiny>();
  ASSERT_EQ(restarted->init(tiny_params()), Status::kOk);
  TinyExchange tx2;
  ASSERT_EQ(tx2.init(*restarted, ExchangeParams{1U, 6U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  feed(*restarted, 0.05F);
  Bytes fresh(TinyExchange::max_delta_size());
  ASSERT_EQ(tx2.export_delta(fresh.data(), fresh.size(), ExportOptions{}, &n, nullptr), Status::kOk);
  fresh.resize(n);
  EXPECT_EQ(pair.rx.merge_delta(fresh.data(), fresh.size(), nullptr), Status::kOk);
  feed(*pair.sender, 0.04F);
  Bytes stale(TinyExchange::max_delta_size());
  ASSERT_EQ(pair.tx.export_delta(stale.data(), stale.size(), ExportOptions{}, &n, nullptr), Status::kOk);
  stale.resize(n);
  EXPECT_EQ(pair.rx.merge_delta(stale.data(), stale.size(), nullptr), Status::kDuplicate) << "an old session";
  EXPECT_EQ(pair.rx.counters().deltas_missed, 1U);
  EXPECT_EQ(pair.rx.counters().refused_duplicate, 4U);
}

TEST(MapExchange, AFullPeerTableRefusesNewSendersOnly) {
  auto receiver = std::make_unique<Tiny>();
  ASSERT_EQ(receiver->init(tiny_params()), Status::kOk);
  MapExchange<TinyConfig, 2> rx;
  ASSERT_EQ(rx.init(*receiver, ExchangeParams{100U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  auto delta_of = [](std::uint32_t id) {
    auto s = std::make_unique<Tiny>();
    EXPECT_EQ(s->init(tiny_params()), Status::kOk);
    TinyExchange ex;
    EXPECT_EQ(ex.init(*s, ExchangeParams{id, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
    feed(*s, 0.0F);
    Bytes d(TinyExchange::max_delta_size());
    std::size_t n = 0;
    EXPECT_EQ(ex.export_delta(d.data(), d.size(), ExportOptions{}, &n, nullptr), Status::kOk);
    d.resize(n);
    return d;
  };
  const Bytes d1 = delta_of(1U), d2 = delta_of(2U), d3 = delta_of(3U);
  EXPECT_EQ(rx.merge_delta(d1.data(), d1.size(), nullptr), Status::kOk);
  EXPECT_EQ(rx.merge_delta(d2.data(), d2.size(), nullptr), Status::kOk);
  const auto before = test::raw_map_state(*receiver);
  EXPECT_EQ(rx.merge_delta(d3.data(), d3.size(), nullptr), Status::kBufferTooSmall);
  EXPECT_EQ(test::raw_map_state(*receiver), before);
}

TEST(MapExchange, LayersFinerThanTheChosenOneWaitForALaterDelta) {
  TinyPair pair;  // its first delta (all layers) is exported; feed more and export per layer
  feed(*pair.sender, 0.05F);
  Bytes coarse(TinyExchange::max_delta_size());
  std::size_t n = 0;
  ExportReport report{};
  ASSERT_EQ(pair.tx.export_delta(coarse.data(), coarse.size(), ExportOptions{0.0F, 1}, &n, &report), Status::kOk);
  coarse.resize(n);
  // The Kalman layer is written last: its count is 0, its cells pending.
  std::size_t at = kFirstLayerAt;
  std::uint32_t counts[3] = {};
  for (int k = 0; k < 3; ++k) {
    counts[k] = get_u32(coarse, at + 8);
    at += 12U + counts[k] * (1U + (k < 2 ? 40U : 12U));
  }
  EXPECT_GT(counts[0] + counts[1], 0U);
  EXPECT_EQ(counts[2], 0U) << "a Kalman cell was sent with finest_layer 1";
  EXPECT_GT(report.cells_pending, 0U);
  Bytes rest(TinyExchange::max_delta_size());
  ASSERT_EQ(pair.tx.export_delta(rest.data(), rest.size(), ExportOptions{0.0F, 0}, &n, &report), Status::kOk);
  EXPECT_EQ(report.cells_pending, 0U);
  EXPECT_GT(report.cells_written, 0U) << "the pending Kalman gains come with the next delta";
  EXPECT_EQ(pair.tx.export_delta(rest.data(), rest.size(), ExportOptions{0.0F, 3}, &n, nullptr),
            Status::kInvalidArgument);
  EXPECT_EQ(pair.tx.export_delta(rest.data(), rest.size(), ExportOptions{0.0F, -1}, &n, nullptr),
            Status::kInvalidArgument);
}

TEST(MapExchange, TheOriginsHeightOffsetMovesMergedHeightsAndNothingElse) {
  TinyPair pair;
  // Two empty receivers whose origins lie 0 and 0.5 m below the sender's (dz = 0, +0.5 m).
  auto level = std::make_unique<Tiny>();
  auto lower = std::make_unique<Tiny>();
  ASSERT_EQ(level->init(tiny_params()), Status::kOk);
  ASSERT_EQ(lower->init(tiny_params()), Status::kOk);
  TinyExchange rx_level, rx_lower;
  ASSERT_EQ(rx_level.init(*level, ExchangeParams{3U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  ASSERT_EQ(rx_lower.init(*lower, ExchangeParams{4U, 1U, CellIndex{0, 0}, -0.5F}), Status::kOk);
  ASSERT_EQ(rx_level.merge_delta(pair.delta.data(), pair.delta.size(), nullptr), Status::kOk);
  ASSERT_EQ(rx_lower.merge_delta(pair.delta.data(), pair.delta.size(), nullptr), Status::kOk);
  int cells = 0;
  for (int c = 0; c < Tiny::kCcmLayerCount; ++c) {
    level->ccm_layer(c).for_each([&](CellIndex i, const CcmCell& a) {
      CcmCell b = *lower->ccm_layer(c).cell(i);
      if (!(a.weight > 0.0F)) return;
      ++cells;
      EXPECT_NEAR(b.mean_z - a.mean_z, 0.5F, 1e-6F);
      b.mean_z = a.mean_z;
      EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "only the height may differ";
    });
  }
  level->fine_layer().for_each([&](CellIndex i, const KalmanCell& a) {
    KalmanCell b = *lower->fine_layer().cell(i);
    if (!(a.weight > 0.0F)) return;
    ++cells;
    EXPECT_NEAR(b.height - a.height, 0.5F, 1e-6F);
    b.height = a.height;
    EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0) << "only the height may differ";
  });
  EXPECT_GT(cells, 3);
}

TEST(MapExchange, CellsOutsideTheReceiversWindowsAreDroppedAndCounted) {
  TinyPair pair;
  // The receiver drives 8 m away: the sender's 4 x 4 windows (2 m .. 4 m cells) do not reach it
  // except for what the coarsest layer still overlaps.
  ASSERT_EQ(pair.receiver->move_to(9.0F, 0.0F), Status::kOk);
  MergeReport report{};
  ASSERT_EQ(pair.rx.merge_delta(pair.delta.data(), pair.delta.size(), &report), Status::kOk);
  DeltaInfo info{};
  ASSERT_EQ(TinyExchange::peek_delta(pair.delta.data(), pair.delta.size(), &info), Status::kOk);
  EXPECT_EQ(report.cells_merged + report.cells_outside, info.cells);
  EXPECT_GT(report.cells_outside, 0U);
  EXPECT_EQ(pair.rx.counters().cells_outside, report.cells_outside);
}

TEST(MapExchange, ReinitialisingTheStackOrBindingAnotherExchangeRetiresIt) {
  TinyPair pair;
  Bytes out(TinyExchange::max_delta_size());
  std::size_t n = 0;
  ASSERT_EQ(pair.receiver->init(tiny_params()), Status::kOk);
  EXPECT_EQ(pair.rx.merge_delta(pair.delta.data(), pair.delta.size(), nullptr), Status::kNotInitialised);
  EXPECT_EQ(pair.rx.export_delta(out.data(), out.size(), ExportOptions{}, &n, nullptr), Status::kNotInitialised);
  TinyExchange second;
  ASSERT_EQ(second.init(*pair.sender, ExchangeParams{9U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  EXPECT_EQ(pair.tx.export_delta(out.data(), out.size(), ExportOptions{}, &n, nullptr), Status::kNotInitialised);
  EXPECT_EQ(second.export_delta(out.data(), out.size(), ExportOptions{}, &n, nullptr), Status::kOk);
  // Arguments.
  EXPECT_EQ(second.export_delta(out.data(), TinyExchange::min_delta_size() - 1, ExportOptions{}, &n, nullptr),
            Status::kBufferTooSmall);
  EXPECT_EQ(second.export_delta(nullptr, out.size(), ExportOptions{}, &n, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(second.export_delta(out.data(), out.size(), ExportOptions{-1.0F, 0}, &n, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(second.merge_delta(nullptr, 10, nullptr), Status::kInvalidArgument);
  TinyExchange unbound;
  EXPECT_EQ(unbound.merge_delta(pair.delta.data(), pair.delta.size(), nullptr), Status::kNotInitialised);
  Tiny uninitialised;
  EXPECT_EQ(unbound.init(uninitialised, ExchangeParams{}), Status::kNotInitialised);
  EXPECT_EQ(unbound.init(*pair.sender, ExchangeParams{1U, 1U, CellIndex{0, 0}, std::nanf("")}),
            Status::kInvalidArgument);
}

TEST(MapExchange, DeltaSizesAreTheDocumentedOnes) {
  // 88-byte header, 12 per layer, 4 trailer; per cell a varint and the codec's bytes.
  EXPECT_EQ(CadreExchange::min_delta_size(), 88U + 5U * 12U + 4U);
  // CCM cells of the full cell: 10 floats, 40 bytes, and the 1-byte varint.
  // Free-space entries: 10 bytes, at most one more per cell (exchange.hpp, max_delta_size).
  EXPECT_EQ(CadreExchange::max_delta_size(),
            152U + 4096U * 13U + (4096U + 4096U + 1024U + 1024U) * 41U + 14336U * 10U);
  TinyPair pair;
  DeltaInfo info{};
  ASSERT_EQ(TinyExchange::peek_delta(pair.delta.data(), pair.delta.size(), &info), Status::kOk);
  EXPECT_EQ(info.sender_id, 1U);
  EXPECT_EQ(info.session, 5U);
  EXPECT_EQ(info.sequence, 1U);
  EXPECT_EQ(info.frames_from, 0U);
  EXPECT_EQ(info.frames_to, 1U);
  // Walk the layers (coarsest first: two CCM layers, then the Kalman layer); positions in a
  // 4 x 4 window are below 128, so every varint is one byte.
  std::size_t at = kFirstLayerAt;
  std::uint32_t cells = 0;
  for (const std::size_t cell_bytes : {40U, 40U, 12U}) {
    const std::uint32_t count = get_u32(pair.delta, at + 8);
    cells += count;
    at += 12U + count * (1U + cell_bytes);
  }
  EXPECT_EQ(cells, info.cells);
  EXPECT_GT(cells, 3U);
  EXPECT_EQ(at + 4U, pair.delta.size());
}

}  // namespace
}  // namespace ccmap
