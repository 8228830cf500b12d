/* The C API from plain C99: placement in static storage, init, frames (with and without
 * weights, map and sensor frame), queries, export, counters, snapshots, map exchange (two half
 * maps exchanging deltas, and a snapshot merge, against one map fed everything), every preset, the
 * planner queries (footprint, path, arc, cost raster), uncertain moves, and the refusal of NULL
 * pointers, foreign handles and bad enum values.
 *
 * One case of the portable harness (tests/baremetal/harness.h; capi_case.cpp registers it), so
 * the same file runs on the host, on aarch64 Linux and on the bare-metal board. No stdio and no
 * double (the board's FPU is single precision). RAM: the host runs every preset; a build that
 * defines CCMAP_TEST_RAM_BYTES (the board: 4 MiB) runs the single-layer presets whose storage
 * fits in what the CADRE maps leave, and says which it skipped. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "capi_checks.h"

static ccmap_cadre_storage g_storage;
static ccmap_cadre_storage g_storage_copy;
/* One storage for the single-layer maps, placed one after another. On the board 896 KiB of RAM
 * stay for the rest of the image (its other statics and the main stack). The board's linker
 * script gives .bss a program header of its own at its RAM address (AT > RAM,
 * platform/boards/mps2_an500/mps2_an500.ld), so QEMU's loader zero-fills it there and only code
 * and .data must fit the 4 MiB flash; the single-layer OMG map fits beside the two CADRE maps. */
#ifdef CCMAP_TEST_RAM_BYTES
#define SINGLE_STORAGE_SIZE (CCMAP_TEST_RAM_BYTES - 2u * CCMAP_CADRE_STORAGE_SIZE - 917504u)
#else
#define SINGLE_STORAGE_SIZE CCMAP_SINGLE_KALMAN_STORAGE_SIZE
#endif
static union {
  unsigned char bytes[SINGLE_STORAGE_SIZE];
  long double align_long_double;
  void* align_pointer;
} g_single;
static uint8_t g_snapshot[CCMAP_CADRE_SNAPSHOT_SIZE];
static ccmap_cell_record g_records[64 * 64];

#define GRID_SIDE 100
static float g_xyz[3 * GRID_SIDE * GRID_SIDE];
static float g_weights[GRID_SIDE * GRID_SIDE];

/* A plane z = 0.1 x + 0.05 y sampled every 2 cm over [-1, 1)^2. Returns the point count. */
static size_t make_plane(void) {
  size_t n = 0;
  int i, j;
  for (j = 0; j < GRID_SIDE; ++j) {
    for (i = 0; i < GRID_SIDE; ++i) {
      const float x = -1.0f + 0.02f * ((float)i + 0.5f);
      const float y = -1.0f + 0.02f * ((float)j + 0.5f);
      g_xyz[3 * n] = x;
      g_xyz[3 * n + 1] = y;
      g_xyz[3 * n + 2] = 0.1f * x + 0.05f * y;
      g_weights[n] = 1.0f;
      ++n;
    }
  }
  return n;
}

static ccmap_params precise_lidar_params(ccmap_preset preset) {
  ccmap_params p;
  CHECK_STATUS(ccmap_default_params(preset, &p), CCMAP_OK);
  p.noise.sensor = CCMAP_SENSOR_LIDAR;
  p.noise.lidar_sigma0_m = 0.0005f;
  p.noise.lidar_sigma_per_m = 0.0f;
  return p;
}

static void test_storage_and_placement(void) {
  ccmap_map* map = NULL;
  unsigned char small[64];
  CHECK(ccmap_cadre_storage_size() > 400000u);
  CHECK(ccmap_cadre_storage_size() <= CCMAP_CADRE_STORAGE_SIZE);
  CHECK(ccmap_cadre_storage_size() == ccmap_storage_size(CCMAP_PRESET_CADRE));
  CHECK(ccmap_cadre_storage_align() >= 4u && ccmap_cadre_storage_align() <= CCMAP_STORAGE_ALIGN);
  CHECK(ccmap_storage_size(CCMAP_PRESET_SINGLE_CCM) <= CCMAP_SINGLE_CCM_STORAGE_SIZE);
  CHECK(ccmap_storage_size(CCMAP_PRESET_SINGLE_KALMAN) <= CCMAP_SINGLE_KALMAN_STORAGE_SIZE);
  CHECK(ccmap_storage_size(CCMAP_PRESET_SINGLE_OMG) <= CCMAP_SINGLE_OMG_STORAGE_SIZE);
  CHECK(ccmap_storage_size((ccmap_preset)99) == 0u);
  CHECK(sizeof g_storage >= CCMAP_CADRE_STORAGE_SIZE);
  CHECK(ccmap_storage_size(CCMAP_PRESET_SINGLE_OMG) <= sizeof g_single);

  CHECK_STATUS(ccmap_place(NULL, sizeof g_storage, CCMAP_PRESET_CADRE, &map), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_place(&g_storage, sizeof g_storage, CCMAP_PRESET_CADRE, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_place(&g_storage, sizeof g_storage, (ccmap_preset)99, &map), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_place(g_storage.bytes + 1, sizeof g_storage - 1, CCMAP_PRESET_CADRE, &map),
               CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_place(&g_storage, ccmap_cadre_storage_size() - 1, CCMAP_PRESET_CADRE, &map),
               CCMAP_BUFFER_TOO_SMALL);
  CHECK(map == NULL);

  /* A handle that ccmap_place did not produce is refused, not dereferenced as a map. */
  memset(small, 0, sizeof small);
  {
    ccmap_query_result r;
    ccmap_params p;
    CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
    CHECK_STATUS(ccmap_query((const ccmap_map*)(const void*)small, 0.0f, 0.0f, &r), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_init((ccmap_map*)(void*)small, &p), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_init(NULL, &p), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_move_to(NULL, 0.0f, 0.0f), CCMAP_INVALID_ARGUMENT);
    CHECK(ccmap_layer_count(NULL) == 0);
    CHECK(ccmap_snapshot_size(NULL) == 0u);
  }

  CHECK_STATUS(ccmap_place(&g_storage, sizeof g_storage, CCMAP_PRESET_CADRE, &map), CCMAP_OK);
  CHECK(map == (ccmap_map*)(void*)&g_storage);
  CHECK(ccmap_layer_count(map) == 5);
  CHECK(ccmap_layer_capacity(map, 0) == 64u * 64u);
  CHECK(ccmap_layer_capacity(map, 4) == 32u * 32u);
  CHECK(ccmap_layer_capacity(map, 5) == 0u);
  {
    ccmap_query_result r;
    CHECK_STATUS(ccmap_query(map, 0.0f, 0.0f, &r), CCMAP_NOT_INITIALISED);
    CHECK_STATUS(ccmap_move_to(map, 1.0f, 0.0f), CCMAP_NOT_INITIALISED);
  }
}

static void test_params(ccmap_map* map) {
  ccmap_params p;
  ccmap_params q;
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_default_params((ccmap_preset)7, &p), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
  CHECK_NEAR(p.finest_cell_width_m, 0.04, 1e-7);
  CHECK_NEAR(p.coverage_tau, 0.8, 1e-7);
  CHECK_NEAR(p.noise.stereo_focal_px, 600.0, 1e-9);
  CHECK(p.noise.sensor == CCMAP_SENSOR_STEREO && p.noise.weight_mode == CCMAP_WEIGHT_CONSTANT);
  CHECK_STATUS(ccmap_default_params_for_width(0.08f, &q), CCMAP_OK);
  CHECK(q.finest_max_sigma_m > p.finest_max_sigma_m);
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_SINGLE_CCM, &q), CCMAP_OK);
  CHECK_NEAR(q.finest_cell_width_m, 0.08, 1e-7);

  CHECK_STATUS(ccmap_init(map, NULL), CCMAP_INVALID_ARGUMENT);
  q = p;
  q.finest_cell_width_m = 0.0f;
  CHECK_STATUS(ccmap_init(map, &q), CCMAP_INVALID_ARGUMENT);
  q = p;
  q.coverage_tau = (float)NAN;
  CHECK_STATUS(ccmap_init(map, &q), CCMAP_NON_FINITE_INPUT);
  q = p;
  q.noise.sensor = 5;
  CHECK_STATUS(ccmap_init(map, &q), CCMAP_INVALID_ARGUMENT);
  q = p;
  q.noise.weight_mode = 9;
  CHECK_STATUS(ccmap_init(map, &q), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);
  CHECK_NEAR(ccmap_layer_cell_width(map, 4), 0.64, 1e-7);
}

