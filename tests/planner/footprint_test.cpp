// The footprint query (planner/footprint.hpp) against independent references:
//  - brute force: every point query (Stack::query) at dense samples inside the rectangle (a grid,
//    the sides every 0.5 mm, the corners). Each sample must fall in a piece of the walk whose
//    answer is the sample's answer (layer, cell, class, slopes, normal variance; height within
//    float rounding), every piece larger than the samples' resolution must hold a sample, and
//    the aggregates must agree with the samples' (exact where the extreme part is sampled);
//  - analytic cases: a plane (its exact height range over the rectangle), a box (obstacle on it,
//    traversable beside it), a half-observed rectangle (unknown share 1/2);
//  - refusals and the documented bound on cells visited, on an adversarial map.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>
#include <tuple>
#include <vector>

#include "ccmap/planner/footprint.hpp"
#include "support/planner_maps.hpp"

namespace ccmap {
namespace {

using Cadre = Stack<CadreConfig>;

const Cadre& terrain_map() {
  static const std::unique_ptr<Cadre> map = [] {
    return test::terrain_stack<CadreConfig>(0.04F, test::precise_lidar_params(0.04F), 4.0, 0.012);
  }();
  return *map;
}

/// A piece of the walk as the test keeps it.
struct KeptPiece {
  std::vector<double> x, y;  // map frame polygon (the whole square when not clipped)
  double area;
  double leaf_width;  // of the leaf cell the piece lies in
  detail::RegionAnswer answer;
  // For contains(): each edge i (vertex i to i + 1) as its vector and length, and the polygon's
  // bounding box with how far, in tolerances, an accepted point may lie outside the polygon
  // (seal_piece).
  std::vector<double> ex, ey, len;
  double min_x = 0.0, min_y = 0.0, max_x = 0.0, max_y = 0.0;
  double reach = std::numeric_limits<double>::infinity();
};

/// Fills the piece's edges and bounding box. An accepted point of a convex polygon lies within
/// the polygon with each edge pushed out by the tolerance, whose corners are the vertices moved
/// by tol / sin(theta / 2) (theta: the interior angle there): reach = 1 / min sin(theta / 2), so
/// contains() may reject outside the box widened by 2 tol reach (twice: the rounding of the edge
/// tests) without changing an answer. Reach stays infinite (no box test) unless every vertex
/// turns left or straight on (a convex CCW polygon) and no angle is below ~0.1 degree.
void seal_piece(KeptPiece& k) {
  const std::size_t n = k.x.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t j = (i + 1) % n;
    k.ex.push_back(k.x[j] - k.x[i]);
    k.ey.push_back(k.y[j] - k.y[i]);
    k.len.push_back(std::hypot(k.ex.back(), k.ey.back()));
  }
  if (n == 0) return;
  k.min_x = *std::min_element(k.x.begin(), k.x.end());
  k.max_x = *std::max_element(k.x.begin(), k.x.end());
  k.min_y = *std::min_element(k.y.begin(), k.y.end());
  k.max_y = *std::max_element(k.y.begin(), k.y.end());
  std::vector<std::size_t> edges;  // the edges contains() tests (not of length 0)
  for (std::size_t i = 0; i < n; ++i) {
    if (k.len[i] != 0.0) edges.push_back(i);
  }
  if (edges.size() < 3) return;
  double min_half_sin = 1.0;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const std::size_t a = edges[e], b = edges[(e + 1) % edges.size()];
    const double cross = (k.ex[a] * k.ey[b] - k.ey[a] * k.ex[b]) / (k.len[a] * k.len[b]);
    const double dot = (k.ex[a] * k.ex[b] + k.ey[a] * k.ey[b]) / (k.len[a] * k.len[b]);
    if (cross < -1e-9) return;  // turns right: not a convex CCW polygon
    // sin(theta / 2) = cos(phi / 2) = sqrt((1 + cos phi) / 2), phi the turn from edge a to b.
    min_half_sin = std::min(min_half_sin, std::sqrt(std::max(0.0, 0.5 * (1.0 + dot))));
  }
  if (min_half_sin > 1e-3) k.reach = 1.0 / min_half_sin;
}

