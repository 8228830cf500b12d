// Routing a point to a layer by its range: the table built from a noise model must pick the
// finest layer whose width satisfies IV-G (w / sqrt(12) >= 2 sigma_m(r)), evaluated here
// independently in double from the model parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>

#include "ccmap/sensor/noise_model.hpp"
#include "support/reference.hpp"

namespace ccmap::sensor {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kMaxFloat = std::numeric_limits<float>::max();
constexpr int kLayers = 5;
const float kCadreWidths[kLayers] = {0.04F, 0.08F, 0.16F, 0.32F, 0.64F};

/// Finest layer whose width satisfies IV-G at this range (double), -1 if none. layer0_max_sigma
/// >= 0 replaces IV-G for layer 0 (exempt constant layer).
int expected_layer(const float (&widths)[kLayers], const std::function<double(double)>& sigma,
                   double range, double layer0_max_sigma = -1.0) {
  const double s = sigma(range);
  for (int k = 0; k < kLayers; ++k) {
    const bool ok = (k == 0 && layer0_max_sigma >= 0.0)
                        ? s <= layer0_max_sigma
                        : static_cast<double>(widths[k]) / std::sqrt(12.0) >= 2.0 * s;
    if (ok) return k;
  }
  return -1;
}

/// Runs select() over many ranges and compares with the double rule. Ranges whose square lies
/// within a relative 1e-5 of a double boundary are left to the boundary test (float rounding).
void sweep_against_reference(const RoutingTable<kLayers>& table, const float (&widths)[kLayers],
                             const std::function<double(double)>& sigma,
                             const double (&boundaries_sq)[kLayers], double layer0_max_sigma,
                             const char* what) {
  SCOPED_TRACE(what);
  test::Rng rng(42);
  int checked = 0;
  int per_layer[kLayers + 1] = {};
  for (int i = 0; i < 6000; ++i) {
    // Log-uniform ranges 1 cm .. 100 m.
    const double range = 0.01 * std::pow(10.0, rng.uniform(0.0, 4.0));
    const float range_sq = static_cast<float>(range * range);
    const double r2 = range_sq;
    bool near_boundary = false;
    for (const double b : boundaries_sq) {
      if (b > 0.0 && std::isfinite(b) && std::fabs(r2 / b - 1.0) < 1e-5) near_boundary = true;
    }
    if (near_boundary) continue;
    const int expected = expected_layer(widths, sigma, std::sqrt(r2), layer0_max_sigma);
    ASSERT_EQ(table.select(range_sq), expected)
        << "range " << std::sqrt(r2) << " m (sigma_m " << sigma(std::sqrt(r2))
        << " m) routed to the wrong layer";
    ++per_layer[expected + 1];
    ++checked;
  }
  EXPECT_GT(checked, 5900) << "too many ranges skipped near boundaries";
  // Every layer with a band of its own (limit above the previous one's) must have been hit,
  // and "too noisy" too when the coarsest layer has a finite limit.
  double previous = 0.0;
  for (int k = 0; k < kLayers; ++k) {
    if (boundaries_sq[k] > previous) {
      EXPECT_GT(per_layer[k + 1], 0) << "no range exercised layer " << k;
    }
    previous = std::fmax(previous, boundaries_sq[k]);
  }
  if (std::isfinite(boundaries_sq[kLayers - 1])) {
    EXPECT_GT(per_layer[0], 0) << "no range was too noisy for every layer";
  }
}

void expect_boundaries_exact(const RoutingTable<kLayers>& table, const double (&boundaries_sq)[kLayers],
                             const char* what) {
  SCOPED_TRACE(what);
  for (int k = 0; k < kLayers; ++k) {
    const float b = table.max_range_sq[k];
    if (boundaries_sq[k] <= 0.0) {
      EXPECT_EQ(b, 0.0F) << "layer " << k << " should never take a point";
      continue;
    }
    if (!std::isfinite(boundaries_sq[k])) {
      EXPECT_EQ(b, kMaxFloat) << "layer " << k << " has no range limit";
      continue;
    }
    EXPECT_NEAR(b, boundaries_sq[k], 1e-6 * boundaries_sq[k]) << "limit of layer " << k;
    // Exactly at the limit: this layer (unless an earlier one has the same limit).
    const int at = table.select(b);
    EXPECT_LE(at, k) << "a point exactly at layer " << k << "'s limit must be taken by it";
    EXPECT_GE(at, 0);
    EXPECT_EQ(table.max_range_sq[at], b);
    // One ulp beyond: the next layer with a larger limit, or -1 past the coarsest.
    const float beyond = std::nextafter(b, kInf);
    int next = -1;
    for (int j = k + 1; j < kLayers; ++j) {
      if (table.max_range_sq[j] >= beyond) {
        next = j;
        break;
      }
    }
    EXPECT_EQ(table.select(beyond), next) << "one ulp beyond layer " << k << "'s limit";
  }
}

void expect_non_decreasing(const RoutingTable<kLayers>& table) {
  for (int k = 1; k < kLayers; ++k) {
    EXPECT_GE(table.max_range_sq[k], table.max_range_sq[k - 1]) << "layer " << k;
  }
}

// ---------------------------------------------------------------------------------------------

TEST(Routing, StereoPicksFinestLayerSatisfyingIvg) {
  const StereoParams params{600.0F, 0.05F, 0.1F};
  const NoiseModel model = NoiseModel::stereo(params);
  RoutingTable<kLayers> table{};
  ASSERT_EQ(build_routing_table(model, kCadreWidths, &table), Status::kOk);
  const double k = static_cast<double>(params.disparity_sigma_px) /
                   (static_cast<double>(params.focal_px) * static_cast<double>(params.baseline_m));
  const auto sigma = [k](double r) { return k * r * r; };
  double boundaries_sq[kLayers];
  for (int i = 0; i < kLayers; ++i) {
    boundaries_sq[i] = static_cast<double>(kCadreWidths[i]) / (2.0 * std::sqrt(12.0)) / k;
  }
  expect_non_decreasing(table);
  sweep_against_reference(table, kCadreWidths, sigma, boundaries_sq, -1.0, "stereo");
  expect_boundaries_exact(table, boundaries_sq, "stereo");
  // Beyond the coarsest limit nothing takes the point.
  EXPECT_EQ(table.select(std::nextafter(table.max_range_sq[kLayers - 1], kInf)), -1);
  EXPECT_EQ(table.select(1e4F), -1);
  EXPECT_EQ(table.select(1e-6F), 0) << "a very close point goes to the finest layer";
}

TEST(Routing, LidarWithFloorSkipsLayersFinerThanItsNoise) {
  const LidarParams params{0.01F, 0.002F};  // floor 1 cm > IV-G limit of 4 cm cells (5.8 mm)
  const NoiseModel model = NoiseModel::lidar(params);
  RoutingTable<kLayers> table{};
  ASSERT_EQ(build_routing_table(model, kCadreWidths, &table), Status::kOk);
  const auto sigma = [&](double r) {
    return static_cast<double>(params.sigma0_m) + static_cast<double>(params.sigma_per_m) * r;
  };
  double boundaries_sq[kLayers];
  for (int i = 0; i < kLayers; ++i) {
    const double limit = static_cast<double>(kCadreWidths[i]) / (2.0 * std::sqrt(12.0));
    const double r = (limit - static_cast<double>(params.sigma0_m)) /
                     static_cast<double>(params.sigma_per_m);
    boundaries_sq[i] = r > 0.0 ? r * r : 0.0;
  }
  EXPECT_EQ(table.max_range_sq[0], 0.0F) << "the 4 cm layer is finer than the lidar floor";
  expect_non_decreasing(table);
  sweep_against_reference(table, kCadreWidths, sigma, boundaries_sq, -1.0, "lidar");
  expect_boundaries_exact(table, boundaries_sq, "lidar");
  EXPECT_EQ(table.select(1e-6F), 1) << "closest points go to the 8 cm layer";
}

TEST(Routing, ConstantNoiseLidarSendsEveryRangeToOneLayer) {
  const NoiseModel model = NoiseModel::lidar({0.015F, 0.0F});  // admissible from 16 cm cells
  RoutingTable<kLayers> table{};
  ASSERT_EQ(build_routing_table(model, kCadreWidths, &table), Status::kOk);
  EXPECT_EQ(table.max_range_sq[0], 0.0F);
  EXPECT_EQ(table.max_range_sq[1], 0.0F);
  for (int k = 2; k < kLayers; ++k) EXPECT_EQ(table.max_range_sq[k], kMaxFloat);
  for (const float r2 : {1e-4F, 1.0F, 1e4F, 1e30F, kMaxFloat}) {
    EXPECT_EQ(table.select(r2), 2) << "range^2 " << r2;
  }
  EXPECT_EQ(table.select(kInf), -1) << "an infinite range is not a point";
}

TEST(Routing, BadRangesAreNotRouted) {
  RoutingTable<kLayers> table{};
  ASSERT_EQ(build_routing_table(cadre_stereo(), kCadreWidths, &table), Status::kOk);
  for (const float bad : {kNaN, -kNaN, -1.0F, -1e-30F, 0.0F, -0.0F, kInf, -kInf}) {
    EXPECT_EQ(table.select(bad), -1) << "range^2 " << bad;
  }
}

TEST(Routing, ConstantFinestLayerUsesItsOwnLimit) {
  const NoiseModel model = cadre_stereo();
  const double k = 0.1 / (600.0 * static_cast<double>(0.05F));
  const auto sigma = [k](double r) { return k * r * r; };

  // Default rule: the constant layer's limit is the IV-G bound of its own width, so the table
  // equals the all-CCM table.
  RoutingTable<kLayers> plain{};
  RoutingTable<kLayers> with_default{};
  ASSERT_EQ(build_routing_table(model, kCadreWidths, &plain), Status::kOk);
  ASSERT_EQ(build_routing_table(model, kCadreWidths, constant_layer_max_sigma(kCadreWidths[0]),
                                &with_default),
            Status::kOk);
  EXPECT_EQ(std::memcmp(&plain, &with_default, sizeof(plain)), 0);

  // A looser caller limit (1.5x IV-G, still below layer 1's IV-G bound of 2x).
  const float finest = 1.5F * max_sigma_for_cell_width(kCadreWidths[0]);
  RoutingTable<kLayers> loose{};
  ASSERT_EQ(build_routing_table(model, kCadreWidths, finest, &loose), Status::kOk);
  double boundaries_sq[kLayers];
  boundaries_sq[0] = static_cast<double>(finest) / k;
  for (int i = 1; i < kLayers; ++i) {
    boundaries_sq[i] = static_cast<double>(kCadreWidths[i]) / (2.0 * std::sqrt(12.0)) / k;
  }
  expect_non_decreasing(loose);
  EXPECT_GT(loose.max_range_sq[0], plain.max_range_sq[0]);
  EXPECT_LT(loose.max_range_sq[0], loose.max_range_sq[1]) << "layer 1 keeps a band";
  sweep_against_reference(loose, kCadreWidths, sigma, boundaries_sq, static_cast<double>(finest),
                          "constant finest layer at 1.5x");
  expect_boundaries_exact(loose, boundaries_sq, "constant finest layer at 1.5x");

  // Limits that would starve layer 1, or make no sense, are refused and leave *out alone.
  RoutingTable<kLayers> untouched;
  for (int i = 0; i < kLayers; ++i) untouched.max_range_sq[i] = -7.0F;
  RoutingTable<kLayers> out = untouched;
  EXPECT_EQ(build_routing_table(model, kCadreWidths, max_sigma_for_cell_width(kCadreWidths[1]),
                                &out),
            Status::kInvalidArgument)
      << "limit equal to layer 1's IV-G bound starves layer 1";
  EXPECT_EQ(build_routing_table(model, kCadreWidths,
                                2.0F * max_sigma_for_cell_width(kCadreWidths[1]), &out),
            Status::kInvalidArgument);
  EXPECT_EQ(build_routing_table(model, kCadreWidths, kInf, &out), Status::kInvalidArgument);
  EXPECT_EQ(build_routing_table(model, kCadreWidths, 0.0F, &out), Status::kInvalidArgument);
  EXPECT_EQ(build_routing_table(model, kCadreWidths, -0.01F, &out), Status::kInvalidArgument);
  EXPECT_EQ(build_routing_table(model, kCadreWidths, kNaN, &out), Status::kNonFiniteInput);
  EXPECT_EQ(std::memcmp(&out, &untouched, sizeof(out)), 0) << "refused build wrote the table";
  // Just below layer 1's bound is accepted: layer 1 keeps a (tiny) band.
  EXPECT_EQ(build_routing_table(model, kCadreWidths,
                                std::nextafter(max_sigma_for_cell_width(kCadreWidths[1]), 0.0F),
                                &out),
            Status::kOk);
  EXPECT_LT(out.max_range_sq[0], out.max_range_sq[1]);

  // A single constant layer may take every range.
  const float one[1] = {0.04F};
  RoutingTable<1> single{};
  ASSERT_EQ(build_routing_table(model, one, kInf, &single), Status::kOk);
  EXPECT_EQ(single.max_range_sq[0], kMaxFloat);
  EXPECT_EQ(single.select(1e6F), 0);
}

TEST(Routing, BadConfigurationIsRefusedAndLeavesTableUnchanged) {
  const NoiseModel model = cadre_stereo();
  RoutingTable<kLayers> untouched;
  for (int i = 0; i < kLayers; ++i) untouched.max_range_sq[i] = -7.0F;
  struct Case {
    float widths[kLayers];
    Status expected;
    const char* what;
  };
  const Case cases[] = {
      {{0.04F, 0.08F, 0.08F, 0.32F, 0.64F}, Status::kInvalidArgument, "equal widths"},
      {{0.08F, 0.04F, 0.16F, 0.32F, 0.64F}, Status::kInvalidArgument, "coarse before fine"},
      {{0.0F, 0.08F, 0.16F, 0.32F, 0.64F}, Status::kInvalidArgument, "zero width"},
      {{-0.04F, 0.08F, 0.16F, 0.32F, 0.64F}, Status::kInvalidArgument, "negative width"},
      {{0.04F, kNaN, 0.16F, 0.32F, 0.64F}, Status::kNonFiniteInput, "NaN width"},
      {{0.04F, 0.08F, 0.16F, 0.32F, kInf}, Status::kNonFiniteInput, "Inf width"},
  };
  for (const Case& c : cases) {
    RoutingTable<kLayers> out = untouched;
    EXPECT_EQ(build_routing_table(model, c.widths, &out), c.expected) << c.what;
    EXPECT_EQ(std::memcmp(&out, &untouched, sizeof(out)), 0) << c.what << ": table written";
    EXPECT_EQ(build_routing_table(model, c.widths, 0.001F, &out), c.expected) << c.what;
  }
  RoutingTable<kLayers> out = untouched;
  RoutingTable<kLayers>* const no_table = nullptr;
  EXPECT_EQ(build_routing_table(model, kCadreWidths, no_table), Status::kInvalidArgument);
  EXPECT_EQ(build_routing_table(model, kCadreWidths, 0.001F, no_table), Status::kInvalidArgument);
  EXPECT_EQ(build_routing_table(NoiseModel{}, kCadreWidths, &out), Status::kNotInitialised);
  EXPECT_EQ(build_routing_table(NoiseModel::stereo({0.0F, 0.05F, 0.1F}), kCadreWidths, &out),
            Status::kInvalidArgument);
  EXPECT_EQ(build_routing_table(NoiseModel::lidar({kNaN, 0.0F}), kCadreWidths, &out),
            Status::kNonFiniteInput);
  EXPECT_EQ(std::memcmp(&out, &untouched, sizeof(out)), 0);
}

TEST(Routing, CadreStackRoutesFiveMetresToSixtyFourCentimetres) {
  RoutingTable<kLayers> table{};
  ASSERT_EQ(build_routing_table(cadre_stereo(), kCadreWidths, &table), Status::kOk);
  EXPECT_EQ(table.select(1.0F), 0) << "1 m: 4 cm layer";
  EXPECT_EQ(table.select(1.5F * 1.5F), 1) << "1.5 m: 8 cm layer";
  EXPECT_EQ(table.select(2.5F * 2.5F), 2) << "2.5 m: 16 cm layer";
  EXPECT_EQ(table.select(3.5F * 3.5F), 3) << "3.5 m: 32 cm layer";
  EXPECT_EQ(table.select(5.0F * 5.0F), 4) << "5 m: 64 cm layer (paper Section VI)";
  EXPECT_EQ(table.select(5.3F * 5.3F), -1) << "5.3 m: too noisy for every layer";
}

}  // namespace
}  // namespace ccmap::sensor
