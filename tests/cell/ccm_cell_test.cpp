// CCM cell: incremental update, limiter, batch merge, queries and degenerate input, each
// checked against a double-precision batch reference computed here from the same points, for
// both cell kinds (CcmCell, CcmPaperCell) where the rule is the same. The lateral covariance and
// the least-squares solve of the full cell: tests/cell/ccm_lateral_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "ccmap/cell/ccm_cell.hpp"
#include "support/ccm_kinds.hpp"
#include "support/reference.hpp"

namespace ccmap {
namespace {

using test::Point;
using test::RefMoments;
using test::Rng;

constexpr float kNoLimit = kNoWeightLimit;

template <typename Cell>
class CcmCellBothKinds : public ::testing::Test {};
TYPED_TEST_SUITE(CcmCellBothKinds, test::CcmCellKinds, test::CcmKindNames);

template <typename Cell = CcmCell>
Cell fold_sequential(const std::vector<Point>& pts, float weight_limit = kNoLimit) {
  Cell cell{};
  for (const Point& p : pts) {
    const Status s = ccm_update(cell, static_cast<float>(p.x), static_cast<float>(p.y),
                                static_cast<float>(p.z), static_cast<float>(p.w), weight_limit);
    EXPECT_EQ(s, Status::kOk);
  }
  return cell;
}

template <typename Cell>
void expect_matches_reference(const Cell& cell, const RefMoments& ref, double tol_mean,
                              double tol_var, const char* what) {
  SCOPED_TRACE(what);
  EXPECT_NEAR(cell.weight, ref.weight, 1e-5 * ref.weight) << "weight";
  EXPECT_NEAR(cell.mean_x, ref.mean_x, tol_mean) << "mean_x";
  EXPECT_NEAR(cell.mean_y, ref.mean_y, tol_mean) << "mean_y";
  EXPECT_NEAR(cell.mean_z, ref.mean_z, tol_mean) << "mean_z";
  const double w = cell.weight;
  EXPECT_NEAR(cell.s_xx / w, ref.var_xx, tol_var) << "sigma_xx^2";
  EXPECT_NEAR(cell.s_yy / w, ref.var_yy, tol_var) << "sigma_yy^2";
  EXPECT_NEAR(cell.s_zz / w, ref.var_zz, tol_var) << "sigma_zz^2";
  EXPECT_NEAR(cell.s_xz / w, ref.cov_xz, tol_var) << "sigma_xz^2";
  EXPECT_NEAR(cell.s_yz / w, ref.cov_yz, tol_var) << "sigma_yz^2";
  if constexpr (kHasLateralCovariance<Cell>) {
    EXPECT_NEAR(cell.s_xy / w, ref.cov_xy, tol_var) << "sigma_xy^2";
  }
}

std::vector<Point> uniform_cloud(Rng& rng, int n, double width, double z0, double a, double b,
                                 double noise, bool random_weights = false) {
  std::vector<Point> pts;
  pts.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    Point p;
    p.x = rng.uniform(-width / 2, width / 2);
    p.y = rng.uniform(-width / 2, width / 2);
    p.z = z0 + a * p.x + b * p.y + noise * rng.normal();
    p.w = random_weights ? rng.uniform(0.2, 3.0) : 1.0;
    pts.push_back(p);
  }
  return pts;
}

// ---------------------------------------------------------------------------------------------
// Update against the double batch reference
// ---------------------------------------------------------------------------------------------

TYPED_TEST(CcmCellBothKinds, RandomCloudMatchesDoubleBatchReference) {
  Rng rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const auto pts = uniform_cloud(rng, 2000, 0.32, rng.uniform(-3, 3), rng.uniform(-1, 1),
                                   rng.uniform(-1, 1), rng.uniform(0.001, 0.05), trial % 2 == 1);
    const RefMoments ref = test::reference_moments(pts);
    const TypeParam cell = fold_sequential<TypeParam>(pts);
    // Float: means to 1e-5 m, variances to 1e-6 m^2 (relative ~1e-4 of w^2/12 = 8.5e-3 m^2).
    expect_matches_reference(cell, ref, 1e-5, 1e-6, "random cloud");
  }
}

