// The stack's outlier gate and change rule (docs/design.md, "Outlier gate and change") on
// analytic ground: outliers rejected (against the true plane and the same map fed clean), real
// change admitted within the number of frames the documentation promises, the range-error
// checks of the coarse layers, the held-point pool's bounds, and the gate off = the paper's
// update. The brute-force model comparison of every gate path is in update_path_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/hash_unit.hpp"
#include "support/reference.hpp"

namespace ccmap {
namespace {

using Ground = std::function<float(float x, float y)>;
constexpr float kNoise = 0.005F;  // lidar range noise (m)

StackParams lidar_params(float width, bool gate) {
  StackParams p = default_stack_params(width);
  p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{kNoise, 0.0F});
  if (!gate) p.outlier_gate_sigma = 0.0F;
  return p;
}

template <typename Config>
std::unique_ptr<Stack<Config>> make_stack(const StackParams& params) {
  auto stack = std::make_unique<Stack<Config>>();
  EXPECT_EQ(stack->init(params), Status::kOk);
  return stack;
}

/// Points of the square [-half, half)^2: per_cell points in each cell of width w (placed by an
/// integer hash, away from the cell's edges), heights from `ground` plus Gaussian noise, a share
/// `outliers` of them thrown 0.2 .. 1 m up. Deterministic by `seed`.
std::vector<PointXYZ> frame(float half, float w, int per_cell, const Ground& ground, float outliers, std::uint32_t seed) {
  test::Rng rng(seed);
  std::vector<PointXYZ> pts;
  const int cells = static_cast<int>(std::lround(2.0F * half / w));
  std::uint32_t id = seed * 7919U;
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      for (int k = 0; k < per_cell; ++k, ++id) {
        const float x = -half + w * (static_cast<float>(i) + 0.05F + 0.9F * test::hash_unit(id, 1U));
        const float y = -half + w * (static_cast<float>(j) + 0.05F + 0.9F * test::hash_unit(id, 2U));
        float z = ground(x, y) + kNoise * static_cast<float>(rng.normal());
        if (test::hash_unit(id, 3U) < outliers) z += 0.2F + 0.8F * test::hash_unit(id, 4U);
        pts.push_back(PointXYZ{x, y, z});
      }
    }
  }
  return pts;
}

/// Folds a frame (sensor 2 m above the centre) and checks that every point is counted once.
template <typename Config>
FrameCounters fold(Stack<Config>& stack, const std::vector<PointXYZ>& pts) {
  FrameCounters c{};
  EXPECT_EQ(stack.update_frame(pts.data(), pts.size(), PointXYZ{0.0F, 0.0F, 2.0F}, &c), Status::kOk);
  EXPECT_EQ(c.used + c.rejected_non_finite + c.rejected_out_of_range + c.rejected_weight + c.outside_map + c.too_noisy +
                c.gated_finer + c.gated_occluded + c.gated_held + c.gated_pool_full,
            c.received)
      << "frame counters do not add up";
  return c;
}

/// Mean height of layer 0's cell containing (x, y), known or not (what the cell holds; NaN if
/// unobserved).
template <typename Config>
float height_at(const Stack<Config>& stack, float x, float y) {
  if constexpr (Stack<Config>::kHasFine) {
    const auto* cell = stack.fine_layer().cell_at(x, y);
    return cell != nullptr && cell->weight > 0.0F ? cell->height : std::nanf("");
  } else {
    const CcmCell* cell = stack.ccm_layer(0).cell_at(x, y);
    return cell != nullptr && cell->weight > 0.0F ? cell->mean_z : std::nanf("");
  }
}

