#include "ccmap/map/update/front.hpp"

#include <cmath>

namespace ccmap::detail {
namespace {

/// round(v * 2^frac_bits) (half away from zero) of a finite float with |v * 2^frac_bits| < 2^62,
/// exact, in integer operations. Per-frame constants only (not the per-point path).
std::int64_t fixed_round(float v, int frac_bits) noexcept {
  const std::uint32_t bits = bits_of(v);
  const std::uint32_t biased = (bits >> 23) & 0xFFU;
  const std::int64_t significand = static_cast<std::int64_t>((bits & 0x7FFFFFU) | (biased != 0U ? 0x800000U : 0U));
  const std::int32_t exponent = static_cast<std::int32_t>(biased) + (biased == 0U ? 1 : 0);
  // v * 2^frac = significand * 2^(exponent - 150 + frac)
  const std::int32_t up = exponent - 150 + frac_bits;
  std::int64_t magnitude = 0;
  if (up >= 0) {
    magnitude = significand << up;  // precondition: < 2^62
  } else if (up > -63) {
    const std::int32_t down = -up;
    magnitude = (significand + (std::int64_t{1} << (down - 1))) >> down;
  }
  return (bits >> 31) != 0U ? -magnitude : magnitude;
}

}  // namespace

Status make_front_config(float finest_width_m, const float* max_range_sq_m2, int layers, FrontConfig* out) noexcept {
  if (out == nullptr || max_range_sq_m2 == nullptr || layers < 1 || layers > kFrontMaxLayers ||
      !(finest_width_m > 0.0F) || !std::isfinite(finest_width_m)) {
    return Status::kInvalidArgument;
  }
  const float inv_w0 = 1.0F / finest_width_m;  // the value RingGrid::init computes
  // Index of |x| <= kMaxAbsCoordinateM within +-2^30, and the product q18 * mult below 2^63:
  // 1/w_0 in [1e-3, 2^30 / 1e5]; validate_stack_params accepts only widths inside.
  if (!(inv_w0 >= 1.0e-3F) || !(inv_w0 * kMaxAbsCoordinateM < 1073741824.0F)) {
    return Status::kInvalidArgument;
  }
  FrontConfig f{};
  const std::uint32_t inv_bits = bits_of(inv_w0);
  f.index_mult = static_cast<std::int32_t>((inv_bits & 0x7FFFFFU) | 0x800000U);
  // q * 2^-18 * mult * 2^(e - 150) = (q * mult) * 2^-(168 - e)
  f.index_shift = 168 - static_cast<std::int32_t>((inv_bits >> 23) & 0xFFU);
  for (std::int64_t& bound : f.max_range_sq) {
    bound = INT64_MAX;
  }
  for (int k = 0; k < layers; ++k) {
    const float units = max_range_sq_m2[k] * 4294967296.0F;  // m^2 -> 2^-32 m^2 (exact scale)
    // A bound beyond int64 (including the +inf of an unbounded model) never refuses.
    f.max_range_sq[k] = !(units < 9.0e18F) ? INT64_MAX : (units < 1.0F ? 0 : floor_to_int64(units));
  }
  for (int k = 0; k < kFrontMaxLayers; ++k) {
    f.max_range_key[k] = route_key_of(f.max_range_sq[k]);
  }
  f.layers = static_cast<std::uint32_t>(layers);
  *out = f;
  return Status::kOk;
}

Status make_frame_pose(const PointXYZ& origin, const float* rotation_row_major, FramePose* out) noexcept {
  if (out == nullptr) {
    return Status::kInvalidArgument;
  }
  const Status origin_status = ccm_check_point(origin.x, origin.y, origin.z);
  if (origin_status != Status::kOk) {
    return origin_status;
  }
  FramePose pose{};
  const float o[3] = {origin.x, origin.y, origin.z};
  for (int a = 0; a < 3; ++a) {
    pose.origin_q18[a] = q18_floor(bits_of(o[a]));
    pose.translation_q18[a] = fixed_round(o[a], kPositionFracBits);
  }
  if (rotation_row_major != nullptr) {
    const float* r = rotation_row_major;
    for (int i = 0; i < 9; ++i) {
      if (!std::isfinite(r[i])) {
        return Status::kNonFiniteInput;
      }
      if (std::fabs(r[i]) > 1.001F) {
        return Status::kInvalidArgument;
      }
    }
    // R^T R = I within 1e-3: a rigid transform, not a scaling or shear (the Q30 format and the
    // range taken in the sensor frame assume it).
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const float dot = r[i] * r[j] + r[3 + i] * r[3 + j] + r[6 + i] * r[6 + j];
        const float expected = i == j ? 1.0F : 0.0F;
        if (std::fabs(dot - expected) > 1.0e-3F) {
          return Status::kInvalidArgument;
        }
      }
    }
    for (int i = 0; i < 9; ++i) {
      pose.rotation_q30[i] = static_cast<std::int32_t>(fixed_round(r[i], kRotationFracBits));
    }
    for (int row = 0; row < 3; ++row) {
      // Rounding to Q18 (+ half a Q48 -> Q18 step) and the mean of the floor in the Q18
      // conversion of each coordinate (+ half a unit, rotated): unbiased results.
      const std::size_t first = 3U * static_cast<std::size_t>(row);
      const std::int64_t row_sum = std::int64_t{pose.rotation_q30[first]} + pose.rotation_q30[first + 1U] +
                                   pose.rotation_q30[first + 2U];
      pose.rotation_bias_q48[row] = (std::int64_t{1} << (kRotationFracBits - 1)) + (row_sum >> 1);
    }
  }
  *out = pose;
  return Status::kOk;
}

}  // namespace ccmap::detail

