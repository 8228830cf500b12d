// Every line of sight of a frame at once (docs/design.md, "Free space from lines of sight",
// "Every line of sight"): the viewshed table. The rays of one frame share their origin, so
// instead of walking each, every sampled routed point (every point, or one in 2, 4, 8, 16)
// writes one entry: the lowest line-of-sight slope of the points whose rays end in its (azimuth
// sector, range bin). One sweep per sector then gives, for every bin, the lowest ray that
// reaches beyond it, and a map cell reads its bound from the sectors that lie wholly inside its
// azimuth interval. Used by the free-space stage (free_space.hpp) when
// StackParams::free_space_rays selects it (sight_stride_of_rays); the update path feeds it chunk
// by chunk while the front's output is in L1 (map/update/update_path.hpp).
//
// Geometry (horizontal positions in finest cells from the sensor, heights in m):
//  - azimuth: the diamond angle a in [0, 4) of (dx, dy) (monotonic in the true angle, one
//    division, no trigonometry); sector = floor(a * kSightSectors / 4), at most 8 / kSightSectors
//    rad wide (0.0078 rad: a CADRE window's narrowest cell, 0.022 rad at its corner, holds one);
//  - range: the ray's walked length, its horizontal length shortened by kSightRangeSigmas range
//    errors (d (1 - k sigma(r) / r)), on a square-root scale: bin = floor(sqrt(d_walked) *
//    bin_scale), clamped to the last bin;
//  - slope: t = (z - z0) / d of the point (d its horizontal distance, m), quantised UP to
//    kSightSlopeUnit (an upper bound stays one); the line of sight is z0 + t s at distance s.
// An entry (bin b, sector k) holds the lowest slope of the rays of sector k whose walked part
// reaches at least edge(b) = (b / bin_scale)^2 cells and less than edge(b + 1); the sweep turns it
// into the lowest slope of those reaching edge(b) or beyond.
// Soundness (tests/map/sight_table_test.cpp holds it to the exact integer walk on random
// frames): a cell's bound comes only from sectors inside its azimuth interval (every such ray
// crosses the cell) whose rays reach beyond the cell's farthest corner, evaluated at the cell's
// nearest (descending ray) or farthest (rising ray) corner: never below the height at which such
// a ray crosses the cell.
//
// Cost (docs/performance.md 13): a key pass over the sampled points of the front's chunk (NEON on
// aarch64), one scattered minimum per sampled point, a sweep over the table, then the cells the
// frame's rays reach: per CADRE frame 17.9 M aarch64 instructions fed by every point, 3.9 M by
// one in 8 (within the 4 M for the stage). No heap.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#if defined(__aarch64__)
#include <arm_neon.h>
#endif

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/map/update/front.hpp"

namespace ccmap {

/// The mark a Config carries when its stack holds the table.
struct EveryLineOfSightTag {};

/// A Config that carries the viewshed table (261 KB per stack, not in the presets: the C API's
/// storage sizes and the presets' memory stay as they are): WithEveryLineOfSight<CadreConfig>.
/// Its stack casts every line of sight when StackParams::free_space_rays is
/// detail::kFreeSpaceEveryRay (65535), those of one point in k at
/// detail::free_space_table_rays(k) = 65536 - k (k = 2, 4, 8, 16), and walks sampled rays at any
/// other value, as the presets do.
template <typename Base>
struct WithEveryLineOfSight : Base, EveryLineOfSightTag {};

template <typename Config>
inline constexpr bool kConfigEveryLineOfSight = std::is_base_of_v<EveryLineOfSightTag, Config>;

}  // namespace ccmap