TYPED_TEST(CcmCellBothKinds, InclinedPlaneGivesKnownSlopeAndZeroNormalVariance) {
  // A regular 20 x 20 grid of samples over a 32 cm cell: x and y are uncorrelated, so the
  // paper's per-axis slopes equal the least-squares plane exactly.
  const double width = 0.32;
  for (const double deg_x : {0.0, 5.0, 10.0, 20.0, 35.0}) {
    const double a = std::tan(deg_x * M_PI / 180.0);
    const double b = -0.5 * a + 0.1;
    std::vector<Point> pts;
    for (int i = 0; i < 20; ++i) {
      for (int j = 0; j < 20; ++j) {
        Point p;
        p.x = -width / 2 + (i + 0.5) * width / 20;
        p.y = -width / 2 + (j + 0.5) * width / 20;
        p.z = 1.7 + a * p.x + b * p.y;
        pts.push_back(p);
      }
    }
    test::RefPlane plane;
    ASSERT_TRUE(test::reference_plane(pts, &plane));
    const TypeParam cell = fold_sequential<TypeParam>(pts);
    const CcmSurface s = ccm_surface(cell);
    EXPECT_NEAR(s.slope_x, plane.a, 2e-4) << "slope_x off on a " << deg_x << " deg plane";
    EXPECT_NEAR(s.slope_y, plane.b, 2e-4) << "slope_y off on a " << deg_x << " deg plane";
    EXPECT_NEAR(s.normal_variance, 0.0, 1e-8) << "a flat plane has no normal variance";
    // Sub-cell height anywhere in the cell follows the plane (eq. 10).
    for (const double qx : {-0.15, 0.0, 0.07}) {
      for (const double qy : {-0.1, 0.12}) {
        EXPECT_NEAR(ccm_height_at(cell, s, static_cast<float>(qx), static_cast<float>(qy)),
                    plane.c + plane.a * qx + plane.b * qy, 1e-5)
            << "sub-cell height at (" << qx << "," << qy << ") on a " << deg_x << " deg plane";
      }
    }
    EXPECT_NEAR(ccm_inclination(s), std::hypot(a, b), 2e-4);
  }
}

TEST(CcmPaperCell, NoisyPlaneSlopesFollowEq9AndMissTheLeastSquaresPlaneByTheSampleCorrelation) {
  Rng rng(7);
  const auto pts = uniform_cloud(rng, 5000, 0.16, 0.4, 0.3, -0.2, 0.01);
  const RefMoments ref = test::reference_moments(pts);
  test::RefPlane plane;
  ASSERT_TRUE(test::reference_plane(pts, &plane));
  const CcmSurface s = ccm_surface(fold_sequential<CcmPaperCell>(pts));
  // Per-axis slopes (eq. 9) equal the double evaluation of eq. 9 to float precision ...
  EXPECT_NEAR(s.slope_x, ref.slope_x(), 1e-3);
  EXPECT_NEAR(s.slope_y, ref.slope_y(), 1e-3);
  EXPECT_NEAR(s.normal_variance, ref.normal_variance(), 2e-6);
  // ... and the least-squares plane only within the small xy correlation of a random cloud.
  EXPECT_NEAR(s.slope_x, plane.a, 0.02);
  EXPECT_NEAR(s.slope_y, plane.b, 0.02);
  EXPECT_NEAR(s.normal_variance, plane.residual_variance, 1e-5);
  EXPECT_NEAR(s.normal_variance, 1e-4, 1.5e-5) << "residual should be the 1 cm noise squared";
}

