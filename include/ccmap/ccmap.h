/* ccmap C API: the map stack for C (C99) and other-language flight software.
 *
 * The map lives in storage the caller owns (static, or a memory pool handed over at set-up):
 * nothing allocates, nothing throws, every call answers with a status. Two-phase life:
 *
 *   static ccmap_cadre_storage storage;   // CCMAP_CADRE_STORAGE_SIZE bytes, aligned for the map
 *   ccmap_map* map = NULL;
 *   ccmap_params params;
 *   if (ccmap_place(&storage, sizeof storage, CCMAP_PRESET_CADRE, &map) != CCMAP_OK) ...
 *   ccmap_default_params(CCMAP_PRESET_CADRE, &params);      // then change what you need
 *   if (ccmap_init(map, &params) != CCMAP_OK) ...
 *   // run phase, every control cycle:
 *   ccmap_move_to(map, robot_x, robot_y);
 *   ccmap_update_frame(map, xyz, NULL, n, sensor_xyz, &frame_counters);
 *   ccmap_query(map, x, y, &result);
 *
 * Units and frames are those of the C++ API (include/ccmap/map/types.hpp): metres in the map
 * frame, relative to the stack origin chosen by the integrator (never absolute world
 * coordinates). See docs/integration.md.
 *
 * Errors: a NULL pointer argument, a handle that was not produced by ccmap_place, or a bad
 * enum value is answered with CCMAP_INVALID_ARGUMENT and changes nothing. A handle whose storage
 * header an upset damaged (docs/integration.md, "Radiation: single-event upsets") is answered
 * with CCMAP_CORRUPT and changes nothing: place and init the map again. Functions that return a
 * number answer 0 for a bad or damaged handle. A map used before a successful ccmap_init or
 * ccmap_load_snapshot answers CCMAP_NOT_INITIALISED; a map whose own state (parameters, windows)
 * failed its check after an upset answers CCMAP_CORRUPT to every call but ccmap_init and
 * ccmap_load_snapshot, changing nothing. Each call below names its other refusals;
 * "refused (counted)" means the map also counts it (ccmap_get_counters) and is left unchanged.
 *
 * Thread safety: none inside; one map must not be used by two threads at once.
 */
#ifndef CCMAP_CCMAP_H
#define CCMAP_CCMAP_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- status codes (the numeric values of ccmap::Status) ------------------------------------ */
typedef enum ccmap_status {
  CCMAP_OK = 0,
  CCMAP_NON_FINITE_INPUT = 1,  /* NaN or Inf in a coordinate, pose or parameter */
  CCMAP_OUT_OF_RANGE = 2,      /* finite but beyond the documented range */
  CCMAP_BAD_WEIGHT = 3,        /* weight <= 0, NaN, Inf or too large */
  CCMAP_OUTSIDE_MAP = 4,       /* position not covered by the map */
  CCMAP_UNKNOWN = 5,           /* cell not observed or not adequately covered */
  CCMAP_INVALID_ARGUMENT = 6,  /* NULL pointer, bad handle, inconsistent sizes, bad configuration */
  CCMAP_BUFFER_TOO_SMALL = 7,  /* the caller's buffer cannot hold the result */
  CCMAP_NOT_INITIALISED = 8,   /* map used before a successful ccmap_init or ccmap_load_snapshot */
  CCMAP_CORRUPT = 9,           /* snapshot failed its integrity or validity checks; or the map's own
                                  state (its storage header, parameters, windows) failed its check
                                  after a single-event upset: re-init (or load a snapshot) */
  CCMAP_VERSION_MISMATCH = 10, /* snapshot of another format version or another preset */
  CCMAP_DUPLICATE = 11,        /* map exchange: delta already merged (sender, sequence) or this map's own */
  CCMAP_MISALIGNED = 12,       /* map exchange: another cell width, or an origin offset off the coarsest grid */
  CCMAP_INSUFFICIENT_OVERLAP = 13, /* registration: too few samples on known cells of the map */
  CCMAP_DEGENERATE_INPUT = 14,     /* registration: no usable points, or all of them at one spot */
  CCMAP_NOT_CONVERGED = 15,        /* registration: no solution within the iteration or search bounds */
  CCMAP_STATUS_MAX_ENUM_ = 0x7FFFFFFF /* not a status: keeps the enum 32 bits wide */
} ccmap_status;

/* Short, stable, lower-case name ("ok", "corrupt", ...); never NULL. */
const char* ccmap_status_string(ccmap_status status);

/* ---- presets (compile-time shapes, include/ccmap/map/config.hpp) --------------------------- */
typedef enum ccmap_preset {
  CCMAP_PRESET_CADRE = 0,          /* 4 cm Kalman 64^2, CCM 8/16/32/64 cm: 64^2, 64^2, 32^2, 32^2 */
  CCMAP_PRESET_SINGLE_CCM = 1,     /* one CCM layer, 256^2 (8 cm default) */
  CCMAP_PRESET_SINGLE_KALMAN = 2,  /* one Kalman layer, 256^2 (baseline) */
  CCMAP_PRESET_SINGLE_OMG = 3,     /* one OMG layer, 256^2 (baseline) */
  CCMAP_PRESET_MAX_ENUM_ = 0x7FFFFFFF /* not a preset: keeps the enum 32 bits wide */
} ccmap_preset;

#define CCMAP_MAX_LAYERS 8

/* Storage for a map placed by ccmap_place. The sizes are upper bounds with headroom for future
 * versions (the library checks at build time that its map fits, and that each KiB figure below
 * is its constant); ccmap_storage_size() gives the exact figure (docs/integration.md, section 7,
 * lists them). The unions give every target's maximum fundamental alignment (16 on
 * x86-64 and aarch64), more than ccmap_storage_align() asks for. */
