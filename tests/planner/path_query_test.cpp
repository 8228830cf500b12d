// The path query (planner/path_query.hpp): its poses against double-precision geometry (std::sin /
// std::cos, the closed-form arc, polyline interpolation), its verdicts against footprint queries
// at independently computed poses (the footprint itself is held to point queries in
// footprint_test.cpp), an analytic approach to a box and to a hole, and its refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <vector>

#include "ccmap/planner/path_query.hpp"
#include "support/flight_cycle.hpp"
#include "support/planner_maps.hpp"

namespace ccmap {
namespace {

using Cadre = Stack<CadreConfig>;
constexpr double kPi = 3.14159265358979323846;

const Cadre& terrain_map() {
  static const std::unique_ptr<Cadre> map =
      test::terrain_stack<CadreConfig>(0.04F, test::precise_lidar_params(0.04F), 4.0, 0.012);
  return *map;
}

TEST(PathQuery, SinCosMatchesDoublePrecision) {
  double worst = 0.0;
  for (int i = -700000; i <= 700000; ++i) {
    const float theta = static_cast<float>(i) * 1e-5F;  // [-7, 7]
    float s = 0.0F, c = 0.0F;
    detail::sin_cos(theta, &s, &c);
    worst = std::max({worst, std::fabs(s - std::sin(double{theta})), std::fabs(c - std::cos(double{theta}))});
  }
  EXPECT_LT(worst, 2e-7) << "sin/cos error over [-7, 7]";
}

TEST(PathQuery, ArcPosesFollowTheCircle) {
  for (const double k : {0.0, 1e-6, 0.3, -0.3, 2.0, -5.0}) {
    const double yaw0 = 0.7, x0 = 1.5, y0 = -2.0;
    const double length = k == 0.0 ? 3.0 : std::min(3.0, 2.0 * kPi / std::fabs(k));
    detail::PathSampler arc;
    ASSERT_EQ(arc.make_arc(PathPose{static_cast<float>(x0), static_cast<float>(y0), static_cast<float>(std::cos(yaw0)),
                                    static_cast<float>(std::sin(yaw0))},
                           static_cast<float>(k), static_cast<float>(length)),
              Status::kOk);
    for (int i = 0; i <= 64; ++i) {
      const double t = length * i / 64.0;
      const PathPose p = arc.pose(static_cast<float>(t));
      // Closed form in double: centre of curvature, or the straight line.
      double ex = x0 + t * std::cos(yaw0), ey = y0 + t * std::sin(yaw0);
      if (k != 0.0) {
        ex = x0 + (std::sin(yaw0 + k * t) - std::sin(yaw0)) / k;
        ey = y0 - (std::cos(yaw0 + k * t) - std::cos(yaw0)) / k;
      }
      EXPECT_NEAR(p.x, ex, 4e-6) << "curvature " << k << ", t " << t;
      EXPECT_NEAR(p.y, ey, 4e-6) << "curvature " << k << ", t " << t;
      EXPECT_NEAR(p.heading_x, std::cos(yaw0 + k * t), 1e-6);
      EXPECT_NEAR(p.heading_y, std::sin(yaw0 + k * t), 1e-6);
    }
  }
}

TEST(PathQuery, PolylinePosesInterpolateTheSegments) {
  const PathPoint pts[] = {{0.0F, 0.0F}, {1.0F, 0.0F}, {1.0F, 0.0F}, {1.0F, 2.0F}, {-1.0F, 2.0F}};
  detail::PathSampler path;
  ASSERT_EQ(path.make_polyline(pts, 5), Status::kOk);
  EXPECT_FLOAT_EQ(path.length(), 5.0F);
  struct Expect {
    float t, x, y, hx, hy;
  };
  const Expect expected[] = {{0.0F, 0.0F, 0.0F, 1.0F, 0.0F},  {0.5F, 0.5F, 0.0F, 1.0F, 0.0F},
                             {1.0F, 1.0F, 0.0F, 0.0F, 1.0F},  // at a vertex: the next segment
                             {2.25F, 1.0F, 1.25F, 0.0F, 1.0F}, {3.0F, 1.0F, 2.0F, -1.0F, 0.0F},
                             {4.5F, -0.5F, 2.0F, -1.0F, 0.0F}, {5.0F, -1.0F, 2.0F, -1.0F, 0.0F},
                             {6.0F, -1.0F, 2.0F, -1.0F, 0.0F}};
  for (const Expect& e : expected) {
    const PathPose p = path.pose(e.t);
    EXPECT_NEAR(p.x, e.x, 1e-6) << "t " << e.t;
    EXPECT_NEAR(p.y, e.y, 1e-6) << "t " << e.t;
    EXPECT_NEAR(p.heading_x, e.hx, 1e-6) << "t " << e.t;
    EXPECT_NEAR(p.heading_y, e.hy, 1e-6) << "t " << e.t;
  }
}

/// The first hazardous and first unknown distances by footprint queries at poses computed in
/// double along the same polyline, every `step` from 0 and at the end.
struct Expected {
  bool hazard = false, unknown = false;
  double hazard_m = 0.0, unknown_m = 0.0;
  std::uint32_t samples = 0;
};
Expected reference_sweep(const Cadre& map, const std::vector<PathPoint>& pts, const PathSweep& sweep) {
  Expected e;
  std::vector<double> cum{0.0};
  for (std::size_t i = 1; i < pts.size(); ++i) cum.push_back(cum.back() + std::hypot(pts[i].x - pts[i - 1].x, pts[i].y - pts[i - 1].y));
  const double length = cum.back();
  std::vector<double> ts;
  for (int i = 0; i * double{sweep.step_m} < length - 1e-3 * sweep.step_m; ++i) ts.push_back(i * double{sweep.step_m});
  ts.push_back(length);
  for (const double t : ts) {
    std::size_t s = 1;
    while (s + 1 < pts.size() && t >= cum[s]) ++s;
    const double dx = pts[s].x - pts[s - 1].x, dy = pts[s].y - pts[s - 1].y, len = std::hypot(dx, dy);
    const double a = t - cum[s - 1];
    const Footprint f{static_cast<float>(pts[s - 1].x + dx / len * a), static_cast<float>(pts[s - 1].y + dy / len * a),
                      static_cast<float>(dx / len), static_cast<float>(dy / len), sweep.length_m, sweep.width_m};
    const FootprintResult r = query_footprint(map, f);
    ++e.samples;
    const CellClass v = footprint_class(r, sweep.max_unknown_share);
    if (!e.hazard && (v == CellClass::kObstacle || v == CellClass::kSteep)) {
      e.hazard = true;
      e.hazard_m = t;
    }
    if (!e.unknown && (r.worst_class == CellClass::kUnknown || r.unknown_share > sweep.max_unknown_share)) {
      e.unknown = true;
      e.unknown_m = t;
    }
    if (e.hazard && e.unknown) break;
  }
  return e;
}

TEST(PathQuery, VerdictsAreThoseOfTheFootprintsAlongThePath) {
  const Cadre& map = terrain_map();
  const PathSweep sweep{0.6F, 0.4F, 0.05F, kDefaultMaxUnknownShare};
  const std::vector<std::vector<PathPoint>> paths = {
      {{-0.5F, -0.35F}, {1.5F, -0.35F}},                    // straight at the box
      {{-0.2F, 0.0F}, {-0.7F, 0.4F}, {-0.7F, 1.4F}},         // into the hole
      {{0.0F, 0.0F}, {1.0F, 1.0F}, {2.4F, 1.1F}},            // to the ramp
      {{0.0F, 0.2F}, {0.5F, 0.2F}},                          // clear
      {{1.0F, -1.9F}, {3.3F, -1.9F}, {3.3F, 0.0F}},          // past the 8 cm window: coarse layers, edge of the map
  };
  for (const auto& pts : paths) {
    const PathResult r = query_path(map, pts.data(), pts.size(), sweep);
    ASSERT_EQ(r.status, Status::kOk);
    const Expected e = reference_sweep(map, pts, sweep);
    SCOPED_TRACE(testing::Message() << "path from (" << pts.front().x << ", " << pts.front().y << "), " << pts.size()
                                    << " points");
    EXPECT_EQ(r.hazard_found, e.hazard);
    EXPECT_EQ(r.unknown_found, e.unknown);
    if (e.hazard) {
      EXPECT_NEAR(r.first_hazard_m, e.hazard_m, 1e-5);
    }
    if (e.unknown) {
      EXPECT_NEAR(r.first_unknown_m, e.unknown_m, 1e-5);
    }
    EXPECT_EQ(r.samples, e.samples);
    EXPECT_GT(r.cells_visited, 0U);
  }
}

/// The per-pose sweep: every pose's footprint in order, as the path query's contract states it
/// (header comment of planner/path_query.hpp), at the poses of the same sampler; stops once both
/// a hazard and an unknown footprint are found. The reference for the grouped sweep.
PathResult per_pose_sweep(const Cadre& map, const detail::PathSampler& path, const PathSweep& sweep) {
  PathResult r{};
  std::uint32_t count = 0U;
  EXPECT_EQ(detail::path_sample_count(path.length(), sweep, &count), Status::kOk);  // the caller checked
  for (std::uint32_t i = 0; i < count && !(r.hazard_found && r.unknown_found); ++i) {
    const float t = detail::path_sample_distance(i, count, sweep.step_m, path.length());
    const PathPose p = path.pose(t);
    const FootprintResult f =
        query_footprint(map, Footprint{p.x, p.y, p.heading_x, p.heading_y, sweep.length_m, sweep.width_m});
    ++r.samples;
    r.checked_m = t;
    if (!r.hazard_found && is_lethal(footprint_class(f, sweep.max_unknown_share))) {
      r.hazard_found = true;
      r.first_hazard_m = t;
      r.hazard_pose = p;
      r.hazard = f;
    }
    if (!r.unknown_found && (f.worst_class == CellClass::kUnknown || f.unknown_share > sweep.max_unknown_share)) {
      r.unknown_found = true;
      r.first_unknown_m = t;
      r.unknown_pose = p;
      r.unknown = f;
    }
  }
  return r;
}

void expect_same_footprint(const FootprintResult& a, const FootprintResult& b) {
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.worst_class, b.worst_class);
  EXPECT_EQ(a.unknown_share, b.unknown_share);
  EXPECT_EQ(a.max_step_m, b.max_step_m);
  EXPECT_EQ(a.worst_layer, b.worst_layer);
  EXPECT_EQ(a.worst_index.x, b.worst_index.x);
  EXPECT_EQ(a.worst_index.y, b.worst_index.y);
}

/// The grouped sweep (one walk over the area a straight run of poses sweeps, then only the poses
/// it flags) answers exactly what the per-pose sweep answers: the same first hazard and first
/// unknown pose, their footprints, the same poses counted, on random straight paths, polylines
/// and arcs over two maps (the test terrain with its box, hole and ramp; the flight cycle's
/// stereo map with its unseen patches), with every unknown-share threshold from 0 to 1 and steps
/// that make groups of 1 to 32 poses and swept areas beyond the footprint limit.
void check_grouped_sweep(const Cadre& map, float lo, float hi, std::uint32_t seed, int paths) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coord(lo, hi);
  std::uniform_real_distribution<float> angle(-3.14159F, 3.14159F);
  const float steps[] = {0.02F, 0.05F, 0.13F, 0.6F};
  const float shares[] = {0.0F, 0.02F, 0.1F, 0.5F, 1.0F};
  const float lengths[] = {0.0F, 0.3F, 1.0F, 2.5F, 5.0F};
  int hazards = 0;
  int unknowns = 0;
  int refused = 0;
  for (int k = 0; k < paths; ++k) {
    const float yaw = angle(rng);
    const PathSweep sweep{k % 3 == 0 ? 0.3F : 0.6F, k % 3 == 0 ? 0.2F : 0.4F, steps[k % 4], shares[(k / 4) % 5]};
    const PathPose start{coord(rng), coord(rng), std::cos(yaw), std::sin(yaw)};
    const float length = lengths[(k / 3) % 5];
    detail::PathSampler sampler;
    PathResult grouped{};
    std::vector<PathPoint> pts;
    if (k % 5 == 4) {  // a polyline of three segments (the body turns at each vertex)
      pts = {{start.x, start.y}, {start.x + 1.5F * start.heading_x, start.y + 1.5F * start.heading_y},
             {start.x + 1.5F * start.heading_x - 0.8F * start.heading_y, start.y + 1.5F * start.heading_y + 0.8F * start.heading_x},
             {coord(rng), coord(rng)}};
      ASSERT_EQ(sampler.make_polyline(pts.data(), pts.size()), Status::kOk);
      grouped = query_path(map, pts.data(), pts.size(), sweep);
    } else {
      const float curvature = k % 7 == 6 ? 0.8F : 0.0F;  // a turning arc: poses judged one by one
      ASSERT_EQ(sampler.make_arc(start, curvature, length), Status::kOk);
      grouped = query_arc(map, start, curvature, length, sweep);
    }
    std::uint32_t count = 0U;
    const Status counted = detail::path_sample_count(sampler.length(), sweep, &count);
    if (counted != Status::kOk) {  // more poses than kMaxPathSamples: refused as a whole
      EXPECT_EQ(grouped.status, counted);
      ++refused;
      continue;
    }
    ASSERT_EQ(grouped.status, Status::kOk);
    const PathResult reference = per_pose_sweep(map, sampler, sweep);
    SCOPED_TRACE(testing::Message() << "path " << k << " from (" << start.x << ", " << start.y << "), step "
                                    << sweep.step_m << ", share " << sweep.max_unknown_share);
    EXPECT_EQ(grouped.samples, reference.samples);
    EXPECT_EQ(grouped.checked_m, reference.checked_m);
    ASSERT_EQ(grouped.hazard_found, reference.hazard_found);
    ASSERT_EQ(grouped.unknown_found, reference.unknown_found);
    if (reference.hazard_found) {
      ++hazards;
      EXPECT_EQ(grouped.first_hazard_m, reference.first_hazard_m);
      EXPECT_EQ(std::memcmp(&grouped.hazard_pose, &reference.hazard_pose, sizeof(PathPose)), 0);
      expect_same_footprint(grouped.hazard, reference.hazard);
    }
    if (reference.unknown_found) {
      ++unknowns;
      EXPECT_EQ(grouped.first_unknown_m, reference.first_unknown_m);
      expect_same_footprint(grouped.unknown, reference.unknown);
    }
  }
  // The paths reach both verdicts often, and clear ground too: the comparison is not vacuous.
  EXPECT_LT(refused, paths / 10);
  EXPECT_GT(hazards, paths / 10);
  EXPECT_GT(unknowns, paths / 10);
  EXPECT_LT(hazards, paths);
}

