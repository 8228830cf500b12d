// Instruction counts of the global map's patch keeper (include/ccmap/global/patch_keeper.hpp) on
// a CADRE rover: it drives `frames` CADRE frames 0.3 m apart along x (sensor frames), every move
// through the keeper (patches of 16 x 16 cells in a caller region), then jumps back to the start
// (every window leaves whole and the start's patches come back). Regions
// (tests/support/icount_marker.hpp):
//   1  PatchKeeper::move_to of a drive step (patch reads and writes of the cells that left)
//   2  update_frame_sensor (the frame's cost beside it)
//   3  the jump back to the start (every window left whole; only tiles with observed cells written)
//   4  a loop closure's alignment: CoarseAligner::align of a second map of the same ground (the
//      drive's frames moved by 0.5 m, 0.3 m) against the rover's, default search (+-2 m, +-20 deg)
//   5  the literal worst move: two places 138 m apart, every cell of every window observed at
//      both and both kept before, the first observed again; the jump from it to the other
//      writes every tile of every window (max_writes_per_move) after reading each, and reads
//      every tile it lands on
// On other targets the markers are empty and the program checks that every call succeeds.
//
//   icount_patch_example [frames width_px height_px]   default: 8 80 50
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "ccmap/global/coarse_alignment.hpp"
#include "ccmap/global/patch_keeper.hpp"
#include "support/cadre_frames.hpp"
#include "support/count_arg.hpp"
#include "support/icount_marker.hpp"

