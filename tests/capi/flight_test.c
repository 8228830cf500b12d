/* The flight interface of the C API from plain C99: parameters as commands (validate, get, set
 * keeping the cells), health and counter reset, the map product (publish, read, decode), and
 * CCMAP_CORRUPT against misuse. References are independent of the call under test: ccmap_init's
 * own answers for validation, a second map initialised with the new parameters and fed the same
 * frames (bitwise equal snapshots) for set_params, the storage's bytes for a refused change,
 * export_layer for the observed cells, the queries and ccmap_fill_costmap for every product cell,
 * and a bitwise CRC-32 written here for the CRCs.
 *
 * One case of the portable harness (flight_case.cpp), host and aarch64 Linux (QEMU). */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "capi_checks.h"

static ccmap_cadre_storage g_a;
static ccmap_cadre_storage g_b;
static ccmap_cadre_storage g_copy;
static uint8_t g_snap_a[CCMAP_CADRE_SNAPSHOT_SIZE];
static uint8_t g_snap_b[CCMAP_CADRE_SNAPSHOT_SIZE];
static ccmap_cell_record g_records[64 * 64];
static ccmap_cell_record g_records_after[64 * 64];

#define SIDE 120
static float g_xyz[3 * SIDE * SIDE];

/* Products of up to 64 x 64 cells: two slots and the staging area. */
#define PRODUCT_CELLS (64u * 64u)
static uint32_t g_product_storage[CCMAP_PRODUCT_BUFFERS_STORAGE_SIZE(PRODUCT_CELLS) / 4u];
static uint8_t g_product[CCMAP_PRODUCT_SIZE(64u, 64u)];
static ccmap_product_cell g_cells[PRODUCT_CELLS];
static uint8_t g_costs[PRODUCT_CELLS];

/* CRC-32 (IEEE 802.3), bit by bit: the reference for the library's table-driven one. */
static uint32_t crc32_bitwise(const uint8_t* data, size_t size) {
  uint32_t c = 0xFFFFFFFFu;
  size_t i;
  int k;
  for (i = 0; i < size; ++i) {
    c ^= data[i];
    for (k = 0; k < 8; ++k) {
      c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    }
  }
  return ~c;
}

/* A slope z = 0.05 x with a 25 cm box at x in [0.4, 0.6), y in [-0.2, 0.2), sampled every
 * 1.5 cm over [-0.9, 0.9)^2 around (cx, cy), shifted by phase (0 .. 1) of a sample. */
static size_t make_terrain(float cx, float cy, float phase) {
  size_t n = 0;
  int i, j;
  for (j = 0; j < SIDE; ++j) {
    for (i = 0; i < SIDE; ++i) {
      const float dx = -0.9f + 0.015f * ((float)i + phase);
      const float dy = -0.9f + 0.015f * ((float)j + phase);
      const int box = dx >= 0.4f && dx < 0.6f && dy >= -0.2f && dy < 0.2f;
      g_xyz[3 * n] = cx + dx;
      g_xyz[3 * n + 1] = cy + dy;
      g_xyz[3 * n + 2] = 0.05f * (cx + dx) + (box ? 0.25f : 0.0f);
      ++n;
    }
  }
  return n;
}

/* Three frames and a move between them: the same sequence for every map that must agree. */
static void feed(ccmap_map* map) {
  const float sensor0[3] = {0.0f, 0.0f, 0.8f};
  const float sensor1[3] = {0.3f, 0.1f, 0.8f};
  size_t n = make_terrain(0.0f, 0.0f, 0.0f);
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, sensor0, NULL), CCMAP_OK);
  n = make_terrain(0.0f, 0.0f, 0.5f);
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, sensor0, NULL), CCMAP_OK);
  CHECK_STATUS(ccmap_move_to(map, 0.3f, 0.1f), CCMAP_OK);
  n = make_terrain(0.3f, 0.1f, 0.25f);
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, sensor1, NULL), CCMAP_OK);
}

/* Two snapshots of maps that must agree: every byte (a snapshot holds no clock reading). */
static int same_snapshot(const uint8_t* a, const uint8_t* b) {
  return memcmp(a, b, CCMAP_CADRE_SNAPSHOT_SIZE) == 0;
}

