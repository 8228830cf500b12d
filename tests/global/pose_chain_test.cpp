// A loop closure distributed over a pose chain (include/ccmap/global/pose_chain.hpp), against
// the chain's weighted least squares solved directly in double: the normal equations of the
// odometry edges (variances from the stamps' sigmas) with the anchor fixed and the loop edge
// given a weight 1e12 times the chain's.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ccmap/global/pose_chain.hpp"

namespace ccmap {
namespace {

/// Corrections of nodes 0..n-1 minimising sum (d_i - d_(i-1))^2 / q_i + w (d_(n-1) - c)^2 with
/// d_j = 0 for j <= anchor (held: removed from the unknowns).
std::vector<double> least_squares(const std::vector<double>& variance, std::size_t anchor, double c) {
  const std::size_t n = variance.size();
  const std::size_t m = n - 1U - anchor;  // unknowns: nodes anchor+1 .. n-1
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  Eigen::VectorXd b = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m));
  for (std::size_t i = anchor + 1U; i < n; ++i) {
    const double w = 1.0 / std::max(variance[i] - variance[i - 1U], 1e-12);
    const auto u = static_cast<Eigen::Index>(i - anchor - 1U);
    a(u, u) += w;
    if (i - 1U > anchor) {
      a(u - 1, u - 1) += w;
      a(u, u - 1) -= w;
      a(u - 1, u) -= w;
    }
  }
  double chain = 0.0;
  for (std::size_t i = anchor + 1U; i < n; ++i) chain += 1.0 / std::max(variance[i] - variance[i - 1U], 1e-12);
  const double loop = 1e12 * chain;
  a(static_cast<Eigen::Index>(m) - 1, static_cast<Eigen::Index>(m) - 1) += loop;
  b(static_cast<Eigen::Index>(m) - 1) += loop * c;
  const Eigen::VectorXd d = a.ldlt().solve(b);
  std::vector<double> out(n, 0.0);
  for (std::size_t k = 0; k < m; ++k) out[anchor + 1U + k] = d(static_cast<Eigen::Index>(k));
  return out;
}

TEST(PoseChain, ALoopClosureIsSharedAsTheLeastSquaresOfTheChain) {
  constexpr std::size_t kNodes = 40U;
  for (const std::size_t anchor : {std::size_t{0}, std::size_t{7}}) {
    PoseChain<64> chain;
    std::vector<double> var_xy, var_yaw;
    std::uint32_t s = 11U;
    float sigma_xy = 0.0F, sigma_yaw = 0.0F;
    for (std::size_t i = 0; i < kNodes; ++i) {
      s = s * 1664525U + 1013904223U;
      const float step = 0.002F + 0.02F * static_cast<float>(s >> 8) / 16777216.0F;  // uneven edges
      sigma_xy = std::sqrt(sigma_xy * sigma_xy + step * step);
      sigma_yaw = std::sqrt(sigma_yaw * sigma_yaw + 0.1F * step * step * static_cast<float>(i % 3U));
      const PatchPose pose{0.5F * static_cast<float>(i), 0.1F * static_cast<float>(i), 0.01F, sigma_xy, sigma_yaw};
      ASSERT_EQ(chain.append(pose, static_cast<std::uint32_t>(i)), Status::kOk);
      var_xy.push_back(static_cast<double>(sigma_xy) * sigma_xy);
      var_yaw.push_back(static_cast<double>(sigma_yaw) * sigma_yaw);
    }
    const float dx = 0.8F, dy = -0.45F, dyaw = 0.12F;
    PoseChain<64> turned = chain;  // the headings' shares, from their own closure
    ASSERT_EQ(chain.close_loop(anchor, dx, dy, 0.0F), Status::kOk);
    ASSERT_EQ(turned.close_loop(anchor, 0.0F, 0.0F, dyaw), Status::kOk);
    const auto rx = least_squares(var_xy, anchor, dx);
    const auto ry = least_squares(var_xy, anchor, dy);
    const auto ryaw = least_squares(var_yaw, anchor, dyaw);
    for (std::size_t k = 0; k < kNodes; ++k) {
      const ChainNode n = chain.node(k);
      EXPECT_NEAR(n.pose.x_m - 0.5F * static_cast<float>(k), rx[k], 2e-6) << k;
      EXPECT_NEAR(n.pose.y_m - 0.1F * static_cast<float>(k), ry[k], 2e-6) << k;
      EXPECT_NEAR(turned.node(k).pose.yaw_rad - 0.01F, ryaw[k], 2e-6) << k;
    }
    EXPECT_NEAR(chain.node(kNodes - 1U).pose.x_m - 0.5F * (kNodes - 1U), dx, 1e-5);
  }
}

