// libFuzzer target: load_snapshot on untrusted bytes (a snapshot from another computer), into a
// small stack that holds a map (tests/support/exchange_seeds.hpp). Invariants (a violation aborts):
//  - every status is a defined Status;
//  - a refused snapshot leaves the stack bitwise unchanged (raw storage, windows, counters);
//  - an accepted one leaves only finite cells, answers finite queries, and saves back to exactly
//    the input bytes (the format has one encoding of each state).
// Seeds: tests/fuzz/corpus/snapshot/ (valid snapshots). Built and run by tools/fuzz.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "support/exchange_seeds.hpp"
#include "support/map_state.hpp"

namespace {

using ccmap::test::SeedStack;

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "ccmap snapshot fuzz: invariant violated: %s\n", what);
  std::abort();
}

/// Raw state: every cell's bytes and window centre (support/map_state.hpp), then the counters.
std::vector<unsigned char> state_of(const SeedStack& s) {
  std::vector<unsigned char> out = ccmap::test::raw_map_state(s);
  const auto* counters = reinterpret_cast<const unsigned char*>(&s.total_counters());
  out.insert(out.end(), counters, counters + sizeof(ccmap::FrameCounters));
  return out;
}

bool finite_query(const ccmap::QueryResult& q) {
  return std::isfinite(q.height_m) && std::isfinite(q.slope_x) && std::isfinite(q.slope_y) &&
         std::isfinite(q.normal_variance) && std::isfinite(q.elevation_variance) && std::isfinite(q.weight);
}

SeedStack g_stack;
std::vector<std::uint8_t> g_original;  // snapshot of the prepared stack, to restore it

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (g_original.empty()) {
    if (!ccmap::test::make_seed_receiver(g_stack)) fail("the receiver could not be prepared");
    g_original = ccmap::test::seed_snapshot(g_stack);
  }
  const std::vector<unsigned char> before = state_of(g_stack);
  const ccmap::Status status = ccmap::load_snapshot(g_stack, data, size);
  if (static_cast<int>(status) > static_cast<int>(ccmap::Status::kMisaligned)) fail("undefined status");
  if (status != ccmap::Status::kOk) {
    if (state_of(g_stack) != before) fail("a refused snapshot changed the stack");
    return 0;
  }
  if (!ccmap::test::all_stored_finite(g_stack)) fail("a loaded cell is not finite");
  for (float y = -8.0F; y <= 8.0F; y += 0.7F) {
    for (float x = -8.0F; x <= 8.0F; x += 0.7F) {
      if (!finite_query(g_stack.query(x, y))) fail("a loaded map answered a non-finite query");
    }
  }
  const std::vector<std::uint8_t> again = ccmap::test::seed_snapshot(g_stack);
  if (again.size() != size || std::memcmp(again.data(), data, size) != 0) fail("save after load differs from the input");
  if (ccmap::load_snapshot(g_stack, g_original.data(), g_original.size()) != ccmap::Status::kOk) {
    fail("the original snapshot no longer loads");
  }
  return 0;
}
