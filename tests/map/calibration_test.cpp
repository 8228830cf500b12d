// Normal-variance threshold calibration (paper Section IV-E, Fig. 4) against the analytic step
// curve sigma_s^2 = h^2 u (1 - 3u), u = c (1 - c), and against a double-precision reference
// of the same weighted sample set.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "ccmap/map/calibration.hpp"
#include "support/reference.hpp"

namespace ccmap {
namespace {

/// Field-wise equality (ThresholdCalibration has padding after the bool: no memcmp).
bool same(const ThresholdCalibration& a, const ThresholdCalibration& b) {
  return std::memcmp(&a.threshold, &b.threshold, sizeof(float)) == 0 &&
         std::memcmp(&a.detect_from_coverage, &b.detect_from_coverage, sizeof(float)) == 0 &&
         std::memcmp(&a.detect_to_coverage, &b.detect_to_coverage, sizeof(float)) == 0 &&
         a.interval_is_contiguous == b.interval_is_contiguous;
}

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

double analytic_curve(double h, double c) {
  const double u = c * (1.0 - c);
  return h * h * u * (1.0 - 3.0 * u);
}

/// Coverage c in [0, 1/2] where c (1 - c) = u.
double coverage_for_u(double u) { return 0.5 * (1.0 - std::sqrt(1.0 - 4.0 * u)); }

/// Grid discretisation bound: the midpoint rule leaves sigma_xx^2 short by ~(w/n)^2/12, which
/// lowers eq. (11) by at most h^2 / (4 n^2); plus float rounding of ~1e3 sequential updates.
double grid_tolerance(double h, int n) { return h * h * (0.25 / (n * n) + 2e-5); }

/// The same weighted sample set as step_normal_variance (no noise), evaluated in double.
double reference_step_variance(double w, double h, double c, int n) {
  std::vector<test::Point> pts;
  const double col = w / n;
  const double edge = w / 2 - c * w;
  for (int i = 0; i < n; ++i) {
    const double lo = -w / 2 + i * col, hi = lo + col;
    for (int j = 0; j < n; ++j) {
      const double y = -w / 2 + (j + 0.5) * col;
      if (lo >= edge) {
        pts.push_back({0.5 * (lo + hi), y, h, 1.0});
      } else if (hi <= edge) {
        pts.push_back({0.5 * (lo + hi), y, 0.0, 1.0});
      } else {
        const double on = (hi - edge) / col;
        pts.push_back({0.5 * (lo + edge), y, 0.0, 1.0 - on});
        pts.push_back({0.5 * (edge + hi), y, h, on});
      }
    }
  }
  return test::reference_moments(pts).normal_variance();
}

// ---------------------------------------------------------------------------------------------
// The curve
// ---------------------------------------------------------------------------------------------

TEST(Calibration, StepCurveFollowsAnalyticCurve) {
  struct Setting {
    float w, h;
    int n;
  };
  for (const Setting s : {Setting{0.32F, 0.24F, 32}, Setting{0.64F, 0.48F, 32},
                          Setting{0.08F, 0.06F, 8}, Setting{0.16F, 0.05F, 64}}) {
    const double h = s.h;
    for (int k = 0; k <= 100; ++k) {
      const float c = static_cast<float>(k) / 100.0F;
      const double v = step_normal_variance(s.w, s.h, c, s.n, 0.0F);
      EXPECT_NEAR(v, analytic_curve(h, c), grid_tolerance(h, s.n))
          << "sigma_s^2 off the analytic step curve at coverage " << c << " (w " << s.w
          << ", h " << s.h << ", n " << s.n << ")";
      EXPECT_NEAR(v, reference_step_variance(s.w, s.h, c, s.n), 2e-5 * h * h)
          << "sigma_s^2 off the double reference of the same samples at coverage " << c;
    }
  }
}

TEST(Calibration, CurveIsContinuousInCoverageNotAStaircase) {
  // With whole columns only, n = 8 would give a staircase in steps of 1/8. The split edge
  // column makes nearby coverages give nearby variances: |d sigma_s^2 / dc| =
  // h^2 |1 - 2c| |1 - 6u| <= h^2 (at c = 0 and 1).
  const float h = 0.06F;
  float previous = step_normal_variance(0.08F, h, 0.0F, 8, 0.0F);
  for (int k = 1; k <= 1000; ++k) {
    const float c = static_cast<float>(k) / 1000.0F;
    const float v = step_normal_variance(0.08F, h, c, 8, 0.0F);
    EXPECT_LE(std::fabs(v - previous), 1.05 * h * h / 1000.0 + 1e-8) << "jump at coverage " << c;
    previous = v;
  }
}

TEST(Calibration, CurvePeaksNearTwentyOneAndSeventyNinePercent) {
  const float w = 0.32F, h = 0.24F;
  int best_low = 0, best_high = 0;
  float max_low = -1.0F, max_high = -1.0F;
  for (int k = 1; k < 1000; ++k) {
    const float c = static_cast<float>(k) / 1000.0F;
    const float v = step_normal_variance(w, h, c, 32, 0.0F);
    if (k < 500 && v > max_low) max_low = v, best_low = k;
    if (k > 500 && v > max_high) max_high = v, best_high = k;
  }
  const double c_peak = coverage_for_u(1.0 / 6.0);  // d/du [u (1 - 3u)] = 0 -> 21.1%
  EXPECT_NEAR(best_low / 1000.0, c_peak, 0.01);
  EXPECT_NEAR(best_high / 1000.0, 1.0 - c_peak, 0.01);
  EXPECT_NEAR(max_low, h * h / 12.0, grid_tolerance(h, 32)) << "peak value h^2/12";
  // The local minimum at 50% is h^2/16.
  EXPECT_NEAR(step_normal_variance(w, h, 0.5F, 32, 0.0F), h * h / 16.0, grid_tolerance(h, 32));
  EXPECT_GT(step_normal_variance(w, h, 0.45F, 32, 0.0F), step_normal_variance(w, h, 0.5F, 32, 0.0F));
  EXPECT_GT(step_normal_variance(w, h, 0.55F, 32, 0.0F), step_normal_variance(w, h, 0.5F, 32, 0.0F));
}

// ---------------------------------------------------------------------------------------------
// The calibration
// ---------------------------------------------------------------------------------------------

TEST(Calibration, FiftyPercentThresholdIsHSquaredOver16AndDetectsNineToNinetyOnePercent) {
  // Analytic: threshold h^2/16, detected where c (1 - c) >= 1/12: 9.175% .. 90.825%.
  const double c_lo = coverage_for_u(1.0 / 12.0);
  struct Setting {
    float w, h;
  };
  for (const Setting s : {Setting{0.32F, 0.24F}, Setting{0.64F, 0.48F}, Setting{0.08F, 0.06F}}) {
    SCOPED_TRACE(testing::Message() << "w " << s.w << " h " << s.h);
    ThresholdCalibration cal{};
    ASSERT_EQ(calibrate_normal_variance_threshold(s.w, s.h, &cal), Status::kOk);
    const double h = s.h;
    EXPECT_NEAR(cal.threshold, h * h / 16.0, grid_tolerance(h, 32)) << "threshold != h^2/16";
    // Edge tolerance: the grid error divided by the curve's slope there (~0.41 h^2).
    EXPECT_NEAR(cal.detect_from_coverage, c_lo, 2e-3) << "detection starts at the wrong coverage";
    EXPECT_NEAR(cal.detect_to_coverage, 1.0 - c_lo, 2e-3) << "detection ends at the wrong coverage";
    EXPECT_NEAR(cal.detect_from_coverage, 1.0F - cal.detect_to_coverage, 1e-4) << "not symmetric";
    EXPECT_TRUE(cal.interval_is_contiguous);
    // The ends are where the curve crosses the threshold.
    EXPECT_GE(step_normal_variance(s.w, s.h, cal.detect_from_coverage, 32, 0.0F), cal.threshold);
    EXPECT_LT(step_normal_variance(s.w, s.h, cal.detect_from_coverage - 1e-4F, 32, 0.0F),
              cal.threshold);
  }
}

TEST(Calibration, ThresholdAboveFiftyPercentMinimumLeavesAGap) {
  // Threshold at 30%: u0 = 0.21 -> flagged where u in [1/3 - 0.21, 0.21]: two intervals
  // 14.4% .. 30% and 70% .. 85.6% with a gap around 50%.
  ThresholdCalibration cal{};
  ASSERT_EQ(calibrate_normal_variance_threshold(0.32F, 0.24F, &cal, 0.3F), Status::kOk);
  const double c_lo = coverage_for_u(1.0 / 3.0 - 0.21);
  EXPECT_NEAR(cal.threshold, analytic_curve(0.24, 0.3), grid_tolerance(0.24, 32));
  EXPECT_NEAR(cal.detect_from_coverage, c_lo, 2e-3);
  EXPECT_NEAR(cal.detect_to_coverage, 1.0 - c_lo, 2e-3);
  EXPECT_FALSE(cal.interval_is_contiguous) << "the 50% dip is below a 30% threshold";
  EXPECT_LT(step_normal_variance(0.32F, 0.24F, 0.5F, 32, 0.0F), cal.threshold);
}

TEST(Calibration, ZeroCoverageThresholdFlagsEverything) {
  ThresholdCalibration cal{};
  ASSERT_EQ(calibrate_normal_variance_threshold(0.32F, 0.24F, &cal, 0.0F), Status::kOk);
  EXPECT_EQ(cal.threshold, 0.0F);
  EXPECT_EQ(cal.detect_from_coverage, 0.0F);
  EXPECT_EQ(cal.detect_to_coverage, 1.0F);
  EXPECT_TRUE(cal.interval_is_contiguous);
}

TEST(Calibration, NoiseIsDeterministicAndAddsItsVariance) {
  const float w = 0.32F, h = 0.24F, sigma = 0.01F;
  // Flat ground: sigma_s^2 is the noise variance (1024 samples: ~5% sampling error).
  const float flat = step_normal_variance(w, h, 0.0F, 32, sigma);
  EXPECT_NEAR(flat, sigma * sigma, 0.15 * sigma * sigma) << "noise-only normal variance";
  // Same inputs, same bits (no hidden state, no libm).
  EXPECT_EQ(step_normal_variance(w, h, 0.37F, 32, sigma), step_normal_variance(w, h, 0.37F, 32, sigma));
  // At 50% the noise adds roughly its own variance to h^2/16.
  ThresholdCalibration noisy{};
  ASSERT_EQ(calibrate_normal_variance_threshold(w, h, &noisy, 0.5F, 32, sigma), Status::kOk);
  EXPECT_NEAR(noisy.threshold, h * h / 16.0 + sigma * sigma, 0.2 * sigma * sigma + grid_tolerance(h, 32));
  ThresholdCalibration again{};
  ASSERT_EQ(calibrate_normal_variance_threshold(w, h, &again, 0.5F, 32, sigma), Status::kOk);
  EXPECT_TRUE(same(noisy, again)) << "calibration not deterministic";
  // Small noise barely moves the detected interval.
  const double c_lo = coverage_for_u(1.0 / 12.0);
  EXPECT_NEAR(noisy.detect_from_coverage, c_lo, 0.01);
  EXPECT_NEAR(noisy.detect_to_coverage, 1.0 - c_lo, 0.01);
}

// ---------------------------------------------------------------------------------------------
// Bad input
// ---------------------------------------------------------------------------------------------

TEST(Calibration, BadInputIsRefusedWithStatusAndNoNaN) {
  struct Case {
    float w, h, c;
    int n;
    float sigma;
    Status expected;
    const char* what;
  };
  const Case cases[] = {
      {0.0F, 0.24F, 0.5F, 32, 0.0F, Status::kInvalidArgument, "zero width"},
      {-0.32F, 0.24F, 0.5F, 32, 0.0F, Status::kInvalidArgument, "negative width"},
      {0.32F, 0.0F, 0.5F, 32, 0.0F, Status::kInvalidArgument, "zero height"},
      {0.32F, -0.24F, 0.5F, 32, 0.0F, Status::kInvalidArgument, "negative height"},
      {0.32F, 0.24F, -0.01F, 32, 0.0F, Status::kInvalidArgument, "coverage below 0"},
      {0.32F, 0.24F, 1.01F, 32, 0.0F, Status::kInvalidArgument, "coverage above 1"},
      {0.32F, 0.24F, 0.5F, 1, 0.0F, Status::kInvalidArgument, "one sample per axis"},
      {0.32F, 0.24F, 0.5F, 0, 0.0F, Status::kInvalidArgument, "no samples"},
      {0.32F, 0.24F, 0.5F, -5, 0.0F, Status::kInvalidArgument, "negative samples"},
      {0.32F, 0.24F, 0.5F, kCalibrationMaxSamplesPerAxis + 1, 0.0F, Status::kInvalidArgument,
       "too many samples"},
      {0.32F, 0.24F, 0.5F, 32, -0.01F, Status::kInvalidArgument, "negative noise"},
      {kNaN, 0.24F, 0.5F, 32, 0.0F, Status::kNonFiniteInput, "NaN width"},
      {0.32F, kInf, 0.5F, 32, 0.0F, Status::kNonFiniteInput, "Inf height"},
      {0.32F, 0.24F, kNaN, 32, 0.0F, Status::kNonFiniteInput, "NaN coverage"},
      {0.32F, 0.24F, 0.5F, 32, kNaN, Status::kNonFiniteInput, "NaN noise"},
      {2000.0F, 0.24F, 0.5F, 32, 0.0F, Status::kOutOfRange, "2 km cell"},
      {0.32F, 2000.0F, 0.5F, 32, 0.0F, Status::kOutOfRange, "2 km obstacle"},
      {0.32F, 0.24F, 0.5F, 32, 2000.0F, Status::kOutOfRange, "2 km noise"},
  };
  const ThresholdCalibration untouched{-1.0F, -2.0F, -3.0F, true};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    ThresholdCalibration out = untouched;
    EXPECT_EQ(calibrate_normal_variance_threshold(c.w, c.h, &out, c.c, c.n, c.sigma), c.expected);
    EXPECT_TRUE(same(out, untouched)) << "refused calibration wrote *out";
    const float v = step_normal_variance(c.w, c.h, c.c, c.n, c.sigma);
    EXPECT_FALSE(std::isnan(v));
    EXPECT_EQ(v, -1.0F) << "refused input must answer -1";
  }
  EXPECT_EQ(calibrate_normal_variance_threshold(0.32F, 0.24F, nullptr), Status::kInvalidArgument);
  // Edges of the accepted ranges.
  ThresholdCalibration out{};
  EXPECT_EQ(calibrate_normal_variance_threshold(0.32F, 0.24F, &out, 1.0F, 2, 0.0F), Status::kOk);
  EXPECT_FALSE(std::isnan(out.threshold));
  EXPECT_GE(step_normal_variance(0.32F, 0.24F, 0.5F, 2, 0.0F), 0.0F);
}

}  // namespace
}  // namespace ccmap
