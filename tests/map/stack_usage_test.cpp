// Stack usage of every public call, measured by stack painting: each call runs on a thread whose
// stack is a static buffer; just before the call the thread paints everything below its own
// frame with a pattern, and the deepest byte no longer holding it after the call gives the
// call's high-water mark (minus the same measurement of a no-op call: the harness's own share).
// Portable: runs under QEMU too.
//
// Contract (docs/integration.md): every public call of Stack<CadreConfig> (and the planner queries
// over it: planner/footprint.hpp, planner/path_query.hpp, planner/costmap.hpp) uses < 4 KiB of stack
// in an optimised build (asserted when built with optimisation and without sanitizers; debug and
// sanitizer builds only report). Worst cases: query/export pool recursively over all layers
// (depth <= layer count), so the deepest call is measured with data in every layer.
// tools/stack-usage gives the static figure from -fstack-usage/-fcallgraph-info.
#include <gtest/gtest.h>
#include <pthread.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/registration/registration.hpp"
#include "support/poses.hpp"

// tests/map/stack_instances.cpp
extern template class ccmap::Stack<ccmap::CadreConfig>;
extern template ccmap::FootprintResult ccmap::query_footprint<ccmap::CadreConfig>(
    const ccmap::Stack<ccmap::CadreConfig>&, const ccmap::Footprint&) noexcept;
extern template ccmap::PathResult ccmap::query_path<ccmap::CadreConfig>(const ccmap::Stack<ccmap::CadreConfig>&,
                                                                       const ccmap::PathPoint*, std::size_t,
                                                                       const ccmap::PathSweep&) noexcept;
extern template ccmap::PathResult ccmap::query_arc<ccmap::CadreConfig>(const ccmap::Stack<ccmap::CadreConfig>&,
                                                                      const ccmap::PathPose&, float, float,
                                                                      const ccmap::PathSweep&) noexcept;
extern template ccmap::Status ccmap::fill_costmap<ccmap::CadreConfig>(const ccmap::Stack<ccmap::CadreConfig>&,
                                                                     const ccmap::CostmapSpec&, std::uint8_t*,
                                                                     std::size_t, ccmap::CostmapStats*) noexcept;

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CCMAP_STACK_SANITIZED 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define CCMAP_STACK_SANITIZED 1
#endif
#if defined(__OPTIMIZE__) && !defined(CCMAP_STACK_SANITIZED)
constexpr bool kAssertLimit = true;
#else
constexpr bool kAssertLimit = false;
#endif