// ---------------------------------------------------------------------------------------------
// The chunk functions. Plain loops over structure-of-arrays scratch, integer operations only,
// written so that gcc vectorises them: NEON on aarch64 (armv8-a baseline); on x86-64 the
// baseline (SSE2) lacks per-lane variable shifts and 32 x 32 -> 64 signed multiplies, so gcc
// also emits an AVX2 clone, chosen at load time (ifunc) on CPUs that have it. Every clone
// computes the same integers (integer arithmetic is exact): results are bitwise equal on every
// target, which tests/map/front_test.cpp and the golden hash check.
// ---------------------------------------------------------------------------------------------
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__gnu_linux__)
#define CCMAP_FRONT_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CCMAP_FRONT_CLONES
#endif

namespace ccmap::detail {
namespace {

constexpr std::uint32_t kAbsMask = 0x7FFFFFFFU;
constexpr std::uint32_t kInfBits = 0x7F800000U;

/// 0 for a usable coordinate triple, else the refusal code: the largest |bits| against
/// `limit_bits` (exclusive when `inclusive` is false).
inline std::int32_t validity(std::uint32_t bx, std::uint32_t by, std::uint32_t bz, std::uint32_t limit_bits,
                             bool limit_inclusive) noexcept {
  const std::uint32_t ax = bx & kAbsMask;
  const std::uint32_t ay = by & kAbsMask;
  const std::uint32_t az = bz & kAbsMask;
  const std::uint32_t largest = ax > ay ? (ax > az ? ax : az) : (ay > az ? ay : az);
  const bool refused = limit_inclusive ? largest > limit_bits : largest >= limit_bits;
  const std::int32_t reason = largest >= kInfBits ? std::int32_t{kFrontNonFinite} : std::int32_t{kFrontOutOfRange};
  return refused ? reason : 0;
}

/// Routing code of a routing key (route_key_of): the number of bound keys it exceeds (bounds are
/// non-decreasing, unused slots saturated), i.e. the first layer that holds it; too noisy beyond
/// the last layer. Written out for the 8 slots (kFrontMaxLayers) so that the vectoriser sees
/// straight-line code in 32-bit lanes. (The sensor itself, range 0, is marked too noisy where the
/// range is formed: at_sensor_code.)
inline std::int32_t route(std::uint32_t key, const std::uint32_t (&bound)[kFrontMaxLayers], std::int32_t layers) noexcept {
  static_assert(kFrontMaxLayers == 8, "route() is written out for 8 bounds");
  const std::int32_t layer = static_cast<std::int32_t>(key > bound[0]) + static_cast<std::int32_t>(key > bound[1]) +
                             static_cast<std::int32_t>(key > bound[2]) + static_cast<std::int32_t>(key > bound[3]) +
                             static_cast<std::int32_t>(key > bound[4]) + static_cast<std::int32_t>(key > bound[5]) +
                             static_cast<std::int32_t>(key > bound[6]) + static_cast<std::int32_t>(key > bound[7]);
  return layer >= layers ? std::int32_t{kFrontTooNoisy} : layer;
}

/// The code of a point whose refusal code so far is `code`: too noisy if it is the sensor itself
/// (range 0: no direction, no noise model), else unchanged.
inline std::int32_t at_sensor_code(std::int32_t code, std::int64_t range_sq) noexcept {
  return ((range_sq == 0) && (code == 0)) ? std::int32_t{kFrontTooNoisy} : code;
}

inline std::int64_t square_sum_q16(std::int32_t dx, std::int32_t dy, std::int32_t dz) noexcept {
  // Q18 -> Q16 (floor); |r| < 2^27: the sum stays < 2^56. 32 x 32 -> 64 multiplies (vectorised).
  const std::int32_t rx = dx >> 2;
  const std::int32_t ry = dy >> 2;
  const std::int32_t rz = dz >> 2;
  return static_cast<std::int64_t>(rx) * rx + static_cast<std::int64_t>(ry) * ry + static_cast<std::int64_t>(rz) * rz;
}

}  // namespace

CCMAP_FRONT_CLONES
void front_map_chunk(const PointXYZ* points, std::size_t n, const FramePose& pose, const FrontConfig& config,
                     FrontChunk& out) noexcept {
  const std::uint32_t limit_bits = bits_of(kMaxAbsCoordinateM);
  std::int64_t* const qx = out.q18[0];
  std::int64_t* const qy = out.q18[1];
  std::int64_t* const qz = out.q18[2];
  std::int32_t* const dx32 = out.scratch_i32[0];
  std::int32_t* const dy32 = out.scratch_i32[1];
  std::int32_t* const dz32 = out.scratch_i32[2];
  const std::int64_t origin[3] = {pose.origin_q18[0], pose.origin_q18[1], pose.origin_q18[2]};
  std::int32_t far_points = 0;
  // Loop 1: validation, Q18 position, offset from the sensor (int32 unless 2^11 m away: far).
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t bx = bits_of(points[i].x);
    const std::uint32_t by = bits_of(points[i].y);
    const std::uint32_t bz = bits_of(points[i].z);
    out.code[i] = validity(bx, by, bz, limit_bits, true);
    const std::int64_t x = q18_floor(bx);
    const std::int64_t y = q18_floor(by);
    const std::int64_t z = q18_floor(bz);
    qx[i] = x;
    qy[i] = y;
    qz[i] = z;
    const std::int64_t dx = x - origin[0];
    const std::int64_t dy = y - origin[1];
    const std::int64_t dz = z - origin[2];
    constexpr auto kSpan = static_cast<std::uint64_t>(2 * kMaxSensorOffsetQ18);
    const bool far = (static_cast<std::uint64_t>(dx + kMaxSensorOffsetQ18) | static_cast<std::uint64_t>(dy + kMaxSensorOffsetQ18) |
                      static_cast<std::uint64_t>(dz + kMaxSensorOffsetQ18)) >= kSpan;
    dx32[i] = static_cast<std::int32_t>(dx);
    dy32[i] = static_cast<std::int32_t>(dy);
    dz32[i] = static_cast<std::int32_t>(dz);
    out.range_sq[i] = far ? INT64_MAX : 0;  // the far flag, completed by loop 2
    far_points += far ? 1 : 0;
  }
  // Loop 2: range, routing, index = floor(q * mult * 2^-shift) = ((q - o) * mult + o * mult) >> shift
  // (a 32 x 32 -> 64 multiply; far points are fixed below), height.
  const std::int32_t mult = config.index_mult;
  const std::int64_t ox_mult = origin[0] * mult;
  const std::int64_t oy_mult = origin[1] * mult;
  const std::int32_t shift = config.index_shift;
  const std::uint32_t (&bounds)[kFrontMaxLayers] = config.max_range_key;
  const auto layers = static_cast<std::int32_t>(config.layers);
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t near_range_sq = square_sum_q16(dx32[i], dy32[i], dz32[i]);
    const std::int64_t range_sq = out.range_sq[i] != 0 ? INT64_MAX : near_range_sq;
    out.range_sq[i] = range_sq;
    out.range_key[i] = route_key_of(range_sq);
    out.code[i] = at_sensor_code(out.code[i], range_sq);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t routed = route(out.range_key[i], bounds, layers);
    const std::int32_t valid = out.code[i];
    out.code[i] = valid != 0 ? valid : routed;
    out.ix0[i] = static_cast<std::int32_t>((static_cast<std::int64_t>(dx32[i]) * mult + ox_mult) >> shift);
    out.iy0[i] = static_cast<std::int32_t>((static_cast<std::int64_t>(dy32[i]) * mult + oy_mult) >> shift);
    out.height_q14[i] = static_cast<std::int32_t>(qz[i] >> (kPositionFracBits - kHeightFracBits));
  }
  if (far_points > 0) {
    // Points 2^11 m or more from the sensor (rare: only layers of unbounded range take them):
    // the index from the full Q18 position (|q| < 2^35, mult < 2^24: the product fits int64).
    for (std::size_t i = 0; i < n; ++i) {
      if (out.range_sq[i] == INT64_MAX) {
        out.ix0[i] = static_cast<std::int32_t>((qx[i] * mult) >> shift);
        out.iy0[i] = static_cast<std::int32_t>((qy[i] * mult) >> shift);
      }
    }
  }
}