static ccmap_map* place(ccmap_cadre_storage* storage) {
  ccmap_map* map = NULL;
  CHECK_STATUS(ccmap_place(storage, sizeof *storage, CCMAP_PRESET_CADRE, &map), CCMAP_OK);
  return map;
}

static size_t snapshot(const ccmap_map* map, uint8_t* out) {
  size_t written = 0;
  CHECK_STATUS(ccmap_save_snapshot(map, out, CCMAP_CADRE_SNAPSHOT_SIZE, &written), CCMAP_OK);
  return written;
}

/* validate_params answers exactly what ccmap_init answers, and touches no map. */
static void test_validate_params(void) {
  ccmap_map* map = place(&g_a);
  ccmap_params p, q;
  int preset;
  int k;
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_validate_params(CCMAP_PRESET_CADRE, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_validate_params((ccmap_preset)9, &p), CCMAP_INVALID_ARGUMENT);
  for (preset = 0; preset <= 3; ++preset) {
    CHECK(ccmap_preset_available((ccmap_preset)preset) == 1);
    CHECK_STATUS(ccmap_default_params((ccmap_preset)preset, &q), CCMAP_OK);
    CHECK_STATUS(ccmap_validate_params((ccmap_preset)preset, &q), CCMAP_OK);
  }
  CHECK(ccmap_preset_available((ccmap_preset)4) == 0);
  /* Each bad set against the answer of ccmap_init on a real map. */
  for (k = 0; k < 9; ++k) {
    ccmap_status by_init;
    q = p;
    switch (k) {
      case 0: q.coverage_tau = 1.5f; break;
      case 1: q.coverage_tau = (float)NAN; break;
      case 2: q.finest_cell_width_m = 0.0f; break;
      case 3: q.outlier_gate_sigma = 0.5f; break;
      case 4: q.change_share = 0.7f; break;
      case 5: q.noise.sensor = 7; break;
      case 6: q.noise.stereo_baseline_m = -1.0f; break;
      case 7: q.finest_max_sigma_m = 1.0f; break; /* starves layer 1 */
      default: q.weight_limit = 1e-4f; break;
    }
    by_init = ccmap_init(map, &q);
    CHECK(by_init != CCMAP_OK);
    CHECK_STATUS(ccmap_validate_params(CCMAP_PRESET_CADRE, &q), by_init);
  }
  CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_validate_params(CCMAP_PRESET_CADRE, &p), ccmap_init(map, &p));
}

/* The parameters read back are the ones given (bitwise), and the CRC in the health is theirs. */
static void test_get_params(void) {
  ccmap_map* map = place(&g_a);
  ccmap_params p, got;
  ccmap_health h;
  CHECK_STATUS(ccmap_get_params(map, &got), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
  p.noise.sensor = CCMAP_SENSOR_LIDAR;
  p.noise.lidar_sigma0_m = 0.002f;
  p.noise.lidar_sigma_per_m = 0.001f;
  p.coverage_tau = 0.7f;
  CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_get_params(map, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_get_params(map, &got), CCMAP_OK);
  CHECK(memcmp(&got, &p, sizeof p) == 0);
  CHECK_STATUS(ccmap_get_health(map, &h), CCMAP_OK);
  CHECK(h.params_crc == crc32_bitwise((const uint8_t*)&p, sizeof p));
  /* A snapshot brings its own parameters: read back as the map runs with them (the same model;
   * a map initialised with what get_params answers saves the same bytes). */
  feed(map);
  snapshot(map, g_snap_a);
  {
    ccmap_map* b = place(&g_b);
    ccmap_params from_snapshot;
    CHECK_STATUS(ccmap_load_snapshot(b, g_snap_a, CCMAP_CADRE_SNAPSHOT_SIZE), CCMAP_OK);
    CHECK_STATUS(ccmap_get_params(b, &from_snapshot), CCMAP_OK);
    CHECK(from_snapshot.noise.sensor == CCMAP_SENSOR_LIDAR);
    CHECK(from_snapshot.coverage_tau == 0.7f);
    CHECK_STATUS(ccmap_init(b, &from_snapshot), CCMAP_OK);
    feed(b);
    CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);
    feed(map);
    snapshot(map, g_snap_a);
    snapshot(b, g_snap_b);
    CHECK(same_snapshot(g_snap_a, g_snap_b));
  }
}