static void test_frames_queries_export(ccmap_map* map) {
  const size_t n = make_plane();
  const float sensor[3] = {0.0f, 0.0f, 0.5f};
  const float nan_sensor[3] = {(float)NAN, 0.0f, 0.0f};
  ccmap_frame_counters c;
  ccmap_query_result r;
  ccmap_counters totals;
  size_t written = 0;
  size_t i;
  ccmap_params p = precise_lidar_params(CCMAP_PRESET_CADRE);
  CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);

  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, sensor, &c), CCMAP_OK);
  CHECK(c.received == n);
  CHECK(c.used == n);
  g_weights[0] = 0.0f; /* refused point */
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, g_weights, n, sensor, &c), CCMAP_OK);
  CHECK(c.rejected_weight == 1u);
  CHECK(c.used == n - 1u);
  CHECK_STATUS(ccmap_update_frame(map, NULL, NULL, 3, sensor, &c), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, NULL, &c), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, nan_sensor, NULL), CCMAP_NON_FINITE_INPUT);
  CHECK_STATUS(ccmap_update_frame(map, NULL, NULL, 0, sensor, NULL), CCMAP_OK);

  CHECK_STATUS(ccmap_query(map, 0.31f, 0.21f, &r), CCMAP_OK);
  CHECK(r.status == CCMAP_OK);
  CHECK(r.layer == 0);
  CHECK_NEAR(r.height_m, 0.1 * 0.30 + 0.05 * 0.22, 0.004); /* 4 cm cell centre (0.30, 0.22) */
  CHECK(r.cell_class == CCMAP_CLASS_TRAVERSABLE);
  CHECK_NEAR(r.slope_x, 0.1, 0.01);
  CHECK_STATUS(ccmap_query_layer(map, 2, 0.4f, -0.4f, &r), CCMAP_OK);
  CHECK_NEAR(r.slope_x, 0.1, 0.005);
  CHECK_NEAR(r.slope_y, 0.05, 0.005);
  CHECK_NEAR(r.height_m, 0.1 * 0.4 - 0.05 * 0.4, 0.002);
  CHECK_STATUS(ccmap_query(map, 3.0f, 3.0f, &r), CCMAP_UNKNOWN);
  CHECK_STATUS(ccmap_query(map, 30.0f, 3.0f, &r), CCMAP_OUTSIDE_MAP);
  CHECK(r.layer == -1);
  CHECK_STATUS(ccmap_query(map, 0.0f, 0.0f, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_layer(map, 9, 0.0f, 0.0f, &r), CCMAP_INVALID_ARGUMENT);
  CHECK(strcmp(ccmap_cell_class_string(CCMAP_CLASS_OBSTACLE), "obstacle") == 0);
  CHECK(strcmp(ccmap_cell_class_string(CCMAP_CLASS_DROP), "drop") == 0);
  CHECK(strcmp(ccmap_cell_class_string(42), "unknown") == 0);

  CHECK_STATUS(ccmap_export_layer(map, 1, g_records, ccmap_layer_capacity(map, 1) - 1, &written),
               CCMAP_BUFFER_TOO_SMALL);
  CHECK(written == 0u);
  CHECK_STATUS(ccmap_export_layer(map, 1, NULL, 10, &written), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_export_layer(map, 1, g_records, sizeof g_records / sizeof g_records[0], &written), CCMAP_OK);
  CHECK(written > 100u);
  for (i = 0; i < written; ++i) {
    const ccmap_cell_record* rec = &g_records[i];
    ccmap_query_result q;
    if (!(rec->weight > 0.0f)) {
      CHECK(rec->weight > 0.0f);
      break;
    }
    if (ccmap_query_layer(map, 1, rec->centre_x, rec->centre_y, &q) == CCMAP_OK &&
        (q.height_m != rec->height_m || q.cell_class != rec->cell_class)) {
      CHECK(q.height_m == rec->height_m && q.cell_class == rec->cell_class);
      break;
    }
    if (fabsf(rec->centre_x - 0.08f * ((float)rec->index_x + 0.5f)) > 1e-5f) {
      CHECK(fabsf(rec->centre_x - 0.08f * ((float)rec->index_x + 0.5f)) <= 1e-5f);
      break;
    }
  }

  /* Sensor-frame update: the identity pose, so the same points as the map frame (a translation
   * would move the ground, and the outlier gate would hold the points as a change). */
  {
    ccmap_pose pose;
    memset(&pose, 0, sizeof pose);
    pose.rotation[0] = pose.rotation[4] = pose.rotation[8] = 1.0f;
    CHECK_STATUS(ccmap_update_frame_sensor(map, g_xyz, n, &pose, &c), CCMAP_OK);
    CHECK(c.used == n);
    CHECK(c.gated_held == 0u && c.gated_pool_full == 0u && c.gated_finer == 0u);
    /* The ground 10 cm higher (a pose jump): every point held, the cells re-seeded, at most one
     * pool of held-point slots (the finest layer's: 1024 cells) per frame; the rest waits. */
    pose.translation[2] = 0.1f;
    CHECK_STATUS(ccmap_update_frame_sensor(map, g_xyz, n, &pose, &c), CCMAP_OK);
    CHECK(c.used == 0u);
    CHECK(c.gated_held + c.gated_pool_full == n);
    CHECK(c.gated_admitted == c.gated_held && c.reseeded_cells == 1024u);
    pose.translation[2] = 0.0f;
    CHECK_STATUS(ccmap_update_frame_sensor(map, g_xyz, n, NULL, &c), CCMAP_INVALID_ARGUMENT);
    pose.rotation[3] = (float)INFINITY;
    CHECK_STATUS(ccmap_update_frame_sensor(map, g_xyz, n, &pose, &c), CCMAP_NON_FINITE_INPUT);
  }

  CHECK_STATUS(ccmap_move_to(map, (float)NAN, 0.0f), CCMAP_NON_FINITE_INPUT);
  CHECK_STATUS(ccmap_move_to(map, 0.1f, 0.0f), CCMAP_OK);
  CHECK_STATUS(ccmap_get_counters(map, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_get_counters(map, &totals), CCMAP_OK);
  CHECK(totals.totals.received == 4u * n);
  CHECK(totals.totals.used == 3u * n - 1u);
  CHECK(totals.totals.gated_held == 1024u * 4u); /* 4 points in each 4 cm cell of the 2 cm grid */
  CHECK(totals.totals.rejected_weight == 1u);
  CHECK(totals.rejected_moves == 1u);
  /* Counted by the map: NULL points, NaN origin, Inf rotation (a NULL origin or pose is refused
   * by the C layer before the map sees the frame). */
  CHECK(totals.rejected_frames == 3u);
}

static void test_snapshots(ccmap_map* map) {
  ccmap_map* copy = NULL;
  ccmap_map* other = NULL;
  size_t written = 0;
  ccmap_query_result a;
  ccmap_query_result b;
  float x;
  int same = 1;
  CHECK(ccmap_snapshot_size(map) == CCMAP_CADRE_SNAPSHOT_SIZE);
  CHECK_STATUS(ccmap_save_snapshot(map, g_snapshot, sizeof g_snapshot - 1, &written), CCMAP_BUFFER_TOO_SMALL);
  CHECK(written == 0u);
  CHECK_STATUS(ccmap_save_snapshot(map, NULL, sizeof g_snapshot, &written), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_save_snapshot(map, g_snapshot, sizeof g_snapshot, &written), CCMAP_OK);
  CHECK(written == CCMAP_CADRE_SNAPSHOT_SIZE);

  CHECK_STATUS(ccmap_place(&g_storage_copy, sizeof g_storage_copy, CCMAP_PRESET_CADRE, &copy), CCMAP_OK);
  CHECK_STATUS(ccmap_load_snapshot(copy, g_snapshot, written - 1), CCMAP_CORRUPT);
  g_snapshot[1000] ^= 0x10u;
  CHECK_STATUS(ccmap_load_snapshot(copy, g_snapshot, written), CCMAP_CORRUPT);
  g_snapshot[1000] ^= 0x10u;
  CHECK_STATUS(ccmap_query(copy, 0.0f, 0.0f, &a), CCMAP_NOT_INITIALISED); /* failed loads left it alone */
  CHECK_STATUS(ccmap_load_snapshot(copy, NULL, written), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_load_snapshot(copy, g_snapshot, written), CCMAP_OK);
  for (x = -1.2f; x < 1.2f; x += 0.013f) {
    const ccmap_status sa = ccmap_query(map, x, 0.37f * x, &a);
    const ccmap_status sb = ccmap_query(copy, x, 0.37f * x, &b);
    if (sa != sb || memcmp(&a, &b, sizeof a) != 0) {
      same = 0;
    }
  }
  CHECK(same); /* bitwise identical answers */

  /* A CADRE snapshot does not load into a single-layer map. */
  CHECK_STATUS(ccmap_place(&g_single, sizeof g_single, CCMAP_PRESET_SINGLE_OMG, &other), CCMAP_OK);
  CHECK_STATUS(ccmap_load_snapshot(other, g_snapshot, written), CCMAP_VERSION_MISMATCH);
}

static uint8_t g_cost[60 * 60];

/* The plane of make_plane with a 15 cm box on [0.42, 0.62] x [-0.21, 0.19]: its edges inside
 * 8 cm cells (a step exactly on a cell edge is no cell's normal variance). */
static size_t make_box_plane(void) {
  const size_t n = make_plane();
  size_t i;
  for (i = 0; i < n; ++i) {
    const float x = g_xyz[3 * i], y = g_xyz[3 * i + 1];
    if (x >= 0.42f && x <= 0.62f && y >= -0.21f && y <= 0.19f) g_xyz[3 * i + 2] += 0.15f;
  }
  return n;
}

static void test_planner_queries(ccmap_map* map) {
  const size_t n = make_box_plane();
  const float sensor[3] = {0.0f, 0.0f, 0.5f};
  const ccmap_footprint flat = {-0.5f, 0.01f, 1.0f, 0.0f, 0.6f, 0.4f};
  const ccmap_footprint on_box = {0.52f, -0.01f, 1.0f, 0.0f, 0.6f, 0.4f};
  const ccmap_footprint off_map = {40.0f, 0.0f, 1.0f, 0.0f, 0.6f, 0.4f};
  ccmap_footprint bad = flat;
  const float path[4] = {-0.8f, 0.0f, 0.8f, 0.0f};
  const ccmap_path_pose start = {-0.8f, 0.0f, 1.0f, 0.0f};
  const ccmap_path_sweep sweep = {0.6f, 0.4f, 0.02f, CCMAP_DEFAULT_MAX_UNKNOWN_SHARE};
  ccmap_path_sweep bad_sweep = sweep;
  ccmap_footprint_result f;
  ccmap_path_result pr;
  ccmap_costmap_spec spec;
  ccmap_costmap_stats stats;
  ccmap_frame_counters c;
  ccmap_params p = precise_lidar_params(CCMAP_PRESET_CADRE);
  CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, sensor, &c), CCMAP_OK);

  /* Footprints: flat ground (the plane's range over 0.6 x 0.4: 0.1 * 0.6 + 0.05 * 0.4 = 0.08, give
   * or take a 4 cm constant cell's step), the box, off the map. */
  CHECK_STATUS(ccmap_query_footprint(map, &flat, &f), CCMAP_OK);
  CHECK(f.worst_class == CCMAP_CLASS_TRAVERSABLE);
  CHECK_NEAR(f.unknown_share, 0.0, 1e-6);
  CHECK_NEAR(f.max_step_m, 0.08, 0.012);
  CHECK_NEAR(f.max_inclination, 0.1118, 0.01);
  CHECK_NEAR(f.area_m2, 0.24, 1e-4);
  CHECK(f.cells_visited > 0u);
  CHECK(ccmap_footprint_class(&f, CCMAP_DEFAULT_MAX_UNKNOWN_SHARE) == CCMAP_CLASS_TRAVERSABLE);
  CHECK_STATUS(ccmap_query_footprint(map, &on_box, &f), CCMAP_OK);
  CHECK(f.worst_class == CCMAP_CLASS_OBSTACLE);
  CHECK(f.max_step_m > 0.12f);
  CHECK(f.worst_x > 0.3f && f.worst_x < 0.7f);
  CHECK(ccmap_footprint_class(&f, CCMAP_DEFAULT_MAX_UNKNOWN_SHARE) == CCMAP_CLASS_OBSTACLE);
  CHECK_STATUS(ccmap_query_footprint(map, &off_map, &f), CCMAP_OUTSIDE_MAP);
  CHECK_NEAR(f.unknown_share, 1.0, 1e-6);
  CHECK(ccmap_footprint_class(&f, 1.0f) == CCMAP_CLASS_UNKNOWN);
  CHECK(ccmap_footprint_class(NULL, 1.0f) == CCMAP_CLASS_UNKNOWN);
  CHECK_STATUS(ccmap_query_footprint(map, NULL, &f), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_footprint(map, &flat, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_footprint(NULL, &flat, &f), CCMAP_INVALID_ARGUMENT);
  bad.x = (float)NAN;
  CHECK_STATUS(ccmap_query_footprint(map, &bad, &f), CCMAP_NON_FINITE_INPUT);
  CHECK(f.worst_layer == -1);
  bad = flat;
  bad.heading_x = 0.0f;
  CHECK_STATUS(ccmap_query_footprint(map, &bad, &f), CCMAP_INVALID_ARGUMENT);
  bad = flat;
  bad.length_m = 3.0f;
  bad.width_m = 3.0f;
  CHECK_STATUS(ccmap_query_footprint(map, &bad, &f), CCMAP_OUT_OF_RANGE);

  /* Path at the box: the body's front (0.3 m ahead) reaches the 8 cm cell [0.40, 0.48] that
   * holds the box edge at 0.9 m (give or take a step). */
  CHECK_STATUS(ccmap_query_path(map, path, 2, &sweep, &pr), CCMAP_OK);
  CHECK(pr.hazard_found == 1);
  CHECK(pr.first_hazard_m > 0.8f && pr.first_hazard_m < 1.0f);
  CHECK_NEAR(pr.hazard_pose.x, -0.8f + pr.first_hazard_m, 1e-5f);
  CHECK(pr.hazard.worst_class == CCMAP_CLASS_OBSTACLE || pr.hazard.worst_class == CCMAP_CLASS_STEEP);
  CHECK_NEAR(pr.path_length_m, 1.6, 1e-6);
  CHECK(pr.samples >= 2u && pr.samples <= 81u);
  CHECK_STATUS(ccmap_query_arc(map, &start, 0.0f, 1.6f, &sweep, &pr), CCMAP_OK);
  CHECK(pr.hazard_found == 1);
  CHECK(pr.first_hazard_m > 0.8f && pr.first_hazard_m < 1.0f);
  CHECK_STATUS(ccmap_query_arc(map, &start, 10.0f, 1.0f, &sweep, &pr), CCMAP_OUT_OF_RANGE);
  CHECK_STATUS(ccmap_query_path(map, NULL, 2, &sweep, &pr), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_path(map, path, 1, &sweep, &pr), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_path(map, path, 2, NULL, &pr), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_arc(map, NULL, 0.0f, 1.0f, &sweep, &pr), CCMAP_INVALID_ARGUMENT);
  bad_sweep.step_m = 0.001f;
  CHECK_STATUS(ccmap_query_path(map, path, 2, &bad_sweep, &pr), CCMAP_OUT_OF_RANGE);
  CHECK(pr.samples == 0u);

  /* Cost raster: 60 x 60 at 4 cm over [-1.2, 1.2]^2 (on the cell grid): the box lethal, the plane
   * costed, the unobserved rim unknown; inflated by 12 cm around the box. */
  spec.centre_x = 0.0f;
  spec.centre_y = 0.0f;
  spec.resolution_m = 0.04f;
  spec.side = 60u;
  spec.inflation_radius_m = 0.0f;
  spec.max_rows = 0u; /* no row budget */
  CHECK_STATUS(ccmap_fill_costmap(map, &spec, g_cost, sizeof g_cost, &stats), CCMAP_OK);
  CHECK(g_cost[(size_t)(41 + 60 * 30)] == CCMAP_COST_LETHAL);  /* (0.46, 0.02): the box edge's cell */
  CHECK(g_cost[(size_t)(12 + 60 * 30)] <= CCMAP_COST_MAX_TRAVERSABLE); /* (-0.7, 0.02) */
  CHECK(g_cost[(size_t)(12 + 60 * 30)] > 0u);  /* a 6 % slope costs something */
  CHECK(g_cost[(size_t)(2 + 60 * 30)] == CCMAP_COST_UNKNOWN);  /* (-1.1, 0.02): never observed */
  CHECK(stats.lethal > 10u && stats.unknown > 100u);
  CHECK(stats.free + stats.cost + stats.inscribed + stats.lethal + stats.unknown == 3600u);
  CHECK(stats.inscribed == 0u);
  spec.inflation_radius_m = 0.12f;
  CHECK_STATUS(ccmap_fill_costmap(map, &spec, g_cost, sizeof g_cost, &stats), CCMAP_OK);
  CHECK(stats.inscribed > 10u);
  CHECK(g_cost[(size_t)(41 + 60 * 30)] == CCMAP_COST_LETHAL);
  CHECK(g_cost[(size_t)(38 + 60 * 30)] == CCMAP_COST_INSCRIBED);  /* 12 cm before the edge's cell */
  CHECK_STATUS(ccmap_fill_costmap(map, &spec, g_cost, sizeof g_cost - 1, &stats), CCMAP_BUFFER_TOO_SMALL);
  CHECK_STATUS(ccmap_fill_costmap(map, &spec, NULL, sizeof g_cost, &stats), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_fill_costmap(map, NULL, g_cost, sizeof g_cost, &stats), CCMAP_INVALID_ARGUMENT);
  spec.resolution_m = (float)NAN;
  CHECK_STATUS(ccmap_fill_costmap(map, &spec, g_cost, sizeof g_cost, NULL), CCMAP_NON_FINITE_INPUT);
  spec.resolution_m = 0.04f;
  spec.side = CCMAP_MAX_COSTMAP_SIDE + 1u;
  CHECK_STATUS(ccmap_fill_costmap(map, &spec, g_cost, sizeof g_cost, NULL), CCMAP_INVALID_ARGUMENT);

  /* Uncertain moves. */
  CHECK_STATUS(ccmap_move_to_uncertain(map, 0.05f, 0.0f, 0.01f), CCMAP_OK);
  CHECK_STATUS(ccmap_move_to_uncertain(map, 0.05f, 0.0f, (float)NAN), CCMAP_NON_FINITE_INPUT);
  CHECK_STATUS(ccmap_move_to_uncertain(map, 0.05f, 0.0f, -1.0f), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_move_to_uncertain(NULL, 0.05f, 0.0f, 0.01f), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_footprint(map, &on_box, &f), CCMAP_OK);
  CHECK(f.worst_class == CCMAP_CLASS_OBSTACLE); /* forgetting keeps classes */
}

