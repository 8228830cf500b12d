// C API (include/ccmap/ccmap.h) over Stack<Config> placed in caller-provided storage.
//
// Storage layout: a HandleHeader at the start of the caller's storage (the ccmap_map* handle
// points at it), the Stack<Config> at kStackOffset. Every entry point checks the header's magic
// and preset, then dispatches to the preset's Stack through a generic lambda.
#include "ccmap/ccmap.h"
#include "ccmap/capi_params.hpp"

#include <cstddef>
#include <atomic>
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
#include "ccmap/map/param_fields.hpp"
#include "ccmap/product/product_format.hpp"
#include "ccmap/product/publish.hpp"
#include "ccmap/registration/alignment.hpp"
#include "ccmap/platform/platform.hpp"
#include "ccmap/registration/registration.hpp"

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
CCMAP_SAME_STATUS(CCMAP_BUSY, kBusy);
#undef CCMAP_SAME_STATUS
static_assert(static_cast<int>(CCMAP_CLASS_UNKNOWN) == static_cast<int>(CellClass::kUnknown), "class");
static_assert(static_cast<int>(CCMAP_CLASS_TRAVERSABLE) == static_cast<int>(CellClass::kTraversable), "class");
static_assert(static_cast<int>(CCMAP_CLASS_OBSTACLE) == static_cast<int>(CellClass::kObstacle), "class");
static_assert(static_cast<int>(CCMAP_CLASS_STEEP) == static_cast<int>(CellClass::kSteep), "class");
static_assert(static_cast<int>(CCMAP_CLASS_DROP) == static_cast<int>(CellClass::kDropOff), "class");
static_assert(CCMAP_MAX_LAYERS == kMaxLayers, "CCMAP_MAX_LAYERS != kMaxLayers");
// Parameter commands: the C field bits are the C++ ones.
static_assert(CCMAP_PARAM_FINEST_CELL_WIDTH_M == param_field::kFinestCellWidth &&
                  CCMAP_PARAM_WEIGHT_LIMIT == param_field::kWeightLimit &&
                  CCMAP_PARAM_COVERAGE_TAU == param_field::kCoverageTau && CCMAP_PARAM_MIN_WEIGHT == param_field::kMinWeight &&
                  CCMAP_PARAM_OBSTACLE_FRACTION == param_field::kObstacleFraction &&
                  CCMAP_PARAM_MAX_INCLINATION == param_field::kMaxInclination &&
                  CCMAP_PARAM_KALMAN_MIN_VARIANCE == param_field::kKalmanMinVariance &&
                  CCMAP_PARAM_NORMAL_VARIANCE_THRESHOLD == param_field::kNormalVarianceThreshold &&
                  CCMAP_PARAM_FINEST_MAX_SIGMA_M == param_field::kFinestMaxSigma &&
                  CCMAP_PARAM_OUTLIER_GATE_SIGMA == param_field::kOutlierGateSigma &&
                  CCMAP_PARAM_CHANGE_MIN_POINTS == param_field::kChangeMinPoints &&
                  CCMAP_PARAM_CHANGE_SHARE == param_field::kChangeShare &&
                  CCMAP_PARAM_FRAME_POINT_BUDGET == param_field::kFramePointBudget &&
                  CCMAP_PARAM_FRAME_TIME_BUDGET_US == param_field::kFrameTimeBudget &&
                  CCMAP_PARAM_FREE_SPACE_RAYS == param_field::kFreeSpaceRays &&
                  CCMAP_PARAM_FREE_SPACE_CLEAR_FRAMES == param_field::kFreeSpaceClearFrames &&
                  CCMAP_PARAM_SENSOR_VIEW_AXIS == param_field::kSensorViewAxis &&
                  CCMAP_PARAM_NOISE == param_field::kNoise && CCMAP_PARAM_ALL == param_field::kAll &&
                  CCMAP_PARAM_REINIT_ALWAYS == param_field::kReinitAlways,
              "CCMAP_PARAM_* != ccmap::param_field");
