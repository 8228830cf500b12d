// C API (include/ccmap/ccmap.h) over Stack<Config> placed in caller-provided storage.
//
// Storage layout: a HandleHeader at the start of the caller's storage (the ccmap_map* handle
// points at it), the Stack<Config> at kStackOffset. Every entry point checks the header's magic
// and preset, then dispatches to the preset's Stack through a generic lambda.
#include "ccmap/ccmap.h"

#include <cstddef>
#include <cstring>
#include <new>
#include <type_traits>

#include "ccmap/map/config.hpp"
#include "ccmap/planner/costmap.hpp"
#include "ccmap/planner/footprint.hpp"
#include "ccmap/planner/path_query.hpp"
#include "ccmap/persistence/exchange.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/registration/alignment.hpp"
#include "ccmap/platform/platform.hpp"

namespace ccmap {
namespace {

// ---- status, class and struct compatibility ----
#define CCMAP_SAME_STATUS(c, cpp) \
  static_assert(static_cast<int>(c) == static_cast<int>(Status::cpp), "ccmap_status " #c " != Status::" #cpp)
CCMAP_SAME_STATUS(CCMAP_OK, kOk);
CCMAP_SAME_STATUS(CCMAP_NON_FINITE_INPUT, kNonFiniteInput);
CCMAP_SAME_STATUS(CCMAP_OUT_OF_RANGE, kOutOfRange);
CCMAP_SAME_STATUS(CCMAP_BAD_WEIGHT, kBadWeight);
CCMAP_SAME_STATUS(CCMAP_OUTSIDE_MAP, kOutsideMap);
CCMAP_SAME_STATUS(CCMAP_UNKNOWN, kUnknown);
CCMAP_SAME_STATUS(CCMAP_INVALID_ARGUMENT, kInvalidArgument);
CCMAP_SAME_STATUS(CCMAP_BUFFER_TOO_SMALL, kBufferTooSmall);
CCMAP_SAME_STATUS(CCMAP_NOT_INITIALISED, kNotInitialised);
CCMAP_SAME_STATUS(CCMAP_CORRUPT, kCorrupt);
CCMAP_SAME_STATUS(CCMAP_VERSION_MISMATCH, kVersionMismatch);
CCMAP_SAME_STATUS(CCMAP_DUPLICATE, kDuplicate);
CCMAP_SAME_STATUS(CCMAP_MISALIGNED, kMisaligned);
CCMAP_SAME_STATUS(CCMAP_INSUFFICIENT_OVERLAP, kInsufficientOverlap);
CCMAP_SAME_STATUS(CCMAP_DEGENERATE_INPUT, kDegenerateInput);
CCMAP_SAME_STATUS(CCMAP_NOT_CONVERGED, kNotConverged);
#undef CCMAP_SAME_STATUS
static_assert(static_cast<int>(CCMAP_CLASS_UNKNOWN) == static_cast<int>(CellClass::kUnknown), "class");
static_assert(static_cast<int>(CCMAP_CLASS_TRAVERSABLE) == static_cast<int>(CellClass::kTraversable), "class");
static_assert(static_cast<int>(CCMAP_CLASS_OBSTACLE) == static_cast<int>(CellClass::kObstacle), "class");
static_assert(static_cast<int>(CCMAP_CLASS_STEEP) == static_cast<int>(CellClass::kSteep), "class");
static_assert(static_cast<int>(CCMAP_CLASS_DROP) == static_cast<int>(CellClass::kDropOff), "class");
static_assert(CCMAP_MAX_LAYERS == kMaxLayers, "CCMAP_MAX_LAYERS != kMaxLayers");
static_assert(sizeof(ccmap_frame_counters) == sizeof(FrameCounters), "ccmap_frame_counters != FrameCounters");

// Points: the caller's float[3 n] is read as PointXYZ[n]. PointXYZ is documented (types.hpp) to
// stay three packed floats for exactly this use.
static_assert(std::is_standard_layout<PointXYZ>::value && sizeof(PointXYZ) == 3U * sizeof(float) &&
                  alignof(PointXYZ) == alignof(float) && offsetof(PointXYZ, x) == 0U &&
                  offsetof(PointXYZ, y) == sizeof(float) && offsetof(PointXYZ, z) == 2U * sizeof(float),
              "PointXYZ must be three packed floats");
// Export: CellRecords are written into the caller's ccmap_cell_record array and converted in
// place, record by record (same size, so record i occupies the same bytes in both forms).
static_assert(sizeof(ccmap_cell_record) == sizeof(CellRecord) && alignof(ccmap_cell_record) >= alignof(CellRecord),
              "ccmap_cell_record and CellRecord must have the same size");

// Planner queries: the C limits and costs are the C++ ones; path points are read as PathPoint.
static_assert(CCMAP_MAX_FOOTPRINT_CELLS == kMaxFootprintCells, "CCMAP_MAX_FOOTPRINT_CELLS");
static_assert(!(CCMAP_DEFAULT_MAX_UNKNOWN_SHARE < kDefaultMaxUnknownShare) &&
                  !(CCMAP_DEFAULT_MAX_UNKNOWN_SHARE > kDefaultMaxUnknownShare),
              "CCMAP_DEFAULT_MAX_UNKNOWN_SHARE");
static_assert(CCMAP_MAX_PATH_SAMPLES == kMaxPathSamples && CCMAP_MAX_PATH_VERTICES == kMaxPathVertices, "path limits");
static_assert(CCMAP_MAX_COSTMAP_SIDE == kMaxCostmapSide && CCMAP_MAX_INFLATION_PIXELS == kMaxInflationPixels,
              "costmap limits");
static_assert(CCMAP_COST_FREE == kCostFree && CCMAP_COST_MAX_TRAVERSABLE == kCostMaxTraversable &&
                  CCMAP_COST_INSCRIBED == kCostInscribed && CCMAP_COST_LETHAL == kCostLethal &&
                  CCMAP_COST_UNKNOWN == kCostUnknown,
              "costmap values");
static_assert(std::is_standard_layout<PathPoint>::value && sizeof(PathPoint) == 2U * sizeof(float) &&
                  alignof(PathPoint) == alignof(float) && offsetof(PathPoint, y) == sizeof(float),
              "PathPoint must be two packed floats");

// ---- storage ----
constexpr std::uint32_t kHandleMagic = 0x43434D48U;  // "CCMH"

/// The start of the caller's storage. `check` seals magic and preset (header_check): a header an
/// upset changed is refused (CCMAP_CORRUPT), never trusted to pick a preset.
struct HandleHeader {
  std::uint32_t magic;
  std::uint32_t preset;
  std::uint32_t check;
};

/// Check word of a header: any single changed bit of magic, preset or check makes it disagree.
constexpr std::uint32_t header_check(std::uint32_t magic, std::uint32_t preset) noexcept {
  return ~(magic ^ (preset * 0x9E3779B1U));
}

/// What a handle's header says.
enum class HeaderState : std::uint8_t { kValid, kForeign, kDamaged };

/// kValid: magic, a valid preset and the check agree. kDamaged: the magic is `magic` or at most
/// two bits from it, and something disagrees (an upset). kForeign: anything else (not a handle
/// of this kind; `other` is the other kind's magic, one bit away: a map handed over as an
/// exchange is foreign, not damaged).
HeaderState classify_header(const HandleHeader& h, std::uint32_t magic, std::uint32_t other, bool preset_valid) noexcept {
  if (h.magic == magic && preset_valid && h.check == header_check(h.magic, h.preset)) {
    return HeaderState::kValid;
  }
  if (h.magic == other) {
    return HeaderState::kForeign;
  }
  std::uint32_t diff = h.magic ^ magic;
  int bits = 0;
  for (; diff != 0U && bits <= 2; diff &= diff - 1U) {
    ++bits;
  }
  return bits <= 2 ? HeaderState::kDamaged : HeaderState::kForeign;
}
constexpr std::size_t kStackOffset = 16U;
static_assert(sizeof(HandleHeader) <= kStackOffset, "header must fit before the stack");

template <typename Config>
struct Preset {
  using StackType = Stack<Config>;
  static_assert(kStackOffset % alignof(StackType) == 0U, "stack offset must respect the stack's alignment");
  static_assert(alignof(StackType) <= CCMAP_STORAGE_ALIGN, "CCMAP_STORAGE_ALIGN too small");
  static constexpr std::size_t kStorageSize = kStackOffset + sizeof(StackType);
  static constexpr std::size_t kStorageAlign = alignof(StackType) > alignof(HandleHeader) ? alignof(StackType)
                                                                                          : alignof(HandleHeader);
};

// F' style: the storage the header promises must hold the implementation.
static_assert(Preset<CadreConfig>::kStorageSize <= CCMAP_CADRE_STORAGE_SIZE, "raise CCMAP_CADRE_STORAGE_SIZE");
static_assert(Preset<SingleCcmConfig>::kStorageSize <= CCMAP_SINGLE_CCM_STORAGE_SIZE,
              "raise CCMAP_SINGLE_CCM_STORAGE_SIZE");
static_assert(Preset<SingleKalmanConfig>::kStorageSize <= CCMAP_SINGLE_KALMAN_STORAGE_SIZE,
              "raise CCMAP_SINGLE_KALMAN_STORAGE_SIZE");
static_assert(Preset<SingleOmgConfig>::kStorageSize <= CCMAP_SINGLE_OMG_STORAGE_SIZE,
              "raise CCMAP_SINGLE_OMG_STORAGE_SIZE");
static_assert(snapshot_size<CadreConfig>() == CCMAP_CADRE_SNAPSHOT_SIZE, "CCMAP_CADRE_SNAPSHOT_SIZE");
static_assert(snapshot_size<SingleCcmConfig>() == CCMAP_SINGLE_CCM_SNAPSHOT_SIZE, "CCMAP_SINGLE_CCM_SNAPSHOT_SIZE");
static_assert(snapshot_size<SingleKalmanConfig>() == CCMAP_SINGLE_KALMAN_SNAPSHOT_SIZE,
              "CCMAP_SINGLE_KALMAN_SNAPSHOT_SIZE");
static_assert(snapshot_size<SingleOmgConfig>() == CCMAP_SINGLE_OMG_SNAPSHOT_SIZE, "CCMAP_SINGLE_OMG_SNAPSHOT_SIZE");

// Exchanges: the same layout (header, then the MapExchange at kStackOffset), another magic.
// Seven bits from kHandleMagic: no single or double upset turns one kind of header into the other.
constexpr std::uint32_t kExchangeMagic = 0x58434D43U;  // "CMCX"

template <typename Config>
struct ExchangePreset {
  using ExchangeType = MapExchange<Config>;
  static_assert(kStackOffset % alignof(ExchangeType) == 0U, "exchange offset must respect its alignment");
  static_assert(alignof(ExchangeType) <= CCMAP_STORAGE_ALIGN, "CCMAP_STORAGE_ALIGN too small");
  static constexpr std::size_t kStorageSize = kStackOffset + sizeof(ExchangeType);
  static constexpr std::size_t kStorageAlign = alignof(ExchangeType) > alignof(HandleHeader) ? alignof(ExchangeType)
                                                                                             : alignof(HandleHeader);
};
static_assert(ExchangePreset<CadreConfig>::kStorageSize <= CCMAP_CADRE_EXCHANGE_STORAGE_SIZE,
              "raise CCMAP_CADRE_EXCHANGE_STORAGE_SIZE");
static_assert(ExchangePreset<SingleCcmConfig>::kStorageSize <= CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE,
              "raise CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE");
static_assert(ExchangePreset<SingleKalmanConfig>::kStorageSize <= CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE,
              "raise CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE");
static_assert(ExchangePreset<SingleOmgConfig>::kStorageSize <= CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE,
              "raise CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE");
static_assert(MapExchange<CadreConfig>::max_delta_size() == CCMAP_CADRE_DELTA_MAX_SIZE, "CCMAP_CADRE_DELTA_MAX_SIZE");
// The smallest CADRE delta, as persistence/exchange.hpp documents it (header, five layer headers, CRC).
static_assert(MapExchange<CadreConfig>::min_delta_size() == 152U, "the empty CADRE delta is documented as 152 bytes");
// The KiB figures beside the storage constants in ccmap.h.
static_assert(CCMAP_CADRE_STORAGE_SIZE == 816U * 1024U && CCMAP_SINGLE_CCM_STORAGE_SIZE == 3136U * 1024U &&
                  CCMAP_SINGLE_KALMAN_STORAGE_SIZE == 3424U * 1024U && CCMAP_SINGLE_OMG_STORAGE_SIZE == 1344U * 1024U,
              "ccmap.h: a map storage constant and its KiB comment disagree");
static_assert(CCMAP_CADRE_EXCHANGE_STORAGE_SIZE == 464U * 1024U &&
                  CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE == 2624U * 1024U &&
                  CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE == 784U * 1024U &&
                  CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE == 784U * 1024U,
              "ccmap.h: an exchange storage constant and its KiB comment disagree");

ccmap_status to_c(Status status) noexcept { return static_cast<ccmap_status>(status); }

bool valid_preset(std::int64_t preset) noexcept {
  return preset >= static_cast<std::int64_t>(CCMAP_PRESET_CADRE) &&
         preset <= static_cast<std::int64_t>(CCMAP_PRESET_SINGLE_OMG);
}

std::size_t storage_size(ccmap_preset preset) noexcept {
  switch (preset) {
    case CCMAP_PRESET_CADRE: return Preset<CadreConfig>::kStorageSize;
    case CCMAP_PRESET_SINGLE_CCM: return Preset<SingleCcmConfig>::kStorageSize;
    case CCMAP_PRESET_SINGLE_KALMAN: return Preset<SingleKalmanConfig>::kStorageSize;
    case CCMAP_PRESET_SINGLE_OMG: return Preset<SingleOmgConfig>::kStorageSize;
    default: break;
  }
  return 0U;
}

std::size_t storage_align(ccmap_preset preset) noexcept {
  switch (preset) {
    case CCMAP_PRESET_CADRE: return Preset<CadreConfig>::kStorageAlign;
    case CCMAP_PRESET_SINGLE_CCM: return Preset<SingleCcmConfig>::kStorageAlign;
    case CCMAP_PRESET_SINGLE_KALMAN: return Preset<SingleKalmanConfig>::kStorageAlign;
    case CCMAP_PRESET_SINGLE_OMG: return Preset<SingleOmgConfig>::kStorageAlign;
    default: break;
  }
  return 0U;
}

float default_width(ccmap_preset preset) noexcept {
  switch (preset) {
    case CCMAP_PRESET_CADRE: return CadreConfig::kDefaultFinestCellWidthM;
    case CCMAP_PRESET_SINGLE_CCM: return SingleCcmConfig::kDefaultFinestCellWidthM;
    case CCMAP_PRESET_SINGLE_KALMAN: return SingleKalmanConfig::kDefaultFinestCellWidthM;
    case CCMAP_PRESET_SINGLE_OMG: return SingleOmgConfig::kDefaultFinestCellWidthM;
    default: break;
  }
  return 0.0F;
}

const HandleHeader* header_of(const ccmap_map* map, bool* damaged = nullptr) noexcept {
  if (map == nullptr) {
    return nullptr;
  }
  const auto* header = std::launder(static_cast<const HandleHeader*>(static_cast<const void*>(map)));
  const HeaderState state =
      classify_header(*header, kHandleMagic, kExchangeMagic, valid_preset(static_cast<std::int64_t>(header->preset)));
  if (damaged != nullptr) {
    *damaged = state == HeaderState::kDamaged;
  }
  return state == HeaderState::kValid ? header : nullptr;
}

template <typename Config>
Stack<Config>& stack_of(const ccmap_map* map) noexcept {
  const auto* bytes = static_cast<const unsigned char*>(static_cast<const void*>(map));
  // The handle is the caller's (non-const) storage; the const in the C signatures is the C
  // API's promise, kept by only calling const Stack members from const entry points.
  auto* stack_bytes = const_cast<unsigned char*>(bytes + kStackOffset);
  return *std::launder(static_cast<Stack<Config>*>(static_cast<void*>(stack_bytes)));
}

/// Result of an entry point for a handle whose header an upset damaged: CCMAP_CORRUPT for a
/// status, else the bad-handle value.
template <typename Result>
Result damaged_result(Result bad) noexcept {
  if constexpr (std::is_same_v<Result, ccmap_status>) {
    return CCMAP_CORRUPT;
  } else {
    return bad;
  }
}

/// Calls fn(Stack<Config>&) for the map's preset; `bad` for a NULL or foreign handle, CCMAP_CORRUPT
/// (or `bad`, for a number) for a damaged one.
template <typename Result, typename Fn>
Result dispatch(const ccmap_map* map, Result bad, Fn&& fn) noexcept {
  bool damaged = false;
  const HandleHeader* header = header_of(map, &damaged);
  if (header == nullptr) {
    return damaged ? damaged_result(bad) : bad;
  }
  switch (static_cast<ccmap_preset>(header->preset)) {
    case CCMAP_PRESET_CADRE: return fn(stack_of<CadreConfig>(map));
    case CCMAP_PRESET_SINGLE_CCM: return fn(stack_of<SingleCcmConfig>(map));
    case CCMAP_PRESET_SINGLE_KALMAN: return fn(stack_of<SingleKalmanConfig>(map));
    case CCMAP_PRESET_SINGLE_OMG: return fn(stack_of<SingleOmgConfig>(map));
    default: break;
  }
  return bad;
}

/// The registration parameters of the C call (NULL: the defaults).
RegistrationParams registration_params_from_c(const ccmap_registration_params* p) noexcept {
  if (p == nullptr) {
    return default_registration_params();
  }
  RegistrationParams out{};
  out.max_points = p->max_points;
  out.max_iterations = p->max_iterations;
  out.min_matches = p->min_matches;
  out.max_translation_m = p->max_translation_m;
  out.max_yaw_rad = p->max_yaw_rad;
  out.max_sigma_m = p->max_sigma_m;
  out.robust_sigmas = p->robust_sigmas;
  out.model_variance_m2 = p->model_variance_m2;
  out.convergence_m = p->convergence_m;
  return out;
}

void registration_to_c(const RegistrationResult& r, float centre_x, float centre_y, std::uint32_t cells,
                       ccmap_registration_result* out) noexcept {
  out->status = static_cast<std::int32_t>(r.status);
  const float correction[4] = {r.dx, r.dy, r.dz, r.dyaw};
  const float sigma[4] = {r.sigma_dx, r.sigma_dy, r.sigma_dz, r.sigma_dyaw};
  for (int k = 0; k < 4; ++k) {
    out->correction[k] = correction[k];
    out->sigma[k] = sigma[k];
    out->observable[k] = r.observable[k] ? 1U : 0U;
  }
  out->rank = r.rank;
  out->iterations = r.iterations;
  out->points_sampled = r.points_sampled;
  out->points_rejected = r.points_rejected;
  out->points_matched = r.points_matched;
  out->lever_m = r.lever_m;
  out->residual_sigma = r.residual_sigma;
  out->centre[0] = centre_x;
  out->centre[1] = centre_y;
  out->cells = cells;
}

const HandleHeader* exchange_header_of(const ccmap_exchange* exchange, bool* damaged = nullptr) noexcept {
  if (exchange == nullptr) {
    return nullptr;
  }
  const auto* header = std::launder(static_cast<const HandleHeader*>(static_cast<const void*>(exchange)));
  const HeaderState state =
      classify_header(*header, kExchangeMagic, kHandleMagic, valid_preset(static_cast<std::int64_t>(header->preset)));
  if (damaged != nullptr) {
    *damaged = state == HeaderState::kDamaged;
  }
  return state == HeaderState::kValid ? header : nullptr;
}

template <typename Config>
MapExchange<Config>& exchange_of(const ccmap_exchange* exchange) noexcept {
  const auto* bytes = static_cast<const unsigned char*>(static_cast<const void*>(exchange));
  auto* exchange_bytes = const_cast<unsigned char*>(bytes + kStackOffset);  // the caller's storage, as stack_of
  return *std::launder(static_cast<MapExchange<Config>*>(static_cast<void*>(exchange_bytes)));
}

/// Calls fn(MapExchange<Config>&) for the exchange's preset; `bad` for a NULL or foreign handle.
template <typename Result, typename Fn>
Result dispatch_exchange(const ccmap_exchange* exchange, Result bad, Fn&& fn) noexcept {
  bool damaged = false;
  const HandleHeader* header = exchange_header_of(exchange, &damaged);
  if (header == nullptr) {
    return damaged ? damaged_result(bad) : bad;
  }
  switch (static_cast<ccmap_preset>(header->preset)) {
    case CCMAP_PRESET_CADRE: return fn(exchange_of<CadreConfig>(exchange));
    case CCMAP_PRESET_SINGLE_CCM: return fn(exchange_of<SingleCcmConfig>(exchange));
    case CCMAP_PRESET_SINGLE_KALMAN: return fn(exchange_of<SingleKalmanConfig>(exchange));
    case CCMAP_PRESET_SINGLE_OMG: return fn(exchange_of<SingleOmgConfig>(exchange));
    default: break;
  }
  return bad;
}

/// Calls fn(MapExchange<C>&, Stack<C>&) when the exchange and the map are of the same preset.
template <typename Fn>
ccmap_status dispatch_pair(ccmap_exchange* exchange, ccmap_map* map, Fn&& fn) noexcept {
  bool exchange_damaged = false;
  bool map_damaged = false;
  const HandleHeader* e = exchange_header_of(exchange, &exchange_damaged);
  const HandleHeader* m = header_of(map, &map_damaged);
  if (exchange_damaged || map_damaged) {
    return CCMAP_CORRUPT;
  }
  if (e == nullptr || m == nullptr || e->preset != m->preset) {
    return CCMAP_INVALID_ARGUMENT;
  }
  switch (static_cast<ccmap_preset>(e->preset)) {
    case CCMAP_PRESET_CADRE: return fn(exchange_of<CadreConfig>(exchange), stack_of<CadreConfig>(map));
    case CCMAP_PRESET_SINGLE_CCM: return fn(exchange_of<SingleCcmConfig>(exchange), stack_of<SingleCcmConfig>(map));
    case CCMAP_PRESET_SINGLE_KALMAN:
      return fn(exchange_of<SingleKalmanConfig>(exchange), stack_of<SingleKalmanConfig>(map));
    case CCMAP_PRESET_SINGLE_OMG: return fn(exchange_of<SingleOmgConfig>(exchange), stack_of<SingleOmgConfig>(map));
    default: break;
  }
  return CCMAP_INVALID_ARGUMENT;
}

void merge_report_to_c(const MergeReport& r, ccmap_merge_report* out) noexcept {
  if (out != nullptr) {
    *out = ccmap_merge_report{r.sender_id, r.sequence, r.cells_merged, r.cells_outside, r.deltas_missed};
  }
}

template <typename Config>
constexpr std::size_t snapshot_bytes(const Stack<Config>&) noexcept {
  return snapshot_size<Config>();
}

template <typename Config>
void place(void* storage) noexcept {
  auto* bytes = static_cast<unsigned char*>(storage);
  new (bytes + kStackOffset) Stack<Config>();
}

// ---- parameters ----
void params_to_c(const StackParams& p, ccmap_params* out) noexcept {
  *out = ccmap_params{};
  out->finest_cell_width_m = p.finest_cell_width_m;
  out->weight_limit = p.weight_limit;
  out->coverage_tau = p.coverage_tau;
  out->min_weight = p.min_weight;
  out->obstacle_fraction = p.obstacle_fraction;
  out->max_inclination = p.max_inclination;
  out->kalman_min_variance = p.kalman_min_variance;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kMaxLayers); ++i) {
    out->normal_variance_threshold[i] = p.normal_variance_threshold[i];
  }
  out->finest_max_sigma_m = p.finest_max_sigma_m;
  out->outlier_gate_sigma = p.outlier_gate_sigma;
  out->change_min_points = p.change_min_points;
  out->change_share = p.change_share;
  out->frame_point_budget = p.frame_point_budget;
  out->frame_time_budget_us = p.frame_time_budget_us;
  out->free_space_rays = p.free_space_rays;
  out->free_space_clear_frames = p.free_space_clear_frames;
  for (std::size_t i = 0; i < 3U; ++i) {
    out->sensor_view_axis[i] = p.sensor_view_axis[i];
  }
  // default_stack_params uses the CADRE stereo model (sensor::cadre_stereo()).
  out->noise.sensor = CCMAP_SENSOR_STEREO;
  out->noise.stereo_focal_px = sensor::kCadreStereoParams.focal_px;
  out->noise.stereo_baseline_m = sensor::kCadreStereoParams.baseline_m;
  out->noise.stereo_disparity_sigma_px = sensor::kCadreStereoParams.disparity_sigma_px;
  out->noise.lidar_sigma0_m = 0.0F;
  out->noise.lidar_sigma_per_m = 0.0F;
  out->noise.weight_mode = CCMAP_WEIGHT_CONSTANT;
  out->noise.reference_range_m = p.noise.reference_range_m();
}

Status params_from_c(const ccmap_params& c, StackParams* out) noexcept {
  StackParams p{};
  p.finest_cell_width_m = c.finest_cell_width_m;
  p.weight_limit = c.weight_limit;
  p.coverage_tau = c.coverage_tau;
  p.min_weight = c.min_weight;
  p.obstacle_fraction = c.obstacle_fraction;
  p.max_inclination = c.max_inclination;
  p.kalman_min_variance = c.kalman_min_variance;
  for (std::size_t i = 0; i < static_cast<std::size_t>(kMaxLayers); ++i) {
    p.normal_variance_threshold[i] = c.normal_variance_threshold[i];
  }
  p.finest_max_sigma_m = c.finest_max_sigma_m;
  p.outlier_gate_sigma = c.outlier_gate_sigma;
  p.change_min_points = c.change_min_points;
  p.change_share = c.change_share;
  p.frame_point_budget = c.frame_point_budget;
  p.frame_time_budget_us = c.frame_time_budget_us;
  p.free_space_rays = c.free_space_rays;
  p.free_space_clear_frames = c.free_space_clear_frames;
  for (std::size_t i = 0; i < 3U; ++i) {
    p.sensor_view_axis[i] = c.sensor_view_axis[i];
  }
  if (c.noise.sensor == CCMAP_SENSOR_STEREO) {
    p.noise = sensor::NoiseModel::stereo(sensor::StereoParams{
        c.noise.stereo_focal_px, c.noise.stereo_baseline_m, c.noise.stereo_disparity_sigma_px});
  } else if (c.noise.sensor == CCMAP_SENSOR_LIDAR) {
    p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{c.noise.lidar_sigma0_m, c.noise.lidar_sigma_per_m});
  } else {
    return Status::kInvalidArgument;
  }
  if (c.noise.weight_mode == CCMAP_WEIGHT_CONSTANT) {
    p.noise.set_weight_mode(sensor::WeightMode::kConstant, c.noise.reference_range_m);
  } else if (c.noise.weight_mode == CCMAP_WEIGHT_INVERSE_VARIANCE) {
    p.noise.set_weight_mode(sensor::WeightMode::kInverseVariance, c.noise.reference_range_m);
  } else {
    return Status::kInvalidArgument;
  }
  *out = p;
  return Status::kOk;
}

