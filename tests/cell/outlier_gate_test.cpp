// The outlier gate of one cell and the change rule (cell/outlier_gate.hpp) against independent
// references: the gate from the batch mean and variance of the points themselves in double (not
// from the cell's incremental state), the floor variance from a dense sample of the plane it
// describes, the OMG merge from sequential updates in double, the change rule on the cases the
// documentation names.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "ccmap/cell/outlier_gate.hpp"
#include "support/reference.hpp"

namespace ccmap {
namespace {

constexpr float kSigma = 3.0F;

TEST(OutlierGate, FloorVarianceIsTheRangeNoiseAndTheSteepestPlaneOverTheCell) {
  // A plane of gradient i (any direction) over a square cell of width w, sampled densely: the
  // variance of its heights is i^2 w^2 / 12 whatever the direction.
  for (const double w : {0.04, 0.16, 0.64}) {
    for (const double angle : {0.0, 0.7, 2.1}) {
      const double i = 0.364, gx = i * std::cos(angle), gy = i * std::sin(angle);
      double sum = 0.0, sum_sq = 0.0;
      const int n = 400;
      for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
          const double z = gx * w * ((a + 0.5) / n - 0.5) + gy * w * ((b + 0.5) / n - 0.5);
          sum += z;
          sum_sq += z * z;
        }
      }
      const double count = static_cast<double>(n) * n;
      const double plane_variance = sum_sq / count - (sum / count) * (sum / count);
      const double sigma = 0.01;
      const double expected = sigma * sigma + plane_variance;
      EXPECT_NEAR(gate_floor_variance(static_cast<float>(sigma), static_cast<float>(w), static_cast<float>(i)), expected,
                  1e-4 * expected)
          << "floor variance of a " << w << " m cell";
    }
  }
}

TEST(OutlierGate, CcmGateIsTheDistanceFromTheMeanInStandardDeviations) {
  // Cells of random points; the reference: the batch mean and variance of those points in
  // double, z outside iff (z - mean)^2 > k^2 (variance + V). Queries 2 % away from the boundary.
  test::Rng rng(7);
  const float floor_variance = 1e-4F;
  const GateConstants gate = make_gate_constants(kSigma, floor_variance);
  int outside = 0, inside = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + static_cast<int>(rng.uniform(0.0, 1.0) * 60.0);
    const double spread = 0.001 + 0.05 * rng.uniform(0.0, 1.0);
    std::vector<test::Point> pts;
    CcmCell cell{};
    for (int i = 0; i < n; ++i) {
      const test::Point p{0.08 * (rng.uniform(0.0, 1.0) - 0.5), 0.08 * (rng.uniform(0.0, 1.0) - 0.5), 0.3 + spread * rng.normal()};
      pts.push_back(p);
      ASSERT_EQ(ccm_update(cell, static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z), 1.0F,
                           kNoWeightLimit),
                Status::kOk);
    }
    const test::RefMoments m = test::reference_moments(pts);
    const double half_width = 3.0 * std::sqrt(m.var_zz + double{floor_variance});
    for (const double f : {0.0, 0.5, 0.98, 1.02, 1.5, 40.0}) {
      for (const double sign : {-1.0, 1.0}) {
        const float z = static_cast<float>(m.mean_z + sign * f * half_width);
        const bool out = ccm_outside_gate(cell, z, gate);
        EXPECT_EQ(out, f > 1.0) << "n " << n << ", " << f << " x the half-width from the mean";
        (out ? outside : inside) += 1;
      }
    }
  }
  EXPECT_GT(outside, 0);
  EXPECT_GT(inside, 0);
  // A never-observed cell takes any point: it holds nothing to judge against.
  EXPECT_FALSE(ccm_outside_gate(CcmCell{}, 1000.0F, gate));
}