/* An allowed change: map A initialised with P1, changed to P2, fed F; map B initialised with P2,
 * fed F: bitwise the same snapshot (cells, parameters, counters). */
static void test_set_params_equivalence(void) {
  ccmap_map* a = place(&g_a);
  ccmap_map* b = place(&g_b);
  ccmap_params p1, p2;
  uint32_t mask = 99u;
  int k;
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p1), CCMAP_OK);
  for (k = 0; k < 8; ++k) {
    p2 = p1;
    switch (k) {
      case 0: p2.coverage_tau = 0.6f; p2.max_inclination = 0.2f; break;
      case 1: p2.outlier_gate_sigma = 0.0f; break;
      case 2: p2.outlier_gate_sigma = 5.0f; p2.change_min_points = 5.0f; p2.change_share = 0.2f; break;
      case 3: p2.frame_point_budget = 5000u; break;
      case 4: p2.free_space_rays = 0.0f; break;
      case 5: p2.obstacle_fraction = 0.5f; p2.normal_variance_threshold[2] = 1e-4f; break;
      case 6: p2.weight_limit = 50.0f; p2.min_weight = 2.0f; p2.kalman_min_variance = 1e-5f; break;
      default: p2.noise.weight_mode = CCMAP_WEIGHT_INVERSE_VARIANCE; p2.noise.reference_range_m = 1.0f; break;
    }
    CHECK_STATUS(ccmap_init(a, &p1), CCMAP_OK);
    mask = 99u;
    CHECK_STATUS(ccmap_set_params(a, &p2, &mask), CCMAP_OK);
    CHECK(mask == 0u);
    CHECK_STATUS(ccmap_init(b, &p2), CCMAP_OK);
    feed(a);
    feed(b);
    snapshot(a, g_snap_a);
    snapshot(b, g_snap_b);
    if (!CHECK(same_snapshot(g_snap_a, g_snap_b))) {
      ccmap_test_note("set_params then frames differs from init with the new parameters");
    }
  }
}

/* A change on a map with cells keeps every cell: the raw statistics of each layer's export
 * (weight, height, slopes; layer 0 is not pooled) before and after agree bitwise. */
static void test_set_params_keeps_cells(void) {
  ccmap_map* a = place(&g_a);
  ccmap_params p, q;
  ccmap_health before, after;
  ccmap_query_result r;
  size_t n0 = 0, n1 = 0, i;
  uint32_t mask = 0u;
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_init(a, &p), CCMAP_OK);
  feed(a);
  CHECK_STATUS(ccmap_get_health(a, &before), CCMAP_OK);
  CHECK_STATUS(ccmap_export_layer(a, 0, g_records, 64 * 64, &n0), CCMAP_OK);
  CHECK(n0 > 100u);
  /* The box top is an obstacle with the defaults; with a huge normal-variance threshold and
   * obstacle fraction it is not: classification changes, cells stay. */
  CHECK_STATUS(ccmap_query(a, 0.5f, 0.0f, &r), CCMAP_OK);
  q = p;
  q.max_inclination = 10.0f;
  CHECK_STATUS(ccmap_set_params(a, &q, &mask), CCMAP_OK);
  CHECK_STATUS(ccmap_export_layer(a, 0, g_records_after, 64 * 64, &n1), CCMAP_OK);
  CHECK(n0 == n1);
  for (i = 0; i < n0 && i < n1; ++i) {
    CHECK(g_records[i].weight == g_records_after[i].weight && g_records[i].height_m == g_records_after[i].height_m &&
          g_records[i].index_x == g_records_after[i].index_x && g_records[i].index_y == g_records_after[i].index_y);
  }
  CHECK_STATUS(ccmap_get_health(a, &after), CCMAP_OK);
  CHECK(after.params_changes == before.params_changes + 1u);
  CHECK(after.layers[0].observed_cells == before.layers[0].observed_cells);
  CHECK(after.layers[3].observed_cells == before.layers[3].observed_cells);
  CHECK(after.params_crc == crc32_bitwise((const uint8_t*)&q, sizeof q));
  CHECK(after.map_sequence == before.map_sequence);
  {
    ccmap_params got;
    CHECK_STATUS(ccmap_get_params(a, &got), CCMAP_OK);
    CHECK(memcmp(&got, &q, sizeof q) == 0);
  }
}

