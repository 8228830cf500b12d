// The stack's update paths (update_frame with map-frame points, with per-point weights, and
// update_frame_sensor with sensor-frame points and a pose) against the independent brute-force
// model of tests/support/model_stack.hpp, for every preset: counters, windows, cell presence and
// weight exactly; statistics within float rounding plus the fixed-point front's position error.
// Frames: the deterministic CADRE frames (tests/support/cadre_frames.hpp), a few moves, hostile
// points mixed in. Points within a margin of a cell edge or a routing bound are left out: there a
// correct arithmetic may decide either way (the front's own tests hold those cases).
#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/cadre_frames.hpp"
#include "support/model_stack.hpp"

namespace ccmap {
namespace {

/// CADRE with the finest layer's pool at a quarter of its default slots, so that the pose jump
/// of gated_frames_match_the_model overflows it (every path of the gate must run).
struct SmallPoolCadre : CadreConfig {
  static constexpr std::size_t kFineHeldSlots = 256U;
};

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

/// A stack of `params` with free space off: the model (tests/support/model_stack.hpp) is the
/// update path's; lines of sight through these frames' points (computed as if the terrain hid
/// nothing) would clear cells it keeps. Free space has its own tests (tests/map/free_space_test.cpp).
template <typename Config>
std::unique_ptr<Stack<Config>> make_stack(const StackParams& params) {
  auto stack = std::make_unique<Stack<Config>>();
  StackParams p = params;
  p.free_space_rays = 0.0F;
  EXPECT_EQ(stack->init(p), Status::kOk);
  return stack;
}

/// Three small CADRE frames along a short drive (heading turning), 0.3 m apart.
std::vector<test::CadreFrame> drive_frames() {
  std::vector<test::CadreFrame> frames;
  for (int k = 0; k < 3; ++k) {
    test::CadreFrameSpec spec;
    spec.width_px = 170;
    spec.height_px = 130;
    spec.sensor_x = 0.3F * static_cast<float>(k);
    spec.sensor_y = 0.05F * static_cast<float>(k);
    const float c = 1.0F - 0.02F * static_cast<float>(k);
    const float s = 0.2F * static_cast<float>(k);
    const float norm = 1.0F / std::sqrt(c * c + s * s);
    spec.heading_cos = c * norm;
    spec.heading_sin = s * norm;
    spec.seed = 11U + static_cast<std::uint32_t>(k);
    frames.push_back(test::make_cadre_frame(spec));
  }
  return frames;
}

/// Inserts hostile points at spread positions of a frame.
void mix_in(std::vector<PointXYZ>& pts, std::initializer_list<PointXYZ> hostile) {
  std::size_t i = 0;
  for (const PointXYZ& p : hostile) {
    pts.insert(pts.begin() + static_cast<std::ptrdiff_t>((i++ * 7919U) % pts.size()), p);
  }
}

template <typename Config>
void map_frame_matches_the_model(const StackParams& params, bool with_weights) {
  auto stack = make_stack<Config>(params);
  test::ModelStack<Config> model(*stack);
  const auto frames = drive_frames();
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const test::CadreFrame& frame = frames[f];
    ASSERT_EQ(stack->move_to(frame.sensor_origin.x, frame.sensor_origin.y), Status::kOk);
    model.move_to(frame.sensor_origin.x, frame.sensor_origin.y);
    std::vector<PointXYZ> pts;
    const PointXYZ o = frame.sensor_origin;
    for (const PointXYZ& p : frame.map_points) {
      const double dx = double{p.x} - o.x, dy = double{p.y} - o.y, dz = double{p.z} - o.z;
      if (model.safe_point(p.x, p.y, dx * dx + dy * dy + dz * dz, 1e-5)) pts.push_back(p);
    }
    // Every refusal reason, and the sensor origin itself (range 0).
    mix_in(pts, {{kNan, 0.5F, 0.0F}, {0.5F, kInf, 0.0F}, {0.5F, 0.5F, -kInf}, {2.0e5F, 0.0F, 0.0F},
                 {0.5F, -1.5e5F, 0.0F}, o, {o.x + 7.05F, o.y + 0.01F, 0.0F}, {o.x + 1.0e4F, o.y + 0.01F, 0.0F}});
    std::vector<float> weights;
    if (with_weights) {
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const float bad[] = {kNan, 0.0F, -1.0F, 2.0e6F, kInf};
        weights.push_back(i % 101U == 3U ? bad[(i / 101U) % 5U] : 0.5F + static_cast<float>(i % 7U) * 0.25F);
      }
    }
    pts = model.without_gate_ambiguity(std::move(pts), &weights, o);
    FrameCounters c{};
    ASSERT_EQ(stack->update_frame(pts.data(), with_weights ? weights.data() : nullptr, pts.size(), o, &c),
              Status::kOk);
    const auto m = model.frame_map(pts, with_weights ? weights.data() : nullptr, o);
    model.expect_matches(c, m, "map frame " + std::to_string(f));
    ASSERT_FALSE(::testing::Test::HasFailure());
  }
}