/// Every piece of the walk (no sliver dropped when min_width is 0).
template <typename Config>
std::vector<KeptPiece> walk_pieces(const Stack<Config>& stack, const detail::OrientedRect& rect, float min_width) {
  std::vector<KeptPiece> pieces;
  auto sink = [&](const detail::RegionPiece& p, const detail::RegionAnswer& a) {
    KeptPiece k;
    if (p.polygon != nullptr) {
      for (int i = 0; i < p.polygon->count; ++i) {
        k.x.push_back(double{rect.cx} + p.polygon->x[i]);
        k.y.push_back(double{rect.cy} + p.polygon->y[i]);
      }
    } else {
      const double cx = double{rect.cx} + p.dx, cy = double{rect.cy} + p.dy, h = p.half;
      k.x = {cx - h, cx + h, cx + h, cx - h};
      k.y = {cy - h, cy - h, cy + h, cy + h};
    }
    k.area = p.area;
    k.leaf_width = 2.0 * p.half;
    k.answer = a;
    seal_piece(k);
    pieces.push_back(k);
  };
  const detail::QueryView<Config> view = detail::PlannerAccess<Config>::view(stack);
  detail::RegionWalk<Config> walk(view, min_width);
  walk.run(rect, sink);
  return pieces;
}

/// Point in convex CCW polygon, with a tolerance (m) on each edge.
bool contains(const KeptPiece& k, double x, double y, double tol) {
  if (k.reach < std::numeric_limits<double>::infinity()) {
    const double margin = 2.0 * tol * k.reach;
    if (x < k.min_x - margin || x > k.max_x + margin || y < k.min_y - margin || y > k.max_y + margin) return false;
  }
  const std::size_t n = k.x.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (k.len[i] == 0.0) continue;
    if ((k.ex[i] * (y - k.y[i]) - k.ey[i] * (x - k.x[i])) / k.len[i] < -tol) return false;
  }
  return true;
}

/// The map cell of the answering layer that holds (x, y) (double floor).
CellIndex cell_of(double x, double y, double w) {
  return CellIndex{static_cast<std::int32_t>(std::floor(x / w)), static_cast<std::int32_t>(std::floor(y / w))};
}

struct Case {
  double cx, cy, yaw_deg, L, W;
};

/// Reference aggregates of the samples.
struct Reference {
  double unknown_share = 0.0;
  int worst_rank = 0;
  double max_inclination = 0.0, max_normal_variance = 0.0, min_h = 1e30, max_h = -1e30;
  bool known = false;
};

Reference reference_of(const std::vector<test::RectSample>& grid_samples) {
  Reference r;
  std::size_t unknown = 0;
  for (const test::RectSample& s : grid_samples) {
    if (s.q.status != Status::kOk) {
      ++unknown;
      continue;
    }
    r.known = true;
    r.worst_rank = std::max(r.worst_rank, detail::hazard_rank(s.q.cell_class));
    r.max_inclination = std::max(r.max_inclination, double{s.q.inclination});
    r.max_normal_variance = std::max(r.max_normal_variance, double{s.q.normal_variance});
    r.min_h = std::min(r.min_h, double{s.q.height_m});
    r.max_h = std::max(r.max_h, double{s.q.height_m});
  }
  r.unknown_share = grid_samples.empty() ? 1.0 : static_cast<double>(unknown) / static_cast<double>(grid_samples.size());
  return r;
}

