// The piece-wise constant Kalman layer's frame batch (docs/design.md 4.3, "Frame batches"): the
// frame's points of a Kalman cell are summed in integers, one record per cell (count, Q14
// heights, range keys: no float operation per point), and fused once at the end of the frame
// as one Kalman update with their mean height and the variance at their mean squared range
// divided by their count: the information form of the sequential updates.
//
// With the outlier gate on, every cell's record also holds the gate's integer interval for
// this frame, [low, low + span] in Q14, set for every cell at the start of the frame: the cell's
// height before the frame +- the half-width sqrt(k^2 (P + V)) (kalman_gate_half_width, floored
// to Q14); a never-observed cell's interval opens on its first point of the frame (that point's
// own height), on the rare path. A point outside is not summed: the caller holds it.
//
// Per point: an integer subtract and compare for the gate, three integer adds in registers (a
// run of points of one cell is summed before its record is touched); inside a run, four points
// at a time (NEON on aarch64: one compare of the slots, one of the gate, a pairwise widening add
// per sum). Per frame:
// O(cells of the layer) to open the intervals and to fuse. No heap, no exceptions.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#if defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#endif

#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/cell/outlier_gate.hpp"
#include "ccmap/map/update/fixed_point.hpp"

namespace ccmap::detail {

/// floor(v 2^14) for |v| <= 1e5 m (a Kalman cell's height: a mean of accepted heights).
/// Integrity: saturated at the int32 range (NaN: INT32_MIN), so that a cell an upset changed
/// converts without undefined behaviour (its check tells the readers; the gate only misjudges
/// its points for a frame, until the scrub resets it: map/detail/integrity.hpp).
[[nodiscard]] inline std::int32_t q14_floor_of(float v) noexcept {
  const float q = std::floor(v * kHeightQ14PerM);
  if (q >= -2147483648.0F && q < 2147483648.0F) {
    return static_cast<std::int32_t>(q);
  }
  return q > 0.0F ? std::int32_t{2147483647} : std::int32_t{-2147483647 - 1};
}

/// floor(v 2^14) of a gate half-width v >= 0 (m), saturated at 2^31 - 128 units (131 km). The
/// conversion is to int32 (a float -> int64 conversion is a soft-double call on 32-bit Arm: no
/// double may enter the core's image, tests/baremetal link.no_soft_double).
[[nodiscard]] inline std::int64_t q14_half_width(float v) noexcept {
  const float units = v * kHeightQ14PerM;
  return units < 2147483520.0F ? std::int64_t{static_cast<std::int32_t>(units)} : std::int64_t{2147483520};
}

/// The gate's interval of one cell for one frame in Q14: [low, low + span], clamped to int32
/// (a point's Q14 height is an int32, so clamping changes no decision; see inside()).
struct Q14Interval {
  std::int32_t low;
  std::uint32_t span;
};
[[nodiscard]] inline Q14Interval q14_interval(std::int32_t reference, std::int64_t half_width) noexcept {
  std::int64_t low = std::int64_t{reference} - half_width;
  std::int64_t high = std::int64_t{reference} + half_width;
  low = low < INT32_MIN ? INT32_MIN : low;
  high = high > INT32_MAX ? INT32_MAX : high;
  return Q14Interval{static_cast<std::int32_t>(low), static_cast<std::uint32_t>(high - low)};
}

/// Per-frame sums of one Kalman cell, each record rewritten whole at every frame's start
/// (begin_frame: whatever an upset did to it between frames never reaches a cell).
struct KalmanFrameSum {
  std::int32_t low;             ///< gate: lowest Q14 height inside (kOpenOnFirstPoint: not yet set)
  std::uint32_t span;           ///< gate: interval width (Q14); inside iff (uint32)(h - low) <= span
  std::uint32_t count;          ///< points summed (inside the gate)
  std::uint32_t reserved;       ///< 0 (keeps the 64-bit sums aligned)
  std::int64_t sum_height_q14;  ///< sum of floor(z * 2^14)
  std::int64_t sum_range_key;   ///< sum of range keys (2^-12 m^2)
};
static_assert(sizeof(KalmanFrameSum) == 32U, "one 32-byte record per cell");

/// The interval of a never-observed cell before its first point of the frame: low = INT32_MIN,
/// span = 0 holds only INT32_MIN, which no Q14 height of a validated point is (|z| <= 1.04e5 m).
inline constexpr std::int32_t kOpenOnFirstPoint = INT32_MIN;

template <std::size_t kCells>
class KalmanBatch {
 public:
  /// Empties every record (init).
  void clear() noexcept {
    for (KalmanFrameSum& sum : sums_) {
      sum = KalmanFrameSum{};
    }
  }

