// Merging cells of the same ground and taking a part back out (map exchange): kalman_merge in
// information form against the sequential Kalman updates in double; ccm_unmerge, kalman_unmerge
// and omg_unmerge against the statistics of the remaining measurements computed directly in
// double (two-pass sums, not the library's merge); refusals leave the cell unchanged.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "support/ccm_kinds.hpp"
#include "support/reference.hpp"

namespace ccmap {
namespace {

using test::Rng;

struct Measurement {
  float z;
  float variance;
};

std::vector<Measurement> measurements(Rng& rng, int n, double height) {
  std::vector<Measurement> out;
  for (int i = 0; i < n; ++i) {
    const double sigma = rng.uniform(0.002, 0.02);
    out.push_back(Measurement{static_cast<float>(height + sigma * rng.normal()), static_cast<float>(sigma * sigma)});
  }
  return out;
}

/// Sequential Kalman updates in double (h += K (z - h), K = P / (P + R), P = P R / (P + R)).
struct KalmanDouble {
  double height = 0.0, variance = 0.0;
  int n = 0;
  void update(const Measurement& m) {
    if (n++ == 0) {
      height = m.z;
      variance = m.variance;
      return;
    }
    const double gain = variance / (variance + m.variance);
    height += gain * (m.z - height);
    variance = gain * m.variance;
  }
};

KalmanCell kalman_of(const std::vector<Measurement>& ms, std::size_t begin, std::size_t end) {
  KalmanCell c{};
  for (std::size_t i = begin; i < end; ++i) {
    EXPECT_EQ(kalman_update(c, ms[i].z, ms[i].variance, 1e-30F), Status::kOk);
  }
  return c;
}

TEST(KalmanMerge, TwoCellsOfDisjointMeasurementsEqualTheSequentialUpdatesInDouble) {
  Rng rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 2 + static_cast<int>(rng.uniform(0.0, 300.0));
    const auto ms = measurements(rng, n, rng.uniform(-50.0, 50.0));
    const auto split = static_cast<std::size_t>(rng.uniform(1.0, n - 1.0));
    KalmanCell a = kalman_of(ms, 0, split);
    const KalmanCell b = kalman_of(ms, split, ms.size());
    ASSERT_EQ(kalman_merge(a, b, 1e-30F), Status::kOk);
    // Reference: the other order (b's measurements first), sequentially, in double.
    KalmanDouble ref;
    for (std::size_t i = split; i < ms.size(); ++i) ref.update(ms[i]);
    for (std::size_t i = 0; i < split; ++i) ref.update(ms[i]);
    EXPECT_EQ(a.weight, static_cast<float>(n));
    EXPECT_NEAR(a.height, ref.height, 2e-6 * (1.0 + std::fabs(ref.height))) << "trial " << trial;
    EXPECT_NEAR(a.variance, ref.variance, 1e-5 * ref.variance) << "trial " << trial;
  }
}

TEST(KalmanMerge, TheFloorActsAfterTheMergeAndEmptyCellsAreNeutral) {
  KalmanCell a{1.0F, 2e-8F, 3.0F};
  const KalmanCell b{1.1F, 2e-8F, 4.0F};
  ASSERT_EQ(kalman_merge(a, b, 1.5e-8F), Status::kOk);
  EXPECT_FLOAT_EQ(a.height, 1.05F);
  EXPECT_FLOAT_EQ(a.variance, 1.5e-8F) << "1e-8 from the information sum, floored";
  EXPECT_EQ(a.weight, 7.0F);
  const KalmanCell before = a;
  ASSERT_EQ(kalman_merge(a, KalmanCell{}, 1.5e-8F), Status::kOk);
  EXPECT_EQ(std::memcmp(&a, &before, sizeof a), 0) << "merging an empty cell changes nothing";
  KalmanCell empty{};
  ASSERT_EQ(kalman_merge(empty, KalmanCell{2.0F, 1e-9F, 1.0F}, 1.5e-8F), Status::kOk);
  EXPECT_EQ(empty.height, 2.0F);
  EXPECT_EQ(empty.variance, 1.5e-8F);
  // Refusals leave the cell unchanged.
  for (const KalmanCell bad : {KalmanCell{1.0F, 0.0F, 1.0F}, KalmanCell{1.0F, -1e-6F, 1.0F}, KalmanCell{NAN, 1e-6F, 1.0F},
                               KalmanCell{1.0F, INFINITY, 1.0F}, KalmanCell{1.0F, 1e-6F, -1.0F}, KalmanCell{1.0F, 1e-6F, NAN}}) {
    EXPECT_EQ(kalman_merge(a, bad, 1.5e-8F), Status::kInvalidArgument);
    EXPECT_EQ(std::memcmp(&a, &before, sizeof a), 0);
  }
  EXPECT_EQ(kalman_merge(a, b, 0.0F), Status::kInvalidArgument);
}

TEST(KalmanUnmerge, TakingAPartOutLeavesTheRestsInformationSum) {
  Rng rng(12);
  double worst_height = 0.0, worst_variance = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 4 + static_cast<int>(rng.uniform(0.0, 300.0));
    const auto ms = measurements(rng, n, rng.uniform(-5.0, 5.0));
    // The part is at most 80 % of the measurements: the cancellation grows like P_p / (P_p - P_t).
    const auto split = static_cast<std::size_t>(rng.uniform(1.0, 0.8 * n));
    const KalmanCell total = kalman_of(ms, 0, ms.size());
    const KalmanCell part = kalman_of(ms, 0, split);
    KalmanCell rest{};
    ASSERT_EQ(kalman_unmerge(total, part, &rest), Status::kOk);
    // Reference: the information sum of the rest, in double.
    double info = 0.0, weighted = 0.0;
    for (std::size_t i = split; i < ms.size(); ++i) {
      info += 1.0 / ms[i].variance;
      weighted += ms[i].z / ms[i].variance;
    }
    EXPECT_EQ(rest.weight, static_cast<float>(ms.size() - split));
    worst_height = std::max(worst_height, std::fabs(rest.height - weighted / info));
    worst_variance = std::max(worst_variance, std::fabs(rest.variance * info - 1.0));
  }
  EXPECT_LE(worst_height, 2e-5) << "m (heights up to 5 m, rest >= 20 % of the information; measured 4.1e-6)";
  EXPECT_LE(worst_variance, 3e-5) << "relative (measured 3.1e-6)";
}

