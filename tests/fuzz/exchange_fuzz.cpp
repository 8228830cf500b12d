// libFuzzer target: map exchange on untrusted bytes (a delta or a snapshot from another rover,
// over the radio). Input starting with "CCMS" is merged as a snapshot (MapExchange::
// merge_snapshot, offset 0), anything else as a delta (merge_delta), into a small stack that
// holds a map of its own (tests/support/exchange_seeds.hpp). Invariants (a violation aborts):
//  - every status is a defined Status;
//  - a refused input leaves the map and the exchange's sent copies bitwise unchanged (checked
//    through the next export: it must be byte-identical to the export of an untouched twin);
//  - an accepted one leaves only finite cells and finite query answers, and the delta the
//    receiver then exports is accepted by a fresh receiver (what the library writes, it reads).
// Seeds: tests/fuzz/corpus/exchange/ (valid deltas and snapshots). Built and run by tools/fuzz.
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

using ccmap::test::SeedExchange;
using ccmap::test::SeedStack;

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "ccmap exchange fuzz: invariant violated: %s\n", what);
  std::abort();
}

bool finite_query(const ccmap::QueryResult& q) {
  return std::isfinite(q.height_m) && std::isfinite(q.slope_x) && std::isfinite(q.slope_y) &&
         std::isfinite(q.normal_variance) && std::isfinite(q.elevation_variance) && std::isfinite(q.weight);
}

std::vector<std::uint8_t> export_of(SeedExchange& ex) {
  std::vector<std::uint8_t> bytes(SeedExchange::max_delta_size());
  std::size_t written = 0;
  if (ex.export_delta(bytes.data(), bytes.size(), ccmap::ExportOptions{0.0F, 0}, &written, nullptr) != ccmap::Status::kOk) {
    fail("export failed");
  }
  bytes.resize(written);
  return bytes;
}

/// A fresh receiver (its own map, an exchange that has sent nothing and knows no peer).
void prepare(SeedStack& stack, SeedExchange& ex) {
  if (!ccmap::test::make_seed_receiver(stack) ||
      ex.init(stack, ccmap::ExchangeParams{ccmap::test::kSeedReceiverId, 1U, ccmap::CellIndex{0, 0}, 0.0F}) !=
          ccmap::Status::kOk) {
    fail("the receiver could not be prepared");
  }
}

SeedStack g_stack, g_twin, g_check;
SeedExchange g_exchange, g_twin_exchange, g_check_exchange;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  prepare(g_stack, g_exchange);
  const bool snapshot = size >= 4 && std::memcmp(data, "CCMS", 4) == 0;
  const ccmap::Status status =
      snapshot ? g_exchange.merge_snapshot(data, size, ccmap::CellIndex{0, 0}, 0.0F, nullptr)
               : g_exchange.merge_delta(data, size, nullptr);
  if (static_cast<int>(status) > static_cast<int>(ccmap::Status::kMisaligned)) fail("undefined status");
  if (status != ccmap::Status::kOk) {
    prepare(g_twin, g_twin_exchange);
    if (export_of(g_exchange) != export_of(g_twin_exchange)) fail("a refused input changed the map or its sent copies");
    return 0;
  }
  if (!ccmap::test::all_stored_finite(g_stack)) fail("a merged cell is not finite");
  for (float y = -8.0F; y <= 8.0F; y += 0.7F) {
    for (float x = -8.0F; x <= 8.0F; x += 0.7F) {
      if (!finite_query(g_stack.query(x, y))) fail("a merged map answered a non-finite query");
    }
  }
  // What the receiver writes now must be read by another rover.
  const std::vector<std::uint8_t> delta = export_of(g_exchange);
  if (!ccmap::test::make_seed_receiver(g_check) ||
      g_check_exchange.init(g_check, ccmap::ExchangeParams{9U, 1U, ccmap::CellIndex{0, 0}, 0.0F}) != ccmap::Status::kOk) {
    fail("the check receiver could not be prepared");
  }
  if (g_check_exchange.merge_delta(delta.data(), delta.size(), nullptr) != ccmap::Status::kOk) {
    fail("a delta this library wrote was refused");
  }
  return 0;
}
