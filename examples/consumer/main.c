/* Minimal C99 consumer of an installed ccmap through the C API (ccmap/ccmap.h): the map in
 * static storage, one frame of a tilted plane, one query, a snapshot round trip. */
#include <math.h>
#include <stdio.h>

#include "ccmap/ccmap.h"

static ccmap_cadre_storage g_storage;
static float g_xyz[3 * 120 * 120];
static uint8_t g_snapshot[CCMAP_CADRE_SNAPSHOT_SIZE];

int main(void) {
  ccmap_map* map = NULL;
  ccmap_params params;
  ccmap_frame_counters counters;
  ccmap_query_result q;
  const float sensor[3] = {0.0f, 0.0f, 0.175f};
  size_t n = 0;
  size_t written = 0;
  int i, j;
  ccmap_status s = ccmap_place(&g_storage, sizeof g_storage, CCMAP_PRESET_CADRE, &map);
  if (s == CCMAP_OK) s = ccmap_default_params(CCMAP_PRESET_CADRE, &params);
  if (s == CCMAP_OK) s = ccmap_init(map, &params);
  if (s != CCMAP_OK) {
    fprintf(stderr, "ccmap set-up failed: %s\n", ccmap_status_string(s));
    return 1;
  }
  for (j = 0; j < 120; ++j) {
    for (i = 0; i < 120; ++i) {
      const float x = 0.3f + 0.01f * (float)i;
      g_xyz[3 * n] = x;
      g_xyz[3 * n + 1] = -0.6f + 0.01f * (float)j;
      g_xyz[3 * n + 2] = 0.1f * x;
      ++n;
    }
  }
  s = ccmap_update_frame(map, g_xyz, NULL, n, sensor, &counters);
  if (s != CCMAP_OK) return 1;
  ccmap_query(map, 0.9f, 0.1f, &q);
  s = ccmap_save_snapshot(map, g_snapshot, sizeof g_snapshot, &written);
  if (s == CCMAP_OK) s = ccmap_load_snapshot(map, g_snapshot, written);
  printf("ccmap consumer (C, platform %s): %u of %u points used; query (0.9, 0.1): %s, layer %d, "
         "height %.4f m, class %s; snapshot round trip %s\n",
         ccmap_platform_name(), (unsigned)counters.used, (unsigned)counters.received,
         ccmap_status_string((ccmap_status)q.status), (int)q.layer, (double)q.height_m,
         ccmap_cell_class_string(q.cell_class), ccmap_status_string(s));
  return (q.status == CCMAP_OK && fabs(q.height_m - 0.09) < 0.01 && s == CCMAP_OK) ? 0 : 1;
}