void result_to_c(const QueryResult& q, ccmap_query_result* out) noexcept {
  out->status = static_cast<std::int32_t>(q.status);
  out->layer = q.layer;
  out->cell_width_m = q.cell_width_m;
  out->height_m = q.height_m;
  out->slope_x = q.slope_x;
  out->slope_y = q.slope_y;
  out->inclination = q.inclination;
  out->normal_variance = q.normal_variance;
  out->elevation_variance = q.elevation_variance;
  out->weight = q.weight;
  out->cell_class = static_cast<std::int32_t>(q.cell_class);
  out->upset = q.upset ? 1 : 0;
}

ccmap_footprint_result footprint_to_c(const FootprintResult& r) noexcept {
  ccmap_footprint_result c{};
  c.status = static_cast<std::int32_t>(r.status);
  c.worst_class = static_cast<std::int32_t>(r.worst_class);
  c.unknown_share = r.unknown_share;
  c.max_step_m = r.max_step_m;
  c.max_inclination = r.max_inclination;
  c.min_height_m = r.min_height_m;
  c.max_height_m = r.max_height_m;
  c.area_m2 = r.area_m2;
  c.worst_layer = r.worst_layer;
  c.worst_index_x = r.worst_index.x;
  c.worst_index_y = r.worst_index.y;
  c.worst_x = r.worst_x;
  c.worst_y = r.worst_y;
  c.cells_visited = r.cells_visited;
  c.upset_share = r.upset_share;
  return c;
}