// The product: the C constants are the format's.
static_assert(CCMAP_PRODUCT_HEADER_SIZE == kProductHeaderSize && CCMAP_PRODUCT_CELL_SIZE == kProductCellSize &&
                  CCMAP_PRODUCT_CRC_SIZE == kProductCrcSize && CCMAP_PRODUCT_VERSION == kProductVersion &&
                  CCMAP_PRODUCT_MAGIC == kProductMagic && CCMAP_PRODUCT_MAX_SIDE == kProductMaxSide &&
                  CCMAP_PRODUCT_READ_TRIES == kProductReadTries && CCMAP_PRODUCT_SIZE(3, 5) == product_size(3U, 5U),
              "ccmap.h product constants != product/product_format.hpp");
// ccmap_params has no padding: its bytes (the CRC of ccmap_health.params_crc) are its fields.
static_assert(sizeof(ccmap_params) == std::size_t{7U + CCMAP_MAX_LAYERS + 6U + 3U + 2U} * sizeof(float) +
                                          sizeof(ccmap_noise_params) &&
                  sizeof(ccmap_noise_params) == std::size_t{8U} * sizeof(float),
              "ccmap_params must have no padding");
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
/// upset changed is refused (CCMAP_CORRUPT), never trusted to pick a preset. The C API's own
/// state of a map follows (not in an exchange's header): the ccmap_params last accepted and its
/// CRC (ccmap_get_params answers them while they still describe what the map runs with), and the
/// products published since init or ccmap_reset_counters.
struct HandleHeader {
  std::uint32_t magic;
  std::uint32_t preset;
  std::uint32_t check;
  std::uint32_t products_published;
  ccmap_params params;
  std::uint32_t params_crc;  ///< CRC-32 of `params`; anything else: no copy (load_snapshot, an upset)
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
constexpr std::size_t kStackOffset = (sizeof(HandleHeader) + CCMAP_STORAGE_ALIGN - 1U) / CCMAP_STORAGE_ALIGN * CCMAP_STORAGE_ALIGN;
static_assert(sizeof(HandleHeader) <= kStackOffset, "header must fit before the stack");

/// Bytes and alignment of the caller's storage for an object (a Stack or a MapExchange) placed
/// behind a handle header.
template <typename Object>
struct Placement {
  static_assert(kStackOffset % alignof(Object) == 0U, "the object's offset must respect its alignment");
  static_assert(alignof(Object) <= CCMAP_STORAGE_ALIGN, "CCMAP_STORAGE_ALIGN too small");
  static constexpr std::size_t kStorageSize = kStackOffset + sizeof(Object);
  static constexpr std::size_t kStorageAlign = alignof(Object) > alignof(HandleHeader) ? alignof(Object)
                                                                                       : alignof(HandleHeader);
};
template <typename Config>
using Preset = Placement<Stack<Config>>;

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
using ExchangePreset = Placement<MapExchange<Config>>;
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
static_assert(CCMAP_CADRE_STORAGE_SIZE == 848U * 1024U && CCMAP_SINGLE_CCM_STORAGE_SIZE == 3280U * 1024U &&
                  CCMAP_SINGLE_KALMAN_STORAGE_SIZE == 3568U * 1024U && CCMAP_SINGLE_OMG_STORAGE_SIZE == 1488U * 1024U,
              "ccmap.h: a map storage constant and its KiB comment disagree");
static_assert(CCMAP_CADRE_EXCHANGE_STORAGE_SIZE == 464U * 1024U &&
                  CCMAP_SINGLE_CCM_EXCHANGE_STORAGE_SIZE == 2640U * 1024U &&
                  CCMAP_SINGLE_KALMAN_EXCHANGE_STORAGE_SIZE == 848U * 1024U &&
                  CCMAP_SINGLE_OMG_EXCHANGE_STORAGE_SIZE == 848U * 1024U,
              "ccmap.h: an exchange storage constant and its KiB comment disagree");

ccmap_status to_c(Status status) noexcept { return static_cast<ccmap_status>(status); }

// ---- the presets this build carries (CMake: CCMAP_CAPI_PRESETS) and the one visitor over them ----
#if !defined(CCMAP_CAPI_WITH_CADRE) && !defined(CCMAP_CAPI_WITH_SINGLE_CCM) && \
    !defined(CCMAP_CAPI_WITH_SINGLE_KALMAN) && !defined(CCMAP_CAPI_WITH_SINGLE_OMG)
#define CCMAP_CAPI_WITH_CADRE 1
#define CCMAP_CAPI_WITH_SINGLE_CCM 1
#define CCMAP_CAPI_WITH_SINGLE_KALMAN 1
#define CCMAP_CAPI_WITH_SINGLE_OMG 1
#endif

template <typename Config>
struct PresetTag {
  using type = Config;
};

/// Calls fn(PresetTag<Config>{}) for `preset` if this build carries it, else answers `bad`: the
/// only place that maps a preset number to a type.
template <typename Result, typename Fn>
Result visit_preset(std::int64_t preset, Result bad, Fn&& fn) noexcept {
  switch (preset) {
#ifdef CCMAP_CAPI_WITH_CADRE
    case CCMAP_PRESET_CADRE: return fn(PresetTag<CadreConfig>{});
#endif
#ifdef CCMAP_CAPI_WITH_SINGLE_CCM
    case CCMAP_PRESET_SINGLE_CCM: return fn(PresetTag<SingleCcmConfig>{});
#endif
#ifdef CCMAP_CAPI_WITH_SINGLE_KALMAN
    case CCMAP_PRESET_SINGLE_KALMAN: return fn(PresetTag<SingleKalmanConfig>{});
#endif
#ifdef CCMAP_CAPI_WITH_SINGLE_OMG
    case CCMAP_PRESET_SINGLE_OMG: return fn(PresetTag<SingleOmgConfig>{});
#endif
    default: break;
  }
  return bad;
}

bool valid_preset(std::int64_t preset) noexcept {
  return visit_preset(preset, false, [](auto) { return true; });
}

std::size_t storage_size(ccmap_preset preset) noexcept {
  return visit_preset(preset, std::size_t{0}, [](auto tag) {
    using Config = typename decltype(tag)::type;
    return Preset<Config>::kStorageSize;
  });
}

std::size_t storage_align(ccmap_preset preset) noexcept {
  return visit_preset(preset, std::size_t{0}, [](auto tag) {
    using Config = typename decltype(tag)::type;
    return Preset<Config>::kStorageAlign;
  });
}

// ---- handles: one header layout, two kinds (map, exchange) ----
template <typename Handle>
struct HandleKind;
template <>
struct HandleKind<ccmap_map> {
  static constexpr std::uint32_t kMagic = kHandleMagic;
  static constexpr std::uint32_t kOther = kExchangeMagic;
  template <typename Config>
  using Object = Stack<Config>;
};
template <>
struct HandleKind<ccmap_exchange> {
  static constexpr std::uint32_t kMagic = kExchangeMagic;
  static constexpr std::uint32_t kOther = kHandleMagic;
  template <typename Config>
  using Object = MapExchange<Config>;
};

/// The header of a valid handle, nullptr otherwise (*damaged: it is one an upset changed).
template <typename Handle>
HandleHeader* header_of(const Handle* handle, bool* damaged = nullptr) noexcept {
  if (damaged != nullptr) {
    *damaged = false;
  }
  if (handle == nullptr) {
    return nullptr;
  }
  // The handle is the caller's (non-const) storage; the const in the C signatures is the C
  // API's promise, kept by only calling const members from const entry points.
  auto* header = std::launder(static_cast<HandleHeader*>(const_cast<void*>(static_cast<const void*>(handle))));
  const HeaderState state = classify_header(*header, HandleKind<Handle>::kMagic, HandleKind<Handle>::kOther,
                                            valid_preset(static_cast<std::int64_t>(header->preset)));
  if (damaged != nullptr) {
    *damaged = state == HeaderState::kDamaged;
  }
  return state == HeaderState::kValid ? header : nullptr;
}

/// The object (Stack or MapExchange of Config) placed behind a handle.
template <typename Config, typename Handle>
auto& object_of(const Handle* handle) noexcept {
  using Object = typename HandleKind<Handle>::template Object<Config>;
  auto* bytes = const_cast<unsigned char*>(static_cast<const unsigned char*>(static_cast<const void*>(handle)));
  return *std::launder(static_cast<Object*>(static_cast<void*>(bytes + kStackOffset)));
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

/// Calls fn(object) for the handle's preset (fn(object, header) when fn takes two); `bad` for a
/// NULL or foreign handle, CCMAP_CORRUPT (or `bad`, for a number) for a damaged one.
template <typename Result, typename Handle, typename Fn>
Result dispatch(const Handle* handle, Result bad, Fn&& fn) noexcept {
  bool damaged = false;
  HandleHeader* header = header_of(handle, &damaged);
  if (header == nullptr) {
    return damaged ? damaged_result(bad) : bad;
  }
  return visit_preset(header->preset, bad, [&](auto tag) {
    using Config = typename decltype(tag)::type;
    auto& object = object_of<Config>(handle);
    if constexpr (std::is_invocable_v<Fn&, decltype(object), HandleHeader&>) {
      return fn(object, *header);
    } else {
      return fn(object);
    }
  });
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

/// Calls fn(MapExchange<C>&, Stack<C>&) when the exchange and the map are of the same preset.
template <typename Fn>
ccmap_status dispatch_pair(ccmap_exchange* exchange, ccmap_map* map, Fn&& fn) noexcept {
  bool exchange_damaged = false;
  bool map_damaged = false;
  const HandleHeader* e = header_of(exchange, &exchange_damaged);
  const HandleHeader* m = header_of(map, &map_damaged);
  if (exchange_damaged || map_damaged) {
    return CCMAP_CORRUPT;
  }
  if (e == nullptr || m == nullptr || e->preset != m->preset) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return visit_preset(e->preset, CCMAP_INVALID_ARGUMENT, [&](auto tag) {
    using Config = typename decltype(tag)::type;
    return fn(object_of<Config>(exchange), object_of<Config>(map));
  });
}

/// ccmap_place and ccmap_exchange_place: the object of `preset` and its header in `storage`.
template <typename Handle>
ccmap_status place_handle(void* storage, std::size_t size, ccmap_preset preset, Handle** out) noexcept {
  if (storage == nullptr || out == nullptr || !valid_preset(static_cast<std::int64_t>(preset))) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return visit_preset(preset, CCMAP_INVALID_ARGUMENT, [&](auto tag) {
    using Config = typename decltype(tag)::type;
    using Object = typename HandleKind<Handle>::template Object<Config>;
    if (reinterpret_cast<std::uintptr_t>(storage) % Placement<Object>::kStorageAlign != 0U) {
      return CCMAP_INVALID_ARGUMENT;
    }
    if (size < Placement<Object>::kStorageSize) {
      return CCMAP_BUFFER_TOO_SMALL;
    }
    new (static_cast<unsigned char*>(storage) + kStackOffset) Object();
    const auto p = static_cast<std::uint32_t>(preset);
    constexpr std::uint32_t kMagic = HandleKind<Handle>::kMagic;
    new (storage) HandleHeader{kMagic, p, header_check(kMagic, p), 0U, ccmap_params{}, 0U};
    *out = static_cast<Handle*>(storage);
    return CCMAP_OK;
  });
}

void merge_report_to_c(const MergeReport& r, ccmap_merge_report* out) noexcept {
  if (out != nullptr) {
    *out = ccmap_merge_report{r.sender_id,     r.sequence,        r.cells_merged,
                              r.cells_outside, r.deltas_missed,   r.drops_merged,
                              r.cells_cleared, r.clears_deferred, r.entries_outside,
                              r.entries_refused, to_c(r.free_space_status)};
  }
}

template <typename Config>
constexpr std::size_t snapshot_bytes(const Stack<Config>&) noexcept {
  return snapshot_size<Config>();
}

// ---- parameters ----
/// `p` as C parameters. The noise model: the CADRE stereo numbers (default_stack_params' model)
/// unless noise_from_model, then p.noise itself (stereo as focal 1 px, baseline 1 m and
/// disparity sigma k: the same model, bitwise, once converted back).
void params_to_c(const StackParams& p, ccmap_params* out, bool noise_from_model = false) noexcept {
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
  if (noise_from_model) {
    const sensor::NoiseModel& n = p.noise;
    const bool stereo = n.kind() == sensor::SensorKind::kStereo;
    out->noise.sensor = stereo ? CCMAP_SENSOR_STEREO : CCMAP_SENSOR_LIDAR;
    out->noise.stereo_focal_px = stereo ? 1.0F : 0.0F;
    out->noise.stereo_baseline_m = stereo ? 1.0F : 0.0F;
    out->noise.stereo_disparity_sigma_px = stereo ? n.stereo_sigma_per_range_sq() : 0.0F;
    out->noise.lidar_sigma0_m = n.lidar_sigma0_m();
    out->noise.lidar_sigma_per_m = n.lidar_sigma_per_m();
    out->noise.weight_mode =
        n.weight_mode() == sensor::WeightMode::kConstant ? CCMAP_WEIGHT_CONSTANT : CCMAP_WEIGHT_INVERSE_VARIANCE;
  }
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

std::uint32_t params_crc(const ccmap_params& p) noexcept {
  return product_crc32(reinterpret_cast<const std::uint8_t*>(&p), sizeof p);
}

/// Keeps the C parameters a map accepted (ccmap_init, ccmap_set_params), sealed by their CRC.
void remember_params(HandleHeader& header, const ccmap_params& p) noexcept {
  header.params = p;
  header.params_crc = params_crc(p);
}

/// The parameters the map runs with, as C parameters: the ones it was given while they are intact
/// and still convert to exactly what the stack holds, else the stack's own (after a load).
template <typename Config>
ccmap_params current_params(const Stack<Config>& stack, const HandleHeader& header) noexcept {
  StackParams given{};
  if (params_crc(header.params) == header.params_crc && params_from_c(header.params, &given) == Status::kOk &&
      changed_param_fields(given, stack.params()) == 0U) {
    return header.params;
  }
  ccmap_params out{};
  params_to_c(stack.params(), &out, true);
  return out;
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

void stack_params_to_c(const StackParams& params, ccmap_params* out) noexcept { params_to_c(params, out, true); }
Status stack_params_from_c(const ccmap_params& params, StackParams* out) noexcept { return params_from_c(params, out); }
std::uint32_t c_params_crc(const ccmap_params& params) noexcept { return params_crc(params); }

}  // namespace ccmap

using ccmap::Status;

extern "C" {

const char* ccmap_status_string(ccmap_status status) {
  const int s = static_cast<int>(status);
  if (s < static_cast<int>(CCMAP_OK) || s > static_cast<int>(CCMAP_BUSY)) {
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
  return ccmap::place_handle<ccmap_map>(storage, storage_size, preset, out);
}

ccmap_status ccmap_default_params(ccmap_preset preset, ccmap_params* out) {
  if (out == nullptr || !ccmap::valid_preset(static_cast<std::int64_t>(preset))) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const float width = ccmap::visit_preset(preset, 0.0F, [](auto tag) {
    using Config = typename decltype(tag)::type;
    return Config::kDefaultFinestCellWidthM;
  });
  ccmap::params_to_c(ccmap::default_stack_params(width), out);
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
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](auto& stack, ccmap::HandleHeader& header) {
    const Status status = stack.init(p);
    if (status == Status::kOk) {
      ccmap::remember_params(header, *params);
    }
    header.products_published = 0U;
    return ccmap::to_c(status);
  });
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
  const ccmap::CostmapSpec s{spec->centre_x, spec->centre_y, spec->resolution_m, spec->side, spec->inflation_radius_m,
                             spec->max_rows};
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack) {
    ccmap::CostmapStats st{};
    const Status status = ccmap::fill_costmap(stack, s, cost, capacity, &st);
    if (stats != nullptr) {
      *stats = ccmap_costmap_stats{st.free, st.cost, st.inscribed, st.lethal, st.unknown, st.cells_visited,
                                   st.rows_skipped};
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
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](auto& stack, ccmap::HandleHeader& header) {
    const Status status = ccmap::load_snapshot(stack, data, size);
    if (status == Status::kOk) {
      header.params = ccmap_params{};  // the snapshot brought its own: ccmap_get_params answers those
      header.params_crc = ~ccmap::params_crc(header.params);
      header.products_published = 0U;
    }
    return ccmap::to_c(status);
  });
}

// ---- map exchange ----
size_t ccmap_delta_max_size(ccmap_preset preset) {
  return ccmap::visit_preset(preset, std::size_t{0},
                             [](auto tag) {
    using Config = typename decltype(tag)::type;
    return ccmap::MapExchange<Config>::max_delta_size();
  });
}

size_t ccmap_delta_min_size(ccmap_preset preset) {
  return ccmap::visit_preset(preset, std::size_t{0},
                             [](auto tag) {
    using Config = typename decltype(tag)::type;
    return ccmap::MapExchange<Config>::min_delta_size();
  });
}

size_t ccmap_exchange_storage_size(ccmap_preset preset) {
  return ccmap::visit_preset(preset, std::size_t{0},
                             [](auto tag) {
    using Config = typename decltype(tag)::type;
    return ccmap::ExchangePreset<Config>::kStorageSize;
  });
}

size_t ccmap_exchange_storage_align(ccmap_preset preset) {
  return ccmap::visit_preset(preset, std::size_t{0},
                             [](auto tag) {
    using Config = typename decltype(tag)::type;
    return ccmap::ExchangePreset<Config>::kStorageAlign;
  });
}

ccmap_status ccmap_exchange_place(void* storage, size_t storage_size, ccmap_preset preset, ccmap_exchange** out) {
  return ccmap::place_handle<ccmap_exchange>(storage, storage_size, preset, out);
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
  return ccmap::dispatch(exchange, CCMAP_INVALID_ARGUMENT, [&](auto& ex) {
    ccmap::ExportReport r{};
    const Status status = ex.export_delta(buffer, capacity, ccmap::ExportOptions{weight_floor, finest_layer}, written, &r);
    if (report != nullptr) {
      *report = ccmap_export_report{r.sequence,      r.cells_written,
                                    r.cells_saturated, r.cells_pending,
                                    static_cast<std::uint64_t>(r.bytes), r.drops_written,
                                    r.clears_written, r.drops_pending};
    }
    return ccmap::to_c(status);
  });
}

ccmap_status ccmap_exchange_merge_delta(ccmap_exchange* exchange, const uint8_t* data, size_t size,
                                        ccmap_merge_report* report) {
  ccmap::merge_report_to_c(ccmap::MergeReport{}, report);
  return ccmap::dispatch(exchange, CCMAP_INVALID_ARGUMENT, [&](auto& ex) {
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
  return ccmap::dispatch(exchange, CCMAP_INVALID_ARGUMENT, [&](auto& ex) {
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
  return ccmap::dispatch(exchange, CCMAP_INVALID_ARGUMENT, [out](const auto& ex) {
    const ccmap::ExchangeCounters& c = ex.counters();
    *out = ccmap_exchange_counters{c.deltas_exported,   c.deltas_merged,      c.snapshots_merged, c.refused,
                                   c.refused_corrupt,   c.refused_duplicate,  c.refused_misaligned, c.deltas_missed,
                                   c.bytes_exported,    c.bytes_merged,       c.cells_exported,   c.cells_merged,
                                   c.cells_outside,     c.drops_exported,     c.clears_exported,  c.drops_merged,
                                   c.cells_cleared,     c.clears_deferred,    c.entries_refused,  c.sections_damaged};
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
    const ccmap::RegistrationResult r = ccmap::register_frame(stack, points, n, origin, p);
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
    const ccmap::RegistrationResult r = ccmap::register_frame_sensor(stack, points, n, p, rp);
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

int32_t ccmap_preset_available(ccmap_preset preset) {
  return ccmap::valid_preset(static_cast<std::int64_t>(preset)) ? 1 : 0;
}

// ---- parameters as commands ----
ccmap_status ccmap_validate_params(ccmap_preset preset, const ccmap_params* params) {
  if (params == nullptr || !ccmap::valid_preset(static_cast<std::int64_t>(preset))) {
    return CCMAP_INVALID_ARGUMENT;
  }
  ccmap::StackParams p{};
  const Status converted = ccmap::params_from_c(*params, &p);
  if (converted != Status::kOk) {
    return ccmap::to_c(converted);
  }
  return ccmap::visit_preset(preset, CCMAP_INVALID_ARGUMENT, [&p](auto tag) {
    using Config = typename decltype(tag)::type;
    return ccmap::to_c(ccmap::Stack<Config>::validate_params(p));
  });
}

ccmap_status ccmap_get_params(const ccmap_map* map, ccmap_params* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [out](const auto& stack, const ccmap::HandleHeader& header) {
    const Status state = stack.state_status();
    if (state == Status::kOk) {
      *out = ccmap::current_params(stack, header);
    }
    return ccmap::to_c(state);
  });
}

ccmap_status ccmap_set_params(ccmap_map* map, const ccmap_params* params, uint32_t* needs_reinit) {
  if (needs_reinit != nullptr) {
    *needs_reinit = 0U;
  }
  if (params == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  ccmap::StackParams p{};
  const Status converted = ccmap::params_from_c(*params, &p);
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](auto& stack, ccmap::HandleHeader& header) {
    // The map's own state answers first (as every call): a damaged or uninitialised map says so.
    const Status state = stack.state_status();
    if (state != Status::kOk) {
      return ccmap::to_c(state);
    }
    if (converted != Status::kOk) {
      return ccmap::to_c(converted);
    }
    const Status status = stack.set_params(p, needs_reinit);
    if (status == Status::kOk) {
      ccmap::remember_params(header, *params);
    }
    return ccmap::to_c(status);
  });
}

// ---- health ----
ccmap_status ccmap_get_health(const ccmap_map* map, ccmap_health* out) {
  if (out == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [out](const auto& stack, const ccmap::HandleHeader& header) {
    using StackType = std::remove_reference_t<decltype(stack)>;
    ccmap_health h{};
    const Status state = stack.state_status();
    h.initialised = stack.initialised() ? 1 : 0;
    h.state = static_cast<std::int32_t>(state);
    h.preset = static_cast<std::int32_t>(header.preset);
    h.layer_count = StackType::kLayerCount;
    const ccmap::FrameCounters& totals = stack.total_counters();
    h.frames_accepted = stack.frames_since_reset();
    h.frames_refused = stack.rejected_frames();
    h.moves_refused = stack.rejected_moves();
    h.points_received = totals.received;
    h.points_used = totals.used;
    h.points_skipped_budget = totals.skipped_budget;
    h.corrupted_cells = totals.corrupted_cells;
    h.corrupted_slots = totals.corrupted_slots;
    h.params_changes = stack.params_changes();
    h.products_published = header.products_published;
    h.last_frame_ns = stack.last_update_ns();
    h.last_frame_points = stack.last_frame().received;
    h.last_frame_used = stack.last_frame().used;
    h.params_crc = state == Status::kOk ? ccmap::params_crc(ccmap::current_params(stack, header)) : 0U;
    h.map_sequence = stack.accepted_frames();
    h.fault_count = ccmap::assert_failure_count();
    for (int layer = 0; layer < StackType::kLayerCount; ++layer) {
      ccmap_layer_health& l = h.layers[layer];
      const ccmap::CellIndex centre = stack.layer_centre(layer);
      l.cell_width_m = stack.layer_cell_width(layer);
      l.centre_index_x = centre.x;
      l.centre_index_y = centre.y;
      l.centre_x_m = static_cast<float>(centre.x) * l.cell_width_m;
      l.centre_y_m = static_cast<float>(centre.y) * l.cell_width_m;
      l.observed_cells = stack.observed_cells(layer);
      l.normal_variance_threshold = stack.normal_variance_threshold(layer);
    }
    *out = h;
    return CCMAP_OK;
  });
}

ccmap_status ccmap_reset_counters(ccmap_map* map) {
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [](auto& stack, ccmap::HandleHeader& header) {
    const Status status = stack.reset_counters();
    if (status == Status::kOk) {
      header.products_published = 0U;
    }
    return ccmap::to_c(status);
  });
}

namespace {
std::atomic<ccmap_fault_hook> g_fault_hook{nullptr};
std::atomic<void*> g_fault_context{nullptr};

void fault_trampoline(const char* file, int line, const char* expression) {
  const ccmap_fault_hook hook = g_fault_hook.load();
  if (hook != nullptr) {
    hook(g_fault_context.load(), file, line, expression);
  }
}
}  // namespace

ccmap_status ccmap_set_fault_hook(ccmap_fault_hook hook, void* context) {
  g_fault_context.store(context);
  g_fault_hook.store(hook);
  (void)ccmap::set_assert_hook(hook != nullptr ? &fault_trampoline : nullptr);
  return CCMAP_OK;
}

// ---- the map product ----
ccmap_status ccmap_product_buffers_init(ccmap_product_buffers* buffers, void* storage, size_t storage_size) {
  return ccmap::to_c(ccmap::product_buffers_init(buffers, storage, storage_size));
}

ccmap_status ccmap_publish(const ccmap_map* map, const ccmap_product_spec* spec, ccmap_product_buffers* buffers) {
  if (spec == nullptr || buffers == nullptr ||
      (spec->answer != CCMAP_PRODUCT_STACK && spec->answer != CCMAP_PRODUCT_LAYER)) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return ccmap::dispatch(map, CCMAP_INVALID_ARGUMENT, [&](const auto& stack, ccmap::HandleHeader& header) {
    ccmap::ProductSpec p{};
    p.layer = spec->layer;
    p.answer = spec->answer == CCMAP_PRODUCT_STACK ? ccmap::ProductAnswer::kStack : ccmap::ProductAnswer::kLayer;
    p.pose_x = spec->pose_x;
    p.pose_y = spec->pose_y;
    p.pose_z = spec->pose_z;
    p.pose_yaw = spec->pose_yaw;
    p.tag = spec->tag;
    p.preset = static_cast<std::uint16_t>(header.preset);
    p.params_crc = stack.state_status() == Status::kOk ? ccmap::params_crc(ccmap::current_params(stack, header)) : 0U;
    const Status status = ccmap::publish_product(stack, p, *buffers);
    if (status == Status::kOk && header.products_published != UINT32_MAX) {
      ++header.products_published;
    }
    return ccmap::to_c(status);
  });
}

ccmap_status ccmap_product_read(const ccmap_product_buffers* buffers, void* out, size_t capacity, size_t* written) {
  if (written != nullptr) {
    *written = 0U;
  }
  if (buffers == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  return ccmap::to_c(ccmap::product_read(*buffers, static_cast<std::uint8_t*>(out), capacity, written));
}

ccmap_status ccmap_product_decode(const void* data, size_t size, ccmap_product_header* header,
                                  ccmap_product_cell* cells, size_t cell_capacity) {
  if (data == nullptr || header == nullptr) {
    return CCMAP_INVALID_ARGUMENT;
  }
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  ccmap::ProductHeader h{};
  const Status status = ccmap::decode_product_header(bytes, size, &h);
  if (status != Status::kOk) {
    return ccmap::to_c(status);
  }
  const std::size_t count = std::size_t{h.side_x} * h.side_y;
  if (cells != nullptr && cell_capacity < count) {
    return CCMAP_BUFFER_TOO_SMALL;
  }
  *header = ccmap_product_header{h.version,      h.total_bytes,    h.product_sequence, h.map_sequence,
                                 h.params_crc,   h.preset,         h.layer,            h.answer,
                                 h.side_x,       h.side_y,         h.cell_width_m,     h.min_index_x,
                                 h.min_index_y,  h.min_corner_x_m, h.min_corner_y_m,   h.centre_x_m,
                                 h.centre_y_m,   h.pose_x,         h.pose_y,           h.pose_z,
                                 h.pose_yaw,     h.tag};
  if (cells != nullptr) {
    for (std::size_t i = 0; i < count; ++i) {
      const ccmap::ProductCell c = ccmap::decode_product_cell(bytes, i);
      cells[i] = ccmap_product_cell{c.cell_class, c.cost, c.status,
                                    c.layer == ccmap::kProductNoLayer ? -1 : static_cast<std::int32_t>(c.layer),
                                    c.height_m, c.inclination};
    }
  }
  return CCMAP_OK;
}

const char* ccmap_platform_name(void) { return ccmap::platform::name(); }

}  // extern "C"
