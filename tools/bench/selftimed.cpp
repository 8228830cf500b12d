// ccmap_bench_selftimed: the benchmark cases of docs/performance.md timed with the platform clock
// (ccmap::platform::monotonic_ns), so that it runs wherever the library runs: on the host and,
// cross-built, under QEMU user mode (no Google Benchmark there). One line per result:
//   <case> <median> <unit>  (min <min>, max <max>, <reps> reps)
// Frames are the synthetic CADRE frames of tests/support/cadre_frames.hpp.
//
//   ccmap_bench_selftimed [reps]     (default 10 repetitions per case; --help; a bad count: exit 2)
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/platform/platform.hpp"
#include "parse_args.hpp"
#include "support/cadre_frames.hpp"
#include "support/flight_cycle.hpp"

namespace {

using ccmap::platform::monotonic_ns;

struct Stats {
  double median;
  double min;
  double max;
};

Stats stats(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  const double median = n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  return Stats{median, v.front(), v.back()};
}

void report(const char* name, const std::vector<double>& values, const char* unit) {
  const Stats s = stats(values);
  std::printf("%-44s %12.3f %-8s (min %.3f, max %.3f, %zu reps)\n", name, s.median, unit, s.min, s.max, values.size());
}

template <typename Config>
std::unique_ptr<ccmap::Stack<Config>> make_stack(float finest_width) {
  auto stack = std::make_unique<ccmap::Stack<Config>>();
  if (stack->init(ccmap::default_stack_params(finest_width)) != ccmap::Status::kOk) {
    std::fprintf(stderr, "init failed\n");
    std::exit(1);
  }
  return stack;
}

/// Milliseconds per update of `frames` (cycled), one sample per frame; the stack keeps folding.
template <typename Config>
std::vector<double> time_frames(ccmap::Stack<Config>& stack, const std::vector<ccmap::test::CadreFrame>& frames,
                                int reps, bool sensor_frame) {
  std::vector<double> ms;
  for (int r = 0; r < reps; ++r) {
    const ccmap::test::CadreFrame& f = frames[static_cast<std::size_t>(r) % frames.size()];
    const std::uint64_t t0 = monotonic_ns();
    const ccmap::Status status =
        sensor_frame ? stack.update_frame_sensor(f.sensor_points.data(), f.sensor_points.size(), f.pose, nullptr)
                     : stack.update_frame(f.map_points.data(), f.map_points.size(), f.sensor_origin, nullptr);
    const std::uint64_t t1 = monotonic_ns();
    if (status != ccmap::Status::kOk) {
      std::fprintf(stderr, "update failed\n");
      std::exit(1);
    }
    ms.push_back(static_cast<double>(t1 - t0) * 1e-6);
  }
  return ms;
}

std::vector<ccmap::test::CadreFrame> frames_of(int count, int width, int height) {
  std::vector<ccmap::test::CadreFrame> frames;
  for (int k = 0; k < count; ++k) {
    frames.push_back(ccmap::test::make_cadre_frame(ccmap::test::cadre_sequence_spec(k, width, height)));
  }
  return frames;
}

template <typename Config>
void per_point_cost(const char* name, float width, const std::vector<ccmap::test::CadreFrame>& frames, int reps) {
  auto stack = make_stack<Config>(width);
  std::vector<double> ns;
  for (double ms : time_frames(*stack, frames, reps, false)) {
    ns.push_back(ms * 1e6 / static_cast<double>(frames[0].map_points.size()));
  }
  report(name, ns, "ns/point");
}

/// The flight cycle of the timing test, `reps` cycles of the ten-frame drive: wall and thread CPU.
template <typename Config>
void flight_cycle(const char* name, int reps) {
  auto stack = make_stack<Config>(0.04F);
  std::vector<double> wall;
  std::vector<double> cpu;
  for (int r = 0; r < reps; ++r) {
    const int k = r % 10;
    const ccmap::test::CadreFrame frame = ccmap::test::cycle_frame(k);
    const std::uint64_t c0 = ccmap::platform::thread_cpu_ns();
    const std::uint64_t t0 = monotonic_ns();
    const ccmap::test::CycleOutcome o = ccmap::test::run_cycle(*stack, ccmap::test::cycle_pose(k), frame);
    wall.push_back(static_cast<double>(monotonic_ns() - t0) * 1e-6);
    cpu.push_back(static_cast<double>(ccmap::platform::thread_cpu_ns() - c0) * 1e-6);
    if (!ccmap::test::cycle_ok(o, frame.sensor_points.size())) {
      std::fprintf(stderr, "%s %d failed\n", name, r);
      std::exit(1);
    }
  }
  char label[64];
  std::snprintf(label, sizeof label, "%s (wall)", name);
  report(label, wall, "ms");
  std::snprintf(label, sizeof label, "%s (thread CPU)", name);
  report(label, cpu, "ms");
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ccmap;
  int reps = 10;
  CLI::App app("The benchmark cases of docs/performance.md timed with the platform clock.", "ccmap_bench_selftimed");
  app.add_option("reps", reps, "repetitions per case")->check(CLI::Range(1, 1000000))->capture_default_str();
  if (const int code = tools::parse_args(app, argc, argv); code >= 0) return code;
  std::printf("# ccmap_bench_selftimed: platform %s, %d reps, synthetic CADRE frames\n", platform::name(), reps);

  // Static memory of each preset (the whole map is one object).
  std::printf("%-44s %12zu bytes\n", "sizeof Stack<CadreConfig>", sizeof(Stack<CadreConfig>));
  std::printf("%-44s %12zu bytes\n", "sizeof Stack<SingleCcmConfig>", sizeof(Stack<SingleCcmConfig>));
  std::printf("%-44s %12zu bytes\n", "sizeof Stack<SingleKalmanConfig>", sizeof(Stack<SingleKalmanConfig>));
  std::printf("%-44s %12zu bytes\n", "sizeof Stack<SingleOmgConfig>", sizeof(Stack<SingleOmgConfig>));
  std::printf("%-44s %12zu bytes\n", "sizeof Stack<PaperCell<CadreConfig>>", sizeof(Stack<PaperCell<CadreConfig>>));

  // The flight cycle of the timing test (move, sensor-frame update, corridor queries), with the
  // full and with the paper's CCM cell (the difference is the lateral covariance's cost).
  flight_cycle<CadreConfig>("flight cycle", reps);
  flight_cycle<PaperCell<CadreConfig>>("flight cycle, paper cell", reps);
  // Full frame updates on the CADRE preset.
  {
    const auto cadre = frames_of(3, 850, 650);
    auto stack = make_stack<CadreConfig>(0.04F);
    report("cadre frame 552500 pts, map frame", time_frames(*stack, cadre, reps, false), "ms");
    report("cadre frame 552500 pts, sensor frame", time_frames(*stack, cadre, reps, true), "ms");
    auto paper = make_stack<PaperCell<CadreConfig>>(0.04F);
    report("cadre frame, map frame, paper cell", time_frames(*paper, cadre, reps, false), "ms");
    report("cadre frame, sensor frame, paper cell", time_frames(*paper, cadre, reps, true), "ms");
  }
  {
    const auto small = frames_of(3, 125, 80);
    auto stack = make_stack<CadreConfig>(0.04F);
    report("cadre frame 10000 pts", time_frames(*stack, small, reps, false), "ms");
  }
  const auto medium = frames_of(3, 400, 250);
  {
    auto stack = make_stack<CadreConfig>(0.04F);
    report("cadre frame 100000 pts", time_frames(*stack, medium, reps, false), "ms");
  }
  // Per-point cost of each cell kind in the same run: one-layer stacks, 8 cm cells.
  per_point_cost<SingleCcmConfig>("per point, CCM cell (SingleCcm)", 0.08F, medium, reps);
  per_point_cost<PaperCell<SingleCcmConfig>>("per point, CCM paper cell", 0.08F, medium, reps);
  per_point_cost<SingleKalmanConfig>("per point, Kalman cell (SingleKalman)", 0.08F, medium, reps);
  per_point_cost<SingleOmgConfig>("per point, OMG cell (SingleOmg)", 0.08F, medium, reps);

  // Queries on a mapped CADRE stack.
  {
    const auto cadre = frames_of(2, 850, 650);
    auto stack = make_stack<CadreConfig>(0.04F);
    (void)time_frames(*stack, cadre, 2, false);
    constexpr int kQueries = 20000;
    std::vector<double> fine_ns;
    std::vector<double> coarse_ns;
    volatile float sink = 0.0F;
    for (int r = 0; r < reps; ++r) {
      std::uint64_t t0 = monotonic_ns();
      for (int q = 0; q < kQueries; ++q) {  // finest cells, 0.3 .. 1.1 m ahead
        const QueryResult res = stack->query(0.3F + 0.00004F * static_cast<float>(q), 0.2F - 0.00002F * static_cast<float>(q));
        sink = sink + res.height_m;
      }
      fine_ns.push_back(static_cast<double>(monotonic_ns() - t0) / kQueries);
      t0 = monotonic_ns();
      for (int q = 0; q < kQueries; ++q) {  // the 64 cm layer: pooled from every finer layer
        const QueryResult res = stack->query_layer(4, 0.5F + 0.0001F * static_cast<float>(q), 0.1F);
        sink = sink + res.height_m;
      }
      coarse_ns.push_back(static_cast<double>(monotonic_ns() - t0) / kQueries);
    }
    report("query, finest cell (Kalman + CCM refine)", fine_ns, "ns/query");
    report("query, 64 cm cell pooled from all layers", coarse_ns, "ns/query");
    // A move of the stack by 1 m (and back): clears the cells that leave every window.
    std::vector<double> move_us;
    for (int r = 0; r < reps; ++r) {
      const std::uint64_t t0 = monotonic_ns();
      (void)stack->move_to(r % 2 == 0 ? 1.0F : 0.0F, 0.0F);
      move_us.push_back(static_cast<double>(monotonic_ns() - t0) * 1e-3);
    }
    report("move_to, 1 m step", move_us, "us");
    (void)stack->move_to(0.0F, 0.0F);

    // Planner queries (planner/footprint.hpp, path_query.hpp, costmap.hpp) on the same map.
    std::vector<double> body_us, large_us, path_us, cost_us, inflated_us;
    std::vector<std::uint8_t> cost(125U * 125U);
    const PathPoint route[] = {{0.3F, 0.0F}, {2.3F, 0.0F}};
    for (int r = 0; r < reps; ++r) {
      std::uint64_t t0 = monotonic_ns();
      sink = sink + query_footprint(*stack, Footprint{0.9F, 0.05F, 1.0F, 0.0F, 0.6F, 0.4F}).max_step_m;
      body_us.push_back(static_cast<double>(monotonic_ns() - t0) * 1e-3);
      t0 = monotonic_ns();
      sink = sink + query_footprint(*stack, Footprint{1.0F, 0.05F, 0.8F, 0.6F, 2.0F, 1.0F}).max_step_m;
      large_us.push_back(static_cast<double>(monotonic_ns() - t0) * 1e-3);
      t0 = monotonic_ns();
      sink = sink + query_path(*stack, route, 2, PathSweep{0.6F, 0.4F, 0.05F, 1.0F}).checked_m;
      path_us.push_back(static_cast<double>(monotonic_ns() - t0) * 1e-3);
      CostmapStats st{};
      t0 = monotonic_ns();
      (void)fill_costmap(*stack, CostmapSpec{0.0F, 0.0F, 0.04F, 125U, 0.0F}, cost.data(), cost.size(), &st);
      cost_us.push_back(static_cast<double>(monotonic_ns() - t0) * 1e-3);
      t0 = monotonic_ns();
      (void)fill_costmap(*stack, CostmapSpec{0.0F, 0.0F, 0.04F, 125U, 0.3F}, cost.data(), cost.size(), &st);
      inflated_us.push_back(static_cast<double>(monotonic_ns() - t0) * 1e-3);
    }
    report("footprint 0.6 x 0.4 m", body_us, "us");
    report("footprint 2 x 1 m at 37 deg", large_us, "us");
    report("path 2 m, 0.6 x 0.4 m body every 5 cm", path_us, "us");
    report("cost raster 5 x 5 m at 4 cm", cost_us, "us");
    report("cost raster 5 x 5 m at 4 cm, 0.3 m inflation", inflated_us, "us");
    // Last: the fading changes the weights the cases above read.
    std::vector<double> uncertain_us;
    for (int r = 0; r < reps; ++r) {
      const std::uint64_t t0 = monotonic_ns();
      (void)stack->move_to(0.0F, 0.0F, 0.005F);
      uncertain_us.push_back(static_cast<double>(monotonic_ns() - t0) * 1e-3);
    }
    report("move_to with uncertainty (every cell)", uncertain_us, "us");
  }
  return 0;
}
