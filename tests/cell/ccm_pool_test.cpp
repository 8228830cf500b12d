// Pooling four fine CCM cells into one coarse cell (eqs. 13-15 with the child-centre offsets),
// for both cell kinds. Missing children and the cross term: tests/cell/ccm_lateral_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ccmap/cell/ccm_cell.hpp"
#include "support/ccm_kinds.hpp"
#include "support/reference.hpp"

namespace ccmap {
namespace {

using test::Point;
using test::Rng;

template <typename Cell>
struct FineAndCoarse {
  Cell children[4]{};
  Cell coarse{};
};

template <typename Cell>
class CcmPool : public ::testing::Test {};
TYPED_TEST_SUITE(CcmPool, test::CcmCellKinds, test::CcmKindNames);

// Fills one coarse cell of width 2*child and its four children from the same points.
template <typename Cell, typename HeightFn>
FineAndCoarse<Cell> fill(Rng& rng, int n, float child, HeightFn height) {
  FineAndCoarse<Cell> out;
  const float half = 0.5F * child;
  for (int i = 0; i < n; ++i) {
    const float x = static_cast<float>(rng.uniform(-child, child));
    const float y = static_cast<float>(rng.uniform(-child, child));
    const float z = height(x, y, rng);
    const int ix = x >= 0.0F ? 1 : 0;
    const int iy = y >= 0.0F ? 1 : 0;
    const float cx = ix != 0 ? half : -half;
    const float cy = iy != 0 ? half : -half;
    EXPECT_EQ(ccm_update(out.children[ix + 2 * iy], x - cx, y - cy, z, 1.0F, kNoWeightLimit), Status::kOk);
    EXPECT_EQ(ccm_update(out.coarse, x, y, z, 1.0F, kNoWeightLimit), Status::kOk);
  }
  return out;
}

TYPED_TEST(CcmPool, FourFineCellsEqualOneCoarseCellOnAUniformCloud) {
  Rng rng(2);
  const float child = 0.16F;
  const auto cells = fill<TypeParam>(rng, 40000, child, [](float x, float y, Rng& r) {
    return 0.5F + 0.3F * x - 0.15F * y + 0.01F * static_cast<float>(r.normal());
  });
  const TypeParam pooled = ccm_pool4(cells.children, child, kNoWeightLimit);
  const TypeParam& direct = cells.coarse;
  EXPECT_FLOAT_EQ(pooled.weight, direct.weight);
  // Equal-area weighting differs from point weighting only by the random imbalance of the
  // four point counts (~0.5% for 10000 points each): tolerances reflect that.
  EXPECT_NEAR(pooled.mean_x, direct.mean_x, 2e-3);
  EXPECT_NEAR(pooled.mean_y, direct.mean_y, 2e-3);
  EXPECT_NEAR(pooled.mean_z, direct.mean_z, 1e-3);
  const auto var = [](float s, float w) { return s / w; };
  EXPECT_NEAR(var(pooled.s_xx, pooled.weight), var(direct.s_xx, direct.weight), 2e-4);
  EXPECT_NEAR(var(pooled.s_yy, pooled.weight), var(direct.s_yy, direct.weight), 2e-4);
  EXPECT_NEAR(var(pooled.s_zz, pooled.weight), var(direct.s_zz, direct.weight), 2e-5);
  EXPECT_NEAR(var(pooled.s_xz, pooled.weight), var(direct.s_xz, direct.weight), 5e-5);
  EXPECT_NEAR(var(pooled.s_yz, pooled.weight), var(direct.s_yz, direct.weight), 5e-5);
  const CcmSurface sp = ccm_surface(pooled);
  const CcmSurface sd = ccm_surface(direct);
  EXPECT_NEAR(sp.slope_x, 0.3, 0.01) << "pooled slope_x off";
  EXPECT_NEAR(sp.slope_y, -0.15, 0.01) << "pooled slope_y off";
  EXPECT_NEAR(sp.slope_x, sd.slope_x, 0.01);
  EXPECT_NEAR(sp.normal_variance, sd.normal_variance, 1e-5);
  EXPECT_TRUE(ccm_is_covered(pooled, 2.0F * child, 0.8F, 3.0F));
}

TYPED_TEST(CcmPool, WithoutChildOffsetsTheSlopeWouldBeLost) {
  // The printed eqs. (13)-(15) without the +-w/4 shift see four cells stacked at one centre:
  // a steep plane then pools to slope 0 from the between-child term. With the shift the slope
  // survives; this is the reason for the rule (docs/design.md, "Pooling").
  Rng rng(8);
  const float child = 0.32F;
  const auto cells = fill<TypeParam>(rng, 8000, child, [](float x, float, Rng&) { return 0.7F * x; });
  const CcmSurface sp = ccm_surface(ccm_pool4(cells.children, child, kNoWeightLimit));
  EXPECT_NEAR(sp.slope_x, 0.7, 1e-3);
  EXPECT_NEAR(sp.normal_variance, 0.0, 1e-6);
}

TYPED_TEST(CcmPool, StepBetweenChildrenShowsAsNormalVariance) {
  Rng rng(12);
  const float child = 0.16F;
  const auto cells = fill<TypeParam>(rng, 20000, child, [](float x, float, Rng&) { return x > 0.0F ? 0.2F : 0.0F; });
  const TypeParam pooled = ccm_pool4(cells.children, child, kNoWeightLimit);
  // A 50% step of height h in a cell: residual variance of the best plane is h^2/16 (analytic:
  // the step's variance h^2/4 minus the part explained by the linear fit, 3h^2/16).
  EXPECT_NEAR(ccm_surface(pooled).normal_variance, 0.2 * 0.2 / 16.0, 1e-4);
  EXPECT_NEAR(ccm_surface(pooled).normal_variance, ccm_surface(cells.coarse).normal_variance, 2e-4);
}

TYPED_TEST(CcmPool, MissingChildrenAreLeftOutAndMakeTheParentUnknown) {
  Rng rng(13);
  const float child = 0.1F;
  auto cells = fill<TypeParam>(rng, 4000, child, [](float, float, Rng&) { return 1.0F; });
  cells.children[1] = TypeParam{};
  cells.children[3] = TypeParam{};  // the +x half never seen
  const TypeParam pooled = ccm_pool4(cells.children, child, kNoWeightLimit);
  EXPECT_FLOAT_EQ(pooled.mean_z, 1.0F) << "unobserved children must not pull the height";
  EXPECT_NEAR(pooled.mean_x, -0.05, 2e-3);
  EXPECT_FALSE(ccm_is_covered(pooled, 2.0F * child, 0.8F, 1.0F));
  TypeParam none[4] = {};
  const TypeParam empty = ccm_pool4(none, child, kNoWeightLimit);
  EXPECT_EQ(empty.weight, 0.0F);
  EXPECT_EQ(empty.s_zz, 0.0F);
}

TYPED_TEST(CcmPool, PooledWeightIsLimitedWithVariancesKept) {
  Rng rng(14);
  const float child = 0.1F;
  const auto cells = fill<TypeParam>(rng, 4000, child, [](float x, float, Rng&) { return 0.2F * x; });
  const TypeParam unlimited = ccm_pool4(cells.children, child, kNoWeightLimit);
  const TypeParam limited = ccm_pool4(cells.children, child, 100.0F);
  EXPECT_FLOAT_EQ(limited.weight, 100.0F);
  EXPECT_NEAR(limited.s_xx / limited.weight, unlimited.s_xx / unlimited.weight, 1e-7);
  EXPECT_NEAR(ccm_surface(limited).slope_x, ccm_surface(unlimited).slope_x, 1e-5);
}

TYPED_TEST(CcmPool, BadArgumentsGiveTheZeroCell) {
  TypeParam children[4] = {};
  children[0].weight = 1.0F;
  EXPECT_EQ(ccm_pool4(children, 0.0F, kNoWeightLimit).weight, 0.0F);
  EXPECT_EQ(ccm_pool4(children, -1.0F, kNoWeightLimit).weight, 0.0F);
  EXPECT_EQ(ccm_pool4(children, 0.1F, 0.0F).weight, 0.0F);
  EXPECT_EQ(ccm_pool4(static_cast<const TypeParam*>(nullptr), 0.1F, kNoWeightLimit).weight, 0.0F);
}

TYPED_TEST(CcmPool, ConstantCellsPoolAsCentreSamples) {
  // Four constant children on a plane of slope 0.5 along x and -0.2 along y pool into a parent
  // with exactly that slope (a surfel model without covariance would give 3/4 of it).
  const float child = 0.04F;
  TypeParam children[4];
  for (int i = 0; i < 4; ++i) {
    const float cx = (i & 1) != 0 ? 0.02F : -0.02F;
    const float cy = (i & 2) != 0 ? 0.02F : -0.02F;
    children[i] = ccm_from_constant<TypeParam>(1.0F + 0.5F * cx - 0.2F * cy, 1e-6F, 10.0F, child);
  }
  const TypeParam pooled = ccm_pool4(children, child, kNoWeightLimit);
  const CcmSurface s = ccm_surface(pooled);
  EXPECT_NEAR(s.slope_x, 0.5, 1e-4) << "slope of pooled constant cells";
  EXPECT_NEAR(s.slope_y, -0.2, 1e-4);
  EXPECT_NEAR(s.normal_variance, 1e-6, 1e-8) << "children's own variance carries over";
  EXPECT_NEAR(pooled.s_xx / pooled.weight, 0.02 * 0.02, 1e-8);
  EXPECT_TRUE(ccm_is_covered(pooled, 2.0F * child, 0.8F, 1.0F)) << "four centre samples cover the parent";
  EXPECT_EQ(ccm_from_constant<TypeParam>(1.0F, 0.1F, 0.0F, child).weight, 0.0F);
  EXPECT_EQ(ccm_from_constant<TypeParam>(NAN, 0.1F, 1.0F, child).weight, 0.0F);
}

}  // namespace
}  // namespace ccmap