FootprintResult footprint_from_c(const ccmap_footprint_result& c) noexcept {
  FootprintResult r{};
  r.status = c.status >= 0 && c.status <= static_cast<std::int32_t>(CCMAP_VERSION_MISMATCH) ? static_cast<Status>(c.status)
                                                                                           : Status::kInvalidArgument;
  r.worst_class = c.worst_class >= CCMAP_CLASS_UNKNOWN && c.worst_class <= CCMAP_CLASS_DROP
                      ? static_cast<CellClass>(c.worst_class)
                      : CellClass::kUnknown;
  r.unknown_share = c.unknown_share;
  r.upset_share = c.upset_share;
  return r;
}

ccmap_path_pose pose_to_c(const PathPose& p) noexcept { return ccmap_path_pose{p.x, p.y, p.heading_x, p.heading_y}; }

void path_to_c(const PathResult& r, ccmap_path_result* out) noexcept {
  *out = ccmap_path_result{};
  out->status = static_cast<std::int32_t>(r.status);
  out->hazard_found = r.hazard_found ? 1 : 0;
  out->first_hazard_m = r.first_hazard_m;
  out->hazard_pose = pose_to_c(r.hazard_pose);
  out->hazard = footprint_to_c(r.hazard);
  out->unknown_found = r.unknown_found ? 1 : 0;
  out->first_unknown_m = r.first_unknown_m;
  out->unknown_pose = pose_to_c(r.unknown_pose);
  out->unknown = footprint_to_c(r.unknown);
  out->path_length_m = r.path_length_m;
  out->checked_m = r.checked_m;
  out->samples = r.samples;
  out->cells_visited = r.cells_visited;
}