void check_against_point_queries(const Cadre& map, const Case& c) {
  SCOPED_TRACE(testing::Message() << "footprint at (" << c.cx << ", " << c.cy << "), yaw " << c.yaw_deg << " deg, "
                                  << c.L << " x " << c.W << " m");
  const double yaw = c.yaw_deg * 3.14159265358979323846 / 180.0;
  const Footprint fp{static_cast<float>(c.cx), static_cast<float>(c.cy), static_cast<float>(std::cos(yaw)),
                     static_cast<float>(std::sin(yaw)), static_cast<float>(c.L), static_cast<float>(c.W)};
  detail::OrientedRect rect{};
  ASSERT_EQ(detail::make_footprint_rect(fp, 0.04F, kMaxFootprintCells, &rect), Status::kOk);
  const std::vector<KeptPiece> pieces = walk_pieces(map, rect, 0.0F);
  ASSERT_FALSE(pieces.empty());

  // Partition: the pieces' areas add up to the rectangle's.
  double area = 0.0;
  for (const KeptPiece& k : pieces) area += k.area;
  EXPECT_NEAR(area, c.L * c.W, 1e-4 * c.L * c.W) << "the pieces do not tile the rectangle";

  const double ux = rect.ux, uy = rect.uy;
  const double edge = 0.0005;
  const std::vector<test::RectSample> samples =
      test::rect_samples(map, rect.cx, rect.cy, ux, uy, c.L, c.W, 0.007, edge, 1e-5, 0.04, 2e-5);
  std::set<std::tuple<int, int, int>> sampled_cells;
  int unmatched = 0, wrong = 0;
  for (const test::RectSample& s : samples) {
    // The piece that holds the sample (pieces overlap only on shared edges, which samples avoid).
    const KeptPiece* holder = nullptr;
    for (const KeptPiece& k : pieces) {
      if (contains(k, s.x, s.y, 1e-7)) {
        holder = &k;
        break;
      }
    }
    if (holder == nullptr) {
      if (unmatched++ == 0) ADD_FAILURE() << "sample (" << s.x << ", " << s.y << ") lies in no piece";
      continue;
    }
    const detail::RegionAnswer& a = holder->answer;
    const bool known = s.q.status == Status::kOk;
    const CellIndex in_layer = known ? cell_of(s.x, s.y, map.layer_cell_width(s.q.layer)) : CellIndex{0, 0};
    const bool same = known == a.known && (!known || (a.layer == s.q.layer && a.index == in_layer &&
                                                      a.cell_class == s.q.cell_class && a.slope_x == s.q.slope_x &&
                                                      a.slope_y == s.q.slope_y && a.normal_variance == s.q.normal_variance &&
                                                      std::fabs(detail::answer_height(a, rect.cx - a.centre_x,
                                                                                      rect.cy - a.centre_y,
                                                                                      s.x - rect.cx, s.y - rect.cy) -
                                                                s.q.height_m) < 2e-6));
    if (!same && wrong++ < 3) {
      ADD_FAILURE() << "sample (" << s.x << ", " << s.y << "): point query says layer " << s.q.layer << " status "
                    << to_string(s.q.status) << " class " << to_string(s.q.cell_class) << " nv " << s.q.normal_variance
                    << "; the piece says layer " << a.layer << " known " << a.known << " class "
                    << to_string(a.cell_class) << " nv " << a.normal_variance;
    }
    sampled_cells.insert({a.layer, a.index.x, a.index.y});
  }
  EXPECT_EQ(unmatched, 0);
  EXPECT_EQ(wrong, 0) << wrong << " of " << samples.size() << " samples disagree with their piece";
  // Every piece larger than the samples resolve (4 edge spacings squared) holds a sample.
  for (const KeptPiece& k : pieces) {
    if (k.area >= 4.0 * edge * edge && k.answer.layer >= 0) {
      EXPECT_TRUE(sampled_cells.count({k.answer.layer, k.answer.index.x, k.answer.index.y}) > 0)
          << "a piece of " << k.area << " m^2 in layer " << k.answer.layer << " holds no sample";
    }
  }

  // Aggregates: the query against the reference of the interior grid samples.
  const std::vector<test::RectSample> grid =
      test::rect_samples(map, rect.cx, rect.cy, ux, uy, c.L, c.W, 0.005, 1e9, 1e-5, 0.04, 0.0);
  const Reference ref = reference_of(grid);
  const FootprintResult r = query_footprint(map, fp);
  ASSERT_TRUE(r.status == Status::kOk) << to_string(r.status);
  EXPECT_NEAR(r.area_m2, c.L * c.W, 1e-4 * c.L * c.W);
  // Midpoint sampling of an indicator: error <= boundary length of the unknown region x spacing.
  EXPECT_NEAR(r.unknown_share, ref.unknown_share, 0.02) << "unknown share";
  EXPECT_GE(detail::hazard_rank(r.worst_class), ref.worst_rank) << "the query misses a class the samples see";
  EXPECT_GE(r.max_inclination, ref.max_inclination) << "the query misses an inclination the samples see";
  if (ref.known) {
    EXPECT_LE(r.min_height_m, ref.min_h + 2e-6);
    EXPECT_GE(r.max_height_m, ref.max_h - 2e-6);
    const double relief = 4.0 * std::sqrt(ref.max_normal_variance);
    EXPECT_GE(r.max_step_m, std::max(ref.max_h - ref.min_h, relief) - 4e-6);
  }
  // Upper side: the extremes from the pieces, which the samples above showed equal to point
  // answers; a piece the grid misses is a sliver, below 1e-4 of the area, or on the boundary.
  double max_incl = 0.0, max_nv = 0.0;
  int rank = 0;
  for (const KeptPiece& k : pieces) {
    // The query drops slivers (area <= 1 um x the cell width): float strips of a shared edge.
    if (!k.answer.known || k.area <= detail::RegionWalk<CadreConfig>::kSliverWidthM * k.leaf_width) continue;
    max_incl = std::max(max_incl, double{k.answer.inclination});
    max_nv = std::max(max_nv, double{k.answer.normal_variance});
    rank = std::max(rank, detail::hazard_rank(k.answer.cell_class));
  }
  EXPECT_EQ(r.max_inclination, static_cast<float>(max_incl));
  EXPECT_EQ(detail::hazard_rank(r.worst_class), rank);
  if (r.worst_layer >= 0) {
    EXPECT_TRUE(sampled_cells.count({r.worst_layer, r.worst_index.x, r.worst_index.y}) > 0 ||
                std::any_of(pieces.begin(), pieces.end(), [&](const KeptPiece& k) {
                  return k.answer.layer == r.worst_layer && k.answer.index == r.worst_index;
                }))
        << "the worst cell is not a piece of the footprint";
  }
}