  /// Start of a frame: every record rewritten whole (integrity: the sums of the last frame and
  /// whatever an upset changed since are gone, map/detail/integrity.hpp). With the gate on
  /// (kGate), each cell's interval from its state (gate constants of the finest layer); without
  /// it the intervals are not read (add<false>) and stay 0.
  template <bool kGate>
  void begin_frame(const KalmanCell* cells, const GateConstants& gate) noexcept {
    for (std::size_t c = 0; c < kCells; ++c) {
      KalmanFrameSum sum{};
      if constexpr (kGate) {
        const KalmanCell& cell = cells[c];
        if (cell.weight > 0.0F) {
          const Q14Interval i =
              q14_interval(q14_floor_of(cell.height), q14_half_width(kalman_gate_half_width(cell, gate)));
          sum.low = i.low;
          sum.span = i.span;
        } else {
          sum.low = kOpenOnFirstPoint;
        }
      } else {
        (void)cells;
        (void)gate;
      }
      sums_[c] = sum;
    }
  }

  /// A run of consecutive points of one cell (stereo rows put tens of points in a row into one
  /// finest cell): their sums are kept in registers and added to the cell's record once.
  struct Run {
    std::int32_t slot = -1;
    std::int32_t low = 0;
    std::uint32_t span = 0U;
    std::uint32_t count = 0U;
    std::uint32_t flushed = 0U;  ///< points of earlier runs added to their records
    std::int64_t sum_height_q14 = 0;
    std::int64_t sum_range_key = 0;
  };

  /// Starts a run of cell `slot` (the previous one flushed first): the cell's gate interval.
  /// The run's `flushed` carries over (the points summed so far by this Run object).
  /// Integrity: the slot is masked to the records (kCells is a power of two), so that no value
  /// of it indexes past them.
  void start(Run& run, std::int32_t slot) noexcept {
    flush(run);
    const std::uint32_t masked = static_cast<std::uint32_t>(slot) & kSlotMask;
    const KalmanFrameSum& sum = sums_[masked];
    run.slot = static_cast<std::int32_t>(masked);
    run.low = sum.low;
    run.span = sum.span;
  }

  /// Adds a point of the run's cell if it is inside the cell's gate (kGate; always without);
  /// false: outside, not added (the caller holds it). `gate` opens a never-observed cell's
  /// interval on its first point of the frame.
  template <bool kGate>
  [[nodiscard]] bool add(Run& run, std::int32_t h, std::int32_t key, const GateConstants& gate) noexcept {
    if constexpr (kGate) {
      if (static_cast<std::uint32_t>(h) - static_cast<std::uint32_t>(run.low) > run.span) {
        if (run.low != kOpenOnFirstPoint || run.span != 0U) {
          return false;
        }
        // The cell's first point of the frame: inside by construction.
        KalmanFrameSum& sum = sums_[static_cast<std::uint32_t>(run.slot)];
        open(sum, h, gate);
        run.low = sum.low;
        run.span = sum.span;
      }
    } else {
      (void)gate;
    }
    ++run.count;
    run.sum_height_q14 += h;
    run.sum_range_key += key;
    return true;
  }

