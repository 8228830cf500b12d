// Instruction counts of a CADRE rover's cycle with map exchange (docs/performance.md): a rover
// drives 0.3 m per frame (CADRE frames of tests/support/cadre_frames.hpp, sensor frame), its
// exchange exports a delta every `every` frames, and a team mate (a second stack that drove the
// same path with its own frames) merges it. Regions (tests/support/icount_marker.hpp):
//   1  update_frame_sensor of the rover      2  move_to of the rover
//   3  export_delta                          4  merge_delta by the team mate
// so that the update path's cost can be compared with and without exchange, and an exchange's
// cost stated per delta. On other targets the markers are empty and the program checks that
// every call succeeds.
//
//   icount_exchange_example [frames every width_px height_px]   default: 6 3 80 50
//   (10 5 850 650: the figures of docs/performance.md)
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "ccmap/persistence/exchange.hpp"
#include "support/cadre_frames.hpp"
#include "support/icount_marker.hpp"

namespace {
bool parse(const char* text, int max, int* value) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v < 1 || v > max) {
    return false;
  }
  *value = static_cast<int>(v);
  return true;
}
}  // namespace

int main(int argc, char** argv) {
  int frames = 6, every = 3, width_px = 80, height_px = 50;
  if (argc != 1 && (argc != 5 || !parse(argv[1], 1000, &frames) || !parse(argv[2], 1000, &every) ||
                    !parse(argv[3], 4000, &width_px) || !parse(argv[4], 4000, &height_px))) {
    std::fprintf(stderr, "usage: icount_exchange_example [frames every width_px height_px]\n");
    return 2;
  }
  using Map = ccmap::Stack<ccmap::CadreConfig>;
  using Exchange = ccmap::MapExchange<ccmap::CadreConfig>;
  // On the heap, as the timing test and icount_stack_example (the counts are of the same code).
  const auto rover = std::make_unique<Map>();
  const auto mate = std::make_unique<Map>();
  const auto rover_exchange = std::make_unique<Exchange>();
  const auto mate_exchange = std::make_unique<Exchange>();
  const ccmap::StackParams params = ccmap::default_stack_params(0.04F);
  if (rover->init(params) != ccmap::Status::kOk || mate->init(params) != ccmap::Status::kOk ||
      rover_exchange->init(*rover, ccmap::ExchangeParams{1U, 1U, ccmap::CellIndex{0, 0}, 0.0F}) != ccmap::Status::kOk ||
      mate_exchange->init(*mate, ccmap::ExchangeParams{2U, 1U, ccmap::CellIndex{0, 0}, 0.0F}) != ccmap::Status::kOk) {
    std::fprintf(stderr, "icount_exchange_example: init failed\n");
    return 1;
  }
  std::vector<std::uint8_t> delta(Exchange::max_delta_size());
  std::size_t bytes = 0, cells = 0;
  for (int k = 0; k < frames; ++k) {
    ccmap::test::CadreFrameSpec spec;
    spec.width_px = width_px;
    spec.height_px = height_px;
    spec.sensor_x = 0.3F * static_cast<float>(k);
    spec.seed = static_cast<std::uint32_t>(k) + 1U;
    const ccmap::test::CadreFrame f = ccmap::test::make_cadre_frame(spec);
    spec.seed += 1000U;  // the team mate's frame from the same place: other noise
    const ccmap::test::CadreFrame g = ccmap::test::make_cadre_frame(spec);
    ccmap::FrameCounters counters{};
    ccmap::test::icount_begin<2>();
    const ccmap::Status moved = rover->move_to(spec.sensor_x, spec.sensor_y);
    ccmap::test::icount_end<2>();
    ccmap::test::icount_begin<1>();
    const ccmap::Status updated = rover->update_frame_sensor(f.sensor_points.data(), f.sensor_points.size(), f.pose, &counters);
    ccmap::test::icount_end<1>();
    if (moved != ccmap::Status::kOk || updated != ccmap::Status::kOk || mate->move_to(spec.sensor_x, spec.sensor_y) != ccmap::Status::kOk ||
        mate->update_frame_sensor(g.sensor_points.data(), g.sensor_points.size(), g.pose, nullptr) != ccmap::Status::kOk) {
      std::fprintf(stderr, "icount_exchange_example: frame %d refused\n", k);
      return 1;
    }
    if ((k + 1) % every == 0) {
      std::size_t written = 0;
      ccmap::ExportReport report{};
      ccmap::test::icount_begin<3>();
      const ccmap::Status exported =
          rover_exchange->export_delta(delta.data(), delta.size(), ccmap::ExportOptions{0.0F, 0}, &written, &report);
      ccmap::test::icount_end<3>();
      ccmap::test::icount_begin<4>();
      const ccmap::Status merged = mate_exchange->merge_delta(delta.data(), written, nullptr);
      ccmap::test::icount_end<4>();
      if (exported != ccmap::Status::kOk || merged != ccmap::Status::kOk) {
        std::fprintf(stderr, "icount_exchange_example: exchange after frame %d failed\n", k);
        return 1;
      }
      bytes += written;
      cells += report.cells_written;
    }
  }
  std::printf("icount_exchange_example: %d frames, %zu delta bytes, %zu cells\n", frames, bytes, cells);
  return 0;
}