TEST(Footprint, EveryPartAnswersAsThePointQueryThere) {
  const Cadre& map = terrain_map();
  const Case cases[] = {
      {0.0, 0.0, 0.0, 0.6, 0.4},      // flat tilted ground, axis aligned
      {0.02, 0.02, 0.0, 0.6, 0.4},    // edges on cell edges
      {0.75, -0.35, 30.0, 0.6, 0.4},  // over the box
      {0.6, -0.2, 45.0, 0.6, 0.4},    // a box corner
      {-0.7, 0.6, 17.0, 0.6, 0.4},    // over the hole: coarser layers answer inside it
      {-0.55, 0.45, 120.0, 0.6, 0.4}, // the hole's rim
      {1.2, 0.3, 63.0, 0.6, 0.4},     // across the Kalman window's edge
      {2.1, 1.2, 200.0, 0.6, 0.4},    // the ramp, 8 cm and 16 cm layers
      {2.5, -2.5, 10.0, 0.6, 0.4},    // beyond the 8 cm window: 16 cm answers
      {0.3, 0.1, 33.0, 2.0, 1.0},     // the lead's timing-test body, over several layers
      {-1.1, -1.0, 91.0, 1.3, 0.07},  // a thin one: every cell a boundary piece
  };
  for (const Case& c : cases) check_against_point_queries(map, c);
}

TEST(Footprint, RandomFootprintsAnswerAsThePointQueries) {
  const Cadre& map = terrain_map();
  std::uint32_t h = 99U;
  auto uniform = [&](double lo, double hi) {
    h = h * 1664525U + 1013904223U;
    return lo + (hi - lo) * static_cast<double>(h >> 8) / 16777216.0;
  };
  for (int i = 0; i < 12; ++i) {
    check_against_point_queries(map, Case{uniform(-3.0, 3.0), uniform(-3.0, 3.0), uniform(0.0, 360.0),
                                          uniform(0.1, 1.0), uniform(0.05, 0.8)});
  }
}