/// The CADRE frame's pose with an extra pitch, so that every rotation entry is non-trivial, and
/// its sensor points expressed for that pose.
Pose pitched(const test::CadreFrame& frame, std::vector<PointXYZ>* sensor) {
  const float cp = 0.96F, sp = 0.28F;  // 16.3 deg; cp^2 + sp^2 = 1 to float rounding
  const Pose& r = frame.pose;
  Pose out = r;
  // R' = R P with P the pitch about y; s' = P^T s, so R' s' = R s.
  for (int i = 0; i < 3; ++i) {
    out.rotation[i][0] = r.rotation[i][0] * cp - r.rotation[i][2] * sp;
    out.rotation[i][1] = r.rotation[i][1];
    out.rotation[i][2] = r.rotation[i][0] * sp + r.rotation[i][2] * cp;
  }
  sensor->clear();
  for (const PointXYZ& s : frame.sensor_points) {
    sensor->push_back(PointXYZ{cp * s.x + sp * s.z, s.y, -sp * s.x + cp * s.z});
  }
  return out;
}

template <typename Config>
void sensor_frame_matches_the_model(const StackParams& params) {
  auto stack = make_stack<Config>(params);
  test::ModelStack<Config> model(*stack);
  const auto frames = drive_frames();
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const test::CadreFrame& frame = frames[f];
    ASSERT_EQ(stack->move_to(frame.sensor_origin.x, frame.sensor_origin.y), Status::kOk);
    model.move_to(frame.sensor_origin.x, frame.sensor_origin.y);
    std::vector<PointXYZ> all;
    const Pose pose = pitched(frame, &all);
    std::vector<PointXYZ> pts;
    for (const PointXYZ& s : all) {
      double m[3];
      test::ModelStack<Config>::transform(pose, s, m);
      // 20 um from every edge: beyond the front's documented 8 um position error.
      if (model.safe_point(m[0], m[1], double{s.x} * s.x + double{s.y} * s.y + double{s.z} * s.z, 2e-5)) {
        pts.push_back(s);
      }
    }
    mix_in(pts, {{kNan, 0.5F, 0.0F}, {0.5F, -kInf, 0.0F}, {2048.0F, 0.0F, 0.0F}, {0.0F, 0.0F, -3.0e4F},
                 {0.0F, 0.0F, 0.0F}, {7.05F, 0.01F, 0.0F}});
    pts = model.without_gate_ambiguity(std::move(pts), pose);
    FrameCounters c{};
    ASSERT_EQ(stack->update_frame_sensor(pts.data(), pts.size(), pose, &c), Status::kOk);
    const auto m = model.frame_sensor(pts, pose);
    model.expect_matches(c, m, "sensor frame " + std::to_string(f), 8e-6);
    ASSERT_FALSE(::testing::Test::HasFailure());
  }
}

StackParams lidar_params(float width) {
  StackParams p = default_stack_params(width);
  p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.002F, 0.0F});
  return p;
}

StackParams inverse_variance_params(float width) {
  StackParams p = default_stack_params(width);
  p.noise.set_weight_mode(sensor::WeightMode::kInverseVariance, 1.0F);
  return p;
}