TEST(PathQuery, GroupedSweepAnswersAsEveryPoseOnTheTestTerrain) {
  check_grouped_sweep(terrain_map(), -3.0F, 4.5F, 7U, 150);
}

TEST(PathQuery, GroupedSweepAnswersAsEveryPoseOnTheFlightCycleMap) {
  // The flight cycle's map after two quarter-size frames: stereo holes, rocks, unseen ground.
  const auto map = std::make_unique<Cadre>();
  ASSERT_EQ(map->init(default_stack_params(0.04F)), Status::kOk);
  for (int k = 0; k < 2; ++k) {
    const test::CyclePose pose = test::cycle_pose(k);
    const test::CadreFrame frame = test::cycle_frame(k, 425, 325);
    ASSERT_EQ(map->move_to(pose.x, pose.y), Status::kOk);
    ASSERT_EQ(map->update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, nullptr),
              Status::kOk);
  }
  check_grouped_sweep(*map, -0.5F, 3.0F, 11U, 150);
}

TEST(PathQuery, FindsTheBoxWhereTheBodyReachesItAndTheUnknownWhereItEnters) {
  const Cadre& map = terrain_map();
  const PathSweep sweep{0.6F, 0.4F, 0.02F, kDefaultMaxUnknownShare};
  // The body's front edge is 0.3 m ahead of its centre; the box starts at x = 0.6, in the 8 cm
  // cell [0.56, 0.64] that the constant layer's class comes from: the first hazard lies between
  // the front reaching 0.56 and reaching 0.6 (+ one step).
  const PathPoint at_box[] = {{-0.5F, -0.35F}, {1.5F, -0.35F}};
  const PathResult box = query_path(map, at_box, 2, sweep);
  ASSERT_EQ(box.status, Status::kOk);
  ASSERT_TRUE(box.hazard_found);
  EXPECT_GE(box.first_hazard_m, 0.56F - 0.3F + 0.5F - 0.02F);
  EXPECT_LE(box.first_hazard_m, 0.6F - 0.3F + 0.5F + 0.02F);
  EXPECT_EQ(box.hazard.worst_class, CellClass::kObstacle);
  EXPECT_NEAR(box.hazard_pose.x, -0.5F + box.first_hazard_m, 1e-5);
  EXPECT_NEAR(box.hazard_pose.y, -0.35F, 1e-6);
  EXPECT_FALSE(box.unknown_found) << "nothing unknown before and on the box";
  // Towards the end of the observed ground (x = 4, the 16 cm layer's own points): the first
  // unknown footprint is where more than 10 % of the body (0.06 m of its length) lies beyond,
  // the front 0.3 m ahead of the centre: t = 4.06 - 0.3 - 3.0, give or take a 16 cm cell.
  const PathPoint off[] = {{3.0F, 0.5F}, {4.5F, 0.5F}};
  const PathResult edge = query_path(map, off, 2, sweep);
  ASSERT_EQ(edge.status, Status::kOk);
  ASSERT_TRUE(edge.unknown_found);
  EXPECT_GE(edge.first_unknown_m, 0.76F - 0.16F);
  EXPECT_LE(edge.first_unknown_m, 0.76F + 0.16F);
  EXPECT_GT(edge.unknown.unknown_share, kDefaultMaxUnknownShare);
  EXPECT_EQ(edge.unknown_pose.heading_x, 1.0F);
  EXPECT_NEAR(edge.unknown_pose.x, 3.0F + edge.first_unknown_m, 1e-5);
  // An arc of the same start that turns away from the box (left, 1 m radius) stays clear longer.
  const PathResult arc = query_arc(map, PathPose{-0.5F, -0.35F, 1.0F, 0.0F}, 1.0F, 1.0F, sweep);
  ASSERT_EQ(arc.status, Status::kOk);
  EXPECT_FALSE(arc.hazard_found && arc.first_hazard_m <= box.first_hazard_m);
  EXPECT_EQ(arc.samples, 51U);
  EXPECT_NEAR(arc.checked_m, 1.0F, 1e-6);
}