static void test_single_layer_presets(void) {
  const ccmap_preset presets[3] = {CCMAP_PRESET_SINGLE_CCM, CCMAP_PRESET_SINGLE_KALMAN, CCMAP_PRESET_SINGLE_OMG};
  const char* const names[3] = {"single CCM", "single Kalman", "single OMG"};
  const float sensor[3] = {0.0f, 0.0f, 0.5f};
  size_t n = make_plane();
  int k;
  for (k = 0; k < 3; ++k) {
    ccmap_map* map = NULL;
    ccmap_query_result r;
    ccmap_frame_counters c;
    ccmap_params p = precise_lidar_params(presets[k]);
    if (ccmap_storage_size(presets[k]) > sizeof g_single) {
      ccmap_test_note("  skipped (its storage does not fit this target's RAM beside the CADRE maps):");
      ccmap_test_note(names[k]);
      continue;
    }
    CHECK_STATUS(ccmap_place(&g_single, sizeof g_single, presets[k], &map), CCMAP_OK);
    CHECK(ccmap_layer_count(map) == 1);
    CHECK(ccmap_layer_capacity(map, 0) == 256u * 256u);
    CHECK(ccmap_layer_capacity(map, 1) == 0u);
    CHECK(ccmap_layer_cell_width(map, 0) == 0.0f); /* before init: no width yet */
    CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);
    CHECK_NEAR(ccmap_layer_cell_width(map, 0), 0.08, 1e-7);
    CHECK(ccmap_layer_cell_width(map, 1) == 0.0f); /* a layer the preset does not have */
    CHECK(ccmap_layer_cell_width(map, -1) == 0.0f);
    CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, sensor, &c), CCMAP_OK);
    CHECK(c.used == n);
    CHECK_STATUS(ccmap_query(map, 0.3f, -0.2f, &r), CCMAP_OK);
    CHECK(r.layer == 0);
    CHECK_NEAR(r.cell_width_m, 0.08, 1e-7);
    CHECK_NEAR(r.height_m, 0.1 * 0.3 - 0.05 * 0.2, 0.006);
  }
}