TEST(CcmFullCell, NoisyPlaneSlopesAndResidualAreTheLeastSquaresPlane) {
  Rng rng(7);
  const auto pts = uniform_cloud(rng, 5000, 0.16, 0.4, 0.3, -0.2, 0.01);
  test::RefPlane plane;
  ASSERT_TRUE(test::reference_plane(pts, &plane));
  const CcmSurface s = ccm_surface(fold_sequential<CcmCell>(pts));
  EXPECT_NEAR(s.slope_x, plane.a, 2e-4) << "slope_x off the least-squares plane";
  EXPECT_NEAR(s.slope_y, plane.b, 2e-4) << "slope_y off the least-squares plane";
  EXPECT_NEAR(s.normal_variance, plane.residual_variance, 2e-7) << "normal variance is not the plane's residual";
  EXPECT_NEAR(s.normal_variance, 1e-4, 1.5e-5) << "residual should be the 1 cm noise squared";
}

TYPED_TEST(CcmCellBothKinds, StepNormalVarianceFollowsReferenceAndAnalyticCurve) {
  // A 24 cm step covering a share c of a 32 cm cell (the Fig. 4 setting). Analytic residual of
  // the per-axis plane fit for a step of height h: h^2 u (1 - 3u) with u = c (1 - c); it peaks
  // at c ~ 21% and 79% and has a local minimum at 50% (docs/design.md, "Thresholds").
  const double width = 0.32, height = 0.24;
  Rng rng(3);
  for (const double coverage : {0.1, 0.21, 0.3, 0.5, 0.7, 0.9}) {
    std::vector<Point> pts;
    for (int i = 0; i < 20000; ++i) {
      Point p;
      p.x = rng.uniform(-width / 2, width / 2);
      p.y = rng.uniform(-width / 2, width / 2);
      p.z = (p.x > width / 2 - coverage * width) ? height : 0.0;
      pts.push_back(p);
    }
    const RefMoments ref = test::reference_moments(pts);
    const CcmSurface s = ccm_surface(fold_sequential<TypeParam>(pts));
    EXPECT_NEAR(s.normal_variance, ref.normal_variance(), 1e-5)
        << "normal variance off the double reference at coverage " << coverage;
    const double u = coverage * (1.0 - coverage);
    const double analytic = height * height * u * (1.0 - 3.0 * u);
    EXPECT_NEAR(s.normal_variance, analytic, 0.05 * analytic)
        << "normal variance off the analytic step curve at coverage " << coverage;
  }
}

// ---------------------------------------------------------------------------------------------
// Eq. (5) as printed vs the stable form
// ---------------------------------------------------------------------------------------------

template <typename T>
struct NaiveCell {
  T w = 0, mx = 0, my = 0, mz = 0, sxx = 0, sxz = 0;
  void update(T x, T y, T z, T wt) {
    (void)y;
    const T w_new = w + wt;
    const T mx_new = mx + wt / w_new * (x - mx);
    const T mz_new = mz + wt / w_new * (z - mz);
    sxx += wt * (x - mx) * (x - mx_new);
    // Eq. (5) as printed: products of means, subtracted.
    sxz += wt * (x * z - mx * mz) + w_new * (-mx_new * mz_new + mx * mz);
    w = w_new;
    mx = mx_new;
    mz = mz_new;
  }
};