/// RMS of the map height against `ground` on a raster over the known cells of [-h, h)^2.
template <typename Config>
double rms_against(const Stack<Config>& stack, float h, const Ground& ground) {
  double sum = 0.0;
  int n = 0;
  for (float y = -h; y < h; y += 0.02F) {
    for (float x = -h; x < h; x += 0.02F) {
      const QueryResult q = stack.query_layer(0, x, y);
      if (q.status != Status::kOk) continue;
      const double e = q.height_m - ground(x, y);
      sum += e * e;
      ++n;
    }
  }
  EXPECT_GT(n, 1000) << "too few known raster points";
  return std::sqrt(sum / n);
}

// ---------------------------------------------------------------------------------------------
// Outliers
// ---------------------------------------------------------------------------------------------

template <typename Config>
void slope_with_outliers(const char* map) {
  const float w = 0.16F;
  const Ground plane = [](float x, float) { return 0.05F * x; };  // 5 % slope
  double rms[3] = {};                                             // clean/on, outliers/on, outliers/off
  for (int run = 0; run < 3; ++run) {
    auto stack = make_stack<Config>(lidar_params(w, run != 2));
    for (std::uint32_t f = 0; f < 4; ++f) {
      (void)fold(*stack, frame(1.6F, w, 40, plane, run == 0 ? 0.0F : 0.01F, 10U + f));
    }
    rms[run] = rms_against(*stack, 1.4F, plane);
  }
  EXPECT_LT(rms[1], rms[0] + 0.002) << map << ": 1 % outliers with the gate: RMS " << 1e3 * rms[1] << " mm against "
                                    << 1e3 * rms[0] << " mm clean";
  EXPECT_GT(rms[2], rms[0] + 0.003) << map << ": the outliers should do visible harm without the gate ("
                                    << 1e3 * rms[2] << " mm)";
}

TEST(OutlierGateStack, OutliersOnASlopeStayWithinTwoMillimetresOfClean) {
  slope_with_outliers<SingleCcmConfig>("CCM");
  slope_with_outliers<SingleKalmanConfig>("Kalman");
  slope_with_outliers<SingleOmgConfig>("OMG");
}

TEST(OutlierGateStack, TheGateOffIsThePaperUpdate) {
  auto off = make_stack<SingleCcmConfig>(lidar_params(0.16F, false));
  const FrameCounters c = fold(*off, frame(1.6F, 0.16F, 20, [](float, float) { return 0.0F; }, 0.05F, 3U));
  EXPECT_EQ(c.used, c.received) << "with the gate off every point is folded in";
  EXPECT_EQ(c.gated_held + c.gated_finer + c.gated_occluded + c.gated_pool_full + c.reseeded_cells + c.merged_cells, 0U);
  EXPECT_EQ(off->held_cells(), 0U);
}

// ---------------------------------------------------------------------------------------------
// Real change
// ---------------------------------------------------------------------------------------------

/// Frames until every cell centre wholly on the box [0.3, 0.9)^2 is within 1 cm of its top, -1
/// if not within `frames`; the ground mapped for 3 frames first.
template <typename Config>
int box_frames(bool gate, int per_cell, int frames) {
  const float w = 0.16F, top = 0.3F;
  auto stack = make_stack<Config>(lidar_params(w, gate));
  const Ground flat = [](float, float) { return 0.0F; };
  const Ground box = [&](float x, float y) { return (x >= 0.32F && x < 0.96F && y >= 0.32F && y < 0.96F) ? top : 0.0F; };
  std::uint32_t seed = 20U;
  for (int f = 0; f < 3; ++f) (void)fold(*stack, frame(1.6F, w, per_cell, flat, 0.0F, seed++));
  for (int f = 1; f <= frames; ++f) {
    (void)fold(*stack, frame(1.6F, w, per_cell, box, 0.0F, seed++));
    bool done = true;
    for (float y = 0.40F; y < 0.96F; y += w) {
      for (float x = 0.40F; x < 0.96F; x += w) done = done && std::fabs(height_at(*stack, x, y) - top) <= 0.01F;
    }
    if (done) return f;
  }
  return -1;
}