TEST(PathQuery, RefusesBadInputWithAStatus) {
  const Cadre& map = terrain_map();
  const PathSweep good{0.6F, 0.4F, 0.05F, 0.1F};
  const PathPoint pts[] = {{0.0F, 0.0F}, {1.0F, 0.0F}};
  const PathPoint same[] = {{0.0F, 0.0F}, {0.0F, 0.0F}};
  const PathPoint nan_pt[] = {{0.0F, 0.0F}, {std::nanf(""), 0.0F}};
  const PathPoint far[] = {{0.0F, 0.0F}, {2e5F, 0.0F}};
  EXPECT_EQ(query_path(map, nullptr, 2, good).status, Status::kInvalidArgument);
  EXPECT_EQ(query_path(map, pts, 1, good).status, Status::kInvalidArgument);
  EXPECT_EQ(query_path(map, pts, kMaxPathVertices + 1, good).status, Status::kInvalidArgument);
  EXPECT_EQ(query_path(map, same, 2, good).status, Status::kInvalidArgument);
  EXPECT_EQ(query_path(map, nan_pt, 2, good).status, Status::kNonFiniteInput);
  EXPECT_EQ(query_path(map, far, 2, good).status, Status::kOutOfRange);
  EXPECT_EQ(query_path(map, pts, 2, PathSweep{0.6F, 0.4F, 0.0F, 0.1F}).status, Status::kInvalidArgument);
  EXPECT_EQ(query_path(map, pts, 2, PathSweep{0.6F, 0.0F, 0.05F, 0.1F}).status, Status::kInvalidArgument);
  EXPECT_EQ(query_path(map, pts, 2, PathSweep{0.6F, 0.4F, 0.05F, 1.5F}).status, Status::kInvalidArgument);
  EXPECT_EQ(query_path(map, pts, 2, PathSweep{0.6F, 0.4F, std::nanf(""), 0.1F}).status, Status::kNonFiniteInput);
  // 256 poses at most: 1 m every 4 mm is 251 poses, every 3 mm 334.
  EXPECT_EQ(query_path(map, pts, 2, PathSweep{0.6F, 0.4F, 0.004F, 0.1F}).status, Status::kOk);
  EXPECT_EQ(query_path(map, pts, 2, PathSweep{0.6F, 0.4F, 0.003F, 0.1F}).status, Status::kOutOfRange);
  // A body beyond the footprint limit.
  EXPECT_EQ(query_path(map, pts, 2, PathSweep{3.0F, 3.0F, 0.05F, 0.1F}).status, Status::kOutOfRange);
  const PathPose start{0.0F, 0.0F, 1.0F, 0.0F};
  EXPECT_EQ(query_arc(map, start, 1.0F, 7.0F, good).status, Status::kOutOfRange) << "more than a full turn";
  EXPECT_EQ(query_arc(map, start, 1.0F, -1.0F, good).status, Status::kInvalidArgument);
  EXPECT_EQ(query_arc(map, PathPose{0.0F, 0.0F, 0.0F, 0.0F}, 1.0F, 1.0F, good).status, Status::kInvalidArgument);
  EXPECT_EQ(query_arc(map, start, INFINITY, 1.0F, good).status, Status::kNonFiniteInput);
  const PathResult zero = query_arc(map, start, 0.0F, 0.0F, good);
  EXPECT_EQ(zero.status, Status::kOk);
  EXPECT_EQ(zero.samples, 1U) << "a path of length 0 is its start pose";
  const PathResult refused = query_path(map, nullptr, 2, good);
  EXPECT_FALSE(refused.hazard_found);
  EXPECT_EQ(refused.samples, 0U);
  EXPECT_EQ(refused.hazard.worst_layer, -1);
  const auto fresh = std::make_unique<Cadre>();
  EXPECT_EQ(query_path(*fresh, pts, 2, good).status, Status::kNotInitialised);
  EXPECT_EQ(query_arc(*fresh, start, 0.0F, 1.0F, good).status, Status::kNotInitialised);
}

}  // namespace
}  // namespace ccmap