#define CCMAP_CADRE_STORAGE_SIZE 835584u          /* 816 KiB */
#define CCMAP_SINGLE_CCM_STORAGE_SIZE 3211264u    /* 3136 KiB */
#define CCMAP_SINGLE_KALMAN_STORAGE_SIZE 3506176u /* 3424 KiB */
#define CCMAP_SINGLE_OMG_STORAGE_SIZE 1376256u    /* 1344 KiB */
#define CCMAP_STORAGE_ALIGN 16u

#define CCMAP_DEFINE_STORAGE_(name, size) \
  typedef union name { /* NOLINT(bugprone-macro-parentheses): a type name */ \
    unsigned char bytes[size];            \
    long double align_long_double;        \
    uint64_t align_u64;                   \
    void* align_pointer;                  \
  } name
CCMAP_DEFINE_STORAGE_(ccmap_cadre_storage, CCMAP_CADRE_STORAGE_SIZE);
CCMAP_DEFINE_STORAGE_(ccmap_single_ccm_storage, CCMAP_SINGLE_CCM_STORAGE_SIZE);
CCMAP_DEFINE_STORAGE_(ccmap_single_kalman_storage, CCMAP_SINGLE_KALMAN_STORAGE_SIZE);
CCMAP_DEFINE_STORAGE_(ccmap_single_omg_storage, CCMAP_SINGLE_OMG_STORAGE_SIZE);

/* Exact bytes and alignment a map of `preset` needs; 0 for a bad preset. */
size_t ccmap_storage_size(ccmap_preset preset);
size_t ccmap_storage_align(ccmap_preset preset);
size_t ccmap_cadre_storage_size(void);
size_t ccmap_cadre_storage_align(void);

/* Bytes of a snapshot of each preset (exact, fixed by the preset). */
#define CCMAP_CADRE_SNAPSHOT_SIZE 516428u
#define CCMAP_SINGLE_CCM_SNAPSHOT_SIZE 2883884u
#define CCMAP_SINGLE_KALMAN_SNAPSHOT_SIZE 1048876u
#define CCMAP_SINGLE_OMG_SNAPSHOT_SIZE 1048876u

/* ---- the map handle ------------------------------------------------------------------------- */
typedef struct ccmap_map ccmap_map; /* opaque: lives at the start of the caller's storage */

/* Constructs an empty, uninitialised map of `preset` in storage[0..storage_size) and writes its
 * handle (== storage) to *out. The storage must stay valid and untouched while the map is used;
 * placing again over the same storage starts afresh. No clean-up call is needed.
 * CCMAP_INVALID_ARGUMENT: NULL storage or out, bad preset, storage not aligned to
 * ccmap_storage_align(preset). CCMAP_BUFFER_TOO_SMALL: storage_size < ccmap_storage_size(preset). */
ccmap_status ccmap_place(void* storage, size_t storage_size, ccmap_preset preset, ccmap_map** out);

/* ---- parameters ----------------------------------------------------------------------------- */
typedef enum ccmap_sensor_kind { CCMAP_SENSOR_STEREO = 0, CCMAP_SENSOR_LIDAR = 1 } ccmap_sensor_kind;
typedef enum ccmap_weight_mode {
  CCMAP_WEIGHT_CONSTANT = 0,         /* every point weighs 1 (the paper's configuration) */
  CCMAP_WEIGHT_INVERSE_VARIANCE = 1  /* sigma_ref^2 / sigma(r)^2, 1 at reference_range_m */
} ccmap_weight_mode;

/* Range-noise model of the sensor (include/ccmap/sensor/noise_model.hpp). */
typedef struct ccmap_noise_params {
  int32_t sensor;                  /* ccmap_sensor_kind */
  float stereo_focal_px;           /* stereo: sigma(r) = r^2 * disparity_sigma / (focal * baseline) */
  float stereo_baseline_m;
  float stereo_disparity_sigma_px;
  float lidar_sigma0_m;            /* lidar: sigma(r) = sigma0 + sigma_per_m * r */
  float lidar_sigma_per_m;
  int32_t weight_mode;             /* ccmap_weight_mode */
  float reference_range_m;         /* inverse-variance weighting only, > 0 */
} ccmap_noise_params;

/* Run-time parameters (ccmap::StackParams). Start from ccmap_default_params. */
typedef struct ccmap_params {
  float finest_cell_width_m;  /* layer 0 width; layer k is 2^k times wider */
  float weight_limit;         /* W_l (eqs. 6-7); INFINITY = no limit */
  float coverage_tau;         /* tau of eq. (12), paper: 0.8 */
  float min_weight;           /* cells with less accumulated weight are unknown */
  float obstacle_fraction;    /* minimum obstacle height as a share of the cell width */
  float max_inclination;      /* steeper gradients (dz/dxy) are CCMAP_CLASS_STEEP */
  float kalman_min_variance;  /* variance floor of Kalman cells (m^2) */
  float normal_variance_threshold[CCMAP_MAX_LAYERS]; /* m^2 per layer; <= 0: calibrate at init */
  float finest_max_sigma_m;   /* largest range sigma the constant finest layer takes (m);
                                 derived from the width: use ccmap_default_params_for_width
                                 when changing finest_cell_width_m */
  float outlier_gate_sigma;   /* outlier gate, standard deviations (1..100); 0 = off: every
                                 point trusted, the paper's update (docs/design.md) */
  float change_min_points;    /* change rule: held points (and those inside the gate) are a surface */
  float change_share;         /* of their own with this many points and this share of the cell's */
  uint32_t frame_point_budget;   /* frame budget: at most this many points per frame (0: all) */
  uint32_t frame_time_budget_us; /* and no new 256-point chunk after this many us (0: no limit);
                                    docs/integration.md, "The frame budget" */
  float free_space_rays;      /* lines of sight walked per frame (whole number, 0..65535); 0 = no
                                 free space: no ghost cleared, no drop-off (docs/design.md) */
  float free_space_clear_frames; /* frames of rays clearly below a surface before it is cleared (1..255) */
  float sensor_view_axis[3];  /* the sensor's viewing direction in its own frame (all 0: not given);
                                 sensor-frame points behind it cast no line of sight */
  ccmap_noise_params noise;
} ccmap_params;

