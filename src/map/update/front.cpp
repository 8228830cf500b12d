#include "ccmap/map/update/front.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#if defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#endif

namespace ccmap::detail {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

/// The finest cell of a map-frame coordinate x and its position inside it: floor(x * c) of the
/// exact product and the exact product minus that floor, rounded once (in [0, 1]). From the
/// rounded product p = fl(x c), i = floor(p), and the remainder r = x c - i rounded once (one
/// fused multiply-add). For |p| < 2^23 the exact product lies in [i - 1, i + 1) (p is within half
/// an ulp <= 1/2 of it, and p >= i + 1 if it were >= i + 1), so the floor is i - 1 iff the exact
/// remainder is negative, which the sign bit of r says even when r underflows to -0; the
/// fraction is then r + 1. |p| >= 2^23 (cells narrower than 12 mm far from the origin) is left to
/// exact_cell: the result is 1 then (0 otherwise).
inline std::uint32_t floor_and_fraction(float x, float c, std::int32_t* index, float* fraction) noexcept {
  const float p = x * c;
  const std::int32_t whole = floor_to_int32(p);
  // + float(-whole): an exact zero remainder is +0 (never -0, whose sign bit would read "negative").
  const float rest = std::fma(x, c, static_cast<float>(-whole));  // exact product - whole, one rounding
  const auto negative = static_cast<std::int32_t>(bits_of(rest) >> 31U);
  const float wrapped = rest + 1.0F;  // computed unconditionally: no float operation under a branch
  *index = whole - negative;
  *fraction = negative != 0 ? wrapped : rest;
  const bool near = (p < 8388608.0F) & (p > -8388608.0F);
  return near ? 0U : 1U;
}

/// The same exactly, in integer operations, for any finite x and positive normal c with
/// |x c| < 2^31: the product of the two 24-bit significands in 64 bits, floored by an
/// arithmetic shift, the remainder converted once. Per-frame constants and rare points only.
inline void exact_cell(float x, float c, std::int32_t* index, float* fraction) noexcept {
  const std::uint32_t xb = bits_of(x);
  const std::uint32_t cb = bits_of(c);
  const std::uint32_t x_biased = (xb >> 23U) & 0xFFU;
  const std::uint64_t xs = (xb & 0x7FFFFFU) | (x_biased != 0U ? 0x800000U : 0U);
  const std::int32_t xe = static_cast<std::int32_t>(x_biased) + (x_biased == 0U ? 1 : 0);
  const std::uint64_t cs = (cb & 0x7FFFFFU) | 0x800000U;
  const auto ce = static_cast<std::int32_t>((cb >> 23U) & 0xFFU);
  // x c = xs cs 2^(xe + ce - 300); shift = 300 - xe - ce >= 0 for |x c| < 2^31 (xs cs >= 2^46).
  const std::int32_t shift = 300 - xe - ce;
  const std::int64_t sign = -static_cast<std::int64_t>(xb >> 31U);
  const std::int64_t product = (static_cast<std::int64_t>(xs * cs) ^ sign) - sign;
  if (shift > 62) {  // |x c| < 2^-14: the floor is 0 or -1
    const float tiny = x * c;
    *index = product < 0 ? -1 : 0;
    *fraction = product < 0 ? tiny + 1.0F : tiny;
    return;
  }
  const std::int32_t s = shift < 0 ? 0 : shift;
  const std::int64_t whole = product >> s;  // arithmetic shift (two's complement): the floor
  // product - whole 2^s, in [0, 2^s): the low s bits (masked, not shifted back: whole may be < 0)
  const auto rest = static_cast<std::int64_t>(static_cast<std::uint64_t>(product) &
                                              ((std::uint64_t{1} << static_cast<std::uint32_t>(s)) - 1U));
  std::uint32_t scale_bits = static_cast<std::uint32_t>(127 - shift) << 23U;  // 2^-shift, normal for shift <= 62
  float scale = 0.0F;
  std::memcpy(&scale, &scale_bits, sizeof scale);
  *index = static_cast<std::int32_t>(whole);
  *fraction = static_cast<float>(rest) * scale;
}

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

}  // namespace

Status make_front_config(float finest_width_m, const float* max_range_sq_m2, int layers, FrontConfig* out) noexcept {
  if (out == nullptr || max_range_sq_m2 == nullptr || layers < 1 || layers > kFrontMaxLayers ||
      !(finest_width_m > 0.0F) || !std::isfinite(finest_width_m)) {
    return Status::kInvalidArgument;
  }
  const float inv_w0 = 1.0F / finest_width_m;  // the value RingGrid::init computes
  // Index of |x| <= kMaxAbsCoordinateM within +-2^30 (validate_stack_params accepts only such widths).
  if (!(inv_w0 >= 1.0e-3F) || !(inv_w0 * kMaxAbsCoordinateM < 1073741824.0F)) {
    return Status::kInvalidArgument;
  }
  FrontConfig f{};
  f.inv_width = inv_w0;
  f.width = finest_width_m;
  for (float& bound : f.max_range_sq) {
    bound = kInfinity;
  }
  for (int k = 0; k < layers; ++k) {
    const float bound = max_range_sq_m2[k];
    if (std::isnan(bound) || bound < 0.0F || (k > 0 && bound < f.max_range_sq[k - 1])) {
      return Status::kInvalidArgument;
    }
    f.max_range_sq[k] = bound;
  }
  f.layers = static_cast<std::uint32_t>(layers);
  *out = f;
  return Status::kOk;
}