TEST(OutlierGate, OmgGateIncludesTheMixtureVariance) {
  // OMG: the mixture variance is the spread plus the mean measurement variance R.
  test::Rng rng(8);
  const float floor_variance = 4e-4F;
  const GateConstants gate = make_gate_constants(kSigma, floor_variance);
  for (int trial = 0; trial < 100; ++trial) {
    const int n = 2 + static_cast<int>(rng.uniform(0.0, 1.0) * 40.0);
    const double r = 1e-4 * (1.0 + rng.uniform(0.0, 1.0));
    OmgCell cell{};
    double sum = 0.0, sum_sq = 0.0;
    for (int i = 0; i < n; ++i) {
      const double z = -1.0 + 0.02 * rng.normal();
      sum += z;
      sum_sq += z * z;
      ASSERT_EQ(omg_update(cell, static_cast<float>(z), static_cast<float>(r), 1.0F), Status::kOk);
    }
    const double mean = sum / n, spread = sum_sq / n - mean * mean;
    const double half_width = 3.0 * std::sqrt(spread + r + double{floor_variance});
    for (const double f : {0.5, 0.98, 1.02, 3.0}) {
      EXPECT_EQ(omg_outside_gate(cell, static_cast<float>(mean + f * half_width), gate), f > 1.0) << "n " << n << ", " << f;
    }
  }
  EXPECT_FALSE(omg_outside_gate(OmgCell{}, 1000.0F, gate));
}

TEST(OutlierGate, KalmanGateIsTheHeightVariancePlusTheFloor) {
  // P after n updates of variance R is R / n (information form); the half-width
  // sqrt(k^2 (P + V)); a never-observed cell: sqrt(k^2 V).
  const float r = 4e-4F, floor_variance = 2e-4F;
  const GateConstants gate = make_gate_constants(kSigma, floor_variance);
  EXPECT_NEAR(kalman_gate_half_width(KalmanCell{}, gate), 3.0 * std::sqrt(2e-4), 1e-7);
  KalmanCell cell{};
  for (int n = 1; n <= 20; ++n) {
    ASSERT_EQ(kalman_update(cell, 0.5F, r), Status::kOk);
    const double expected = 3.0 * std::sqrt(double{r} / n + double{floor_variance});
    EXPECT_NEAR(kalman_gate_half_width(cell, gate), expected, 1e-6 * expected) << n << " updates";
    EXPECT_FALSE(kalman_outside_gate(cell, static_cast<float>(0.5 + 0.98 * expected), gate));
    EXPECT_TRUE(kalman_outside_gate(cell, static_cast<float>(0.5 - 1.02 * expected), gate));
  }
  EXPECT_FALSE(kalman_outside_gate(KalmanCell{}, 1000.0F, gate));
}

TEST(OutlierGate, HeldPointsAreTightWithinTheFloor) {
  const GateConstants gate = make_gate_constants(kSigma, 1e-4F);  // k^2 V = 9e-4 m^2
  EXPECT_TRUE(held_is_tight(0.8e-3F * 10.0F, 10.0F, gate));
  EXPECT_FALSE(held_is_tight(1.0e-3F * 10.0F, 10.0F, gate));
}

TEST(ChangeRule, TheDocumentedCases) {
  const ChangeRule rule{3.0F, 0.08F};
  struct Case {
    const char* what;
    std::uint32_t accepted, held;
    bool tight, may_wait;
    ChangeVerdict expected;
  };
  const Case cases[] = {
      {"an isolated outlier among 99 points", 99, 1, true, true, ChangeVerdict::kDrop},
      {"3 outliers among 100 points (3 %, below the share)", 97, 3, true, true, ChangeVerdict::kDrop},
      {"a tight tenth of the cell: a box covering part of it", 90, 10, true, true, ChangeVerdict::kMerge},
      {"a scattered tenth: outliers", 90, 10, false, true, ChangeVerdict::kDrop},
      {"a scattered majority: a rock face seen from the front", 40, 60, false, true, ChangeVerdict::kMerge},
      {"95 of 100 points held: 5 inside are no surface (5 % < 8 %)", 5, 95, true, true, ChangeVerdict::kReseed},
      {"30 held, 2 inside: fewer than 3 inside", 2, 30, true, true, ChangeVerdict::kReseed},
      {"a cell first seeded by an outlier: 1 inside, 6 held", 1, 6, true, true, ChangeVerdict::kReseed},
      {"one point, held: may wait", 0, 1, true, true, ChangeVerdict::kPending},
      {"two points held, one inside: may wait", 1, 2, true, true, ChangeVerdict::kPending},
      {"two points held, may not wait any more", 1, 2, true, false, ChangeVerdict::kDrop},
      {"3 held of 3: re-seed", 0, 3, false, true, ChangeVerdict::kReseed},
      {"exactly the share (8 of 100) and tight", 92, 8, true, true, ChangeVerdict::kMerge},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(static_cast<int>(change_verdict(c.accepted, c.held, c.tight, c.may_wait, rule)),
              static_cast<int>(c.expected))
        << c.what;
  }
}

}  // namespace
}  // namespace ccmap