/* CADRE defaults for the preset's default finest width (CADRE: 4 cm, single layers: 8 cm).
 * CCMAP_INVALID_ARGUMENT: NULL out or bad preset. */
ccmap_status ccmap_default_params(ccmap_preset preset, ccmap_params* out);
/* The same defaults for another finest cell width (m). CCMAP_INVALID_ARGUMENT: NULL out. The
 * width is not checked here: ccmap_init refuses a bad one. */
ccmap_status ccmap_default_params_for_width(float finest_cell_width_m, ccmap_params* out);

/* Validates the parameters and (re)initialises the map: every layer centred on the origin and
 * empty. On failure the map is uninitialised (CCMAP_NOT_INITIALISED for every other call).
 * CCMAP_INVALID_ARGUMENT: NULL params or map, a bad handle, noise.sensor or noise.weight_mode
 * outside its enum, or a parameter outside its range (e.g. finest_cell_width_m below 0.19 mm or
 * giving coarsest cells over 100 m, coverage_tau outside (0, 1], weight_limit below 1e-3 or NaN,
 * outlier_gate_sigma neither 0 nor in [1, 100], change_share outside (0, 0.5]).
 * CCMAP_NON_FINITE_INPUT: NaN or Inf in any other parameter (the noise model's included). */
ccmap_status ccmap_init(ccmap_map* map, const ccmap_params* params);

/* ---- run phase ------------------------------------------------------------------------------ */
/* What happened to the points of one frame (ccmap::FrameCounters). */
typedef struct ccmap_frame_counters {
  uint32_t received;
  uint32_t used;
  uint32_t rejected_non_finite;
  uint32_t rejected_out_of_range;
  uint32_t rejected_weight;
  uint32_t outside_map;
  uint32_t too_noisy;
  uint32_t gated_finer;      /* outside the gate of the next finer layer's cell there: dropped */
  uint32_t gated_occluded;   /* stereo: its line of sight passes under known ground: dropped */
  uint32_t gated_held;       /* outside its cell's outlier gate: held for the change rule */
  uint32_t gated_pool_full;  /* outside the gate while every held-point slot was taken: dropped */
  uint32_t gated_admitted;   /* held points the change rule admitted (re-seed or merge) */
  uint32_t gated_dropped;    /* held points it dropped as outliers (or whose cell left the map) */
  uint32_t reseeded_cells;   /* cells replaced by their held points */
  uint32_t merged_cells;     /* cells that took their held points in beside their own */
  uint32_t skipped_budget;   /* not processed: the frame budget was spent */
  uint32_t corrupted_cells;  /* single-event upsets: cells whose bits disagreed with their check, reset */
  uint32_t corrupted_slots;  /* held-point slots whose bits disagreed with their seal, dropped */
  /* ---- free space from lines of sight (rays and cells, not points) ---- */
  uint32_t free_rays;        /* lines of sight walked (free space; not points) */
  uint32_t free_rays_refused; /* sampled points whose line of sight was refused (bad point, behind
                                 the sensor, sensor outside the map): they change nothing */
  uint32_t cleared_cells;    /* cells emptied: lines of sight passed clearly below their surface */
  uint32_t drop_cells;       /* unobserved cells that became drop-offs */
} ccmap_frame_counters;

/* Re-centres every layer on the robot at (x, y) (m). Refused (counted): a non-finite position
 * (CCMAP_NON_FINITE_INPUT), |x| or |y| above 1e5 m (CCMAP_OUT_OF_RANGE). */
ccmap_status ccmap_move_to(ccmap_map* map, float x, float y);

/* The same move for a pose known only to position_sigma_m (m, 1-sigma, isotropic): the
 * odometry's uncertainty of the position change since the last move. Every observed cell then
 * forgets in proportion to inclination^2 sigma^2 (Stack::move_to(x, y, sigma); one pass over
 * every cell). 0 is ccmap_move_to exactly. Refused (counted): as ccmap_move_to, and a non-finite
 * (CCMAP_NON_FINITE_INPUT), negative (CCMAP_INVALID_ARGUMENT) or > 1e5 m (CCMAP_OUT_OF_RANGE) sigma. */
ccmap_status ccmap_move_to_uncertain(ccmap_map* map, float x, float y, float position_sigma_m);

/* Folds n points, xyz[3*i .. 3*i+2] in the map frame (m). weights may be NULL (the noise
 * model's weight) or n weights, one per point (the w_t of eq. (1)); a weight outside
 * (0, 1e6] refuses its point. sensor_origin_xyz: the sensor position in the map frame (3 floats).
 * counters may be NULL. Refused as a whole, the map unchanged: NULL sensor_origin_xyz
 * (CCMAP_INVALID_ARGUMENT, not counted); counted: NULL xyz with n > 0, n >= 2^32
 * (CCMAP_INVALID_ARGUMENT), a non-finite sensor origin (CCMAP_NON_FINITE_INPUT), a coordinate of
 * the sensor origin above 1e5 m (CCMAP_OUT_OF_RANGE). Points are refused one by one, counted in
 * counters by reason (non-finite, out of range, weight, outside the map, too noisy). */
