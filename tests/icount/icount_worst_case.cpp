// aarch64 instructions of every call a ground command can trigger, each at its worst case
// (issue 29, item 5; docs/performance.md, "Worst case per call"), on a Stack<CadreConfig>
// mapped from synthetic CADRE frames (tests/support/cadre_frames.hpp). One icount region per
// call (tests/support/icount_marker.hpp); tests/icount/CMakeLists.txt asserts each within its
// bound. The frame update's worst case is the flight cycle's (tests/map/cycle_icount.cpp).
//   region 1  init with the thresholds calibrated (default parameters)
//   region 2  init with the thresholds given (those region 1 calibrated)
//   region 3  save_snapshot of the mapped stack
//   region 4  load_snapshot of it
//   region 5  fill_costmap at its largest: 1024 x 1024 pixels, inflation at its largest (32
//             pixels), pixels of 1, 2 and 4 cm (10.24 m: the 16 cm layer's window; 20.48 m: the
//             coarsest window; 40.96 m: three quarters of it off the map) (3 intervals)
//   region 6  query_arc at its most samples (kMaxPathSamples = 256 poses, a turning arc: every
//             pose walked as a footprint) with the largest body the footprint limit admits
//   region 7  register_frame_sensor at its largest: kMaxRegistrationPoints samples of a frame
//             whose pose is 8 cm and 0.03 rad off, up to kMaxRegistrationIterations iterations
//             (a convergence threshold no step meets; the model-fit stop still ends it)
//   region 8  publish_product of each layer's window, the stack's answers (5 intervals)
//   region 9  move_to(x, y, sigma): the motion pass over every cell of the mapped stack
//   region 10 move_to over 2.52, 5.04, 10.0, 20.0 and 100 m (each from the origin): the move
//             that clears each layer's cells one by one (a shift of almost its side), and the
//             jump that replaces every window (5 intervals)
//   region 11 fill_costmap as region 5 at 2 cm with a row budget of 64 rows (CostmapSpec::max_rows)
// Under qemu-aarch64 with the plugin the ctest prints and checks the counts; elsewhere the
// markers are empty and this only checks the calls' results.
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/product/publish.hpp"
#include "ccmap/registration/registration.hpp"
#include "support/cadre_frames.hpp"
#include "support/icount_marker.hpp"

namespace {
int fail(const char* what) {
  std::fprintf(stderr, "icount_worst_case: %s\n", what);
  return 1;
}
}  // namespace

