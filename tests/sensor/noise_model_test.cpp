// Sensor noise models: stereo (sigma ~ r^2) and lidar (sigma linear in r), the IV-G size bound,
// weights, the CADRE preset and bad input. References are evaluated here in double from the
// model parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "ccmap/sensor/noise_model.hpp"

namespace ccmap::sensor {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

double stereo_sigma_ref(const StereoParams& p, double range) {
  return range * range * static_cast<double>(p.disparity_sigma_px) /
         (static_cast<double>(p.focal_px) * static_cast<double>(p.baseline_m));
}

// ---------------------------------------------------------------------------------------------
// Stereo
// ---------------------------------------------------------------------------------------------

TEST(NoiseModel, StereoSigmaGrowsWithRangeSquared) {
  const StereoParams params{600.0F, 0.05F, 0.1F};
  const NoiseModel model = NoiseModel::stereo(params);
  ASSERT_EQ(model.validate(), Status::kOk);
  EXPECT_EQ(model.kind(), SensorKind::kStereo);
  for (double r = 0.05; r < 30.0; r *= 1.137) {
    const float rf = static_cast<float>(r);
    const double expected = stereo_sigma_ref(params, rf);
    EXPECT_NEAR(model.sigma_at_range(rf), expected, 2e-6 * expected)
        << "stereo sigma off the r^2 sigma_d/(f b) law at r = " << r << " m";
    EXPECT_EQ(model.sigma_at_range(rf), model.sigma_at_range_sq(rf * rf))
        << "sigma from r and from r^2 disagree at r = " << r << " m";
    // Doubling the range quadruples the error (2r is exact in float).
    EXPECT_NEAR(model.sigma_at_range(2.0F * rf) / model.sigma_at_range(rf), 4.0, 1e-6)
        << "sigma(2r)/sigma(r) is not 4 at r = " << r << " m";
  }
  EXPECT_EQ(model.sigma_at_range(0.0F), 0.0F) << "stereo error at the optical centre is 0";
}

TEST(NoiseModel, StereoMaxRangeInvertsSigma) {
  const StereoParams params{600.0F, 0.05F, 0.1F};
  const NoiseModel model = NoiseModel::stereo(params);
  for (const float sigma : {1e-4F, 0.00577F, 0.01F, 0.0924F, 0.5F, 3.0F}) {
    const double expected = std::sqrt(static_cast<double>(sigma) * 600.0 * 0.05 / 0.1);
    EXPECT_NEAR(model.max_range_for_sigma(sigma), expected, 2e-6 * expected)
        << "max range for sigma " << sigma << " m off sqrt(sigma f b / sigma_d)";
    EXPECT_NEAR(model.max_range_sq_for_sigma(sigma), expected * expected, 4e-6 * expected * expected);
    const float r = model.max_range_for_sigma(sigma);
    EXPECT_NEAR(model.sigma_at_range(r), sigma, 4e-6 * sigma) << "sigma(max_range(sigma)) != sigma";
  }
  EXPECT_EQ(model.max_range_for_sigma(0.0F), 0.0F);
  EXPECT_EQ(model.max_range_for_sigma(kInf), kInf);
  EXPECT_EQ(model.max_range_for_sigma(-1.0F), 0.0F) << "negative sigma: no range satisfies it";
  EXPECT_EQ(model.max_range_for_sigma(kNaN), 0.0F) << "NaN sigma: no range satisfies it";
  EXPECT_EQ(model.max_range_sq_for_sigma(kNaN), 0.0F);
}

TEST(NoiseModel, NoiseFreeStereoIsZeroEverywhereAndNeverExceeded) {
  const NoiseModel model = NoiseModel::stereo({600.0F, 0.05F, 0.0F});
  ASSERT_EQ(model.validate(), Status::kOk);
  EXPECT_EQ(model.sigma_at_range(100.0F), 0.0F);
  EXPECT_EQ(model.max_range_for_sigma(0.0F), kInf);
  EXPECT_EQ(model.max_range_sq_for_sigma(0.01F), kInf);
}

// ---------------------------------------------------------------------------------------------
// Lidar
// ---------------------------------------------------------------------------------------------

TEST(NoiseModel, LidarSigmaIsLinearInRange) {
  const LidarParams params{0.01F, 0.002F};
  const NoiseModel model = NoiseModel::lidar(params);
  ASSERT_EQ(model.validate(), Status::kOk);
  EXPECT_EQ(model.kind(), SensorKind::kLidar);
  for (double r = 0.0; r < 100.0; r += 0.731) {
    const float rf = static_cast<float>(r);
    const double expected = 0.01 + 0.002 * static_cast<double>(rf);
    EXPECT_NEAR(model.sigma_at_range(rf), static_cast<float>(0.01) + 0.002F * rf, 1e-7);
    EXPECT_NEAR(model.sigma_at_range(rf), expected, 2e-6 * expected) << "lidar sigma at r = " << r;
    EXPECT_NEAR(model.sigma_at_range_sq(rf * rf), expected, 2e-6 * expected);
    // Linear: equal increments per equal range step.
    EXPECT_NEAR(model.sigma_at_range(2.0F * rf) - model.sigma_at_range(rf), 0.002 * rf,
                1e-6 + 2e-6 * rf);
  }
  // Inverse, with the floor.
  EXPECT_NEAR(model.max_range_for_sigma(0.03F), 10.0, 1e-4);
  EXPECT_NEAR(model.max_range_sq_for_sigma(0.03F), 100.0, 2e-3);
  EXPECT_EQ(model.max_range_for_sigma(0.009F), 0.0F) << "sigma below the floor: no range";
  EXPECT_EQ(model.max_range_for_sigma(kInf), kInf);
}

TEST(NoiseModel, ConstantLidarNeverExceedsItsSigma) {
  const NoiseModel model = NoiseModel::lidar({0.02F, 0.0F});
  ASSERT_EQ(model.validate(), Status::kOk);
  EXPECT_EQ(model.sigma_at_range(0.1F), 0.02F);
  EXPECT_EQ(model.sigma_at_range(1000.0F), 0.02F);
  EXPECT_EQ(model.max_range_for_sigma(0.02F), kInf);
  EXPECT_EQ(model.max_range_for_sigma(0.05F), kInf);
  EXPECT_EQ(model.max_range_for_sigma(0.019F), 0.0F);
}

// ---------------------------------------------------------------------------------------------
// Bad ranges and bad parameters
// ---------------------------------------------------------------------------------------------

TEST(NoiseModel, BadRangeGivesInfiniteSigma) {
  for (const NoiseModel& model : {NoiseModel::stereo({600.0F, 0.05F, 0.1F}),
                                  NoiseModel::lidar({0.01F, 0.002F})}) {
    for (const float bad : {-1.0F, -1e-30F, kNaN, -kInf}) {
      EXPECT_EQ(model.sigma_at_range(bad), kInf) << "range " << bad;
      EXPECT_EQ(model.sigma_at_range_sq(bad), kInf) << "range^2 " << bad;
    }
    EXPECT_EQ(model.sigma_at_range(kInf), kInf);
    EXPECT_EQ(model.sigma_at_range_sq(kInf), kInf);
  }
}

TEST(NoiseModel, BadParametersAreReportedAndAnsweredConservatively) {
  struct Case {
    NoiseModel model;
    Status expected;
    const char* what;
  };
  const Case cases[] = {
      {NoiseModel{}, Status::kNotInitialised, "default-constructed"},
      {NoiseModel::stereo({0.0F, 0.05F, 0.1F}), Status::kInvalidArgument, "focal 0"},
      {NoiseModel::stereo({-600.0F, 0.05F, 0.1F}), Status::kInvalidArgument, "negative focal"},
      {NoiseModel::stereo({600.0F, 0.0F, 0.1F}), Status::kInvalidArgument, "baseline 0"},
      {NoiseModel::stereo({600.0F, 0.05F, -0.1F}), Status::kInvalidArgument, "negative sigma_d"},
      {NoiseModel::stereo({kNaN, 0.05F, 0.1F}), Status::kNonFiniteInput, "NaN focal"},
      {NoiseModel::stereo({600.0F, kInf, 0.1F}), Status::kNonFiniteInput, "Inf baseline"},
      {NoiseModel::stereo({600.0F, 0.05F, kNaN}), Status::kNonFiniteInput, "NaN sigma_d"},
      {NoiseModel::stereo({1e-30F, 1e-30F, 1.0F}), Status::kInvalidArgument, "f*b underflows"},
      {NoiseModel::lidar({-0.01F, 0.0F}), Status::kInvalidArgument, "negative sigma0"},
      {NoiseModel::lidar({0.01F, -0.001F}), Status::kInvalidArgument, "negative slope"},
      {NoiseModel::lidar({kNaN, 0.0F}), Status::kNonFiniteInput, "NaN sigma0"},
      {NoiseModel::lidar({0.01F, kInf}), Status::kNonFiniteInput, "Inf slope"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    EXPECT_EQ(c.model.validate(), c.expected);
    EXPECT_EQ(c.model.sigma_at_range(1.0F), kInf) << "an invalid model must accept no point";
    EXPECT_EQ(c.model.sigma_at_range_sq(1.0F), kInf);
    EXPECT_EQ(c.model.max_range_for_sigma(0.1F), 0.0F);
    EXPECT_EQ(c.model.max_range_sq_for_sigma(0.1F), 0.0F);
    EXPECT_EQ(c.model.weight_at_range_sq(1.0F), 1.0F);
    NoiseModel inverse = c.model;
    inverse.set_weight_mode(WeightMode::kInverseVariance, 2.0F);
    EXPECT_EQ(inverse.validate(), c.expected) << "parameter errors are reported first";
    EXPECT_EQ(inverse.weight_at_range_sq(4.0F), 1.0F);
  }
  // Noise-free lidar is a valid idealisation.
  EXPECT_EQ(NoiseModel::lidar({0.0F, 0.0F}).validate(), Status::kOk);
}

// ---------------------------------------------------------------------------------------------
// Weights
// ---------------------------------------------------------------------------------------------

TEST(NoiseModel, ConstantWeightIsOneEverywhere) {
  const NoiseModel model = NoiseModel::stereo({600.0F, 0.05F, 0.1F});
  EXPECT_EQ(model.weight_mode(), WeightMode::kConstant) << "the paper's default";
  for (const float r2 : {1e-6F, 0.25F, 1.0F, 25.0F, 1e6F, -1.0F, kNaN, kInf}) {
    EXPECT_EQ(model.weight_at_range_sq(r2), 1.0F) << "range^2 " << r2;
  }
}

TEST(NoiseModel, InverseVarianceWeightIsNormalisedAndClamped) {
  NoiseModel stereo = NoiseModel::stereo({600.0F, 0.05F, 0.1F});
  stereo.set_weight_mode(WeightMode::kInverseVariance, 2.0F);
  ASSERT_EQ(stereo.validate(), Status::kOk);
  EXPECT_EQ(stereo.reference_range_m(), 2.0F);
  EXPECT_EQ(stereo.weight_at_range_sq(4.0F), 1.0F) << "a point at the reference range weighs 1";
  for (double r = 0.4; r < 10.0; r *= 1.09) {
    const float r2 = static_cast<float>(r * r);
    // Stereo: w = sigma_ref^2 / sigma^2 = (r_ref^2 / r^2)^2.
    double expected = (4.0 / static_cast<double>(r2)) * (4.0 / static_cast<double>(r2));
    expected = std::fmin(std::fmax(expected, 1e-3), 1e3);
    EXPECT_NEAR(stereo.weight_at_range_sq(r2), expected, 1e-5 * expected) << "r = " << r;
  }
  EXPECT_EQ(stereo.weight_at_range_sq(1e-4F), kMaxInverseVarianceWeight) << "clamped high";
  EXPECT_EQ(stereo.weight_at_range_sq(0.0F), kMaxInverseVarianceWeight) << "zero sigma";
  EXPECT_EQ(stereo.weight_at_range_sq(1e4F), kMinInverseVarianceWeight) << "clamped low";
  EXPECT_EQ(stereo.weight_at_range_sq(-1.0F), kMinInverseVarianceWeight) << "bad range";
  EXPECT_EQ(stereo.weight_at_range_sq(kNaN), kMinInverseVarianceWeight) << "NaN range";
  EXPECT_EQ(stereo.weight_at_range_sq(kInf), kMinInverseVarianceWeight) << "Inf range";

  NoiseModel lidar = NoiseModel::lidar({0.01F, 0.002F});
  lidar.set_weight_mode(WeightMode::kInverseVariance, 5.0F);  // sigma_ref = 0.02 m
  ASSERT_EQ(lidar.validate(), Status::kOk);
  EXPECT_EQ(lidar.weight_at_range_sq(25.0F), 1.0F);
  EXPECT_NEAR(lidar.weight_at_range_sq(0.0F), 4.0, 1e-5) << "(0.02 / 0.01)^2 at range 0";
  EXPECT_NEAR(lidar.weight_at_range_sq(400.0F), 0.16, 1e-6) << "(0.02 / 0.05)^2 at 20 m";

  // Back to constant.
  lidar.set_weight_mode(WeightMode::kConstant);
  EXPECT_EQ(lidar.weight_at_range_sq(400.0F), 1.0F);
}

TEST(NoiseModel, BadWeightSettingsAreReported) {
  NoiseModel model = NoiseModel::stereo({600.0F, 0.05F, 0.1F});
  model.set_weight_mode(WeightMode::kInverseVariance, 0.0F);
  EXPECT_EQ(model.validate(), Status::kInvalidArgument) << "reference range 0";
  EXPECT_EQ(model.weight_at_range_sq(4.0F), 1.0F);
  model.set_weight_mode(WeightMode::kInverseVariance, -1.0F);
  EXPECT_EQ(model.validate(), Status::kInvalidArgument) << "negative reference range";
  model.set_weight_mode(WeightMode::kInverseVariance, kNaN);
  EXPECT_EQ(model.validate(), Status::kNonFiniteInput) << "NaN reference range";
  model.set_weight_mode(WeightMode::kInverseVariance, kInf);
  EXPECT_EQ(model.validate(), Status::kNonFiniteInput) << "Inf reference range";
  model.set_weight_mode(WeightMode::kInverseVariance, 1e20F);
  EXPECT_EQ(model.validate(), Status::kInvalidArgument) << "r_ref^2 overflows";
  WeightMode bogus;
  const std::uint8_t raw = 7U;
  std::memcpy(&bogus, &raw, sizeof(bogus));
  model.set_weight_mode(bogus, 1.0F);
  EXPECT_EQ(model.validate(), Status::kInvalidArgument) << "weight mode outside the enum";
  EXPECT_EQ(model.weight_at_range_sq(4.0F), 1.0F);
  model.set_weight_mode(WeightMode::kConstant, kNaN);
  EXPECT_EQ(model.validate(), Status::kOk) << "the reference range is unused by kConstant";

  NoiseModel noise_free = NoiseModel::lidar({0.0F, 0.0F});
  noise_free.set_weight_mode(WeightMode::kInverseVariance, 1.0F);
  EXPECT_EQ(noise_free.validate(), Status::kInvalidArgument) << "nothing to normalise by";
}

// ---------------------------------------------------------------------------------------------
// IV-G bound
// ---------------------------------------------------------------------------------------------

TEST(NoiseModel, IvgCellWidthBoundMatchesTwiceSqrt12Sigma) {
  for (const float sigma : {0.0F, 1e-4F, 0.00577F, 0.01F, 0.0833F, 1.0F}) {
    const double expected = 2.0 * std::sqrt(12.0) * static_cast<double>(sigma);
    EXPECT_NEAR(min_cell_width_for_sigma(sigma), expected, 1e-6 * expected)
        << "min width for sigma " << sigma;
    // The width found satisfies w / sqrt(12) >= 2 sigma (to float rounding).
    const double w = min_cell_width_for_sigma(sigma);
    EXPECT_GE(w / std::sqrt(12.0), 2.0 * sigma * (1.0 - 1e-6));
  }
  for (const float w : {0.0F, 0.04F, 0.08F, 0.16F, 0.32F, 0.64F, 3.0F}) {
    const double expected = static_cast<double>(w) / (2.0 * std::sqrt(12.0));
    EXPECT_NEAR(max_sigma_for_cell_width(w), expected, 1e-6 * expected) << "width " << w;
    EXPECT_NEAR(min_cell_width_for_sigma(max_sigma_for_cell_width(w)), w, 1e-6 * w);
  }
  EXPECT_EQ(min_cell_width_for_sigma(kNaN), kInf);
  EXPECT_EQ(min_cell_width_for_sigma(-0.01F), kInf);
  EXPECT_EQ(min_cell_width_for_sigma(kInf), kInf);
  EXPECT_EQ(max_sigma_for_cell_width(kNaN), 0.0F);
  EXPECT_EQ(max_sigma_for_cell_width(-0.1F), 0.0F);
  EXPECT_EQ(constant_layer_max_sigma(0.04F), max_sigma_for_cell_width(0.04F));
}

// ---------------------------------------------------------------------------------------------
// CADRE preset
// ---------------------------------------------------------------------------------------------

TEST(NoiseModelCadre, SixtyFourCentimetreLayerReachesFiveMetres) {
  const NoiseModel model = cadre_stereo();
  ASSERT_EQ(model.validate(), Status::kOk);
  EXPECT_EQ(model.weight_mode(), WeightMode::kConstant);
  EXPECT_EQ(kCadreStereoParams.baseline_m, 0.05F) << "paper: 5 cm baseline";
  EXPECT_EQ(kCadreCameraHeightM, 0.175F) << "paper: 17.5 cm above ground";
  EXPECT_EQ(kCadreImageWidthPx, 850);
  EXPECT_EQ(kCadreImageHeightPx, 650);
  // ~70 deg horizontal field of view.
  const double hfov_deg =
      2.0 * std::atan(425.0 / static_cast<double>(kCadreStereoParams.focal_px)) * 180.0 / M_PI;
  EXPECT_NEAR(hfov_deg, 70.0, 2.0);

  // Section VI: obstacles over 48 cm (75% of a 64 cm cell) at 5 m -> the 64 cm layer
  // satisfies IV-G at 5 m: w / sqrt(12) >= 2 sigma_m(5 m).
  const double sigma_5m = model.sigma_at_range(5.0F);
  EXPECT_GE(0.64 / std::sqrt(12.0), 2.0 * sigma_5m) << "64 cm layer too fine for 5 m";
  EXPECT_GE(model.max_range_for_sigma(max_sigma_for_cell_width(0.64F)), 5.0F);
  // ... but not with a large margin (the claim is about 5 m, not 10 m).
  EXPECT_LT(model.max_range_for_sigma(max_sigma_for_cell_width(0.64F)), 6.0F);

  // The per-layer ranges written in the header comment (to 1 mm).
  const float widths[] = {0.04F, 0.08F, 0.16F, 0.32F, 0.64F};
  const double ranges[] = {1.316, 1.861, 2.632, 3.722, 5.264};
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(model.max_range_for_sigma(max_sigma_for_cell_width(widths[k])), ranges[k], 1e-3)
        << "CADRE IV-G range of the " << widths[k] << " m layer";
  }
}

}  // namespace
}  // namespace ccmap::sensor