/// A single-CCM stack (8 cm) over a noise-free plane z = a x + b y: every cell holds the plane.
std::unique_ptr<Stack<SingleCcmConfig>> plane_map(double a, double b) {
  auto stack = std::make_unique<Stack<SingleCcmConfig>>();
  if (stack->init(test::precise_lidar_params(0.08F)) != Status::kOk) return nullptr;
  std::vector<PointXYZ> pts;
  for (double y = -3.0 + 0.0051; y < 3.0; y += 0.01) {
    for (double x = -3.0 + 0.0049; x < 3.0; x += 0.01) {
      pts.push_back(PointXYZ{static_cast<float>(x), static_cast<float>(y), static_cast<float>(a * x + b * y)});
    }
  }
  if (stack->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr) != Status::kOk) return nullptr;
  return stack;
}

TEST(Footprint, OnAPlaneTheStepIsThePlanesHeightRangeOverTheRectangle) {
  const double a = 0.2, b = -0.1;
  const auto map = plane_map(a, b);
  ASSERT_NE(map, nullptr);
  for (const double yaw_deg : {0.0, 25.0, 90.0, 137.0}) {
    const double yaw = yaw_deg * 3.14159265358979323846 / 180.0;
    const double ux = std::cos(yaw), uy = std::sin(yaw), L = 0.6, W = 0.4;
    const FootprintResult r =
        query_footprint(*map, Footprint{0.37F, -0.21F, static_cast<float>(ux), static_cast<float>(uy), 0.6F, 0.4F});
    ASSERT_EQ(r.status, Status::kOk);
    // Over a rectangle a plane ranges by |grad . u| L + |grad . v| W.
    const double range = std::fabs(a * ux + b * uy) * L + std::fabs(-a * uy + b * ux) * W;
    EXPECT_NEAR(r.max_step_m, range, 2e-4) << "yaw " << yaw_deg << ": height range of the plane";
    EXPECT_NEAR(r.max_height_m - r.min_height_m, range, 2e-4);
    EXPECT_NEAR(r.max_inclination, std::hypot(a, b), 1e-4) << "yaw " << yaw_deg;
    EXPECT_EQ(r.worst_class, CellClass::kTraversable);
    EXPECT_EQ(r.unknown_share, 0.0F);
    EXPECT_EQ(footprint_class(r, kDefaultMaxUnknownShare), CellClass::kTraversable);
    // Centre height on the plane.
    EXPECT_NEAR(0.5 * (r.max_height_m + r.min_height_m), a * 0.37 + b * -0.21, 2e-4);
  }
}

TEST(Footprint, ABoxIsAnObstacleUnderTheBodyAndNotBesideIt) {
  const Cadre& map = terrain_map();
  // The 15 cm box on [0.6, 0.9] x [-0.5, -0.2].
  const FootprintResult on = query_footprint(map, Footprint{0.75F, -0.35F, 1.0F, 0.0F, 0.6F, 0.4F});
  ASSERT_EQ(on.status, Status::kOk);
  EXPECT_EQ(on.worst_class, CellClass::kObstacle);
  EXPECT_EQ(footprint_class(on, kDefaultMaxUnknownShare), CellClass::kObstacle);
  EXPECT_GT(on.max_step_m, 0.12F) << "the 15 cm box edge";
  EXPECT_GE(on.worst_x, 0.5F);
  EXPECT_LE(on.worst_x, 1.0F);
  EXPECT_GE(on.worst_y, -0.6F);
  EXPECT_LE(on.worst_y, -0.1F);
  // 0.3 m clear of the box (more than one 8 cm cell): traversable, step ~ the plane's range.
  const FootprintResult beside = query_footprint(map, Footprint{0.0F, -0.35F, 1.0F, 0.0F, 0.6F, 0.4F});
  ASSERT_EQ(beside.status, Status::kOk);
  EXPECT_EQ(beside.worst_class, CellClass::kTraversable);
  EXPECT_LT(beside.max_step_m, 0.06F);
  EXPECT_EQ(footprint_class(beside, kDefaultMaxUnknownShare), CellClass::kTraversable);
}

