// ccmap_bench: host benchmarks (Google Benchmark) of the update path, the cells, queries,
// moves, and the static memory of each preset. docs/performance.md lists the results and the
// command; tools/bench/run runs this and the self-timed program (host and QEMU).
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/map/stack.hpp"
#include "support/cadre_frames.hpp"
#include "support/flight_cycle.hpp"

namespace {

using ccmap::test::CadreFrame;

const std::vector<CadreFrame>& frames(int width, int height) {
  static std::vector<std::vector<CadreFrame>> cache;
  static std::vector<std::pair<int, int>> keys;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (keys[i] == std::make_pair(width, height)) {
      return cache[i];
    }
  }
  std::vector<CadreFrame> made;
  for (int k = 0; k < 3; ++k) {
    made.push_back(ccmap::test::make_cadre_frame(ccmap::test::cadre_sequence_spec(k, width, height)));
  }
  keys.emplace_back(width, height);
  cache.push_back(std::move(made));
  return cache.back();
}

template <typename Config>
std::unique_ptr<ccmap::Stack<Config>> make_stack(float width) {
  auto stack = std::make_unique<ccmap::Stack<Config>>();
  if (stack->init(ccmap::default_stack_params(width)) != ccmap::Status::kOk) {
    std::abort();
  }
  return stack;
}

enum class Path { kMapFrame, kSensorFrame };

template <typename Config>
void frame_update(benchmark::State& state, int width, int height, float cell, Path path) {
  const auto& fs = frames(width, height);
  auto stack = make_stack<Config>(cell);
  std::size_t k = 0;
  for (auto _ : state) {
    const CadreFrame& f = fs[k++ % fs.size()];
    ccmap::Status s = ccmap::Status::kOk;
    switch (path) {
      case Path::kMapFrame: s = stack->update_frame(f.map_points.data(), f.map_points.size(), f.sensor_origin, nullptr); break;
      case Path::kSensorFrame: s = stack->update_frame_sensor(f.sensor_points.data(), f.sensor_points.size(), f.pose, nullptr); break;
    }
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * width * height);
  state.counters["ns_per_point"] = benchmark::Counter(static_cast<double>(state.iterations()) * width * height,
                                                      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_CadreFrame(benchmark::State& s) { frame_update<ccmap::CadreConfig>(s, 850, 650, 0.04F, Path::kMapFrame); }
void BM_CadreFrameSensor(benchmark::State& s) { frame_update<ccmap::CadreConfig>(s, 850, 650, 0.04F, Path::kSensorFrame); }
void BM_CadreFrame10k(benchmark::State& s) { frame_update<ccmap::CadreConfig>(s, 125, 80, 0.04F, Path::kMapFrame); }
void BM_CadreFrame100k(benchmark::State& s) { frame_update<ccmap::CadreConfig>(s, 400, 250, 0.04F, Path::kMapFrame); }
void BM_CellCcm(benchmark::State& s) { frame_update<ccmap::SingleCcmConfig>(s, 400, 250, 0.08F, Path::kMapFrame); }
void BM_CellKalman(benchmark::State& s) { frame_update<ccmap::SingleKalmanConfig>(s, 400, 250, 0.08F, Path::kMapFrame); }
void BM_CellOmg(benchmark::State& s) { frame_update<ccmap::SingleOmgConfig>(s, 400, 250, 0.08F, Path::kMapFrame); }
// The same with the paper's 9-float CCM cell (PaperCell<Config>): the cost of the lateral
// covariance is the difference (docs/performance.md).
using PaperCadre = ccmap::PaperCell<ccmap::CadreConfig>;
void BM_CadreFramePaperCell(benchmark::State& s) { frame_update<PaperCadre>(s, 850, 650, 0.04F, Path::kMapFrame); }
void BM_CadreFrameSensorPaperCell(benchmark::State& s) { frame_update<PaperCadre>(s, 850, 650, 0.04F, Path::kSensorFrame); }
void BM_CellCcmPaperCell(benchmark::State& s) {
  frame_update<ccmap::PaperCell<ccmap::SingleCcmConfig>>(s, 400, 250, 0.08F, Path::kMapFrame);
}
// The flight cycle of the timing test (tests/support/flight_cycle.hpp): move_to, a sensor-frame
// frame with 8 % unusable pixels, the corridor footprint and the 2 m path; ten frames of the drive, cycled.
void BM_FlightCycle(benchmark::State& state) {
  static const std::vector<CadreFrame> drive = [] {
    std::vector<CadreFrame> f;
    for (int k = 0; k < 10; ++k) f.push_back(ccmap::test::cycle_frame(k));
    return f;
  }();
  auto stack = make_stack<ccmap::CadreConfig>(0.04F);
  std::size_t k = 0;
  for (auto _ : state) {
    const int cycle = static_cast<int>(k++ % drive.size());
    benchmark::DoNotOptimize(ccmap::test::run_cycle(*stack, ccmap::test::cycle_pose(cycle), drive[static_cast<std::size_t>(cycle)]));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * 850 * 650);
}
BENCHMARK(BM_FlightCycle)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CadreFrame)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CadreFrameSensor)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CadreFrame10k)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CadreFrame100k)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CellCcm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CellKalman)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CellOmg)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CadreFramePaperCell)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CadreFrameSensorPaperCell)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CellCcmPaperCell)->Unit(benchmark::kMicrosecond);

