// The loop experiment (docs/design.md section 13.5): a rover drives a 100 m square
// loop over analytic terrain with drifting odometry (3 % of distance, 0.005 rad/m of heading),
// maps it through a PatchKeeper (patches in a caller region), and back at the start aligns its
// view against the patches of the start (CoarseAligner, nominal offset: "I am back where I
// started"), then shares the correction over the trajectory (PoseChain). Prints the pose error
// at the closure before and after, the trajectory's RMS error before and after, and the cost per
// frame of keeping patches (thread CPU time on the host; the aarch64 instruction counts of a
// keeper move: tests/icount/icount_patch_example.cpp).
//
//   build/host-release/tools/bench/ccmap_loop_experiment [--side-m 25] [--step-m 0.5]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include "ccmap/global/coarse_alignment.hpp"
#include "ccmap/global/patch_keeper.hpp"
#include "ccmap/global/pose_chain.hpp"
#include "support/global_configs.hpp"

namespace {

using LoopConfig = ccmap::test::ThreeCcmConfig;
using Map = ccmap::Stack<LoopConfig>;
using Keeper = ccmap::PatchKeeper<LoopConfig, 16>;

double terrain(double x, double y) {
  return 0.25 * std::sin(1.3 * x + 0.4) * std::cos(0.9 * y) + 0.15 * std::sin(0.7 * y - 0.5 * x) +
         0.05 * std::cos(3.1 * x) + 0.08 * std::sin(2.3 * y + 0.2 * x);
}

struct Pose {
  double x, y, yaw;
};

double thread_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// The ground within `radius` of the true pose, as the rover places it with its believed pose.
std::vector<ccmap::PointXYZ> frame(const Pose& truth, const Pose& believed, double radius, std::uint32_t seed) {
  std::vector<ccmap::PointXYZ> out;
  std::uint32_t s = seed * 2654435761U + 1U;
  const double ct = std::cos(truth.yaw), st = std::sin(truth.yaw);
  const double cb = std::cos(believed.yaw), sb = std::sin(believed.yaw);
  for (double v = -radius; v <= radius; v += 0.03) {
    for (double u = -radius; u <= radius; u += 0.03) {
      if (u * u + v * v > radius * radius) continue;
      s = s * 1664525U + 1013904223U;
      const double noise = 0.006 * (static_cast<double>(s >> 8) / 16777216.0 - 0.5);
      const double gx = truth.x + ct * u - st * v, gy = truth.y + st * u + ct * v;  // the true ground point
      out.push_back(ccmap::PointXYZ{static_cast<float>(believed.x + cb * u - sb * v),
                                    static_cast<float>(believed.y + sb * u + cb * v),
                                    static_cast<float>(terrain(gx, gy) + noise)});
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  double side = 25.0, step = 0.5;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--side-m") == 0) side = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--step-m") == 0) step = std::atof(argv[i + 1]);
  }
  const auto map = std::make_unique<Map>();
  const auto keeper = std::make_unique<Keeper>();
  const std::size_t slot = Keeper::kMaxPatchBytes + ccmap::platform::RegionPatchStorage::kSlotHeaderBytes;
  std::vector<std::uint8_t> region(4096U * slot);
  ccmap::platform::RegionPatchStorage storage;
  ccmap::StackParams params = ccmap::default_stack_params(0.04F);
  params.free_space_rays = 0.0F;
  if (map->init(params) != ccmap::Status::kOk || !storage.init(region.data(), region.size(), slot) ||
      keeper->init(*map, storage.table()) != ccmap::Status::kOk) {
    std::fprintf(stderr, "loop_experiment: init failed\n");
    return 1;
  }
  // The true path: a square, counter-clockwise, frames every `step` m; odometry integrates the
  // true increments with a 3 % scale error and a heading drift of 0.005 rad per metre.
  std::vector<Pose> truth, believed;
  const int per_side = static_cast<int>(std::lround(side / step));
  Pose t{0.0, 0.0, 0.0}, b{0.0, 0.0, 0.0};
  double travelled = 0.0;
  ccmap::PoseChain<1024> chain;
  double keep_time = 0.0, update_time = 0.0, worst_keep = 0.0;
  std::uint32_t worst_writes = 0U;
  for (int leg = 0; leg < 4; ++leg) {
    for (int k = 0; k < per_side; ++k) {
      truth.push_back(t);
      believed.push_back(b);
      // Odometry sigmas whose variance grows with distance (a random walk per metre).
      const float sigma_xy = static_cast<float>(0.03 * std::sqrt(travelled));
      const float sigma_yaw = static_cast<float>(0.005 * std::sqrt(travelled));
      const ccmap::PatchPose stamp{static_cast<float>(b.x), static_cast<float>(b.y), static_cast<float>(b.yaw),
                                   sigma_xy, sigma_yaw};
      ccmap::PatchMoveReport report{};
      const double t0 = thread_seconds();
      const ccmap::Status moved = keeper->move_to(stamp.x_m, stamp.y_m, stamp, &report);
      const double t1 = thread_seconds();
      const auto points = frame(t, b, 2.5, static_cast<std::uint32_t>(truth.size()));
      const ccmap::Status updated =
          map->update_frame(points.data(), points.size(), ccmap::PointXYZ{stamp.x_m, stamp.y_m, 1.2F}, nullptr);
      const double t2 = thread_seconds();
      if (moved != ccmap::Status::kOk || updated != ccmap::Status::kOk ||
          chain.append(stamp, static_cast<std::uint32_t>(truth.size() - 1U)) != ccmap::Status::kOk) {
        std::fprintf(stderr, "loop_experiment: frame %zu refused\n", truth.size());
        return 1;
      }
      keep_time += t1 - t0;
      update_time += t2 - t1;
      worst_keep = std::fmax(worst_keep, t1 - t0);
      worst_writes = report.patches_written > worst_writes ? report.patches_written : worst_writes;
      // The next true pose, and what odometry makes of the move.
      const double turn = (k == per_side - 1) ? M_PI / 2.0 : 0.0;
      t = Pose{t.x + step * std::cos(t.yaw), t.y + step * std::sin(t.yaw), t.yaw + turn};
      b = Pose{b.x + 1.03 * step * std::cos(b.yaw), b.y + 1.03 * step * std::sin(b.yaw), b.yaw + turn + 0.005 * step};
      travelled += step;
    }
  }
  // Back at the start (t is the start again): the view, in the believed frame.
  const auto view = std::make_unique<Map>();
  const auto old_map = std::make_unique<Map>();
  const auto reader = std::make_unique<Keeper>();
  const auto aligner = std::make_unique<ccmap::CoarseAligner<LoopConfig>>();
  const auto points = frame(t, b, 3.0, 99999U);
  ccmap::PatchMoveReport read{};
  if (view->init(params) != ccmap::Status::kOk ||
      view->move_to(static_cast<float>(b.x), static_cast<float>(b.y)) != ccmap::Status::kOk ||
      view->update_frame(points.data(), points.size(),
                         ccmap::PointXYZ{static_cast<float>(b.x), static_cast<float>(b.y), 1.2F},
                         nullptr) != ccmap::Status::kOk ||
      old_map->init(params) != ccmap::Status::kOk ||
      reader->init(*old_map, storage.table(), &read) != ccmap::Status::kOk) {
    std::fprintf(stderr, "loop_experiment: the revisit failed\n");
    return 1;
  }
  // The hypothesis "back at the start": the view's believed position taken for the first pose's.
  const ccmap::MapOffset offset{static_cast<float>(believed[0].x - b.x), static_cast<float>(believed[0].y - b.y), 0.0F};
  ccmap::CoarseSearchParams search = ccmap::default_coarse_search_params();
  search.range_yaw_rad = 0.7F;  // 0.005 rad/m over 100 m: 0.5 rad
  ccmap::RegistrationParams reg = ccmap::default_registration_params();
  reg.max_iterations = 30U;
  ccmap::CoarseReport coarse{};
  const double a0 = thread_seconds();
  const ccmap::AlignmentResult a = aligner->align(*old_map, *view, offset, reg, search, &coarse);
  const double align_time = thread_seconds() - a0;
  const auto error = [&](const Pose& p) { return std::hypot(p.x - t.x, p.y - t.y); };
  std::printf(
      "loop: %.0f m square, %zu frames every %.2f m, odometry 3 %% + 0.005 rad/m; %u patches written, "
      "%u cells read back for the revisit\n",
      4.0 * side, truth.size(), step, keeper->counters().patches_written, read.cells_restored);
  std::printf("closure before: position error %.3f m, heading error %.2f deg\n", error(b),
              (b.yaw - t.yaw) * 180.0 / M_PI);
  if (a.correction.status != ccmap::Status::kOk) {
    std::printf("closure: alignment %s (no correction)\n", ccmap::to_string(a.correction.status));
    return 0;
  }
  // The corrected pose: the view's point at the believed position, moved by offset and correction.
  const double c = std::cos(a.correction.dyaw), s = std::sin(a.correction.dyaw);
  const double px = b.x + offset.x_m - a.centre_x_m, py = b.y + offset.y_m - a.centre_y_m;
  const Pose corrected{c * px - s * py + a.centre_x_m + a.correction.dx,
                       s * px + c * py + a.centre_y_m + a.correction.dy, b.yaw + a.correction.dyaw};
  std::printf("closure after: position error %.3f m, heading error %.2f deg (alignment %s, %.1f ms, rank %u)\n",
              error(corrected), (corrected.yaw - t.yaw) * 180.0 / M_PI, ccmap::to_string(a.correction.status),
              1e3 * align_time, static_cast<unsigned>(a.correction.rank));
  // Shared over the trajectory: the last node (the pose one step before the closing one) takes
  // the closing pose's correction.
  if (chain.close_loop(0U, static_cast<float>(corrected.x - b.x), static_cast<float>(corrected.y - b.y),
                       static_cast<float>(corrected.yaw - b.yaw)) != ccmap::Status::kOk) {
    std::fprintf(stderr, "loop_experiment: close_loop refused\n");
    return 1;
  }
  double before = 0.0, after = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const ccmap::ChainNode n = chain.node(i);
    before += std::pow(believed[i].x - truth[i].x, 2) + std::pow(believed[i].y - truth[i].y, 2);
    after += std::pow(n.pose.x_m - truth[i].x, 2) + std::pow(n.pose.y_m - truth[i].y, 2);
  }
  std::printf("trajectory RMS position error: before %.3f m, after the chain's share %.3f m\n",
              std::sqrt(before / static_cast<double>(truth.size())),
              std::sqrt(after / static_cast<double>(truth.size())));
  std::printf(
      "cost per frame (host thread CPU): keeper move %.3f ms mean, %.3f ms worst (%u patch writes), frame update "
      "%.3f ms mean\n",
      1e3 * keep_time / static_cast<double>(truth.size()), 1e3 * worst_keep, worst_writes,
      1e3 * update_time / static_cast<double>(truth.size()));
  return 0;
}
