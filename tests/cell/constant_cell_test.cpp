// Piece-wise constant cells (Kalman, OMG) against analytic and double batch references.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "ccmap/cell/constant_cell.hpp"
#include "support/reference.hpp"

namespace ccmap {
namespace {

TEST(KalmanCell, EqualVariancesGiveTheMeanAndVarianceOverN) {
  test::Rng rng(1);
  KalmanCell cell{};
  const double r = 0.0004;
  double sum = 0.0;
  const int n = 200;
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 + 0.02 * rng.normal();
    sum += z;
    ASSERT_EQ(kalman_update(cell, static_cast<float>(z), static_cast<float>(r)), Status::kOk);
  }
  EXPECT_NEAR(cell.height, sum / n, 1e-5) << "Kalman height is the mean for equal variances";
  EXPECT_NEAR(cell.variance, r / n, 1e-9) << "Kalman variance is R/n";
  EXPECT_FLOAT_EQ(cell.weight, static_cast<float>(n));
}

TEST(KalmanCell, UnequalVariancesGiveInverseVarianceWeighting) {
  KalmanCell cell{};
  ASSERT_EQ(kalman_update(cell, 1.0F, 0.01F), Status::kOk);
  ASSERT_EQ(kalman_update(cell, 2.0F, 0.04F), Status::kOk);
  const double expected = (1.0 / 0.01 + 2.0 / 0.04) / (1.0 / 0.01 + 1.0 / 0.04);
  EXPECT_NEAR(cell.height, expected, 1e-6);
  EXPECT_NEAR(cell.variance, 1.0 / (1.0 / 0.01 + 1.0 / 0.04), 1e-8);
}

TEST(KalmanCell, VarianceFloorKeepsNewDataRelevant) {
  KalmanCell cell{};
  for (int i = 0; i < 100000; ++i) {
    ASSERT_EQ(kalman_update(cell, 0.0F, 1e-4F, 1e-6F), Status::kOk);
  }
  EXPECT_FLOAT_EQ(cell.variance, 1e-6F);
  ASSERT_EQ(kalman_update(cell, 1.0F, 1e-4F, 1e-6F), Status::kOk);
  EXPECT_NEAR(cell.height, 1e-6 / (1e-6 + 1e-4), 1e-6);
}

TEST(KalmanCell, IgnoresSampleSpread) {
  // The paper's criticism: a rough cell (heights 0 and 1) reports a tiny variance.
  KalmanCell cell{};
  for (int i = 0; i < 100; ++i) {
    ASSERT_EQ(kalman_update(cell, static_cast<float>(i % 2), 1e-4F), Status::kOk);
  }
  EXPECT_LT(cell.variance, 1e-5F);
}

TEST(OmgCell, MixtureVarianceMatchesDoubleReference) {
  test::Rng rng(2);
  OmgCell cell{};
  std::vector<double> z, var, w;
  for (int i = 0; i < 500; ++i) {
    z.push_back(0.3 + 0.05 * rng.normal() + (i % 7 == 0 ? 0.2 : 0.0));
    var.push_back(rng.uniform(1e-5, 1e-3));
    w.push_back(rng.uniform(0.5, 2.0));
    ASSERT_EQ(omg_update(cell, static_cast<float>(z.back()), static_cast<float>(var.back()),
                         static_cast<float>(w.back())), Status::kOk);
  }
  double sw = 0, mean = 0;
  for (std::size_t i = 0; i < z.size(); ++i) {
    sw += w[i];
    mean += w[i] * z[i];
  }
  mean /= sw;
  double mix = 0;
  for (std::size_t i = 0; i < z.size(); ++i) mix += w[i] * (var[i] + (z[i] - mean) * (z[i] - mean));
  mix /= sw;
  EXPECT_NEAR(cell.height, mean, 1e-5);
  EXPECT_NEAR(omg_variance(cell), mix, 1e-6) << "OMG mixture variance off";
}

TEST(OmgCell, LimiterKeepsVarianceAndCapsWeight) {
  OmgCell cell{};
  for (int i = 0; i < 1000; ++i) {
    ASSERT_EQ(omg_update(cell, static_cast<float>(i % 2), 1e-4F, 1.0F, 50.0F), Status::kOk);
  }
  EXPECT_FLOAT_EQ(cell.weight, 50.0F);
  EXPECT_NEAR(omg_variance(cell), 0.25 + 1e-4, 0.02);
}

TEST(ConstantCells, RejectedInputLeavesCellsUnchanged) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  KalmanCell k{};
  OmgCell o{};
  ASSERT_EQ(kalman_update(k, 1.0F, 0.01F), Status::kOk);
  ASSERT_EQ(omg_update(o, 1.0F, 0.01F, 1.0F), Status::kOk);
  const KalmanCell k0 = k;
  const OmgCell o0 = o;
  EXPECT_EQ(kalman_update(k, nan, 0.01F), Status::kNonFiniteInput);
  EXPECT_EQ(kalman_update(k, 1.0F, inf), Status::kNonFiniteInput);
  EXPECT_EQ(kalman_update(k, 1e6F, 0.01F), Status::kOutOfRange);
  EXPECT_EQ(kalman_update(k, 1.0F, 0.0F), Status::kInvalidArgument);
  EXPECT_EQ(kalman_update(k, 1.0F, -1.0F), Status::kInvalidArgument);
  EXPECT_EQ(kalman_update(k, 1.0F, 0.01F, 0.0F), Status::kInvalidArgument);
  EXPECT_EQ(omg_update(o, inf, 0.01F, 1.0F), Status::kNonFiniteInput);
  EXPECT_EQ(omg_update(o, 1.0F, 0.01F, 0.0F), Status::kBadWeight);
  EXPECT_EQ(omg_update(o, 1.0F, 0.01F, nan), Status::kBadWeight);
  EXPECT_EQ(omg_update(o, 1.0F, 0.01F, 1.0F, -1.0F), Status::kInvalidArgument);
  EXPECT_EQ(std::memcmp(&k, &k0, sizeof k), 0);
  EXPECT_EQ(std::memcmp(&o, &o0, sizeof o), 0);
}

}  // namespace
}  // namespace ccmap