/// The outlier gate and the change rule against the model: drive frames with 3 % of their points
/// thrown 0.2 .. 1 m up (held and dropped; some cells merge or re-seed) and 2 % pushed along their
/// ray to 1.5 .. 3 times their range (stereo mismatches: underground, judged by the finer layer
/// and the line of sight), then a frame whose
/// every point is 15 cm higher (a pose jump: held, re-seeded, the pools overflow), then a
/// normal frame again, in the map frame or the sensor frame. Every path of the gate must run
/// (the pool overflow where the jump moves more cells than a pool has slots: CADRE's 4 cm layer
/// with a smaller pool, SmallPoolCadre).
template <typename Config>
void gated_frames_match_the_model(const StackParams& params, bool sensor_frame, bool pool_overflows, bool stereo) {
  auto stack = make_stack<Config>(params);
  test::ModelStack<Config> model(*stack);
  auto frames = drive_frames();
  frames.push_back(frames.back());
  frames.push_back(frames.back());
  frames.push_back(frames.back());
  FrameCounters totals{};
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const test::CadreFrame& frame = frames[f];
    ASSERT_EQ(stack->move_to(frame.sensor_origin.x, frame.sensor_origin.y), Status::kOk);
    model.move_to(frame.sensor_origin.x, frame.sensor_origin.y);
    const float jump = f == 4U ? 0.15F : 0.0F;
    std::vector<PointXYZ> pts;
    for (std::size_t i = 0; i < frame.map_points.size(); ++i) {
      PointXYZ p = sensor_frame ? frame.sensor_points[i] : frame.map_points[i];
      // Outliers in frames 1 .. 3: z up, in either frame (the sensor's z is the map's z up to
      // the translation: the CADRE frames' rotation is a yaw).
      const std::uint32_t h = static_cast<std::uint32_t>(i) * 2654435761U + static_cast<std::uint32_t>(f) * 40503U;
      if (f >= 1U && f <= 3U && (h >> 8) % 100U < 3U) p.z += 0.2F + 0.8F * static_cast<float>((h >> 16) % 1000U) / 1000.0F;
      if (f >= 1U && f <= 3U && (h >> 8) % 100U >= 97U) {
        // Along the ray from the sensor: sensor-frame coordinates scale, map-frame ones about
        // the sensor origin.
        const float stretch = 1.5F + 1.5F * static_cast<float>((h >> 16) % 1000U) / 1000.0F;
        const PointXYZ o = sensor_frame ? PointXYZ{0.0F, 0.0F, 0.0F} : frame.sensor_origin;
        p = PointXYZ{o.x + stretch * (p.x - o.x), o.y + stretch * (p.y - o.y), o.z + stretch * (p.z - o.z)};
      }
      p.z += jump;
      double m[3] = {p.x, p.y, p.z};
      double r2 = 0.0;
      if (sensor_frame) {
        test::ModelStack<Config>::transform(frame.pose, p, m);
        r2 = double{p.x} * p.x + double{p.y} * p.y + double{p.z} * p.z;
      } else {
        const PointXYZ o = frame.sensor_origin;
        r2 = (m[0] - o.x) * (m[0] - o.x) + (m[1] - o.y) * (m[1] - o.y) + (m[2] - o.z) * (m[2] - o.z);
      }
      if (model.safe_point(m[0], m[1], r2, sensor_frame ? 2e-5 : 1e-5)) pts.push_back(p);
    }
    FrameCounters c{};
    typename test::ModelStack<Config>::Counts expected;
    if (sensor_frame) {
      pts = model.without_gate_ambiguity(std::move(pts), frame.pose);
      ASSERT_EQ(stack->update_frame_sensor(pts.data(), pts.size(), frame.pose, &c), Status::kOk);
      expected = model.frame_sensor(pts, frame.pose);
    } else {
      pts = model.without_gate_ambiguity(std::move(pts), nullptr, frame.sensor_origin);
      ASSERT_EQ(stack->update_frame(pts.data(), pts.size(), frame.sensor_origin, &c), Status::kOk);
      expected = model.frame_map(pts, nullptr, frame.sensor_origin);
    }
    model.expect_matches(c, expected, std::string(sensor_frame ? "sensor" : "map") + " frame " + std::to_string(f),
                         sensor_frame ? 8e-6 : 1e-6);
    ASSERT_FALSE(::testing::Test::HasFailure());
    detail::accumulate(totals, c);
  }
  EXPECT_GT(totals.gated_held, 0U) << "no point was held";
  EXPECT_GT(totals.gated_dropped, 0U) << "no held point was dropped";
  EXPECT_GT(totals.gated_admitted, 0U) << "no held point was admitted";
  EXPECT_GT(totals.reseeded_cells, 0U) << "no cell was re-seeded";
  EXPECT_GT(totals.merged_cells, 0U) << "no cell was merged";
  if (pool_overflows) {
    EXPECT_GT(totals.gated_pool_full, 0U) << "the pose jump should overflow a pool";
  }
  if (stereo && Stack<Config>::kLayerCount > 1) {
    EXPECT_GT(totals.gated_finer, 0U) << "no mismatch was judged by the finer layer";
    EXPECT_GT(totals.gated_occluded, 0U) << "no mismatch was found behind known ground";
  }
}