PathSweep sweep_from_c(const ccmap_path_sweep& s) noexcept {
  return PathSweep{s.length_m, s.width_m, s.step_m, s.max_unknown_share};
}

void counters_to_c(const FrameCounters& f, ccmap_frame_counters* out) noexcept {
  *out = ccmap_frame_counters{f.received,      f.used,          f.rejected_non_finite,
                              f.rejected_out_of_range, f.rejected_weight, f.outside_map,
                              f.too_noisy,     f.gated_finer,   f.gated_occluded,
                              f.gated_held,    f.gated_pool_full, f.gated_admitted,
                              f.gated_dropped, f.reseeded_cells, f.merged_cells,
                              f.skipped_budget, f.corrupted_cells, f.corrupted_slots,
                              f.free_rays,     f.free_rays_refused, f.cleared_cells,
                              f.drop_cells};
}

}  // namespace
}  // namespace ccmap

using ccmap::Status;

extern "C" {

const char* ccmap_status_string(ccmap_status status) {
  const int s = static_cast<int>(status);
  if (s < static_cast<int>(CCMAP_OK) || s > static_cast<int>(CCMAP_NOT_CONVERGED)) {
    return "invalid_status";
  }
  return ccmap::to_string(static_cast<Status>(s));
}

const char* ccmap_cell_class_string(int32_t cell_class) {
  if (cell_class < CCMAP_CLASS_UNKNOWN || cell_class > CCMAP_CLASS_DROP) {
    return "unknown";
  }
  return ccmap::to_string(static_cast<ccmap::CellClass>(cell_class));
}

size_t ccmap_storage_size(ccmap_preset preset) { return ccmap::storage_size(preset); }
size_t ccmap_storage_align(ccmap_preset preset) { return ccmap::storage_align(preset); }
size_t ccmap_cadre_storage_size(void) { return ccmap::storage_size(CCMAP_PRESET_CADRE); }
size_t ccmap_cadre_storage_align(void) { return ccmap::storage_align(CCMAP_PRESET_CADRE); }

ccmap_status ccmap_place(void* storage, size_t storage_size, ccmap_preset preset, ccmap_map** out) {
  if (storage == nullptr || out == nullptr || !ccmap::valid_preset(static_cast<std::int64_t>(preset))) {
    return CCMAP_INVALID_ARGUMENT;
  }
  if (reinterpret_cast<std::uintptr_t>(storage) % ccmap::storage_align(preset) != 0U) {
    return CCMAP_INVALID_ARGUMENT;
  }
  if (storage_size < ccmap::storage_size(preset)) {
    return CCMAP_BUFFER_TOO_SMALL;
  }
  switch (preset) {
    case CCMAP_PRESET_CADRE: ccmap::place<ccmap::CadreConfig>(storage); break;
    case CCMAP_PRESET_SINGLE_CCM: ccmap::place<ccmap::SingleCcmConfig>(storage); break;
    case CCMAP_PRESET_SINGLE_KALMAN: ccmap::place<ccmap::SingleKalmanConfig>(storage); break;
    case CCMAP_PRESET_SINGLE_OMG: ccmap::place<ccmap::SingleOmgConfig>(storage); break;
    default: return CCMAP_INVALID_ARGUMENT;
  }
  new (storage) ccmap::HandleHeader{ccmap::kHandleMagic, static_cast<std::uint32_t>(preset),
                                    ccmap::header_check(ccmap::kHandleMagic, static_cast<std::uint32_t>(preset))};
  *out = static_cast<ccmap_map*>(storage);
  return CCMAP_OK;
}

ccmap_status ccmap_default_params(ccmap_preset preset, ccmap_params* out) {
  if (out == nullptr || !ccmap::valid_preset(static_cast<std::int64_t>(preset))) {
    return CCMAP_INVALID_ARGUMENT;
  }
  ccmap::params_to_c(ccmap::default_stack_params(ccmap::default_width(preset)), out);
  return CCMAP_OK;
}

ccmap_status ccmap_default_params_for_width(float finest_cell_width_m, ccmap_params* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  ccmap::params_to_c(ccmap::default_stack_params(finest_cell_width_m), out);
  return CCMAP_OK;
}

ccmap_status ccmap_init(ccmap_map* map, const ccmap_params* params) {
  if (params == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  ccmap::StackParams p{};
  const Status converted = ccmap::params_from_c(*params, &p);
  if (converted != Status::kOk) {
    return ccmap::to_c(converted);
  }
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&p](auto& stack) { return ccmap::to_c(stack.init(p)); });
}

