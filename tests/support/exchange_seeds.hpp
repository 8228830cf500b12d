// Small maps and the valid snapshots and deltas they produce, shared by the fuzz targets
// (tests/fuzz/snapshot_fuzz.cpp, tests/fuzz/exchange_fuzz.cpp: the receivers they merge into)
// and by the test that checks the committed seed corpora (tests/persistence/fuzz_seeds_test.cpp).
// Deterministic: fixed points, no randomness. Allocates (test support).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "ccmap/persistence/exchange.hpp"
#include "ccmap/persistence/snapshot.hpp"

namespace ccmap::test {

/// 4 x 4 Kalman, two 4 x 4 CCM layers of 0.5 / 1 / 2 m: 1,552-byte snapshots, deltas < 1 KB.
struct SeedConfig {
  static constexpr FineKind kFineKind = FineKind::kKalman;
  static constexpr std::int32_t kFineSide = 4;
  static constexpr std::array<std::int32_t, 2> kCcmSides{{4, 4}};
  static constexpr float kDefaultFinestCellWidthM = 0.5F;
};
using SeedStack = Stack<SeedConfig>;
using SeedExchange = MapExchange<SeedConfig>;

/// The team of the seeds: senders 1 and 3, receiver 2, all at the team origin.
inline constexpr std::uint32_t kSeedReceiverId = 2U;

/// Lidar noise and fixed thresholds (calibration at init would dominate a fuzz iteration).
inline StackParams seed_params() {
  StackParams p = default_stack_params(SeedConfig::kDefaultFinestCellWidthM);
  p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{0.001F, 0.0F});
  for (std::size_t k = 0; k < 3U; ++k) {
    p.normal_variance_threshold[k] = 0.01F * static_cast<float>(1U << k);
  }
  return p;
}

/// A frame of points on a tilted plane with a step, around (cx, cy), height offset dz.
inline std::vector<PointXYZ> seed_frame(float cx, float cy, float dz, int n) {
  std::vector<PointXYZ> pts;
  for (int i = 0; i < n; ++i) {
    const float u = static_cast<float>((i * 37) % 101) / 101.0F - 0.5F;
    const float v = static_cast<float>((i * 53) % 97) / 97.0F - 0.5F;
    const float x = cx + 7.0F * u;
    const float y = cy + 7.0F * v;
    const float step = x > cx + 1.0F ? 0.4F : 0.0F;
    pts.push_back(PointXYZ{x, y, 0.05F * x - 0.02F * y + step + dz + 0.003F * static_cast<float>((i * 7) % 5)});
  }
  return pts;
}

/// Folds one seed frame (map frame, sensor 1 m above its centre).
inline bool feed_seed_frame(SeedStack& stack, float cx, float cy, float dz, int n) {
  const std::vector<PointXYZ> pts = seed_frame(cx, cy, dz, n);
  return stack.move_to(cx, cy) == Status::kOk &&
         stack.update_frame(pts.data(), pts.size(), PointXYZ{cx, cy, 1.0F + dz}, nullptr) == Status::kOk;
}

/// The receiver every fuzz input is merged into: two frames of its own.
inline bool make_seed_receiver(SeedStack& stack) {
  return stack.init(seed_params()) == Status::kOk && feed_seed_frame(stack, 0.0F, 0.0F, 0.02F, 60) &&
         feed_seed_frame(stack, 0.3F, -0.2F, 0.03F, 40);
}

/// A snapshot of the stack with its last-update duration (the only measured field: the 8 bytes
/// before the CRC) set to 0 and the CRC recomputed, so that the seeds are reproducible.
inline std::vector<std::uint8_t> seed_snapshot(const SeedStack& stack) {
  std::vector<std::uint8_t> bytes(snapshot_size<SeedConfig>());
  std::size_t written = 0;
  if (save_snapshot(stack, bytes.data(), bytes.size(), &written) != Status::kOk) {
    bytes.clear();
    return bytes;
  }
  const std::size_t crc_at = bytes.size() - 4U;
  for (std::size_t i = crc_at - 8U; i < crc_at; ++i) {
    bytes[i] = 0U;
  }
  const std::uint32_t crc = crc32_update(0U, bytes.data(), crc_at);
  for (std::size_t i = 0; i < 4U; ++i) {
    bytes[crc_at + i] = static_cast<std::uint8_t>(crc >> (8U * i));
  }
  return bytes;
}

/// Named valid inputs: snapshots (an empty map, a mapped one, one after moves) and the deltas
/// of two senders (a first full delta, a later smaller one, an empty one, one with a floor).
inline std::vector<std::pair<std::string, std::vector<std::uint8_t>>> seed_snapshots() {
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> out;
  auto stack = std::make_unique<SeedStack>();
  if (stack->init(seed_params()) != Status::kOk) return out;
  out.emplace_back("empty.snap", seed_snapshot(*stack));
  if (!feed_seed_frame(*stack, 0.0F, 0.0F, 0.0F, 80)) return out;
  out.emplace_back("mapped.snap", seed_snapshot(*stack));
  if (!feed_seed_frame(*stack, 2.5F, 1.0F, 0.0F, 80) || !feed_seed_frame(*stack, -1.0F, 0.5F, 0.0F, 50)) return out;
  out.emplace_back("moved.snap", seed_snapshot(*stack));
  return out;
}

inline std::vector<std::pair<std::string, std::vector<std::uint8_t>>> seed_deltas() {
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> out;
  auto export_one = [&out](SeedExchange& ex, const char* name, float floor) {
    std::vector<std::uint8_t> bytes(SeedExchange::max_delta_size());
    std::size_t written = 0;
    if (ex.export_delta(bytes.data(), bytes.size(), ExportOptions{floor, 0}, &written, nullptr) == Status::kOk) {
      bytes.resize(written);
      out.emplace_back(name, bytes);
    }
  };
  for (const std::uint32_t id : {1U, 3U}) {
    auto stack = std::make_unique<SeedStack>();
    SeedExchange ex;
    if (stack->init(seed_params()) != Status::kOk ||
        ex.init(*stack, ExchangeParams{id, 1U, CellIndex{0, 0}, 0.0F}) != Status::kOk) {
      return out;
    }
    const std::string prefix = "rover" + std::to_string(id) + "_";
    export_one(ex, (prefix + "empty.delta").c_str(), 0.0F);
    (void)feed_seed_frame(*stack, 0.0F, 0.0F, 0.0F, 80);
    export_one(ex, (prefix + "first.delta").c_str(), 0.0F);
    (void)feed_seed_frame(*stack, 1.5F, 0.5F, 0.0F, 30);
    export_one(ex, (prefix + "floor.delta").c_str(), 2.0F);
    (void)feed_seed_frame(*stack, -1.0F, 1.0F, 0.0F, 30);
    export_one(ex, (prefix + "later.delta").c_str(), 0.0F);
  }
  return out;
}

}  // namespace ccmap::test