int main() {
  using namespace ccmap;
  using CadreStack = Stack<CadreConfig>;
  const auto stack = std::make_unique<CadreStack>();  // on the heap, as the timing test's
  test::icount_begin<1>();
  const Status calibrated = stack->init(default_stack_params(0.04F));
  test::icount_end<1>();
  if (calibrated != Status::kOk) return fail("init (calibrating) refused");
  StackParams given = default_stack_params(0.04F);
  for (int layer = 0; layer < CadreStack::kLayerCount; ++layer) {
    given.normal_variance_threshold[static_cast<std::size_t>(layer)] = stack->normal_variance_threshold(layer);
  }
  test::icount_begin<2>();
  const Status uncalibrated = stack->init(given);
  test::icount_end<2>();
  if (uncalibrated != Status::kOk) return fail("init (thresholds given) refused");
  for (int k = 0; k < 3; ++k) {
    const test::CadreFrame frame = test::make_cadre_frame(test::cadre_sequence_spec(k, 400, 250));
    if (stack->update_frame_sensor(frame.sensor_points.data(), frame.sensor_points.size(), frame.pose, nullptr) !=
        Status::kOk) {
      return fail("update refused");
    }
  }

  std::vector<std::uint8_t> snapshot(snapshot_size<CadreConfig>());
  std::size_t written = 0U;
  test::icount_begin<3>();
  const Status saved = save_snapshot(*stack, snapshot.data(), snapshot.size(), &written);
  test::icount_end<3>();
  test::icount_begin<4>();
  const Status loaded = load_snapshot(*stack, snapshot.data(), written);
  test::icount_end<4>();
  if (saved != Status::kOk || loaded != Status::kOk) return fail("snapshot round trip refused");

  std::vector<std::uint8_t> cost(std::size_t{kMaxCostmapSide} * kMaxCostmapSide);
  CostmapStats stats{};
  for (const float pixel_m : {0.01F, 0.02F, 0.04F}) {
    const CostmapSpec raster{0.0F, 0.0F, pixel_m, kMaxCostmapSide, pixel_m * static_cast<float>(kMaxInflationPixels)};
    test::icount_begin<5>();
    const Status filled = fill_costmap(*stack, raster, cost.data(), cost.size(), &stats);
    test::icount_end<5>();
    if (filled != Status::kOk || stats.free + stats.cost == 0U) return fail("the largest costmap refused or empty");
  }

  // 256 poses 2 cm apart along a left turn of 0.5 / m, a 1.7 m square body (its bounding box at
  // 45 deg: 2.40 m, within kMaxFootprintCells' 2.56 m); max_unknown_share 1: no pose stops it.
  const PathSweep sweep{1.7F, 1.7F, 0.02F, 1.0F};
  const PathPose start{0.0F, -1.0F, 1.0F, 0.0F};
  test::icount_begin<6>();
  const PathResult arc = query_arc(*stack, start, 0.5F, 0.02F * static_cast<float>(kMaxPathSamples - 1U), sweep);
  test::icount_end<6>();
  if (arc.status != Status::kOk || arc.samples != kMaxPathSamples) return fail("the longest path refused or cut short");

  const test::CadreFrame probe = test::make_cadre_frame(test::cadre_sequence_spec(1, 330, 200));
  Pose off = probe.pose;  // the estimate the registration corrects: 8 cm, 0.03 rad off
  off.translation.x += 0.06F;
  off.translation.y -= 0.05F;
  const float c = 0.99955003F;  // cos 0.03
  const float sn = 0.0299955F;  // sin 0.03
  for (int col = 0; col < 3; ++col) {
    const float r0 = probe.pose.rotation[0][col];
    const float r1 = probe.pose.rotation[1][col];
    off.rotation[0][col] = c * r0 - sn * r1;
    off.rotation[1][col] = sn * r0 + c * r1;
  }
  RegistrationParams rp = default_registration_params();
  rp.max_points = kMaxRegistrationPoints;
  rp.max_iterations = kMaxRegistrationIterations;
  rp.convergence_m = 1.0e-30F;
  test::icount_begin<7>();
  const RegistrationResult reg = ccmap::register_frame_sensor(*stack, probe.sensor_points.data(), probe.sensor_points.size(),
                                                              off, rp);
  test::icount_end<7>();
  if (reg.status != Status::kOk && reg.status != Status::kNotConverged) return fail("registration refused");

  std::vector<std::uint32_t> product_storage(3U * product_size(kProductMaxSide, 64U) / 4U + 3U);
  ProductBuffers buffers{};
  if (product_buffers_init(&buffers, product_storage.data(), product_storage.size() * 4U) != Status::kOk) {
    return fail("product buffers refused");
  }
  for (int layer = 0; layer < CadreStack::kLayerCount; ++layer) {
    ProductSpec spec{};
    spec.layer = layer;
    test::icount_begin<8>();
    const Status published = publish_product(*stack, spec, buffers);
    test::icount_end<8>();
    if (published != Status::kOk) return fail("publish refused");
  }

  test::icount_begin<9>();
  const Status faded = stack->move_to(0.04F, 0.0F, 0.005F);
  test::icount_end<9>();
  if (faded != Status::kOk) return fail("move refused");
  CostmapSpec budgeted{0.0F, 0.0F, 0.02F, kMaxCostmapSide, 0.02F * static_cast<float>(kMaxInflationPixels)};
  budgeted.max_rows = 64U;
  CostmapStats band{};
  test::icount_begin<11>();
  const Status banded = fill_costmap(*stack, budgeted, cost.data(), cost.size(), &band);
  test::icount_end<11>();
  if (banded != Status::kOk || band.rows_skipped != kMaxCostmapSide - 64U) return fail("the budgeted costmap");
  for (const float jump_m : {2.52F, 5.04F, 10.0F, 20.0F, 100.0F}) {
    if (stack->move_to(0.0F, 0.0F) != Status::kOk) return fail("move back refused");
    test::icount_begin<10>();
    const Status jumped = stack->move_to(jump_m, 0.0F);
    test::icount_end<10>();
    if (jumped != Status::kOk) return fail("move refused");
  }
  std::printf("icount_worst_case: costmap %u free, %u cost, %u unknown, %u lethal pixels; path %u poses; "
              "registration %u iterations\n",
              stats.free, stats.cost, stats.unknown, stats.lethal, arc.samples, reg.iterations);
  return 0;
}