namespace ccmap::detail {

/// The free_space_rays value that selects every line of sight (the viewshed table) instead of a
/// sample of walked rays.
inline constexpr float kFreeSpaceEveryRay = 65535.0F;

/// Largest stride of the sampled table: every 16th point.
inline constexpr int kSightMaxStride = 16;

/// The free_space_rays value that selects the viewshed table fed by every stride-th point of the
/// frame (stride 1, 2, 4, 8 or 16): 65536 - stride (65535: every line of sight; 65532: every
/// fourth point). The table's soundness does not depend on the stride (a subset of the frame's
/// rays); its coverage does.
[[nodiscard]] inline constexpr float free_space_table_rays(int stride) noexcept {
  return 65536.0F - static_cast<float>(stride);
}

/// The table's stride a free_space_rays value selects on a stack that carries the table: 0 (the
/// sampled walk) below free_space_table_rays(kSightMaxStride), else 65536 - rays rounded down to
/// a power of two (1 .. kSightMaxStride).
[[nodiscard]] inline constexpr int sight_stride_of_rays(float free_space_rays) noexcept {
  if (!(free_space_rays >= free_space_table_rays(kSightMaxStride))) {
    return 0;
  }
  const int gap = free_space_rays >= kFreeSpaceEveryRay ? 1 : static_cast<int>(65536.0F - free_space_rays);
  int stride = 1;
  while (stride * 2 <= gap && stride < kSightMaxStride) {
    stride *= 2;
  }
  return stride;
}

/// Range errors by which every line of sight is shortened before its point. The sampled walk's
/// 3 (free_space.hpp) leaves 0.27 % of the rays reaching past their true point: harmless for 128
/// rays, ~1,500 of a CADRE frame's 552,500, each a ray under real ground, and the table keeps
/// minima. At 5 about 0.3 rays a frame.
inline constexpr float kSightRangeSigmas = 5.0F;

inline constexpr int kSightSectorBits = 10;
inline constexpr int kSightSectors = 1 << kSightSectorBits;  ///< diamond-angle sectors
inline constexpr int kSightBins = 64;                         ///< square-root range bins
inline constexpr std::size_t kSightEntries = std::size_t{kSightSectors} * kSightBins;
static_assert(kSightEntries == 65536U, "a key is 16 bits: every key names an entry");
/// An entry no ray wrote: no bound.
inline constexpr std::int16_t kSightEmpty = 32767;
/// Slope unit of an entry: 2^-12 (2.4 mm of height at 10 m), entries span slopes of +-8.
inline constexpr float kSightSlopeUnit = 0.000244140625F;
inline constexpr float kSightSlopeUnitsInv = 4096.0F;

/// The constants of a frame's table (derived per frame from the pose and the stage's init).
struct SightFrameConstants {
  float sensor_u[2];     ///< sensor position in finest cells from the anchor cell's corner
  float z0;              ///< sensor height (m)
  float bin_scale;       ///< bins per sqrt(cell)
  float cell_width_m;    ///< w_0 (m)
  float sigma_c[3];      ///< kSightRangeSigmas sigma(r) = c0 + c1 r + c2 r^2 (m)
  float view_axis[3];    ///< sensor-frame viewing direction (all zero: not given)
  bool view_axis_set;
  std::int32_t layers;   ///< routed codes below this cast rays
  std::int32_t stride;   ///< one point in stride casts a line of sight (SightTable::stride_of)
  std::int32_t phase;    ///< the sampled groups' offset in their block (SightTable::sampled_point)
};

/// What the table says about one cell (SightTable::read_cell).
struct SightCell {
  int lo, hi;            ///< sectors wholly inside the cell's azimuth interval: [lo, hi), modulo kSightSectors
  int bin;               ///< first bin whose rays reach beyond the cell's farthest corner
  float s_near, s_far;   ///< nearest and farthest distance of the cell (finest cells)
  std::int32_t qmin;     ///< lowest slope over those sectors (kSightSlopeUnit)
  std::int32_t qmax;     ///< highest slope over those holding one
  int covered;           ///< sectors holding a slope
};

class SightTable;
/// What a stack without the table carries in its place.
struct NoSightTable {};

/// What the update path feeds the free-space stage with in table mode (free_space.hpp,
/// begin_sight): the table, chunk by chunk, and what the frame's confirmations read
/// (docs/design.md 12): per cell, the highest of the points the frame folded into it (m, map
/// frame; -infinity: none), which the stage compares with the cell's surface after the frame as
/// a walked ray's point is (FreeSpace::on_surface). For a CCM cell the points are the first of
/// each run of consecutive points folded into it (a store a run: every point's would cost the
/// flight cycle more than its budget leaves, docs/performance.md 13), for an OMG cell every
/// point; a Kalman finest layer needs none (the stage reads its frame batch's mean,
/// KalmanFrameSum). Frame scratch, reset by begin_sight: an upset in it can confirm a cell (keep
/// it one more frame) or miss one confirmation, never empty a cell by itself.
struct SightFeed {
  SightTable* table = nullptr;
  float* ccm_top = nullptr;   ///< per CCM cell, in the layers' storage order (LayerSet::ccm_storage)
  float* fine_top = nullptr;  ///< per finest cell of a piece-wise constant (OMG) layer; else nullptr
};

class SightTable {
 public:
  /// Empties the table for a new frame.
  void begin(const SightFrameConstants& k) noexcept {
    k_ = k;
    k_.stride = stride_of(k.stride);
    k_.phase = phase_of(k_.stride, k.phase);
    for (std::size_t i = 0; i < kSightEntries; ++i) {
      raw_[i] = kSightEmpty;
    }
    points_ = 0U;
    refused_ = 0U;
  }

  [[nodiscard]] const SightFrameConstants& constants() const noexcept { return k_; }
  /// Points that wrote an entry this frame.
  [[nodiscard]] std::uint32_t points() const noexcept { return points_; }
  /// Points given this frame that cast no line of sight (not routed, a bad weight, behind the
  /// sensor).
  [[nodiscard]] std::uint32_t refused() const noexcept { return refused_; }

  /// The chunk's sampled points (the front's output for count <= kFrontChunkPoints points):
  /// one in constants().stride, sampled_point(j, stride, phase) for j = 0, 1, ... (chunks start
  /// at multiples of kFrontChunkPoints, so the pattern repeats over the frame). sensor: the chunk's
  /// sensor-frame points (for the view axis) or nullptr; weights: the chunk's map-frame weights
  /// or nullptr (a point with a bad weight casts no ray).
  void add_chunk(const FrontChunk& chunk, std::size_t count, const PointXYZ* sensor, const float* weights,
                 CellIndex anchor) noexcept {
    if (count > kFrontChunkPoints) {
      count = kFrontChunkPoints;  // integrity: the front never gives more
    }
    std::uint32_t written = 0U;
    switch (k_.stride) {
      case 2: written = key_pass<2>(chunk, count, anchor); break;
      case 4: written = key_pass<4>(chunk, count, anchor); break;
      case 8: written = key_pass<8>(chunk, count, anchor); break;
      case 16: written = key_pass<16>(chunk, count, anchor); break;
      default: written = key_pass<1>(chunk, count, anchor); break;
    }
    const int stride = stride_of(k_.stride);
    const int phase = k_.phase;
    const std::size_t sampled = sampled_count(count, stride, phase);
    constexpr std::uint32_t kRefused = static_cast<std::uint16_t>(kSightEmpty);
    // Refusals the key pass does not see (scalar, only when given).
    if (sensor != nullptr && k_.view_axis_set) {
      for (std::size_t j = 0; j < sampled; ++j) {
        const PointXYZ& s = sensor[sampled_point(j, stride, phase)];
        if (!(s.x * k_.view_axis[0] + s.y * k_.view_axis[1] + s.z * k_.view_axis[2] > 0.0F) &&
            packed_[j] != kRefused) {
          packed_[j] = kRefused;
          --written;
        }
      }
    }
    if (weights != nullptr) {
      for (std::size_t j = 0; j < sampled; ++j) {
        if (ccm_check_weight(weights[sampled_point(j, stride, phase)]) != Status::kOk && packed_[j] != kRefused) {
          packed_[j] = kRefused;
          --written;
        }
      }
    }
    // Pass 2: the scattered minimum. The key is the upper 16 bits: always inside the table.
    // Two points a turn, each a load, a compare and a store only when lower (the table's base
    // in a register: 8.5 aarch64 instructions a point instead of 11 for the plain select);
    // in order, so two points of one entry leave the lower slope.
    std::int16_t* const table = raw_;
    const std::uint32_t* const packed = packed_;
    std::size_t i = 0;
    for (; i + 2U <= sampled; i += 2U) {
      store_min(table, packed[i]);
      store_min(table, packed[i + 1U]);
    }
    if (i < sampled) {
      store_min(table, packed[i]);
    }
    points_ += written;
    refused_ += static_cast<std::uint32_t>(sampled) - written;
  }

