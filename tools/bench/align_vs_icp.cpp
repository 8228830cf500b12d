// Covariance alignment (include/ccmap/global/coarse_alignment.hpp) against PCL's ICP, GICP and
// NDT on the same patch pairs of real terrain (../shared/data): a 3 x 3 m frame with 5 mm noise,
// moved by a random rigid motion (0.5-1 m, 5-10 deg), aligned against a 4 x 4 m map (the Mars
// DTM at 1/20: 3.4 x 4 m, its width) from the identity. Per method: success rate (every corner
// of the frame within 5 cm of where the true motion puts it), the median and worst error of the
// successes, the median time per alignment. Run it pinned to one core:
//   taskset -c 1 build/host-release/tools/bench/ccmap_align_vs_icp --draws 20
// Host tool (std library, PCL): built only when PCL is installed (tools/install-deps pcl).
//
// What is timed. ccmap: the frame's own map (a Stack, its thresholds calibrated once, reset and
// fed the frame's points) and the alignment: align_frame (the search on the frame's map, the
// registration on its points: row "ccmap") and align (the registration on its cells: row
// "cells"); the map it aligns against exists already (the rover's), as does PCL's target
// cloud. After the table: ccmap's errors on the draws each PCL method aligned. PCL: one
// align() from the identity, the target's k-d tree built once outside the timing for ICP and
// GICP (setSearchMethodTarget, no recompute); GICP computes its covariances inside align().
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/ndt.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "ccmap/global/coarse_alignment.hpp"
#include "support/global_configs.hpp"
#include "support/terrain_data.hpp"

#ifndef CCMAP_DEFAULT_DATA_DIR
#define CCMAP_DEFAULT_DATA_DIR "../shared/data"
#endif

namespace {

using ccmap::PointXYZ;

using BenchConfig = ccmap::test::ThreeCcmConfig;
using Map = ccmap::Stack<BenchConfig>;

struct P3 {
  double x, y, z;
};
/// A rigid motion about (cx, cy): p' = R(yaw) (p - c) + c + (dx, dy, dz).
struct Motion {
  double cx, cy, dx, dy, dz, yaw;
  [[nodiscard]] P3 apply(const P3& p) const {
    const double c = std::cos(yaw), s = std::sin(yaw);
    return P3{c * (p.x - cx) - s * (p.y - cy) + cx + dx, s * (p.x - cx) + c * (p.y - cy) + cy + dy, p.z + dz};
  }
  [[nodiscard]] P3 inverse(const P3& p) const {
    const double c = std::cos(yaw), s = std::sin(yaw);
    const double x = p.x - cx - dx, y = p.y - cy - dy;
    return P3{c * x + s * y + cx, -s * x + c * y + cy, p.z - dz};
  }
};

struct Scene {
  std::string name;
  std::vector<P3> map;    ///< the 4 x 4 m map's points
  std::vector<P3> frame;  ///< the 3 x 3 m frame's points (ground truth frame), noise added per draw
  double fx, fy, half;    ///< the frame's centre and half side
  double map_cx, map_cy;
};

/// CPU time of this thread (s): the machine is shared, wall time would count the others.
double thread_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

/// Largest horizontal distance, over the frame's corners, between the estimate and the truth;
/// est maps frame points to map points as a 4 x 4 matrix.
double corner_error(const Eigen::Matrix4d& est, const Motion& truth, const Scene& s) {
  double worst = 0.0;
  for (int i = 0; i < 4; ++i) {
    const P3 ground{s.fx + ((i & 1) != 0 ? s.half : -s.half), s.fy + ((i & 2) != 0 ? s.half : -s.half), 0.0};
    const P3 q = truth.inverse(ground);  // where the moved frame holds that ground point
    const Eigen::Vector4d e = est * Eigen::Vector4d(q.x, q.y, q.z, 1.0);
    worst = std::max(worst, std::hypot(e.x() - ground.x, e.y() - ground.y));
  }
  return worst;
}

struct Tally {
  explicit Tally(const char* name) : method(name) {}
  std::string method;
  int success = 0, draws = 0;
  std::vector<double> errors, times;
  std::vector<double> every;  ///< every draw's error, failures included (1e9 when nothing came back)
  void add(double error, double time) {
    ++draws;
    every.push_back(error);
    times.push_back(time);
    if (error < 0.05) {
      ++success;
      errors.push_back(error);
    }
  }
};

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

void print(const Scene& s, const Tally& t) {
  const double worst = t.errors.empty() ? std::nan("") : *std::max_element(t.errors.begin(), t.errors.end());
  std::printf("%-10s %-8s success %3d/%-3d  error median %7.2f mm  worst %7.2f mm  time median %8.2f ms\n",
              s.name.c_str(), t.method.c_str(), t.success, t.draws, 1e3 * median(t.errors), 1e3 * worst,
              1e3 * median(t.times));
}

pcl::PointCloud<pcl::PointXYZ>::Ptr cloud_of(const std::vector<P3>& points) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr c(new pcl::PointCloud<pcl::PointXYZ>);
  c->reserve(points.size());
  for (const P3& p : points)
    c->push_back(pcl::PointXYZ(static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)));
  return c;
}

