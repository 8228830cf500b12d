// Uncertainty with motion (Stack::move_to(x, y, sigma), map/detail/motion.hpp) against
// independent references:
//  - the brute-force double model (tests/support/model_stack.hpp), which implements the
//    documented rule from docs/design.md, over frames and uncertain moves on noisy sloped
//    ground, for the CADRE (Kalman + CCM, both CCM cells) and OMG presets: every cell's weight,
//    statistics and variance;
//  - the analytic statement of the rule: a CCM cell's elevation variance at its mean grows by
//    exactly inclination^2 sigma^2 (above the weight floor), a flat cell is untouched, and
//    sigma = 0 is the plain move bitwise;
//  - refusals are counted and leave the map unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/hash_unit.hpp"
#include "support/map_state.hpp"
#include "support/model_stack.hpp"

namespace ccmap {
namespace {

using test::hash_unit;

/// Noisy sloped ground around (rx, ry), points kept 10 % of a finest cell from its edges and off
/// the routing bounds (the model's safe points).
template <typename Config>
std::vector<PointXYZ> sloped_frame(const test::ModelStack<Config>& model, float w0, float rx, float ry, PointXYZ origin,
                                   std::uint32_t frame, std::uint32_t n) {
  std::vector<PointXYZ> pts;
  for (std::uint32_t i = 0; i < n; ++i) {
    const std::uint32_t id = frame * n + i;
    const float x = rx - 2.5F + 5.0F * hash_unit(id, 1U);
    const float y = ry - 2.5F + 5.0F * hash_unit(id, 2U);
    const float xs = (std::floor(x / w0) + 0.1F + 0.8F * hash_unit(id, 4U)) * w0;
    const float ys = (std::floor(y / w0) + 0.1F + 0.8F * hash_unit(id, 5U)) * w0;
    // 16 % and -8 % slopes, a wave, 8 mm of noise: residuals far above float cancellation.
    const float z = 0.16F * xs - 0.08F * ys + 0.03F * std::sin(2.0F * xs) + 0.008F * hash_unit(id, 3U);
    const double dx = double{xs} - origin.x, dy = double{ys} - origin.y, dz = double{z} - origin.z;
    if (model.safe_point(xs, ys, dx * dx + dy * dy + dz * dz, 0.1 * w0)) pts.push_back(PointXYZ{xs, ys, z});
  }
  return pts;
}

template <typename Config>
void matches_the_model_over_uncertain_moves(const StackParams& params) {
  auto stack = std::make_unique<Stack<Config>>();
  ASSERT_EQ(stack->init(params), Status::kOk);
  test::ModelStack<Config> model(*stack);
  const float w0 = stack->layer_cell_width(0);
  for (std::uint32_t f = 0; f < 12; ++f) {
    const float rx = 0.07F * static_cast<float>(f), ry = -0.03F * static_cast<float>(f);
    // Every other move uncertain, sigma from 2 mm to 2 cm.
    const double sigma = f % 2 == 1 ? 0.002 * (1.0 + f) : 0.0;
    if (sigma > 0.0) {
      ASSERT_EQ(stack->move_to(rx, ry, static_cast<float>(sigma)), Status::kOk);
    } else {
      ASSERT_EQ(stack->move_to(rx, ry), Status::kOk);
    }
    model.move_to(rx, ry, static_cast<double>(static_cast<float>(sigma)));
    // The comparison right after the move, then after the frame.
    model.expect_matches(FrameCounters{}, typename test::ModelStack<Config>::Counts{}, "after move " + std::to_string(f));
    const PointXYZ origin{rx, ry, 1.0F};
    const std::vector<PointXYZ> pts = sloped_frame(model, w0, rx, ry, origin, f, 6000U);
    FrameCounters c{};
    ASSERT_EQ(stack->update_frame(pts.data(), pts.size(), origin, &c), Status::kOk);
    const auto m = model.frame_map(pts, nullptr, origin);
    model.expect_matches(c, m, "frame " + std::to_string(f));
    ASSERT_FALSE(testing::Test::HasFailure()) << "diverged at frame " << f;
  }
  EXPECT_TRUE(test::all_stored_finite(*stack));
}

TEST(Motion, UncertainMovesMatchTheDocumentedRuleInDoubleCadre) {
  StackParams p = default_stack_params(0.04F);
  p.weight_limit = 300.0F;  // the limiter engages too
  matches_the_model_over_uncertain_moves<CadreConfig>(p);
}

TEST(Motion, UncertainMovesMatchTheDocumentedRuleInDoubleCadrePaperCell) {
  // The paper's cell: slopes by eq. (9) per axis in the rule (the model's CcmCellDouble::slopes).
  StackParams p = default_stack_params(0.04F);
  p.weight_limit = 300.0F;
  matches_the_model_over_uncertain_moves<PaperCell<CadreConfig>>(p);
}

TEST(Motion, UncertainMovesMatchTheDocumentedRuleInDoubleOmg) {
  matches_the_model_over_uncertain_moves<SingleOmgConfig>(default_stack_params(0.08F));
}

/// A single 8 cm CCM layer over a noisy plane of gradient (a, b), or flat ground.
std::unique_ptr<Stack<SingleCcmConfig>> noisy_plane(float a, float b) {
  auto stack = std::make_unique<Stack<SingleCcmConfig>>();
  StackParams p = default_stack_params(0.08F);
  p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.001F, 0.0F});
  // The paper's update: the test's last point, 6 cm off a cell of a few mm, measures the faded
  // weight; the outlier gate would hold it (it does not widen with a move's sigma).
  p.outlier_gate_sigma = 0.0F;
  if (stack->init(p) != Status::kOk) return nullptr;
  std::vector<PointXYZ> pts;
  for (std::uint32_t i = 0; i < 200000U; ++i) {
    const float x = -1.0F + 2.0F * hash_unit(i, 1U), y = -1.0F + 2.0F * hash_unit(i, 2U);
    pts.push_back(PointXYZ{x, y, a * x + b * y + 0.004F * (hash_unit(i, 3U) - 0.5F)});
  }
  if (stack->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr) != Status::kOk) return nullptr;
  return stack;
}