  /// The stride a table samples with: a power of two in [1, kSightMaxStride] (any other value
  /// reads as 1).
  [[nodiscard]] static constexpr int stride_of(int stride) noexcept {
    return (stride == 2 || stride == 4 || stride == 8 || stride == 16) ? stride : 1;
  }

  /// The chunk index of the j-th point a table of this stride samples: groups of four points
  /// min(stride, 4) apart, one group in every 4 stride points, `phase` points into its block
  /// (phase_of). Strides 1, 2, 4: every stride-th point; 8 and 16: points phase + 0, 4, 8, 12
  /// of every 32 or 64 (one de-interleaving load per field and group: vld4).
  [[nodiscard]] static constexpr std::size_t sampled_point(std::size_t j, int stride, int phase) noexcept {
    const auto s = static_cast<std::size_t>(stride_of(stride));
    return (j / 4U) * (4U * s) + static_cast<std::size_t>(phase_of(stride, phase)) + (j % 4U) * (s < 4U ? s : 4U);
  }
  /// How many of a chunk's first `count` points a table of this stride and phase samples.
  [[nodiscard]] static constexpr std::size_t sampled_count(std::size_t count, int stride, int phase) noexcept {
    std::size_t j = (count / (4U * static_cast<std::size_t>(stride_of(stride)))) * 4U;
    while (sampled_point(j, stride, phase) < count) {
      ++j;
    }
    return j;
  }
  /// The phase a table of this stride uses: 0 for strides up to 4 (the group fills its block);
  /// for 8 and 16, `phase` modulo the 4 stride - 15 offsets at which a group of 16 points lies
  /// wholly inside its block (so a turn's loads never leave the chunk).
  [[nodiscard]] static constexpr int phase_of(int stride, int phase) noexcept {
    const int s = stride_of(stride);
    if (s <= 4) {
      return 0;
    }
    const int span = 4 * s - 15;
    if (phase >= 0 && phase < span) {
      return phase;  // begin() stores it so: no division per chunk
    }
    const int p = phase % span;
    return p < 0 ? p + span : p;
  }

  /// table[w >> 16] = min(it, the slope in w's lower 16 bits).
  static void store_min(std::int16_t* table, std::uint32_t w) noexcept {
    const auto q = static_cast<std::int16_t>(static_cast<std::uint16_t>(w & 0xFFFFU));
    const std::uint32_t at = w >> 16;
    if (q < table[at]) {
      table[at] = q;
    }
  }

  /// Lower edge of bin b (finest cells): (b / bin_scale)^2.
  [[nodiscard]] float edge(int b) const noexcept {
    const float e = static_cast<float>(b) / k_.bin_scale;
    return e * e;
  }

  /// The sweep, far to near: swept(b, k) = the lowest slope of sector k's rays that reach
  /// edge(b) or beyond (kSightEmpty: none). Vectorisable across sectors.
  void sweep() noexcept {
    std::int16_t* last = swept_ + static_cast<std::size_t>(kSightBins - 1) * kSightSectors;
    std::memcpy(last, raw_ + static_cast<std::size_t>(kSightBins - 1) * kSightSectors, sizeof(std::int16_t) * kSightSectors);
    for (int b = kSightBins - 2; b >= 0; --b) {
      const std::int16_t* row = raw_ + static_cast<std::size_t>(b) * kSightSectors;
      const std::int16_t* next = swept_ + static_cast<std::size_t>(b + 1) * kSightSectors;
      std::int16_t* out = swept_ + static_cast<std::size_t>(b) * kSightSectors;
      for (int k = 0; k < kSightSectors; ++k) {
        out[k] = row[k] < next[k] ? row[k] : next[k];
      }
    }
    // Sectors holding a ray at all (bin 0 after the sweep), counted before each of the
    // 2 kSightSectors positions a cell's [lo, hi) can name: read_cell's test for "none".
    sectors_with_rays_[0] = 0U;
    for (int k = 0; k < 2 * kSightSectors; ++k) {
      const bool any = swept_[static_cast<std::size_t>(k & (kSightSectors - 1))] != kSightEmpty;
      sectors_with_rays_[k + 1] = static_cast<std::uint16_t>(sectors_with_rays_[k] + (any ? 1U : 0U));
    }
    find_reach();
  }