ccmap_status ccmap_move_to(ccmap_map* map, float x, float y) {
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [x, y](auto& stack) { return ccmap::to_c(stack.move_to(x, y)); });
}

ccmap_status ccmap_move_to_uncertain(ccmap_map* map, float x, float y, float position_sigma_m) {
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT,
                         [=](auto& stack) { return ccmap::to_c(stack.move_to(x, y, position_sigma_m)); });
}

ccmap_status ccmap_update_frame(ccmap_map* map, const float* xyz, const float* weights, size_t n,
                                const float* sensor_origin_xyz, ccmap_frame_counters* counters) {
  if (sensor_origin_xyz == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  // NULL xyz with n > 0 is refused (and counted) by the stack itself.
  const auto* points = reinterpret_cast<const ccmap::PointXYZ*>(xyz);
  const ccmap::PointXYZ origin{sensor_origin_xyz[0], sensor_origin_xyz[1], sensor_origin_xyz[2]};
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](auto& stack) {
    ccmap::FrameCounters frame{};
    const Status status = stack.update_frame(points, weights, n, origin, &frame);
    if (counters != nullptr) {
      ccmap::counters_to_c(frame, counters);
    }
    return ccmap::to_c(status);
  });
}

ccmap_status ccmap_update_frame_sensor(ccmap_map* map, const float* xyz, size_t n, const ccmap_pose* pose,
                                       ccmap_frame_counters* counters) {
  if (pose == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const auto* points = reinterpret_cast<const ccmap::PointXYZ*>(xyz);
  ccmap::Pose p{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      p.rotation[r][c] = pose->rotation[3 * r + c];
    }
  }
  p.translation = ccmap::PointXYZ{pose->translation[0], pose->translation[1], pose->translation[2]};
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](auto& stack) {
    ccmap::FrameCounters frame{};
    const Status status = stack.update_frame_sensor(points, n, p, &frame);
    if (counters != nullptr) {
      ccmap::counters_to_c(frame, counters);
    }
    return ccmap::to_c(status);
  });
}

