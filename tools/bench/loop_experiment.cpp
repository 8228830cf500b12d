// The loop experiment (docs/evaluation.md, "The global map on a loop"): a rover drives a 100 m
// square loop over analytic terrain with rocks, with drifting odometry (3 % of distance by default, 0.005
// rad/m of heading), maps it through a PatchKeeper and a PatchStitcher (patches in a POSIX
// directory), and back at the start aligns its view against the patches of the start
// (CoarseAligner, nominal offset: "I am back where I started"), shares the correction over the
// trajectory and re-stamps the patches, 8 a frame. Prints the pose error at the closure before
// and after, the trajectory's RMS error before and after, the global map's (tools/global_map,
// finest layer) height RMS against the terrain and the rocks it marks as hazards, stitched and
// not, and the cost per frame of keeping and stitching patches (thread CPU time on the host;
// the aarch64 instruction counts: tests/icount/icount_stitch_example.cpp).
//
//   build/host-release/tools/bench/ccmap_loop_experiment [--side-m 25] [--step-m 0.5] [--scale-error 0.03]
//                                                        [--patches DIR]
// (DIR: an empty directory that keeps the patches; default a temporary one, removed at exit).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <string>
#include <vector>

#include <filesystem>

#include "ccmap/global/coarse_alignment.hpp"
#include "ccmap/global/patch_stitcher.hpp"
#include "global_map.hpp"
#include "support/global_configs.hpp"

