// Instruction counts of stitching (include/ccmap/global/patch_stitcher.hpp) on a CADRE rover: it
// drives 8 CADRE frames (80 x 50 pixels) 0.3 m apart along x, every move through a PatchStitcher
// beside its PatchKeeper (patches of 16 x 16 cells in a caller region); then the chain is filled to
// its kMaxNodes with moves that write nothing, a loop is closed over the whole chain and the
// patches are re-stamped, kPerStep a call. Regions (tests/support/icount_marker.hpp):
//   1  PatchStitcher::move_to of a drive step (the keeper's move and the log of its writes)
//   2  PatchStitcher::close_loop over a full chain (kMaxNodes nodes, every logged patch marked)
//   3  PatchStitcher::restamp_step, kPerStep patches a call (each read, checked, resealed, written)
// On other targets the markers are empty and the program checks that every call succeeds.
//
//   icount_stitch_example
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "ccmap/global/patch_stitcher.hpp"
#include "support/cadre_frames.hpp"
#include "support/icount_marker.hpp"

namespace {
constexpr std::size_t kNodes = 128U;
constexpr std::size_t kPatches = 256U;
constexpr std::uint32_t kPerStep = 4U;
}  // namespace

int main() {
  constexpr int kFrames = 8;  // CADRE frames of 80 x 50 pixels, 0.3 m apart
  using Map = ccmap::Stack<ccmap::CadreConfig>;
  using Keeper = ccmap::PatchKeeper<ccmap::CadreConfig, 16>;
  using Stitcher = ccmap::PatchStitcher<kNodes, kPatches>;
  const auto map = std::make_unique<Map>();
  const auto keeper = std::make_unique<Keeper>();
  const auto stitcher = std::make_unique<Stitcher>();
  const std::size_t slot_bytes = Keeper::kMaxPatchBytes + ccmap::platform::RegionPatchStorage::kSlotHeaderBytes;
  std::vector<std::uint8_t> region(512U * slot_bytes);
  const auto storage = std::make_unique<ccmap::platform::RegionPatchStorage>();
  if (map->init(ccmap::default_stack_params(0.04F)) != ccmap::Status::kOk ||
      !storage->init(region.data(), region.size(), slot_bytes) ||
      keeper->init(*map, storage->table()) != ccmap::Status::kOk || stitcher->attach(*keeper) != ccmap::Status::kOk) {
    std::fprintf(stderr, "icount_stitch_example: init failed\n");
    return 1;
  }
  std::uint32_t most_written = 0U;
  float x = 0.0F;
  float sigma = 0.0F;
  for (int k = 0; k < kFrames; ++k) {
    ccmap::test::CadreFrameSpec spec;
    spec.width_px = 80;
    spec.height_px = 50;
    spec.sensor_x = 0.3F * static_cast<float>(k);
    spec.seed = static_cast<std::uint32_t>(k) + 1U;
    const ccmap::test::CadreFrame f = ccmap::test::make_cadre_frame(spec);
    x = spec.sensor_x;
    sigma = 0.01F * static_cast<float>(k);
    ccmap::PatchMoveReport report{};
    const ccmap::PatchPose stamp{spec.sensor_x, spec.sensor_y, 0.0F, sigma, 0.1F * sigma};
    ccmap::test::icount_begin<1>();
    const ccmap::Status moved = stitcher->move_to(*keeper, spec.sensor_x, spec.sensor_y, stamp, &report);
    ccmap::test::icount_end<1>();
    if (moved != ccmap::Status::kOk ||
        map->update_frame_sensor(f.sensor_points.data(), f.sensor_points.size(), f.pose, nullptr) !=
            ccmap::Status::kOk) {
      std::fprintf(stderr, "icount_stitch_example: frame %d refused\n", k);
      return 1;
    }
    most_written = report.patches_written > most_written ? report.patches_written : most_written;
  }
  // The chain filled with moves that write nothing (the rover standing), then the jump back to
  // the start as the last node: its patches are logged too.
  while (stitcher->node_count() + 1U < kNodes) {
    if (stitcher->move_to(*keeper, x, 0.0F, ccmap::PatchPose{x, 0.0F, 0.0F, sigma, 0.1F * sigma}, nullptr) !=
        ccmap::Status::kOk) {
      return 1;
    }
  }
  if (stitcher->move_to(*keeper, 0.0F, 0.0F, ccmap::PatchPose{0.0F, 0.0F, 0.0F, sigma, 0.1F * sigma}, nullptr) !=
          ccmap::Status::kOk ||
      stitcher->node_count() != kNodes) {
    return 1;
  }
  ccmap::test::icount_begin<2>();
  const ccmap::Status closed = stitcher->close_loop(0U, 0.05F, -0.03F, 0.01F);
  ccmap::test::icount_end<2>();
  const std::uint32_t marked = stitcher->pending();
  std::uint32_t calls = 0U;
  std::uint32_t restamped = 0U;
  ccmap::StitchReport r{};
  do {
    ccmap::test::icount_begin<3>();
    stitcher->restamp_step(*keeper, kPerStep, &r);
    ccmap::test::icount_end<3>();
    restamped += r.restamped;
    ++calls;
  } while (r.remaining > 0U && calls < 1000U);
  if (closed != ccmap::Status::kOk || r.remaining != 0U || restamped != marked || stitcher->restamp_failures() != 0U ||
      stitcher->untracked_writes() != 0U) {
    std::fprintf(stderr, "icount_stitch_example: the closure failed\n");
    return 1;
  }
  std::printf("icount_stitch_example: %d frames, most patches written by a step %u; chain %zu nodes, %zu patches "
              "logged, %u re-stamped in %u calls of %u; stitcher %zu bytes\n",
              kFrames, most_written, stitcher->node_count(), stitcher->logged_patches(), restamped, calls, kPerStep,
              sizeof(Stitcher));
  return 0;
}