ccmap_status ccmap_update_frame(ccmap_map* map, const float* xyz, const float* weights, size_t n,
                                const float* sensor_origin_xyz, ccmap_frame_counters* counters);

/* Sensor pose: p_map = rotation * p_sensor + translation; rotation row-major 3 x 3. */
typedef struct ccmap_pose {
  float rotation[9];
  float translation[3];
} ccmap_pose;

/* Same as ccmap_update_frame for points in the sensor frame (noise-model weights); a sensor-frame
 * coordinate of 2^11 m or more refuses its point (out of range). Refused as a whole, the map
 * unchanged: NULL pose (CCMAP_INVALID_ARGUMENT, not counted); counted: NULL xyz with n > 0,
 * n >= 2^32, a rotation that is not one (an entry above 1.001 in magnitude, or R^T R off the
 * identity by more than 1e-3: CCMAP_INVALID_ARGUMENT), NaN or Inf in the rotation or the
 * translation (CCMAP_NON_FINITE_INPUT), a translation coordinate above 1e5 m (CCMAP_OUT_OF_RANGE). */
ccmap_status ccmap_update_frame_sensor(ccmap_map* map, const float* xyz, size_t n, const ccmap_pose* pose,
                                       ccmap_frame_counters* counters);

/* ---- registration (include/ccmap/registration/registration.hpp, types.hpp) ------------------ */
/* The rigid correction (dx, dy, dz m; dyaw rad about the vertical through the rotation centre:
 * the sensor origin of a frame) that best aligns a frame's map-frame points with the map: p' =
 * Rz(dyaw)(p - o) + o + d. Axes a terrain does not fix are not claimed: observable[k] == 0, their
 * sigma +infinity, and the correction has no component along them. Indices: 0 dx, 1 dy, 2 dz, 3 dyaw. */
typedef struct ccmap_registration_params {
  uint32_t max_points;      /* points used, at most (every k-th): 1 .. 65536 */
  uint32_t max_iterations;  /* 1 .. 64 */
  uint32_t min_matches;     /* fewest points on known cells, >= 3 */
  float max_translation_m;  /* search bound of |(dx, dy)| and |dz| */
  float max_yaw_rad;        /* search bound of |dyaw|, (0, 0.5] */
  float max_sigma_m;        /* a direction is observable when its sigma is at most this (yaw times the lever) */
  float robust_sigmas;      /* Cauchy weight scale in standard deviations */
  float model_variance_m2;  /* variance added to every residual */
  float convergence_m;      /* a step moving no point by more than this ends the iterations */
} ccmap_registration_params;

typedef struct ccmap_registration_result {
  int32_t status;          /* ccmap_status; on any but CCMAP_OK nothing is claimed */
  float correction[4];     /* dx, dy, dz (m), dyaw (rad) */
  float sigma[4];          /* 1-sigma; +infinity where not observable */
  uint8_t observable[4];   /* 1 where the terrain fixes the parameter */
  uint32_t rank;           /* observable directions, 0 .. 4 */
  uint32_t iterations;
  uint32_t points_sampled;
  uint32_t points_rejected;
  uint32_t points_matched;
  float lever_m;           /* the yaw's lever arm */
  float residual_sigma;    /* RMS residual in its own standard deviations */
  float centre[2];         /* rotation centre, map frame (m): the sensor origin; team alignment: the
                              centre of the other map's cells */
  uint32_t cells;          /* team alignment: the other map's usable cells; 0 for a frame */
} ccmap_registration_result;

/* The library's defaults (1,024 points, 10 iterations, ...). CCMAP_INVALID_ARGUMENT for NULL. */
ccmap_status ccmap_default_registration_params(ccmap_registration_params* out);
/* Registers map-frame points (xyz: 3 n floats) seen from sensor_origin_xyz before they are folded
 * in; changes nothing in the map. params NULL: the defaults. Returns out->status:
 * CCMAP_NOT_INITIALISED, CCMAP_INVALID_ARGUMENT (NULL out or origin, NULL xyz with n > 0, bad
 * params), CCMAP_NON_FINITE_INPUT, CCMAP_OUT_OF_RANGE, CCMAP_DEGENERATE_INPUT, CCMAP_OUTSIDE_MAP
 * (a pose far from the map), CCMAP_INSUFFICIENT_OVERLAP, CCMAP_NOT_CONVERGED. */
ccmap_status ccmap_register_frame(const ccmap_map* map, const float* xyz, size_t n, const float* sensor_origin_xyz,
                                  const ccmap_registration_params* params, ccmap_registration_result* out);
/* The same for sensor-frame points with the sensor pose (rotation centre: its translation). */
ccmap_status ccmap_register_frame_sensor(const ccmap_map* map, const float* xyz, size_t n, const ccmap_pose* pose,
                                         const ccmap_registration_params* params, ccmap_registration_result* out);
/* Team alignment (include/ccmap/registration/alignment.hpp): the correction of another map of the
 * same preset, a snapshot (ccmap_save_snapshot) placed by the nominal offset (its map-frame
 * point p lies at p + offset in this map, m), or an exchange delta placed by the two origins in
 * the team frame (this map's origin given here). Also CCMAP_CORRUPT, CCMAP_VERSION_MISMATCH,
 * CCMAP_MISALIGNED (another cell width), CCMAP_OUT_OF_RANGE (a bad offset). */
