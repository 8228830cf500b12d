// Soak: a 10^4-frame moving traverse with no state corruption.
//
// What "rebuild" means here. A cell that leaves a window is cleared, so the map after a
// traverse is not a function of all frames: each cell in the final windows holds exactly the
// points routed to it since it last entered its window. Routing itself depends on the windows
// at the time of each frame (a point goes to the finest layer whose window holds it), so
// replaying the frames into a stack sitting at the final pose would route differently. The
// rebuild is therefore a brute-force model, replayed frame by frame alongside the stack:
// (tests/support/model_stack.hpp: per layer a hash map from global cell index to the cell's
// state in double, its own windows, routing and indexing re-derived per point from the documented
// rules, Kalman cells by the documented frame batch).
// The generated points keep 10 % of the finest cell width away from every cell edge and 0.1 %
// away from every IV-G range bound, so routing is unambiguous. Then every cell's presence and
// weight must match the model exactly (an aliased, lost, stale or wrongly cleared cell, or
// cross-talk in the ring buffers over 10^4 moves, changes them) and its statistics within float
// rounding.
// Compared at checkpoints over the whole storage of every layer, not by queries.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/hash_unit.hpp"
#include "support/map_state.hpp"
#include "support/model_stack.hpp"

namespace ccmap {
namespace {

using S = Stack<CadreConfig>;
using ccmap::test::hash_unit;

TEST(StackSoak, TenThousandFrameTraverseMatchesABruteForceRebuild) {
  constexpr int kFrames = 10000;
  constexpr std::uint32_t kPointsPerFrame = 32;
  auto stack = std::make_unique<S>();
  ASSERT_EQ(stack->init(default_stack_params(0.04F)), Status::kOk);
  test::ModelStack<CadreConfig> model(*stack);
  std::vector<PointXYZ> pts;
  FrameCounters totals{};
  std::uint32_t model_used = 0;
  for (int f = 0; f < kFrames; ++f) {
    // A figure-of-eight loop of +-12 m, ~1.5 cm per frame: windows move on every layer, cells
    // leave and re-enter, the loop crosses itself.
    const double t = 2.0 * 3.141592653589793 * f / 5000.0;
    const float rx = static_cast<float>(12.0 * std::sin(t));
    const float ry = static_cast<float>(6.0 * std::sin(2.0 * t));
    const float hx = static_cast<float>(std::cos(t)), hy = static_cast<float>(std::cos(2.0 * t));
    ASSERT_EQ(stack->move_to(rx, ry), Status::kOk);
    model.move_to(rx, ry);
    const PointXYZ origin{rx, ry, 0.5F};
    const float w0 = stack->layer_cell_width(0);
    pts.clear();
    for (std::uint32_t i = 0; i < kPointsPerFrame; ++i) {
      const std::uint32_t id = static_cast<std::uint32_t>(f) * kPointsPerFrame + i;
      // Ahead of the robot out to 6 m (some points beyond every IV-G bound), +-3 m sideways.
      const float ahead = 0.2F + 5.8F * hash_unit(id, 1U);
      const float side = 6.0F * hash_unit(id, 2U) - 3.0F;
      const float norm = 1.0F / std::sqrt(hx * hx + hy * hy + 1e-6F);
      const float x = rx + (hx * ahead - hy * side) * norm;
      const float y = ry + (hy * ahead + hx * side) * norm;
      // 10 % of the finest width away from every cell edge (coarser edges are finer edges).
      const float x_safe = (std::floor(x / w0) + 0.1F + 0.8F * hash_unit(id, 4U)) * w0;
      const float y_safe = (std::floor(y / w0) + 0.1F + 0.8F * hash_unit(id, 5U)) * w0;
      const float z = 0.05F * std::sin(0.7F * x_safe) + 0.03F * std::cos(1.3F * y_safe) + 0.004F * hash_unit(id, 3U);
      const double dx = double{x_safe} - origin.x, dy = double{y_safe} - origin.y, dz = double{z} - origin.z;
      if (model.safe_point(x_safe, y_safe, dx * dx + dy * dy + dz * dz, 0.1 * w0)) pts.push_back(PointXYZ{x_safe, y_safe, z});
    }
    pts = model.without_gate_ambiguity(std::move(pts), nullptr, origin);
    FrameCounters c{};
    ASSERT_EQ(stack->update_frame(pts.data(), pts.size(), origin, &c), Status::kOk);
    const auto m = model.frame_map(pts, nullptr, origin);
    model_used += m.used;
    ASSERT_EQ(c.used + c.rejected_non_finite + c.rejected_out_of_range + c.rejected_weight + c.outside_map +
                  c.too_noisy + c.gated_finer + c.gated_occluded + c.gated_held + c.gated_pool_full,
              c.received)
        << "frame counters do not add up at frame " << f;
    detail::accumulate(totals, c);
    if ((f + 1) % 1000 == 0) {
      model.expect_matches(c, m, "frame " + std::to_string(f));
      ASSERT_FALSE(HasFailure()) << "state corrupted by frame " << f;
      ASSERT_TRUE(test::all_stored_finite(*stack)) << "NaN/Inf in the map at frame " << f;
    }
  }
  EXPECT_EQ(totals.used, model_used) << "the stack used a different number of points than the rebuild";
  EXPECT_EQ(std::memcmp(&totals, &stack->total_counters(), sizeof totals), 0) << "total counters drifted";
  EXPECT_GT(totals.used, kFrames * kPointsPerFrame / 2) << "most points should be mapped";
  EXPECT_GT(totals.too_noisy, 0U) << "the traverse should also exercise the IV-G refusal";
  std::printf("[ soak     ] traverse: %u points used\n", totals.used);
}

}  // namespace
}  // namespace ccmap
