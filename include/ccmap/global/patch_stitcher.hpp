// Stitching: a loop closure's correction distributed over the patches written since its anchor,
// and those patches re-stamped with their corrected poses.
//
// A PatchStitcher sits beside a PatchKeeper. Every move goes through PatchStitcher::move_to,
// which appends the move's stamp to a PoseChain (one node per move: global/pose_chain.hpp) and
// logs, through the keeper's write observer, which node last wrote each patch. On a loop
// closure (the drift of the last node relative to an anchor node, e.g. from CoarseAligner
// against the anchor's patches) close_loop shares the correction over the nodes after the
// anchor (PoseChain::close_loop: the least squares of the chain) and marks the patches those
// nodes wrote for re-stamping; restamp_step then re-stamps at most `max_patches` of them per
// call (PatchKeeper::restamp: the patch's corrected pose at format offset 52, cells untouched),
// so that the work of a closure is spread over frames.
//
// Which correction a patch takes: its cells were placed with the poses of the frames that saw
// them, not with the pose of the move that wrote the patch (up to a window and a tile later).
// A patch takes the correction M_k = C_k W_k^-1 (corrected after odometry pose) of the node k
// nearest to its tile's centre among the kSearchNodes nodes up to its writer n (the frames that
// passed over it last), stored as the corrected pose M_k W_n, so that C W^-1 in its header is
// M_k. On the 21 m drive of tests/tools/global_map_test.cpp (a heading drift of 0.01 rad/m) this
// took the stitched map's height RMS against the terrain from 2.1 mm (the writer's correction)
// to 0.6 mm.
// The patches stay at the cell indices they were written at: a reader of the store (the global
// map tool, tools/global_map) places each patch's cells by C W^-1 (corrected pose after written
// pose), and the flight map itself stays in the odometry frame it was built in.
//
// Bounds (no heap, fixed sizes): kMaxNodes chain nodes, kMaxPatches logged patches (36 bytes a
// node, 20 a patch). Per move: the keeper's move plus one log lookup of at most kMaxPatches keys
// per patch written. Per restamp_step: at most max_patches keeper restamps (one patch read and
// written each) and a scan of at most kMaxPatches log entries. Per close_loop: O(kMaxNodes)
// (the chain) and O(kMaxPatches) (the marks). Asserted as instruction counts by
// tests/icount/icount_stitch_example.cpp.
//
// One loop per chain: after a closure (and its re-stamping) the chain holds corrected poses, and
// new moves would append odometry poses after them; clear() starts a new chain (the next
// anchor is then its first node). A move whose node the chain cannot take (full) still moves,
// its patches are logged to no node and not re-stamped (counted: untracked_writes).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "ccmap/core/status.hpp"
#include "ccmap/global/patch_keeper.hpp"
#include "ccmap/global/pose_chain.hpp"

namespace ccmap {

/// What restamp_step did.
struct StitchReport {
  std::uint32_t restamped;  ///< patches re-stamped by this call
  std::uint32_t failed;     ///< patches whose re-stamp was refused (missing, corrupt, storage refused)
  std::uint32_t remaining;  ///< patches still to re-stamp after this call
};

template <std::size_t kMaxNodes, std::size_t kMaxPatches>
class PatchStitcher {
 public:
  static_assert(kMaxPatches >= 1U, "a log needs a patch");
  static constexpr std::uint32_t kNoNode = 0xFFFFFFFFU;
  /// Nodes searched back from a patch's writer for the one nearest to it.
  static constexpr std::size_t kSearchNodes = 64U;

  /// Binds the stitcher to an initialised keeper (its write observer) and empties it.
  /// kNotInitialised: the keeper is not.
  template <typename Keeper>
  [[nodiscard]] Status attach(Keeper& keeper) noexcept {
    if (!keeper.initialised()) {
      return Status::kNotInitialised;
    }
    keeper.set_write_observer(&PatchStitcher::on_write, this);
    clear();
    return Status::kOk;
  }

  /// Appends the stamp as the next node (its index: node_count() - 1 afterwards) and moves the
  /// keeper (PatchKeeper::move_to), logging the patches written to the node. The stamp is
  /// checked by the chain first (kInvalidArgument: non-finite, or sigmas smaller than the last
  /// node's): then nothing moves. A full chain does not stop the move (untracked_writes).
  template <typename Keeper>
  [[nodiscard]] Status move_to(Keeper& keeper, float x, float y, const PatchPose& stamp,
                               PatchMoveReport* report) noexcept {
    const Status appended = chain_.append(stamp, static_cast<std::uint32_t>(chain_.size()));
    if (appended == Status::kInvalidArgument) {
      if (report != nullptr) {
        *report = PatchMoveReport{};
      }
      return appended;
    }
    current_ = appended == Status::kOk ? static_cast<std::uint32_t>(chain_.size() - 1U) : kNoNode;
    if (appended == Status::kOk) {
      written_[current_] = PlanarPose{stamp.x_m, stamp.y_m, stamp.yaw_rad};
    }
    const Status moved = keeper.move_to(x, y, stamp, report);
    current_ = kNoNode;
    return moved;
  }