Status check_rotation(const float* r) noexcept {
  for (int i = 0; i < 9; ++i) {
    if (!std::isfinite(r[i])) {
      return Status::kNonFiniteInput;
    }
    if (std::fabs(r[i]) > 1.001F) {
      return Status::kInvalidArgument;
    }
  }
  // R^T R = I within 1e-3: a rigid transform, not a scaling or shear (the range is taken in
  // the sensor frame, which assumes it).
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const float dot = r[i] * r[j] + r[3 + i] * r[3 + j] + r[6 + i] * r[6 + j];
      const float expected = i == j ? 1.0F : 0.0F;
      if (std::fabs(dot - expected) > 1.0e-3F) {
        return Status::kInvalidArgument;
      }
    }
  }
  return Status::kOk;
}

Status make_frame_pose(const PointXYZ& origin, const float* rotation_row_major, const FrontConfig& config,
                       FramePose* out) noexcept {
  if (out == nullptr || !(config.inv_width > 0.0F) || config.layers == 0U) {
    return Status::kInvalidArgument;
  }
  const Status origin_status = ccm_check_point(origin.x, origin.y, origin.z);
  if (origin_status != Status::kOk) {
    return origin_status;
  }
  FramePose pose{};
  pose.origin[0] = origin.x;
  pose.origin[1] = origin.y;
  pose.origin[2] = origin.z;
  exact_cell(origin.x, config.inv_width, &pose.anchor.x, &pose.anchor_fraction[0]);
  exact_cell(origin.y, config.inv_width, &pose.anchor.y, &pose.anchor_fraction[1]);
  // Within 2^11 m * sqrt(3) (3548 m) of the limit on some axis: check sensor points one by one.
  constexpr float kNear = kMaxAbsCoordinateM - 3548.0F;
  pose.near_limit = std::fabs(origin.x) > kNear || std::fabs(origin.y) > kNear || std::fabs(origin.z) > kNear;
  if (rotation_row_major != nullptr) {
    const float* r = rotation_row_major;
    const Status rotation_status = check_rotation(r);
    if (rotation_status != Status::kOk) {
      return rotation_status;
    }
    for (int i = 0; i < 9; ++i) {
      pose.rotation[i] = r[i];
    }
    for (int i = 0; i < 6; ++i) {
      pose.rotation_cells[i] = r[i] * config.inv_width;
    }
  }
  *out = pose;
  return Status::kOk;
}

}  // namespace ccmap::detail

// ---------------------------------------------------------------------------------------------
// The chunk functions. Plain loops over structure-of-arrays, written so that gcc vectorises
// them: NEON on aarch64 (armv8-a baseline); on x86-64 gcc also emits an AVX2+FMA clone, chosen
// at load time (ifunc) on CPUs that have it (the baseline clone calls fmaf). Every clone
// computes the same floats: single IEEE operations in the same order, the fused multiply-add
// written out (std::fma rounds once everywhere). tests/map/front_test.cpp and the golden hashes
// check it. Two traps (either leaves the host running the baseline clone's scalar SSE without a
// word): a clone compiles only what is inlined into it, so the loops below are
// forced inline (CCMAP_FRONT_LOOP) into the two cloned entry points; and the clone is named by
// its ISA level (x86-64-v3: AVX2, FMA, BMI2; gcc >= 12), which the loader tests with
// __builtin_cpu_supports, not by a CPU model: "arch=haswell" is chosen only on a CPU that *is* a
// Haswell (__builtin_cpu_is), never on a later Intel or an AMD one.
// ---------------------------------------------------------------------------------------------
// A coverage build defines CCMAP_FRONT_NO_CLONES (src/map/sources.cmake): one baseline copy.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__gnu_linux__) && __GNUC__ >= 12 && \
    !defined(CCMAP_FRONT_NO_CLONES)
#define CCMAP_FRONT_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#define CCMAP_FRONT_LOOP __attribute__((always_inline)) inline
#else
#define CCMAP_FRONT_CLONES
#define CCMAP_FRONT_LOOP
#endif