/* A refused change leaves the map's storage bitwise as it was, and says which fields. */
static void test_set_params_refusals(void) {
  ccmap_map* a = place(&g_a);
  ccmap_params p, q;
  uint32_t mask = 0u;
  int k;
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
  q = p;
  CHECK_STATUS(ccmap_set_params(a, &q, &mask), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_init(a, &p), CCMAP_OK);
  feed(a);
  for (k = 0; k < 6; ++k) {
    uint32_t expected_mask = 0u;
    ccmap_status expected = CCMAP_INVALID_ARGUMENT;
    q = p;
    switch (k) {
      case 0: CHECK_STATUS(ccmap_default_params_for_width(0.05f, &q), CCMAP_OK); q.coverage_tau = 0.7f;
              expected_mask = CCMAP_PARAM_FINEST_CELL_WIDTH_M | CCMAP_PARAM_FINEST_MAX_SIGMA_M; break;
      case 1: q.noise.stereo_focal_px = 500.0f; expected_mask = CCMAP_PARAM_NOISE; break;
      case 2: q.noise.sensor = CCMAP_SENSOR_LIDAR; q.noise.lidar_sigma0_m = 0.01f; expected_mask = CCMAP_PARAM_NOISE; break;
      case 3: q.finest_max_sigma_m = 0.5f * p.finest_max_sigma_m; expected_mask = CCMAP_PARAM_FINEST_MAX_SIGMA_M; break;
      case 4: q.coverage_tau = 1.5f; break;
      default: q.min_weight = (float)INFINITY; expected = CCMAP_NON_FINITE_INPUT; break;
    }
    memcpy(&g_copy, &g_a, sizeof g_a);
    mask = 0u;
    CHECK_STATUS(ccmap_set_params(a, &q, &mask), expected);
    CHECK_EQ(mask, expected_mask);
    if (!CHECK(memcmp(&g_copy, &g_a, sizeof g_a) == 0)) {
      ccmap_test_note("a refused set_params changed the map's storage");
    }
  }
  CHECK_STATUS(ccmap_set_params(a, NULL, &mask), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_set_params(a, &p, NULL), CCMAP_OK);
}