namespace {

using LoopConfig = ccmap::test::ThreeCcmConfig;
using Map = ccmap::Stack<LoopConfig>;
using Keeper = ccmap::PatchKeeper<LoopConfig, 16>;

/// Rocks: 0.3 m boxes, 0.2 m high, 1 m to the left of the path every 10 m (set by main).
struct Rock {
  double x, y;
};
std::vector<Rock> g_rocks;
constexpr double kRockHalfM = 0.15;
constexpr double kRockHeightM = 0.2;

double ground(double x, double y) {
  return 0.25 * std::sin(1.3 * x + 0.4) * std::cos(0.9 * y) + 0.15 * std::sin(0.7 * y - 0.5 * x) +
         0.05 * std::cos(3.1 * x) + 0.08 * std::sin(2.3 * y + 0.2 * x);
}
/// Distance (m, Chebyshev) from (x, y) to the nearest rock's footprint; 0 inside.
double rock_distance(double x, double y) {
  double best = 1e9;
  for (const Rock& r : g_rocks) {
    best = std::fmin(best, std::fmax(std::fmax(std::fabs(x - r.x), std::fabs(y - r.y)) - kRockHalfM, 0.0));
  }
  return best;
}
double terrain(double x, double y) { return ground(x, y) + (rock_distance(x, y) == 0.0 ? kRockHeightM : 0.0); }

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

/// The global map against the terrain: the height RMS off the rocks' edges (a step no cell width
/// resolves); the rocks with an obstacle pixel within 0.25 m of their footprint and the median
/// distance from a rock's centre to the nearest obstacle pixel; obstacle pixels farther than
/// 0.1 m from every rock; and off the rocks, how often the map's steep class agrees with the
/// terrain's own inclination (above max_inclination).
struct MapScore {
  double rms_m = 0.0;
  int pixels = 0;
  int rocks_marked = 0;
  double rock_median_m = 0.0;
  int stray_obstacles = 0;
  double steep_agreement = 0.0;
};
MapScore score(const ccmap::tools::GlobalRaster& r, double max_inclination) {
  MapScore out;
  double sum = 0.0;
  int classified = 0, agree = 0;
  std::vector<double> nearest(g_rocks.size(), 1e9);
  for (int iy = 0; iy < r.ny; ++iy) {
    for (int ix = 0; ix < r.nx; ++ix) {
      const std::size_t i = static_cast<std::size_t>(iy) * static_cast<std::size_t>(r.nx) + static_cast<std::size_t>(ix);
      if (!std::isfinite(r.height[i])) continue;
      const double x = (static_cast<double>(r.ix_min + ix) + 0.5) * r.cell_width_m;
      const double y = (static_cast<double>(r.iy_min + iy) + 0.5) * r.cell_width_m;
      const double d = rock_distance(x, y);
      const auto cls = static_cast<ccmap::CellClass>(static_cast<int>(r.cell_class[i]));
      if (d > 2.0 * r.cell_width_m) {  // off the rocks and their edges
        sum += std::pow(r.height[i] - terrain(x, y), 2);
        ++out.pixels;
        if (cls == ccmap::CellClass::kTraversable || cls == ccmap::CellClass::kSteep) {
          const double e = 1e-4;
          const double gx = (ground(x + e, y) - ground(x - e, y)) / (2.0 * e);
          const double gy = (ground(x, y + e) - ground(x, y - e)) / (2.0 * e);
          ++classified;
          agree += (std::hypot(gx, gy) > max_inclination) == (cls == ccmap::CellClass::kSteep) ? 1 : 0;
        }
      }
      if (cls == ccmap::CellClass::kObstacle) {
        out.stray_obstacles += d > 0.1 ? 1 : 0;
        for (std::size_t k = 0; k < g_rocks.size(); ++k) {
          nearest[k] = std::fmin(nearest[k], std::hypot(x - g_rocks[k].x, y - g_rocks[k].y));
        }
      }
    }
  }
  out.rms_m = out.pixels > 0 ? std::sqrt(sum / out.pixels) : 0.0;
  out.steep_agreement = classified > 0 ? static_cast<double>(agree) / classified : 0.0;
  for (const double n : nearest) out.rocks_marked += n <= kRockHalfM * std::sqrt(2.0) + 0.25 ? 1 : 0;
  std::vector<double> sorted = nearest;
  std::sort(sorted.begin(), sorted.end());
  out.rock_median_m = sorted.empty() ? 0.0 : sorted[sorted.size() / 2];
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  double side = 25.0, step = 0.5, scale_error = 0.03;
  std::string patch_dir;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--side-m") == 0) side = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--step-m") == 0) step = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--patches") == 0) patch_dir = argv[i + 1];
    if (std::strcmp(argv[i], "--scale-error") == 0) scale_error = std::atof(argv[i + 1]);
  }
  // The patch directory: the caller's, or a temporary one removed at exit.
  std::string temporary;
  if (patch_dir.empty()) {
    std::string pattern = (std::filesystem::temp_directory_path() / "ccmap_loop_XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      std::fprintf(stderr, "loop_experiment: cannot create a temporary directory\n");
      return 1;
    }
    temporary = patch_dir = pattern;
  }
  struct Cleanup {
    std::string path;
    ~Cleanup() {
      std::error_code ec;
      if (!path.empty()) std::filesystem::remove_all(path, ec);
    }
  } cleanup{temporary};
  // Rocks 1 m to the left of the path (inside the square), every 10 m.
  for (double d = 5.0; d < 4.0 * side; d += 10.0) {
    const int leg = static_cast<int>(d / side);
    const double along = d - leg * side;
    const double px[4] = {along, side - 1.0, side - along, 1.0};
    const double py[4] = {1.0, along, side - 1.0, side - along};
    g_rocks.push_back(Rock{px[leg], py[leg]});
  }
  using Stitcher = ccmap::PatchStitcher<1024, 16384>;
  const auto map = std::make_unique<Map>();
  const auto keeper = std::make_unique<Keeper>();
  const auto stitcher = std::make_unique<Stitcher>();
  ccmap::platform::PosixDirectory directory{};
  ccmap::platform::PatchStorage storage{};
  ccmap::StackParams params = ccmap::default_stack_params(0.04F);
  params.free_space_rays = 0.0F;
  if (map->init(params) != ccmap::Status::kOk ||
      !ccmap::platform::posix_directory_storage(patch_dir.c_str(), &directory, &storage) ||
      keeper->init(*map, storage) != ccmap::Status::kOk || stitcher->attach(*keeper) != ccmap::Status::kOk) {
    std::fprintf(stderr, "loop_experiment: init failed (patch directory %s)\n", patch_dir.c_str());
    return 1;
  }
  // The true path: a square, counter-clockwise, frames every `step` m; odometry integrates the
  // true increments with a scale error (default 3 %) and a heading drift of 0.005 rad per metre.
  std::vector<Pose> truth, believed;
  const int per_side = static_cast<int>(std::lround(side / step));
  Pose t{0.0, 0.0, 0.0}, b{0.0, 0.0, 0.0};
  double travelled = 0.0;
  double keep_time = 0.0, update_time = 0.0, worst_keep = 0.0;
  std::uint32_t worst_writes = 0U;
  ccmap::PatchPose stamp{};
  for (int leg = 0; leg < 4; ++leg) {
    for (int k = 0; k < per_side; ++k) {
      truth.push_back(t);
      believed.push_back(b);
      // Odometry sigmas whose variance grows with distance (a random walk per metre).
      const float sigma_xy = static_cast<float>(0.03 * std::sqrt(travelled));
      const float sigma_yaw = static_cast<float>(0.005 * std::sqrt(travelled));
      stamp = ccmap::PatchPose{static_cast<float>(b.x), static_cast<float>(b.y), static_cast<float>(b.yaw), sigma_xy,
                               sigma_yaw};
      ccmap::PatchMoveReport report{};
      const double t0 = thread_seconds();
      const ccmap::Status moved = stitcher->move_to(*keeper, stamp.x_m, stamp.y_m, stamp, &report);
      const double t1 = thread_seconds();
      const auto points = frame(t, b, 2.5, static_cast<std::uint32_t>(truth.size()));
      const ccmap::Status updated =
          map->update_frame(points.data(), points.size(), ccmap::PointXYZ{stamp.x_m, stamp.y_m, 1.2F}, nullptr);
      const double t2 = thread_seconds();
      if (moved != ccmap::Status::kOk || updated != ccmap::Status::kOk) {
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
      b = Pose{b.x + (1.0 + scale_error) * step * std::cos(b.yaw), b.y + (1.0 + scale_error) * step * std::sin(b.yaw), b.yaw + turn + 0.005 * step};
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
      old_map->init(params) != ccmap::Status::kOk || reader->init(*old_map, storage, &read) != ccmap::Status::kOk) {
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
      "loop: %.0f m square, %zu frames every %.2f m, odometry %.1f %% + 0.005 rad/m, %zu rocks; %u patches written, "
      "%u cells read back for the revisit\n",
      4.0 * side, truth.size(), step, 100.0 * scale_error, g_rocks.size(), keeper->counters().patches_written, read.cells_restored);
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
  // The closing pose as the chain's last node (the rover standing at the start), the window
  // moved off so that its cells are in patches too; then the correction shared and the patches
  // re-stamped, 8 a frame.
  ccmap::PatchMoveReport flush{};
  const ccmap::PatchPose last{static_cast<float>(b.x), static_cast<float>(b.y), static_cast<float>(b.yaw),
                              stamp.sigma_xy_m, stamp.sigma_yaw_rad};
  if (stitcher->move_to(*keeper, last.x_m, last.y_m, last, nullptr) != ccmap::Status::kOk ||
      stitcher->move_to(*keeper, last.x_m + 200.0F, last.y_m, last, &flush) != ccmap::Status::kOk) {
    std::fprintf(stderr, "loop_experiment: the last moves were refused\n");
    return 1;
  }
  const double c0 = thread_seconds();
  const ccmap::Status closed = stitcher->close_loop(0U, static_cast<float>(corrected.x - b.x),
                                                    static_cast<float>(corrected.y - b.y),
                                                    static_cast<float>(corrected.yaw - b.yaw));
  const double close_time = thread_seconds() - c0;
  if (closed != ccmap::Status::kOk) {
    std::fprintf(stderr, "loop_experiment: close_loop refused\n");
    return 1;
  }
  const std::uint32_t marked = stitcher->pending();
  ccmap::StitchReport stitch{};
  double stitch_time = 0.0, worst_stitch = 0.0;
  int stitch_frames = 0;
  std::uint32_t restamped = 0U;
  do {
    const double s0 = thread_seconds();
    stitcher->restamp_step(*keeper, 8U, &stitch);
    const double s1 = thread_seconds() - s0;
    stitch_time += s1;
    worst_stitch = std::fmax(worst_stitch, s1);
    restamped += stitch.restamped;
    ++stitch_frames;
  } while (stitch.remaining > 0U);
  double before = 0.0, after = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const ccmap::ChainNode n = stitcher->chain().node(i);
    before += std::pow(believed[i].x - truth[i].x, 2) + std::pow(believed[i].y - truth[i].y, 2);
    after += std::pow(n.pose.x_m - truth[i].x, 2) + std::pow(n.pose.y_m - truth[i].y, 2);
  }
  std::printf("trajectory RMS position error: before %.3f m, after the chain's share %.3f m\n",
              std::sqrt(before / static_cast<double>(truth.size())),
              std::sqrt(after / static_cast<double>(truth.size())));
  std::printf("stitching: %u patches marked, %u re-stamped (%u failed) in %d frames of 8; close_loop %.3f ms\n", marked,
              restamped, stitcher->restamp_failures(), stitch_frames, 1e3 * close_time);
  // The global map of each layer, stitched and not.
  for (int layer = 0; layer < Map::kLayerCount; ++layer) {
    std::vector<ccmap::tools::GlobalPatch> patches;
    ccmap::tools::PatchDirectoryCounts counts;
    std::string why;
    ccmap::tools::GlobalMapOptions options;
    options.params = params;
    options.normal_variance_threshold = map->normal_variance_threshold(layer);
    ccmap::tools::GlobalRaster stitched, raw;
    bool ok = ccmap::tools::read_patch_directory(patch_dir, layer, &patches, &counts, &why) &&
              ccmap::tools::assemble_global_map(patches, options, &stitched, &why);
    options.apply_corrections = false;
    ok = ok && ccmap::tools::assemble_global_map(patches, options, &raw, &why);
    if (!ok) {
      std::fprintf(stderr, "loop_experiment: the global map of layer %d failed: %s\n", layer, why.c_str());
      return 1;
    }
    const MapScore with = score(stitched, params.max_inclination);
    const MapScore without = score(raw, params.max_inclination);
    std::printf("global map, layer %d (%.2f m, %d patches, %d refused), stitched / not: height RMS %.4f / %.4f m "
                "(%d pixels off the rocks); rocks marked (an obstacle within 0.25 m) %d / %d of %zu, rock to nearest "
                "obstacle median %.2f / %.2f m, obstacle pixels off the rocks %d / %d; steep class agrees with the "
                "terrain's inclination on %.1f / %.1f %% of the pixels\n",
                layer, stitched.cell_width_m, counts.used, counts.refused, with.rms_m, without.rms_m, with.pixels,
                with.rocks_marked, without.rocks_marked, g_rocks.size(), with.rock_median_m, without.rock_median_m,
                with.stray_obstacles, without.stray_obstacles, 100.0 * with.steep_agreement,
                100.0 * without.steep_agreement);
  }
  std::printf(
      "cost per frame (host thread CPU): keeper move %.3f ms mean, %.3f ms worst (%u patch writes), frame update "
      "%.3f ms mean; re-stamping %.3f ms mean, %.3f ms worst per frame of 8 patches\n",
      1e3 * keep_time / static_cast<double>(truth.size()), 1e3 * worst_keep, worst_writes,
      1e3 * update_time / static_cast<double>(truth.size()), 1e3 * stitch_time / stitch_frames, 1e3 * worst_stitch);
  return 0;
}
