// Determinism across targets: two fixed scenarios, generated in-process, each hashed over the
// whole map (tests/support/board_scenario.hpp: every float's IEEE-754 bits, every window, the
// counters, an export of every layer, little-endian): the same input must give the same hash on
// x86-64, on aarch64 and on the bare-metal Cortex-M7 (all built with -ffp-contract=off, see
// cmake/CcmapFlags.cmake).
//   cadre_traverse   400 frames of 600 points along a rounded path (this file), host and aarch64
//   cadre_traverse_paper_cell  the same with the paper's 9-float CCM cell
//                    (Stack<PaperCell<CadreConfig>>), host and aarch64
//   board_scenario   24 frames of 10,000 points, sized for a 1 MiB controller
//                    (board_scenario.hpp), host, aarch64 and the board
//                    (tests/baremetal/scenario_cases.cpp)
//
// Nothing on the generation path calls libm (see board_scenario.hpp). The map's own update path
// uses + - * / sqrt floor fabs only (checked by the nm test next to this one).
//
//   ccmap_determinism_dump                      prints "<name> <hash>" for each scenario
//   ccmap_determinism_dump --check FILE [NAME]  exit 0 iff the hash of NAME (default: every
//                                               scenario) equals its line "NAME <hash>" in FILE
//   ccmap_determinism_dump --write FILE         replaces the hash lines of FILE (comments stay)
//   ccmap_determinism_dump --raw FILE           also writes the traverse's raw storage bytes
//
// Regenerating tests/golden/determinism.txt after an intended change of the map's arithmetic:
//   build/host-release/tests/map/ccmap_determinism_dump --write tests/golden/determinism.txt
// then run the other targets before committing (the golden file is what proves them equal):
//   ctest --preset aarch64 -R golden          (cadre_traverse and board_scenario under QEMU)
//   ctest --preset cortex-m7 -R scenario      (board_scenario on the Cortex-M7; the board build
//                                              reads the file at configure time and re-configures
//                                              when it changes)
// A mismatch on one target only means that target's arithmetic differs.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/board_scenario.hpp"
#include "support/hash_unit.hpp"
#include "support/map_state.hpp"

namespace {

using S = ccmap::Stack<ccmap::CadreConfig>;
using PaperS = ccmap::Stack<ccmap::PaperCell<ccmap::CadreConfig>>;
using ccmap::test::hash_unit;
namespace scenario = ccmap::test::scenario;

struct Result {
  std::uint64_t hash;
  std::vector<unsigned char> raw;
};

void print_gate_counters(const char* name, const ccmap::FrameCounters& c) {
  std::fprintf(stderr,
               "%s: outlier gate: finer %u, occluded %u, held %u (pool full %u), admitted %u, dropped %u; cells "
               "re-seeded %u, merged %u\n",
               name, c.gated_finer, c.gated_occluded, c.gated_held, c.gated_pool_full, c.gated_admitted, c.gated_dropped,
               c.reseeded_cells, c.merged_cells);
}

template <typename StackT>
Result run_traverse(const char* name) {
  auto stack = std::make_unique<StackT>();
  ccmap::StackParams params = ccmap::default_stack_params(0.04F);
  if (stack->init(params) != ccmap::Status::kOk) {
    std::fprintf(stderr, "init failed\n");
    std::exit(2);
  }
  constexpr int kFrames = 400;
  constexpr std::uint32_t kPoints = 600;
  std::vector<ccmap::PointXYZ> pts(kPoints);
  for (int f = 0; f < kFrames; ++f) {
    // A rounded path: 2 cm per frame along x, a parabolic drift in y.
    const float fx = static_cast<float>(f);
    const float rx = 0.02F * fx;
    const float ry = 0.5F * (fx / kFrames) * (fx / kFrames) - 0.2F;
    const float yaw_t = 0.3F * (fx / kFrames) - 0.1F;
    if (stack->move_to(rx, ry) != ccmap::Status::kOk) std::exit(3);
    const bool sensor_frame = (f % 2) == 1;
    const ccmap::Pose pose = scenario::pose_from(rx, ry, yaw_t);
    for (std::uint32_t i = 0; i < kPoints; ++i) {
      const std::uint32_t id = static_cast<std::uint32_t>(f) * kPoints + i;
      const float ahead = 0.2F + 5.5F * hash_unit(id, 1U);
      const float side = (6.0F * hash_unit(id, 2U) - 3.0F) * (0.2F + ahead / 5.7F);
      const float noise = 0.004F * (hash_unit(id, 3U) - 0.5F);
      pts[i] = scenario::terrain_point(pose, rx, ry, ahead, side, noise, sensor_frame);
    }
    // A few hostile points per frame, refused and counted alike on every target.
    if (f % 50 == 0) pts[0].x = std::numeric_limits<float>::quiet_NaN();
    if (f % 70 == 0) pts[1].z = 3e5F;
    ccmap::FrameCounters frame{};
    const ccmap::Status st =
        sensor_frame ? stack->update_frame_sensor(pts.data(), pts.size(), pose, &frame)
                     : stack->update_frame(pts.data(), pts.size(), ccmap::PointXYZ{rx, ry, 0.5F}, &frame);
    if (st != ccmap::Status::kOk) std::exit(4);
  }
  const ccmap::FrameCounters c = stack->total_counters();
  ccmap::test::Fnv1a64 h;
  h.byte(0);  // format version of this dump
  std::vector<ccmap::CellRecord> records(StackT::layer_capacity(0));
  if (!scenario::hash_stack(*stack, records.data(), records.size(), h)) std::exit(5);
  std::fprintf(stderr, "%s: received %u used %u non-finite %u out-of-range %u outside %u too-noisy %u\n", name,
               c.received, c.used, c.rejected_non_finite, c.rejected_out_of_range, c.outside_map, c.too_noisy);
  print_gate_counters(name, c);
  return Result{h.hash, ccmap::test::raw_map_state(*stack)};
}

std::uint64_t run_board() {
  auto stack = std::make_unique<S>();
  std::vector<ccmap::PointXYZ> points(scenario::kBoardFramePoints);
  std::vector<float> weights(scenario::kBoardFramePoints);
  std::vector<ccmap::CellRecord> records(S::layer_capacity(0));
  const scenario::BoardResult r = scenario::run_board_scenario(*stack, points.data(), weights.data(), records.data());
  if (r.failed_step != 0) {
    std::fprintf(stderr, "board_scenario failed at step %d\n", r.failed_step);
    std::exit(6);
  }
  const ccmap::FrameCounters& c = r.totals;
  std::fprintf(stderr,
               "board_scenario: received %u used %u non-finite %u out-of-range %u weight %u outside %u too-noisy %u\n",
               c.received, c.used, c.rejected_non_finite, c.rejected_out_of_range, c.rejected_weight, c.outside_map,
               c.too_noisy);
  print_gate_counters("board_scenario", c);
  return r.hash;
}

std::string hex(std::uint64_t v) {
  char text[32];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(v));
  return text;
}

