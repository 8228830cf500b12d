// The flight interface across threads: a planner thread reads the map product through
// ccmap_product_read (no map handle) while the mapper updates, moves and publishes; and the C
// fault hook. The reader checks every product it accepts against the writer's own record of
// what it published under that sequence number (the CRC the writer computed, kept in a table
// the reader reads), so a torn or mixed copy accepted as whole is caught independently of the
// reader's checks; CCMAP_CORRUPT must never be answered (no byte of the buffers is damaged).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

#include "ccmap/ccmap.h"
#include "ccmap/map/stack.hpp"
#include "ccmap/product/product_format.hpp"

namespace {

struct Recorded {
  std::atomic<std::uint64_t> entry{0U};  ///< sequence << 32 | CRC of that product
};

/// A slope with a box, n x n points around (cx, cy).
std::vector<float> terrain(float cx, float cy, int n) {
  std::vector<float> xyz;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const float dx = -1.0F + 2.0F * (static_cast<float>(i) + 0.5F) / static_cast<float>(n);
      const float dy = -1.0F + 2.0F * (static_cast<float>(j) + 0.5F) / static_cast<float>(n);
      const bool box = dx > 0.3F && dx < 0.6F && dy > -0.2F && dy < 0.2F;
      xyz.push_back(cx + dx);
      xyz.push_back(cy + dy);
      xyz.push_back(0.05F * (cx + dx) + (box ? 0.3F : 0.0F));
    }
  }
  return xyz;
}