  /// Adds entries i, i+1, ... to the run while they are points of the run's cell (slots[j] ==
  /// run.slot) inside its gate (kGate; all of them without); returns the first entry not taken
  /// (i itself when entry i is outside the gate: the caller takes it alone with add()). The
  /// common case of the frame batch: blocks of four points that are all of the run and all
  /// inside are summed at once (take_block: NEON on aarch64, ~4 instructions a point with the
  /// gate); the run's tail, and a block that fails, go one point at a time (about a dozen
  /// instructions a point). Integer sums: the same totals in any order, so the blocks change no
  /// bit of the map.
  template <bool kGate>
  [[nodiscard]] std::size_t add_while_inside(Run& run, const std::int32_t* slots, const std::int32_t* heights,
                                             const std::int32_t* keys, std::size_t i, std::size_t count) noexcept {
    const std::int32_t slot = run.slot;
    const auto low = static_cast<std::uint32_t>(run.low);
    const std::uint32_t span = run.span;
    BlockSums blocks{};
    std::size_t j = i;
    while (j + kBlock <= count && take_block<kGate>(slot, low, span, slots + j, heights + j, keys + j, blocks)) {
      j += kBlock;
    }
    std::int64_t sum_height = blocks.total_height();
    std::int64_t sum_key = blocks.total_key();
    // The tail one by one: entry i itself (the caller matched its slot), or the next entry if it
    // is still of the run.
    if (j == i || (j < count && slots[j] == slot)) {
      do {
        const std::int32_t h = heights[j];
        if constexpr (kGate) {
          if (static_cast<std::uint32_t>(h) - low > span) {
            break;
          }
        }
        sum_height += h;
        sum_key += keys[j];
        ++j;
      } while (j < count && slots[j] == slot);
    }
    run.count += static_cast<std::uint32_t>(j - i);
    run.sum_height_q14 += sum_height;
    run.sum_range_key += sum_key;
    return j;
  }

  /// Adds the run's sums to its cell's record; the run is then empty (same cell).
  void flush(Run& run) noexcept {
    if (run.count > 0U) {
      KalmanFrameSum& sum = sums_[static_cast<std::uint32_t>(run.slot)];
      sum.count += run.count;
      sum.sum_height_q14 += run.sum_height_q14;
      sum.sum_range_key += run.sum_range_key;
      run.flushed += run.count;
      run.count = 0U;
      run.sum_height_q14 = 0;
      run.sum_range_key = 0;
    }
  }

  /// Adds one point to cell `slot` alone (a point outside a run: weighted input).
  template <bool kGate>
  [[nodiscard]] bool add(std::uint32_t slot, std::int32_t h, std::int32_t key, const GateConstants& gate) noexcept {
    Run run{};
    start(run, static_cast<std::int32_t>(slot));
    const bool inside = add<kGate>(run, h, key, gate);
    flush(run);
    return inside;
  }

  /// The frame's sums of cell `slot` (masked to the records: integrity).
  [[nodiscard]] const KalmanFrameSum& sum(std::uint32_t slot) const noexcept { return sums_[slot & kSlotMask]; }

  /// End of the frame: fuse(slot, sum) for every cell that summed points. The sums stay
  /// readable (the change rule reads the counts) until the next begin_frame rewrites them.
  template <typename Fuse>
  void fuse(Fuse&& fuse_cell) const noexcept {
    for (std::size_t c = 0; c < kCells; ++c) {
      if (sums_[c].count > 0U) {
        fuse_cell(static_cast<std::uint32_t>(c), sums_[c]);
      }
    }
  }

 private:
  /// Points per block of add_while_inside.
  static constexpr std::size_t kBlock = 4U;

#if defined(__aarch64__) && defined(__ARM_NEON)
  /// The blocks' sums: two 64-bit lanes each (pairwise sums of the 32-bit entries).
  struct BlockSums {
    int64x2_t height = vdupq_n_s64(0);
    int64x2_t key = vdupq_n_s64(0);
    [[nodiscard]] std::int64_t total_height() const noexcept { return vaddvq_s64(height); }
    [[nodiscard]] std::int64_t total_key() const noexcept { return vaddvq_s64(key); }
  };