namespace ccmap::detail {
namespace {

/// Routing code of a squared range for a stack of kLayers layers: the number of bounds it
/// exceeds (bounds are non-decreasing), i.e. the first layer that holds it; too noisy beyond
/// the last one and for the sensor itself (range 0: no direction, no noise model).
template <int kLayers>
inline std::int32_t route(float range_sq, const float (&bound)[kFrontMaxLayers]) noexcept {
  // Every comparison unconditional (| not ||): a float operation under a branch would keep the
  // loop from being vectorised (gcc does not speculate it under -ftrapping-math).
  std::int32_t layer = 0;
  for (int k = 0; k < kLayers; ++k) {
    layer += range_sq > bound[k] ? 1 : 0;
  }
  const bool at_sensor = !(range_sq > 0.0F);
  return ((layer >= kLayers) | at_sensor) ? std::int32_t{kFrontTooNoisy} : layer;
}

/// Writes entry i from its validity code, finest index, height and squared range: routing, the
/// Kalman slot, the Q14 height and the range key. Inlined into each chunk loop.
struct FineSlot {
  std::uint32_t side;  ///< 0: no slot
  std::uint32_t mask;
  std::uint32_t log2_side;
  std::uint32_t min_x;
  std::uint32_t min_y;
};
inline FineSlot fine_slot_of(const FineWindow& fine) noexcept {
  const auto side = static_cast<std::uint32_t>(fine.side);
  return FineSlot{side, side - 1U, static_cast<std::uint32_t>(fine.log2_side), static_cast<std::uint32_t>(fine.min.x),
                  static_cast<std::uint32_t>(fine.min.y)};
}

#if defined(__x86_64__) && defined(__GNUC__)
#define CCMAP_FRONT_VECTOR 1
// finish_entries (below) eight points per step in GCC vector extensions, for x86-64: its loop,
// inlined into the chunk functions, stays scalar ("control flow in loop", -fopt-info-vec-missed).
// The AVX2 clone computes each step in 32-byte registers, the baseline one (and a coverage build)
// in two SSE2 halves. The same IEEE operations on the same values as that loop, lane by lane; a
// vector compare is all ones (-1) where true, and `m ? a : b` selects lane by lane.
// tests/map/front_test.cpp checks the chunks bit for bit against one point at a time, and the
// golden hashes host against aarch64.
using F8 = float __attribute__((vector_size(32)));
using I8 = std::int32_t __attribute__((vector_size(32)));
using U8 = std::uint32_t __attribute__((vector_size(32)));

/// floor of eight floats as int32 (|v| < 2^31): the truncation, less one where it rounded up.
/// A macro: a function taking or returning a 32-byte vector by value is an ABI warning (-Wpsabi)
/// in the baseline clone.
#define CCMAP_FLOOR8(v, out)                                                  \
  do {                                                                        \
    const I8 t_ = __builtin_convertvector((v), I8);                           \
    (out) = t_ + static_cast<I8>(__builtin_convertvector(t_, F8) > (v));      \
  } while (false)

/// Entries [first, first + 8 k) of finish_entries, for the largest k; returns where it stopped.
template <int kLayers>
CCMAP_FRONT_LOOP std::size_t finish_entries_x8(std::size_t first, std::size_t n, const float (&bounds)[kFrontMaxLayers],
                                               const FineSlot& fine, FrontChunk& __restrict out) noexcept {
  constexpr auto kBounds = static_cast<std::size_t>(kLayers);
  const std::size_t done = first + (n - first) / 8U * 8U;
  F8 bound[kBounds];
  for (std::size_t k = 0; k < kBounds; ++k) {
    bound[k] = F8{} + bounds[k];
  }
  const U8 side = U8{} + fine.side;
  const U8 mask = U8{} + fine.mask;
  const U8 min_x = U8{} + fine.min_x;
  const U8 min_y = U8{} + fine.min_y;
  const F8 key_cap = F8{} + kRangeKeyCapM2;
  const I8 too_noisy = I8{} + std::int32_t{kFrontTooNoisy};
  const I8 none = I8{} - 1;
  for (std::size_t i = first; i < done; i += 8U) {
    I8 valid;
    F8 r2;
    I8 ix0;
    I8 iy0;
    F8 z;
    std::memcpy(&valid, &out.code[i], sizeof valid);
    std::memcpy(&r2, &out.range_sq[i], sizeof r2);
    std::memcpy(&ix0, &out.ix0[i], sizeof ix0);
    std::memcpy(&iy0, &out.iy0[i], sizeof iy0);
    std::memcpy(&z, &out.z[i], sizeof z);
    I8 layer = I8{};
    for (std::size_t k = 0; k < kBounds; ++k) {
      layer -= (r2 > bound[k]);
    }
    const I8 noisy = (layer >= kLayers) | ~(r2 > F8{});  // beyond the last bound, or at the sensor
    const I8 routed = noisy ? too_noisy : layer;
    const I8 code = (valid != 0) ? valid : routed;
    const U8 ux = __builtin_convertvector(ix0, U8);
    const U8 uy = __builtin_convertvector(iy0, U8);
    const I8 ok = ((ux - min_x) < side) & ((uy - min_y) < side) & (code == 0);
    const I8 slot = __builtin_convertvector(((uy & mask) << fine.log2_side) | (ux & mask), I8);
    const I8 fine_slot = ok ? slot : none;
    const F8 capped = (r2 < key_cap) ? r2 : key_cap;
    I8 height;
    I8 key;
    CCMAP_FLOOR8(z * kHeightQ14PerM, height);
    CCMAP_FLOOR8(capped * kRangeKeysPerM2, key);
    std::memcpy(&out.code[i], &code, sizeof code);
    std::memcpy(&out.fine_slot[i], &fine_slot, sizeof fine_slot);
    std::memcpy(&out.height_q14[i], &height, sizeof height);
    std::memcpy(&out.range_key[i], &key, sizeof key);
  }
  return done;
}
#undef CCMAP_FLOOR8
#endif

/// The entries derived from code, index, height and range (second loop of a chunk: gcc does not
/// vectorise the routing's float compares in one loop with the transform): routing, the Kalman
/// slot, the Q14 height and the range key.
template <int kLayers>
CCMAP_FRONT_LOOP void finish_entries(std::size_t first, std::size_t n, const float (&bounds)[kFrontMaxLayers],
                                      const FineSlot& fine, FrontChunk& __restrict out) noexcept {
#if defined(CCMAP_FRONT_VECTOR)
  first = finish_entries_x8<kLayers>(first, n, bounds, fine, out);
#endif
  for (std::size_t i = first; i < n; ++i) {
    const std::int32_t valid = out.code[i];
    const float r2 = out.range_sq[i];
    const std::int32_t routed = route<kLayers>(r2, bounds);
    const std::int32_t code = valid != 0 ? valid : routed;
    out.code[i] = code;
    const auto ux = static_cast<std::uint32_t>(out.ix0[i]);
    const auto uy = static_cast<std::uint32_t>(out.iy0[i]);
    // All ones iff routed to layer 0 and inside the window (unsigned wrap: one compare per axis).
    const std::uint32_t ok =
        0U - static_cast<std::uint32_t>(((ux - fine.min_x) < fine.side) & ((uy - fine.min_y) < fine.side) & (code == 0));
    const std::uint32_t slot = ((uy & fine.mask) << fine.log2_side) | (ux & fine.mask);
    out.fine_slot[i] = static_cast<std::int32_t>((slot & ok) | ~ok);  // the slot, or -1
    out.height_q14[i] = floor_to_int32(out.z[i] * kHeightQ14PerM);       // |z| <= 1.04e5 m: < 2^31
    out.range_key[i] = floor_to_int32((r2 < kRangeKeyCapM2 ? r2 : kRangeKeyCapM2) * kRangeKeysPerM2);
  }
}

#if defined(__aarch64__) && defined(__ARM_NEON)
#define CCMAP_FRONT_NEON 1
// The chunk functions in NEON, four points per step, for the first n - n % 4 points (the rest,
// and every other target, take the portable loops): the same IEEE operations in the same order
// as map_chunk / sensor_chunk and finish_entries, fused into one pass (the vectoriser keeps them
// in two and spills their constants). tests/map/front_test.cpp checks them against the portable
// loops bit for bit, and the golden hashes check host == aarch64.

/// Routing, the Kalman slot, the Q14 height and the range key of four points, and every store.
template <int kLayers>
struct NeonFinish {
  explicit NeonFinish(const FrontConfig& config, const FineSlot& fine) noexcept
      : side(vdupq_n_u32(fine.side)),
        mask(vdupq_n_u32(fine.mask)),
        log2_side(vdupq_n_s32(static_cast<std::int32_t>(fine.log2_side))),
        min_x(vdupq_n_u32(fine.min_x)),
        min_y(vdupq_n_u32(fine.min_y)),
        q14(vdupq_n_f32(kHeightQ14PerM)),
        key_cap(vdupq_n_f32(kRangeKeyCapM2)),
        key_scale(vdupq_n_f32(kRangeKeysPerM2)) {
    for (int k = 0; k < kLayers; ++k) {
      bound[static_cast<std::size_t>(k)] = vdupq_n_f32(config.max_range_sq[k]);
    }
  }