ccmap_status ccmap_align_snapshot(const ccmap_map* map, const uint8_t* data, size_t size, const float* offset_xyz_m,
                                  const ccmap_registration_params* params, ccmap_registration_result* out);
ccmap_status ccmap_align_delta(const ccmap_map* map, const uint8_t* data, size_t size, int32_t origin_x_cells,
                               int32_t origin_y_cells, float origin_z_m, const ccmap_registration_params* params,
                               ccmap_registration_result* out);

/* ---- queries -------------------------------------------------------------------------------- */
typedef enum ccmap_cell_class {
  CCMAP_CLASS_UNKNOWN = 0,
  CCMAP_CLASS_TRAVERSABLE = 1,
  CCMAP_CLASS_OBSTACLE = 2,
  CCMAP_CLASS_STEEP = 3,
  CCMAP_CLASS_DROP = 4  /* unobserved, lines of sight passed far below the ground before it: a
                           crater, ditch or ledge; a hazard (docs/design.md, free space) */
} ccmap_cell_class;

/* "unknown", "traversable", "obstacle", "steep", "drop"; never NULL. */
const char* ccmap_cell_class_string(int32_t cell_class);

/* Answer of a point query (ccmap::QueryResult). On status != CCMAP_OK the numbers are 0. */
typedef struct ccmap_query_result {
  int32_t status;             /* ccmap_status */
  int32_t layer;              /* layer that answered (0 = finest), -1 if none holds the point */
  float cell_width_m;
  float height_m;             /* sub-cell height at the point (eq. 10) */
  float slope_x;              /* dz/dx of the cell's least-squares plane (ccm_surface) */
  float slope_y;
  float inclination;          /* sqrt(slope_x^2 + slope_y^2) */
  float normal_variance;      /* sigma_s^2 (eq. 11; the plane's residual), m^2 */
  float elevation_variance;   /* m^2 */
  float weight;
  int32_t cell_class;         /* ccmap_cell_class */
  int32_t upset;              /* 1 with CCMAP_UNKNOWN: the answering cell (or one pooled into it) failed
                                 its check or was reset by the scrub (a single-event upset); unknown
                                 until new points observe it, and no other layer answers the place */
} ccmap_query_result;

/* Answer of the finest layer that knows (x, y). Returns out->status (CCMAP_OK,
 * CCMAP_UNKNOWN, CCMAP_OUTSIDE_MAP, CCMAP_NOT_INITIALISED, CCMAP_CORRUPT) or
 * CCMAP_INVALID_ARGUMENT. A cell whose bits an upset changed answers CCMAP_UNKNOWN with upset = 1. */
ccmap_status ccmap_query(const ccmap_map* map, float x, float y, ccmap_query_result* out);
/* Answer of one layer (0 = finest): as ccmap_query, and CCMAP_INVALID_ARGUMENT for a layer outside
 * [0, ccmap_layer_count(map)). */
ccmap_status ccmap_query_layer(const ccmap_map* map, int32_t layer, float x, float y, ccmap_query_result* out);

/* Layers: count (0 for a bad handle), cells per layer (0 for a bad layer), cell width (m, 0 for
 * a bad layer or before init). */
int32_t ccmap_layer_count(const ccmap_map* map);
size_t ccmap_layer_capacity(const ccmap_map* map, int32_t layer);
float ccmap_layer_cell_width(const ccmap_map* map, int32_t layer);

/* One exported cell (ccmap::CellRecord). */
typedef struct ccmap_cell_record {
  int32_t index_x;            /* global cell index (stable across moves) */
  int32_t index_y;
  float centre_x;             /* cell centre, map frame (m) */
  float centre_y;
  float weight;
  float height_m;             /* at the cell centre */
  float slope_x;
  float slope_y;
  float normal_variance;
  float elevation_variance;
  uint8_t cell_class;         /* ccmap_cell_class */
  uint8_t reserved[3];
} ccmap_cell_record;

/* Writes every observed cell of `layer` into out[0..*written). CCMAP_BUFFER_TOO_SMALL (nothing
 * written) if capacity < ccmap_layer_capacity(map, layer); CCMAP_INVALID_ARGUMENT: NULL out or
 * written, a bad handle, a bad layer. *written is 0 on every refusal. */
ccmap_status ccmap_export_layer(const ccmap_map* map, int32_t layer, ccmap_cell_record* out, size_t capacity,
                                size_t* written);

/* ---- planner queries (include/ccmap/planner/footprint.hpp, path_query.hpp, costmap.hpp) -------- */
#define CCMAP_MAX_FOOTPRINT_CELLS 4096u      /* bounding box of a footprint, in finest-layer cells */
#define CCMAP_DEFAULT_MAX_UNKNOWN_SHARE 0.1f
#define CCMAP_MAX_PATH_SAMPLES 256u
#define CCMAP_MAX_PATH_VERTICES 256u
#define CCMAP_MAX_COSTMAP_SIDE 1024u
#define CCMAP_MAX_INFLATION_PIXELS 32
#define CCMAP_COST_FREE 0u
#define CCMAP_COST_MAX_TRAVERSABLE 252u
#define CCMAP_COST_INSCRIBED 253u
#define CCMAP_COST_LETHAL 254u
#define CCMAP_COST_UNKNOWN 255u

/* An oriented rectangle (map frame): centre, direction of the length axis (any length >= 1e-6;
 * build it from cos/sin of the yaw), full extents (m). */