TEST(OutlierGateStack, ABoxOnMappedGroundAppearsInTheNextFrame) {
  EXPECT_EQ(box_frames<SingleCcmConfig>(true, 30, 3), 1) << "CCM";
  EXPECT_EQ(box_frames<SingleKalmanConfig>(true, 30, 3), 1) << "Kalman";
  EXPECT_EQ(box_frames<SingleOmgConfig>(true, 30, 3), 1) << "OMG";
  // The paper's update dilutes the box into the ground it mapped: not within 3 frames.
  EXPECT_EQ(box_frames<SingleCcmConfig>(false, 30, 3), -1) << "CCM, gate off";
}

TEST(OutlierGateStack, SparseCellsGatherTheEvidenceOfAChangeOverFrames) {
  // One point per cell and frame: a change needs change_min_points (3) held points, so the box
  // is in after exactly 3 frames.
  EXPECT_EQ(box_frames<SingleCcmConfig>(true, 1, 6), 3) << "CCM";
  EXPECT_EQ(box_frames<SingleKalmanConfig>(true, 1, 6), 3) << "Kalman";
  EXPECT_EQ(box_frames<SingleOmgConfig>(true, 1, 6), 3) << "OMG";
}

TEST(OutlierGateStack, ABoxOverPartOfACellIsMergedIntoAnObstacle) {
  // A step of 0.75 w over 40 % of one 16 cm cell, on ground mapped for 3 frames: the cell
  // becomes an obstacle in the next frame, as with the paper's update (the held step is a tight
  // 40 % of the cell's points: a second surface, merged).
  const float w = 0.16F, h = 0.12F;
  for (const bool gate : {false, true}) {
    auto stack = make_stack<SingleCcmConfig>(lidar_params(w, gate));
    const Ground flat = [](float, float) { return 0.0F; };
    const Ground step = [&](float x, float y) { return (x >= 0.32F && x < 0.384F && y >= 0.32F && y < 0.48F) ? h : 0.0F; };
    for (std::uint32_t f = 0; f < 3; ++f) (void)fold(*stack, frame(1.6F, w, 60, flat, 0.0F, 30U + f));
    const FrameCounters c = fold(*stack, frame(1.6F, w, 60, step, 0.0F, 40U));
    const QueryResult q = stack->query_layer(0, 0.40F, 0.40F);
    EXPECT_EQ(q.status, Status::kOk);
    EXPECT_EQ(q.cell_class, CellClass::kObstacle) << (gate ? "gate on" : "gate off") << ": the partly covered cell";
    if (gate) {
      EXPECT_EQ(c.merged_cells, 1U) << "the step should be merged, not re-seeded or dropped";
    }
  }
}

template <typename Config>
void seeded_by_outliers(const char* map) {
  // Five outliers alone in one cell (0.5 m up), then the ground around it: the next frame
  // re-seeds the cell from the ground (only the held points are a surface).
  const float w = 0.16F;
  for (const bool gate : {true, false}) {
    auto stack = make_stack<Config>(lidar_params(w, gate));
    std::vector<PointXYZ> seed;
    for (int i = 0; i < 5; ++i) {
      seed.push_back(PointXYZ{0.40F + 0.02F * static_cast<float>(i % 3), 0.40F + 0.03F * static_cast<float>(i / 3),
                              0.5F + 0.01F * static_cast<float>(i)});
    }
    (void)fold(*stack, seed);
    (void)fold(*stack, frame(1.6F, w, 30, [](float, float) { return 0.0F; }, 0.0F, 50U));
    const float h = height_at(*stack, 0.40F, 0.40F);
    if (gate) {
      EXPECT_NEAR(h, 0.0F, 0.005F) << map << ": the cell seeded by outliers should hold the ground";
    } else {
      EXPECT_GT(h, 0.05F) << map << ": the paper's update keeps the outliers' share (5 of 35 points)";
    }
  }
}