TEST(CcmCell, StableCovarianceEqualsEq5InDoubleAndBeatsItInFloat) {
  // Heights far from 0 (a crater floor 500 m below the stack origin is legal) with a small
  // correlated signal: eq. (5) subtracts W * mu_x * mu_z products of order 1e2 to find
  // covariances of order 1e-3.
  Rng rng(11);
  std::vector<Point> pts;
  for (int i = 0; i < 20000; ++i) {
    Point p;
    p.x = 0.05 + rng.uniform(-0.04, 0.04);
    p.y = rng.uniform(-0.04, 0.04);
    p.z = -500.0 + 0.5 * p.x + 0.002 * rng.normal();
    pts.push_back(p);
  }
  const RefMoments ref = test::reference_moments(pts);

  NaiveCell<double> naive_d;
  NaiveCell<float> naive_f;
  for (const Point& p : pts) {
    naive_d.update(p.x, p.y, p.z, 1.0);
    naive_f.update(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z), 1.0F);
  }
  const CcmCell stable = fold_sequential(pts);

  // In double, eq. (5) and the stable form agree (both are exact in real arithmetic).
  EXPECT_NEAR(naive_d.sxz / naive_d.w, ref.cov_xz, 1e-9 * std::fabs(ref.cov_xz) + 1e-12);
  const double err_stable = std::fabs(stable.s_xz / stable.weight - ref.cov_xz);
  const double err_naive = std::fabs(static_cast<double>(naive_f.sxz) / naive_f.w - ref.cov_xz);
  EXPECT_LT(err_stable, 1e-3 * std::fabs(ref.cov_xz)) << "stable float covariance not accurate";
  EXPECT_GT(err_naive, 10.0 * err_stable)
      << "eq. (5) in float should be much worse than the stable form (naive " << err_naive
      << ", stable " << err_stable << ")";
}

// ---------------------------------------------------------------------------------------------
// Weight limiter, eqs. (6)-(7)
// ---------------------------------------------------------------------------------------------

TYPED_TEST(CcmCellBothKinds, LimiterHoldsRelativeWeightOfNewPoints) {
  const float limit = 50.0F;
  TypeParam cell{};
  Rng rng(5);
  for (int i = 0; i < 500; ++i) {
    ASSERT_EQ(ccm_update(cell, static_cast<float>(rng.uniform(-0.1, 0.1)),
                         static_cast<float>(rng.uniform(-0.1, 0.1)), 0.0F, 1.0F, limit),
              Status::kOk);
  }
  EXPECT_FLOAT_EQ(cell.weight, limit);
  // A new point at height 1 moves the mean by exactly w / (W_l + w) of the way, every time.
  for (int i = 0; i < 5; ++i) {
    const float before = cell.mean_z;
    const float w = 1.0F;
    ASSERT_EQ(ccm_update(cell, 0.0F, 0.0F, 1.0F, w, limit), Status::kOk);
    const float gain = (cell.mean_z - before) / (1.0F - before);
    EXPECT_NEAR(gain, w / (limit + w), 1e-5) << "relative weight after convergence";
    EXPECT_FLOAT_EQ(cell.weight, limit);
  }
}

TYPED_TEST(CcmCellBothKinds, LimiterKeepsVariancesUnchanged) {
  TypeParam cell{};
  Rng rng(9);
  const auto pts = uniform_cloud(rng, 100, 0.2, 0.0, 0.2, 0.1, 0.01);
  for (const Point& p : pts) {
    ASSERT_EQ(ccm_update(cell, static_cast<float>(p.x), static_cast<float>(p.y),
                         static_cast<float>(p.z), 1.0F, kNoLimit), Status::kOk);
  }
  const TypeParam before = cell;
  ccm_apply_weight_limit(cell, 10.0F);
  EXPECT_FLOAT_EQ(cell.weight, 10.0F);
  EXPECT_NEAR(cell.s_xx / cell.weight, before.s_xx / before.weight, 1e-7);
  EXPECT_NEAR(cell.s_zz / cell.weight, before.s_zz / before.weight, 1e-9);
  EXPECT_NEAR(cell.s_xz / cell.weight, before.s_xz / before.weight, 1e-8);
  if constexpr (kHasLateralCovariance<TypeParam>) {
    EXPECT_NE(before.s_xy, 0.0F) << "test premise: a sample correlation to scale";
    EXPECT_NEAR(cell.s_xy / cell.weight, before.s_xy / before.weight, 1e-9) << "the limiter must scale s_xy too";
  }
  EXPECT_EQ(cell.mean_z, before.mean_z);
}

// Updates of CcmCell.HundredMillionUpdatesStayFiniteAndBounded: 10^8; 10^7 under the emulator
// (tests/cell/CMakeLists.txt), where the cell soak runs 10^7 too: the limiter's memory is W_l =
// 10^3 updates, so the moments are stationary long before either count.
#ifndef CCMAP_CELL_LIMITER_UPDATES
#define CCMAP_CELL_LIMITER_UPDATES 100000000U
#endif