/* Every `step`-th point of the plane from `first` on, into the map, one point per frame. */
static void feed_every(ccmap_map* map, size_t n, size_t first, size_t step) {
  const float sensor[3] = {0.0f, 0.0f, 0.5f};
  size_t i;
  for (i = first; i < n; i += step) {
    ccmap_frame_counters c;
    CHECK_STATUS(ccmap_update_frame(map, &g_xyz[3 * i], NULL, 1, sensor, &c), CCMAP_OK);
  }
}

/* Largest height difference between two maps' answers on a raster; -1 if the answers differ in
 * status, layer or class anywhere. */
static float max_height_difference(const ccmap_map* a, const ccmap_map* b) {
  float worst = 0.0f;
  float x, y;
  for (y = -0.95f; y < 0.95f; y += 0.05f) {
    for (x = -0.95f; x < 0.95f; x += 0.05f) {
      ccmap_query_result qa, qb;
      const ccmap_status sa = ccmap_query(a, x, y, &qa);
      const ccmap_status sb = ccmap_query(b, x, y, &qb);
      if (sa != sb || qa.cell_class != qb.cell_class || qa.layer != qb.layer) {
        return -1.0f;
      }
      if (fabsf(qa.height_m - qb.height_m) > worst) {
        worst = fabsf(qa.height_m - qb.height_m);
      }
    }
  }
  return worst;
}

/* Rounds a pointer into g_single up to the storage alignment. */
static unsigned char* aligned_in_single(size_t offset) {
  const uintptr_t base = (uintptr_t)(void*)&g_single.bytes[offset];
  const uintptr_t align = CCMAP_STORAGE_ALIGN;
  return &g_single.bytes[offset + (size_t)((align - base % align) % align)];
}

/* Two half maps (the even and the odd points of the plane, maps A and B in the CADRE storages)
 * exchange deltas and must then answer as a map fed every point (the reference, placed with the
 * two exchanges and the delta buffer in the single-layer storage, free by now). No limiter and no
 * effective floor: the merge is exact up to float rounding. */