typedef struct ccmap_footprint {
  float x;
  float y;
  float heading_x;
  float heading_y;
  float length_m;
  float width_m;
} ccmap_footprint;

/* Answer of a footprint query (ccmap::FootprintResult). */
typedef struct ccmap_footprint_result {
  int32_t status;          /* CCMAP_OK, CCMAP_OUTSIDE_MAP (no layer holds any part), or the refusal */
  int32_t worst_class;     /* ccmap_cell_class of the known parts (drop > obstacle > steep > traversable);
                              CCMAP_CLASS_UNKNOWN if none is known */
  float unknown_share;     /* [0, 1] of the area */
  float max_step_m;        /* height range over the known parts, or 4 sigma_s relief if larger */
  float max_inclination;   /* dz/dxy */
  float min_height_m;
  float max_height_m;
  float area_m2;
  int32_t worst_layer;     /* answering layer of the worst part, -1 if none is known */
  int32_t worst_index_x;   /* its cell (global index) */
  int32_t worst_index_y;
  float worst_x;           /* that cell's centre (m) */
  float worst_y;
  uint32_t cells_visited;  /* map cells read */
  float upset_share;       /* [0, unknown_share]: unknown because of an upset; > 0 makes the
                              footprint unknown whatever the tolerated share */
} ccmap_footprint_result;

/* Every part of the rectangle answered by the finest layer that knows it, as ccmap_query would
 * answer its points. Returns out->status, or CCMAP_INVALID_ARGUMENT (NULL pointers, bad handle);
 * CCMAP_NOT_INITIALISED.
 * Refusals: CCMAP_NON_FINITE_INPUT, CCMAP_INVALID_ARGUMENT (zero heading, extents not > 0),
 * CCMAP_OUT_OF_RANGE (centre beyond 1e5 m; bounding box over CCMAP_MAX_FOOTPRINT_CELLS cells). */
ccmap_status ccmap_query_footprint(const ccmap_map* map, const ccmap_footprint* footprint, ccmap_footprint_result* out);

/* The verdict: obstacle/steep if a known part is; else unknown if unknown_share > max_unknown_share
 * or nothing is known; else traversable (ccmap_cell_class). Unknown for NULL or a refused result. */
int32_t ccmap_footprint_class(const ccmap_footprint_result* result, float max_unknown_share);

typedef struct ccmap_path_pose {
  float x;
  float y;
  float heading_x; /* unit direction of travel */
  float heading_y;
} ccmap_path_pose;

/* The body swept along a path: length along the travel, width, distance between poses (all > 0),
 * and the unknown share above which a footprint counts as unknown ([0, 1]). */
typedef struct ccmap_path_sweep {
  float length_m;
  float width_m;
  float step_m;
  float max_unknown_share;
} ccmap_path_sweep;

typedef struct ccmap_path_result {
  int32_t status;
  int32_t hazard_found;            /* 1: a pose's footprint is obstacle or steep */
  float first_hazard_m;            /* its distance along the path; 0 if none */
  ccmap_path_pose hazard_pose;
  ccmap_footprint_result hazard;
  int32_t unknown_found;           /* 1: a pose's footprint has more unknown area than allowed */
  float first_unknown_m;
  ccmap_path_pose unknown_pose;
  ccmap_footprint_result unknown;
  float path_length_m;
  float checked_m;                 /* distance of the last pose evaluated */
  uint32_t samples;                /* poses evaluated (step apart from 0, and the end) */
  uint32_t cells_visited;
} ccmap_path_result;

/* The body at poses every sweep->step_m along the polyline xy[2*i], xy[2*i+1] (count 2 ..
 * CCMAP_MAX_PATH_VERTICES points, heading along each segment), until both a hazard and an unknown
 * footprint are found. Returns out->status. Refused: CCMAP_INVALID_ARGUMENT (NULL sweep or out, a
 * bad handle; NULL xy, fewer than 2 or more than CCMAP_MAX_PATH_VERTICES points, no segment of
 * 1 um or more; sweep extents or step not > 0, max_unknown_share outside [0, 1]),
 * CCMAP_NON_FINITE_INPUT (a point or the sweep), CCMAP_OUT_OF_RANGE (a point beyond 1e5 m, more
 * than CCMAP_MAX_PATH_SAMPLES poses), CCMAP_NOT_INITIALISED. */
ccmap_status ccmap_query_path(const ccmap_map* map, const float* xy, size_t count, const ccmap_path_sweep* sweep,
                              ccmap_path_result* out);
/* The same along a circular arc from `start` (curvature 1/m, > 0 left; |curvature| length_m <= 2 pi).
 * Refused: CCMAP_INVALID_ARGUMENT (NULL start, sweep or out, a bad handle; a heading shorter than
 * 1e-6, a negative length; the sweep's as ccmap_query_path), CCMAP_NON_FINITE_INPUT,
 * CCMAP_OUT_OF_RANGE (start beyond 1e5 m, |curvature| length_m > 2 pi, length_m > 1e4 m, more
 * than CCMAP_MAX_PATH_SAMPLES poses), CCMAP_NOT_INITIALISED. */
ccmap_status ccmap_query_arc(const ccmap_map* map, const ccmap_path_pose* start, float curvature, float length_m,
                             const ccmap_path_sweep* sweep, ccmap_path_result* out);

/* A cost raster of side x side pixels of resolution_m around (centre_x, centre_y): pixel
 * (ix, iy) at cost[ix + side * iy], row 0 at the lowest y (costmap_2d). inflation_radius_m 0: none. */
