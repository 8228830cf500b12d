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
 * Errors: a NULL pointer argument or a bad enum value is answered with CCMAP_INVALID_ARGUMENT
 * and changes nothing. Functions that return a number answer 0 for a bad or damaged handle. A map
 * used before a successful ccmap_init or ccmap_load_snapshot answers CCMAP_NOT_INITIALISED. Each
 * call below names its other refusals; "refused (counted)" means the map also counts it
 * (ccmap_get_counters, ccmap_get_health) and is left unchanged.
 *
 * CCMAP_CORRUPT versus misuse: two different faults, two different responses.
 *  - Misuse (a programming error): a handle that ccmap_place never produced (a wrong pointer, an
 *    exchange handed over as a map, storage another object overwrote) is answered with
 *    CCMAP_INVALID_ARGUMENT. The map behind it, if any, is not known to be damaged: do not wipe
 *    it; fix the caller (count it, raise a software fault).
 *  - A damaged map (an upset: docs/integration.md, "Radiation: single-event upsets"): the map's
 *    own state (its storage header, parameters, windows, derived constants) failed its check and
 *    every call but ccmap_init, ccmap_load_snapshot and ccmap_get_health answers CCMAP_CORRUPT,
 *    changing nothing. Its cells can no longer be trusted: re-init it (ccmap_place + ccmap_init),
 *    or load the last good snapshot. ccmap_get_health(...).state runs the same check on demand.
 *    A snapshot or delta that fails its checks is also CCMAP_CORRUPT: that one refuses the data,
 *    not the map (the map is unchanged and healthy).
 *  Single cells an upset changed are not a CCMAP_CORRUPT: they read as unknown and the scrub
 *  resets and counts them (ccmap_health.corrupted_cells).
 *
 * Threads (every call below is marked):
 *  [writer] calls change the map; [map reader] calls only read it. Both kinds run on the map's
 *  own thread (the mapper's rate group): one map must not be used by two threads at once, and
 *  nothing inside locks. [any thread] calls touch no map: ccmap_product_read and the decoders
 *  read the caller-owned product buffers that ccmap_publish fills, from any thread, concurrently
 *  with the writer, lock-free ("Readers beside the writer" below; docs/integration.md, "Flight
 *  interface"). [set-up] calls change process-wide state: call them before other threads run.
 *  Writers (the map's thread): ccmap_place, ccmap_init, ccmap_set_params, ccmap_reset_counters,
 *    ccmap_move_to(_uncertain), ccmap_update_frame(_sensor), ccmap_load_snapshot,
 *    ccmap_merge_snapshot, ccmap_exchange_init/export/merge_delta/merge_snapshot (they write the
 *    exchange and, merges, the map).
 *  Map readers (the map's thread): ccmap_get_params, ccmap_get_health, ccmap_get_counters,
 *    ccmap_query(_layer), ccmap_query_footprint/path/arc, ccmap_fill_costmap, ccmap_export_layer,
 *    ccmap_layer_*, ccmap_save_snapshot, ccmap_snapshot_size, ccmap_register_frame(_sensor),
 *    ccmap_align_snapshot/delta, ccmap_exchange_get_counters, ccmap_publish (it writes only the
 *    product buffers: one publishing thread per buffers).
 *  Any thread: ccmap_product_read, ccmap_product_decode, ccmap_validate_params,
 *    ccmap_default_params(_for_width), ccmap_default_registration_params, ccmap_footprint_class,
 *    ccmap_status_string, ccmap_cell_class_string, the size and alignment functions,
 *    ccmap_platform_name.
 *  Set-up: ccmap_set_fault_hook, ccmap_product_buffers_init.
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
  CCMAP_CORRUPT = 9,           /* data (snapshot, delta, product) failed its integrity checks: the
                                  data is refused; or the map's own state (storage header, parameters,
                                  windows) failed its check after an upset: re-init or load a snapshot
                                  (never the answer to misuse: see "CCMAP_CORRUPT versus misuse") */
  CCMAP_VERSION_MISMATCH = 10, /* snapshot of another format version or another preset */
  CCMAP_DUPLICATE = 11,        /* map exchange: delta already merged (sender, sequence) or this map's own */
  CCMAP_MISALIGNED = 12,       /* map exchange: another cell width, or an origin offset off the coarsest grid */
  CCMAP_INSUFFICIENT_OVERLAP = 13, /* registration: too few samples on known cells of the map */
  CCMAP_DEGENERATE_INPUT = 14,     /* registration: no usable points, or all of them at one spot */
  CCMAP_NOT_CONVERGED = 15,        /* registration: no solution within the iteration or search bounds */
  CCMAP_BUSY = 16,                 /* product read: the writer replaced the product during every try
                                      (CCMAP_PRODUCT_READ_TRIES): nothing changed, read again later */
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

/* [any thread] 1 if this build of the library carries `preset`, else 0. The CMake cache variable
 * CCMAP_CAPI_PRESETS (default "all"; e.g. "cadre" for a flight image) chooses which presets the C
 * API instantiates; every call naming another preset (ccmap_place, ccmap_default_params,
 * ccmap_validate_params, the size functions, ...) answers CCMAP_INVALID_ARGUMENT (or 0). */
int32_t ccmap_preset_available(ccmap_preset preset);

/* Storage for a map placed by ccmap_place. The sizes are upper bounds with headroom for future
 * versions (the library checks at build time that its map fits, and that each KiB figure below
 * is its constant); ccmap_storage_size() gives the exact figure (docs/integration.md, section 7,
 * lists them). The unions give every target's maximum fundamental alignment (16 on
 * x86-64 and aarch64), more than ccmap_storage_align() asks for. */
#define CCMAP_CADRE_STORAGE_SIZE 868352u          /* 848 KiB */
#define CCMAP_SINGLE_CCM_STORAGE_SIZE 3358720u    /* 3280 KiB */
#define CCMAP_SINGLE_KALMAN_STORAGE_SIZE 3653632u /* 3568 KiB */
#define CCMAP_SINGLE_OMG_STORAGE_SIZE 1523712u    /* 1488 KiB */
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

/* ---- parameters as commands ----------------------------------------------------------------- */
/* One bit per member of ccmap_params (a mask names fields: which changed, which need a re-init). */
#define CCMAP_PARAM_FINEST_CELL_WIDTH_M (1u << 0)
#define CCMAP_PARAM_WEIGHT_LIMIT (1u << 1)
#define CCMAP_PARAM_COVERAGE_TAU (1u << 2)
#define CCMAP_PARAM_MIN_WEIGHT (1u << 3)
#define CCMAP_PARAM_OBSTACLE_FRACTION (1u << 4)
#define CCMAP_PARAM_MAX_INCLINATION (1u << 5)
#define CCMAP_PARAM_KALMAN_MIN_VARIANCE (1u << 6)
#define CCMAP_PARAM_NORMAL_VARIANCE_THRESHOLD (1u << 7)
#define CCMAP_PARAM_FINEST_MAX_SIGMA_M (1u << 8)
#define CCMAP_PARAM_OUTLIER_GATE_SIGMA (1u << 9)
#define CCMAP_PARAM_CHANGE_MIN_POINTS (1u << 10)
#define CCMAP_PARAM_CHANGE_SHARE (1u << 11)
#define CCMAP_PARAM_FRAME_POINT_BUDGET (1u << 12)
#define CCMAP_PARAM_FRAME_TIME_BUDGET_US (1u << 13)
#define CCMAP_PARAM_FREE_SPACE_RAYS (1u << 14)
#define CCMAP_PARAM_FREE_SPACE_CLEAR_FRAMES (1u << 15)
#define CCMAP_PARAM_SENSOR_VIEW_AXIS (1u << 16)
#define CCMAP_PARAM_NOISE (1u << 17)
#define CCMAP_PARAM_ALL ((1u << 18) - 1u)
/* Fields a running map can never take without a re-init: the cell width binds every layer. The
 * noise model and finest_max_sigma_m need one only when they change the routing (which layer a
 * range goes to); ccmap_set_params decides that by building the new routing table. */
#define CCMAP_PARAM_REINIT_ALWAYS CCMAP_PARAM_FINEST_CELL_WIDTH_M

/* [any thread: touches no map] Exactly ccmap_init's checks of `params` for a map of `preset`,
 * nothing touched: CCMAP_OK if ccmap_init would accept them, else the status ccmap_init would
 * answer (CCMAP_INVALID_ARGUMENT, CCMAP_NON_FINITE_INPUT; the list at ccmap_init), and
 * CCMAP_INVALID_ARGUMENT for NULL params or a bad preset (or one this build left out:
 * CCMAP_CAPI_PRESETS). It takes a preset, not a map: the checks depend on the preset's shape
 * only (layer count, what is compiled in), so a ground tool or a table-validation callback can
 * run them with no map at hand, and no handle can be misused to change one. */
ccmap_status ccmap_validate_params(ccmap_preset preset, const ccmap_params* params);

/* [map reader] The map's parameters as it runs with them (after ccmap_init, ccmap_set_params,
 * or ccmap_load_snapshot, which brings the snapshot's own). Thresholds given as <= 0 (calibrate)
 * read back as given (the values in use: ccmap_health.layers[k].normal_variance_threshold).
 * CCMAP_INVALID_ARGUMENT (NULL out, bad handle), CCMAP_NOT_INITIALISED, CCMAP_CORRUPT (out
 * untouched). */
ccmap_status ccmap_get_params(const ccmap_map* map, ccmap_params* out);

/* [writer] Changes the parameters of an initialised map and keeps every cell: after CCMAP_OK the
 * map is the one ccmap_init(params) followed by the same frames and moves would have built, as
 * far as the changed fields allow (classification, coverage, thresholds, gate and change rule,
 * budgets, free space, weight limit, Kalman floor, a noise model that keeps the routing: they act
 * on the next frame or query; cells already folded keep the points they took). Held points of
 * the outlier gate are judged under the new gate at the next frame's end.
 * needs_reinit (may be NULL) receives the mask (CCMAP_PARAM_*) of the changed fields that need a
 * re-init; 0 on CCMAP_OK and on every refusal that is not about them.
 * Refused, the map bitwise unchanged (its cells, parameters, counters, seals):
 *  CCMAP_INVALID_ARGUMENT: NULL params, a bad handle, params ccmap_validate_params refuses (the
 *    status it answers is returned, CCMAP_NON_FINITE_INPUT included), or a change that needs a
 *    re-init (*needs_reinit != 0 says which fields: finest_cell_width_m; noise or
 *    finest_max_sigma_m when the routing they build differs from the map's);
 *  CCMAP_NOT_INITIALISED; CCMAP_CORRUPT (the state check failed: re-init).
 * Counts accepted changes (ccmap_health.params_changes); params_crc follows. */
ccmap_status ccmap_set_params(ccmap_map* map, const ccmap_params* params, uint32_t* needs_reinit);

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
  uint32_t max_rows;   /* row budget: 0 fills every row; else the central band of max_rows rows
                          only, every other pixel 255 (unknown) and counted (rows_skipped) */
} ccmap_costmap_spec;

typedef struct ccmap_costmap_stats {
  uint32_t free;       /* cost 0 */
  uint32_t cost;       /* 1 .. 252 */
  uint32_t inscribed;  /* 253 */
  uint32_t lethal;     /* 254 */
  uint32_t unknown;    /* 255 */
  uint32_t cells_visited;
  uint32_t rows_skipped; /* rows left unknown by the row budget */
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

/* ---- health (housekeeping telemetry) -------------------------------------------------------- */
/* One layer's window and contents. */
typedef struct ccmap_layer_health {
  float cell_width_m;
  int32_t centre_index_x;          /* window centre: global cell index of this layer */
  int32_t centre_index_y;
  float centre_x_m;                /* the same in metres (map frame): index * cell_width_m */
  float centre_y_m;
  uint32_t observed_cells;         /* cells of this layer holding points (weight > 0), intact ones only */
  float normal_variance_threshold; /* in use (calibrated at init when the parameter was <= 0), m^2 */
} ccmap_layer_health;

typedef struct ccmap_health {
  int32_t initialised;        /* 1 after a successful ccmap_init or ccmap_load_snapshot, else 0 */
  int32_t state;              /* ccmap_status of the state check run by this call: CCMAP_OK,
                                 CCMAP_NOT_INITIALISED or CCMAP_CORRUPT (then re-init or load) */
  int32_t preset;             /* ccmap_preset */
  int32_t layer_count;
  /* ---- counters since init, load or ccmap_reset_counters (saturating at 2^32 - 1) ---- */
  uint32_t frames_accepted;   /* frame updates folded in */
  uint32_t frames_refused;    /* frame updates refused as a whole */
  uint32_t moves_refused;
  uint32_t points_received;   /* over the accepted frames */
  uint32_t points_used;
  uint32_t points_skipped_budget;
  uint32_t corrupted_cells;   /* upsets: cells reset by the scrub or a read (ccmap_frame_counters) */
  uint32_t corrupted_slots;   /* upsets: held-point slots dropped */
  uint32_t params_changes;    /* ccmap_set_params accepted */
  uint32_t products_published; /* ccmap_publish accepted */
  /* ---- the last accepted frame ---- */
  uint64_t last_frame_ns;     /* its duration (platform monotonic clock), 0 before the first */
  uint32_t last_frame_points; /* its points received */
  uint32_t last_frame_used;   /* of them folded in */
  /* ---- identity of what the map runs with ---- */
  uint32_t params_crc;        /* CRC-32 (IEEE 802.3) of the ccmap_params bytes ccmap_get_params
                                 writes: the ground compares it with the table it sent */
  uint32_t map_sequence;      /* frame updates since init or load (wraps; never reset by
                                 ccmap_reset_counters): the product's frame sequence */
  uint32_t fault_count;       /* contract violations reported to the fault hook, process-wide */
  ccmap_layer_health layers[CCMAP_MAX_LAYERS]; /* [0, layer_count) written, the rest zero */
} ccmap_health;

/* [map reader] Fills *out. Answers CCMAP_OK whenever out was written, also for an uninitialised
 * or damaged map (out->state says which; counters and windows of a damaged map are what its
 * memory holds, to be read as evidence, not trusted); the state check is run now, whatever
 * the last call found. Cost: the state check plus one pass over every cell (observed_cells).
 * CCMAP_INVALID_ARGUMENT: NULL out, a bad handle (out untouched); CCMAP_CORRUPT: the handle's
 * storage header is damaged (out untouched: nothing in it can be trusted to pick a preset). */
ccmap_status ccmap_get_health(const ccmap_map* map, ccmap_health* out);

/* [writer] Zeroes the counters ccmap_health counts since a reset (frames_accepted ..
 * products_published) and those of ccmap_get_counters; changes no cell, no parameter, not
 * map_sequence (map exchange numbers its deltas by it). CCMAP_INVALID_ARGUMENT (bad handle),
 * CCMAP_NOT_INITIALISED, CCMAP_CORRUPT. */
ccmap_status ccmap_reset_counters(ccmap_map* map);

/* [set-up] The fault hook: every contract violation inside the library (an assert that reports
 * and returns a safe value; include/ccmap/core/assert.hpp) calls hook(context, file, line,
 * expression) on the thread that found it; the hook must return (raise an event, count, log).
 * NULL restores the platform's default (ccmap::platform::fault). Process-wide, for every map.
 * Always CCMAP_OK. */
typedef void (*ccmap_fault_hook)(void* context, const char* file, int line, const char* expression);
ccmap_status ccmap_set_fault_hook(ccmap_fault_hook hook, void* context);

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

/* ---- readers beside the writer: the map product ---------------------------------------------- */
/* A product is a compact, self-contained picture of one layer's window for a planner in another
 * thread or a ground station: little-endian bytes, versioned, CRC-checked (byte format:
 * include/ccmap/product/product_format.hpp; every field: docs/icd.md).
 *   header (CCMAP_PRODUCT_HEADER_SIZE bytes): magic "CCMP", version, sizes, product sequence,
 *     map sequence (frames folded in), params CRC, preset, layer, answer mode, side_x, side_y,
 *     cell width, global index and map-frame corner of cell (0, 0), the layer's window centre,
 *     the caller's pose (echoed), a caller tag;
 *   side_x * side_y cells (CCMAP_PRODUCT_CELL_SIZE bytes each, x fastest, row 0 at the lowest y):
 *     hazard class, costmap_2d cost, query status, answering layer, height (m), inclination (dz/dxy);
 *   CRC-32 (IEEE 802.3) of every byte before it.
 * Each cell holds what ccmap_query (answer CCMAP_PRODUCT_STACK) or ccmap_query_layer (answer
 * CCMAP_PRODUCT_LAYER) answers at the cell's centre, and the cost ccmap_fill_costmap gives that
 * cell's square (no inflation).
 *
 * Double buffering: two slots and a private staging area in caller-owned memory
 * (ccmap_product_buffers). The writer composes the product in the staging area, then copies it
 * into the slot readers are not pointed at, inside a per-slot sequence lock (odd while being
 * written), and only then points readers at it (release). A reader copies the slot it is pointed
 * at and accepts the copy only if the slot's sequence was even and unchanged across the copy
 * (acquire) and the CRC, size and product sequence agree; else it tries again, at most
 * CCMAP_PRODUCT_READ_TRIES times (CCMAP_BUSY). The writer never waits for a reader. Every access
 * to the slots and sequence words is a 32-bit atomic (the product's words stored with release and
 * loaded with acquire; include/ccmap/product/product_buffers.hpp gives the argument), so the
 * exchange is free of data races in the C11/C++11 memory model, also for 32-bit targets. A reader on the ground decodes the bytes alone
 * (ccmap_product_decode, the C++ header-only decoder, Python ccmap.decode_product). */
#define CCMAP_PRODUCT_HEADER_SIZE 88u
#define CCMAP_PRODUCT_CELL_SIZE 12u
#define CCMAP_PRODUCT_CRC_SIZE 4u
#define CCMAP_PRODUCT_VERSION 1u
#define CCMAP_PRODUCT_MAGIC 0x504D4343u /* bytes 'C' 'C' 'M' 'P' */
#define CCMAP_PRODUCT_MAX_SIDE 256u
#define CCMAP_PRODUCT_READ_TRIES 8u
/* Bytes of a product of side_x * side_y cells. */
#define CCMAP_PRODUCT_SIZE(side_x, side_y) \
  (CCMAP_PRODUCT_HEADER_SIZE + CCMAP_PRODUCT_CELL_SIZE * (side_x) * (side_y) + CCMAP_PRODUCT_CRC_SIZE)
/* Caller storage for the double buffer of products of up to `cells` cells: two slots + staging. */
#define CCMAP_PRODUCT_BUFFERS_STORAGE_SIZE(cells) (3u * CCMAP_PRODUCT_SIZE(cells, 1u))

typedef enum ccmap_product_answer {
  CCMAP_PRODUCT_STACK = 0, /* each cell: the stack's answer at its centre (finest layer that knows) */
  CCMAP_PRODUCT_LAYER = 1  /* each cell: the chosen layer's own answer */
} ccmap_product_answer;

typedef struct ccmap_product_spec {
  int32_t layer;    /* whose window and cells the product covers, [0, ccmap_layer_count) */
  int32_t answer;   /* ccmap_product_answer */
  float pose_x;     /* the robot pose the product belongs to (map frame, m, rad), echoed into the */
  float pose_y;     /* header as given (finite; the caller's estimate at the frame it follows) */
  float pose_z;
  float pose_yaw;
  uint32_t tag;     /* echoed (e.g. the caller's time tag of the frame) */
} ccmap_product_spec;

/* The double buffer. Set it up with ccmap_product_buffers_init; then its members belong to the
 * library (written by ccmap_publish, read by ccmap_product_read: never touch them directly). */
typedef struct ccmap_product_buffers {
  uint32_t magic;            /* set by ccmap_product_buffers_init */
  uint32_t slot_bytes;       /* capacity of each slot (bytes, a multiple of 4) */
  uint32_t* storage;         /* slot 0, slot 1, staging: 3 * slot_bytes bytes, 4-byte aligned */
  uint32_t published;        /* atomic: products published; the latest is in slot (published & 1) */
  uint32_t slot_sequence[2]; /* atomic: per-slot sequence lock, odd while the writer writes it */
} ccmap_product_buffers;

/* [set-up] Binds storage[0 .. storage_size) (4-byte aligned, at least 3 slots) as the double
 * buffer of products up to floor(storage_size / 3) bytes each; nothing published yet. Call it
 * before the writer and readers start. CCMAP_INVALID_ARGUMENT: NULL, misaligned storage, a
 * storage_size above 3 * 2^31 or not holding a product of one cell. */
ccmap_status ccmap_product_buffers_init(ccmap_product_buffers* buffers, void* storage, size_t storage_size);

/* [map reader; the one writer of `buffers`] Composes the product of spec->layer's window and
 * publishes it (the readers see it from their next read). Cost: one query per cell and one
 * costmap of the window (docs/performance.md). Refused, nothing published (the readers keep the
 * previous product): CCMAP_INVALID_ARGUMENT (NULL, bad handle, buffers not set up, a bad layer or
 * answer, a non-finite pose), CCMAP_BUFFER_TOO_SMALL (the layer's product exceeds a slot),
 * CCMAP_NOT_INITIALISED, CCMAP_CORRUPT. One thread publishes into a given buffers at a time. */
ccmap_status ccmap_publish(const ccmap_map* map, const ccmap_product_spec* spec, ccmap_product_buffers* buffers);

/* [any thread, no map handle] Copies the latest whole product into out[0 .. *written) and
 * checks it (sequence lock, size, CRC). CCMAP_OK: out holds a product that was whole at one
 * instant; CCMAP_NOT_INITIALISED: nothing published yet; CCMAP_BUSY: the writer replaced the slot
 * during each of CCMAP_PRODUCT_READ_TRIES tries (only when it publishes faster than a copy
 * takes); CCMAP_CORRUPT: a slot that no writer touched during the copy fails its CRC or header
 * (the shared memory was damaged: an upset, a stray write; the next publish replaces it);
 * CCMAP_BUFFER_TOO_SMALL: capacity below the product's size; CCMAP_INVALID_ARGUMENT: NULL, buffers
 * not set up. *written is 0 on every answer but CCMAP_OK. Never writes to `buffers`. */
ccmap_status ccmap_product_read(const ccmap_product_buffers* buffers, void* out, size_t capacity, size_t* written);

/* A decoded product header (host order). */
typedef struct ccmap_product_header {
  uint32_t version;
  uint32_t total_bytes;
  uint32_t product_sequence; /* 1 for the first product of these buffers, +1 per publish */
  uint32_t map_sequence;     /* the map's frame updates since init or load (ccmap_health.map_sequence) */
  uint32_t params_crc;       /* ccmap_health.params_crc at publish */
  int32_t preset;
  int32_t layer;
  int32_t answer;            /* ccmap_product_answer */
  uint32_t side_x;
  uint32_t side_y;
  float cell_width_m;
  int32_t min_index_x;       /* global index (of `layer`) of cell (0, 0) */
  int32_t min_index_y;
  float min_corner_x_m;      /* map-frame corner (lowest x, lowest y) of cell (0, 0) */
  float min_corner_y_m;
  float centre_x_m;          /* the layer's window centre (ccmap_layer_health) */
  float centre_y_m;
  float pose_x;              /* ccmap_product_spec, echoed */
  float pose_y;
  float pose_z;
  float pose_yaw;
  uint32_t tag;
} ccmap_product_header;

/* One decoded cell. */
typedef struct ccmap_product_cell {
  int32_t cell_class;  /* ccmap_cell_class */
  int32_t cost;        /* costmap_2d value, CCMAP_COST_* */
  int32_t status;      /* ccmap_status of the query at the cell centre (CCMAP_OK, CCMAP_UNKNOWN, ...) */
  int32_t layer;       /* answering layer, -1 if none */
  float height_m;      /* 0 unless status is CCMAP_OK */
  float inclination;   /* dz/dxy; 0 unless status is CCMAP_OK */
} ccmap_product_cell;

/* [any thread, no map] Checks a product's bytes (size, magic, version, CRC) and decodes its
 * header; cells may be NULL (header only), else cells[0 .. side_x * side_y) are decoded if
 * cell_capacity holds them. CCMAP_CORRUPT (bad magic, sizes or CRC), CCMAP_VERSION_MISMATCH
 * (another version), CCMAP_BUFFER_TOO_SMALL (cell_capacity), CCMAP_INVALID_ARGUMENT (NULL data
 * or header). */
ccmap_status ccmap_product_decode(const void* data, size_t size, ccmap_product_header* header,
                                  ccmap_product_cell* cells, size_t cell_capacity);

/* ---- map exchange between rovers (include/ccmap/persistence/exchange.hpp: rules and byte format) ---- */
/* An exchange holds one copy of its map's cells (what it last sent) and a table of 8 peers; it
 * lives in caller storage like the map. Sizes: upper bounds with headroom, exact figures from
 * ccmap_exchange_storage_size(). */
#define CCMAP_CADRE_EXCHANGE_STORAGE_SIZE 475136u          /* 464 KiB */
#define CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE 2703360u    /* 2640 KiB */
#define CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE 868352u  /* 848 KiB */
#define CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE 868352u     /* 848 KiB */
CCMAP_DEFINE_STORAGE_(ccmap_cadre_exchange_storage, CCMAP_CADRE_EXCHANGE_STORAGE_SIZE);
CCMAP_DEFINE_STORAGE_(ccmap_single_ccm_exchange_storage, CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE);
CCMAP_DEFINE_STORAGE_(ccmap_single_kalman_exchange_storage, CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE);
CCMAP_DEFINE_STORAGE_(ccmap_single_omg_exchange_storage, CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE);

/* Largest delta of a preset (every cell) and the smallest (no cell); 0 for a bad preset. */
#define CCMAP_CADRE_DELTA_MAX_SIZE 616600u
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
  uint32_t drops_written;    /* free-space entries (delta format 3): drop-offs */
  uint32_t clears_written;   /* free-space entries: cells this map's lines of sight emptied */
  uint32_t drops_pending;    /* drop-offs not written for want of room: sent later */
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
  /* The delta's free-space section (exchange.hpp gives the receiver's rule for clears): */
  uint32_t drops_merged;     /* drop-offs folded into this map's records */
  uint32_t cells_cleared;    /* cells a team mate's clear emptied here */
  uint32_t clears_deferred;  /* clears of cells holding this map's own points: evidence raised only */
  uint32_t entries_outside;  /* outside this map's windows: dropped */
  uint32_t entries_refused;  /* failed their check or a field check, or missing (truncated) */
  ccmap_status free_space_status; /* CCMAP_OK, or CCMAP_CORRUPT for a damaged section (good entries merged) */
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
  uint64_t drops_exported;
  uint64_t clears_exported;
  uint64_t drops_merged;
  uint64_t cells_cleared;
  uint64_t clears_deferred;
  uint64_t entries_refused;
  uint32_t sections_damaged; /* merged deltas whose free-space section was damaged */
} ccmap_exchange_counters;
/* CCMAP_INVALID_ARGUMENT: NULL out, a bad handle. An exchange never bound answers zeros. */
ccmap_status ccmap_exchange_get_counters(const ccmap_exchange* exchange, ccmap_exchange_counters* out);

/* Name of the linked platform implementation ("posix", "baremetal"). */
const char* ccmap_platform_name(void);

#ifdef __cplusplus
}  /* extern "C" */
#endif

#endif /* CCMAP_CCMAP_H */