namespace ccmap {
namespace {

TEST(KalmanCell, FrameBatchEqualsSequentialUpdatesWithTheSameVariance) {
  // n measurements of variance R fused as one of their mean with R / n: the same posterior as
  // n sequential updates (information form), while the floor does not engage.
  test::Rng rng(4);
  for (int trial = 0; trial < 50; ++trial) {
    KalmanCell sequential{};
    KalmanCell batch{};
    const float r = static_cast<float>(rng.uniform(1e-6, 1e-3));
    // A prior from an earlier frame (or none, on even trials).
    if (trial % 2 == 1) {
      const float z0 = static_cast<float>(rng.uniform(-1.0, 1.0));
      ASSERT_EQ(kalman_update(sequential, z0, 4.0F * r), Status::kOk);
      ASSERT_EQ(kalman_update(batch, z0, 4.0F * r), Status::kOk);
    }
    const std::uint32_t n = 1U + static_cast<std::uint32_t>(rng.uniform(0.0, 300.0));
    double sum = 0.0;
    for (std::uint32_t i = 0; i < n; ++i) {
      const float z = static_cast<float>(0.3 + 0.01 * rng.normal());
      sum += z;
      ASSERT_EQ(kalman_update(sequential, z, r, 1e-12F), Status::kOk);
    }
    detail::kalman_update_batch_unchecked(batch, static_cast<float>(sum / n), r, n, 1e-12F);
    EXPECT_NEAR(batch.height, sequential.height, 2e-6) << "trial " << trial << ", n " << n;
    EXPECT_NEAR(batch.variance, sequential.variance, 1e-4 * sequential.variance) << "trial " << trial;
    EXPECT_EQ(batch.weight, sequential.weight);
  }
}

TEST(KalmanCell, FrameBatchOfOneIsTheSingleUpdate) {
  KalmanCell a{};
  KalmanCell b{};
  ASSERT_EQ(kalman_update(a, 1.0F, 0.01F), Status::kOk);
  ASSERT_EQ(kalman_update(b, 1.0F, 0.01F), Status::kOk);
  ASSERT_EQ(kalman_update(a, 1.5F, 0.02F), Status::kOk);
  detail::kalman_update_batch_unchecked(b, 1.5F, 0.02F, 1U, kKalmanDefaultMinVariance);
  EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0);
}

}  // namespace
}  // namespace ccmap