typedef struct ccmap_costmap_spec {
  float centre_x;
  float centre_y;
  float resolution_m;
  uint32_t side;
  float inflation_radius_m;
} ccmap_costmap_spec;

typedef struct ccmap_costmap_stats {
  uint32_t free;       /* cost 0 */
  uint32_t cost;       /* 1 .. 252 */
  uint32_t inscribed;  /* 253 */
  uint32_t lethal;     /* 254 */
  uint32_t unknown;    /* 255 */
  uint32_t cells_visited;
} ccmap_costmap_stats;

/* Fills cost[0 .. side^2) in the costmap_2d convention (0 free .. 252, 253 inscribed, 254 lethal,
 * 255 unknown; the worst over each pixel's square; include/ccmap/planner/costmap.hpp has the cost
 * function). stats may be NULL. Refused, buffer untouched: CCMAP_INVALID_ARGUMENT (NULL, side 0 or
 * above CCMAP_MAX_COSTMAP_SIDE, resolution not > 0, negative radius), CCMAP_BUFFER_TOO_SMALL,
 * CCMAP_NON_FINITE_INPUT, CCMAP_OUT_OF_RANGE (raster beyond 1e5 m, radius above
 * CCMAP_MAX_INFLATION_PIXELS pixels), CCMAP_NOT_INITIALISED. */
ccmap_status ccmap_fill_costmap(const ccmap_map* map, const ccmap_costmap_spec* spec, uint8_t* cost, size_t capacity,
                                ccmap_costmap_stats* stats);

/* ---- counters ------------------------------------------------------------------------------- */
typedef struct ccmap_counters {
  ccmap_frame_counters totals;  /* accumulated over the map's life (saturating) */
  uint32_t rejected_moves;
  uint32_t rejected_frames;
  uint64_t last_update_ns;      /* duration of the last accepted frame update */
} ccmap_counters;

/* CCMAP_INVALID_ARGUMENT: NULL out, a bad handle; CCMAP_NOT_INITIALISED (out untouched);
 * CCMAP_CORRUPT: the map's state failed its check after an upset, out written all the same (the
 * counters say what the map saw before). */
ccmap_status ccmap_get_counters(const ccmap_map* map, ccmap_counters* out);

/* ---- snapshots (include/ccmap/persistence/snapshot.hpp has the byte format) ------------------------- */
/* Bytes of a snapshot of this map (0 for a bad handle). */
size_t ccmap_snapshot_size(const ccmap_map* map);
/* *written = bytes written (0 on a refusal). CCMAP_BUFFER_TOO_SMALL if capacity <
 * ccmap_snapshot_size(map); CCMAP_INVALID_ARGUMENT: NULL buffer or written, a bad handle;
 * CCMAP_NOT_INITIALISED; CCMAP_NON_FINITE_INPUT: the map holds a NaN or Inf that a load would
 * refuse (no update of this library writes one). */
ccmap_status ccmap_save_snapshot(const ccmap_map* map, uint8_t* buffer, size_t capacity, size_t* written);
/* All-or-nothing restore (the map may be uninitialised; on a refusal it is bitwise unchanged):
 * CCMAP_INVALID_ARGUMENT (NULL data, a bad handle), CCMAP_CORRUPT (truncated, trailing bytes, CRC
 * mismatch, content no save writes), CCMAP_VERSION_MISMATCH (another format version or a snapshot
 * of another preset). */
ccmap_status ccmap_load_snapshot(ccmap_map* map, const uint8_t* data, size_t size);

/* ---- map exchange between rovers (include/ccmap/persistence/exchange.hpp: rules and byte format) ---- */
/* An exchange holds one copy of its map's cells (what it last sent) and a table of 8 peers; it
 * lives in caller storage like the map. Sizes: upper bounds with headroom, exact figures from
 * ccmap_exchange_storage_size(). */
#define CCMAP_CADRE_EXCHANGE_STORAGE_SIZE 475136u          /* 464 KiB */
#define CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE 2686976u    /* 2624 KiB */
#define CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE 802816u  /* 784 KiB */
#define CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE 802816u     /* 784 KiB */
CCMAP_DEFINE_STORAGE_(ccmap_cadre_exchange_storage, CCMAP_CADRE_EXCHANGE_STORAGE_SIZE);
CCMAP_DEFINE_STORAGE_(ccmap_single_ccm_exchange_storage, CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE);
CCMAP_DEFINE_STORAGE_(ccmap_single_kalman_exchange_storage, CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE);
CCMAP_DEFINE_STORAGE_(ccmap_single_omg_exchange_storage, CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE);

/* Largest delta of a preset (every cell) and the smallest (no cell); 0 for a bad preset. */
#define CCMAP_CADRE_DELTA_MAX_SIZE 473240u
size_t ccmap_delta_max_size(ccmap_preset preset);
size_t ccmap_delta_min_size(ccmap_preset preset);

typedef struct ccmap_exchange ccmap_exchange; /* opaque: lives at the start of the caller's storage */

/* Exact bytes and alignment an exchange of `preset` needs; 0 for a bad preset. */
size_t ccmap_exchange_storage_size(ccmap_preset preset);
size_t ccmap_exchange_storage_align(ccmap_preset preset);
/* Constructs an unbound exchange of `preset` in storage, with ccmap_place's refusals. */
ccmap_status ccmap_exchange_place(void* storage, size_t storage_size, ccmap_preset preset, ccmap_exchange** out);