  /// Sums the four entries at slots/heights/keys into `sums` if all four are of cell `slot` and
  /// (kGate) inside [low, low + span]; false (nothing summed) otherwise.
  template <bool kGate>
  [[nodiscard]] static bool take_block(std::int32_t slot, std::uint32_t low, std::uint32_t span, const std::int32_t* slots,
                                       const std::int32_t* heights, const std::int32_t* keys, BlockSums& sums) noexcept {
    uint32x4_t ok = vceqq_s32(vld1q_s32(slots), vdupq_n_s32(slot));
    const int32x4_t h = vld1q_s32(heights);
    if constexpr (kGate) {
      const uint32x4_t offset = vsubq_u32(vreinterpretq_u32_s32(h), vdupq_n_u32(low));
      ok = vandq_u32(ok, vcleq_u32(offset, vdupq_n_u32(span)));
    } else {
      (void)low;
      (void)span;
    }
    if (vminvq_u32(ok) == 0U) {
      return false;
    }
    sums.height = vpadalq_s32(sums.height, h);
    sums.key = vpadalq_s32(sums.key, vld1q_s32(keys));
    return true;
  }
#else
  /// The blocks' sums (portable: the compiler may vectorise take_block's four lanes).
  struct BlockSums {
    std::int64_t height = 0;
    std::int64_t key = 0;
    [[nodiscard]] std::int64_t total_height() const noexcept { return height; }
    [[nodiscard]] std::int64_t total_key() const noexcept { return key; }
  };

  /// As the NEON take_block: the four entries summed if all are of cell `slot` and inside.
  template <bool kGate>
  [[nodiscard]] static bool take_block(std::int32_t slot, std::uint32_t low, std::uint32_t span, const std::int32_t* slots,
                                       const std::int32_t* heights, const std::int32_t* keys, BlockSums& sums) noexcept {
    bool ok = true;
    for (std::size_t l = 0; l < kBlock; ++l) {
      ok = ok && slots[l] == slot;
      if constexpr (kGate) {
        ok = ok && static_cast<std::uint32_t>(heights[l]) - low <= span;
      }
    }
    if (!ok) {
      return false;
    }
    for (std::size_t l = 0; l < kBlock; ++l) {
      sums.height += heights[l];
      sums.key += keys[l];
    }
    return true;
  }
#endif

  /// Opens a never-observed cell's interval on its first point h of the frame.
  static void open(KalmanFrameSum& sum, std::int32_t h, const GateConstants& gate) noexcept {
    const Q14Interval i = q14_interval(h, q14_half_width(kalman_gate_half_width(KalmanCell{}, gate)));
    sum.low = i.low;
    sum.span = i.span;
  }

  /// Integrity: record indices are masked with this (map/detail/integrity.hpp).
  static constexpr std::uint32_t kSlotMask = static_cast<std::uint32_t>(kCells - 1U);
  static_assert((kCells & (kCells - 1U)) == 0U, "record indices are masked: kCells must be a power of two");

  KalmanFrameSum sums_[kCells]{};  // zero-initialised: a static stack lives in .bss
};

/// One Kalman batch update of `count` > 0 points with these sums: their mean height (the floored
/// Q14 mean, + half a unit: unbiased) and their mean range key (+ half a key likewise) in m^2,
/// for the caller to turn into the measurement variance.
struct BatchMean {
  float height_m;
  float range_sq_m2;
};
[[nodiscard]] inline BatchMean batch_mean(std::int64_t sum_height_q14, std::int64_t sum_range_key,
                                          std::uint32_t count) noexcept {
  const auto n = static_cast<std::int64_t>(count);
  std::int64_t whole = sum_height_q14 / n;
  std::int64_t rest = sum_height_q14 % n;
  if (rest < 0) {
    --whole;
    rest += n;
  }
  const float nf = static_cast<float>(n);
  const float mean_q14 = static_cast<float>(whole) + (static_cast<float>(rest) + 0.5F * nf) / nf;
  const std::int64_t whole_key = sum_range_key / n;  // keys are >= 0
  const std::int64_t rest_key = sum_range_key % n;
  const float mean_key = static_cast<float>(whole_key) + (static_cast<float>(rest_key) + 0.5F * nf) / nf;
  return BatchMean{mean_q14 * kHeightMPerQ14, mean_key * kRangeKeyM2};
}

}  // namespace ccmap::detail
