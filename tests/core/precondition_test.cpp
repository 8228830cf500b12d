// Every "Precondition:" of the core outside map/update/ is asserted through the assert hook
// (core/assert.hpp), so that a release build whose hook returns stays safe. Each test violates one
// precondition with a recording hook installed and checks (1) that the hook saw it, (2) the safe
// value the documentation promises, and (3) that nothing was written: the safe values are stated
// independently of the code (an unchanged cell, an index inside the storage, an empty answer).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/core/assert.hpp"
#include "ccmap/grid/ring_grid.hpp"
#include "ccmap/grid/ring_index.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/detail/motion.hpp"
#include "ccmap/map/query/answers.hpp"
#include "ccmap/map/query/pooling.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/map/update/gate.hpp"
#include "ccmap/persistence/exchange.hpp"

namespace ccmap {
namespace {

int g_reports = 0;
const char* g_expression = nullptr;

void record(const char*, int, const char* expression) {
  ++g_reports;
  g_expression = expression;
}

/// Installs the recording hook for one test and restores the previous one.
class RecordingHook {
 public:
  RecordingHook() : previous_(set_assert_hook(&record)) {
    g_reports = 0;
    g_expression = nullptr;
  }
  ~RecordingHook() { set_assert_hook(previous_); }
  RecordingHook(const RecordingHook&) = delete;
  RecordingHook& operator=(const RecordingHook&) = delete;
  [[nodiscard]] int reports() const { return g_reports; }
  [[nodiscard]] std::string expression() const { return g_expression != nullptr ? g_expression : ""; }