// A drive whose odometry heading drifts at a constant rate (variance growing with distance, as
// the stamps say): closing the loop with the true correction of the last pose turns every step
// back, and the whole corrected trajectory lies on the true one.
TEST(PoseChain, AHeadingDriftIsUndoneAlongTheWholeDrive) {
  PoseChain<256> chain;
  std::vector<double> tx, ty;
  double x = 0.0, y = 0.0, yaw = 0.0, bx = 0.0, by = 0.0, byaw = 0.0, d = 0.0;
  for (int i = 0; i < 200; ++i) {
    tx.push_back(x);
    ty.push_back(y);
    const float sigma = static_cast<float>(std::sqrt(d));  // variance proportional to distance
    ASSERT_EQ(chain.append(PatchPose{static_cast<float>(bx), static_cast<float>(by), static_cast<float>(byaw),
                                     0.03F * sigma, 0.005F * sigma},
                           static_cast<std::uint32_t>(i)),
              Status::kOk);
    const double turn = (i % 50 == 49) ? M_PI / 2.0 : 0.0;
    x += 0.5 * std::cos(yaw);
    y += 0.5 * std::sin(yaw);
    yaw += turn;
    bx += 0.5 * std::cos(byaw);
    by += 0.5 * std::sin(byaw);
    byaw += turn + 0.0025;  // 0.005 rad/m
    d += 0.5;
  }
  const ChainNode last = chain.node(199U);
  const double drift = 0.0025 * 199.0;
  const auto dx = static_cast<float>(tx[199] - last.pose.x_m);
  const auto dy = static_cast<float>(ty[199] - last.pose.y_m);
  ASSERT_EQ(chain.close_loop(0U, dx, dy, static_cast<float>(-drift)), Status::kOk);
  double after = 0.0;
  for (int i = 0; i < 200; ++i) {
    const ChainNode n = chain.node(static_cast<std::size_t>(i));
    const auto k = static_cast<std::size_t>(i);
    after = std::fmax(after, std::hypot(n.pose.x_m - tx[k], n.pose.y_m - ty[k]));
  }
  EXPECT_LT(after, 0.01);  // the drift had moved the last pose by metres
  EXPECT_GT(std::hypot(tx[199] - last.pose.x_m, ty[199] - last.pose.y_m), 5.0);
}

TEST(PoseChain, RefusesBadNodesAndCountsAFullChain) {
  PoseChain<3> chain;
  EXPECT_EQ(chain.append(PatchPose{0, 0, 0, 0.1F, 0.01F}, 1U), Status::kOk);
  EXPECT_EQ(chain.append(PatchPose{NAN, 0, 0, 0.1F, 0.01F}, 2U), Status::kInvalidArgument);
  EXPECT_EQ(chain.append(PatchPose{1, 0, 0, 0.05F, 0.01F}, 2U), Status::kInvalidArgument);  // variance shrank
  EXPECT_EQ(chain.close_loop(0U, 1.0F, 0.0F, 0.0F), Status::kInvalidArgument);             // one node
  EXPECT_EQ(chain.append(PatchPose{1, 0, 0, 0.1F, 0.01F}, 2U), Status::kOk);  // no new variance: shared evenly
  EXPECT_EQ(chain.append(PatchPose{2, 0, 0, 0.1F, 0.01F}, 3U), Status::kOk);
  EXPECT_EQ(chain.append(PatchPose{3, 0, 0, 0.2F, 0.01F}, 4U), Status::kBufferTooSmall);
  EXPECT_EQ(chain.dropped(), 1U);
  EXPECT_EQ(chain.close_loop(2U, 1.0F, 0.0F, 0.0F), Status::kInvalidArgument);  // the anchor is the last node
  ASSERT_EQ(chain.close_loop(0U, 1.0F, 0.0F, 0.0F), Status::kOk);
  EXPECT_FLOAT_EQ(chain.node(1U).pose.x_m, 1.5F);
  EXPECT_FLOAT_EQ(chain.node(2U).pose.x_m, 3.0F);
}

}  // namespace
}  // namespace ccmap