/* Health against what the test did, and the counter reset. */
static void test_health(void) {
  ccmap_map* a = place(&g_a);
  ccmap_params p;
  ccmap_health h;
  ccmap_counters counters;
  const float sensor[3] = {0.0f, 0.0f, 0.8f};
  size_t n, exported = 0, i, observed = 0;
  int layer;
  CHECK_STATUS(ccmap_get_health(a, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_get_health(a, &h), CCMAP_OK);
  CHECK(h.initialised == 0 && h.state == CCMAP_NOT_INITIALISED && h.preset == CCMAP_PRESET_CADRE);
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_init(a, &p), CCMAP_OK);
  feed(a);
  CHECK_STATUS(ccmap_update_frame(a, g_xyz, NULL, 3, NULL, NULL), CCMAP_INVALID_ARGUMENT); /* not counted */
  g_xyz[0] = (float)NAN;
  {
    const float bad_sensor[3] = {(float)NAN, 0.0f, 0.0f};
    CHECK_STATUS(ccmap_update_frame(a, g_xyz, NULL, 10, bad_sensor, NULL), CCMAP_NON_FINITE_INPUT);
  }
  CHECK_STATUS(ccmap_move_to(a, 1e9f, 0.0f), CCMAP_OUT_OF_RANGE);
  n = make_terrain(0.3f, 0.1f, 0.75f);
  CHECK_STATUS(ccmap_update_frame(a, g_xyz, NULL, 100, sensor, NULL), CCMAP_OK);
  CHECK_STATUS(ccmap_get_health(a, &h), CCMAP_OK);
  CHECK(h.initialised == 1 && h.state == CCMAP_OK && h.layer_count == 5);
  CHECK_EQ(h.frames_accepted, 4);
  CHECK_EQ(h.map_sequence, 4);
  CHECK_EQ(h.frames_refused, 1);
  CHECK_EQ(h.moves_refused, 1);
  CHECK_EQ(h.last_frame_points, 100);
  CHECK_EQ(h.points_received, 3u * n + 100u);
  CHECK_STATUS(ccmap_get_counters(a, &counters), CCMAP_OK);
  CHECK_EQ(h.points_used, counters.totals.used);
  /* Window centres: the nearest even index of the robot position (0.3, 0.1) per layer. */
  for (layer = 0; layer < h.layer_count; ++layer) {
    const float w = 0.04f * (float)(1 << layer);
    const int32_t ex = 2 * (int32_t)floorf(0.3f * (0.5f / w) + 0.5f);
    const int32_t ey = 2 * (int32_t)floorf(0.1f * (0.5f / w) + 0.5f);
    CHECK(h.layers[layer].cell_width_m == w);
    CHECK_EQ(h.layers[layer].centre_index_x, ex);
    CHECK_EQ(h.layers[layer].centre_index_y, ey);
    CHECK(h.layers[layer].centre_x_m == (float)ex * w);
    CHECK(h.layers[layer].normal_variance_threshold > 0.0f);
  }
  CHECK(h.layers[5].cell_width_m == 0.0f && h.layers[5].observed_cells == 0u);
  /* Observed cells of the finest layer (not pooled) against its export. */
  CHECK_STATUS(ccmap_export_layer(a, 0, g_records, 64 * 64, &exported), CCMAP_OK);
  for (i = 0; i < exported; ++i) {
    observed += g_records[i].weight > 0.0f ? 1u : 0u;
  }
  CHECK_EQ(h.layers[0].observed_cells, observed);
  CHECK(h.layers[1].observed_cells > 0u);

  CHECK_STATUS(ccmap_reset_counters(NULL), CCMAP_INVALID_ARGUMENT);
  snapshot(a, g_snap_a);
  CHECK_STATUS(ccmap_reset_counters(a), CCMAP_OK);
  CHECK_STATUS(ccmap_get_health(a, &h), CCMAP_OK);
  CHECK(h.frames_accepted == 0u && h.frames_refused == 0u && h.moves_refused == 0u && h.points_received == 0u &&
        h.params_changes == 0u && h.products_published == 0u);
  CHECK_EQ(h.map_sequence, 4);
  CHECK_EQ(h.layers[0].observed_cells, observed);
  CHECK_STATUS(ccmap_export_layer(a, 0, g_records_after, 64 * 64, &i), CCMAP_OK);
  CHECK(i == exported && memcmp(g_records, g_records_after, exported * sizeof g_records[0]) == 0);
}

