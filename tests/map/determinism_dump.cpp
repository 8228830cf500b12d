// Determinism across targets: a fixed traverse, generated in-process, mapped into a
// Stack<CadreConfig>; prints a 64-bit FNV-1a hash of the raw storage of every layer (every
// float's IEEE-754 bits, little-endian, finest layer first, buffer order), of every window and
// of the frame counters. The same input must give the same hash on x86-64 and on aarch64
// (both built with -ffp-contract=off, see cmake/CcmapFlags.cmake).
//
// Nothing on the generation path calls libm: the noise is an integer hash, the terrain and the
// path are polynomials and quotients (+ - * / are correctly rounded IEEE operations, identical
// on every target), the sensor rotation is a rational (Cayley) parametrisation. The map's own
// update path uses + - * / sqrt floor fabs only (checked by the nm test next to this one).
//
//   ccmap_determinism_dump                 prints the hash
//   ccmap_determinism_dump --check FILE    exit 0 iff the hash equals the first token of FILE
//   ccmap_determinism_dump --raw FILE      also writes the raw storage bytes to FILE
//   ccmap_determinism_dump --paper-cell    (first) the same with Stack<PaperCell<CadreConfig>>,
//                                          golden tests/golden/determinism_paper_cell.txt
//
// Regenerating the golden hash (tests/golden/determinism.txt and determinism_paper_cell.txt,
// first token, the latter with --paper-cell) after an intended
// change of the map's arithmetic: replace the file's first line with the output of the host
// build's build/host-release/tests/map/ccmap_determinism_dump, then run the aarch64 test
// (ctest --preset aarch64 -R determinism) before committing: the golden file is what proves
// host == aarch64. A mismatch on one target only means that target's arithmetic differs.
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "ccmap/map/stack.hpp"
#include "support/poses.hpp"
#include "support/hash_unit.hpp"
#include "support/map_state.hpp"