TEST(FlightThreads, ReaderBesideWriterSeesOnlyWholeProducts) {
  static ccmap_cadre_storage storage;
  ccmap_map* map = nullptr;
  ASSERT_EQ(ccmap_place(&storage, sizeof storage, CCMAP_PRESET_CADRE, &map), CCMAP_OK);
  ccmap_params params{};
  ASSERT_EQ(ccmap_default_params(CCMAP_PRESET_CADRE, &params), CCMAP_OK);
  params.free_space_rays = 16.0F;
  ASSERT_EQ(ccmap_init(map, &params), CCMAP_OK);

  constexpr std::uint32_t kSide = 32U;  // CADRE layers 3 and 4
  static std::uint32_t buffer_storage[CCMAP_PRODUCT_BUFFERS_STORAGE_SIZE(kSide * kSide) / 4U];
  ccmap_product_buffers buffers{};
  ASSERT_EQ(ccmap_product_buffers_init(&buffers, buffer_storage, sizeof buffer_storage), CCMAP_OK);
  static Recorded record[1024];

  const char* env = std::getenv("CCMAP_PRODUCT_READS");
  const unsigned long reads = env != nullptr ? std::strtoul(env, nullptr, 10) : 50000UL;
  std::atomic<bool> done{false};
  unsigned long ok = 0, busy = 0, corrupt = 0, torn = 0, unchecked = 0, backwards = 0;
  std::thread reader([&] {
    std::vector<std::uint8_t> copy(CCMAP_PRODUCT_SIZE(kSide, kSide));
    std::uint32_t last = 0U;
    unsigned long polls = 0U;
    const auto start = std::chrono::steady_clock::now();
    for (unsigned long r = 0; r < reads;) {
      if (++polls % 4096U == 0U && std::chrono::steady_clock::now() - start > std::chrono::seconds(4)) {
        break;  // a slow host or emulator: what was read is checked all the same
      }
      std::size_t written = 0U;
      const ccmap_status status = ccmap_product_read(&buffers, copy.data(), copy.size(), &written);
      if (status == CCMAP_OK) {
        ccmap::ProductHeader h{};
        ASSERT_EQ(ccmap::decode_product_header(copy.data(), written, &h), ccmap::Status::kOk);
        const std::uint32_t crc = ccmap::product_detail::get_u32(copy.data() + written - 4U);
        const std::uint64_t entry = record[h.product_sequence % 1024U].entry.load(std::memory_order_acquire);
        if (static_cast<std::uint32_t>(entry >> 32U) != h.product_sequence) {
          ++unchecked;  // the writer has lapped the table: nothing to compare with
        } else if (static_cast<std::uint32_t>(entry) != crc) {
          ++torn;
        }
        backwards += h.product_sequence < last ? 1U : 0U;
        last = h.product_sequence;
        ++ok;
      } else if (status == CCMAP_BUSY) {
        ++busy;
      } else if (status != CCMAP_NOT_INITIALISED) {
        ++corrupt;
      }
      r += status == CCMAP_NOT_INITIALISED ? 0U : 1U;  // reads count from the first product on
    }
    done.store(true);
  });

  // The mapper: a frame, a move, a product, as a flight cycle would (the layers alternate).
  const float origin[3] = {0.0F, 0.0F, 0.8F};
  std::uint32_t cycle = 0U;
  std::vector<std::uint8_t> mine(CCMAP_PRODUCT_SIZE(kSide, kSide));
  while (!done.load()) {
    const float x = 0.05F * static_cast<float>(cycle % 200U);
    const std::vector<float> xyz = terrain(x, 0.0F, 40);
    const float sensor[3] = {x, origin[1], origin[2]};
    ASSERT_EQ(ccmap_move_to(map, x, 0.0F), CCMAP_OK);
    ASSERT_EQ(ccmap_update_frame(map, xyz.data(), nullptr, xyz.size() / 3U, sensor, nullptr), CCMAP_OK);
    ccmap_product_spec spec{};
    spec.layer = 3 + static_cast<std::int32_t>(cycle % 2U);
    spec.answer = CCMAP_PRODUCT_STACK;
    spec.pose_x = x;
    spec.tag = cycle;
    // What the product will be: published into private buffers first (the writer's record).
    static std::uint32_t private_storage[CCMAP_PRODUCT_BUFFERS_STORAGE_SIZE(kSide * kSide) / 4U];
    ccmap_product_buffers mirror{};
    ASSERT_EQ(ccmap_product_buffers_init(&mirror, private_storage, sizeof private_storage), CCMAP_OK);
    mirror.published = buffers.published;  // the same sequence numbers (the writer's own word)
    ASSERT_EQ(ccmap_publish(map, &spec, &mirror), CCMAP_OK);
    std::size_t written = 0U;
    ASSERT_EQ(ccmap_product_read(&mirror, mine.data(), mine.size(), &written), CCMAP_OK);
    ccmap::ProductHeader h{};
    ASSERT_EQ(ccmap::decode_product_header(mine.data(), written, &h), ccmap::Status::kOk);
    const std::uint32_t crc = ccmap::product_detail::get_u32(mine.data() + written - 4U);
    record[h.product_sequence % 1024U].entry.store((std::uint64_t{h.product_sequence} << 32U) | crc,
                                                   std::memory_order_release);
    ASSERT_EQ(ccmap_publish(map, &spec, &buffers), CCMAP_OK);
    ++cycle;
  }
  reader.join();
  std::printf("%lu reads: %lu whole (%lu not comparable), %lu busy; %u cycles\n", reads, ok, unchecked, busy, cycle);
  EXPECT_EQ(torn, 0U) << "a product accepted as whole differs from what the writer published";
  EXPECT_EQ(corrupt, 0U) << "CCMAP_CORRUPT answered for undamaged buffers";
  EXPECT_EQ(backwards, 0U) << "an older product read after a newer one";
  EXPECT_GT(ok, 100U);
  EXPECT_GT(cycle, 10U);
}

struct HookRecord {
  int calls = 0;
  int line = 0;
};

void record_fault(void* context, const char*, int line, const char*) {
  auto* r = static_cast<HookRecord*>(context);
  ++r->calls;
  r->line = line;
}

TEST(FlightThreads, FaultHookFromCReceivesContractViolations) {
  static ccmap::Stack<ccmap::CadreConfig> stack;
  static ccmap_cadre_storage storage;
  ccmap_map* map = nullptr;
  ASSERT_EQ(ccmap_place(&storage, sizeof storage, CCMAP_PRESET_CADRE, &map), CCMAP_OK);
  ccmap_health before{};
  ASSERT_EQ(ccmap_get_health(map, &before), CCMAP_OK);
  HookRecord r{};
  ASSERT_EQ(ccmap_set_fault_hook(&record_fault, &r), CCMAP_OK);
  const auto& none = stack.ccm_layer(-1);  // a contract violation: reported, answered safely
  EXPECT_EQ(none.side(), 0);
  ASSERT_EQ(ccmap_set_fault_hook(nullptr, nullptr), CCMAP_OK);
  EXPECT_EQ(r.calls, 1);
  EXPECT_GT(r.line, 0);
  ccmap_health after{};
  ASSERT_EQ(ccmap_get_health(map, &after), CCMAP_OK);
  EXPECT_EQ(after.fault_count, before.fault_count + 1U);
}

}  // namespace