TEST(KalmanUnmerge, NothingLeftOrNoInformationGainedIsRefused) {
  const KalmanCell part{1.0F, 1e-6F, 5.0F};
  KalmanCell rest{9.0F, 9.0F, 9.0F};
  EXPECT_EQ(kalman_unmerge(part, part, &rest), Status::kBadWeight);
  EXPECT_EQ(kalman_unmerge(KalmanCell{1.0F, 2e-6F, 6.0F}, part, &rest), Status::kBadWeight) << "less information";
  EXPECT_EQ(rest.height, 9.0F);
  EXPECT_EQ(kalman_unmerge(part, part, nullptr), Status::kInvalidArgument);
  ASSERT_EQ(kalman_unmerge(part, KalmanCell{}, &rest), Status::kOk);
  EXPECT_EQ(std::memcmp(&rest, &part, sizeof rest), 0) << "an empty part leaves the total";
}

/// Points in a 0.16 m cell on a tilted plane with noise, 2 m above the origin.
struct Point {
  float x, y, z, w;
};
std::vector<Point> cell_points(Rng& rng, int n) {
  std::vector<Point> out;
  for (int i = 0; i < n; ++i) {
    const double x = rng.uniform(-0.08, 0.08), y = rng.uniform(-0.08, 0.08);
    out.push_back(Point{static_cast<float>(x), static_cast<float>(y),
                        static_cast<float>(2.0 + 0.3 * x - 0.1 * y + 0.005 * rng.normal()),
                        static_cast<float>(rng.uniform(0.5, 2.0))});
  }
  return out;
}