TEST(CcmCell, HundredMillionUpdatesStayFiniteAndBounded) {
  // 1e8 updates of one cell with the limiter on: S stays finite and bounded by W_l times the
  // largest squared spread of the input, and the moments track the stationary distribution.
  const float limit = 1000.0F;
  CcmCell cell{};
  std::uint32_t state = 12345U;
  auto next = [&state]() {
    state = state * 1664525U + 1013904223U;  // LCG: cheap enough for 1e8 draws
    return static_cast<float>(state >> 8) * (1.0F / 16777216.0F) - 0.5F;  // [-0.5, 0.5)
  };
  const float width = 0.08F;
  for (std::uint32_t i = 0; i < CCMAP_CELL_LIMITER_UPDATES; ++i) {
    const float x = width * next();
    const float y = width * next();
    const float z = 2.0F + 0.5F * x + 0.01F * next();
    detail::ccm_update_unchecked(cell, x, y, z, 1.0F, limit);
  }
  for (const float s : {cell.s_xx, cell.s_yy, cell.s_zz, cell.s_xz, cell.s_yz, cell.mean_x,
                        cell.mean_y, cell.mean_z}) {
    ASSERT_TRUE(std::isfinite(s));
  }
  EXPECT_FLOAT_EQ(cell.weight, limit);
  EXPECT_LE(cell.s_xx, limit * width * width);
  const double expected_var_x = width * width / 12.0;
  EXPECT_NEAR(cell.s_xx / cell.weight, expected_var_x, 0.25 * expected_var_x);
  const CcmSurface s = ccm_surface(cell);
  EXPECT_NEAR(s.slope_x, 0.5, 0.1) << "slope drifted after " << CCMAP_CELL_LIMITER_UPDATES << " updates";
  EXPECT_NEAR(cell.mean_z, 2.0, 0.01);
}

// ---------------------------------------------------------------------------------------------
// Batch merge
// ---------------------------------------------------------------------------------------------

TYPED_TEST(CcmCellBothKinds, BatchUpdateEqualsSequential) {
  Rng rng(21);
  for (int trial = 0; trial < 10; ++trial) {
    const auto first = uniform_cloud(rng, 300, 0.64, 1.0, 0.1, 0.2, 0.02, true);
    const auto second = uniform_cloud(rng, 700, 0.64, 1.1, 0.1, 0.2, 0.05, true);
    TypeParam sequential = fold_sequential<TypeParam>(first);
    TypeParam batched = sequential;
    for (const Point& p : second) {
      ASSERT_EQ(ccm_update(sequential, static_cast<float>(p.x), static_cast<float>(p.y),
                           static_cast<float>(p.z), static_cast<float>(p.w), kNoLimit),
                Status::kOk);
    }
    std::vector<float> x, y, z, w;
    for (const Point& p : second) {
      x.push_back(static_cast<float>(p.x));
      y.push_back(static_cast<float>(p.y));
      z.push_back(static_cast<float>(p.z));
      w.push_back(static_cast<float>(p.w));
    }
    const CcmBatchCounts counts = ccm_update_batch(batched, x.data(), y.data(), z.data(), w.data(),
                                                   1.0F, x.size(), kNoLimit);
    EXPECT_EQ(counts.accepted, second.size());
    std::vector<Point> all = first;
    all.insert(all.end(), second.begin(), second.end());
    const RefMoments ref = test::reference_moments(all);
    expect_matches_reference(batched, ref, 1e-5, 2e-6, "batched");
    expect_matches_reference(sequential, ref, 1e-5, 2e-6, "sequential");
  }
}

