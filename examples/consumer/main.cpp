// Minimal C++ consumer of an installed ccmap: a CADRE stack in static storage, one frame of a
// tilted plane seen by the CADRE stereo camera, one query. Exit status 0 if the map answers the
// plane's height and slope.
#include <cmath>
#include <cstdio>

#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/map/stack.hpp"

namespace {
ccmap::Stack<ccmap::CadreConfig> g_map;  // ~430 KB: static storage, never on a task stack
ccmap::PointXYZ g_points[120 * 120];
std::uint8_t g_snapshot[ccmap::snapshot_size<ccmap::CadreConfig>()];
}  // namespace

int main() {
  if (g_map.init(ccmap::default_stack_params(0.04F)) != ccmap::Status::kOk) {
    return 1;
  }
  if (g_map.move_to(0.0F, 0.0F) != ccmap::Status::kOk) {
    return 1;
  }
  // Plane z = 0.1 x sampled every 1 cm over [0.3, 1.5) x [-0.6, 0.6) m.
  std::size_t n = 0;
  for (int j = 0; j < 120; ++j) {
    for (int i = 0; i < 120; ++i) {
      const float x = 0.3F + 0.01F * static_cast<float>(i);
      const float y = -0.6F + 0.01F * static_cast<float>(j);
      g_points[n++] = ccmap::PointXYZ{x, y, 0.1F * x};
    }
  }
  ccmap::FrameCounters counters{};
  const ccmap::PointXYZ sensor{0.0F, 0.0F, 0.175F};
  if (g_map.update_frame(g_points, n, sensor, &counters) != ccmap::Status::kOk) {
    return 1;
  }
  const ccmap::QueryResult q = g_map.query(0.9F, 0.1F);
  std::size_t written = 0;
  const ccmap::Status saved = ccmap::save_snapshot(g_map, g_snapshot, sizeof g_snapshot, &written);
  std::printf("ccmap consumer (C++, platform %s): %u of %u points used; query (0.9, 0.1): %s, "
              "layer %d, height %.4f m, slope_x %.3f, class %s; snapshot %s, %zu bytes\n",
              ccmap::platform::name(), counters.used, counters.received, ccmap::to_string(q.status),
              static_cast<int>(q.layer), static_cast<double>(q.height_m), static_cast<double>(q.slope_x),
              ccmap::to_string(q.cell_class), ccmap::to_string(saved), written);
  const bool ok = q.status == ccmap::Status::kOk && std::fabs(q.height_m - 0.09F) < 0.01F &&
                  std::fabs(q.slope_x - 0.1F) < 0.02F && saved == ccmap::Status::kOk;
  return ok ? 0 : 1;
}