int main(int argc, char** argv) {
  int frames = 8, width_px = 80, height_px = 50;
  if (argc != 1 &&
      (argc != 4 || !ccmap::test::parse_count(argv[1], 1000, &frames) ||
       !ccmap::test::parse_count(argv[2], 4000, &width_px) || !ccmap::test::parse_count(argv[3], 4000, &height_px))) {
    std::fprintf(stderr, "usage: icount_patch_example [frames width_px height_px]\n");
    return 2;
  }
  using Map = ccmap::Stack<ccmap::CadreConfig>;
  using Keeper = ccmap::PatchKeeper<ccmap::CadreConfig, 16>;
  const auto map = std::make_unique<Map>();
  const auto keeper = std::make_unique<Keeper>();
  const std::size_t slot_bytes = Keeper::kMaxPatchBytes + ccmap::platform::RegionPatchStorage::kSlotHeaderBytes;
  std::vector<std::uint8_t> region(512U * slot_bytes);
  const auto storage = std::make_unique<ccmap::platform::RegionPatchStorage>();
  if (map->init(ccmap::default_stack_params(0.04F)) != ccmap::Status::kOk ||
      !storage->init(region.data(), region.size(), slot_bytes) ||
      keeper->init(*map, storage->table()) != ccmap::Status::kOk) {
    std::fprintf(stderr, "icount_patch_example: init failed\n");
    return 1;
  }
  const auto other = std::make_unique<Map>();
  if (other->init(ccmap::default_stack_params(0.04F)) != ccmap::Status::kOk) {
    return 1;
  }
  std::uint32_t most_written = 0U;
  for (int k = 0; k < frames; ++k) {
    ccmap::test::CadreFrameSpec spec;
    spec.width_px = width_px;
    spec.height_px = height_px;
    spec.sensor_x = 0.3F * static_cast<float>(k);
    spec.seed = static_cast<std::uint32_t>(k) + 1U;
    const ccmap::test::CadreFrame f = ccmap::test::make_cadre_frame(spec);
    ccmap::PatchMoveReport report{};
    const ccmap::PatchPose stamp{spec.sensor_x, spec.sensor_y, 0.0F, 0.01F, 0.001F};
    ccmap::test::icount_begin<1>();
    const ccmap::Status moved = keeper->move_to(spec.sensor_x, spec.sensor_y, stamp, &report);
    ccmap::test::icount_end<1>();
    ccmap::test::icount_begin<2>();
    const ccmap::Status updated =
        map->update_frame_sensor(f.sensor_points.data(), f.sensor_points.size(), f.pose, nullptr);
    ccmap::test::icount_end<2>();
    if (moved != ccmap::Status::kOk || updated != ccmap::Status::kOk || report.patches_written > Keeper::max_writes_per_step()) {
      std::fprintf(stderr, "icount_patch_example: frame %d refused\n", k);
      return 1;
    }
    most_written = report.patches_written > most_written ? report.patches_written : most_written;
    // The second map: the same ground, its frame 0.5 m, 0.3 m off (it drives the same path).
    std::vector<ccmap::PointXYZ> shifted = f.map_points;
    for (ccmap::PointXYZ& p : shifted) {
      p.x += 0.5F;
      p.y += 0.3F;
    }
    const ccmap::PointXYZ origin{f.sensor_origin.x + 0.5F, f.sensor_origin.y + 0.3F, f.sensor_origin.z};
    if (other->move_to(origin.x, origin.y) != ccmap::Status::kOk ||
        other->update_frame(shifted.data(), shifted.size(), origin, nullptr) != ccmap::Status::kOk) {
      return 1;
    }
  }
  ccmap::PatchMoveReport jump{};
  ccmap::test::icount_begin<3>();
  const ccmap::Status back = keeper->move_to(0.0F, 0.0F, ccmap::PatchPose{}, &jump);
  ccmap::test::icount_end<3>();
  if (back != ccmap::Status::kOk || jump.patches_written > Keeper::max_writes_per_move() || jump.cells_restored == 0U ||
      keeper->counters().cells_lost != 0U) {
    std::fprintf(stderr, "icount_patch_example: the jump back failed\n");
    return 1;
  }
  const auto aligner = std::make_unique<ccmap::CoarseAligner<ccmap::CadreConfig>>();
  ccmap::CoarseReport coarse{};
  ccmap::test::icount_begin<4>();
  const ccmap::AlignmentResult a =
      aligner->align(*map, *other, ccmap::MapOffset{0.0F, 0.0F, 0.0F}, ccmap::default_registration_params(),
                     ccmap::default_coarse_search_params(), &coarse);
  ccmap::test::icount_end<4>();
  std::printf("icount_patch_example: alignment %s, dx %.3f dy %.3f dyaw %.4f, rank %u (search: %u candidates, "
              "%u samples, best %.3f %.3f %.4f, %u matched)\n",
              ccmap::to_string(a.correction.status), static_cast<double>(a.correction.dx),
              static_cast<double>(a.correction.dy), static_cast<double>(a.correction.dyaw),
              static_cast<unsigned>(a.correction.rank), coarse.candidates, coarse.samples,
              static_cast<double>(coarse.dx_m), static_cast<double>(coarse.dy_m), static_cast<double>(coarse.dyaw_rad),
              coarse.matched);
  std::printf("icount_patch_example: %d frames, most patches written by a drive step %u (bound %u), jump: %u written, "
              "%u read, %u cells restored (bound %u writes); patch %zu bytes\n",
              frames, most_written, Keeper::max_writes_per_step(), jump.patches_written, jump.patches_read,
              jump.cells_restored, Keeper::max_writes_per_move(), Keeper::kCcmPatchBytes);
  // Region 5: places A (101, 3) and B (3, 101), where every layer's window straddles 5 x 5 tiles,
  // every cell of every window observed:
  // for each layer a lattice of two points per cell width over its window, fed in blocks with
  // the sensor above each at a height whose range only that layer takes (Section IV-G: CADRE's
  // layers take ranges up to 1.32, 1.86, 2.63, 3.72, 5.26 m). A is kept by a jump to B, B by
  // the jump back to A, A observed again (every stored patch of A changes); then A -> B again.
  const auto fill = [&](float cx, float cy) {
    const float heights[Map::kLayerCount] = {1.2F, 1.6F, 2.2F, 3.2F, 4.5F};
    const float blocks[Map::kLayerCount] = {0.5F, 0.5F, 1.0F, 1.0F, 2.0F};
    std::vector<ccmap::PointXYZ> block;
    for (int layer = 0; layer < Map::kLayerCount; ++layer) {
      const float w = map->layer_cell_width(layer);
      const float half = 0.5F * static_cast<float>(Map::layer_side(layer)) * w + w;
      const float b = blocks[layer];
      for (float by = -half; by < half; by += b) {
        for (float bx = -half; bx < half; bx += b) {
          block.clear();
          for (float v = 0.25F * w; v < b; v += 0.5F * w) {
            for (float u = 0.25F * w; u < b; u += 0.5F * w) {
              block.push_back(ccmap::PointXYZ{cx + bx + u, cy + by + v, 0.0F});
            }
          }
          const ccmap::PointXYZ origin{cx + bx + 0.5F * b, cy + by + 0.5F * b, heights[layer]};
          if (map->update_frame(block.data(), block.size(), origin, nullptr) != ccmap::Status::kOk) {
            return false;
          }
        }
      }
    }
    return true;
  };
  const ccmap::PatchPose still{0.0F, 0.0F, 0.0F, 0.0F, 0.0F};
  ccmap::PatchMoveReport worst{};
  if (keeper->move_to(101.0F, 3.0F, still, nullptr) != ccmap::Status::kOk || !fill(101.0F, 3.0F) ||
      keeper->move_to(3.0F, 101.0F, still, nullptr) != ccmap::Status::kOk || !fill(3.0F, 101.0F) ||
      keeper->move_to(101.0F, 3.0F, still, nullptr) != ccmap::Status::kOk || !fill(101.0F, 3.0F)) {
    std::fprintf(stderr, "icount_patch_example: the worst move's set-up failed\n");
    return 1;
  }
  ccmap::test::icount_begin<5>();
  const ccmap::Status jumped = keeper->move_to(3.0F, 101.0F, still, &worst);
  ccmap::test::icount_end<5>();
  std::printf("icount_patch_example: the worst move: %u written, %u read, %u cells saved, %u restored, %u lost\n",
              worst.patches_written, worst.patches_read, worst.cells_saved, worst.cells_restored, worst.cells_lost);
  if (jumped != ccmap::Status::kOk || worst.patches_written != Keeper::max_writes_per_move() ||
      worst.patches_read != 2U * Keeper::max_writes_per_move() || worst.cells_lost != 0U) {
    std::fprintf(stderr, "icount_patch_example: the worst move did not write and read every tile\n");
    return 1;
  }
  return 0;
}