namespace ccmap {
namespace {

using S = Stack<CadreConfig>;
constexpr std::size_t kLimitBytes = 4096;
constexpr std::size_t kThreadStackBytes = 256 * 1024;  // >= PTHREAD_STACK_MIN + TLS, anywhere
constexpr unsigned char kPattern = 0xA5;
alignas(64) unsigned char g_thread_stack[kThreadStackBytes];

struct Job {
  void (*fn)(void*);
  void* context;
  std::size_t used;
};

/// Runs on the painted thread: repaints everything below its own frame (the thread start-up
/// code may have written there), calls the job, then finds the deepest byte written (the stack
/// grows down: the untouched pattern is at the low end) and records its distance from here.
void* trampoline(void* arg) {
  Job* job = static_cast<Job*>(arg);
  // The current stack pointer; bytes below it (minus the x86-64 red zone and memset's return
  // address) are free and get repainted.
#if defined(__x86_64__)
  unsigned char* here = nullptr;
  asm volatile("mov %%rsp, %0" : "=r"(here));
  constexpr std::size_t kKeep = 128;
#elif defined(__aarch64__)
  unsigned char* here = nullptr;
  asm volatile("mov %0, sp" : "=r"(here));
  constexpr std::size_t kKeep = 128;
#else
  volatile unsigned char marker = 0;
  unsigned char* const here = const_cast<unsigned char*>(&marker);
  constexpr std::size_t kKeep = 512;  // this frame and memset's own, untouched by the repaint
#endif
  const std::size_t below = static_cast<std::size_t>(here - g_thread_stack);
  if (below > kKeep) std::memset(g_thread_stack, kPattern, below - kKeep);
  job->fn(job->context);
  std::size_t untouched = 0;
  while (untouched < below && g_thread_stack[untouched] == kPattern) ++untouched;
  job->used = below - untouched;  // from this frame's stack pointer down to the deepest write
  return nullptr;
}

/// Bytes of stack below the trampoline's frame touched while running fn(context).
std::size_t high_water(void (*fn)(void*), void* context) {
  pthread_attr_t attr;
  EXPECT_EQ(pthread_attr_init(&attr), 0);
  EXPECT_EQ(pthread_attr_setstack(&attr, g_thread_stack, sizeof g_thread_stack), 0);
  Job job{fn, context, 0U};
  pthread_t thread;
  EXPECT_EQ(pthread_create(&thread, &attr, trampoline, &job), 0);
  EXPECT_EQ(pthread_join(thread, nullptr), 0);
  pthread_attr_destroy(&attr);
  return job.used;
}

struct Fixture {
  std::unique_ptr<S> stack = std::make_unique<S>();
  std::vector<PointXYZ> points;
  std::vector<CellRecord> records = std::vector<CellRecord>(64 * 64);
  std::vector<std::uint8_t> cost = std::vector<std::uint8_t>(125 * 125);
  std::vector<PathPoint> path = std::vector<PathPoint>{PathPoint{0.0F, 0.0F}, PathPoint{2.0F, 0.3F}};
  PathSweep sweep{0.6F, 0.4F, 0.05F, 0.1F};
  PathPose start{0.0F, 0.0F, 1.0F, 0.0F};
  Pose pose;
  volatile float sink = 0.0F;  // keeps results alive
  Fixture() {
    EXPECT_EQ(stack->init(default_stack_params(0.04F)), Status::kOk);
    for (float y = -5.0F; y < 5.0F; y += 0.05F) {
      for (float x = -5.0F; x < 5.0F; x += 0.05F) points.push_back(PointXYZ{x, y, -0.5F + 0.02F * x});
    }
    EXPECT_EQ(stack->update_frame(points.data(), points.size(), PointXYZ{0.0F, 0.0F, 0.0F}, nullptr), Status::kOk);
    pose = test::identity_pose(PointXYZ{0.0F, 0.0F, 0.5F});
  }
};

#define CCMAP_CALL(name, body)                       \
  {                                                  \
    name, [](void* p) {                              \
      Fixture& f = *static_cast<Fixture*>(p);        \
      (void)f;                                       \
      body;                                          \
    }                                                \
  }

struct Call {
  const char* name;
  void (*fn)(void*);
};

TEST(StackUsage, EveryPublicCallUsesLessThanFourKiB) {
  Fixture fixture;
  const Call calls[] = {
      CCMAP_CALL("noop", {}),
      CCMAP_CALL("init", { f.sink = f.stack->init(default_stack_params(0.04F)) == Status::kOk ? 1.0F : 0.0F; }),
      CCMAP_CALL("update_frame", {
        FrameCounters c{};
        f.sink = f.stack->update_frame(f.points.data(), f.points.size(), PointXYZ{0.0F, 0.0F, 0.0F}, &c) ==
                         Status::kOk ? static_cast<float>(c.used) : -1.0F;
      }),
      CCMAP_CALL("update_frame_sensor", {
        FrameCounters c{};
        f.sink = f.stack->update_frame_sensor(f.points.data(), 2000U, f.pose, &c) == Status::kOk ? 1.0F : 0.0F;
      }),
      CCMAP_CALL("move_to (1 cell)", { f.sink = f.stack->move_to(0.04F, 0.0F) == Status::kOk ? 1.0F : 0.0F; }),
      CCMAP_CALL("move_to (back)", { f.sink = f.stack->move_to(0.0F, 0.0F) == Status::kOk ? 1.0F : 0.0F; }),
      CCMAP_CALL("query (fine)", { f.sink = f.stack->query(0.3F, 0.2F).height_m; }),
      CCMAP_CALL("query (coarse, through every layer)", { f.sink = f.stack->query(8.0F, 8.0F).height_m; }),
      CCMAP_CALL("query_layer (coarsest, pooled over all)", { f.sink = f.stack->query_layer(4, 0.5F, 0.5F).height_m; }),
      CCMAP_CALL("pooled_cell (coarsest)", { f.sink = f.stack->pooled_cell(4, CellIndex{0, 0}).weight; }),
      CCMAP_CALL("export_layer (coarsest)", {
        std::size_t n = 0;
        f.sink = f.stack->export_layer(4, f.records.data(), f.records.size(), &n) == Status::kOk ? static_cast<float>(n) : -1.0F;
      }),
      CCMAP_CALL("export_layer (fine)", {
        std::size_t n = 0;
        f.sink = f.stack->export_layer(0, f.records.data(), f.records.size(), &n) == Status::kOk ? static_cast<float>(n) : -1.0F;
      }),
      CCMAP_CALL("move_to with uncertainty", { f.sink = f.stack->move_to(0.0F, 0.0F, 0.01F) == Status::kOk ? 1.0F : 0.0F; }),
      CCMAP_CALL("query_footprint (0.6 x 0.4 m)", {
        f.sink = query_footprint(*f.stack, Footprint{0.3F, 0.1F, 0.8F, 0.6F, 0.6F, 0.4F}).max_step_m;
      }),
      CCMAP_CALL("query_footprint (far: coarse layers pool)", {
        f.sink = query_footprint(*f.stack, Footprint{7.0F, 7.0F, 0.8F, 0.6F, 2.0F, 1.0F}).max_step_m;
      }),
      CCMAP_CALL("query_path (2 m)",
                 { f.sink = query_path(*f.stack, f.path.data(), f.path.size(), f.sweep).first_hazard_m; }),
      CCMAP_CALL("query_arc (2 m)", { f.sink = query_arc(*f.stack, f.start, 0.5F, 2.0F, f.sweep).checked_m; }),
      CCMAP_CALL("fill_costmap (5 m at 4 cm, inflated)", {
        CostmapStats st{};
        f.sink = fill_costmap(*f.stack, CostmapSpec{0.0F, 0.0F, 0.04F, 125U, 0.3F}, f.cost.data(), f.cost.size(), &st) ==
                         Status::kOk ? static_cast<float>(st.lethal) : -1.0F;
      }),
      CCMAP_CALL("register_frame", {
        f.sink = ccmap::register_frame(*f.stack, f.points.data(), f.points.size(), PointXYZ{0.0F, 0.0F, 0.0F},
                                         default_registration_params()).dz;
      }),
      CCMAP_CALL("register_frame_sensor", {
        f.sink = ccmap::register_frame_sensor(*f.stack, f.points.data(), 2000U, f.pose, default_registration_params()).dz;
      }),
      CCMAP_CALL("move_to (teleport)", { f.sink = f.stack->move_to(500.0F, 500.0F) == Status::kOk ? 1.0F : 0.0F; }),
  };
  // Warm runs only: the first call of anything may resolve lazily bound symbols (ld.so's
  // resolver runs on the caller's stack; flight images are linked statically or BIND_NOW).
  // The baseline is the least of several no-op runs (QEMU's thread start varies a little).
  std::size_t baseline = static_cast<std::size_t>(-1);
  for (int i = 0; i < 4; ++i) {
    const std::size_t b = high_water(calls[0].fn, &fixture);
    baseline = b < baseline ? b : baseline;
  }
  std::printf("[ stack    ] baseline (call of a no-op through the harness): %zu bytes\n", baseline);
  std::size_t worst = 0;
  for (const Call& call : calls) {
    (void)high_water(call.fn, &fixture);  // warm-up
    const std::size_t raw = high_water(call.fn, &fixture);
    const std::size_t used = raw > baseline ? raw - baseline : 0U;
    std::printf("[ stack    ] %-42s %5zu bytes\n", call.name, used);
    testing::Test::RecordProperty(call.name, std::to_string(used));
    worst = used > worst ? used : worst;
    if (kAssertLimit) {
      EXPECT_LT(used, kLimitBytes) << call.name << " uses " << used << " bytes of stack";
    }
  }
  EXPECT_GT(worst, 0U) << "the painting saw no stack use: measurement broken";
}

}  // namespace
}  // namespace ccmap