TEST(Motion, ElevationVarianceAtTheCellMeanGrowsByInclinationSquaredSigmaSquared) {
  const float a = 0.2F, b = 0.1F;
  const auto map = noisy_plane(a, b);
  ASSERT_NE(map, nullptr);
  const CellIndex index{3, -2};
  const CcmCell before = *map->ccm_layer(0).cell(index);
  const float w = map->layer_cell_width(0);
  const float mx = grid::cell_centre(index.x, w) + before.mean_x, my = grid::cell_centre(index.y, w) + before.mean_y;
  const QueryResult q0 = map->query_layer(0, mx, my);
  ASSERT_EQ(q0.status, Status::kOk);
  const float sigma = 0.002F;  // small enough that the weight stays above min_weight
  ASSERT_EQ(map->move_to(0.0F, 0.0F, sigma), Status::kOk);
  const CcmCell after = *map->ccm_layer(0).cell(index);
  const QueryResult q1 = map->query_layer(0, mx, my);
  ASSERT_EQ(q1.status, Status::kOk);
  ASSERT_GT(after.weight, map->params().min_weight);
  const double i2 = double{q0.inclination} * q0.inclination;
  // Elevation variance at the mean: sigma_s^2 (1 + 1 / W); the plane term sigma_s^2 / W grows.
  EXPECT_NEAR(double{q1.elevation_variance} - q0.elevation_variance, i2 * sigma * sigma, 1e-4 * i2 * sigma * sigma)
      << "inclination " << q0.inclination;
  EXPECT_LT(after.weight, before.weight);
  // Mean, slopes, normal variance and class stay (the statistics are scaled, not changed).
  EXPECT_EQ(after.mean_z, before.mean_z);
  EXPECT_NEAR(q1.slope_x, q0.slope_x, 1e-6);
  EXPECT_NEAR(q1.slope_y, q0.slope_y, 1e-6);
  EXPECT_NEAR(q1.normal_variance, q0.normal_variance, 1e-5 * q0.normal_variance);
  EXPECT_EQ(q1.cell_class, q0.cell_class);
  // A large sigma fades the weight to min_weight, no further: the cell stays known.
  ASSERT_EQ(map->move_to(0.0F, 0.0F, 0.5F), Status::kOk);
  EXPECT_EQ(map->ccm_layer(0).cell(index)->weight, map->params().min_weight);
  EXPECT_EQ(map->query_layer(0, mx, my).cell_class, q0.cell_class);
  // The next point now moves the mean by w / (W + w) = 1/6 of its distance, not 1/1001.
  PointXYZ p{mx, my, q0.height_m + 0.06F};
  ASSERT_EQ(map->update_frame(&p, 1, PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
  EXPECT_NEAR(map->ccm_layer(0).cell(index)->mean_z - after.mean_z, 0.06F / 6.0F, 2e-4F);
}

TEST(Motion, FlatCellsAndZeroSigmaAreUntouched) {
  // Exactly level ground: every covariance with z is 0, the inclination 0, the cell untouched.
  auto flat = std::make_unique<Stack<SingleCcmConfig>>();
  ASSERT_EQ(flat->init(default_stack_params(0.08F)), Status::kOk);
  std::vector<PointXYZ> level;
  for (std::uint32_t i = 0; i < 50000U; ++i) level.push_back(PointXYZ{hash_unit(i, 1U) - 0.5F, hash_unit(i, 2U) - 0.5F, 0.1F});
  ASSERT_EQ(flat->update_frame(level.data(), level.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
  const RingGrid<CcmCell>& g = flat->ccm_layer(0);
  const std::vector<CcmCell> level_before(g.storage(), g.storage() + g.cell_count());
  ASSERT_EQ(flat->move_to(0.0F, 0.0F, 0.05F), Status::kOk);
  EXPECT_EQ(std::memcmp(level_before.data(), g.storage(), level_before.size() * sizeof(CcmCell)), 0);
  const auto sloped = noisy_plane(0.2F, 0.1F);
  const auto plain = noisy_plane(0.2F, 0.1F);
  ASSERT_TRUE(sloped && plain);
  // sigma = 0: bitwise the plain move.
  ASSERT_EQ(sloped->move_to(0.5F, 0.3F, 0.0F), Status::kOk);
  ASSERT_EQ(plain->move_to(0.5F, 0.3F), Status::kOk);
  const RingGrid<CcmCell>& a = sloped->ccm_layer(0);
  const RingGrid<CcmCell>& b = plain->ccm_layer(0);
  EXPECT_EQ(std::memcmp(a.storage(), b.storage(), a.cell_count() * sizeof(CcmCell)), 0);
  EXPECT_EQ(a.centre(), b.centre());
}

TEST(Motion, RefusedUncertainMovesAreCountedAndChangeNothing) {
  const auto map = noisy_plane(0.2F, 0.1F);
  ASSERT_NE(map, nullptr);
  const RingGrid<CcmCell>& grid = map->ccm_layer(0);
  std::vector<CcmCell> before(grid.storage(), grid.storage() + grid.cell_count());
  EXPECT_EQ(map->move_to(1.0F, 0.0F, std::nanf("")), Status::kNonFiniteInput);
  EXPECT_EQ(map->move_to(1.0F, 0.0F, INFINITY), Status::kNonFiniteInput);
  EXPECT_EQ(map->move_to(1.0F, 0.0F, -0.01F), Status::kInvalidArgument);
  EXPECT_EQ(map->move_to(1.0F, 0.0F, 2e5F), Status::kOutOfRange);
  EXPECT_EQ(map->move_to(std::nanf(""), 0.0F, 0.01F), Status::kNonFiniteInput);
  EXPECT_EQ(map->move_to(2e5F, 0.0F, 0.01F), Status::kOutOfRange);
  EXPECT_EQ(map->rejected_moves(), 6U);
  EXPECT_EQ(std::memcmp(before.data(), grid.storage(), before.size() * sizeof(CcmCell)), 0);
  EXPECT_EQ(grid.centre(), (CellIndex{0, 0}));
  const auto fresh = std::make_unique<Stack<CadreConfig>>();
  EXPECT_EQ(fresh->move_to(0.0F, 0.0F, 0.01F), Status::kNotInitialised);
}

}  // namespace
}  // namespace ccmap