/* A damaged map and misuse are told apart. */
static void test_corrupt_versus_misuse(void) {
  ccmap_map* a = place(&g_a);
  ccmap_params p;
  ccmap_health h;
  ccmap_query_result r;
  unsigned char not_a_map[256];
  memset(not_a_map, 0x5A, sizeof not_a_map);
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_init(a, &p), CCMAP_OK);
  feed(a);
  /* Misuse: a pointer that is no map. */
  CHECK_STATUS(ccmap_get_health((const ccmap_map*)(const void*)not_a_map, &h), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_set_params((ccmap_map*)(void*)not_a_map, &p, NULL), CCMAP_INVALID_ARGUMENT);
  /* Damage inside the map's sealed state (a byte well inside the stack, after the handle's
   * header: a parameter or window word or a cell; the state check or the cell check finds it). */
  memcpy(&g_copy, &g_a, sizeof g_a);
  {
    /* The map's copy of the parameters: weight_limit, coverage_tau, min_weight in a row (the C
     * handle's own copy comes first, in its header: skip it). */
    size_t at = 0, found = 0;
    for (at = 64u; at + 12u <= sizeof g_a && !found; at += 4u) {
      if (memcmp(g_a.bytes + at, &p.weight_limit, 12u) == 0 && at > 256u) {
        found = at;
      }
    }
    CHECK(found > 0u);
    g_a.bytes[found + 4u] ^= 0x10u; /* coverage_tau */
    CHECK_STATUS(ccmap_get_health(a, &h), CCMAP_OK);
    CHECK(h.state == CCMAP_CORRUPT && h.initialised == 1);
    CHECK_STATUS(ccmap_query(a, 0.0f, 0.0f, &r), CCMAP_CORRUPT);
    CHECK_STATUS(ccmap_get_params(a, &p), CCMAP_CORRUPT);
    CHECK_STATUS(ccmap_set_params(a, &p, NULL), CCMAP_CORRUPT);
    CHECK_STATUS(ccmap_reset_counters(a), CCMAP_CORRUPT);
    memcpy(&g_a, &g_copy, sizeof g_a); /* the map's verdict is sticky: back to the saved bytes */
  }
  CHECK_STATUS(ccmap_get_health(a, &h), CCMAP_OK);
  CHECK(h.state == CCMAP_OK);
  /* The handle's own header damaged: CCMAP_CORRUPT, not "invalid argument". */
  g_a.bytes[0] ^= 0x01u;
  CHECK_STATUS(ccmap_get_health(a, &h), CCMAP_CORRUPT);
  g_a.bytes[0] ^= 0x01u;
  CHECK_STATUS(ccmap_get_health(a, &h), CCMAP_OK);
  CHECK(h.state == CCMAP_OK);
}

/* Every product field against the map's own answers, computed here independently. */
static void check_product(const ccmap_map* map, const uint8_t* bytes, size_t size, int32_t layer, int32_t answer,
                          uint32_t expected_sequence, uint32_t tag) {
  ccmap_product_header h;
  ccmap_health health;
  ccmap_costmap_spec spec;
  uint32_t side, i;
  const float w = ccmap_layer_cell_width(map, layer);
  CHECK_STATUS(ccmap_product_decode(bytes, size, &h, g_cells, PRODUCT_CELLS), CCMAP_OK);
  CHECK_STATUS(ccmap_get_health(map, &health), CCMAP_OK);
  side = (uint32_t)(layer == 0 ? 64 : layer < 3 ? 64 : 32);
  CHECK_EQ(h.version, CCMAP_PRODUCT_VERSION);
  CHECK_EQ(h.total_bytes, size);
  CHECK_EQ(size, CCMAP_PRODUCT_SIZE(side, side));
  CHECK_EQ(h.product_sequence, expected_sequence);
  CHECK_EQ(h.map_sequence, health.map_sequence);
  CHECK_EQ(h.params_crc, health.params_crc);
  CHECK_EQ(h.preset, CCMAP_PRESET_CADRE);
  CHECK_EQ(h.layer, layer);
  CHECK_EQ(h.answer, answer);
  CHECK_EQ(h.side_x, side);
  CHECK_EQ(h.side_y, side);
  CHECK(h.cell_width_m == w);
  CHECK_EQ(h.min_index_x, health.layers[layer].centre_index_x - (int32_t)side / 2);
  CHECK_EQ(h.min_index_y, health.layers[layer].centre_index_y - (int32_t)side / 2);
  CHECK(h.min_corner_x_m == (float)h.min_index_x * w);
  CHECK(h.centre_x_m == health.layers[layer].centre_x_m && h.centre_y_m == health.layers[layer].centre_y_m);
  CHECK(h.pose_x == 0.25f && h.pose_y == -0.5f && h.pose_z == 0.125f && h.pose_yaw == 1.5f && h.tag == tag);
  CHECK(crc32_bitwise(bytes, size - 4u) == ((uint32_t)bytes[size - 4u] | ((uint32_t)bytes[size - 3u] << 8) |
                                            ((uint32_t)bytes[size - 2u] << 16) | ((uint32_t)bytes[size - 1u] << 24)));
  spec.centre_x = health.layers[layer].centre_x_m;
  spec.centre_y = health.layers[layer].centre_y_m;
  spec.resolution_m = w;
  spec.side = side;
  spec.inflation_radius_m = 0.0f;
  spec.max_rows = 0u; /* no row budget */
  CHECK_STATUS(ccmap_fill_costmap(map, &spec, g_costs, sizeof g_costs, NULL), CCMAP_OK);
  {
    uint32_t known = 0u, mismatches = 0u;
    for (i = 0; i < side * side; ++i) {
      const int32_t ix = h.min_index_x + (int32_t)(i % side);
      const int32_t iy = h.min_index_y + (int32_t)(i / side);
      const float x = ((float)ix + 0.5f) * w;
      const float y = ((float)iy + 0.5f) * w;
      ccmap_query_result q;
      const ccmap_product_cell* c = &g_cells[i];
      if (answer == CCMAP_PRODUCT_STACK) {
        (void)ccmap_query(map, x, y, &q);
      } else {
        (void)ccmap_query_layer(map, layer, x, y, &q);
      }
      if (c->status != q.status || c->cell_class != q.cell_class || c->layer != q.layer || c->cost != g_costs[i] ||
          c->height_m != (q.status == CCMAP_OK ? q.height_m : 0.0f) ||
          c->inclination != (q.status == CCMAP_OK ? q.inclination : 0.0f)) {
        ++mismatches;
      }
      known += q.status == CCMAP_OK ? 1u : 0u;
    }
    CHECK_EQ(mismatches, 0);
    CHECK(known >= 4u);
  }
}