TYPED_TEST(CcmCellBothKinds, MergeOfTwoCellsEqualsCellOfUnion) {
  Rng rng(33);
  const auto a = uniform_cloud(rng, 400, 0.3, -2.0, 0.4, 0.0, 0.01, true);
  const auto b = uniform_cloud(rng, 100, 0.3, -1.8, 0.0, 0.4, 0.03, true);
  TypeParam cell_a = fold_sequential<TypeParam>(a);
  const TypeParam cell_b = fold_sequential<TypeParam>(b);
  ASSERT_EQ(ccm_merge(cell_a, cell_b, kNoLimit), Status::kOk);
  std::vector<Point> all = a;
  all.insert(all.end(), b.begin(), b.end());
  expect_matches_reference(cell_a, test::reference_moments(all), 1e-5, 2e-6, "merged");
}

TYPED_TEST(CcmCellBothKinds, BatchSkipsAndCountsInvalidPoints) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const float x[] = {0.0F, nan, 0.01F, 0.02F, 2.0e5F, -0.01F};
  const float y[] = {0.0F, 0.0F, inf, 0.01F, 0.0F, 0.01F};
  const float z[] = {1.0F, 1.0F, 1.0F, 1.2F, 1.0F, 1.1F};
  const float w[] = {1.0F, 1.0F, 1.0F, -1.0F, 1.0F, 2.0F};
  TypeParam cell{};
  const CcmBatchCounts counts = ccm_update_batch(cell, x, y, z, w, 1.0F, 6U, kNoLimit);
  EXPECT_EQ(counts.accepted, 2U);
  EXPECT_EQ(counts.rejected_non_finite, 2U);
  EXPECT_EQ(counts.rejected_out_of_range, 1U);
  EXPECT_EQ(counts.rejected_weight, 1U);
  EXPECT_FLOAT_EQ(cell.weight, 3.0F);
  EXPECT_NEAR(cell.mean_z, (1.0 + 2.0 * 1.1) / 3.0, 1e-6);
}

// ---------------------------------------------------------------------------------------------
// Coverage, eq. (12)
// ---------------------------------------------------------------------------------------------

TYPED_TEST(CcmCellBothKinds, CoverageSeparatesFullAndPartialCells) {
  Rng rng(4);
  const float width = 0.32F;
  TypeParam full{};
  TypeParam half{};
  for (int i = 0; i < 3000; ++i) {
    const float x = static_cast<float>(rng.uniform(-0.16, 0.16));
    const float y = static_cast<float>(rng.uniform(-0.16, 0.16));
    ASSERT_EQ(ccm_update(full, x, y, 0.0F, 1.0F, kNoLimit), Status::kOk);
    // Shadow: only the near half of the cell seen, sigma_x = 0.5 sigma_r < 0.8 sigma_r.
    ASSERT_EQ(ccm_update(half, 0.5F * x - 0.08F, y, 0.0F, 1.0F, kNoLimit), Status::kOk);
  }
  EXPECT_TRUE(ccm_is_covered(full, width, 0.8F, 3.0F));
  EXPECT_FALSE(ccm_is_covered(half, width, 0.8F, 3.0F)) << "a half-shadowed cell must be unknown";
  EXPECT_FALSE(ccm_is_covered(full, width, 0.8F, 5000.0F)) << "minimum weight not enforced";
  EXPECT_FALSE(ccm_is_covered(TypeParam{}, width, 0.8F, 0.0F)) << "an empty cell is never covered";
}

// ---------------------------------------------------------------------------------------------
// Degenerate and hostile input
// ---------------------------------------------------------------------------------------------

template <typename Cell>
void expect_all_finite(const Cell& c) {
  static_assert(sizeof(Cell) % sizeof(float) == 0U, "CCM cells are packed floats");
  float v[sizeof(Cell) / sizeof(float)];
  std::memcpy(v, &c, sizeof v);
  for (const float f : v) EXPECT_TRUE(std::isfinite(f));
  const CcmSurface s = ccm_surface(c);
  EXPECT_TRUE(std::isfinite(s.slope_x));
  EXPECT_TRUE(std::isfinite(s.slope_y));
  EXPECT_TRUE(std::isfinite(s.normal_variance));
  EXPECT_GE(s.normal_variance, 0.0F);
  EXPECT_TRUE(std::isfinite(ccm_height_at(c, s, 0.1F, -0.1F)));
  EXPECT_TRUE(std::isfinite(ccm_elevation_variance(c, s, 0.1F, -0.1F)));
}