/// Weighted mean and co-moments of points [begin, end) in double, two passes.
struct Moments {
  double w = 0, mx = 0, my = 0, mz = 0, sxx = 0, syy = 0, szz = 0, sxz = 0, syz = 0, sxy = 0;
};
Moments moments(const std::vector<Point>& p, std::size_t begin, std::size_t end) {
  Moments m;
  for (std::size_t i = begin; i < end; ++i) {
    m.w += p[i].w;
    m.mx += p[i].w * double{p[i].x};
    m.my += p[i].w * double{p[i].y};
    m.mz += p[i].w * double{p[i].z};
  }
  m.mx /= m.w;
  m.my /= m.w;
  m.mz /= m.w;
  for (std::size_t i = begin; i < end; ++i) {
    const double dx = p[i].x - m.mx, dy = p[i].y - m.my, dz = p[i].z - m.mz;
    m.sxx += p[i].w * dx * dx;
    m.syy += p[i].w * dy * dy;
    m.szz += p[i].w * dz * dz;
    m.sxz += p[i].w * dx * dz;
    m.syz += p[i].w * dy * dz;
    m.sxy += p[i].w * dx * dy;
  }
  return m;
}

template <typename Cell>
Cell ccm_of(const std::vector<Point>& p, std::size_t begin, std::size_t end) {
  Cell c{};
  for (std::size_t i = begin; i < end; ++i) {
    EXPECT_EQ(ccm_update(c, p[i].x, p[i].y, p[i].z, p[i].w, kNoWeightLimit), Status::kOk);
  }
  return c;
}

/// Both CCM cells (the full cell's s_xy checked too).
template <typename Cell>
class CcmUnmerge : public ::testing::Test {};
TYPED_TEST_SUITE(CcmUnmerge, test::CcmCellKinds, test::CcmKindNames);

TYPED_TEST(CcmUnmerge, TakingAPartOutLeavesTheMomentsOfTheRest) {
  using Cell = TypeParam;
  Rng rng(13);
  double worst_mean = 0.0, worst_moment = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 4 + static_cast<int>(rng.uniform(0.0, 400.0));
    const auto pts = cell_points(rng, n);
    const auto split = static_cast<std::size_t>(rng.uniform(1.0, 0.8 * n));
    const Cell total = ccm_of<Cell>(pts, 0, pts.size());
    const Cell part = ccm_of<Cell>(pts, 0, split);
    Cell rest{};
    ASSERT_EQ(ccm_unmerge(total, part, &rest), Status::kOk);
    const Moments m = moments(pts, split, pts.size());
    EXPECT_NEAR(rest.weight, m.w, 1e-5 * m.w);
    worst_mean = std::max({worst_mean, std::fabs(rest.mean_x - m.mx), std::fabs(rest.mean_y - m.my),
                           std::fabs(rest.mean_z - m.mz)});
    // Second moments per weight against the spread of a 16 cm cell (w^2 / 12) and of the noise.
    const double lateral = 0.16 * 0.16 / 12.0, vertical = m.szz / m.w;
    worst_moment = std::max({worst_moment, std::fabs(rest.s_xx - m.sxx) / m.w / lateral,
                             std::fabs(rest.s_yy - m.syy) / m.w / lateral, std::fabs(rest.s_zz - m.szz) / m.w / vertical,
                             std::fabs(rest.s_xz - m.sxz) / m.w / std::sqrt(lateral * vertical),
                             std::fabs(rest.s_yz - m.syz) / m.w / std::sqrt(lateral * vertical)});
    if constexpr (kHasLateralCovariance<Cell>) {
      worst_moment = std::max(worst_moment, std::fabs(rest.s_xy - m.sxy) / m.w / lateral);
    }
  }
  EXPECT_LE(worst_mean, 1e-5) << "m (z around 2 m, rest >= 20 % of the weight; measured 4.3e-6)";
  EXPECT_LE(worst_moment, 5e-3) << "relative to the cell's spread (measured 9e-4)";
}