 private:
  AssertHook previous_;
};

template <typename T>
bool same_bytes(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

using Layers = detail::LayerSet<CadreConfig>;

TEST(Precondition, WeightLimitNotPositiveLeavesTheCellAlone) {
  CcmCell cell{};
  for (int i = 0; i < 5; ++i) {
    const float x = 0.01F * static_cast<float>(i);
    ASSERT_EQ(ccm_update(cell, x, 0.5F * x, 0.1F * x, 1.0F, kNoWeightLimit), Status::kOk);
  }
  const CcmCell before = cell;
  for (const float bad : {0.0F, -2.0F, std::numeric_limits<float>::quiet_NaN()}) {
    RecordingHook hook;
    ccm_apply_weight_limit(cell, bad);
    EXPECT_EQ(hook.reports(), 1) << "weight limit " << bad << " must be reported";
    EXPECT_TRUE(same_bytes(cell, before)) << "a weight limit of " << bad
                                           << " must not rescale the cell (a negative one would flip its variances)";
  }
  RecordingHook hook;
  ccm_apply_weight_limit(cell, 2.0F);  // valid: 5 points held at weight 2
  EXPECT_EQ(hook.reports(), 0);
  EXPECT_FLOAT_EQ(cell.weight, 2.0F);
  EXPECT_NEAR(cell.s_xx, before.s_xx * 2.0F / 5.0F, 1e-9F) << "eq. (7): S scaled by W_l / W";
}

TEST(Precondition, WrapAndBufferOffsetRefuseASideThatIsNotAPowerOfTwo) {
  RecordingHook hook;
  EXPECT_EQ(grid::wrap(5, 6), 0) << "the safe ring position of a bad side is 0";
  EXPECT_EQ(hook.reports(), 1);
  EXPECT_EQ(grid::buffer_offset(CellIndex{3, 5}, 12), 0U);
  EXPECT_EQ(hook.reports(), 2);
  EXPECT_EQ(grid::buffer_offset(CellIndex{3, 5}, grid::kMaxSide * 2), 0U) << "a side above kMaxSide";
  EXPECT_EQ(hook.reports(), 3);
  EXPECT_EQ(grid::wrap(-3, 0), 0) << "side 0";
  EXPECT_EQ(hook.reports(), 4);
  // Valid sides: no report, the mathematical remainder.
  EXPECT_EQ(grid::wrap(-3, 8), 5);
  EXPECT_EQ(grid::buffer_offset(CellIndex{-1, 2}, 4), 2U * 4U + 3U);
  EXPECT_EQ(hook.reports(), 4);
}

TEST(Precondition, FloorScaledBitsRefusesANegativeShiftAndNonFiniteValues) {
  RecordingHook hook;
  // v = 2^100 with mult 2^23 and q = 0: 150 + 0 - exponent(2^100) = 150 - 227 < 0.
  EXPECT_EQ(grid::detail::floor_scaled_bits(grid::detail::float_bits(1.2676506e30F), 1U << 23, 0), 0);
  EXPECT_EQ(hook.reports(), 1) << "a negative shift is undefined behaviour: it must be reported, not done";
  EXPECT_EQ(grid::detail::floor_scaled_bits(grid::detail::float_bits(std::numeric_limits<float>::infinity()), 1U, 100),
            0);
  EXPECT_EQ(hook.reports(), 2) << "Inf has no value to floor";
  // In range: floor(2.5 * 3) = 7 exactly, no report.
  EXPECT_EQ(grid::detail::floor_scaled_bits(grid::detail::float_bits(2.5F), 3U, 0), 7);
  EXPECT_EQ(hook.reports(), 2);
}

TEST(Precondition, CellUncheckedOutsideTheWindowIsReportedAndStaysInTheStorage) {
  float storage[16] = {};
  RingGrid<float> g;
  ASSERT_EQ(g.init(storage, 4, 1.0F, CellIndex{0, 0}), Status::kOk);
  RecordingHook hook;
  const float& inside = g.cell_unchecked(CellIndex{0, 0});
  EXPECT_EQ(hook.reports(), 0);
  EXPECT_EQ(&inside, &storage[grid::buffer_offset(CellIndex{0, 0}, 4)]);
  const float& outside = g.cell_unchecked(CellIndex{100, -7});
  EXPECT_EQ(hook.reports(), 1) << "an index outside the window must be reported";
  EXPECT_GE(&outside, &storage[0]);
  EXPECT_LE(&outside, &storage[15]) << "the aliased slot must stay inside the storage";
  const RingGrid<float>& read_only = g;
  EXPECT_EQ(&read_only.cell_unchecked(CellIndex{-5, 9}), &storage[grid::buffer_offset(CellIndex{-5, 9}, 4)])
      << "outside the window, the wrapped slot";
  EXPECT_EQ(hook.reports(), 2) << "the const overload must report too";
}

TEST(Precondition, CellUncheckedBeforeInitAnswersAScratchCellOutsideAnyMap) {
  float storage[16] = {};
  RingGrid<float> g;  // not initialised: no storage, no window
  RecordingHook hook;
  float& scratch = g.cell_unchecked(CellIndex{0, 0});
  EXPECT_EQ(hook.reports(), 1) << "no cell is inside the window of a grid before init";
  EXPECT_TRUE(&scratch < &storage[0] || &scratch > &storage[15]);
  scratch = 5.0F;  // a write goes nowhere a map reads
  const RingGrid<float>& read_only = g;
  EXPECT_EQ(&read_only.cell_unchecked(CellIndex{3, 3}), &scratch) << "one scratch cell per cell type";
  EXPECT_EQ(hook.reports(), 2);
  ASSERT_EQ(g.init(storage, 4, 1.0F, CellIndex{0, 0}), Status::kOk);
  EXPECT_EQ(g.cell(CellIndex{0, 0}), &storage[grid::buffer_offset(CellIndex{0, 0}, 4)]);
  EXPECT_EQ(*g.cell(CellIndex{0, 0}), 0.0F) << "the scratch write must not reach a grid's storage";
}

TEST(Precondition, CcmGridOfANonCcmLayerAnswersAGridInBounds) {
  auto layers = std::make_unique<Layers>();
  ASSERT_EQ(layers->init(0.04F), Status::kOk);
  RecordingHook hook;
  EXPECT_EQ(&layers->ccm_grid(1), &layers->ccm[0]);
  EXPECT_EQ(hook.reports(), 0);
  for (const int bad : {0, -1, Layers::kLayerCount, 1000}) {
    const RingGrid<Layers::CcmCellType>& g = std::as_const(*layers).ccm_grid(bad);
    EXPECT_GE(&g, &layers->ccm[0]) << "layer " << bad;
    EXPECT_LT(&g, &layers->ccm[0] + Layers::kCcmSlots) << "layer " << bad << ": a grid outside the set";
  }
  EXPECT_EQ(hook.reports(), 4);
}

/// A LayerSet with one observed CCM cell and one observed fine cell at the origin.
std::unique_ptr<Layers> observed_layers() {
  auto layers = std::make_unique<Layers>();
  EXPECT_EQ(layers->init(0.04F), Status::kOk);
  CcmCell& c = layers->ccm[0].cell_unchecked(CellIndex{0, 0});
  for (int i = 0; i < 6; ++i) {
    const float t = 0.01F * static_cast<float>(i);
    EXPECT_EQ(ccm_update(c, t, 0.07F - t, 0.3F * t, 1.0F, kNoWeightLimit), Status::kOk);
  }
  KalmanCell& k = layers->fine.cell_unchecked(CellIndex{0, 0});
  k.height = 0.1F;
  k.variance = 1e-4F;
  k.weight = 1.0F;
  return layers;
}

TEST(Precondition, ForgetForMotionRefusesABadSigmaAndChangesNoCell) {
  auto layers = observed_layers();
  const StackParams params = default_stack_params(0.04F);
  const CcmCell ccm_before = layers->ccm[0].cell_unchecked(CellIndex{0, 0});
  const KalmanCell fine_before = layers->fine.cell_unchecked(CellIndex{0, 0});
  for (const float bad : {0.0F, -1e-4F, std::numeric_limits<float>::quiet_NaN(),
                          std::numeric_limits<float>::infinity()}) {
    RecordingHook hook;
    detail::forget_for_motion(*layers, params, bad);
    EXPECT_EQ(hook.reports(), 1) << "sigma^2 = " << bad;
    EXPECT_TRUE(same_bytes(layers->ccm[0].cell_unchecked(CellIndex{0, 0}), ccm_before)) << "sigma^2 = " << bad;
    EXPECT_TRUE(same_bytes(layers->fine.cell_unchecked(CellIndex{0, 0}), fine_before)) << "sigma^2 = " << bad;
  }
}

TEST(Precondition, PooledOutsideTheWindowOrOnTheFineLayerIsTheEmptyCell) {
  auto layers = observed_layers();
  RecordingHook hook;
  EXPECT_GT(detail::pooled(*layers, kNoWeightLimit, 1, CellIndex{0, 0}).weight, 0.0F);
  EXPECT_EQ(hook.reports(), 0);
  const Layers::CcmCellType zero{};
  EXPECT_TRUE(same_bytes(detail::pooled(*layers, kNoWeightLimit, 0, CellIndex{0, 0}), zero))
      << "layer 0 is the Kalman layer: no CCM statistics";
  EXPECT_EQ(hook.reports(), 1);
  // Far outside the window: 2 * index would overflow int32 without the check.
  EXPECT_TRUE(same_bytes(detail::pooled(*layers, kNoWeightLimit, 4, CellIndex{1 << 30, 0}), zero));
  EXPECT_EQ(hook.reports(), 2);
}

TEST(Precondition, AnswerAtOutsideTheWindowIsOutsideMapAndThresholdOfABadLayerIsZero) {
  auto layers = observed_layers();
  const StackParams params = default_stack_params(0.04F);
  const float thresholds[Layers::kLayerSlots] = {1e-4F, 2e-4F, 3e-4F, 4e-4F, 5e-4F};
  const detail::QueryView<CadreConfig> view(*layers, params, thresholds);
  RecordingHook hook;
  EXPECT_EQ(view.answer_at(1, CellIndex{0, 0}, 0.0F, 0.0F, false).status, Status::kOk);
  EXPECT_EQ(hook.reports(), 0);
  for (const int layer : {0, 1, 4}) {
    const QueryResult q = view.answer_at(layer, CellIndex{5000, 5000}, 200.0F, 200.0F, false);
    EXPECT_EQ(q.status, Status::kOutsideMap) << "layer " << layer;
    EXPECT_EQ(q.cell_class, CellClass::kUnknown) << "layer " << layer;
  }
  EXPECT_EQ(view.answer_at(7, CellIndex{0, 0}, 0.0F, 0.0F, false).status, Status::kOutsideMap) << "no layer 7";
  EXPECT_EQ(hook.reports(), 4);

  EXPECT_FLOAT_EQ(view.threshold(2), 3e-4F);
  EXPECT_EQ(hook.reports(), 4);
  // 0: every cell with any plane residual is an obstacle (the conservative answer).
  EXPECT_EQ(view.threshold(-1), 0.0F);
  EXPECT_EQ(view.threshold(Layers::kLayerCount), 0.0F);
  EXPECT_EQ(hook.reports(), 6);
}

TEST(Precondition, ExchangeWriteLayersWithoutSettleOrRoomWritesNothing) {
  using Access = detail::ExchangeAccess<CadreConfig>;
  auto stack = std::make_unique<Stack<CadreConfig>>();
  ASSERT_EQ(stack->init(default_stack_params(0.04F)), Status::kOk);
  auto sent = std::make_unique<Access::SentCells>();
  Access::clear(*sent);
  Access::settle(*stack, *sent);
  std::vector<std::uint8_t> buffer(4096, 0xA5U);
  ExportReport report{};
  {
    // Room: fewer bytes than the five layer headers and the trailer.
    RecordingHook hook;
    detail::SnapshotWriter w(buffer.data(), 20U);
    Access::write_layers(*stack, *sent, w, 20U, ExportOptions{}, report);
    EXPECT_EQ(hook.reports(), 1) << "a writer without room for the layer headers must be reported";
    EXPECT_EQ(w.position(), 0U) << "nothing written";
  }
  {
    // Not settled: a move since the last settle leaves the sent copies describing other cells.
    ASSERT_EQ(stack->move_to(3.0F, 0.0F), Status::kOk);
    RecordingHook hook;
    detail::SnapshotWriter w(buffer.data(), buffer.size());
    Access::write_layers(*stack, *sent, w, buffer.size(), ExportOptions{}, report);
    EXPECT_EQ(hook.reports(), 1) << "write_layers before settle() must be reported";
    EXPECT_EQ(w.position(), 0U);
    Access::settle(*stack, *sent);
    Access::write_layers(*stack, *sent, w, buffer.size(), ExportOptions{}, report);
    EXPECT_EQ(hook.reports(), 1) << "settled, with room: no report";
    EXPECT_EQ(w.position(), static_cast<std::size_t>(Stack<CadreConfig>::kLayerCount) * detail::kDeltaLayerHeaderBytes)
        << "an empty map writes the five layer headers only";
  }
  EXPECT_EQ(report.cells_written, 0U);
}

TEST(Precondition, KalmanFuseOfABadVarianceLeavesTheCellAlone) {
  KalmanCell cell{};
  detail::kalman_fuse(cell, 0.25F, 1e-4F, 1.0F, 1e-8F);  // valid: the first measurement
  const KalmanCell before = cell;
  for (const float bad : {0.0F, -1e-4F, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    RecordingHook hook;
    detail::kalman_fuse(cell, 0.5F, bad, 1.0F, 1e-8F);
    EXPECT_EQ(hook.reports(), 1) << "variance " << bad << " must be reported";
    EXPECT_TRUE(same_bytes(cell, before)) << "variance " << bad << " must not change the cell";
  }
  RecordingHook hook;
  detail::kalman_fuse(cell, 0.5F, 1e-4F, 1.0F, 0.0F);  // a floor of 0
  EXPECT_EQ(hook.reports(), 1);
  EXPECT_TRUE(same_bytes(cell, before));
}

TEST(Precondition, TheFinerCheckOfTheFinestLayerContradictsNothing) {
  // The finer-layer check of the outlier gate has no finer layer for layer 0: reported, false.
  Layers layers{};
  ASSERT_EQ(layers.init(0.04F), Status::kOk);
  detail::LayerWalk<CadreConfig> walk{};
  walk.begin_frame(layers);
  detail::OutlierGate<CadreConfig> gate{};
  gate.init(default_stack_params(0.04F), std::vector<float>(5, 100.0F).data(), layers);
  RecordingHook hook;
  EXPECT_FALSE(gate.contradicted_by_finer(layers, walk, 0, 0, 0, -5.0F));
  EXPECT_EQ(hook.reports(), 1);
}

}  // namespace
}  // namespace ccmap