TEST(OutlierGateStack, ACellFirstSeededByFiveOutliersRecoversTheGround) {
  seeded_by_outliers<SingleCcmConfig>("CCM");
  seeded_by_outliers<SingleKalmanConfig>("Kalman");
  seeded_by_outliers<SingleOmgConfig>("OMG");
}

TEST(OutlierGateStack, IsolatedOutliersInSparseCellsAreDropped) {
  // One point per cell and frame; a single outlier in a cell never becomes a change (it waits
  // for more held points, and the points inside the gate outvote it).
  const float w = 0.16F;
  auto stack = make_stack<SingleCcmConfig>(lidar_params(w, true));
  const Ground flat = [](float, float) { return 0.0F; };
  for (std::uint32_t f = 0; f < 4; ++f) (void)fold(*stack, frame(1.6F, w, 1, flat, 0.0F, 60U + f));
  std::vector<PointXYZ> one = frame(1.6F, w, 1, flat, 0.0F, 70U);
  one[100].z = 0.8F;
  FrameCounters c = fold(*stack, one);
  EXPECT_EQ(c.gated_held, 1U);
  EXPECT_EQ(stack->held_cells(), 1U) << "one held point waits for the next frames";
  FrameCounters later{};
  for (std::uint32_t f = 0; f < 8; ++f) detail::accumulate(later, fold(*stack, frame(1.6F, w, 1, flat, 0.0F, 80U + f)));
  EXPECT_EQ(later.gated_dropped, 1U) << "the held outlier should be dropped";
  EXPECT_EQ(later.gated_admitted, 0U);
  EXPECT_EQ(stack->held_cells(), 0U);
  EXPECT_NEAR(height_at(*stack, one[100].x, one[100].y), 0.0F, 0.01F);
}

TEST(OutlierGateStack, APoseJumpReseedsAPoolOfCellsPerFrame) {
  // The ground seen 10 cm higher over 1600 cells: every point is held, 512 cells (one pool of
  // slots) re-seed per frame, the rest is dropped and counted until its turn: all cells hold the
  // new ground after ceil(1600 / 512) = 4 frames.
  const float w = 0.08F;
  auto stack = make_stack<SingleCcmConfig>(lidar_params(w, true));
  for (std::uint32_t f = 0; f < 2; ++f) (void)fold(*stack, frame(1.6F, w, 8, [](float, float) { return 0.0F; }, 0.0F, 90U + f));
  const Ground raised = [](float, float) { return 0.1F; };
  int frames = 0;
  for (std::uint32_t f = 0; f < 6; ++f) {
    const FrameCounters c = fold(*stack, frame(1.6F, w, 8, raised, 0.0F, 100U + f));
    EXPECT_LE(c.reseeded_cells, Stack<SingleCcmConfig>::kCcmHeldSlots);
    if (f == 0) {
      EXPECT_EQ(stack->last_frame_held_cells(), Stack<SingleCcmConfig>::kCcmHeldSlots)
          << "the frame ended with its pool full";
      EXPECT_EQ(c.reseeded_cells, Stack<SingleCcmConfig>::kCcmHeldSlots);
      EXPECT_GT(c.gated_pool_full, 0U);
    }
    int high = 0;
    for (int j = 0; j < 40; ++j) {
      for (int i = 0; i < 40; ++i) {
        high += std::fabs(height_at(*stack, -1.6F + w * (i + 0.5F), -1.6F + w * (j + 0.5F)) - 0.1F) < 0.01F ? 1 : 0;
      }
    }
    if (high == 1600 && frames == 0) frames = static_cast<int>(f) + 1;
  }
  EXPECT_EQ(frames, 4) << "the jump should be in after ceil(1600 / 512) frames";
}

