// A minimal flight-like image of one preset, for the memory figures of docs/performance.md and
// docs/integration.md: the map and a frame buffer of CCMAP_FOOTPRINT_FRAME_POINTS points in
// static storage (.bss), one cycle of the run-phase calls (move_to, update_frame,
// update_frame_sensor, query, query_layer), exit code 0 if every call answered as it should
// (else the number of the first call that did not). Its
// arm-none-eabi-size is what an integration of that preset costs, this board layer included
// (the export and snapshot buffers an integration adds are listed beside the figures).
#include <cstdint>

#include "ccmap/map/stack.hpp"

#ifndef CCMAP_FOOTPRINT_CONFIG
#error "CCMAP_FOOTPRINT_CONFIG (a preset of ccmap/map/config.hpp) is not defined"
#endif
#ifndef CCMAP_FOOTPRINT_FRAME_POINTS
#error "CCMAP_FOOTPRINT_FRAME_POINTS is not defined"
#endif

namespace {
using Map = ccmap::Stack<ccmap::CCMAP_FOOTPRINT_CONFIG>;
Map g_map;
ccmap::PointXYZ g_frame[CCMAP_FOOTPRINT_FRAME_POINTS];
}  // namespace

int main() {
  constexpr std::uint32_t n = CCMAP_FOOTPRINT_FRAME_POINTS;
  if (g_map.init(ccmap::default_stack_params(ccmap::CCMAP_FOOTPRINT_CONFIG::kDefaultFinestCellWidthM)) !=
      ccmap::Status::kOk) {
    return 1;
  }
  if (g_map.move_to(0.0F, 0.0F) != ccmap::Status::kOk) {
    return 2;
  }
  // A gently sloped plane, 200 x 100 points every cm, seen from 0.5 m above the origin.
  for (std::uint32_t i = 0; i < n; ++i) {
    const float x = static_cast<float>(i % 200U) / 100.0F - 1.0F;
    const float y = static_cast<float>((i / 200U) % 100U) / 100.0F - 0.5F;
    g_frame[i] = ccmap::PointXYZ{x, y, 0.1F * x - 0.05F * y};
  }
  ccmap::FrameCounters counters{};
  if (g_map.update_frame(g_frame, n, ccmap::PointXYZ{0.0F, 0.0F, 0.5F}, &counters) != ccmap::Status::kOk ||
      counters.used != n) {
    return 3;
  }
  const ccmap::Pose pose{{{1.0F, 0.0F, 0.0F}, {0.0F, 1.0F, 0.0F}, {0.0F, 0.0F, 1.0F}}, ccmap::PointXYZ{0.0F, 0.0F, 0.5F}};
  for (std::uint32_t i = 0; i < n; ++i) {
    g_frame[i].z -= 0.5F;  // the same points in the sensor frame
  }
  if (g_map.update_frame_sensor(g_frame, n, pose, &counters) != ccmap::Status::kOk || counters.used != n) {
    return 4;
  }
  if (g_map.query(0.3F, 0.2F).status != ccmap::Status::kOk) {
    return 5;
  }
  if (g_map.query_layer(Map::kLayerCount - 1, 0.3F, 0.2F).status == ccmap::Status::kInvalidArgument) {
    return 6;
  }
  return 0;
}