ccmap_status ccmap_query(const ccmap_map* map, float x, float y, ccmap_query_result* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    const ccmap::QueryResult q = stack.query(x, y);
    ccmap::result_to_c(q, out);
    return ccmap::to_c(q.status);
  });
}

ccmap_status ccmap_query_layer(const ccmap_map* map, int32_t layer, float x, float y, ccmap_query_result* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    const ccmap::QueryResult q = stack.query_layer(layer, x, y);
    ccmap::result_to_c(q, out);
    return ccmap::to_c(q.status);
  });
}

ccmap_status ccmap_query_footprint(const ccmap_map* map, const ccmap_footprint* footprint, ccmap_footprint_result* out) {
  if (footprint == nullptr || out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const ccmap::Footprint f{footprint->x,        footprint->y,        footprint->heading_x,
                           footprint->heading_y, footprint->length_m, footprint->width_m};
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    const ccmap::FootprintResult r = ccmap::query_footprint(stack, f);
    *out = ccmap::footprint_to_c(r);
    return ccmap::to_c(r.status);
  });
}

int32_t ccmap_footprint_class(const ccmap_footprint_result* result, float max_unknown_share) {
  if (result == nullptr) {
    return CCMAP_CLASS_UNKNOWN;
  }
  return static_cast<std::int32_t>(ccmap::footprint_class(ccmap::footprint_from_c(*result), max_unknown_share));
}

ccmap_status ccmap_query_path(const ccmap_map* map, const float* xy, size_t count, const ccmap_path_sweep* sweep,
                              ccmap_path_result* out) {
  if (sweep == nullptr || out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  // NULL xy is refused by the query itself (kInvalidArgument, in out->status).
  const auto* points = reinterpret_cast<const ccmap::PathPoint*>(xy);
  const ccmap::PathSweep s = ccmap::sweep_from_c(*sweep);
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    const ccmap::PathResult r = ccmap::query_path(stack, points, count, s);
    ccmap::path_to_c(r, out);
    return ccmap::to_c(r.status);
  });
}

ccmap_status ccmap_query_arc(const ccmap_map* map, const ccmap_path_pose* start, float curvature, float length_m,
                             const ccmap_path_sweep* sweep, ccmap_path_result* out) {
  if (start == nullptr || sweep == nullptr || out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const ccmap::PathPose p{start->x, start->y, start->heading_x, start->heading_y};
  const ccmap::PathSweep s = ccmap::sweep_from_c(*sweep);
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    const ccmap::PathResult r = ccmap::query_arc(stack, p, curvature, length_m, s);
    ccmap::path_to_c(r, out);
    return ccmap::to_c(r.status);
  });
}

ccmap_status ccmap_fill_costmap(const ccmap_map* map, const ccmap_costmap_spec* spec, uint8_t* cost, size_t capacity,
                                ccmap_costmap_stats* stats) {
  if (stats != nullptr) {
    *stats = ccmap_costmap_stats{};
  }
  if (spec == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const ccmap::CostmapSpec s{spec->centre_x, spec->centre_y, spec->resolution_m, spec->side, spec->inflation_radius_m};
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    ccmap::CostmapStats st{};
    const Status status = ccmap::fill_costmap(stack, s, cost, capacity, &st);
    if (stats != nullptr) {
      *stats = ccmap_costmap_stats{st.free, st.cost, st.inscribed, st.lethal, st.unknown, st.cells_visited};
    }
    return ccmap::to_c(status);
  });
}

int32_t ccmap_layer_count(const ccmap_map* map) {
  return ccmap::dispatch(map, std::int32_t{0}, [](const auto& stack) {
    return static_cast<std::int32_t>(std::remove_reference_t<decltype(stack)>::kLayerCount);
  });
}

size_t ccmap_layer_capacity(const ccmap_map* map, int32_t layer) {
  return ccmap::dispatch(map, std::size_t{0}, [layer](const auto& stack) {
    return std::remove_reference_t<decltype(stack)>::layer_capacity(layer);
  });
}

float ccmap_layer_cell_width(const ccmap_map* map, int32_t layer) {
  return ccmap::dispatch(map, 0.0F, [layer](const auto& stack) {
    return stack.initialised() ? stack.layer_cell_width(layer) : 0.0F;
  });
}

ccmap_status ccmap_export_layer(const ccmap_map* map, int32_t layer, ccmap_cell_record* out, size_t capacity,
                                size_t* written) {
  if (written != nullptr) {
    *written = 0U;
  }
  if (out == nullptr || written == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    using StackType = std::remove_reference_t<decltype(stack)>;
    if (stack.initialised() && layer >= 0 && layer < StackType::kLayerCount &&
        capacity < StackType::layer_capacity(layer)) {
      return CCMAP_BUFFER_TOO_SMALL;
    }
    // CellRecord objects in the caller's storage, then converted in place (same size).
    auto* bytes = static_cast<unsigned char*>(static_cast<void*>(out));
    const std::size_t records = capacity < StackType::layer_capacity(layer) ? capacity : StackType::layer_capacity(layer);
    for (std::size_t i = 0; i < records; ++i) {
      new (bytes + i * sizeof(ccmap::CellRecord)) ccmap::CellRecord{};
    }
    auto* cpp_records = std::launder(static_cast<ccmap::CellRecord*>(static_cast<void*>(bytes)));
    std::size_t count = 0U;
    const Status status = stack.export_layer(layer, cpp_records, records, &count);
    for (std::size_t i = 0; i < count; ++i) {
      ccmap::CellRecord r{};
      std::memcpy(&r, bytes + i * sizeof r, sizeof r);
      ccmap_cell_record c{};
      c.index_x = r.index.x;
      c.index_y = r.index.y;
      c.centre_x = r.centre_x;
      c.centre_y = r.centre_y;
      c.weight = r.weight;
      c.height_m = r.height_m;
      c.slope_x = r.slope_x;
      c.slope_y = r.slope_y;
      c.normal_variance = r.normal_variance;
      c.elevation_variance = r.elevation_variance;
      c.cell_class = static_cast<std::uint8_t>(r.cell_class);
      std::memcpy(bytes + i * sizeof c, &c, sizeof c);
    }
    *written = count;
    return ccmap::to_c(status);
  });
}