  /// After sweep(): the columns [*lo, *hi] (of 0 .. side - 1) of the window row whose cells are
  /// [bx + i cw, bx + (i + 1) cw] x [y0, y1] (finest cells from the sensor) that read_cell may
  /// bound: those within the farthest ray's reach and, when the frame's rays lie within half a
  /// turn, inside the wedge of sectors holding them (widened by a sector each side and a column
  /// each end against rounding). False if none. Every cell outside the span reads nothing
  /// (SightTable.ReadsNothingOutsideTheRowSpans): the cells pass skips it without reading it.
  [[nodiscard]] bool row_span(float y0, float y1, float bx, float cw, std::int32_t side, std::int32_t* lo,
                              std::int32_t* hi) const noexcept {
    if (!any_ray_) {
      return false;
    }
    const float ny = y0 > 0.0F ? y0 : (y1 < 0.0F ? -y1 : 0.0F);
    const float room = reach_sq_ - ny * ny;
    if (!(room >= 0.0F)) {
      return false;
    }
    const float hx = std::sqrt(room);
    const float inv = 1.0F / cw;
    float first = std::floor((-hx - cw - bx) * inv);
    float last = std::ceil((hx - bx) * inv);
    if (wedge_) {
      // The wedge's clockwise edge: some corner with cross(e_lo, p) >= 0.
      const float yl = e_lo_[0] >= 0.0F ? y1 : y0;
      if (e_lo_[1] > 0.0F) {
        last = clamp_min(last, std::ceil((e_lo_[0] * yl / e_lo_[1] - bx) * inv));
      } else if (e_lo_[1] < 0.0F) {
        first = clamp_max(first, std::floor((e_lo_[0] * yl / e_lo_[1] - bx - cw) * inv));
      } else if (e_lo_[0] * yl < 0.0F) {
        return false;
      }
      // Its counter-clockwise edge: some corner with cross(e_hi, p) <= 0.
      const float yh = e_hi_[0] >= 0.0F ? y0 : y1;
      if (e_hi_[1] > 0.0F) {
        first = clamp_max(first, std::floor((e_hi_[0] * yh / e_hi_[1] - bx - cw) * inv));
      } else if (e_hi_[1] < 0.0F) {
        last = clamp_min(last, std::ceil((e_hi_[0] * yh / e_hi_[1] - bx) * inv));
      } else if (e_hi_[0] * yh > 0.0F) {
        return false;
      }
    }
    const float top = static_cast<float>(side - 1);
    first = first > 0.0F ? first - 1.0F : 0.0F;
    last = last < top ? last + 1.0F : top;
    if (!(first <= last)) {  // also NaN
      return false;
    }
    *lo = static_cast<std::int32_t>(first);
    *hi = static_cast<std::int32_t>(last);
    return true;
  }

  /// After sweep(): the ground each sector's points showed before bin b, turning raw_ into it
  /// (height from the sensor in 2^-10 m; read it with ground()): near to far, the
  /// lowest point of each bin that holds points is the ground there, unless it rose faster than
  /// max_slope (per finest cell of distance) plus noise_m from the ground before (a rock, a
  /// rover: the ground stays the level before it until a bin comes back within noise_m of it).
  /// An approximation for the drop-off rule's reference (a point's height from its bin's middle
  /// distance), not a bound.
  /// Cost: only the sectors some point wrote are tracked (a sector no point wrote holds
  /// kSightEmpty in every bin, which is also its answer: no ground), one sector at a time.
  /// Only the bins up to the farthest any ray reaches are turned (read_cell bounds no cell
  /// beyond them, so no rule reads the ground there).
  void track_ground(float max_slope, float noise_m) noexcept {
    const int bins = reach_bin_ + 1;  // 0 when no ray reaches a bin
    // The lowest entry of each sector over the bins (vectorisable across sectors).
    std::int16_t lowest[kSightSectors];
    std::memcpy(lowest, raw_, sizeof(lowest));
    for (int b = 1; b < bins; ++b) {
      const std::int16_t* row = raw_ + static_cast<std::size_t>(b) * kSightSectors;
      for (int k = 0; k < kSightSectors; ++k) {
        lowest[k] = row[k] < lowest[k] ? row[k] : lowest[k];
      }
    }
    const float unit_m = kSightSlopeUnit * k_.cell_width_m;
    float mid[kSightBins];
    float per_unit[kSightBins];  // height (m) of one slope unit at the bin's middle
    for (int b = 0; b < kSightBins; ++b) {
      mid[b] = 0.5F * (edge(b) + edge(b + 1));
      per_unit[b] = unit_m * mid[b];
    }
    for (int k = 0; k < kSightSectors; ++k) {
      if (lowest[k] == kSightEmpty) {
        continue;
      }
      float ground = 0.0F;
      float prev_h = 0.0F;
      float prev_s = 0.0F;
      std::int32_t state = 0;  // 0 no ground yet, 1 on ground, 2 on an obstacle
      for (int b = 0; b < bins; ++b) {
        std::int16_t& entry = raw_[static_cast<std::size_t>(b) * kSightSectors + static_cast<std::size_t>(k)];
        const std::int16_t q = entry;
        // Ground before this bin, in 2^-10 m from the sensor (kSightEmpty: none).
        float g = ground * 1024.0F;
        g = g < -32767.0F ? -32767.0F : (g > 32766.0F ? 32766.0F : g);
        entry = state == 0 ? kSightEmpty : static_cast<std::int16_t>(g);
        if (q == kSightEmpty) {
          continue;
        }
        const float h = static_cast<float>(q) * per_unit[b];
        if (state == 0) {
          ground = h;
          state = 1;
        } else if (state == 1) {
          if (h > prev_h + max_slope * (mid[b] - prev_s) + noise_m) {
            state = 2;
          } else {
            ground = h;
          }
        } else if (h <= ground + noise_m) {
          state = 1;
          ground = h;
        }
        prev_h = h;
        prev_s = mid[b];
      }
    }
  }