static void test_exchange(void) {
  const size_t exchange_size = ccmap_exchange_storage_size(CCMAP_PRESET_CADRE) + CCMAP_STORAGE_ALIGN;
  const size_t map_size = ccmap_storage_size(CCMAP_PRESET_CADRE) + CCMAP_STORAGE_ALIGN;
  const size_t delta_capacity = 131072u;
  unsigned char* ex_a_storage = aligned_in_single(0u);
  unsigned char* ex_b_storage = aligned_in_single(exchange_size);
  unsigned char* all_storage = aligned_in_single(2u * exchange_size);
  unsigned char* delta = aligned_in_single(2u * exchange_size + map_size);
  ccmap_map *a = NULL, *b = NULL, *all = NULL;
  ccmap_exchange *ex_a = NULL, *ex_b = NULL;
  ccmap_exchange_params pa, pb;
  ccmap_export_report er;
  ccmap_merge_report mr;
  ccmap_exchange_counters counters;
  size_t written = 0, delta_size = 0, snapshot_size = 0;
  unsigned char crc_before[4];
  const size_t n = make_plane();
  ccmap_params p = precise_lidar_params(CCMAP_PRESET_CADRE);
  p.weight_limit = (float)INFINITY;
  p.kalman_min_variance = 1e-30f;

  CHECK(ccmap_exchange_storage_size(CCMAP_PRESET_CADRE) <= CCMAP_CADRE_EXCHANGE_STORAGE_SIZE);
  CHECK(ccmap_exchange_storage_size(CCMAP_PRESET_SINGLE_CCM) <= CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE);
  CHECK(ccmap_exchange_storage_size(CCMAP_PRESET_SINGLE_KALMAN) <= CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE);
  CHECK(ccmap_exchange_storage_size(CCMAP_PRESET_SINGLE_OMG) <= CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE);
  CHECK(ccmap_exchange_storage_size((ccmap_preset)9) == 0u);
  CHECK(ccmap_delta_max_size(CCMAP_PRESET_CADRE) == CCMAP_CADRE_DELTA_MAX_SIZE);
  CHECK(ccmap_delta_min_size(CCMAP_PRESET_CADRE) == 152u);
  CHECK(strcmp(ccmap_status_string(CCMAP_DUPLICATE), "duplicate") == 0);
  CHECK(strcmp(ccmap_status_string(CCMAP_MISALIGNED), "misaligned") == 0);
  if ((size_t)(delta + delta_capacity - g_single.bytes) > sizeof g_single) {
    ccmap_test_note("  map exchange skipped (two exchanges and a map do not fit this target's RAM)");
    return;
  }

  CHECK_STATUS(ccmap_place(&g_storage, sizeof g_storage, CCMAP_PRESET_CADRE, &a), CCMAP_OK);
  CHECK_STATUS(ccmap_place(&g_storage_copy, sizeof g_storage_copy, CCMAP_PRESET_CADRE, &b), CCMAP_OK);
  CHECK_STATUS(ccmap_place(all_storage, map_size, CCMAP_PRESET_CADRE, &all), CCMAP_OK);
  CHECK_STATUS(ccmap_init(a, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_init(b, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_init(all, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_exchange_place(ex_a_storage, ccmap_exchange_storage_size(CCMAP_PRESET_CADRE) - 1u,
                                    CCMAP_PRESET_CADRE, &ex_a),
               CCMAP_BUFFER_TOO_SMALL);
  CHECK_STATUS(ccmap_exchange_place(ex_a_storage, exchange_size, (ccmap_preset)7, &ex_a), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_exchange_place(ex_a_storage, exchange_size, CCMAP_PRESET_CADRE, &ex_a), CCMAP_OK);
  CHECK_STATUS(ccmap_exchange_place(ex_b_storage, exchange_size, CCMAP_PRESET_CADRE, &ex_b), CCMAP_OK);
  pa.rover_id = 1u;
  pa.session = 1u;
  pa.origin_x_cells = 0;
  pa.origin_y_cells = 0;
  pa.origin_z_m = 0.0f;
  pb = pa;
  pb.rover_id = 2u;
  CHECK_STATUS(ccmap_exchange_init(ex_a, (ccmap_map*)(void*)ex_b_storage, &pa), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_exchange_init(ex_a, a, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_exchange_init(NULL, a, &pa), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_exchange_init(ex_a, a, &pa), CCMAP_OK);
  CHECK_STATUS(ccmap_exchange_init(ex_b, b, &pb), CCMAP_OK);

  feed_every(a, n, 0u, 2u); /* the even points */
  feed_every(b, n, 1u, 2u); /* the odd points */
  feed_every(all, n, 0u, 1u);
  CHECK_STATUS(ccmap_save_snapshot(b, g_snapshot, sizeof g_snapshot, &snapshot_size), CCMAP_OK);

  /* A -> B, B -> A. */
  CHECK_STATUS(ccmap_exchange_export(ex_a, delta, 100u, 0.0f, 0, &written, &er), CCMAP_BUFFER_TOO_SMALL);
  CHECK_STATUS(ccmap_exchange_export(ex_a, delta, delta_capacity, -1.0f, 0, &written, &er), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_exchange_export(ex_a, delta, delta_capacity, 0.0f, 5, &written, &er), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_exchange_export(ex_a, delta, delta_capacity, 0.0f, 0, &written, &er), CCMAP_OK);
  CHECK(er.sequence == 1u && er.cells_written > 100u && er.bytes == written && er.cells_pending == 0u);
  delta_size = written;
  /* A flipped bit is refused and leaves B's map as it was: its snapshot, saved again, has the
   * same CRC-32 trailer (no frame ran in between, so even the timing field is the same). */
  memcpy(crc_before, &g_snapshot[snapshot_size - 4u], 4u);
  delta[delta_size / 2u] ^= 0x04u;
  CHECK_STATUS(ccmap_exchange_merge_delta(ex_b, delta, delta_size, &mr), CCMAP_CORRUPT);
  delta[delta_size / 2u] ^= 0x04u;
  CHECK_STATUS(ccmap_save_snapshot(b, g_snapshot, sizeof g_snapshot, &written), CCMAP_OK);
  CHECK(written == snapshot_size && memcmp(crc_before, &g_snapshot[snapshot_size - 4u], 4u) == 0);
  CHECK_STATUS(ccmap_exchange_merge_delta(ex_a, delta, delta_size, &mr), CCMAP_DUPLICATE); /* its own */
  CHECK_STATUS(ccmap_exchange_merge_delta(ex_b, delta, delta_size, &mr), CCMAP_OK);
  CHECK(mr.sender_id == 1u && mr.sequence == 1u && mr.cells_merged == er.cells_written && mr.cells_outside == 0u);
  /* The free-space section (delta format 3): every entry the export wrote merged or was placed. */
  CHECK(mr.free_space_status == CCMAP_OK && mr.entries_refused == 0u &&
        mr.drops_merged + mr.entries_outside <= er.drops_written);
  CHECK_STATUS(ccmap_exchange_merge_delta(ex_b, delta, delta_size, &mr), CCMAP_DUPLICATE); /* twice */
  CHECK_STATUS(ccmap_exchange_export(ex_b, delta, delta_capacity, 0.0f, 0, &written, &er), CCMAP_OK);
  CHECK(er.cells_pending == 0u);
  CHECK_STATUS(ccmap_exchange_merge_delta(ex_a, delta, written, &mr), CCMAP_OK);
  CHECK(max_height_difference(a, all) >= 0.0f && max_height_difference(a, all) < 1e-5f);
  CHECK(max_height_difference(b, all) >= 0.0f && max_height_difference(b, all) < 1e-5f);

  CHECK_STATUS(ccmap_exchange_get_counters(ex_b, &counters), CCMAP_OK);
  CHECK(counters.deltas_exported == 1u && counters.deltas_merged == 1u && counters.refused == 2u &&
        counters.refused_corrupt == 1u && counters.refused_duplicate == 1u);
  CHECK_STATUS(ccmap_exchange_get_counters(NULL, &counters), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_exchange_merge_delta((ccmap_exchange*)(void*)&g_storage, delta, written, &mr),
               CCMAP_INVALID_ARGUMENT); /* a map handle is not an exchange */

  /* Re-initialising A retires its exchange; A fed the even points again, plus the snapshot of B's
   * half, is the map fed everything. */
  CHECK_STATUS(ccmap_init(a, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_exchange_export(ex_a, delta, delta_capacity, 0.0f, 0, &written, &er), CCMAP_NOT_INITIALISED);
  feed_every(a, n, 0u, 2u);
  CHECK_STATUS(ccmap_merge_snapshot(a, g_snapshot, snapshot_size, 1, 0, 0.0f, &mr), CCMAP_MISALIGNED);
  CHECK_STATUS(ccmap_merge_snapshot(a, g_snapshot, snapshot_size - 1u, 0, 0, 0.0f, &mr), CCMAP_CORRUPT);
  CHECK_STATUS(ccmap_merge_snapshot(a, g_snapshot, snapshot_size, 0, 0, 0.0f, &mr), CCMAP_OK);
  CHECK(mr.cells_merged > 100u && mr.sender_id == 0u);
  CHECK(max_height_difference(a, all) >= 0.0f && max_height_difference(a, all) < 1e-5f);
}

/* Registration and team alignment: a saddle z = 0.03 (x^2 - y^2) + 0.02 x y sampled every 2 cm,
 * mapped (twice), then registered again with its heights 2 cm low; a snapshot of the map aligned with
 * the map itself 2 cm off in x. */
static void test_registration(ccmap_map* map) {
  ccmap_params p;
  ccmap_registration_params rp;
  ccmap_registration_result r;
  const float origin[3] = {0.0f, 0.0f, 0.5f};
  const float offset[3] = {0.02f, 0.0f, 0.0f};
  size_t n = 0, snapshot_size = 0, i;
  int j, k;
  for (j = 0; j < GRID_SIDE; ++j) {
    for (k = 0; k < GRID_SIDE; ++k) {
      const float x = -1.0f + 0.02f * ((float)k + 0.5f);
      const float y = -1.0f + 0.02f * ((float)j + 0.5f);
      g_xyz[3 * n] = x;
      g_xyz[3 * n + 1] = y;
      g_xyz[3 * n + 2] = 0.03f * (x * x - y * y) + 0.02f * x * y;
      ++n;
    }
  }
  CHECK_STATUS(ccmap_default_registration_params(&rp), CCMAP_OK);
  CHECK(rp.max_points == 1024u && rp.max_iterations >= 1u);
  CHECK_STATUS(ccmap_default_registration_params(NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_default_params(CCMAP_PRESET_CADRE, &p), CCMAP_OK);
  CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);
  /* Twice: 4 points per 4 cm cell each time, and a cell is known from 5. */
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, origin, NULL), CCMAP_OK);
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, origin, NULL), CCMAP_OK);
  for (i = 0; i < n; ++i) g_xyz[3 * i + 2] -= 0.02f;
  CHECK_STATUS(ccmap_register_frame(map, g_xyz, n, origin, &rp, &r), CCMAP_OK);
  CHECK(r.status == CCMAP_OK && r.observable[2] == 1u);
  CHECK_NEAR(r.correction[2], 0.02f, 0.003f);
  CHECK(r.sigma[2] < 0.002f && r.points_matched >= rp.min_matches && r.centre[0] == 0.0f);
  CHECK_STATUS(ccmap_register_frame(map, g_xyz, n, origin, NULL, &r), CCMAP_OK); /* NULL params: the defaults */
  {
    ccmap_pose pose;
    memset(&pose, 0, sizeof pose);
    pose.rotation[0] = pose.rotation[4] = pose.rotation[8] = 1.0f;
    pose.translation[2] = 0.5f;
    for (i = 0; i < n; ++i) g_xyz[3 * i + 2] -= 0.5f; /* sensor frame: the pose adds it back */
    CHECK_STATUS(ccmap_register_frame_sensor(map, g_xyz, n, &pose, &rp, &r), CCMAP_OK);
    CHECK_NEAR(r.correction[2], 0.02f, 0.003f);
    pose.rotation[1] = 0.5f;
    CHECK_STATUS(ccmap_register_frame_sensor(map, g_xyz, n, &pose, &rp, &r), CCMAP_INVALID_ARGUMENT);
    CHECK(r.observable[2] == 0u && r.correction[2] == 0.0f);
    CHECK_STATUS(ccmap_register_frame_sensor(map, g_xyz, n, NULL, &rp, &r), CCMAP_INVALID_ARGUMENT);
  }
  /* Refusals: nothing claimed, the status in the result too. */
  CHECK_STATUS(ccmap_register_frame(map, g_xyz, n, origin, &rp, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_register_frame(map, g_xyz, n, NULL, &rp, &r), CCMAP_INVALID_ARGUMENT);
  CHECK(r.status == CCMAP_INVALID_ARGUMENT && r.observable[2] == 0u);
  CHECK_STATUS(ccmap_register_frame(map, NULL, 5u, origin, &rp, &r), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_register_frame(map, g_xyz, 0u, origin, &rp, &r), CCMAP_DEGENERATE_INPUT);
  CHECK_STATUS(ccmap_register_frame(NULL, g_xyz, n, origin, &rp, &r), CCMAP_INVALID_ARGUMENT);
  rp.max_iterations = 0u;
  CHECK_STATUS(ccmap_register_frame(map, g_xyz, n, origin, &rp, &r), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_default_registration_params(&rp), CCMAP_OK);
  {
    const float far_origin[3] = {40.0f, 0.0f, 0.5f};
    CHECK_STATUS(ccmap_register_frame(map, g_xyz, n, far_origin, &rp, &r), CCMAP_OUTSIDE_MAP);
    CHECK(r.sigma[0] > 1e30f && r.correction[0] == 0.0f);
  }
  CHECK(strcmp(ccmap_status_string(CCMAP_INSUFFICIENT_OVERLAP), "insufficient_overlap") == 0);
  CHECK(strcmp(ccmap_status_string(CCMAP_DEGENERATE_INPUT), "degenerate_input") == 0);
  CHECK(strcmp(ccmap_status_string(CCMAP_NOT_CONVERGED), "not_converged") == 0);

  /* Team alignment: the map's own snapshot, believed 2 cm east: the correction takes it back. */
  CHECK_STATUS(ccmap_save_snapshot(map, g_snapshot, sizeof g_snapshot, &snapshot_size), CCMAP_OK);
  CHECK_STATUS(ccmap_align_snapshot(map, g_snapshot, snapshot_size, offset, &rp, &r), CCMAP_OK);
  CHECK(r.observable[0] == 1u && r.cells > 100u);
  CHECK_NEAR(r.correction[0], -0.02f, 0.004f);
  CHECK_STATUS(ccmap_align_snapshot(map, g_snapshot, snapshot_size - 1u, offset, &rp, &r), CCMAP_CORRUPT);
  CHECK_STATUS(ccmap_align_snapshot(map, g_snapshot, snapshot_size, NULL, &rp, &r), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_align_delta(map, g_snapshot, 100u, 0, 0, 0.0f, &rp, &r), CCMAP_CORRUPT);
  CHECK_STATUS(ccmap_align_delta(map, g_snapshot, 100u, 0, 0, 0.0f, &rp, NULL), CCMAP_INVALID_ARGUMENT);
}

/* Every refusal that include/ccmap/ccmap.h names and the tests above do not reach, call by call:
 * the status, and for the counted ones the count. Uses the second CADRE storage and the single-layer
 * storage (free by now). */
static void test_named_refusals(void) {
  ccmap_map* map = NULL;
  ccmap_map* fresh = NULL;
  ccmap_params p;
  ccmap_params q;
  ccmap_query_result r;
  ccmap_counters totals;
  ccmap_frame_counters c;
  ccmap_pose pose;
  size_t written = 99u;
  const float sensor[3] = {0.0f, 0.0f, 0.5f};
  const float far_sensor[3] = {2.0e5f, 0.0f, 0.5f};
  const float path[4] = {-0.8f, 0.0f, 0.8f, 0.0f};
  float bad_path[4] = {-0.8f, 0.0f, 0.8f, 0.0f};
  const ccmap_path_sweep sweep = {0.6f, 0.4f, 0.02f, CCMAP_DEFAULT_MAX_UNKNOWN_SHARE};
  const ccmap_footprint flat = {-0.5f, 0.01f, 1.0f, 0.0f, 0.6f, 0.4f};
  ccmap_path_pose start = {-0.8f, 0.0f, 1.0f, 0.0f};
  ccmap_path_result pr;
  ccmap_footprint_result f;
  ccmap_costmap_spec spec = {0.0f, 0.0f, 0.04f, 8u, 0.0f, 0u};
  uint8_t cost[64];
  ccmap_cell_record record;
  const size_t n = make_plane();

  /* Before init: the calls that read the map answer CCMAP_NOT_INITIALISED. */
  CHECK_STATUS(ccmap_place(&g_storage_copy, sizeof g_storage_copy, CCMAP_PRESET_CADRE, &fresh), CCMAP_OK);
  CHECK_STATUS(ccmap_export_layer(fresh, 0, g_records, sizeof g_records / sizeof g_records[0], &written),
               CCMAP_NOT_INITIALISED);
  CHECK(written == 0u);
  CHECK_STATUS(ccmap_get_counters(fresh, &totals), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_get_counters(NULL, &totals), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_save_snapshot(fresh, g_snapshot, sizeof g_snapshot, &written), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_query_footprint(fresh, &flat, &f), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_query_path(fresh, path, 2, &sweep, &pr), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_query_arc(fresh, &start, 0.0f, 1.0f, &sweep, &pr), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_fill_costmap(fresh, &spec, cost, sizeof cost, NULL), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_update_frame(fresh, g_xyz, NULL, n, sensor, &c), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_merge_snapshot(fresh, g_snapshot, sizeof g_snapshot, 0, 0, 0.0f, NULL), CCMAP_NOT_INITIALISED);
  CHECK_STATUS(ccmap_load_snapshot(NULL, g_snapshot, sizeof g_snapshot), CCMAP_INVALID_ARGUMENT);

  /* Parameters. */
  CHECK_STATUS(ccmap_default_params_for_width(0.04f, NULL), CCMAP_INVALID_ARGUMENT);
  p = precise_lidar_params(CCMAP_PRESET_CADRE);
  q = p;
  q.weight_limit = (float)NAN; /* INFINITY is "no limit"; NaN is no limit at all */
  CHECK_STATUS(ccmap_init(fresh, &q), CCMAP_INVALID_ARGUMENT);
  q = p;
  q.finest_cell_width_m = 1.0e-4f; /* below 0.19 mm: indices of 1e5 m would leave +-2^29 */
  CHECK_STATUS(ccmap_init(fresh, &q), CCMAP_INVALID_ARGUMENT);
  q = p;
  q.finest_cell_width_m = 7.0f; /* the coarsest layer (16x wider) would have 112 m cells */
  CHECK_STATUS(ccmap_init(fresh, &q), CCMAP_INVALID_ARGUMENT);
  q = p;
  q.noise.lidar_sigma_per_m = (float)INFINITY;
  CHECK_STATUS(ccmap_init(fresh, &q), CCMAP_NON_FINITE_INPUT);
  q = p;
  q.outlier_gate_sigma = 0.5f;
  CHECK_STATUS(ccmap_init(fresh, &q), CCMAP_INVALID_ARGUMENT);
  q = p;
  q.change_share = 0.75f;
  CHECK_STATUS(ccmap_init(fresh, &q), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_init(fresh, &p), CCMAP_OK);
  map = fresh;

  /* Moves and frames: each refusal counted, the map unchanged. */
  CHECK_STATUS(ccmap_move_to(map, 2.0e5f, 0.0f), CCMAP_OUT_OF_RANGE);
  CHECK_STATUS(ccmap_move_to_uncertain(map, 0.0f, 0.0f, 2.0e5f), CCMAP_OUT_OF_RANGE);
  CHECK_STATUS(ccmap_update_frame(map, g_xyz, NULL, n, far_sensor, &c), CCMAP_OUT_OF_RANGE);
  CHECK(c.received == 0u && c.used == 0u);
  memset(&pose, 0, sizeof pose);
  pose.rotation[0] = pose.rotation[4] = pose.rotation[8] = 1.0f;
  CHECK_STATUS(ccmap_update_frame_sensor(map, NULL, n, &pose, &c), CCMAP_INVALID_ARGUMENT);
  pose.rotation[0] = 1.5f; /* a scaling, not a rotation: an entry above 1.001 */
  CHECK_STATUS(ccmap_update_frame_sensor(map, g_xyz, n, &pose, &c), CCMAP_INVALID_ARGUMENT);
  pose.rotation[0] = 1.0f;
  pose.rotation[1] = 0.5f; /* a shear: every entry within 1.001, R^T R off the identity */
  CHECK_STATUS(ccmap_update_frame_sensor(map, g_xyz, n, &pose, &c), CCMAP_INVALID_ARGUMENT);
  pose.rotation[1] = 0.0f;
  pose.translation[1] = (float)NAN;
  CHECK_STATUS(ccmap_update_frame_sensor(map, g_xyz, n, &pose, &c), CCMAP_NON_FINITE_INPUT);
  pose.translation[1] = -2.0e5f;
  CHECK_STATUS(ccmap_update_frame_sensor(map, g_xyz, n, &pose, &c), CCMAP_OUT_OF_RANGE);
  pose.translation[1] = 0.0f;
  CHECK_STATUS(ccmap_get_counters(map, &totals), CCMAP_OK);
  CHECK(totals.rejected_moves == 2u);
  CHECK(totals.rejected_frames == 6u);
  CHECK(totals.totals.received == 0u);
  /* A sensor-frame point 2^11 m or more from the sensor is refused alone, counted as out of range. */
  g_xyz[0] = 2048.0f;
  CHECK_STATUS(ccmap_update_frame_sensor(map, g_xyz, n, &pose, &c), CCMAP_OK);
  CHECK(c.received == n && c.rejected_out_of_range == 1u && c.used == n - 1u);
  (void)make_plane();

  /* Queries and export. */
  CHECK_STATUS(ccmap_query_layer(map, -1, 0.0f, 0.0f, &r), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_layer(map, 5, 0.0f, 0.0f, &r), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_export_layer(map, 0, g_records, sizeof g_records / sizeof g_records[0], NULL),
               CCMAP_INVALID_ARGUMENT);
  written = 99u;
  CHECK_STATUS(ccmap_export_layer(map, 5, &record, 1u, &written), CCMAP_INVALID_ARGUMENT);
  CHECK(written == 0u);
  CHECK_STATUS(ccmap_export_layer(NULL, 0, g_records, sizeof g_records / sizeof g_records[0], &written),
               CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_save_snapshot(map, g_snapshot, sizeof g_snapshot, NULL), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_save_snapshot(NULL, g_snapshot, sizeof g_snapshot, &written), CCMAP_INVALID_ARGUMENT);

  /* Path and arc refusals. */
  bad_path[2] = (float)NAN;
  CHECK_STATUS(ccmap_query_path(map, bad_path, 2, &sweep, &pr), CCMAP_NON_FINITE_INPUT);
  bad_path[2] = 2.0e5f;
  CHECK_STATUS(ccmap_query_path(map, bad_path, 2, &sweep, &pr), CCMAP_OUT_OF_RANGE);
  bad_path[2] = bad_path[0]; /* both points the same: no segment of 1 um */
  CHECK_STATUS(ccmap_query_path(map, bad_path, 2, &sweep, &pr), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_path(map, path, CCMAP_MAX_PATH_VERTICES + 1u, &sweep, &pr), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_arc(map, &start, (float)NAN, 1.0f, &sweep, &pr), CCMAP_NON_FINITE_INPUT);
  CHECK_STATUS(ccmap_query_arc(map, &start, 0.0f, -1.0f, &sweep, &pr), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_arc(map, &start, 0.0f, 2.0e4f, &sweep, &pr), CCMAP_OUT_OF_RANGE);
  CHECK_STATUS(ccmap_query_arc(map, &start, 0.0f, 1.0f, NULL, &pr), CCMAP_INVALID_ARGUMENT);
  CHECK_STATUS(ccmap_query_arc(map, &start, 0.0f, 1.0f, &sweep, NULL), CCMAP_INVALID_ARGUMENT);
  start.heading_x = 0.0f; /* no direction */
  CHECK_STATUS(ccmap_query_arc(map, &start, 0.0f, 1.0f, &sweep, &pr), CCMAP_INVALID_ARGUMENT);
  start.heading_x = 1.0f;
  start.x = 2.0e5f;
  CHECK_STATUS(ccmap_query_arc(map, &start, 0.0f, 1.0f, &sweep, &pr), CCMAP_OUT_OF_RANGE);

  /* Map exchange: an unbound exchange, then the binding's own refusals. */
  if (ccmap_exchange_storage_size(CCMAP_PRESET_CADRE) + CCMAP_STORAGE_ALIGN > sizeof g_single) {
    ccmap_test_note("  exchange refusals skipped (an exchange does not fit this target's RAM beside the maps)");
    return;
  }
  {
    unsigned char* storage = aligned_in_single(0u);
    ccmap_exchange* ex = NULL;
    ccmap_exchange_params ep;
    ccmap_exchange_counters ec;
    ccmap_merge_report mr;
    uint8_t delta[256];
    CHECK_STATUS(ccmap_exchange_place(storage, ccmap_exchange_storage_size(CCMAP_PRESET_CADRE), CCMAP_PRESET_CADRE, &ex),
                 CCMAP_OK);
    CHECK_STATUS(ccmap_exchange_get_counters(ex, NULL), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_exchange_get_counters(ex, &ec), CCMAP_OK);
    CHECK(ec.deltas_exported == 0u && ec.refused == 0u && ec.bytes_merged == 0u);
    CHECK_STATUS(ccmap_exchange_export(ex, delta, sizeof delta, 0.0f, 0, &written, NULL), CCMAP_NOT_INITIALISED);
    CHECK_STATUS(ccmap_exchange_merge_delta(ex, delta, sizeof delta, &mr), CCMAP_NOT_INITIALISED);
    CHECK_STATUS(ccmap_exchange_merge_snapshot(ex, g_snapshot, sizeof g_snapshot, 0, 0, 0.0f, &mr),
                 CCMAP_NOT_INITIALISED);
    ep.rover_id = 3u;
    ep.session = 1u;
    ep.origin_x_cells = 0;
    ep.origin_y_cells = 0;
    ep.origin_z_m = (float)NAN;
    CHECK_STATUS(ccmap_exchange_init(ex, map, &ep), CCMAP_INVALID_ARGUMENT);
    ep.origin_z_m = 0.0f;
    ep.origin_x_cells = INT32_MAX;
    CHECK_STATUS(ccmap_exchange_init(ex, map, &ep), CCMAP_INVALID_ARGUMENT);
    ep.origin_x_cells = 0;
    {
      ccmap_map* unready = NULL;
      CHECK_STATUS(ccmap_place(&g_storage, sizeof g_storage, CCMAP_PRESET_CADRE, &unready), CCMAP_OK);
      CHECK_STATUS(ccmap_exchange_init(ex, unready, &ep), CCMAP_NOT_INITIALISED);
    }
    CHECK_STATUS(ccmap_exchange_init(ex, map, &ep), CCMAP_OK);
    CHECK_STATUS(ccmap_exchange_export(ex, NULL, sizeof delta, 0.0f, 0, &written, NULL), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_exchange_export(ex, delta, sizeof delta, 0.0f, 0, NULL, NULL), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_exchange_export(ex, delta, sizeof delta, (float)NAN, 0, &written, NULL), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_exchange_export(ex, delta, sizeof delta, 0.0f, -1, &written, NULL), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_exchange_merge_delta(ex, NULL, sizeof delta, &mr), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_exchange_merge_delta(NULL, delta, sizeof delta, &mr), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_save_snapshot(map, g_snapshot, sizeof g_snapshot, &written), CCMAP_OK);
    CHECK_STATUS(ccmap_exchange_merge_snapshot(ex, NULL, written, 0, 0, 0.0f, &mr), CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_exchange_merge_snapshot(ex, g_snapshot, written, 0, 0, (float)INFINITY, &mr),
                 CCMAP_INVALID_ARGUMENT);
    CHECK_STATUS(ccmap_exchange_merge_snapshot(ex, g_snapshot, written, 1, 0, 0.0f, &mr), CCMAP_MISALIGNED);
    CHECK_STATUS(ccmap_exchange_get_counters(ex, &ec), CCMAP_OK);
    /* Refusals of a bound exchange are counted (NULL data twice, Inf height, misaligned); a NULL
     * handle reaches no exchange, and the unbound ones were before init zeroed the counters. */
    CHECK(ec.deltas_exported == 0u && ec.snapshots_merged == 0u);
    CHECK(ec.refused == 4u && ec.refused_misaligned == 1u);
  }
}

/* The size and alignment queries and the exchange placement of every preset (and a bad one), an
 * exchange of each single-layer preset answering, and the inverse-variance weighting accepted by
 * init. References: the header's constants and the alignment the storage unions give. */
static void test_every_preset_entry(void) {
  const ccmap_preset presets[4] = {CCMAP_PRESET_CADRE, CCMAP_PRESET_SINGLE_CCM, CCMAP_PRESET_SINGLE_KALMAN,
                                   CCMAP_PRESET_SINGLE_OMG};
  const size_t exchange_bounds[4] = {CCMAP_CADRE_EXCHANGE_STORAGE_SIZE, CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE,
                                     CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE, CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE};
  ccmap_params p;
  ccmap_map* map = NULL;
  int k;
  for (k = 0; k < 4; ++k) {
    const size_t align = ccmap_storage_align(presets[k]);
    const size_t exchange_align = ccmap_exchange_storage_align(presets[k]);
    CHECK(align >= 4u && align <= CCMAP_STORAGE_ALIGN && (align & (align - 1u)) == 0u);
    CHECK(exchange_align >= 4u && exchange_align <= CCMAP_STORAGE_ALIGN && (exchange_align & (exchange_align - 1u)) == 0u);
    /* The smallest delta: the 88-byte header, 12 bytes per layer, the 4-byte CRC. */
    CHECK(ccmap_delta_min_size(presets[k]) == 88u + 12u * (k == 0 ? 5u : 1u) + 4u);
    CHECK(ccmap_exchange_storage_size(presets[k]) <= exchange_bounds[k]);
    if (ccmap_exchange_storage_size(presets[k]) + CCMAP_STORAGE_ALIGN <= sizeof g_single) {
      ccmap_exchange* ex = NULL;
      ccmap_exchange_counters ec;
      CHECK_STATUS(ccmap_exchange_place(aligned_in_single(0u), ccmap_exchange_storage_size(presets[k]), presets[k], &ex),
                   CCMAP_OK);
      CHECK_STATUS(ccmap_exchange_get_counters(ex, &ec), CCMAP_OK);
      CHECK(ec.deltas_exported == 0u && ec.refused == 0u);
    }
  }
  CHECK(ccmap_storage_align((ccmap_preset)9) == 0u);
  CHECK(ccmap_exchange_storage_align((ccmap_preset)9) == 0u);
  CHECK(ccmap_delta_min_size((ccmap_preset)9) == 0u);
  CHECK(ccmap_delta_max_size((ccmap_preset)9) == 0u);

  /* An OMG map and its exchange side by side in the single-layer storage: bound, exporting. */
  {
    const size_t map_size = ccmap_storage_size(CCMAP_PRESET_SINGLE_OMG) + CCMAP_STORAGE_ALIGN;
    if (map_size + ccmap_exchange_storage_size(CCMAP_PRESET_SINGLE_OMG) + CCMAP_STORAGE_ALIGN <= sizeof g_single) {
      ccmap_exchange* ex = NULL;
      ccmap_exchange_params ep;
      uint8_t delta[256];
      size_t written = 0;
      CHECK_STATUS(ccmap_place(aligned_in_single(0u), map_size, CCMAP_PRESET_SINGLE_OMG, &map), CCMAP_OK);
      p = precise_lidar_params(CCMAP_PRESET_SINGLE_OMG);
      CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);
      CHECK_STATUS(ccmap_exchange_place(aligned_in_single(map_size), ccmap_exchange_storage_size(CCMAP_PRESET_SINGLE_OMG),
                                        CCMAP_PRESET_SINGLE_OMG, &ex),
                   CCMAP_OK);
      ep.rover_id = 5u;
      ep.session = 1u;
      ep.origin_x_cells = 0;
      ep.origin_y_cells = 0;
      ep.origin_z_m = 0.0f;
      CHECK_STATUS(ccmap_exchange_init(ex, map, &ep), CCMAP_OK);
      CHECK_STATUS(ccmap_exchange_export(ex, delta, sizeof delta, 0.0f, 0, &written, NULL), CCMAP_OK);
      CHECK(written == ccmap_delta_min_size(CCMAP_PRESET_SINGLE_OMG)); /* an empty map: no cell */
      /* Bound to no map, or to a map of another preset: refused, the exchange unchanged. */
      CHECK_STATUS(ccmap_exchange_init(ex, NULL, &ep), CCMAP_INVALID_ARGUMENT);
      {
        ccmap_map* cadre = NULL;
        CHECK_STATUS(ccmap_place(&g_storage_copy, sizeof g_storage_copy, CCMAP_PRESET_CADRE, &cadre), CCMAP_OK);
        CHECK_STATUS(ccmap_exchange_init(ex, cadre, &ep), CCMAP_INVALID_ARGUMENT);
      }
      CHECK_STATUS(ccmap_exchange_export(ex, delta, sizeof delta, 0.0f, 0, &written, NULL), CCMAP_OK);
      CHECK(written == ccmap_delta_min_size(CCMAP_PRESET_SINGLE_OMG));
    }
  }

  /* Inverse-variance weighting: accepted with a positive reference range, refused without one. */
  CHECK_STATUS(ccmap_place(&g_storage_copy, sizeof g_storage_copy, CCMAP_PRESET_CADRE, &map), CCMAP_OK);
  p = precise_lidar_params(CCMAP_PRESET_CADRE);
  p.noise.weight_mode = CCMAP_WEIGHT_INVERSE_VARIANCE;
  p.noise.reference_range_m = 2.0f;
  CHECK_STATUS(ccmap_init(map, &p), CCMAP_OK);
  p.noise.reference_range_m = 0.0f;
  CHECK_STATUS(ccmap_init(map, &p), CCMAP_INVALID_ARGUMENT);
}

/* The whole C API test: one case (capi_case.cpp). CCMAP_TEST_PLATFORM_NAME: the platform
 * library the build links ("posix" or "baremetal"). */
void ccmap_capi_test(void) {
  ccmap_map* map = NULL;
  CHECK(strcmp(ccmap_status_string(CCMAP_OK), "ok") == 0);
  CHECK(strcmp(ccmap_status_string(CCMAP_CORRUPT), "corrupt") == 0);
  CHECK(strcmp(ccmap_status_string(CCMAP_VERSION_MISMATCH), "version_mismatch") == 0);
  CHECK(strcmp(ccmap_status_string((ccmap_status)99), "invalid_status") == 0);
  CHECK(strcmp(ccmap_platform_name(), CCMAP_TEST_PLATFORM_NAME) == 0);

  test_storage_and_placement();
  CHECK_STATUS(ccmap_place(&g_storage, sizeof g_storage, CCMAP_PRESET_CADRE, &map), CCMAP_OK);
  test_params(map);
  test_frames_queries_export(map);
  test_snapshots(map);
  test_planner_queries(map);
  test_single_layer_presets();
  test_exchange();
  test_registration(map);
  test_named_refusals();
  test_every_preset_entry();
}