static void test_product(void) {
  ccmap_map* a = place(&g_a);
  ccmap_params p;
  ccmap_product_buffers buffers;
  ccmap_product_spec spec;
  ccmap_health h;
  size_t written = 7;
  uint32_t sequence = 0u;
  int32_t layer;
  CHECK_STATUS(ccmap_product_buffers_init(NULL, g_product_storage, sizeof g_product_storage), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_product_buffers_init(&buffers, (uint8_t*)g_product_storage + 1, 3000u), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_product_buffers_init(&buffers, g_product_storage, 12u), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_product_buffers_init(&buffers, g_product_storage, sizeof g_product_storage), CCMAP_OK);
  CHECK(buffers.slot_bytes >= CCMAP_PRODUCT_SIZE(64u, 64u));
  CHECK_STATUS(ccmap_product_read(&buffers, g_product, sizeof g_product, &written), CCMAP_NOT_INITIALISED);
  CHECK(written == 0u);
  spec.layer = 0;
  spec.answer = CCMAP_PRODUCT_STACK;
  spec.pose_x = 0.25f;
  spec.pose_y = -0.5f;
  spec.pose_z = 0.125f;
  spec.pose_yaw = 1.5f;
  spec.tag = 77u;
  CHECK_STATUS(ccmap_publish(a, &spec, &buffers), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_init(a, &p), CCMAP_OK);
  feed(a);
  CHECK_STATUS(ccmap_publish(a, NULL, &buffers), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_publish(a, &spec, NULL), CCMAP_INVALID_ARGUMENT);
  spec.layer = 5;
  CHECK_STATUS(ccmap_publish(a, &spec, &buffers), CCMAP_INVALID_ARGUMENT);
  spec.layer = 0;
  spec.pose_yaw = (float)NAN;
  CHECK_STATUS(ccmap_publish(a, &spec, &buffers), CCMAP_INVALID_ARGUMENT);
  spec.pose_yaw = 1.5f;
  spec.answer = 2;
  CHECK_STATUS(ccmap_publish(a, &spec, &buffers), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_product_read(&buffers, g_product, sizeof g_product, &written), CCMAP_NOT_INITIALISED);
  for (layer = 0; layer < 5; ++layer) {
    int32_t answer;
    for (answer = 0; answer < 2; ++answer) {
      spec.layer = layer;
      spec.answer = answer;
      spec.tag = (uint32_t)(100 + 2 * layer + answer);
      CHECK_STATUS(ccmap_publish(a, &spec, &buffers), CCMAP_OK);
      ++sequence;
      CHECK_STATUS(ccmap_product_read(&buffers, g_product, sizeof g_product, &written), CCMAP_OK);
      check_product(a, g_product, written, layer, answer, sequence, spec.tag);
    }
  }
  CHECK_STATUS(ccmap_get_health(a, &h), CCMAP_OK);
  CHECK_EQ(h.products_published, sequence);
  /* A product follows the map: after a move and a frame it says so. */
  CHECK_STATUS(ccmap_move_to(a, 0.9f, -0.4f), CCMAP_OK);
  {
    const float sensor[3] = {0.9f, -0.4f, 0.8f};
    const size_t n = make_terrain(0.9f, -0.4f, 0.1f);
    CHECK_STATUS(ccmap_update_frame(a, g_xyz, NULL, n, sensor, NULL), CCMAP_OK);
  }
  spec.layer = 1;
  spec.answer = CCMAP_PRODUCT_STACK;
  spec.tag = 5u;
  CHECK_STATUS(ccmap_publish(a, &spec, &buffers), CCMAP_OK);
  ++sequence;
  CHECK_STATUS(ccmap_product_read(&buffers, g_product, sizeof g_product, &written), CCMAP_OK);
  check_product(a, g_product, written, 1, CCMAP_PRODUCT_STACK, sequence, 5u);
  /* Refusals of the reader and the decoder. */
  CHECK_STATUS(ccmap_product_read(&buffers, g_product, 100u, &written), CCMAP_BUFFER_TOO_SMALL);
  CHECK(written == 0u);
  CHECK_STATUS(ccmap_product_read(NULL, g_product, sizeof g_product, &written), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_product_read(&buffers, g_product, sizeof g_product, &written), CCMAP_OK);
  {
    ccmap_product_header hd;
    g_product[200] ^= 0x04u;
    CHECK_STATUS(ccmap_product_decode(g_product, written, &hd, NULL, 0u), CCMAP_CORRUPT);
    g_product[200] ^= 0x04u;
    CHECK_STATUS(ccmap_product_decode(g_product, written - 4u, &hd, NULL, 0u), CCMAP_CORRUPT);
    CHECK_STATUS(ccmap_product_decode(g_product, written, &hd, g_cells, 10u), CCMAP_BUFFER_TOO_SMALL);
    g_product[4] = 2u;
    CHECK_STATUS(ccmap_product_decode(g_product, written, &hd, NULL, 0u), CCMAP_VERSION_MISMATCH);
    g_product[4] = 1u;
    CHECK_STATUS(ccmap_product_decode(g_product, written, &hd, NULL, 0u), CCMAP_OK);
  }
  /* Damage in the published slot (no writer near): CCMAP_CORRUPT, never a product. The latest
   * product is in slot (published & 1); its byte 300. */
  {
    uint8_t* slot = (uint8_t*)g_product_storage + (size_t)buffers.slot_bytes * (buffers.published & 1u);
    slot[300] ^= 0x80u;
    CHECK_STATUS(ccmap_product_read(&buffers, g_product, sizeof g_product, &written), CCMAP_CORRUPT);
    slot[300] ^= 0x80u;
    CHECK_STATUS(ccmap_product_read(&buffers, g_product, sizeof g_product, &written), CCMAP_OK);
  }
  /* A slot too small for the layer: refused, the readers keep the previous product. */
  {
    ccmap_product_buffers small;
    CHECK_STATUS(ccmap_product_buffers_init(&small, g_product_storage, 3u * CCMAP_PRODUCT_SIZE(32u, 32u)), CCMAP_OK);
    spec.layer = 0;
    CHECK_STATUS(ccmap_publish(a, &spec, &small), CCMAP_BUFFER_TOO_SMALL);
    spec.layer = 4;
    CHECK_STATUS(ccmap_publish(a, &spec, &small), CCMAP_OK);
    spec.layer = 0;
    CHECK_STATUS(ccmap_publish(a, &spec, &small), CCMAP_BUFFER_TOO_SMALL);
    CHECK_STATUS(ccmap_product_read(&small, g_product, sizeof g_product, &written), CCMAP_OK);
    CHECK_EQ(written, CCMAP_PRODUCT_SIZE(32u, 32u));
  }
}

void ccmap_flight_test(void) {
  CHECK(strcmp(ccmap_status_string(CCMAP_BUSY), "busy") == 0);
  test_validate_params();
  test_get_params();
  test_set_params_equivalence();
  test_set_params_keeps_cells();
  test_set_params_refusals();
  test_health();
  test_corrupt_versus_misuse();
  test_product();
}
