// Proof of "no heap after initialisation": this test binary replaces the global allocation
// functions (operator new/delete in all forms, and malloc/calloc/realloc/free through glibc's
// __libc_* entry points) with counting versions, builds a CADRE stack, and asserts that
// feeding frames, moving (also with a position sigma), querying, exporting, the planner queries
// (footprint, path, arc, cost raster) and map exchange's export, delta merge and snapshot merge
// allocate nothing.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/persistence/exchange.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/registration/alignment.hpp"
#include "ccmap/registration/registration.hpp"
#include "support/poses.hpp"

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t n, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void __libc_free(void* p);
}

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
void count() {
  if (g_counting.load(std::memory_order_relaxed)) {
    g_allocations.fetch_add(1, std::memory_order_relaxed);
  }
}
}  // namespace

extern "C" {
void* malloc(std::size_t size) {
  count();
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  count();
  return __libc_realloc(p, size);
}
void free(void* p) { __libc_free(p); }
}

void* operator new(std::size_t size) {
  count();
  void* p = __libc_malloc(size == 0 ? 1 : size);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t size) { return operator new(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  count();
  return __libc_malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return operator new(size, std::nothrow); }
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }

namespace ccmap {
namespace {

// Stack in static storage, as flight software would place it.
Stack<CadreConfig> g_stack;
CellRecord g_records[64 * 64];
std::uint8_t g_cost[125 * 125];

TEST(NoHeap, CountingAllocatorSeesAllocations) {
  // The instrument works: a vector allocation is counted.
  g_allocations = 0;
  g_counting = true;
  { std::vector<int> v(100); (void)v; }
  { auto p = std::make_unique<int>(3); (void)p; }
  void* raw = std::malloc(10);
  std::free(raw);
  g_counting = false;
  EXPECT_GE(g_allocations.load(), 3L);
}

TEST(NoHeap, CadreStackRunsWithoutAllocatingAfterInit) {
  ASSERT_EQ(g_stack.init(default_stack_params(0.04F)), Status::kOk);
  // Frames prepared before counting (the caller's buffers).
  std::vector<PointXYZ> frame;
  for (int i = 0; i < 100000; ++i) {
    const float x = -4.0F + 8.0F * static_cast<float>(i % 400) / 400.0F;
    const float y = -4.0F + 8.0F * static_cast<float>(i / 400) / 250.0F;
    frame.push_back(PointXYZ{x, y, 0.1F * x + ((i % 37) == 0 ? 0.2F : 0.0F)});
  }
  frame[5].x = std::numeric_limits<float>::quiet_NaN();
  const Pose pose = test::identity_pose(PointXYZ{0.1F, 0.0F, 0.175F});

  g_allocations = 0;
  g_counting = true;
  FrameCounters counters{};
  long status_errors = 0;
  for (int step = 0; step < 5; ++step) {
    status_errors += g_stack.move_to(0.3F * static_cast<float>(step), 0.1F) != Status::kOk;
    status_errors += g_stack.update_frame(frame.data(), frame.size(), PointXYZ{0.0F, 0.0F, 0.175F}, &counters) != Status::kOk;
    status_errors += g_stack.update_frame_sensor(frame.data(), frame.size(), pose, &counters) != Status::kOk;
    for (int q = 0; q < 1000; ++q) {
      const QueryResult r = g_stack.query(-3.0F + 0.006F * static_cast<float>(q), 0.5F);
      status_errors += r.status == Status::kNotInitialised;
    }
    for (int layer = 0; layer < Stack<CadreConfig>::kLayerCount; ++layer) {
      std::size_t written = 0;
      status_errors += g_stack.export_layer(layer, g_records, 64 * 64, &written) != Status::kOk;
    }
    // The planner queries and the uncertain move.
    status_errors += g_stack.move_to(0.3F * static_cast<float>(step), 0.1F, 0.01F) != Status::kOk;
    status_errors += query_footprint(g_stack, Footprint{0.5F, 0.2F, 0.8F, 0.6F, 2.0F, 1.0F}).status != Status::kOk;
    const PathPoint route[] = {{0.0F, 0.0F}, {2.0F, 0.5F}, {2.5F, 2.0F}};
    status_errors += query_path(g_stack, route, 3, PathSweep{0.6F, 0.4F, 0.05F, 1.0F}).status != Status::kOk;
    status_errors += query_arc(g_stack, PathPose{0.0F, 0.0F, 1.0F, 0.0F}, 0.5F, 2.0F, PathSweep{0.6F, 0.4F, 0.05F, 1.0F})
                         .status != Status::kOk;
    status_errors += fill_costmap(g_stack, CostmapSpec{0.0F, 0.0F, 0.04F, 125U, 0.3F}, g_cost, sizeof g_cost, nullptr) !=
                     Status::kOk;
  }
  (void)g_stack.move_to(std::numeric_limits<float>::quiet_NaN(), 0.0F);
  (void)g_stack.move_to(1000.0F, 1000.0F);
  g_counting = false;
  EXPECT_EQ(status_errors, 0);
  EXPECT_EQ(g_allocations.load(), 0L) << "the map allocated on the heap after init";
  EXPECT_GT(g_stack.total_counters().used, 100000U);
}

Stack<CadreConfig> g_mate;
MapExchange<CadreConfig> g_exchange, g_mate_exchange;
std::uint8_t g_delta[MapExchange<CadreConfig>::max_delta_size()];
std::uint8_t g_snapshot[snapshot_size<CadreConfig>()];

TEST(NoHeap, MapExchangeExportsAndMergesWithoutAllocating) {
  ASSERT_EQ(g_stack.init(default_stack_params(0.04F)), Status::kOk);
  ASSERT_EQ(g_mate.init(default_stack_params(0.04F)), Status::kOk);
  ASSERT_EQ(g_exchange.init(g_stack, ExchangeParams{1U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  ASSERT_EQ(g_mate_exchange.init(g_mate, ExchangeParams{2U, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
  std::vector<PointXYZ> frame;
  for (int i = 0; i < 20000; ++i) {
    const float x = -3.0F + 6.0F * static_cast<float>(i % 200) / 200.0F;
    const float y = -3.0F + 6.0F * static_cast<float>(i / 200) / 100.0F;
    frame.push_back(PointXYZ{x, y, 0.05F * y});
  }
  std::size_t snapshot_bytes = 0;
  ASSERT_EQ(save_snapshot(g_mate, g_snapshot, sizeof g_snapshot, &snapshot_bytes), Status::kOk);
  g_allocations = 0;
  g_counting = true;
  long status_errors = 0;
  for (int step = 0; step < 3; ++step) {
    status_errors += g_stack.move_to(0.2F * static_cast<float>(step), 0.0F) != Status::kOk;
    status_errors += g_stack.update_frame(frame.data(), frame.size(), PointXYZ{0.0F, 0.0F, 0.175F}, nullptr) != Status::kOk;
    std::size_t written = 0;
    status_errors += g_exchange.export_delta(g_delta, sizeof g_delta, ExportOptions{0.0F, 0}, &written, nullptr) != Status::kOk;
    status_errors += g_mate_exchange.merge_delta(g_delta, written, nullptr) != Status::kOk;
    status_errors += g_mate_exchange.merge_delta(g_delta, written, nullptr) != Status::kDuplicate;
  }
  status_errors += g_exchange.merge_snapshot(g_snapshot, snapshot_bytes, CellIndex{0, 0}, 0.0F, nullptr) != Status::kOk;
  g_counting = false;
  EXPECT_EQ(status_errors, 0);
  EXPECT_EQ(g_allocations.load(), 0L) << "map exchange allocated on the heap";
}

TEST(NoHeap, RegistrationAndAlignmentRunWithoutAllocating) {
  ASSERT_EQ(g_stack.init(default_stack_params(0.04F)), Status::kOk);
  // Rolling ground around the sensor, mapped once; the same ground registered again, map frame
  // and sensor frame, and refused (a NaN origin).
  std::vector<PointXYZ> frame;
  for (int i = 0; i < 40000; ++i) {
    const float x = 0.3F + 4.0F * static_cast<float>(i % 200) / 200.0F;
    const float y = -2.0F + 4.0F * static_cast<float>(i / 200) / 200.0F;
    frame.push_back(PointXYZ{x, y, 0.05F * x * x - 0.04F * x * y + 0.03F * y * y});
  }
  const PointXYZ origin{0.0F, 0.0F, 0.175F};
  ASSERT_EQ(g_stack.update_frame(frame.data(), frame.size(), origin, nullptr), Status::kOk);
  std::vector<PointXYZ> sensor(frame.size());
  for (std::size_t i = 0; i < frame.size(); ++i) {
    sensor[i] = PointXYZ{frame[i].x, frame[i].y, frame[i].z - origin.z};
  }
  const Pose pose = test::identity_pose(origin);
  const RegistrationParams params = default_registration_params();
  std::size_t snapshot_bytes = 0;
  ASSERT_EQ(save_snapshot(g_stack, g_snapshot, sizeof g_snapshot, &snapshot_bytes), Status::kOk);
  g_allocations = 0;
  g_counting = true;
  long status_errors = 0;
  for (int k = 0; k < 3; ++k) {
    status_errors += ccmap::register_frame(g_stack, frame.data(), frame.size(), origin, params).status != Status::kOk;
    status_errors += ccmap::register_frame_sensor(g_stack, sensor.data(), sensor.size(), pose, params).status != Status::kOk;
    status_errors += ccmap::register_frame(g_stack, frame.data(), frame.size(), PointXYZ{std::nanf(""), 0.0F, 0.0F}, params)
                         .status != Status::kNonFiniteInput;
    // Team alignment: the same map as another rover's, from the stack and from its snapshot.
    status_errors += align_maps(g_stack, g_stack, MapOffset{0.01F, 0.0F, 0.0F}, params).correction.status != Status::kOk;
    status_errors += align_snapshot(g_stack, g_snapshot, snapshot_bytes, MapOffset{0.0F, 0.01F, 0.0F}, params)
                         .correction.status != Status::kOk;
  }
  g_counting = false;
  EXPECT_EQ(status_errors, 0);
  EXPECT_EQ(g_allocations.load(), 0L) << "registration allocated on the heap";
}

}  // namespace
}  // namespace ccmap