TYPED_TEST(CcmCellBothKinds, SinglePointHasNoSlopeNoVarianceAndIsNotCovered) {
  TypeParam cell{};
  ASSERT_EQ(ccm_update(cell, 0.01F, -0.02F, 3.0F, 1.0F, kNoLimit), Status::kOk);
  expect_all_finite<TypeParam>(cell);
  const CcmSurface s = ccm_surface(cell);
  EXPECT_EQ(s.slope_x, 0.0F);
  EXPECT_EQ(s.slope_y, 0.0F);
  EXPECT_EQ(s.normal_variance, 0.0F);
  EXPECT_FLOAT_EQ(ccm_height_at(cell, s, 0.05F, 0.05F), 3.0F);
  EXPECT_FALSE(ccm_is_covered(cell, 0.1F, 0.8F, 1.0F));
}

TYPED_TEST(CcmCellBothKinds, PointsOnALineGiveZeroSlopeAlongTheDegenerateAxis) {
  TypeParam on_x_line{};  // all at x = 0.02: sigma_xx = 0
  TypeParam on_y_line{};  // all at y = -0.03: sigma_yy = 0
  for (int i = 0; i < 50; ++i) {
    const float t = -0.05F + 0.002F * static_cast<float>(i);
    ASSERT_EQ(ccm_update(on_x_line, 0.02F, t, 1.0F + 0.3F * t, 1.0F, kNoLimit), Status::kOk);
    ASSERT_EQ(ccm_update(on_y_line, t, -0.03F, 1.0F - 0.2F * t, 1.0F, kNoLimit), Status::kOk);
  }
  expect_all_finite<TypeParam>(on_x_line);
  expect_all_finite<TypeParam>(on_y_line);
  EXPECT_EQ(ccm_surface(on_x_line).slope_x, 0.0F);
  EXPECT_NEAR(ccm_surface(on_x_line).slope_y, 0.3F, 1e-4);
  EXPECT_EQ(ccm_surface(on_y_line).slope_y, 0.0F);
  EXPECT_NEAR(ccm_surface(on_y_line).slope_x, -0.2F, 1e-4);
  EXPECT_FALSE(ccm_is_covered(on_x_line, 0.1F, 0.8F, 1.0F));
  EXPECT_FALSE(ccm_is_covered(on_y_line, 0.1F, 0.8F, 1.0F));
}

TYPED_TEST(CcmCellBothKinds, RejectedInputLeavesCellBitwiseUnchanged) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const float denorm = std::numeric_limits<float>::denorm_min();
  TypeParam cell{};
  for (int i = 0; i < 10; ++i) {
    ASSERT_EQ(ccm_update(cell, 0.01F * static_cast<float>(i), 0.0F, 1.0F, 1.0F, 100.0F), Status::kOk);
  }
  const TypeParam before = cell;
  struct Case {
    float x, y, z, w, limit;
    Status expected;
  };
  const Case cases[] = {
      {nan, 0, 0, 1, 100, Status::kNonFiniteInput},  {0, inf, 0, 1, 100, Status::kNonFiniteInput},
      {0, 0, -inf, 1, 100, Status::kNonFiniteInput}, {2e5F, 0, 0, 1, 100, Status::kOutOfRange},
      {0, 0, 1e30F, 1, 100, Status::kOutOfRange},    {0, 0, 0, 0, 100, Status::kBadWeight},
      {0, 0, 0, -1, 100, Status::kBadWeight},        {0, 0, 0, nan, 100, Status::kBadWeight},
      {0, 0, 0, inf, 100, Status::kBadWeight},       {0, 0, 0, 1e7F, 100, Status::kBadWeight},
      {0, 0, 0, denorm * 0.0F, 100, Status::kBadWeight},
      {0, 0, 0, 1, 0, Status::kInvalidArgument},     {0, 0, 0, 1, -5, Status::kInvalidArgument},
      {0, 0, 0, 1, nan, Status::kInvalidArgument},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(ccm_update(cell, c.x, c.y, c.z, c.w, c.limit), c.expected)
        << "input (" << c.x << "," << c.y << "," << c.z << ") w=" << c.w << " limit=" << c.limit;
    EXPECT_EQ(std::memcmp(&cell, &before, sizeof cell), 0) << "refused input changed the cell";
  }
  TypeParam bad_other{};
  bad_other.weight = -1.0F;
  EXPECT_EQ(ccm_merge(cell, bad_other, 100.0F), Status::kBadWeight);
  bad_other.weight = nan;
  EXPECT_EQ(ccm_merge(cell, bad_other, 100.0F), Status::kBadWeight);
  EXPECT_EQ(ccm_merge(cell, before, 0.0F), Status::kInvalidArgument);
  EXPECT_EQ(std::memcmp(&cell, &before, sizeof cell), 0);
}