TEST(UpdatePath, CadreGateMatchesTheModel) {
  gated_frames_match_the_model<SmallPoolCadre>(default_stack_params(0.04F), false, true, true);
  gated_frames_match_the_model<SmallPoolCadre>(default_stack_params(0.04F), true, true, true);
  gated_frames_match_the_model<SmallPoolCadre>(lidar_params(0.04F), false, true, false);
  gated_frames_match_the_model<CadreConfig>(default_stack_params(0.04F), true, false, true);
}
TEST(UpdatePath, SingleLayerGatesMatchTheModel) {
  gated_frames_match_the_model<SingleCcmConfig>(default_stack_params(0.08F), false, false, true);
  gated_frames_match_the_model<SingleKalmanConfig>(default_stack_params(0.08F), true, false, true);
  gated_frames_match_the_model<SingleOmgConfig>(default_stack_params(0.08F), false, false, true);
}
TEST(UpdatePath, GateOffMatchesTheModel) {
  StackParams off = default_stack_params(0.04F);
  off.outlier_gate_sigma = 0.0F;
  map_frame_matches_the_model<CadreConfig>(off, true);
  sensor_frame_matches_the_model<CadreConfig>(off);
}

TEST(UpdatePath, CadreMapFrameMatchesTheModel) { map_frame_matches_the_model<CadreConfig>(default_stack_params(0.04F), false); }
TEST(UpdatePath, CadreMapFrameWithWeightsMatchesTheModel) {
  map_frame_matches_the_model<CadreConfig>(default_stack_params(0.04F), true);
}
TEST(UpdatePath, CadreInverseVarianceWeightsMatchTheModel) {
  map_frame_matches_the_model<CadreConfig>(inverse_variance_params(0.04F), false);
}
TEST(UpdatePath, CadreSensorFrameMatchesTheModel) { sensor_frame_matches_the_model<CadreConfig>(default_stack_params(0.04F)); }
TEST(UpdatePath, SingleCcmMatchesTheModel) {
  map_frame_matches_the_model<SingleCcmConfig>(default_stack_params(0.08F), true);
  sensor_frame_matches_the_model<SingleCcmConfig>(default_stack_params(0.08F));
}
TEST(UpdatePath, SingleKalmanMatchesTheModel) {
  map_frame_matches_the_model<SingleKalmanConfig>(default_stack_params(0.08F), false);
  sensor_frame_matches_the_model<SingleKalmanConfig>(default_stack_params(0.08F));
}
TEST(UpdatePath, SingleOmgMatchesTheModel) {
  map_frame_matches_the_model<SingleOmgConfig>(default_stack_params(0.08F), true);
  sensor_frame_matches_the_model<SingleOmgConfig>(default_stack_params(0.08F));
}
TEST(UpdatePath, PaperCellCadreAndSingleCcmMatchTheModel) {
  map_frame_matches_the_model<PaperCell<CadreConfig>>(default_stack_params(0.04F), true);
  sensor_frame_matches_the_model<PaperCell<CadreConfig>>(default_stack_params(0.04F));
  map_frame_matches_the_model<PaperCell<SingleCcmConfig>>(default_stack_params(0.08F), false);
}
TEST(UpdatePath, LidarCadreMatchesTheModel) {
  map_frame_matches_the_model<CadreConfig>(lidar_params(0.04F), false);
  sensor_frame_matches_the_model<CadreConfig>(lidar_params(0.04F));
}

