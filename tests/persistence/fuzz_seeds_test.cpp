// The committed seed corpora of the snapshot and exchange fuzz targets (tests/fuzz/corpus/
// snapshot/, tests/fuzz/corpus/exchange/) are valid inputs of the current formats: each file is
// the byte-exact output of tests/support/exchange_seeds.hpp, loads or merges into the fuzz
// targets' receiver, and so starts the fuzzer inside the format rather than at its magic.
// After an intended format change, regenerate them:
//   CCMAP_WRITE_FUZZ_SEEDS=1 build/host-release/tests/persistence/ccmap_test_fuzz_seeds
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "support/exchange_seeds.hpp"

namespace ccmap {
namespace {

using Named = std::vector<std::pair<std::string, std::vector<std::uint8_t>>>;

std::vector<std::uint8_t> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void check_or_write(const Named& seeds, const std::string& dir) {
  const bool write = std::getenv("CCMAP_WRITE_FUZZ_SEEDS") != nullptr;
  for (const auto& [name, bytes] : seeds) {
    const std::string path = dir + "/" + name;
    ASSERT_FALSE(bytes.empty()) << name << ": the generator failed";
    if (write) {
      std::ofstream out(path, std::ios::binary);
      out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
      ASSERT_TRUE(out.good()) << "cannot write " << path;
    }
    EXPECT_EQ(read_file(path), bytes) << path << " is missing or not the current format; regenerate it (see the top of "
                                      << __FILE__ << ")";
  }
}

const std::string kCorpus = std::string(CCMAP_SOURCE_DIR) + "/tests/fuzz/corpus";

TEST(FuzzSeeds, SnapshotSeedsAreCurrentAndLoad) {
  const Named seeds = test::seed_snapshots();
  ASSERT_EQ(seeds.size(), 3U);
  check_or_write(seeds, kCorpus + "/snapshot");
  auto stack = std::make_unique<test::SeedStack>();
  for (const auto& [name, bytes] : seeds) {
    EXPECT_EQ(load_snapshot(*stack, bytes.data(), bytes.size()), Status::kOk) << name;
  }
}

TEST(FuzzSeeds, ExchangeSeedsAreCurrentAndMergeIntoTheFuzzReceiver) {
  Named seeds = test::seed_deltas();
  ASSERT_EQ(seeds.size(), 8U);
  const Named snapshots = test::seed_snapshots();
  seeds.insert(seeds.end(), snapshots.begin(), snapshots.end());
  check_or_write(seeds, kCorpus + "/exchange");
  for (const auto& [name, bytes] : seeds) {
    auto stack = std::make_unique<test::SeedStack>();
    test::SeedExchange ex;
    ASSERT_TRUE(test::make_seed_receiver(*stack));
    ASSERT_EQ(ex.init(*stack, ExchangeParams{test::kSeedReceiverId, 1U, CellIndex{0, 0}, 0.0F}), Status::kOk);
    const bool snapshot = name.size() > 5 && name.compare(name.size() - 5, 5, ".snap") == 0;
    MergeReport report{};
    const Status s = snapshot ? ex.merge_snapshot(bytes.data(), bytes.size(), CellIndex{0, 0}, 0.0F, &report)
                              : ex.merge_delta(bytes.data(), bytes.size(), &report);
    EXPECT_EQ(s, Status::kOk) << name;
  }
}

}  // namespace
}  // namespace ccmap
