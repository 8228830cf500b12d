// The poses of the patches written since a loop's anchor, and a loop closure's correction
// distributed over them: the least-squares solution of a pose chain with one loop edge.
//
// Model (linearised: x, y and yaw each on its own; close_loop then turns the positions by
// the heading corrections, below). Nodes 0..n-1 are patch stamps in write order (PatchPose: the rover's pose and its
// odometry sigmas, which grow along the drive: the variance V_i = sigma_i^2 accumulated since
// the start). Consecutive nodes are joined by odometry edges of variance q_i = V_i - V_(i-1).
// A loop closure says the last node lies at its pose + c relative to node a (the anchor: the
// old patches a revisit was aligned against), known far better than the chain (a rigid
// constraint). Minimising sum_i (d_i - d_(i-1))^2 / q_i over the corrections d, with d_a = 0
// and d_(n-1) = c, gives
//     d_k = c (V_k - V_a) / (V_(n-1) - V_a)   for k >= a,   d_k = 0 for k <= a:
// each edge takes the share of the loop's error its variance is of the chain's. Where the chain
// holds no variance (V_(n-1) = V_a) the correction is shared equally per edge.
// tests/global/pose_chain_test.cpp checks it against the normal equations solved in double.
//
// Fixed size (kMaxNodes), no heap; O(n) per closure. What it does not do: move the cells of the
// patches (they stay at the indices they were written at; docs/design.md section 13.6).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "ccmap/core/status.hpp"
#include "ccmap/global/patch_keeper.hpp"

namespace ccmap {

struct ChainNode {
  PatchPose pose;          ///< as stamped, then corrected by close_loop
  std::uint32_t sequence;  ///< the patch write it belongs to (PatchHeader::sequence), caller's key
};

template <std::size_t kMaxNodes>
class PoseChain {
 public:
  static_assert(kMaxNodes >= 2U, "a chain needs two nodes");

  /// Appends a node. kBufferTooSmall when full (the node is not kept; counted);
  /// kInvalidArgument for a non-finite pose or sigma, or sigmas smaller than the last node's
  /// (odometry variance only grows along a chain).
  [[nodiscard]] Status append(const PatchPose& pose, std::uint32_t sequence) noexcept {
    const bool finite = std::isfinite(pose.x_m) && std::isfinite(pose.y_m) && std::isfinite(pose.yaw_rad) &&
                        std::isfinite(pose.sigma_xy_m) && std::isfinite(pose.sigma_yaw_rad) &&
                        pose.sigma_xy_m >= 0.0F && pose.sigma_yaw_rad >= 0.0F;
    if (!finite || (size_ > 0U && (pose.sigma_xy_m < nodes_[size_ - 1U].pose.sigma_xy_m ||
                                   pose.sigma_yaw_rad < nodes_[size_ - 1U].pose.sigma_yaw_rad))) {
      return Status::kInvalidArgument;
    }
    if (size_ == kMaxNodes) {
      ++dropped_;
      return Status::kBufferTooSmall;
    }
    nodes_[size_] = ChainNode{pose, sequence};
    ++size_;
    return Status::kOk;
  }

  /// Moves the last node by (dx, dy, dyaw) (map frame, m and rad) relative to node `anchor`, the
  /// nodes in between by their least-squares shares (file comment), the nodes up to the anchor
  /// not at all. kInvalidArgument: anchor not before the last node, a non-finite correction.
  ///
  /// Headings first: node k's heading takes its share of dyaw, and every odometry step after
  /// the anchor is turned by its start node's heading correction (the positions re-integrated:
  /// a heading error moves everything after it); the translation that then remains at the last
  /// node is shared by the position shares. With dyaw = 0 this is the linear chain exactly.
  [[nodiscard]] Status close_loop(std::size_t anchor, float dx, float dy, float dyaw) noexcept {
    // size_ <= kMaxNodes always; said here so that the compiler knows every index below is in range.
    if (size_ < 2U || size_ > kMaxNodes || anchor >= size_ - 1U || !std::isfinite(dx) || !std::isfinite(dy) ||
        !std::isfinite(dyaw)) {
      return Status::kInvalidArgument;
    }
    const std::size_t last = size_ - 1U;
    const float target_x = nodes_[last].pose.x_m + dx;
    const float target_y = nodes_[last].pose.y_m + dy;
    // Headings, and the positions re-integrated with the turned steps.
    float previous_x = nodes_[anchor].pose.x_m;  // the uncorrected position of node k - 1
    float previous_y = nodes_[anchor].pose.y_m;
    float turn = 0.0F;  // heading correction of node k - 1
    for (std::size_t k = anchor + 1U; k <= last; ++k) {
      PatchPose& p = nodes_[k].pose;
      const float step_x = p.x_m - previous_x;
      const float step_y = p.y_m - previous_y;
      previous_x = p.x_m;
      previous_y = p.y_m;
      const float c = std::cos(turn);
      const float s = std::sin(turn);
      const PatchPose& before = nodes_[k - 1U].pose;  // already corrected
      p.x_m = before.x_m + c * step_x - s * step_y;
      p.y_m = before.y_m + s * step_x + c * step_y;
      turn = share(anchor, k, &PatchPose::sigma_yaw_rad) * dyaw;
      p.yaw_rad += turn;
    }
    // The translation left at the last node, shared.
    const float rest_x = target_x - nodes_[last].pose.x_m;
    const float rest_y = target_y - nodes_[last].pose.y_m;
    for (std::size_t k = anchor + 1U; k <= last; ++k) {
      const float f = share(anchor, k, &PatchPose::sigma_xy_m);
      nodes_[k].pose.x_m += f * rest_x;
      nodes_[k].pose.y_m += f * rest_y;
    }
    return Status::kOk;
  }

  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  /// Node i (0 <= i < size()); the zero node beyond.
  [[nodiscard]] ChainNode node(std::size_t i) const noexcept { return i < size_ ? nodes_[i] : ChainNode{}; }
  /// Nodes refused because the chain was full.
  [[nodiscard]] std::uint32_t dropped() const noexcept { return dropped_; }
  void clear() noexcept {
    size_ = 0U;
    dropped_ = 0U;
  }

 private:
  [[nodiscard]] static float variance(float sigma) noexcept { return sigma * sigma; }
  /// Node k's share of a correction between the anchor and the last node, by the variance of the
  /// sigma `field` (equal shares per edge where the chain holds none).
  [[nodiscard]] float share(std::size_t anchor, std::size_t k, float PatchPose::*field) const noexcept {
    const std::size_t last = size_ - 1U;
    const float va = variance(nodes_[anchor].pose.*field);
    const float span = variance(nodes_[last].pose.*field) - va;
    return span > 0.0F ? (variance(nodes_[k].pose.*field) - va) / span
                       : static_cast<float>(k - anchor) / static_cast<float>(last - anchor);
  }

  ChainNode nodes_[kMaxNodes]{};
  std::size_t size_ = 0U;
  std::uint32_t dropped_ = 0U;
};

}  // namespace ccmap