// KalmanBatch::add_while_inside (map/update/kalman_batch.hpp) takes a run's entries four at a
// time where all four are of the run and inside the gate, and one by one otherwise. Against a
// brute-force model of the run's rule (entry i always, then every next entry while it is of the
// run's cell and, with the gate, inside [low, low + span]): the entry it stops at and the
// run's count and sums, on random chunks of runs 1 to 13 long with points outside the gate,
// foreign slots and chunk ends at every offset. The model is written here, one point at a time.
template <bool kGate>
void check_runs_against_the_model(std::uint32_t seed) {
  using Batch = detail::KalmanBatch<64U>;
  auto batch = std::make_unique<Batch>();
  batch->clear();
  std::uint32_t state = seed;
  const auto next = [&state]() {
    state = state * 1664525U + 1013904223U;
    return state >> 8U;
  };
  constexpr std::size_t kCount = 256U;
  std::vector<std::int32_t> slots(kCount), heights(kCount), keys(kCount);
  for (int trial = 0; trial < 200; ++trial) {
    // Runs of one cell (slots 0..63, an upset's out-of-range value now and then).
    for (std::size_t i = 0; i < kCount;) {
      const std::uint32_t r = next();
      const std::int32_t slot = (r % 50U == 0U) ? static_cast<std::int32_t>(64U + r % 7U) : static_cast<std::int32_t>(r % 64U);
      const std::size_t length = 1U + next() % 13U;
      for (std::size_t k = 0; k < length && i < kCount; ++k, ++i) {
        slots[i] = slot;
      }
    }
    // Heights around 10,000 Q14 units; the interval [9,000, 11,000]; 1 in 12 outside.
    for (std::size_t i = 0; i < kCount; ++i) {
      const std::uint32_t r = next();
      heights[i] = (r % 12U == 0U) ? static_cast<std::int32_t>(r % 2U == 0U ? 8000U + r % 999U : 11001U + r % 5000U)
                                   : static_cast<std::int32_t>(9000U + r % 2001U);
      keys[i] = static_cast<std::int32_t>(next() % 100000U) - 20000;
    }
    const std::int32_t low = 9000;
    const std::uint32_t span = 2000U;
    const std::size_t count = kCount - next() % 9U;  // chunk ends at every offset mod 4
    for (std::size_t i = 0; i < count; ++i) {
      Batch::Run run{};
      run.slot = slots[i] & 63;
      run.low = low;
      run.span = span;
      const std::size_t got = batch->add_while_inside<kGate>(run, slots.data(), heights.data(), keys.data(), i, count);
      // The model.
      std::size_t j = i;
      std::int64_t sum_h = 0;
      std::int64_t sum_k = 0;
      do {
        if (kGate && (heights[j] < low || heights[j] > low + static_cast<std::int32_t>(span))) {
          break;
        }
        sum_h += heights[j];
        sum_k += keys[j];
        ++j;
      } while (j < count && slots[j] == run.slot);
      ASSERT_EQ(got, j) << "seed " << seed << " trial " << trial << " entry " << i;
      ASSERT_EQ(run.count, static_cast<std::uint32_t>(j - i));
      ASSERT_EQ(run.sum_height_q14, sum_h);
      ASSERT_EQ(run.sum_range_key, sum_k);
    }
  }
}

TEST(KalmanBatchRuns, FourPointBlocksTakeWhatThePointByPointRuleTakes) {
  for (const std::uint32_t seed : {1U, 2U, 3U}) {
    check_runs_against_the_model<true>(seed);
    check_runs_against_the_model<false>(seed);
  }
}