  /// After track_ground(): the ground of sector k before bin b (m from the sensor); false if
  /// its points showed none.
  [[nodiscard]] bool ground(int b, int k, float* height_m) const noexcept {
    const std::int16_t g = raw_[static_cast<std::size_t>(b) * kSightSectors + static_cast<std::size_t>(k & (kSightSectors - 1))];
    *height_m = static_cast<float>(g) * 0.0009765625F;
    return g != kSightEmpty;
  }

  /// Lowest quantised slope of sector k for rays reaching bin b or beyond (kSightEmpty: none).
  [[nodiscard]] std::int16_t slope(int b, int k) const noexcept {
    return swept_[static_cast<std::size_t>(b) * kSightSectors + static_cast<std::size_t>(k & (kSightSectors - 1))];
  }

  /// The lowest quantised slope of the points whose walked rays end in entry (b, k);
  /// kSightEmpty if none.
  [[nodiscard]] std::int16_t raw(int b, int k) const noexcept {
    return raw_[static_cast<std::size_t>(b) * kSightSectors + static_cast<std::size_t>(k & (kSightSectors - 1))];
  }

  /// The sectors wholly inside the azimuth interval of the cell [x0, x1] x [y0, y1] (finest
  /// cells from the sensor, the sensor outside it): [lo, hi) (hi may exceed kSightSectors: taken
  /// modulo). False if none.
  [[nodiscard]] static bool sectors_inside(float x0, float x1, float y0, float y1, float per_unit, int* lo,
                                           int* hi) noexcept {
    float a[4] = {diamond(x0, y0), diamond(x1, y0), diamond(x0, y1),
                  diamond(x1, y1)};
    float amin = a[0], amax = a[0];
    for (float v : a) {
      amin = v < amin ? v : amin;
      amax = v > amax ? v : amax;
    }
    if (amax - amin > 2.0F) {
      // The interval wraps through 0: shift the small angles by a full turn.
      amin = 4.0F;
      amax = 0.0F;
      for (float& v : a) {
        v = v < 2.0F ? v + 4.0F : v;
        amin = v < amin ? v : amin;
        amax = v > amax ? v : amax;
      }
    }
    // A margin of 1/64 sector each side against the rounding of the corners' and points' angles.
    const float first = std::ceil(amin * per_unit + 0.015625F);
    const float last = std::floor(amax * per_unit - 0.015625F);
    if (!(last - first >= 1.0F)) {
      return false;
    }
    *lo = static_cast<int>(first);
    *hi = static_cast<int>(last);
    return true;
  }

  /// After sweep(): the bound of the cell [x0, x1] x [y0, y1] (finest cells from the sensor):
  /// false if the sensor lies in it, no sector lies wholly inside its azimuth interval, no bin
  /// reaches beyond it or no ray of those sectors does. The terrain the rays of sector s crossed in the cell
  /// lies below z0 + q(s) kSightSlopeUnit w_0 (q < 0 ? s_near : s_far) (m).
  [[nodiscard]] bool read_cell(float x0, float x1, float y0, float y1, SightCell* out) const noexcept {
    if (x0 <= 0.0F && x1 >= 0.0F && y0 <= 0.0F && y1 >= 0.0F) {
      return false;
    }
    const float nx = x0 > 0.0F ? x0 : (x1 < 0.0F ? -x1 : 0.0F);
    const float ny = y0 > 0.0F ? y0 : (y1 < 0.0F ? -y1 : 0.0F);
    const float fx = x0 * x0 > x1 * x1 ? x0 * x0 : x1 * x1;
    const float fy = y0 * y0 > y1 * y1 ? y0 * y0 : y1 * y1;
    SightCell c{};
    c.s_far = std::sqrt(fx + fy);
    c.bin = first_bin_beyond(c.s_far);
    if (c.bin >= kSightBins ||
        !sectors_inside(x0, x1, y0, y1, static_cast<float>(kSightSectors) * 0.25F, &c.lo, &c.hi)) {
      return false;
    }
    // A cell whose sectors hold no ray at all (most cells outside the camera's view) ends here.
    if (c.lo < 0 || c.hi > 2 * kSightSectors || sectors_with_rays_[c.hi] == sectors_with_rays_[c.lo]) {
      return false;
    }
    scan_sectors(&c);
    if (c.covered == 0) {
      return false;
    }
    c.s_near = std::sqrt(nx * nx + ny * ny);
    *out = c;
    return true;
  }

  /// Diamond angle in [0, 4) of a horizontal direction (0 for the zero vector).
  [[nodiscard]] static float diamond(float dx, float dy) noexcept {
    const float ax = dx < 0.0F ? -dx : dx;
    const float ay = dy < 0.0F ? -dy : dy;
    const float l1 = ax + ay;
    const float p = dy / (l1 > 0.0F ? l1 : 1.0F);
    return dx >= 0.0F ? (dy >= 0.0F ? p : 4.0F + p) : 2.0F - p;
  }

  /// The bin of a walked length of `cells` finest cells (the last bin beyond the table).
  [[nodiscard]] int bin_of(float cells) const noexcept {
    const float b = std::sqrt(cells > 0.0F ? cells : 0.0F) * k_.bin_scale;
    return b < static_cast<float>(kSightBins - 1) ? static_cast<int>(b) : kSightBins - 1;
  }

  /// First bin whose rays reach `cells` finest cells (kSightBins if none can be trusted to).
  [[nodiscard]] int first_bin_beyond(float cells) const noexcept {
    // edge(b) >= cells  <=>  b >= sqrt(cells) * scale; raised by 2^-16 against the rounding of
    // the square roots and products here and in the points' bins (a few ulps each).
    const float b = std::ceil(std::sqrt(cells > 0.0F ? cells : 0.0F) * k_.bin_scale * 1.0000153F);
    return b < static_cast<float>(kSightBins) ? static_cast<int>(b) : kSightBins;
  }