bool read_lines(const char* path, std::vector<std::string>* lines) {
  std::ifstream in(path);
  if (!in) return false;
  for (std::string line; std::getline(in, line);) lines->push_back(line);
  return true;
}

/// The hash on the line "<name> <hash>" of the golden file, or "" if there is none.
std::string golden_of(const std::vector<std::string>& lines, const std::string& name) {
  for (const std::string& line : lines) {
    std::istringstream words(line);
    std::string key, value;
    if (words >> key >> value && key == name) return value;
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  const Result traverse = run_traverse<S>("cadre_traverse");
  const Result paper_traverse = run_traverse<PaperS>("cadre_traverse_paper_cell");
  const std::vector<std::pair<std::string, std::string>> hashes = {
      {"cadre_traverse", hex(traverse.hash)},
      {"cadre_traverse_paper_cell", hex(paper_traverse.hash)},
      {"board_scenario", hex(run_board())}};
  for (const auto& [name, value] : hashes) std::printf("%s %s\n", name.c_str(), value.c_str());
  if (argc == 3 && std::strcmp(argv[1], "--raw") == 0) {
    std::FILE* f = std::fopen(argv[2], "wb");
    if (f == nullptr || std::fwrite(traverse.raw.data(), 1, traverse.raw.size(), f) != traverse.raw.size()) return 2;
    std::fclose(f);
    return 0;
  }
  if ((argc == 3 || argc == 4) && std::strcmp(argv[1], "--check") == 0) {
    std::vector<std::string> lines;
    if (!read_lines(argv[2], &lines)) {
      std::fprintf(stderr, "cannot read the golden file %s\n", argv[2]);
      return 2;
    }
    int status = 0;
    bool checked = false;
    for (const auto& [name, value] : hashes) {
      if (argc == 4 && name != argv[3]) continue;
      checked = true;
      const std::string golden = golden_of(lines, name);
      if (golden != value) {
        std::fprintf(stderr,
                     "%s: map hash %s differs from the golden '%s' (%s): this target's arithmetic differs, or the "
                     "map changed on purpose (then regenerate: see tests/map/determinism_dump.cpp)\n",
                     name.c_str(), value.c_str(), golden.c_str(), argv[2]);
        status = 1;
      } else {
        std::fprintf(stderr, "%s: map hash matches the golden %s\n", name.c_str(), argv[2]);
      }
    }
    if (!checked) {
      std::fprintf(stderr, "no scenario named %s\n", argv[3]);
      return 2;
    }
    return status;
  }
  if (argc == 3 && std::strcmp(argv[1], "--write") == 0) {
    std::vector<std::string> lines;
    if (!read_lines(argv[2], &lines)) {
      std::fprintf(stderr, "cannot read the golden file %s\n", argv[2]);
      return 2;
    }
    std::ofstream out(argv[2]);
    for (const auto& [name, value] : hashes) out << name << ' ' << value << '\n';
    for (const std::string& line : lines) {
      if (line.empty() || line[0] == '#') out << line << '\n';
    }
    std::fprintf(stderr, "wrote %s\n", argv[2]);
    return out ? 0 : 2;
  }
  if (argc != 1) {
    std::fprintf(stderr, "usage: %s [--check FILE [NAME] | --write FILE | --raw FILE]\n", argv[0]);
    return 2;
  }
  return 0;
}