/* Who this map is in the team, and where its map frame lies in the team frame. */
typedef struct ccmap_exchange_params {
  uint32_t rover_id;       /* unique per rover */
  uint32_t session;        /* new value on every restart of this rover's map (e.g. a boot counter) */
  int32_t origin_x_cells;  /* map-frame origin in the team frame, in finest-layer cells */
  int32_t origin_y_cells;
  float origin_z_m;        /* map-frame origin height in the team frame (m) */
} ccmap_exchange_params;

/* Binds the exchange to an initialised map of the same preset and starts afresh (nothing counts
 * as sent: the first export sends the whole map). Re-initialising or re-loading the map retires
 * the exchange (CCMAP_NOT_INITIALISED) until it is bound again. CCMAP_INVALID_ARGUMENT: NULL,
 * bad handles, another preset, a bad origin (origin_z_m not finite or beyond 1e5 m, a cell
 * origin beyond +-2^30); CCMAP_NOT_INITIALISED: the map is not initialised. */
ccmap_status ccmap_exchange_init(ccmap_exchange* exchange, ccmap_map* map, const ccmap_exchange_params* params);

typedef struct ccmap_export_report {
  uint32_t sequence;         /* the delta's sequence number */
  uint32_t cells_written;
  uint32_t cells_saturated;  /* of those, sent whole: weight limit or variance floor engaged */
  uint32_t cells_pending;    /* changed, not written (below the floor or no room): sent later */
  uint64_t bytes;
} ccmap_export_report;

/* Writes a delta of what the map gained since the last export (coarsest layer first, as many
 * cells as fit) and counts it as sent. weight_floor >= 0: cells whose gain weighs less stay
 * pending; so do the cells of layers finer than finest_layer (0: every layer). report may be
 * NULL. CCMAP_BUFFER_TOO_SMALL: capacity < ccmap_delta_min_size; CCMAP_INVALID_ARGUMENT: NULL
 * buffer or written, a bad handle, a negative or NaN floor, a layer outside the map's;
 * CCMAP_NOT_INITIALISED: the exchange is not bound, or its map was re-initialised or re-loaded
 * since. Nothing counts as sent on a refusal. */
ccmap_status ccmap_exchange_export(ccmap_exchange* exchange, uint8_t* buffer, size_t capacity, float weight_floor,
                                   int32_t finest_layer, size_t* written, ccmap_export_report* report);

typedef struct ccmap_merge_report {
  uint32_t sender_id;      /* 0 for a snapshot */
  uint32_t sequence;       /* 0 for a snapshot */
  uint32_t cells_merged;
  uint32_t cells_outside;  /* outside this map's windows: dropped */
  uint32_t deltas_missed;  /* sequence numbers of this sender lost before this delta */
} ccmap_merge_report;

/* Folds another rover's delta into the map, all-or-nothing: CCMAP_NOT_INITIALISED (as for
 * export), CCMAP_INVALID_ARGUMENT (NULL data, a bad handle), CCMAP_CORRUPT, CCMAP_VERSION_MISMATCH,
 * CCMAP_MISALIGNED, CCMAP_DUPLICATE, CCMAP_BUFFER_TOO_SMALL (peer table full), CCMAP_OUT_OF_RANGE
 * (the merge would leave a cell non-finite or beyond 1e5 m); on any of them the map is bitwise
 * unchanged (include/ccmap/persistence/exchange.hpp lists when each applies). report may be NULL. */
ccmap_status ccmap_exchange_merge_delta(ccmap_exchange* exchange, const uint8_t* data, size_t size,
                                        ccmap_merge_report* report);
/* Folds a snapshot of an independently built map (its origin minus this one's: finest cells, m),
 * all-or-nothing: CCMAP_NOT_INITIALISED (as for export), ccmap_load_snapshot's refusals, then
 * CCMAP_MISALIGNED (another finest cell width, or an offset that is not a whole number of
 * coarsest cells), CCMAP_INVALID_ARGUMENT (a non-finite offset_z_m), CCMAP_OUT_OF_RANGE (as for a
 * delta). report may be NULL. */
ccmap_status ccmap_exchange_merge_snapshot(ccmap_exchange* exchange, const uint8_t* data, size_t size,
                                           int32_t offset_x_cells, int32_t offset_y_cells, float offset_z_m,
                                           ccmap_merge_report* report);
/* The same into a map without an exchange (e.g. merging saved maps on the ground), with the same
 * refusals (CCMAP_NOT_INITIALISED: the map is not initialised). */
ccmap_status ccmap_merge_snapshot(ccmap_map* map, const uint8_t* data, size_t size, int32_t offset_x_cells,
                                  int32_t offset_y_cells, float offset_z_m, ccmap_merge_report* report);

/* Life-time counters of an exchange (ccmap::ExchangeCounters). */
typedef struct ccmap_exchange_counters {
  uint32_t deltas_exported;
  uint32_t deltas_merged;
  uint32_t snapshots_merged;
  uint32_t refused;
  uint32_t refused_corrupt;
  uint32_t refused_duplicate;
  uint32_t refused_misaligned;
  uint32_t deltas_missed;
  uint64_t bytes_exported;
  uint64_t bytes_merged;
  uint64_t cells_exported;
  uint64_t cells_merged;
  uint64_t cells_outside;
} ccmap_exchange_counters;
/* CCMAP_INVALID_ARGUMENT: NULL out, a bad handle. An exchange never bound answers zeros. */
ccmap_status ccmap_exchange_get_counters(const ccmap_exchange* exchange, ccmap_exchange_counters* out);

/* Name of the linked platform implementation ("posix", "baremetal"). */
const char* ccmap_platform_name(void);

#ifdef __cplusplus
}  /* extern "C" */
#endif

#endif /* CCMAP_CCMAP_H */