 private:
  /// Pass 1 of add_chunk: key and quantised slope of the chunk's points sampled_point(j, S, phase)
  /// into packed_[j]; returns the points that cast a ray. On aarch64 a group of four points at a
  /// time in NEON (GCC does not vectorise the plain loop there: -fmath-errno puts a branch after
  /// each sqrt), the lanes loaded de-interleaved (vld2/vld4); the same IEEE operations in the
  /// same order as the scalar loop, which finishes the chunk.
  template <int S>
  std::uint32_t key_pass(const FrontChunk& chunk, std::size_t count, CellIndex anchor) noexcept {
    const float sx = k_.sensor_u[0];
    const float sy = k_.sensor_u[1];
    const float c0 = k_.sigma_c[0];
    const float c1 = k_.sigma_c[1];
    const float c2 = k_.sigma_c[2];
    const float scale = k_.bin_scale;
    const float z0 = k_.z0;
    const float w0 = k_.cell_width_m;
    const std::int32_t layers = k_.layers;
    const float sectors_per_unit = static_cast<float>(kSightSectors) * 0.25F;
    // A point that casts no ray writes kSightEmpty to entry 0: a minimum that changes nothing.
    constexpr std::uint32_t kRefused = static_cast<std::uint16_t>(kSightEmpty);
    std::uint32_t written = 0U;
    std::size_t first = 0;  // the first sampled point the scalar loop takes (its index / S)
#if defined(__aarch64__)
    {
      const int32x4_t vax = vdupq_n_s32(anchor.x);
      const int32x4_t vay = vdupq_n_s32(anchor.y);
      const float32x4_t vsx = vdupq_n_f32(sx);
      const float32x4_t vsy = vdupq_n_f32(sy);
      const float32x4_t zero = vdupq_n_f32(0.0F);
      const float32x4_t one = vdupq_n_f32(1.0F);
      const float32x4_t two = vdupq_n_f32(2.0F);
      const float32x4_t four = vdupq_n_f32(4.0F);
      const float32x4_t last_bin = vdupq_n_f32(static_cast<float>(kSightBins - 1));
      const float32x4_t lo_q = vdupq_n_f32(-32767.0F);
      const float32x4_t hi_q = vdupq_n_f32(32767.0F);
      const uint32x4_t sector_mask = vdupq_n_u32(kSightSectors - 1U);
      const uint32x4_t refused = vdupq_n_u32(kRefused);
      const uint32x4_t low16 = vdupq_n_u32(0xFFFFU);
      uint32x4_t cast = vdupq_n_u32(0U);
      const uint32x4_t vlayers = vdupq_n_u32(static_cast<std::uint32_t>(layers));
      constexpr std::size_t kBlock = 4U * static_cast<std::size_t>(S);  // points of a group's turn
      // The group's first point in its block; its 4 min(S, 4) points lie inside the block.
      const auto phase = static_cast<std::size_t>(phase_of(S, k_.phase));
      for (std::size_t i = 0; i + kBlock <= count; i += kBlock) {
        const std::size_t j = (i / kBlock) * 4U;
        const std::size_t at = i + phase;
        first = j + 4U;
        const float32x4_t dx = vaddq_f32(vcvtq_f32_s32(vsubq_s32(lanes<S>(chunk.ix0 + at), vax)),
                                         vsubq_f32(lanes<S>(chunk.fx + at), vsx));
        const float32x4_t dy = vaddq_f32(vcvtq_f32_s32(vsubq_s32(lanes<S>(chunk.iy0 + at), vay)),
                                         vsubq_f32(lanes<S>(chunk.fy + at), vsy));
        const float32x4_t l1 = vaddq_f32(vabsq_f32(dx), vabsq_f32(dy));
        const uint32x4_t l1_pos = vcgtq_f32(l1, zero);
        // Lanes with l1 = 0 or d = 0 are refused (ok below): no guard on their divisions.
        const float32x4_t p = vdivq_f32(dy, l1);
        const float32x4_t right = vbslq_f32(vcgeq_f32(dy, zero), p, vaddq_f32(four, p));
        const float32x4_t a = vbslq_f32(vcgeq_f32(dx, zero), right, vsubq_f32(two, p));
        const uint32x4_t sector =
            vandq_u32(vreinterpretq_u32_s32(vcvtq_s32_f32(vmulq_n_f32(a, sectors_per_unit))), sector_mask);
        const float32x4_t rsq = lanes<S>(chunk.range_sq + at);
        const float32x4_t r = vsqrtq_f32(rsq);
        const float32x4_t margin =
            vaddq_f32(vaddq_f32(vdupq_n_f32(c0), vmulq_n_f32(r, c1)), vmulq_n_f32(rsq, c2));
        const uint32x4_t r_pos = vcgtq_f32(r, zero);
        const float32x4_t f = vsubq_f32(one, vdivq_f32(margin, vbslq_f32(r_pos, r, one)));
        const float32x4_t d = vsqrtq_f32(vaddq_f32(vmulq_f32(dx, dx), vmulq_f32(dy, dy)));
        const float32x4_t walked = vmulq_f32(d, f);
        // walked >= 0 in every lane that is not refused (d > 0, f > 0).
        float32x4_t b = vmulq_n_f32(vsqrtq_f32(walked), scale);
        b = vbslq_f32(vcltq_f32(b, last_bin), b, last_bin);
        const uint32x4_t bin = vreinterpretq_u32_s32(vcvtq_s32_f32(b));
        const uint32x4_t code = vreinterpretq_u32_s32(lanes<S>(chunk.code + at));
        const uint32x4_t d_pos = vcgtq_f32(d, zero);
        const uint32x4_t ok =
            vandq_u32(vandq_u32(vcltq_u32(code, vlayers), vandq_u32(l1_pos, d_pos)), vcgtq_f32(f, zero));
        const float32x4_t t = vdivq_f32(vsubq_f32(lanes<S>(chunk.z + at), vdupq_n_f32(z0)), vmulq_n_f32(d, w0));
        // Clamped as the scalar loop clamps (FMAX/FMIN: the same for the finite slopes of the
        // lanes that are not refused).
        const float32x4_t q = vminq_f32(vmaxq_f32(vrndpq_f32(vmulq_n_f32(t, kSightSlopeUnitsInv)), lo_q), hi_q);
        const uint32x4_t key = vorrq_u32(vshlq_n_u32(bin, kSightSectorBits), sector);
        const uint32x4_t slope = vandq_u32(vreinterpretq_u32_s32(vcvtq_s32_f32(q)), low16);
        vst1q_u32(packed_ + j, vbslq_u32(ok, vorrq_u32(vshlq_n_u32(key, 16), slope), refused));
        cast = vsubq_u32(cast, ok);  // ok lanes are all ones: minus -1
      }
      written += vaddvq_u32(cast);
    }
#else
#endif
    for (std::size_t j = first; sampled_point(j, S, k_.phase) < count; ++j) {
      const std::size_t i = sampled_point(j, S, k_.phase);
      const float dx = static_cast<float>(chunk.ix0[i] - anchor.x) + (chunk.fx[i] - sx);
      const float dy = static_cast<float>(chunk.iy0[i] - anchor.y) + (chunk.fy[i] - sy);
      const float ax = dx < 0.0F ? -dx : dx;
      const float ay = dy < 0.0F ? -dy : dy;
      const float l1 = ax + ay;
      const float p = dy / (l1 > 0.0F ? l1 : 1.0F);
      const float a = dx >= 0.0F ? (dy >= 0.0F ? p : 4.0F + p) : 2.0F - p;
      const float rsq = chunk.range_sq[i];
      const float r = std::sqrt(rsq);
      const float margin = c0 + c1 * r + c2 * rsq;
      const float f = 1.0F - margin / (r > 0.0F ? r : 1.0F);
      const float d = std::sqrt(dx * dx + dy * dy);
      const float walked = d * f;
      float b = std::sqrt(walked > 0.0F ? walked : 0.0F) * scale;
      b = b < static_cast<float>(kSightBins - 1) ? b : static_cast<float>(kSightBins - 1);
      const bool ok = static_cast<std::uint32_t>(chunk.code[i]) < static_cast<std::uint32_t>(layers) && l1 > 0.0F &&
                      d > 0.0F && f > 0.0F;
      // A slope of 8 or more bounds nothing: the entry's empty value; below -8: -8 (higher, safe).
      const float t = (chunk.z[i] - z0) / (d > 0.0F ? d * w0 : 1.0F);
      float q = std::ceil(t * kSightSlopeUnitsInv);
      q = q < -32767.0F ? -32767.0F : (q > 32767.0F ? 32767.0F : q);
      if (!ok) {
        packed_[j] = kRefused;
        continue;
      }
      const std::uint32_t sector =
          static_cast<std::uint32_t>(static_cast<std::int32_t>(a * sectors_per_unit)) & (kSightSectors - 1U);
      const std::uint32_t key = (static_cast<std::uint32_t>(static_cast<std::int32_t>(b)) << kSightSectorBits) | sector;
      packed_[j] = (key << 16) | (static_cast<std::uint32_t>(static_cast<std::int32_t>(q)) & 0xFFFFU);
      ++written;
    }
    return written;
  }

#if defined(__aarch64__)
  /// Values p[0], p[g], p[2 g], p[3 g], g = min(S, 4) (a group of sampled_point): one load.
  template <int S>
  // cppcheck-suppress unusedPrivateFunction ; called as lanes<S>(chunk.fx + at) above, which cppcheck does not resolve
  static float32x4_t lanes(const float* p) noexcept {
    if constexpr (S == 1) {
      return vld1q_f32(p);
    } else if constexpr (S == 2) {
      return vld2q_f32(p).val[0];
    } else {
      return vld4q_f32(p).val[0];
    }
  }
  template <int S>
  static int32x4_t lanes(const std::int32_t* p) noexcept {
    if constexpr (S == 1) {
      return vld1q_s32(p);
    } else if constexpr (S == 2) {
      return vld2q_s32(p).val[0];
    } else {
      return vld4q_s32(p).val[0];
    }
  }
#endif