/// The stacks' parameters, their normal-variance thresholds calibrated once (init calibrates
/// a threshold given as 0, about 2 ms: a rover does that once at boot, not per frame), so
/// that the frame's map is built as a running rover resets and fills it.
const ccmap::StackParams& stack_params() {
  static const ccmap::StackParams params = [] {
    ccmap::StackParams p = ccmap::default_stack_params(0.04F);
    p.free_space_rays = 0.0F;  // no sensor rays here: the points are a survey, not a camera frame
    static Map calibrating;
    if (calibrating.init(p) == ccmap::Status::kOk) {
      for (int layer = 0; layer < Map::kLayerCount; ++layer) {
        p.normal_variance_threshold[static_cast<std::size_t>(layer)] = calibrating.normal_variance_threshold(layer);
      }
    }
    return p;
  }();
  return params;
}

bool build_map(Map& map, const std::vector<P3>& points, double cx, double cy) {
  if (map.init(stack_params()) != ccmap::Status::kOk ||
      map.move_to(static_cast<float>(cx), static_cast<float>(cy)) != ccmap::Status::kOk) {
    return false;
  }
  std::vector<PointXYZ> pts;
  pts.reserve(points.size());
  for (const P3& p : points)
    pts.push_back(PointXYZ{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
  return map.update_frame(pts.data(), pts.size(), PointXYZ{static_cast<float>(cx), static_cast<float>(cy), 1.5F},
                          nullptr) == ccmap::Status::kOk;
}

struct Options {
  int draws = 20;
  std::uint32_t seed = 1U;
  bool verbose = false;
  bool pcl = true;  ///< --pcl 0: ccmap only
  float origin_z = 1.5F;
  ccmap::RegistrationParams registration = ccmap::default_registration_params();
  /// align_frame's: every point of the frame (about 5,600 on the scan, 14,400 on the DTM).
  ccmap::RegistrationParams point_registration = [] {
    ccmap::RegistrationParams p = ccmap::default_registration_params();
    p.max_points = 16384U;
    return p;
  }();
  ccmap::CoarseSearchParams search = ccmap::default_coarse_search_params();
};

void run(const Scene& s, const Options& o) {
  const int draws = o.draws;
  const std::uint32_t seed = o.seed;
  static Map ours;
  static Map theirs;
  static ccmap::CoarseAligner<BenchConfig> aligner;
  if (!build_map(ours, s.map, s.map_cx, s.map_cy)) {
    std::printf("%s: map refused\n", s.name.c_str());
    return;
  }
  const auto target = cloud_of(s.map);
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  tree->setInputCloud(target);
  Tally cov("ccmap"), cells("cells"), icp_t("ICP"), gicp_t("GICP"), ndt_t("NDT");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.005);
  for (int d = 0; d < draws; ++d) {
    const double r = 0.5 + 0.5 * u(rng);
    const double dir = 2.0 * M_PI * u(rng);
    const double yaw = (u(rng) < 0.5 ? -1.0 : 1.0) * (5.0 + 5.0 * u(rng)) * M_PI / 180.0;
    const Motion truth{s.fx, s.fy, r * std::cos(dir), r * std::sin(dir), 0.0, yaw};
    std::vector<P3> moved;
    moved.reserve(s.frame.size());
    for (const P3& p : s.frame) {
      const P3 q = truth.inverse(p);
      moved.push_back(P3{q.x + noise(rng), q.y + noise(rng), q.z + noise(rng)});
    }
    // ccmap: the frame's map, then the coarse-to-fine alignment; its registration on the frame's
    // points (align_frame, "ccmap") or on their map's cells (align, "ccmap cells").
    static std::vector<PointXYZ> points;
    points.clear();
    for (const P3& p : moved) {
      points.push_back(PointXYZ{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
    }
    for (const bool on_points : {true, false}) {
      const double t0 = thread_seconds();
      const bool built = build_map(theirs, moved, s.fx, s.fy);
      const double t_built = thread_seconds();
      const ccmap::MapOffset identity{0.0F, 0.0F, 0.0F};
      const ccmap::PointXYZ origin{static_cast<float>(s.fx), static_cast<float>(s.fy), o.origin_z};
      const ccmap::AlignmentResult a =
          on_points ? aligner.align_frame(ours, theirs, points.data(), points.size(), origin, identity,
                                          o.point_registration, o.search, nullptr)
                    : aligner.align(ours, theirs, identity, o.registration, o.search, nullptr);
      const double t = thread_seconds() - t0;
      double error = 1e9;
      if (built && a.correction.status == ccmap::Status::kOk) {
        const double c = std::cos(a.correction.dyaw), sn = std::sin(a.correction.dyaw);
        Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
        m(0, 0) = c;
        m(0, 1) = -sn;
        m(1, 0) = sn;
        m(1, 1) = c;
        m(0, 3) = a.centre_x_m - (c * a.centre_x_m - sn * a.centre_y_m) + a.correction.dx;
        m(1, 3) = a.centre_y_m - (sn * a.centre_x_m + c * a.centre_y_m) + a.correction.dy;
        m(2, 3) = a.correction.dz;
        error = corner_error(m, truth, s);
      }
      (on_points ? cov : cells).add(error, t);
      if (o.verbose) {
        std::printf(
            "  draw %d: offset %.2f m %.1f deg: %s %s observable %d%d%d%d error %.1f mm sigma x %.1f mm yaw %.2f "
            "mrad; %u iterations; build %.2f ms, align %.2f ms\n",
            d, r, yaw * 180.0 / M_PI, on_points ? "ccmap" : "ccmap cells", ccmap::to_string(a.correction.status),
            a.correction.observable[0], a.correction.observable[1], a.correction.observable[2],
            a.correction.observable[3], 1e3 * error, 1e3 * a.correction.sigma_dx, 1e3 * a.correction.sigma_dyaw, a.correction.iterations,
            1e3 * (t_built - t0), 1e3 * (thread_seconds() - t_built));
      }
    }
    if (!o.pcl) {
      continue;
    }
    const auto source = cloud_of(moved);
    pcl::PointCloud<pcl::PointXYZ> out;
    auto timed = [&](auto& reg, Tally& tally) {
      const double t0 = thread_seconds();
      reg.setInputSource(source);
      reg.align(out);
      const double t = thread_seconds() - t0;
      tally.add(reg.hasConverged() ? corner_error(reg.getFinalTransformation().template cast<double>(), truth, s) : 1e9,
                t);
    };
    {
      pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp;
      icp.setInputTarget(target);
      icp.setSearchMethodTarget(tree, true);
      icp.setMaxCorrespondenceDistance(1.0);
      icp.setMaximumIterations(50);
      icp.setTransformationEpsilon(1e-8);
      timed(icp, icp_t);
    }
    {
      pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
      gicp.setInputTarget(target);
      gicp.setSearchMethodTarget(tree, true);
      gicp.setMaxCorrespondenceDistance(1.0);
      gicp.setMaximumIterations(50);
      timed(gicp, gicp_t);
    }
    {
      pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ> ndt;
      ndt.setResolution(0.5F);
      ndt.setStepSize(0.1);
      ndt.setTransformationEpsilon(0.001);
      ndt.setMaximumIterations(50);
      ndt.setInputTarget(target);
      timed(ndt, ndt_t);
    }
  }
  for (const Tally* t : {&cov, &cells, &icp_t, &gicp_t, &ndt_t}) {
    if (t->draws > 0) {
      print(s, *t);
    }
  }
  // The same pairs: ccmap's errors on the draws a PCL method aligned (success rates differ, and a
  // median over different draws compares different pairs).
  for (const Tally* t : {&icp_t, &gicp_t, &ndt_t}) {
    if (t->success == 0) {
      continue;
    }
    std::vector<double> pcl_errors, ours_there;
    for (std::size_t k = 0; k < t->every.size() && k < cov.every.size(); ++k) {
      if (t->every[k] < 0.05) {
        pcl_errors.push_back(t->every[k]);
        ours_there.push_back(cov.every[k]);
      }
    }
    const double worst_theirs = *std::max_element(pcl_errors.begin(), pcl_errors.end());
    const double worst_ours = *std::max_element(ours_there.begin(), ours_there.end());
    std::printf("%-10s on the %zu draws %s aligned: %s median %.2f mm worst %.2f mm, ccmap median %.2f mm worst %.2f mm\n",
                s.name.c_str(), pcl_errors.size(), t->method.c_str(), t->method.c_str(), 1e3 * median(pcl_errors),
                1e3 * worst_theirs, 1e3 * median(ours_there), 1e3 * worst_ours);
  }
}

bool lone_star(const std::string& dir, Scene* s) {
  std::vector<double> xyz;
  if (!ccmap::test::load_xyz_centred(ccmap::test::lone_star_crop_file(dir), &xyz)) return false;
  s->name = "lone_star";
  s->map_cx = 0.0;
  s->map_cy = 0.0;
  s->fx = 0.3;
  s->fy = -0.2;
  s->half = 1.5;
  for (std::size_t i = 0; i < xyz.size(); i += 3U) {
    const P3 p{xyz[i], xyz[i + 1U], xyz[i + 2U]};
    if (std::fabs(p.x) <= 2.0 && std::fabs(p.y) <= 2.0) s->map.push_back(p);
    if (std::fabs(p.x - s->fx) <= s->half && std::fabs(p.y - s->fy) <= s->half) s->frame.push_back(p);
  }
  return true;
}

bool mars(const std::string& dir, Scene* s) {
  static ccmap::test::Dtm dtm;
  if (!ccmap::test::load_dtm(ccmap::test::mars_dtm_file(dir), 1.0F / 20.0F, &dtm)) return false;
  s->name = "mars_1/20";
  s->map_cx = 0.5 * dtm.width();
  s->map_cy = 0.5 * dtm.height();
  s->fx = s->map_cx + 0.1;
  s->fy = s->map_cy - 0.2;
  s->half = 1.5;
  std::mt19937 rng(5U);
  std::uniform_real_distribution<double> jitter(-0.0125, 0.0125);
  for (double y = s->map_cy - 2.0; y <= s->map_cy + 2.0; y += 0.025) {
    for (double x = s->map_cx - 1.7; x <= s->map_cx + 1.7; x += 0.025) {
      const double px = x + jitter(rng), py = y + jitter(rng);
      const P3 p{px, py, dtm.at(static_cast<float>(px), static_cast<float>(py))};
      s->map.push_back(p);
      if (std::fabs(px - s->fx) <= s->half && std::fabs(py - s->fy) <= s->half) s->frame.push_back(p);
    }
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string dir = ccmap::test::terrain_data_dir(CCMAP_DEFAULT_DATA_DIR);
  Options o;
  // The search box: the largest offsets drawn (1 m, 10 deg) with a margin.
  o.search.range_xy_m = 1.2F;
  o.search.range_yaw_rad = 0.21F;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    const char* v = argv[i + 1];
    if (flag == "--data") dir = v;
    if (flag == "--draws") o.draws = std::max(1, std::atoi(v));
    if (flag == "--seed") o.seed = static_cast<std::uint32_t>(std::atoi(v));
    if (flag == "--range-m") o.search.range_xy_m = static_cast<float>(std::atof(v));
    if (flag == "--range-deg") o.search.range_yaw_rad = static_cast<float>(std::atof(v) * M_PI / 180.0);
    if (flag == "--iterations") o.registration.max_iterations = static_cast<std::uint32_t>(std::atoi(v));
    if (flag == "--verbose") o.verbose = std::atoi(v) != 0;
    if (flag == "--pcl") o.pcl = std::atoi(v) != 0;
    if (flag == "--origin-z") o.origin_z = static_cast<float>(std::atof(v));
    if (flag == "--frame-iterations") o.point_registration.max_iterations = static_cast<std::uint32_t>(std::atoi(v));
    if (flag == "--frame-robust") o.point_registration.robust_sigmas = static_cast<float>(std::atof(v));
    if (flag == "--frame-model-var") o.point_registration.model_variance_m2 = static_cast<float>(std::atof(v));
    if (flag == "--frame-convergence") o.point_registration.convergence_m = static_cast<float>(std::atof(v));
    if (flag == "--frame-points") o.point_registration.max_points = static_cast<std::uint32_t>(std::atoi(v));
    if (flag == "--points") o.registration.max_points = static_cast<std::uint32_t>(std::atoi(v));
  }
  std::printf("ccmap: search +-%.2f m, +-%.1f deg; registration %u points, %u iterations\n", o.search.range_xy_m,
              o.search.range_yaw_rad * 180.0 / M_PI, o.registration.max_points, o.registration.max_iterations);
  int ran = 0;
  for (auto* load : {&lone_star, &mars}) {
    Scene s;
    if (!load(dir, &s)) {
      std::printf("real-data file under %s is not available (--data DIR or CCMAP_DATA_DIR): skipped\n", dir.c_str());
      continue;
    }
    std::printf("%s: map %zu points, frame %zu points, %d draws, offsets 0.5-1 m, 5-10 deg\n", s.name.c_str(),
                s.map.size(), s.frame.size(), o.draws);
    run(s, o);
    ++ran;
  }
  return ran > 0 ? 0 : 1;
}