namespace {

using ccmap::test::hash_unit;

/// Terrain: a rational bump field plus a 12 cm step, + - * / only.
float terrain(float x, float y) {
  const float a = x * 0.3F, b = y * 0.25F;
  float h = 0.2F * a / (1.0F + a * a) + 0.1F * b * b / (1.0F + b * b);
  if (x > 3.0F && x < 3.5F) h += 0.12F;
  return h;
}

/// Rotation about z from t = tan(yaw / 2) (Cayley): cos = (1 - t^2) / (1 + t^2),
/// sin = 2t / (1 + t^2). No trigonometric function.
ccmap::Pose pose_from(float x, float y, float t) {
  const float d = 1.0F / (1.0F + t * t);
  const float c = (1.0F - t * t) * d, s = 2.0F * t * d;
  return ccmap::test::yaw_pose(c, s, ccmap::PointXYZ{x, y, 0.5F});
}

struct Result {
  std::uint64_t hash;
  std::vector<unsigned char> raw;
};

template <typename Config>
Result run() {
  using S = ccmap::Stack<Config>;
  auto stack = std::make_unique<S>();
  ccmap::StackParams params = ccmap::default_stack_params(0.04F);
  if (stack->init(params) != ccmap::Status::kOk) {
    std::fprintf(stderr, "init failed\n");
    std::exit(2);
  }
  constexpr int kFrames = 400;
  constexpr std::uint32_t kPoints = 600;
  std::vector<ccmap::PointXYZ> pts(kPoints);
  ccmap::FrameCounters c{};
  for (int f = 0; f < kFrames; ++f) {
    // A rounded path: 2 cm per frame along x, a parabolic drift in y.
    const float fx = static_cast<float>(f);
    const float rx = 0.02F * fx;
    const float ry = 0.5F * (fx / kFrames) * (fx / kFrames) - 0.2F;
    const float yaw_t = 0.3F * (fx / kFrames) - 0.1F;
    if (stack->move_to(rx, ry) != ccmap::Status::kOk) std::exit(3);
    const bool sensor_frame = (f % 2) == 1;
    const ccmap::Pose pose = pose_from(rx, ry, yaw_t);
    for (std::uint32_t i = 0; i < kPoints; ++i) {
      const std::uint32_t id = static_cast<std::uint32_t>(f) * kPoints + i;
      const float ahead = 0.2F + 5.5F * hash_unit(id, 1U);
      const float side = (6.0F * hash_unit(id, 2U) - 3.0F) * (0.2F + ahead / 5.7F);
      const float noise = 0.004F * (hash_unit(id, 3U) - 0.5F);
      if (sensor_frame) {
        // Sensor frame: the map point through the inverse pose (R^T (p - t)).
        const float mx = rx + pose.rotation[0][0] * ahead + pose.rotation[0][1] * side;
        const float my = ry + pose.rotation[1][0] * ahead + pose.rotation[1][1] * side;
        pts[i] = ccmap::PointXYZ{ahead, side, terrain(mx, my) + noise - 0.5F};
      } else {
        const float mx = rx + ahead;
        const float my = ry + side;
        pts[i] = ccmap::PointXYZ{mx, my, terrain(mx, my) + noise};
      }
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
  c = stack->total_counters();
  ccmap::test::Fnv1a64 h;
  h.byte(0);  // format version of this dump
  h.u32(static_cast<std::uint32_t>(ccmap::test::map_hash(*stack) >> 32));
  h.u32(static_cast<std::uint32_t>(ccmap::test::map_hash(*stack)));
  for (const std::uint32_t v : {c.received, c.used, c.rejected_non_finite, c.rejected_out_of_range, c.rejected_weight,
                                c.outside_map, c.too_noisy}) {
    h.u32(v);
  }
  // Queries and an export of every layer, through the pooling path.
  for (int k = 0; k < S::kLayerCount; ++k) {
    std::vector<ccmap::CellRecord> records(S::layer_capacity(k));
    std::size_t written = 0;
    if (stack->export_layer(k, records.data(), records.size(), &written) != ccmap::Status::kOk) std::exit(5);
    h.u32(static_cast<std::uint32_t>(written));
    for (std::size_t i = 0; i < written; ++i) {
      const ccmap::CellRecord& r = records[i];
      h.i32(r.index.x);
      h.i32(r.index.y);
      for (const float v : {r.weight, r.height_m, r.slope_x, r.slope_y, r.normal_variance, r.elevation_variance}) h.f32(v);
      h.byte(static_cast<std::uint8_t>(r.cell_class));
    }
  }
  std::fprintf(stderr, "received %u used %u non-finite %u out-of-range %u outside %u too-noisy %u\n", c.received,
               c.used, c.rejected_non_finite, c.rejected_out_of_range, c.outside_map, c.too_noisy);
  return Result{h.hash, ccmap::test::raw_map_state(*stack)};
}

}  // namespace

int main(int argc, char** argv) {
  const bool paper_cell = argc > 1 && std::strcmp(argv[1], "--paper-cell") == 0;
  const Result r = paper_cell ? run<ccmap::PaperCell<ccmap::CadreConfig>>() : run<ccmap::CadreConfig>();
  char text[32];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(r.hash));
  std::printf("%s\n", text);
  for (int i = paper_cell ? 2 : 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--raw") == 0) {
      std::FILE* f = std::fopen(argv[i + 1], "wb");
      if (f == nullptr || std::fwrite(r.raw.data(), 1, r.raw.size(), f) != r.raw.size()) return 2;
      std::fclose(f);
    } else if (std::strcmp(argv[i], "--check") == 0) {
      std::FILE* f = std::fopen(argv[i + 1], "r");
      char golden[64] = {};
      if (f == nullptr || std::fscanf(f, "%63s", golden) != 1) {
        std::fprintf(stderr, "cannot read the golden hash from %s\n", argv[i + 1]);
        return 2;
      }
      std::fclose(f);
      if (std::strcmp(golden, text) != 0) {
        std::fprintf(stderr,
                     "map hash %s differs from the golden %s (%s): this target's arithmetic differs, or the map "
                     "changed on purpose (then regenerate: see tests/map/determinism_dump.cpp)\n",
                     text, golden, argv[i + 1]);
        return 1;
      }
      std::fprintf(stderr, "map hash matches the golden %s\n", argv[i + 1]);
    } else {
      std::fprintf(stderr, "usage: %s [--paper-cell] [--check FILE] [--raw FILE]\n", argv[0]);
      return 2;
    }
  }
  return 0;
}