  /// The lowest and highest slope of bin c->bin over the sectors [c->lo, c->hi) that hold one,
  /// and how many do (on aarch64 eight sectors a turn, the last turn's lanes beyond hi masked;
  /// integer operations: the scalar loop's answer).
  void scan_sectors(SightCell* c) const noexcept {
    const std::int16_t* row = swept_ + static_cast<std::size_t>(c->bin) * kSightSectors;
#if defined(__aarch64__)
    // The interval [lo, hi) taken modulo kSightSectors: at most two runs of the row.
    const int lo = c->lo & (kSightSectors - 1);
    const int n = c->hi - c->lo;
    const int first_run = n < kSightSectors - lo ? n : kSightSectors - lo;
    const int16x8_t empty = vdupq_n_s16(kSightEmpty);
    const int16x8_t lowest = vdupq_n_s16(-32768);
    static constexpr std::int16_t kLane[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    const int16x8_t lane = vld1q_s16(kLane);
    int16x8_t vmin = empty;
    int16x8_t vmax = lowest;
    uint16x8_t count = vdupq_n_u16(0U);
    const int starts[2] = {lo, 0};
    const int lengths[2] = {first_run, n - first_run};
    for (int r = 0; r < 2; ++r) {
      const std::int16_t* p = row + starts[r];
      for (int done = 0; done < lengths[r]; done += 8, p += 8) {
        // Reads up to 7 entries past the run: swept_ is padded by kSightPad entries.
        const int16x8_t v = vld1q_s16(p);
        const uint16x8_t in = vcltq_s16(lane, vdupq_n_s16(static_cast<std::int16_t>(lengths[r] - done)));
        const uint16x8_t has = vandq_u16(in, vmvnq_u16(vceqq_s16(v, empty)));
        vmin = vminq_s16(vmin, vbslq_s16(has, v, empty));
        vmax = vmaxq_s16(vmax, vbslq_s16(has, v, lowest));
        count = vsubq_u16(count, has);
      }
    }
    c->qmin = vminvq_s16(vmin);
    c->qmax = vmaxvq_s16(vmax);
    c->covered = static_cast<int>(vaddvq_u16(count));
#else
    std::int32_t qmin = kSightEmpty;
    std::int32_t qmax = -32768;
    int covered = 0;
    for (int s = c->lo; s < c->hi; ++s) {
      const std::int32_t q = row[s & (kSightSectors - 1)];
      if (q != kSightEmpty) {
        qmin = q < qmin ? q : qmin;
        qmax = q > qmax ? q : qmax;
        ++covered;
      }
    }
    c->qmin = qmin;
    c->qmax = qmax;
    c->covered = covered;
#endif
  }

  static float clamp_min(float a, float b) noexcept { return b < a ? b : a; }  // min; a NaN b leaves a
  static float clamp_max(float a, float b) noexcept { return b > a ? b : a; }  // max; a NaN b leaves a

  /// The frame's reach and wedge (row_span), from the swept table: the reach is the upper edge
  /// of the farthest bin any ray reaches (a cell nearer than it by its nearest corner may read a
  /// bound); the wedge is the complement of the longest circular run of sectors holding no ray,
  /// widened by one sector each side, used when it spans less than half a turn.
  void find_reach() noexcept {
    int reach_bin = -1;
    for (int b = kSightBins - 1; b >= 0 && reach_bin < 0; --b) {
      const std::int16_t* row = swept_ + static_cast<std::size_t>(b) * kSightSectors;
      std::int16_t low = kSightEmpty;
      for (int k = 0; k < kSightSectors; ++k) {
        low = row[k] < low ? row[k] : low;
      }
      reach_bin = low != kSightEmpty ? b : -1;
    }
    reach_bin_ = reach_bin;
    any_ray_ = reach_bin >= 0;
    wedge_ = false;
    if (!any_ray_) {
      return;
    }
    const float reach = edge(reach_bin + 1);
    reach_sq_ = reach * reach;
    // The longest run of empty sectors, going round twice (a run through sector 0).
    int best = 0, best_end = 0, run = 0;
    for (int k = 0; k < 2 * kSightSectors; ++k) {
      const bool empty = sectors_with_rays_[k + 1] == sectors_with_rays_[k];
      run = empty ? (run < kSightSectors ? run + 1 : run) : 0;
      if (run > best) {
        best = run;
        best_end = k + 1;
      }
    }
    // Sectors holding rays: [best_end, best_end - best + kSightSectors), widened by one each side.
    const int width = kSightSectors - best + 2;
    if (width >= kSightSectors / 2) {
      return;
    }
    const float per_sector = 4.0F / static_cast<float>(kSightSectors);
    diamond_direction(static_cast<float>((best_end - 1) & (kSightSectors - 1)) * per_sector, e_lo_);
    diamond_direction(static_cast<float>((best_end - 1 + width) & (kSightSectors - 1)) * per_sector, e_hi_);
    wedge_ = true;
  }

  /// The direction (L1 length 1) whose diamond angle is a (in [0, 4)).
  static void diamond_direction(float a, float* e) noexcept {
    if (a < 1.0F) {
      e[0] = 1.0F - a;
      e[1] = a;
    } else if (a < 3.0F) {
      e[1] = 2.0F - a;
      e[0] = -(1.0F - (e[1] < 0.0F ? -e[1] : e[1]));
    } else {
      e[0] = a - 3.0F;
      e[1] = a - 4.0F;
    }
  }

  SightFrameConstants k_{};
  bool any_ray_ = false;   ///< some ray of the frame reaches a bin (find_reach)
  int reach_bin_ = -1;     ///< the farthest bin some ray reaches (-1: none)
  bool wedge_ = false;     ///< the frame's rays lie within the wedge e_lo_ .. e_hi_ (counter-clockwise)
  float reach_sq_ = 0.0F;  ///< squared reach of the farthest ray (finest cells^2)
  float e_lo_[2]{}, e_hi_[2]{};
  std::uint32_t points_ = 0U;
  std::uint32_t refused_ = 0U;
  /// Per point of a chunk: key (bin << kSightSectorBits | sector) << 16 | quantised slope.
  std::uint32_t packed_[kFrontChunkPoints]{};
  std::int16_t raw_[kSightEntries]{};  ///< [bin][sector]
  /// Entries past the table that scan_sectors' last turn may read (and masks off).
  static constexpr std::size_t kSightPad = 8U;
  std::int16_t swept_[kSightEntries + kSightPad]{};
  /// sectors_with_rays_[i]: sectors k < i (taken modulo kSightSectors) holding a ray (sweep()).
  std::uint16_t sectors_with_rays_[2 * kSightSectors + 1]{};
};

}  // namespace ccmap::detail