ccmap_status ccmap_get_counters(const ccmap_map* map, ccmap_counters* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [out](const auto& stack) {
    const Status state = stack.state_status();
    if (state == Status::kNotInitialised) {
      return CCMAP_NOT_INITIALISED;
    }
    // After an upset (CCMAP_CORRUPT) the counters are still written: telemetry of what happened.
    *out = ccmap_counters{};
    ccmap::counters_to_c(stack.total_counters(), &out->totals);
    out->rejected_moves = stack.rejected_moves();
    out->rejected_frames = stack.rejected_frames();
    out->last_update_ns = stack.last_update_ns();
    return ccmap::to_c(state);
  });
}

size_t ccmap_snapshot_size(const ccmap_map* map) {
  return ccmap::dispatch(map, std::size_t{0}, [](const auto& stack) { return ccmap::snapshot_bytes(stack); });
}

ccmap_status ccmap_save_snapshot(const ccmap_map* map, uint8_t* buffer, size_t capacity, size_t* written) {
  if (written != nullptr) {
    *written = 0U;
  }
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    return ccmap::to_c(ccmap::save_snapshot(stack, buffer, capacity, written));
  });
}

ccmap_status ccmap_load_snapshot(ccmap_map* map, const uint8_t* data, size_t size) {
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](auto& stack) {
    return ccmap::to_c(ccmap::load_snapshot(stack, data, size));
  });
}

// ---- map exchange ----
size_t ccmap_delta_max_size(ccmap_preset preset) {
  switch (preset) {
    case CCMAP_PRESET_CADRE: return ccmap::MapExchange<ccmap::CadreConfig>::max_delta_size();
    case CCMAP_PRESET_SINGLE_CCM: return ccmap::MapExchange<ccmap::SingleCcmConfig>::max_delta_size();
    case CCMAP_PRESET_SINGLE_KALMAN: return ccmap::MapExchange<ccmap::SingleKalmanConfig>::max_delta_size();
    case CCMAP_PRESET_SINGLE_OMG: return ccmap::MapExchange<ccmap::SingleOmgConfig>::max_delta_size();
    default: break;
  }
  return 0U;
}

size_t ccmap_delta_min_size(ccmap_preset preset) {
  switch (preset) {
    case CCMAP_PRESET_CADRE: return ccmap::MapExchange<ccmap::CadreConfig>::min_delta_size();
    case CCMAP_PRESET_SINGLE_CCM: return ccmap::MapExchange<ccmap::SingleCcmConfig>::min_delta_size();
    case CCMAP_PRESET_SINGLE_KALMAN: return ccmap::MapExchange<ccmap::SingleKalmanConfig>::min_delta_size();
    case CCMAP_PRESET_SINGLE_OMG: return ccmap::MapExchange<ccmap::SingleOmgConfig>::min_delta_size();
    default: break;
  }
  return 0U;
}

size_t ccmap_exchange_storage_size(ccmap_preset preset) {
  switch (preset) {
    case CCMAP_PRESET_CADRE: return ccmap::ExchangePreset<ccmap::CadreConfig>::kStorageSize;
    case CCMAP_PRESET_SINGLE_CCM: return ccmap::ExchangePreset<ccmap::SingleCcmConfig>::kStorageSize;
    case CCMAP_PRESET_SINGLE_KALMAN: return ccmap::ExchangePreset<ccmap::SingleKalmanConfig>::kStorageSize;
    case CCMAP_PRESET_SINGLE_OMG: return ccmap::ExchangePreset<ccmap::SingleOmgConfig>::kStorageSize;
    default: break;
  }
  return 0U;
}

size_t ccmap_exchange_storage_align(ccmap_preset preset) {
  switch (preset) {
    case CCMAP_PRESET_CADRE: return ccmap::ExchangePreset<ccmap::CadreConfig>::kStorageAlign;
    case CCMAP_PRESET_SINGLE_CCM: return ccmap::ExchangePreset<ccmap::SingleCcmConfig>::kStorageAlign;
    case CCMAP_PRESET_SINGLE_KALMAN: return ccmap::ExchangePreset<ccmap::SingleKalmanConfig>::kStorageAlign;
    case CCMAP_PRESET_SINGLE_OMG: return ccmap::ExchangePreset<ccmap::SingleOmgConfig>::kStorageAlign;
    default: break;
  }
  return 0U;
}

ccmap_status ccmap_exchange_place(void* storage, size_t storage_size, ccmap_preset preset, ccmap_exchange** out) {
  if (storage == nullptr || out == nullptr || !ccmap::valid_preset(static_cast<std::int64_t>(preset))) {
    return CCMAP_INVALID_ARGUMENT;
  }
  if (reinterpret_cast<std::uintptr_t>(storage) % ccmap_exchange_storage_align(preset) != 0U) {
    return CCMAP_INVALID_ARGUMENT;
  }
  if (storage_size < ccmap_exchange_storage_size(preset)) {
    return CCMAP_BUFFER_TOO_SMALL;
  }
  auto* bytes = static_cast<unsigned char*>(storage) + ccmap::kStackOffset;
  switch (preset) {
    case CCMAP_PRESET_CADRE: new (bytes) ccmap::MapExchange<ccmap::CadreConfig>(); break;
    case CCMAP_PRESET_SINGLE_CCM: new (bytes) ccmap::MapExchange<ccmap::SingleCcmConfig>(); break;
    case CCMAP_PRESET_SINGLE_KALMAN: new (bytes) ccmap::MapExchange<ccmap::SingleKalmanConfig>(); break;
    case CCMAP_PRESET_SINGLE_OMG: new (bytes) ccmap::MapExchange<ccmap::SingleOmgConfig>(); break;
    default: return CCMAP_INVALID_ARGUMENT;
  }
  new (storage) ccmap::HandleHeader{ccmap::kExchangeMagic, static_cast<std::uint32_t>(preset),
                                    ccmap::header_check(ccmap::kExchangeMagic, static_cast<std::uint32_t>(preset))};
  *out = static_cast<ccmap_exchange*>(storage);
  return CCMAP_OK;
}