  /// The loop closure: node `anchor`'s pose is right, the last node's pose is off by (dx, dy,
  /// dyaw) (map frame, m and rad: add them to correct it). Shares the correction over the
  /// nodes after the anchor (PoseChain::close_loop) and marks every logged patch of those nodes
  /// for restamp_step. kInvalidArgument: the chain's refusals (anchor not before the last node,
  /// non-finite correction); nothing changes then.
  [[nodiscard]] Status close_loop(std::size_t anchor, float dx, float dy, float dyaw) noexcept {
    const Status closed = chain_.close_loop(anchor, dx, dy, dyaw);
    if (closed != Status::kOk) {
      return closed;
    }
    pending_ = 0U;
    for (std::size_t i = 0; i < logged_; ++i) {
      log_[i].pending = log_[i].node != kNoNode && log_[i].node > anchor;
      pending_ += log_[i].pending ? 1U : 0U;
    }
    cursor_ = 0U;
    return Status::kOk;
  }

  /// Re-stamps at most max_patches of the marked patches with their node's corrected pose.
  /// A refused re-stamp is counted (report->failed) and not retried. report may be nullptr.
  template <typename Keeper>
  void restamp_step(Keeper& keeper, std::uint32_t max_patches, StitchReport* report) noexcept {
    StitchReport r{};
    while (cursor_ < logged_ && r.restamped + r.failed < max_patches) {
      Entry& e = log_[cursor_];
      ++cursor_;
      if (!e.pending) {
        continue;
      }
      e.pending = false;
      --pending_;
      if (keeper.restamp(e.key, corrected_pose(keeper, e)) == Status::kOk) {
        ++r.restamped;
      } else {
        ++r.failed;
        ++restamp_failures_;
      }
    }
    r.remaining = pending_;
    if (report != nullptr) {
      *report = r;
    }
  }

  /// Empties the chain and the log (a new chain after a closure).
  void clear() noexcept {
    chain_.clear();
    logged_ = 0U;
    cursor_ = 0U;
    pending_ = 0U;
    current_ = kNoNode;
  }

  [[nodiscard]] const PoseChain<kMaxNodes>& chain() const noexcept { return chain_; }
  [[nodiscard]] std::size_t node_count() const noexcept { return chain_.size(); }
  [[nodiscard]] std::size_t logged_patches() const noexcept { return logged_; }
  [[nodiscard]] std::uint32_t pending() const noexcept { return pending_; }
  /// Patch writes logged to no node (the chain or the log was full): never re-stamped.
  [[nodiscard]] std::uint32_t untracked_writes() const noexcept { return untracked_; }
  [[nodiscard]] std::uint32_t restamp_failures() const noexcept { return restamp_failures_; }

 private:
  struct Entry {
    platform::PatchKey key;
    std::uint32_t node;  ///< the node that last wrote the patch, kNoNode if none
    bool pending;        ///< marked by close_loop, not yet re-stamped
  };

  /// The patch's corrected pose: M_k W_n (file comment).
  template <typename Keeper>
  [[nodiscard]] PlanarPose corrected_pose(const Keeper& keeper, const Entry& e) const noexcept {
    std::size_t best = e.node;
    float cx = 0.0F;
    float cy = 0.0F;
    if (keeper.tile_centre(e.key, &cx, &cy)) {
      float best_d2 = distance2(written_[e.node], cx, cy);
      const std::size_t first = e.node >= kSearchNodes ? e.node + 1U - kSearchNodes : 0U;
      for (std::size_t k = first; k < e.node; ++k) {
        const float d2 = distance2(written_[k], cx, cy);
        if (d2 < best_d2) {
          best_d2 = d2;
          best = k;
        }
      }
    }
    const PlanarPose& wk = written_[best];
    const PatchPose ck = chain_.node(best).pose;
    const PlanarPose& wn = written_[e.node];
    const float turn = ck.yaw_rad - wk.yaw_rad;
    const float c = std::cos(turn);
    const float s = std::sin(turn);
    const float dx = wn.x_m - wk.x_m;
    const float dy = wn.y_m - wk.y_m;
    return PlanarPose{ck.x_m + c * dx - s * dy, ck.y_m + s * dx + c * dy, wn.yaw_rad + turn};
  }
  [[nodiscard]] static float distance2(const PlanarPose& p, float x, float y) noexcept {
    return (p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y);
  }

  static void on_write(void* context, const platform::PatchKey& key, std::uint32_t /*sequence*/) {
    auto* self = static_cast<PatchStitcher*>(context);
    if (self != nullptr) {
      self->log(key);
    }
  }
  void log(const platform::PatchKey& key) noexcept {
    std::size_t i = 0U;
    while (i < logged_ && !platform::same_key(log_[i].key, key)) {
      ++i;
    }
    if (i == kMaxPatches) {
      ++untracked_;  // the log is full: the patch keeps no node
      return;
    }
    untracked_ += current_ == kNoNode ? 1U : 0U;
    log_[i] = Entry{key, current_, false};  // a rewrite belongs to its last writer only
    logged_ = i == logged_ ? logged_ + 1U : logged_;
  }

  PoseChain<kMaxNodes> chain_{};
  PlanarPose written_[kMaxNodes]{};  ///< the nodes' poses as stamped (the chain corrects its own)
  Entry log_[kMaxPatches]{};
  std::size_t logged_ = 0U;
  std::size_t cursor_ = 0U;
  std::uint32_t pending_ = 0U;
  std::uint32_t current_ = kNoNode;
  std::uint32_t untracked_ = 0U;
  std::uint32_t restamp_failures_ = 0U;
};

}  // namespace ccmap