// The gate's count of in-gate CCM points (map/update/held_pool.hpp): the update path counts a
// run of points folded into one cell in a register (AcceptRun) and hands the run to the pool
// when a run of another cell starts and at the chunk's end; slots are taken on a cell's first
// held point in between. Against a model written here, per cell: the in-gate points before its
// first held point (the tag: saturating at 32,767, never reached here) become the slot's count,
// those after add to it; slots in the order of first held points, none beyond kSlots (that
// cell's held points are refused). Random frames of runs of 1-9 points over 40 cells, 1 in 15
// points held, chunks of 1-256 points; every slot's cell, in-gate and held counts at the end.
TEST(AcceptRuns, HandTheSlotsWhatPointByPointCountingGives) {
  constexpr std::size_t kCells = 40U;
  constexpr std::size_t kSlots = 8U;
  struct Held {
    float sum;
  };
  using Pool = detail::HeldPool<Held, kCells, kSlots>;
  struct Model {
    std::uint32_t before = 0U;  // in-gate points before the slot
    std::uint32_t after = 0U;   // in-gate points since
    std::uint32_t held = 0U;
    int slot = -1;
  };
  std::uint32_t state = 7U;
  const auto next = [&state]() {
    state = state * 1664525U + 1013904223U;
    return state >> 8U;
  };
  auto pool = std::make_unique<Pool>();
  for (int frame = 0; frame < 300; ++frame) {
    pool->clear();
    std::vector<Model> model(kCells);
    int slots_taken = 0;
    std::size_t in_chunk = 0U;
    std::size_t chunk = 1U + next() % 256U;
    detail::AcceptRun<Pool> accepts{};
    std::uint32_t run_cell = 0xFFFFFFFFU;  // the cell of the last point folded in this chunk
    std::uint32_t expect_handed = 0U;
    for (int point = 0; point < 600;) {
      const std::uint32_t cell = next() % kCells;
      const std::uint32_t length = 1U + next() % 9U;
      for (std::uint32_t k = 0; k < length; ++k, ++point) {
        if (next() % 15U == 0U) {
          Model& m = model[cell];
          if (m.slot < 0 && slots_taken < static_cast<int>(kSlots)) {
            m.slot = slots_taken++;
          }
          auto* slot = pool->hold(cell, CellIndex{static_cast<std::int32_t>(cell), 0}, 1);
          ASSERT_EQ(slot != nullptr, m.slot >= 0) << "frame " << frame << " point " << point;
          if (slot != nullptr) {
            ++m.held;
          }
        } else {
          const bool new_run = cell != run_cell;  // the update path's run (ChunkRuns)
          if (new_run) {
            accepts.start(*pool, cell);
            run_cell = cell;
          }
          accepts.add();
          ++expect_handed;
          Model& m = model[cell];
          ++(m.slot >= 0 ? m.after : m.before);
        }
        if (++in_chunk == chunk) {  // the chunk's end: the last run handed over
          accepts.flush(*pool);
          ASSERT_EQ(accepts.handed(), expect_handed);
          accepts = detail::AcceptRun<Pool>{};
          expect_handed = 0U;
          run_cell = 0xFFFFFFFFU;
          in_chunk = 0U;
          chunk = 1U + next() % 256U;
        }
      }
    }
    accepts.flush(*pool);
    std::vector<bool> seen(kCells, false);
    (void)pool->end_frame([&](const Pool::Slot& slot) {
      EXPECT_LT(slot.cell, kCells);
      if (slot.cell >= kCells) {
        return false;
      }
      const Model& m = model[slot.cell];
      seen[slot.cell] = true;
      EXPECT_GE(m.slot, 0) << "frame " << frame << " cell " << slot.cell;
      EXPECT_EQ(slot.accepted, m.before + m.after) << "frame " << frame << " cell " << slot.cell;
      EXPECT_EQ(slot.count, m.held) << "frame " << frame << " cell " << slot.cell;
      return false;
    });
    for (std::size_t cell = 0; cell < kCells; ++cell) {
      EXPECT_EQ(seen[cell], model[cell].slot >= 0) << "frame " << frame << " cell " << cell;
    }
  }
}

// The tag saturates at 32,767 in-gate points; a slot taken after that starts from 32,767 and
// counts on without bound; runs handed over in one step saturate as one by one would.
TEST(AcceptRuns, TheTagSaturatesAndTheSlotCountsOn) {
  struct Held {
    float sum;
  };
  using Pool = detail::HeldPool<Held, 4U, 2U>;
  auto pool = std::make_unique<Pool>();
  pool->clear();
  for (int run = 0; run < 200; ++run) {  // 200 runs of 250: 50,000 points
    pool->accept(2U, 250U);
  }
  pool->accept(3U, 32766U);
  pool->accept(3U, 1U);
  pool->accept(3U, 1U);  // saturated: stays 32,767
  ASSERT_NE(pool->hold(2U, CellIndex{2, 0}, 1), nullptr);
  ASSERT_NE(pool->hold(3U, CellIndex{3, 0}, 1), nullptr);
  pool->accept(2U, 40000U);  // a slot's count does not saturate at 15 bits
  pool->accept(3U, 1U);
  std::uint32_t accepted[4] = {0U, 0U, 0U, 0U};
  (void)pool->end_frame([&](const Pool::Slot& slot) {
    accepted[slot.cell & 3U] = slot.accepted;
    return false;
  });
  EXPECT_EQ(accepted[2], 32767U + 40000U);
  EXPECT_EQ(accepted[3], 32768U);
}

}  // namespace
}  // namespace ccmap