ccmap::Stack<ccmap::CadreConfig>& mapped_cadre() {
  static std::unique_ptr<ccmap::Stack<ccmap::CadreConfig>> stack = [] {
    auto s = make_stack<ccmap::CadreConfig>(0.04F);
    for (const CadreFrame& f : frames(850, 650)) {
      (void)s->update_frame(f.map_points.data(), f.map_points.size(), f.sensor_origin, nullptr);
    }
    return s;
  }();
  return *stack;
}

void BM_QueryFinest(benchmark::State& state) {
  const auto& stack = mapped_cadre();
  int q = 0;
  for (auto _ : state) {
    const float t = static_cast<float>(q++ & 16383);
    benchmark::DoNotOptimize(stack.query(0.3F + 0.00004F * t, 0.2F - 0.00002F * t));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
void BM_QueryCoarsePooled(benchmark::State& state) {
  const auto& stack = mapped_cadre();
  int q = 0;
  for (auto _ : state) {
    const float t = static_cast<float>(q++ & 16383);
    benchmark::DoNotOptimize(stack.query_layer(4, 0.5F + 0.0001F * t, 0.1F));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_QueryFinest);
BENCHMARK(BM_QueryCoarsePooled);

void BM_Move1m(benchmark::State& state) {
  auto& stack = mapped_cadre();
  int k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(stack.move_to((k++ & 1) != 0 ? 1.0F : 0.0F, 0.0F));
  }
}
BENCHMARK(BM_Move1m)->Unit(benchmark::kMicrosecond);

void BM_MoveUncertain(benchmark::State& state) {
  // Its own map: the fading changes the weights the other cases read.
  auto stack = make_stack<ccmap::CadreConfig>(0.04F);
  for (const CadreFrame& f : frames(850, 650)) {
    (void)stack->update_frame(f.map_points.data(), f.map_points.size(), f.sensor_origin, nullptr);
  }
  for (auto _ : state) {
    benchmark::DoNotOptimize(stack->move_to(0.0F, 0.0F, 0.005F));
  }
}
BENCHMARK(BM_MoveUncertain)->Unit(benchmark::kMicrosecond);

// Planner queries on the mapped CADRE stack: the rover body 0.6 m x 0.4 m 0.9 m ahead, a
// 2 m x 1 m body at 37 deg, a 2 m path (a footprint every 5 cm, all 41 evaluated: no footprint
// counts as unknown with max_unknown_share 1), a 5 m x 5 m cost raster at 4 cm.
void BM_Footprint(benchmark::State& state) {
  const auto& stack = mapped_cadre();
  for (auto _ : state) {
    benchmark::DoNotOptimize(ccmap::query_footprint(stack, ccmap::Footprint{0.9F, 0.05F, 1.0F, 0.0F, 0.6F, 0.4F}));
  }
}
void BM_FootprintLarge(benchmark::State& state) {
  const auto& stack = mapped_cadre();
  for (auto _ : state) {
    benchmark::DoNotOptimize(ccmap::query_footprint(stack, ccmap::Footprint{1.0F, 0.05F, 0.8F, 0.6F, 2.0F, 1.0F}));
  }
}
void BM_Path2m(benchmark::State& state) {
  const auto& stack = mapped_cadre();
  const ccmap::PathPoint route[] = {{0.3F, 0.0F}, {2.3F, 0.0F}};
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        ccmap::query_path(stack, route, 2, ccmap::PathSweep{0.6F, 0.4F, 0.05F, 1.0F}));
  }
}
void BM_Costmap5m(benchmark::State& state) {
  const auto& stack = mapped_cadre();
  std::vector<std::uint8_t> cost(125U * 125U);
  const float radius = static_cast<float>(state.range(0)) * 0.01F;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        ccmap::fill_costmap(stack, ccmap::CostmapSpec{0.0F, 0.0F, 0.04F, 125U, radius}, cost.data(), cost.size(), nullptr));
  }
}
// The flight cycle's corridor (1 m x 2 m, 0.3 .. 2.3 m ahead) after three cycles of the drive:
// the 1250 per-cell point queries (test::corridor_queries), and the footprint query run_cycle asks.
const ccmap::Stack<ccmap::CadreConfig>& cycle_map() {
  static std::unique_ptr<ccmap::Stack<ccmap::CadreConfig>> stack = [] {
    auto s = make_stack<ccmap::CadreConfig>(0.04F);
    for (int k = 0; k < 3; ++k) {
      const ccmap::test::CyclePose p = ccmap::test::cycle_pose(k);
      const CadreFrame f = ccmap::test::cycle_frame(k);
      (void)s->move_to(p.x, p.y);
      (void)s->update_frame_sensor(f.sensor_points.data(), f.sensor_points.size(), f.pose, nullptr);
    }
    return s;
  }();
  return *stack;
}
void BM_CorridorCells(benchmark::State& state) {
  const auto& stack = cycle_map();
  const ccmap::test::CyclePose p = ccmap::test::cycle_pose(2);
  for (auto _ : state) {
    int hazards = 0;
    benchmark::DoNotOptimize(ccmap::test::corridor_queries(stack, p, &hazards));
    benchmark::DoNotOptimize(hazards);
  }
}
void BM_CorridorFootprint(benchmark::State& state) {
  const auto& stack = cycle_map();
  const ccmap::test::CyclePose p = ccmap::test::cycle_pose(2);
  const ccmap::Footprint corridor = ccmap::test::corridor_footprint(p);
  for (auto _ : state) {
    benchmark::DoNotOptimize(ccmap::query_footprint(stack, corridor));
  }
}
BENCHMARK(BM_CorridorCells)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_CorridorFootprint)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Footprint)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FootprintLarge)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Path2m)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Costmap5m)->Arg(0)->Arg(30)->Unit(benchmark::kMicrosecond);

void BM_StaticMemory(benchmark::State& state) {
  for (auto _ : state) {
  }
  state.counters["CadreConfig_bytes"] = static_cast<double>(sizeof(ccmap::Stack<ccmap::CadreConfig>));
  state.counters["CadreConfig_paper_cell_bytes"] = static_cast<double>(sizeof(ccmap::Stack<PaperCadre>));
  state.counters["SingleCcmConfig_bytes"] = static_cast<double>(sizeof(ccmap::Stack<ccmap::SingleCcmConfig>));
  state.counters["SingleKalmanConfig_bytes"] = static_cast<double>(sizeof(ccmap::Stack<ccmap::SingleKalmanConfig>));
  state.counters["SingleOmgConfig_bytes"] = static_cast<double>(sizeof(ccmap::Stack<ccmap::SingleOmgConfig>));
}
BENCHMARK(BM_StaticMemory)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