ccmap_status ccmap_exchange_init(ccmap_exchange* exchange, ccmap_map* map, const ccmap_exchange_params* params) {
  if (params == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const ccmap::ExchangeParams p{params->rover_id, params->session,
                                ccmap::CellIndex{params->origin_x_cells, params->origin_y_cells}, params->origin_z_m};
  return ccmap::dispatch_pair(exchange, map, [&p](auto& ex, auto& stack) { return ccmap::to_c(ex.init(stack, p)); });
}

ccmap_status ccmap_exchange_export(ccmap_exchange* exchange, uint8_t* buffer, size_t capacity, float weight_floor,
                                   int32_t finest_layer, size_t* written, ccmap_export_report* report) {
  if (written != nullptr) {
    *written = 0U;
  }
  if (report != nullptr) {
    *report = ccmap_export_report{};
  }
  return ccmap::dispatch_exchange(exchange, CCMAP_INVALID_ARGUMENT, [&](auto& ex) {
    ccmap::ExportReport r{};
    const Status status = ex.export_delta(buffer, capacity, ccmap::ExportOptions{weight_floor, finest_layer}, written, &r);
    if (report != nullptr) {
      *report = ccmap_export_report{r.sequence, r.cells_written, r.cells_saturated, r.cells_pending,
                                    static_cast<std::uint64_t>(r.bytes)};
    }
    return ccmap::to_c(status);
  });
}

ccmap_status ccmap_exchange_merge_delta(ccmap_exchange* exchange, const uint8_t* data, size_t size,
                                        ccmap_merge_report* report) {
  ccmap::merge_report_to_c(ccmap::MergeReport{}, report);
  return ccmap::dispatch_exchange(exchange, CCMAP_INVALID_ARGUMENT, [&](auto& ex) {
    ccmap::MergeReport r{};
    const Status status = ex.merge_delta(data, size, &r);
    ccmap::merge_report_to_c(r, report);
    return ccmap::to_c(status);
  });
}

ccmap_status ccmap_exchange_merge_snapshot(ccmap_exchange* exchange, const uint8_t* data, size_t size,
                                           int32_t offset_x_cells, int32_t offset_y_cells, float offset_z_m,
                                           ccmap_merge_report* report) {
  ccmap::merge_report_to_c(ccmap::MergeReport{}, report);
  return ccmap::dispatch_exchange(exchange, CCMAP_INVALID_ARGUMENT, [&](auto& ex) {
    ccmap::MergeReport r{};
    const Status status =
        ex.merge_snapshot(data, size, ccmap::CellIndex{offset_x_cells, offset_y_cells}, offset_z_m, &r);
    ccmap::merge_report_to_c(r, report);
    return ccmap::to_c(status);
  });
}

ccmap_status ccmap_merge_snapshot(ccmap_map* map, const uint8_t* data, size_t size, int32_t offset_x_cells,
                                  int32_t offset_y_cells, float offset_z_m, ccmap_merge_report* report) {
  ccmap::merge_report_to_c(ccmap::MergeReport{}, report);
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](auto& stack) {
    ccmap::MergeReport r{};
    const Status status =
        ccmap::merge_snapshot(stack, data, size, ccmap::CellIndex{offset_x_cells, offset_y_cells}, offset_z_m, &r);
    ccmap::merge_report_to_c(r, report);
    return ccmap::to_c(status);
  });
}

ccmap_status ccmap_exchange_get_counters(const ccmap_exchange* exchange, ccmap_exchange_counters* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return ccmap::dispatch_exchange(exchange, CCMAP_INVALID_ARGUMENT, [out](const auto& ex) {
    const ccmap::ExchangeCounters& c = ex.counters();
    *out = ccmap_exchange_counters{c.deltas_exported,   c.deltas_merged,      c.snapshots_merged, c.refused,
                                   c.refused_corrupt,   c.refused_duplicate,  c.refused_misaligned, c.deltas_missed,
                                   c.bytes_exported,    c.bytes_merged,       c.cells_exported,   c.cells_merged,
                                   c.cells_outside};
    return CCMAP_OK;
  });
}

ccmap_status ccmap_default_registration_params(ccmap_registration_params* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const ccmap::RegistrationParams p = ccmap::default_registration_params();
  *out = ccmap_registration_params{p.max_points,  p.max_iterations, p.min_matches,      p.max_translation_m,
                                   p.max_yaw_rad, p.max_sigma_m,    p.robust_sigmas,    p.model_variance_m2,
                                   p.convergence_m};
  return CCMAP_OK;
}

ccmap_status ccmap_register_frame(const ccmap_map* map, const float* xyz, size_t n, const float* sensor_origin_xyz,
                                  const ccmap_registration_params* params, ccmap_registration_result* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  ccmap::registration_to_c(ccmap::detail::unclaimed_result(Status::kInvalidArgument), 0.0F, 0.0F, 0U, out);
  if (sensor_origin_xyz == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const auto* points = reinterpret_cast<const ccmap::PointXYZ*>(xyz);
  const ccmap::PointXYZ origin{sensor_origin_xyz[0], sensor_origin_xyz[1], sensor_origin_xyz[2]};
  const ccmap::RegistrationParams p = ccmap::registration_params_from_c(params);
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    const ccmap::RegistrationResult r = stack.register_frame(points, n, origin, p);
    ccmap::registration_to_c(r, origin.x, origin.y, 0U, out);
    return ccmap::to_c(r.status);
  });
}

ccmap_status ccmap_register_frame_sensor(const ccmap_map* map, const float* xyz, size_t n, const ccmap_pose* pose,
                                         const ccmap_registration_params* params, ccmap_registration_result* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  ccmap::registration_to_c(ccmap::detail::unclaimed_result(Status::kInvalidArgument), 0.0F, 0.0F, 0U, out);
  if (pose == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const auto* points = reinterpret_cast<const ccmap::PointXYZ*>(xyz);
  ccmap::Pose p{};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      p.rotation[r][c] = pose->rotation[3 * r + c];
    }
  }
  p.translation = ccmap::PointXYZ{pose->translation[0], pose->translation[1], pose->translation[2]};
  const ccmap::RegistrationParams rp = ccmap::registration_params_from_c(params);
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    const ccmap::RegistrationResult r = stack.register_frame_sensor(points, n, p, rp);
    ccmap::registration_to_c(r, p.translation.x, p.translation.y, 0U, out);
    return ccmap::to_c(r.status);
  });
}

ccmap_status ccmap_align_snapshot(const ccmap_map* map, const uint8_t* data, size_t size, const float* offset_xyz_m,
                                  const ccmap_registration_params* params, ccmap_registration_result* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  ccmap::registration_to_c(ccmap::detail::unclaimed_result(Status::kInvalidArgument), 0.0F, 0.0F, 0U, out);
  if (offset_xyz_m == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const ccmap::MapOffset offset{offset_xyz_m[0], offset_xyz_m[1], offset_xyz_m[2]};
  const ccmap::RegistrationParams p = ccmap::registration_params_from_c(params);
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    const ccmap::AlignmentResult a = ccmap::align_snapshot(stack, data, size, offset, p);
    ccmap::registration_to_c(a.correction, a.centre_x_m, a.centre_y_m, a.cells, out);
    return ccmap::to_c(a.correction.status);
  });
}

ccmap_status ccmap_align_delta(const ccmap_map* map, const uint8_t* data, size_t size, int32_t origin_x_cells,
                               int32_t origin_y_cells, float origin_z_m, const ccmap_registration_params* params,
                               ccmap_registration_result* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  ccmap::registration_to_c(ccmap::detail::unclaimed_result(Status::kInvalidArgument), 0.0F, 0.0F, 0U, out);
  const ccmap::RegistrationParams p = ccmap::registration_params_from_c(params);
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    const ccmap::AlignmentResult a =
        ccmap::align_delta(stack, data, size, ccmap::CellIndex{origin_x_cells, origin_y_cells}, origin_z_m, p);
    ccmap::registration_to_c(a.correction, a.centre_x_m, a.centre_y_m, a.cells, out);
    return ccmap::to_c(a.correction.status);
  });
}

const char* ccmap_platform_name(void) { return ccmap::platform::name(); }

}  // extern "C"