  void store(std::size_t i, uint32x4_t refused, uint32x4_t valid, int32x4_t ix0, int32x4_t iy0, float32x4_t fx,
             float32x4_t fy, float32x4_t z, float32x4_t r2, FrontChunk& __restrict out) const noexcept {
    // Routing: the bounds the range exceeds; too noisy beyond the last (bounds are
    // non-decreasing: then it exceeds them all) or at the sensor (not > 0).
    uint32x4_t layer = vdupq_n_u32(0U);
    for (int k = 0; k + 1 < kLayers; ++k) {
      layer = vsubq_u32(layer, vcgtq_f32(r2, bound[static_cast<std::size_t>(k)]));  // true is all ones: -1
    }
    const uint32x4_t noisy = vorrq_u32(vcgtq_f32(r2, bound[static_cast<std::size_t>(kLayers - 1)]), vclezq_f32(r2));
    const uint32x4_t routed = vbslq_u32(noisy, vdupq_n_u32(kFrontTooNoisy), layer);
    const uint32x4_t code = vbslq_u32(refused, valid, routed);
    // The Kalman slot: routed to layer 0 and inside the finest window.
    const uint32x4_t uix = vreinterpretq_u32_s32(ix0);
    const uint32x4_t uiy = vreinterpretq_u32_s32(iy0);
    const uint32x4_t ok = vandq_u32(vandq_u32(vcltq_u32(vsubq_u32(uix, min_x), side), vcltq_u32(vsubq_u32(uiy, min_y), side)),
                                    vceqzq_u32(code));
    const uint32x4_t slot = vorrq_u32(vshlq_u32(vandq_u32(uiy, mask), log2_side), vandq_u32(uix, mask));
    vst1q_s32(&out.code[i], vreinterpretq_s32_u32(code));
    vst1q_s32(&out.ix0[i], ix0);
    vst1q_s32(&out.iy0[i], iy0);
    vst1q_f32(&out.fx[i], fx);
    vst1q_f32(&out.fy[i], fy);
    vst1q_f32(&out.z[i], z);
    vst1q_f32(&out.range_sq[i], r2);
    vst1q_s32(&out.fine_slot[i], vreinterpretq_s32_u32(vornq_u32(vandq_u32(slot, ok), ok)));
    vst1q_s32(&out.height_q14[i], vcvtmq_s32_f32(vmulq_f32(z, q14)));
    vst1q_s32(&out.range_key[i], vcvtmq_s32_f32(vmulq_f32(vminq_f32(r2, key_cap), key_scale)));
  }