TEST(OutlierGateStack, HeldPointsOfCellsThatLeaveTheWindowAreDropped) {
  const float w = 0.16F;
  auto stack = make_stack<SingleCcmConfig>(lidar_params(w, true));
  const Ground flat = [](float, float) { return 0.0F; };
  (void)fold(*stack, frame(1.6F, w, 3, flat, 0.0F, 110U));
  std::vector<PointXYZ> one = {PointXYZ{0.4F, 0.4F, 0.9F}};
  (void)fold(*stack, one);
  ASSERT_EQ(stack->held_cells(), 1U);
  ASSERT_EQ(stack->move_to(100.0F, 0.0F), Status::kOk);  // every cell leaves the window
  const FrameCounters c = fold(*stack, {});
  EXPECT_EQ(c.gated_dropped, 1U) << "the held point of a cell that left should be dropped and counted";
  EXPECT_EQ(stack->held_cells(), 0U);
}

// ---------------------------------------------------------------------------------------------
// Range errors of the coarse layers (stereo): the finer layer, the line of sight
// ---------------------------------------------------------------------------------------------

TEST(OutlierGateStack, RangeErrorsOfCoarseLayersAreJudgedByFinerGroundAndTheLineOfSight) {
  // CADRE stack, stereo, sensor 0.175 m above flat ground at the origin, looking along +x: the
  // ground mapped by points within each layer's range. Then points pushed far along their ray
  // (a stereo mismatch), ending metres underground and routed by their long range to a coarse
  // layer: one where the next finer layer knows the ground there, one where it does not but
  // the line of sight passes under known ground.
  using S = Stack<CadreConfig>;
  auto stack = make_stack<CadreConfig>(default_stack_params(0.04F));
  const PointXYZ sensor{0.0F, 0.0F, 0.175F};
  std::vector<PointXYZ> ground;
  for (float x = 0.3F; x < 4.5F; x += 0.013F) {
    for (float y = -1.0F; y < 1.0F; y += 0.013F) ground.push_back(PointXYZ{x, y, 0.0F});
  }
  FrameCounters c{};
  for (int f = 0; f < 2; ++f) ASSERT_EQ(stack->update_frame(ground.data(), ground.size(), sensor, &c), Status::kOk);
  const auto before = [&] {
    std::vector<float> h;
    for (int k = 0; k < S::kLayerCount; ++k) h.push_back(stack->query_layer(k, 3.0F, 0.0F).height_m);
    return h;
  }();
  // 1. Down a ray to (3.0, 0, -3.0): range 4.4 m, the 64 cm layer; the 32 cm layer knows (3, 0).
  // 2. Down a ray to (3.0, 1.7, -2.6): the 32 cm cell there is unobserved (|y| > 1), the middle of
  //    the line of sight (1.5, 0.85) is over mapped ground at 0 while the line is 1.2 m below.
  const PointXYZ mismatches[] = {{3.0F, 0.0F, -3.0F}, {3.0F, 1.7F, -2.6F}};
  ASSERT_EQ(stack->update_frame(mismatches, 2U, sensor, &c), Status::kOk);
  EXPECT_EQ(c.gated_finer, 1U) << "the mismatch over known finer ground";
  EXPECT_EQ(c.gated_occluded, 1U) << "the mismatch behind known ground";
  EXPECT_EQ(c.used, 0U);
  for (int k = 0; k < S::kLayerCount; ++k) {
    EXPECT_EQ(stack->query_layer(k, 3.0F, 0.0F).height_m, before[static_cast<std::size_t>(k)]) << "layer " << k;
  }
  // The same points with the lidar model (which may come with a nominal origin): no line of
  // sight test; the finer check still applies.
  StackParams lidar = default_stack_params(0.04F);
  lidar.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.01F, 0.02F});
  auto other = make_stack<CadreConfig>(lidar);
  for (int f = 0; f < 2; ++f) ASSERT_EQ(other->update_frame(ground.data(), ground.size(), sensor, &c), Status::kOk);
  ASSERT_EQ(other->update_frame(mismatches, 2U, sensor, &c), Status::kOk);
  EXPECT_EQ(c.gated_occluded, 0U);
}

}  // namespace
}  // namespace ccmap
