// The 4 x 4 algebra of registration (src/registration/detail/normal_equations.cpp, compiled into this
// test again with EIGEN_RUNTIME_NO_MALLOC and assertions on): no Eigen heap allocation while
// Eigen::internal::set_is_malloc_allowed(false) (an eigen_assert fires otherwise), and the
// answers against a double-precision solve of the same equations.
#ifndef EIGEN_RUNTIME_NO_MALLOC
#error "build with EIGEN_RUNTIME_NO_MALLOC (tests/registration/CMakeLists.txt)"
#endif
#ifdef NDEBUG
#error "build with assertions on: EIGEN_RUNTIME_NO_MALLOC is an eigen_assert"
#endif

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <random>

#include "ccmap/registration/detail/normal_equations.hpp"

namespace ccmap::detail {
namespace {

/// Normal equations of n random residuals with gradients (-gx, -gy, 1, gx ly - gy lx): a terrain
/// with slopes of `slope` (0: flat) and levers up to 3 m.
NormalEquations4 random_equations(std::uint32_t seed, float slope, int groups_n, GroupEquations4* groups) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0F, 1.0F);
  NormalEquations4 eq{};
  eq.clear();
  for (int k = 0; k < groups_n; ++k) groups[k].clear();
  for (int i = 0; i < 800; ++i) {
    const float gx = slope * g(rng), gy = slope * g(rng);
    const float lx = 3.0F * std::fabs(g(rng)), ly = g(rng);
    const float j[4] = {-gx, -gy, 1.0F, gx * ly - gy * lx};
    const float w = 1.0e5F * (0.5F + std::fabs(g(rng)));
    const float r = 1.0e-3F * g(rng);
    eq.add(j, w, r, true);
    eq.add_gradient_noise(w, 1e-6F, 1e-6F, 0.0F, lx, ly);
    if (groups_n > 0) groups[i % groups_n].add(j, w, r);
  }
  return eq;
}

TEST(RegistrationAlgebra, SolvesWithoutTheHeap) {
  GroupEquations4 groups[kJackknifeGroups];
  bool used[kJackknifeGroups];
  for (bool& u : used) u = true;
  for (const float slope : {0.0F, 0.05F, 0.3F}) {
    const NormalEquations4 eq = random_equations(7U, slope, kJackknifeGroups, groups);
    Eigen::internal::set_is_malloc_allowed(false);
    const Solve4 s = solve_normal_equations(eq, 1.5F, 1.0F, 0.03F, 2.0F);
    float jack[4][4] = {};
    const bool jack_ok = s.rank > 0U && jackknife_covariance(groups, used, s, 1.5F, jack);
    Eigen::internal::set_is_malloc_allowed(true);
    ASSERT_TRUE(s.ok) << "slope " << slope;
    if (s.rank > 0U) {
      EXPECT_TRUE(jack_ok) << "slope " << slope;
    }
  }
}

TEST(RegistrationAlgebraDeathTest, TheGuardCatchesAnEigenHeapAllocation) {
  // The guard itself: a dynamic-size matrix allocates, and the assertion stops it.
  EXPECT_DEATH(
      {
        Eigen::internal::set_is_malloc_allowed(false);
        Eigen::MatrixXf m(4, 4);
        m.setZero();
        Eigen::internal::set_is_malloc_allowed(true);
      },
      "malloc");
}

TEST(RegistrationAlgebra, FullRankStepAndCovarianceMatchADoubleSolve) {
  GroupEquations4 groups[1];
  const NormalEquations4 eq = random_equations(11U, 0.3F, 0, groups);
  const Solve4 s = solve_normal_equations(eq, 1.5F, 1.0F, 0.03F, 2.0F);
  ASSERT_TRUE(s.ok);
  ASSERT_EQ(s.rank, 4U) << "slopes of 0.3 fix all four";
  Eigen::Matrix4d h, e, n;
  Eigen::Vector4d b;
  for (int i = 0; i < 4; ++i) {
    b(i) = eq.b[i];
    for (int j = 0; j < 4; ++j) {
      const int a = std::min(i, j), c = std::max(i, j);
      h(i, j) = eq.e[a][c] + eq.f[a][c];
      e(i, j) = eq.e[a][c];
      n(i, j) = eq.n[a][c];
    }
  }
  const Eigen::Vector4d step = -h.ldlt().solve(b);
  const Eigen::Matrix4d cov = (e - n).inverse();
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(s.step[i], step(i), 1e-4 * std::fabs(step(i)) + 1e-9) << "step " << i;
    EXPECT_NEAR(s.covariance[i][i], cov(i, i), 1e-3 * cov(i, i)) << "variance " << i;
    EXPECT_TRUE(s.axis_observable[i]);
  }
}

TEST(RegistrationAlgebra, FlatGroundKeepsOnlyTheHeight) {
  GroupEquations4 groups[1];
  const NormalEquations4 eq = random_equations(13U, 0.0F, 0, groups);
  const Solve4 s = solve_normal_equations(eq, 1.5F, 1.0F, 0.03F, 2.0F);
  ASSERT_TRUE(s.ok);
  EXPECT_EQ(s.rank, 1U);
  EXPECT_TRUE(s.axis_observable[2]);
  EXPECT_FALSE(s.axis_observable[0] || s.axis_observable[1] || s.axis_observable[3]);
  // The height step is the weighted mean residual's negative: -b_z / H_zz.
  EXPECT_NEAR(s.step[2], -eq.b[2] / eq.e[2][2], 1e-6);
  EXPECT_EQ(s.step[0], 0.0F);
}

TEST(RegistrationAlgebra, RefusesNonFiniteEquations) {
  GroupEquations4 groups[1];
  NormalEquations4 eq = random_equations(17U, 0.3F, 0, groups);
  eq.e[0][1] = std::nanf("");
  EXPECT_FALSE(solve_normal_equations(eq, 1.5F, 1.0F, 0.03F, 2.0F).ok);
  eq = random_equations(17U, 0.3F, 0, groups);
  EXPECT_FALSE(solve_normal_equations(eq, 0.0F, 1.0F, 0.03F, 2.0F).ok) << "a zero lever";
  EXPECT_FALSE(solve_normal_equations(eq, 1.5F, 0.5F, 0.03F, 2.0F).ok) << "a variance factor below 1";
}

}  // namespace
}  // namespace ccmap::detail