CCMAP_FRONT_CLONES
void front_sensor_chunk(const PointXYZ* points, std::size_t n, const FramePose& pose, const FrontConfig& config,
                        FrontChunk& out) noexcept {
  constexpr std::uint32_t kLimitBits = 0x45000000U;  // bits_of(2048.0F), exclusive
  std::int32_t* const sx = out.scratch_i32[0];
  std::int32_t* const sy = out.scratch_i32[1];
  std::int32_t* const sz = out.scratch_i32[2];
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t bx = bits_of(points[i].x);
    const std::uint32_t by = bits_of(points[i].y);
    const std::uint32_t bz = bits_of(points[i].z);
    out.code[i] = validity(bx, by, bz, kLimitBits, false);
    sx[i] = q18_floor_small(bx);
    sy[i] = q18_floor_small(by);
    sz[i] = q18_floor_small(bz);
  }
  std::int32_t r[9];
  for (int k = 0; k < 9; ++k) {
    r[k] = pose.rotation_q30[k];
  }
  const std::int64_t bias[3] = {pose.rotation_bias_q48[0], pose.rotation_bias_q48[1], pose.rotation_bias_q48[2]};
  const std::int64_t t[3] = {pose.translation_q18[0], pose.translation_q18[1], pose.translation_q18[2]};
  const std::int32_t mult = config.index_mult;
  const std::int64_t tx_mult = pose.translation_q18[0] * mult;
  const std::int64_t ty_mult = pose.translation_q18[1] * mult;
  const std::int32_t shift = config.index_shift;
  const std::uint32_t (&bounds)[kFrontMaxLayers] = config.max_range_key;
  const auto layers = static_cast<std::int32_t>(config.layers);
  constexpr std::int64_t kMaxQ18 = std::int64_t{100000} << kPositionFracBits;
  // Loop 1: rotation and range (32 x 32 -> 64 multiply-accumulates).
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t x = sx[i];
    const std::int32_t y = sy[i];
    const std::int32_t z = sz[i];
    // |r| <= 2^30 * 1.001 and |s| < 2^29: each product < 2^59.01, the sum of three < 2^60.6;
    // the rotated offset |d| < 2^29 * sqrt(3) * 1.001 < 2^30 fits int32.
    out.q18[0][i] = (std::int64_t{r[0]} * x + std::int64_t{r[1]} * y + std::int64_t{r[2]} * z + bias[0]) >> 30;
    out.q18[1][i] = (std::int64_t{r[3]} * x + std::int64_t{r[4]} * y + std::int64_t{r[5]} * z + bias[1]) >> 30;
    out.q18[2][i] = (std::int64_t{r[6]} * x + std::int64_t{r[7]} * y + std::int64_t{r[8]} * z + bias[2]) >> 30;
    const std::int64_t range_sq = square_sum_q16(x, y, z);
    out.range_sq[i] = range_sq;
    out.range_key[i] = route_key_of(range_sq);
    out.code[i] = at_sensor_code(out.code[i], range_sq);
  }
  // Loop 2: the map-frame position, routing, index, height.
  for (std::size_t i = 0; i < n; ++i) {
    const auto dx = static_cast<std::int32_t>(out.q18[0][i]);  // |offset| < 2^30 (see above)
    const auto dy = static_cast<std::int32_t>(out.q18[1][i]);
    const std::int64_t mx = dx + t[0];
    const std::int64_t my = dy + t[1];
    const std::int64_t mz = out.q18[2][i] + t[2];
    out.q18[0][i] = mx;
    out.q18[1][i] = my;
    out.q18[2][i] = mz;
    const std::int32_t routed = route(out.range_key[i], bounds, layers);
    const std::int32_t valid = out.code[i];
    out.code[i] = valid != 0 ? valid : routed;
    out.ix0[i] = static_cast<std::int32_t>((static_cast<std::int64_t>(dx) * mult + tx_mult) >> shift);
    out.iy0[i] = static_cast<std::int32_t>((static_cast<std::int64_t>(dy) * mult + ty_mult) >> shift);
    out.height_q14[i] = static_cast<std::int32_t>(mz >> (kPositionFracBits - kHeightFracBits));
  }
  // The map-frame range check (|m| <= 1e5 m on every axis) can only refuse a point when the
  // sensor is within 2^11 m * sqrt(3) (< 2^30 Q18) of that limit on some axis.
  const auto near_limit = [](std::int64_t v) { return (v < 0 ? -v : v) > kMaxQ18 - (std::int64_t{1} << 30); };
  if (near_limit(t[0]) || near_limit(t[1]) || near_limit(t[2])) {
    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t mx = out.q18[0][i];
      const std::int64_t my = out.q18[1][i];
      const std::int64_t mz = out.q18[2][i];
      const bool outside = mx > kMaxQ18 || mx < -kMaxQ18 || my > kMaxQ18 || my < -kMaxQ18 || mz > kMaxQ18 || mz < -kMaxQ18;
      const bool refused = out.code[i] >= std::int32_t{kFrontNonFinite} && out.code[i] != std::int32_t{kFrontTooNoisy};
      out.code[i] = outside && !refused ? std::int32_t{kFrontOutOfRange} : out.code[i];
    }
  }
}

}  // namespace ccmap::detail