TEST(Footprint, HalfOverUnobservedGroundIsHalfUnknown) {
  // Only x < 0 observed (8 cm single CCM layer): a footprint centred on x = 0 is half unknown.
  auto map = std::make_unique<Stack<SingleCcmConfig>>();
  ASSERT_EQ(map->init(test::precise_lidar_params(0.08F)), Status::kOk);
  std::vector<PointXYZ> pts;
  for (double y = -2.0 + 0.0051; y < 2.0; y += 0.01)
    for (double x = -2.0 + 0.0049; x < 0.0; x += 0.01) pts.push_back(PointXYZ{static_cast<float>(x), static_cast<float>(y), 0.0F});
  ASSERT_EQ(map->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
  const FootprintResult r = query_footprint(*map, Footprint{0.0F, 0.31F, 1.0F, 0.0F, 0.64F, 0.4F});
  ASSERT_EQ(r.status, Status::kOk);
  EXPECT_NEAR(r.unknown_share, 0.5, 1e-5);
  EXPECT_EQ(r.worst_class, CellClass::kTraversable);
  EXPECT_EQ(footprint_class(r, 0.6F), CellClass::kTraversable);
  EXPECT_EQ(footprint_class(r, kDefaultMaxUnknownShare), CellClass::kUnknown);
  // Entirely over the unobserved half, then entirely off the map.
  const FootprintResult unseen = query_footprint(*map, Footprint{1.0F, 0.0F, 1.0F, 0.0F, 0.6F, 0.4F});
  EXPECT_EQ(unseen.status, Status::kOk);
  EXPECT_EQ(unseen.unknown_share, 1.0F);
  EXPECT_EQ(unseen.worst_class, CellClass::kUnknown);
  EXPECT_EQ(unseen.worst_layer, -1);
  EXPECT_EQ(footprint_class(unseen, 1.0F), CellClass::kUnknown);
  const FootprintResult off = query_footprint(*map, Footprint{50.0F, 0.0F, 1.0F, 0.0F, 0.6F, 0.4F});
  EXPECT_EQ(off.status, Status::kOutsideMap);
  EXPECT_EQ(off.unknown_share, 1.0F);
}

TEST(Footprint, RefusesBadInputWithAStatus) {
  const Cadre& map = terrain_map();
  const float nan = std::nanf("");
  const float inf = INFINITY;
  EXPECT_EQ(query_footprint(map, Footprint{nan, 0.0F, 1.0F, 0.0F, 0.6F, 0.4F}).status, Status::kNonFiniteInput);
  EXPECT_EQ(query_footprint(map, Footprint{0.0F, 0.0F, inf, 0.0F, 0.6F, 0.4F}).status, Status::kNonFiniteInput);
  EXPECT_EQ(query_footprint(map, Footprint{0.0F, 0.0F, 1.0F, 0.0F, nan, 0.4F}).status, Status::kNonFiniteInput);
  EXPECT_EQ(query_footprint(map, Footprint{0.0F, 0.0F, 0.0F, 0.0F, 0.6F, 0.4F}).status, Status::kInvalidArgument);
  EXPECT_EQ(query_footprint(map, Footprint{0.0F, 0.0F, 1e-7F, 0.0F, 0.6F, 0.4F}).status, Status::kInvalidArgument);
  EXPECT_EQ(query_footprint(map, Footprint{0.0F, 0.0F, 1.0F, 0.0F, 0.0F, 0.4F}).status, Status::kInvalidArgument);
  EXPECT_EQ(query_footprint(map, Footprint{0.0F, 0.0F, 1.0F, 0.0F, 0.6F, -0.4F}).status, Status::kInvalidArgument);
  EXPECT_EQ(query_footprint(map, Footprint{2e5F, 0.0F, 1.0F, 0.0F, 0.6F, 0.4F}).status, Status::kOutOfRange);
  // The bounding-box limit: 64 x 64 cells of 4 cm. 2.52 m axis aligned touches 64 (cell edges
  // avoided); 2.6 m touches 66; a 2 x 1 m body at 45 deg (2.12 m box) fits.
  EXPECT_EQ(query_footprint(map, Footprint{0.01F, 0.01F, 1.0F, 0.0F, 2.52F, 2.52F}).status, Status::kOk);
  EXPECT_EQ(query_footprint(map, Footprint{0.01F, 0.01F, 1.0F, 0.0F, 2.6F, 2.52F}).status, Status::kOutOfRange);
  EXPECT_EQ(query_footprint(map, Footprint{0.0F, 0.0F, 1.0F, 1.0F, 2.0F, 1.0F}).status, Status::kOk);
  EXPECT_EQ(query_footprint(map, Footprint{0.0F, 0.0F, 1.0F, 0.0F, 3e38F, 3e38F}).status, Status::kOutOfRange);
  // A refused result says nothing.
  const FootprintResult refused = query_footprint(map, Footprint{nan, 0.0F, 1.0F, 0.0F, 0.6F, 0.4F});
  EXPECT_EQ(refused.worst_class, CellClass::kUnknown);
  EXPECT_EQ(refused.worst_layer, -1);
  EXPECT_EQ(refused.cells_visited, 0U);
  EXPECT_EQ(footprint_class(refused, 1.0F), CellClass::kUnknown);
  // Before init.
  const auto fresh = std::make_unique<Cadre>();
  EXPECT_EQ(query_footprint(*fresh, Footprint{0.0F, 0.0F, 1.0F, 0.0F, 0.6F, 0.4F}).status, Status::kNotInitialised);
}

// The worst case of cells read, for CADRE: a map where no cell is known but every cell has
// weight (so every piece asks every layer above it, each CCM cell pooling its whole subtree),
// and the largest footprint. Bound (docs/design.md section 6): for each layer k, the cells the
// bounding box touches, n_k = (64 / 2^k + 1)^2, times the reads of one answer there: 1 + 9 for a
// constant cell, R_k = (4^(k+1) - 1) / 3 for a CCM cell of stack layer k (own cell and every
// cell below).
TEST(Footprint, CellsVisitedStayWithinTheDocumentedWorstCase) {
  auto map = std::make_unique<Cadre>();
  StackParams p = test::precise_lidar_params(0.04F);
  p.min_weight = 1e6F;  // nothing is ever known
  ASSERT_EQ(map->init(p), Status::kOk);
  const std::vector<PointXYZ> pts = test::terrain_points(11.0, 0.03);
  ASSERT_EQ(map->update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 1.0F}, nullptr), Status::kOk);
  double bound = 0.0;
  for (int k = 0; k < Cadre::kLayerCount; ++k) {
    const double n = std::pow(64.0 / std::pow(2.0, k) + 1.0, 2.0);
    bound += n * (k == 0 ? 10.0 : (std::pow(4.0, k + 1) - 1.0) / 3.0);
  }
  std::uint32_t worst = 0;
  for (const float yaw : {0.0F, 0.3F, 0.785398F}) {
    // The largest footprint the limit admits at this heading.
    const float c = std::cos(yaw), s = std::sin(yaw);
    const float side = 2.5F / (c + s);
    const FootprintResult r = query_footprint(*map, Footprint{0.013F, 0.017F, c, s, side, side});
    ASSERT_EQ(r.status, Status::kOk) << yaw;
    EXPECT_EQ(r.unknown_share, 1.0F);
    worst = std::max(worst, r.cells_visited);
  }
  std::printf("[ bound    ] CADRE footprint, nothing known: %u cells read at most; documented bound %.0f\n", worst, bound);
  EXPECT_LE(worst, bound);
  EXPECT_GT(worst, 0.25 * bound) << "the adversarial map does not exercise the worst case";
  // The rover body (0.6 m x 0.4 m) on the mapped terrain: leaves, their first CCM parents.
  const FootprintResult body = query_footprint(terrain_map(), Footprint{0.1F, 0.1F, 0.8F, 0.6F, 0.6F, 0.4F});
  ASSERT_EQ(body.status, Status::kOk);
  std::printf("[ bound    ] CADRE 0.6 m x 0.4 m footprint on known ground: %u cells read\n", body.cells_visited);
  EXPECT_LE(body.cells_visited, 19U * 19U + 10U * 10U * 5U);
}

}  // namespace
}  // namespace ccmap