TYPED_TEST(CcmUnmerge, MergeThenUnmergeGivesThePartBackAndRefusalsLeaveTheOutputAlone) {
  using Cell = TypeParam;
  Rng rng(14);
  const auto pts = cell_points(rng, 50);
  const Cell a = ccm_of<Cell>(pts, 0, 20);
  const Cell b = ccm_of<Cell>(pts, 20, 50);
  Cell total = a;
  ASSERT_EQ(ccm_merge(total, b, kNoWeightLimit), Status::kOk);
  Cell back{};
  ASSERT_EQ(ccm_unmerge(total, a, &back), Status::kOk);
  EXPECT_NEAR(back.weight, b.weight, 1e-5F);
  EXPECT_NEAR(back.mean_z, b.mean_z, 1e-6F);
  EXPECT_NEAR(back.s_zz, b.s_zz, 1e-4F * b.s_zz + 1e-9F);
  if constexpr (kHasLateralCovariance<Cell>) {
    EXPECT_NEAR(back.s_xy, b.s_xy, 1e-4F * b.s_xx + 1e-9F);
  }
  const float fields[10] = {1.0F, 2.0F, 3.0F, 4.0F, 5.0F, 6.0F, 7.0F, 8.0F, 9.0F, 10.0F};
  Cell untouched{};
  std::memcpy(&untouched, fields, sizeof(Cell));  // packed floats (static_asserts in ccm_cell.hpp)
  const Cell copy = untouched;
  EXPECT_EQ(ccm_unmerge(a, a, &untouched), Status::kBadWeight) << "nothing left";
  EXPECT_EQ(ccm_unmerge(a, total, &untouched), Status::kBadWeight) << "the part outweighs the total";
  Cell nan_weight = a;
  nan_weight.weight = NAN;
  EXPECT_EQ(ccm_unmerge(total, nan_weight, &untouched), Status::kBadWeight);
  EXPECT_EQ(std::memcmp(&untouched, &copy, sizeof copy), 0);
  EXPECT_EQ(ccm_unmerge(total, a, nullptr), Status::kInvalidArgument);
}

TEST(OmgMerge, CellsOfDisjointMeasurementsMergeToTheMixtureOfAllAndUnmergeBack) {
  Rng rng(15);
  for (int trial = 0; trial < 100; ++trial) {
    const int n = 4 + static_cast<int>(rng.uniform(0.0, 200.0));
    const auto ms = measurements(rng, n, rng.uniform(-5.0, 5.0));
    const auto split = static_cast<std::size_t>(rng.uniform(1.0, 0.8 * n));
    OmgCell a{}, b{}, total{};
    for (std::size_t i = 0; i < ms.size(); ++i) {
      OmgCell& c = i < split ? a : b;
      ASSERT_EQ(omg_update(c, ms[i].z, ms[i].variance, 1.0F), Status::kOk);
      ASSERT_EQ(omg_update(total, ms[i].z, ms[i].variance, 1.0F), Status::kOk);
    }
    // Reference in double: mean of z, mixture second moment sum(sigma^2 + (z - mean)^2).
    auto mixture = [&](std::size_t begin, std::size_t end, double* mean, double* s) {
      *mean = 0.0;
      for (std::size_t i = begin; i < end; ++i) *mean += ms[i].z;
      *mean /= static_cast<double>(end - begin);
      *s = 0.0;
      for (std::size_t i = begin; i < end; ++i) *s += ms[i].variance + (ms[i].z - *mean) * (ms[i].z - *mean);
    };
    double mean = 0.0, s = 0.0;
    OmgCell merged = a;
    ASSERT_EQ(omg_merge(merged, b, kNoWeightLimit), Status::kOk);
    mixture(0, ms.size(), &mean, &s);
    EXPECT_EQ(merged.weight, static_cast<float>(n));
    EXPECT_NEAR(merged.height, mean, 2e-6 * (1.0 + std::fabs(mean)));
    EXPECT_NEAR(merged.s, s, 1e-4 * s);
    OmgCell rest{};
    ASSERT_EQ(omg_unmerge(total, a, &rest), Status::kOk);
    mixture(split, ms.size(), &mean, &s);
    EXPECT_NEAR(rest.height, mean, 1e-5 * (1.0 + std::fabs(mean)));
    EXPECT_NEAR(rest.s, s, 1e-2 * s);
  }
  OmgCell limited{10.0F, 1.0F, 0.5F};
  ASSERT_EQ(omg_merge(limited, OmgCell{10.0F, 1.2F, 0.5F}, 10.0F), Status::kOk);
  EXPECT_EQ(limited.weight, 10.0F) << "the limiter acts after the merge";
  EXPECT_FLOAT_EQ(limited.height, 1.1F);
  EXPECT_EQ(omg_merge(limited, OmgCell{1.0F, NAN, 0.0F}, 10.0F), Status::kBadWeight);
  EXPECT_EQ(omg_merge(limited, OmgCell{1.0F, 1.0F, 0.0F}, 0.0F), Status::kInvalidArgument);
}

}  // namespace
}  // namespace ccmap