  float32x4_t bound[static_cast<std::size_t>(kLayers)];
  uint32x4_t side, mask;
  int32x4_t log2_side;
  uint32x4_t min_x, min_y;
  float32x4_t q14, key_cap, key_scale;
};

/// Validity of four points from their bit patterns shifted left by one (the sign dropped):
/// all-ones lanes in *refused, the reason (kFrontOutOfRange, or kFrontNonFinite for NaN/Inf)
/// in the result. `inclusive`: the limit itself is accepted (map frame) or not (sensor frame).
inline uint32x4_t neon_validity(uint32x4_t bx, uint32x4_t by, uint32x4_t bz, std::uint32_t limit_bits, bool inclusive,
                                uint32x4_t* refused) noexcept {
  const uint32x4_t largest2 = vmaxq_u32(vmaxq_u32(vshlq_n_u32(bx, 1), vshlq_n_u32(by, 1)), vshlq_n_u32(bz, 1));
  const uint32x4_t limit2 = vdupq_n_u32(limit_bits << 1U);
  *refused = inclusive ? vcgtq_u32(largest2, limit2) : vcgeq_u32(largest2, limit2);
  // kFrontOutOfRange, minus one (kFrontNonFinite) where NaN or Inf: a true compare is all ones.
  return vandq_u32(*refused, vaddq_u32(vdupq_n_u32(kFrontOutOfRange), vcgeq_u32(largest2, vdupq_n_u32(kInfBits << 1U))));
}

/// floor_and_fraction of four coordinates: the index and fraction; `far` gathers |x c| >= 2^23.
inline void neon_floor_and_fraction(float32x4_t x, float32x4_t c, int32x4_t* index, float32x4_t* fraction,
                                    uint32x4_t* far) noexcept {
  const float32x4_t p = vmulq_f32(x, c);
  const int32x4_t whole = vcvtmq_s32_f32(p);
  // x c + float(-whole), one rounding (FMLA): the portable std::fma(x, c, float(-whole)).
  const float32x4_t rest = vfmaq_f32(vcvtq_f32_s32(vnegq_s32(whole)), x, c);
  const int32x4_t negative = vshrq_n_s32(vreinterpretq_s32_f32(rest), 31);  // all ones if the sign bit is set
  *index = vaddq_s32(whole, negative);
  *fraction = vbslq_f32(vreinterpretq_u32_s32(negative), vaddq_f32(rest, vdupq_n_f32(1.0F)), rest);
  *far = vorrq_u32(*far, vcageq_f32(p, vdupq_n_f32(8388608.0F)));
}

template <int kLayers>
std::size_t map_chunk_neon(const PointXYZ* __restrict points, std::size_t n, const FramePose& pose,
                           const FrontConfig& config, const FineSlot& fine, FrontChunk& __restrict out,
                           std::uint32_t* far_points) noexcept {
  const NeonFinish<kLayers> finish(config, fine);
  const float32x4_t ox = vdupq_n_f32(pose.origin[0]);
  const float32x4_t oy = vdupq_n_f32(pose.origin[1]);
  const float32x4_t oz = vdupq_n_f32(pose.origin[2]);
  const float32x4_t inv = vdupq_n_f32(config.inv_width);
  const std::uint32_t limit_bits = bits_of(kMaxAbsCoordinateM);
  uint32x4_t far = vdupq_n_u32(0U);
  const std::size_t done = n - n % 4U;
  for (std::size_t i = 0; i < done; i += 4U) {
    const float32x4x3_t p = vld3q_f32(&points[i].x);
    const uint32x4_t bx = vreinterpretq_u32_f32(p.val[0]);
    const uint32x4_t by = vreinterpretq_u32_f32(p.val[1]);
    const uint32x4_t bz = vreinterpretq_u32_f32(p.val[2]);
    uint32x4_t refused;
    const uint32x4_t valid = neon_validity(bx, by, bz, limit_bits, true, &refused);
    const float32x4_t x = vreinterpretq_f32_u32(vbicq_u32(bx, refused));  // refused lanes: zeros
    const float32x4_t y = vreinterpretq_f32_u32(vbicq_u32(by, refused));
    const float32x4_t z = vreinterpretq_f32_u32(vbicq_u32(bz, refused));
    const float32x4_t dx = vsubq_f32(x, ox);
    const float32x4_t dy = vsubq_f32(y, oy);
    const float32x4_t dz = vsubq_f32(z, oz);
    const float32x4_t r2 = vaddq_f32(vaddq_f32(vmulq_f32(dx, dx), vmulq_f32(dy, dy)), vmulq_f32(dz, dz));
    int32x4_t ix0;
    int32x4_t iy0;
    float32x4_t fx;
    float32x4_t fy;
    neon_floor_and_fraction(x, inv, &ix0, &fx, &far);
    neon_floor_and_fraction(y, inv, &iy0, &fy, &far);
    finish.store(i, refused, valid, ix0, iy0, fx, fy, z, r2, out);
  }
  *far_points = vmaxvq_u32(far) != 0U ? 1U : 0U;
  return done;
}

template <int kLayers>
std::size_t sensor_chunk_neon(const PointXYZ* __restrict points, std::size_t n, const FramePose& pose,
                              const FrontConfig& config, const FineSlot& fine, FrontChunk& __restrict out) noexcept {
  const NeonFinish<kLayers> finish(config, fine);
  const float32x4_t c0 = vdupq_n_f32(pose.rotation_cells[0]);
  const float32x4_t c1 = vdupq_n_f32(pose.rotation_cells[1]);
  const float32x4_t c2 = vdupq_n_f32(pose.rotation_cells[2]);
  const float32x4_t c3 = vdupq_n_f32(pose.rotation_cells[3]);
  const float32x4_t c4 = vdupq_n_f32(pose.rotation_cells[4]);
  const float32x4_t c5 = vdupq_n_f32(pose.rotation_cells[5]);
  const float32x4_t r6 = vdupq_n_f32(pose.rotation[6]);
  const float32x4_t r7 = vdupq_n_f32(pose.rotation[7]);
  const float32x4_t r8 = vdupq_n_f32(pose.rotation[8]);
  const float32x4_t fx0 = vdupq_n_f32(pose.anchor_fraction[0]);
  const float32x4_t fy0 = vdupq_n_f32(pose.anchor_fraction[1]);
  const float32x4_t oz = vdupq_n_f32(pose.origin[2]);
  const int32x4_t ax = vdupq_n_s32(pose.anchor.x);
  const int32x4_t ay = vdupq_n_s32(pose.anchor.y);
  const std::size_t done = n - n % 4U;
  for (std::size_t i = 0; i < done; i += 4U) {
    const float32x4x3_t p = vld3q_f32(&points[i].x);
    const uint32x4_t bx = vreinterpretq_u32_f32(p.val[0]);
    const uint32x4_t by = vreinterpretq_u32_f32(p.val[1]);
    const uint32x4_t bz = vreinterpretq_u32_f32(p.val[2]);
    uint32x4_t refused;
    const uint32x4_t valid = neon_validity(bx, by, bz, 0x45000000U, false, &refused);  // bits_of(2048.0F), exclusive
    const float32x4_t sx = vreinterpretq_f32_u32(vbicq_u32(bx, refused));  // refused lanes: zeros
    const float32x4_t sy = vreinterpretq_f32_u32(vbicq_u32(by, refused));
    const float32x4_t sz = vreinterpretq_f32_u32(vbicq_u32(bz, refused));
    const float32x4_t ux = vaddq_f32(vaddq_f32(vaddq_f32(vmulq_f32(c0, sx), vmulq_f32(c1, sy)), vmulq_f32(c2, sz)), fx0);
    const float32x4_t uy = vaddq_f32(vaddq_f32(vaddq_f32(vmulq_f32(c3, sx), vmulq_f32(c4, sy)), vmulq_f32(c5, sz)), fy0);
    const float32x4_t z = vaddq_f32(vaddq_f32(vaddq_f32(vmulq_f32(r6, sx), vmulq_f32(r7, sy)), vmulq_f32(r8, sz)), oz);
    const float32x4_t r2 = vaddq_f32(vaddq_f32(vmulq_f32(sx, sx), vmulq_f32(sy, sy)), vmulq_f32(sz, sz));
    const int32x4_t wx = vcvtmq_s32_f32(ux);  // floor
    const int32x4_t wy = vcvtmq_s32_f32(uy);
    finish.store(i, refused, valid, vaddq_s32(ax, wx), vaddq_s32(ay, wy), vsubq_f32(ux, vcvtq_f32_s32(wx)),
                 vsubq_f32(uy, vcvtq_f32_s32(wy)), z, r2, out);
  }
  return done;
}
#endif

// __restrict: the caller's points and the chunk never overlap (the chunk is the update path's
// own scratch), which lets the loops vectorise without run-time alias checks.
template <int kLayers>
CCMAP_FRONT_LOOP void map_chunk(const PointXYZ* __restrict points, std::size_t n, const FramePose& pose,
                                 const FrontConfig& config, const FineWindow& window,
                                 FrontChunk& __restrict out) noexcept {
  const std::uint32_t limit_bits = bits_of(kMaxAbsCoordinateM);
  const float inv = config.inv_width;
  const float ox = pose.origin[0];
  const float oy = pose.origin[1];
  const float oz = pose.origin[2];
  const FineSlot fine = fine_slot_of(window);
  std::uint32_t far = 0U;
  std::size_t first = 0U;
#if defined(CCMAP_FRONT_NEON)
  first = map_chunk_neon<kLayers>(points, n, pose, config, fine, out, &far);
#endif
  for (std::size_t i = first; i < n; ++i) {
    const std::int32_t valid = validity(bits_of(points[i].x), bits_of(points[i].y), bits_of(points[i].z), limit_bits, true);
    // Refused lanes compute on zeros: every conversion below stays in range.
    const float x = valid == 0 ? points[i].x : 0.0F;
    const float y = valid == 0 ? points[i].y : 0.0F;
    const float z = valid == 0 ? points[i].z : 0.0F;
    const float dx = x - ox;
    const float dy = y - oy;
    const float dz = z - oz;
    out.code[i] = valid;
    out.z[i] = z;
    out.range_sq[i] = dx * dx + dy * dy + dz * dz;
    far |= floor_and_fraction(x, inv, &out.ix0[i], &out.fx[i]);
    far |= floor_and_fraction(y, inv, &out.iy0[i], &out.fy[i]);
  }
  if (far != 0U) {
    // Products of 2^23 cells or more (cells narrower than 12 mm far from the origin): exactly,
    // and the Kalman slot from the exact index.
    for (std::size_t i = 0; i < n; ++i) {
      // Valid points only: routed (the NEON part, before `first`) or valid so far (0, after it).
      if (out.code[i] < std::int32_t{kFrontNonFinite}) {
        exact_cell(points[i].x, inv, &out.ix0[i], &out.fx[i]);
        exact_cell(points[i].y, inv, &out.iy0[i], &out.fy[i]);
      }
    }
    // The NEON part's slots from the exact indices (the portable part is finished below).
    finish_entries<kLayers>(0U, first, config.max_range_sq, fine, out);
  }
  finish_entries<kLayers>(first, n, config.max_range_sq, fine, out);
}


template <int kLayers>
CCMAP_FRONT_LOOP void sensor_chunk(const PointXYZ* __restrict points, std::size_t n, const FramePose& pose,
                                    const FrontConfig& config, const FineWindow& window,
                                    FrontChunk& __restrict out) noexcept {
  constexpr std::uint32_t kLimitBits = 0x45000000U;  // bits_of(2048.0F), exclusive
  const float c[6] = {pose.rotation_cells[0], pose.rotation_cells[1], pose.rotation_cells[2],
                      pose.rotation_cells[3], pose.rotation_cells[4], pose.rotation_cells[5]};
  const float r[9] = {pose.rotation[0], pose.rotation[1], pose.rotation[2], pose.rotation[3], pose.rotation[4],
                      pose.rotation[5], pose.rotation[6], pose.rotation[7], pose.rotation[8]};
  const float fx0 = pose.anchor_fraction[0];
  const float fy0 = pose.anchor_fraction[1];
  const std::int32_t ax = pose.anchor.x;
  const std::int32_t ay = pose.anchor.y;
  const float oz = pose.origin[2];
  const FineSlot fine = fine_slot_of(window);
  std::size_t first = 0U;
#if defined(CCMAP_FRONT_NEON)
  first = sensor_chunk_neon<kLayers>(points, n, pose, config, fine, out);
#endif
  for (std::size_t i = first; i < n; ++i) {
    const std::int32_t valid = validity(bits_of(points[i].x), bits_of(points[i].y), bits_of(points[i].z), kLimitBits, false);
    const float sx = valid == 0 ? points[i].x : 0.0F;
    const float sy = valid == 0 ? points[i].y : 0.0F;
    const float sz = valid == 0 ? points[i].z : 0.0F;
    // Offset from the anchor cell's corner in cells (|u| < 2^11 m * sqrt(3) * 1.001 / w_0 + 1 < 2^31).
    const float ux = c[0] * sx + c[1] * sy + c[2] * sz + fx0;
    const float uy = c[3] * sx + c[4] * sy + c[5] * sz + fy0;
    const float z = r[6] * sx + r[7] * sy + r[8] * sz + oz;
    const std::int32_t wx = floor_to_int32(ux);
    const std::int32_t wy = floor_to_int32(uy);
    out.code[i] = valid;
    out.z[i] = z;
    out.range_sq[i] = sx * sx + sy * sy + sz * sz;
    out.ix0[i] = ax + wx;  // |A| <= 2^30 + 1: no overflow
    out.iy0[i] = ay + wy;
    out.fx[i] = ux - static_cast<float>(wx);  // exact (Sterbenz)
    out.fy[i] = uy - static_cast<float>(wy);
  }
  if (pose.near_limit) {
    // The map-frame position must lie within kMaxAbsCoordinateM on every axis.
    for (std::size_t i = 0; i < n; ++i) {
      // Refused already (by validity): keep that reason. A routed or too-noisy point (the NEON
      // part is routed already) beyond the map's limit is out of range.
      if (out.code[i] == std::int32_t{kFrontNonFinite} || out.code[i] == std::int32_t{kFrontOutOfRange}) {
        continue;
      }
      const PointXYZ& s = points[i];
      const float mx = r[0] * s.x + r[1] * s.y + r[2] * s.z + pose.origin[0];
      const float my = r[3] * s.x + r[4] * s.y + r[5] * s.z + pose.origin[1];
      const float mz = out.z[i];
      if (std::fabs(mx) > kMaxAbsCoordinateM || std::fabs(my) > kMaxAbsCoordinateM || std::fabs(mz) > kMaxAbsCoordinateM) {
        out.code[i] = std::int32_t{kFrontOutOfRange};
        out.fine_slot[i] = -1;
      }
    }
  }
  finish_entries<kLayers>(first, n, config.max_range_sq, fine, out);
}

}  // namespace

CCMAP_FRONT_CLONES
void front_map_chunk(const PointXYZ* points, std::size_t n, const FramePose& pose, const FrontConfig& config,
                     const FineWindow& fine, FrontChunk& out) noexcept {
  static_assert(kFrontMaxLayers == 8, "one instance per layer count");
  switch (config.layers) {
    case 1U: map_chunk<1>(points, n, pose, config, fine, out); break;
    case 2U: map_chunk<2>(points, n, pose, config, fine, out); break;
    case 3U: map_chunk<3>(points, n, pose, config, fine, out); break;
    case 4U: map_chunk<4>(points, n, pose, config, fine, out); break;
    case 5U: map_chunk<5>(points, n, pose, config, fine, out); break;
    case 6U: map_chunk<6>(points, n, pose, config, fine, out); break;
    case 7U: map_chunk<7>(points, n, pose, config, fine, out); break;
    default: map_chunk<8>(points, n, pose, config, fine, out); break;
  }
}

CCMAP_FRONT_CLONES
void front_sensor_chunk(const PointXYZ* points, std::size_t n, const FramePose& pose, const FrontConfig& config,
                        const FineWindow& fine, FrontChunk& out) noexcept {
  switch (config.layers) {
    case 1U: sensor_chunk<1>(points, n, pose, config, fine, out); break;
    case 2U: sensor_chunk<2>(points, n, pose, config, fine, out); break;
    case 3U: sensor_chunk<3>(points, n, pose, config, fine, out); break;
    case 4U: sensor_chunk<4>(points, n, pose, config, fine, out); break;
    case 5U: sensor_chunk<5>(points, n, pose, config, fine, out); break;
    case 6U: sensor_chunk<6>(points, n, pose, config, fine, out); break;
    case 7U: sensor_chunk<7>(points, n, pose, config, fine, out); break;
    default: sensor_chunk<8>(points, n, pose, config, fine, out); break;
  }
}

}  // namespace ccmap::detail