TYPED_TEST(CcmCellBothKinds, DenormalCoordinatesAndTinyWeightsStayFinite) {
  const float denorm = std::numeric_limits<float>::denorm_min();
  TypeParam cell{};
  ASSERT_EQ(ccm_update(cell, denorm, -denorm, denorm, 1.0F, kNoLimit), Status::kOk);
  ASSERT_EQ(ccm_update(cell, 0.0F, 0.0F, 0.0F, 1e-30F, kNoLimit), Status::kOk);
  ASSERT_EQ(ccm_update(cell, 0.01F, 0.01F, 0.01F, kMaxMeasurementWeight, kNoLimit), Status::kOk);
  expect_all_finite<TypeParam>(cell);
}

TYPED_TEST(CcmCellBothKinds, SubnormalWeightLimitIsRefusedAndTinyWeightsStayFinite) {
  // Found by the stack fuzzer: W limited to 5.5e-41 made S / W overflow (normal variance Inf)
  // and leverage / W overflow (elevation variance 0 * Inf = NaN). Such limits are refused; tiny
  // measurement weights stay legal and the queries stay finite.
  TypeParam cell{};
  const TypeParam before = cell;
  EXPECT_EQ(ccm_update(cell, 0.0F, 0.0F, 0.5F, 1.0F, 5.52447907e-41F), Status::kInvalidArgument);
  EXPECT_EQ(ccm_update(cell, 0.0F, 0.0F, 0.5F, 1.0F, 0.5F * kMinWeightLimit), Status::kInvalidArgument);
  EXPECT_EQ(std::memcmp(&cell, &before, sizeof cell), 0);
  TypeParam flat{};
  TypeParam rough{};
  for (int i = 0; i < 10; ++i) {
    const float x = 0.001F * static_cast<float>(i);
    ASSERT_EQ(ccm_update(flat, x, -x, 0.5F, 1e-40F, kMinWeightLimit), Status::kOk);
    ASSERT_EQ(ccm_update(rough, x, -x, 0.5F + 0.01F * static_cast<float>(i % 2), 1e-40F, kNoLimit), Status::kOk);
  }
  expect_all_finite<TypeParam>(flat);
  expect_all_finite<TypeParam>(rough);
  // The elevation variance saturates rather than overflowing when W is tiny.
  EXPECT_LE(ccm_elevation_variance(rough, ccm_surface(rough), 0.01F, 0.01F), std::numeric_limits<float>::max());
}

TYPED_TEST(CcmCellBothKinds, EmptyCellQueriesAreZeroAndFinite) {
  const TypeParam empty{};
  expect_all_finite<TypeParam>(empty);
  EXPECT_EQ(ccm_variance(empty.s_zz, empty.weight), 0.0F);
}

}  // namespace
}  // namespace ccmap
