// Free space from lines of sight (docs/design.md, "Free space from lines of sight"): after the
// points of a frame are folded in, a bounded subsample of lines of sight, from the sensor to the
// frame's points, is walked over every layer (map/visibility/ray_walk.hpp): the frame's even
// subsample gives the slots, each with kRayCandidates candidates, and the candidates whose lines
// of sight cross hidden ground, pass below a known cell's top just before a point on ground below
// it, or cross a contradicted cell are walked first (choose, score_candidate). A line of sight says
// the terrain along it lies below it:
//  - a cell whose surface the rays pass clearly below, in kContradictionsPerFrame rays of a
//    frame, in free_space_clear_frames frames with no ray ending on the surface in between, is
//    emptied (a rover that drove on, a ghost of a bad pose) and counted (cleared_cells);
//  - an unobserved cell gets an upper bound on its terrain (FreeSpaceCell), and is a drop-off when
//    kDropRays rays proved one in it: a ray passed over it, or over a later cell of the same run
//    of unobserved cells (the same layer, no known cell in between), more than its layer's
//    obstacle height below the ground it crossed last (a crater, a ditch, the far side of a
//    ledge); the ground follows the known cells along the ray and climbs at most
//    max_inclination: a rock is not ground, so its shadow is not a drop (drop_cells;
//    CellClass::kDropOff in queries).
// Owned by Stack<Config> beside the layers; one record per cell of every layer, moved with the
// windows (a cell that leaves a window loses its record exactly as the cell is cleared). A
// Config with kFreeSpace = false gets FreeSpace<Config, false>: no storage, no work.
//
// Refused rays change nothing: points the front refuses (non-finite, out of range, too noisy),
// points with a bad weight, sensor-frame points behind the sensor (StackParams::sensor_view_axis),
// every ray of a frame whose sensor no window holds (counted: free_rays_refused). A refused frame
// (a non-finite origin, ...) never reaches this stage.
//
// Margins (derived at init, per layer; the design section gives the argument):
//  - the walk ends kRangeSigmas sigma_m(r) short of the point along the ray (sigma_m the noise
//    model's range error at the point's range r): before that the ray is the line of sight to the
//    true point, which clears the terrain by definition, unless the range error exceeds 3 sigma;
//    no cell holding the point itself is judged by its ray;
//  - a surface is contradicted only where its top (a CCM cell: mean + sqrt(3) sigma_zz; a
//    constant cell: its height) stands above the ray by more than clear_margin =
//    max(obstacle_fraction w, kRangeSigmas sigma_k, for a constant cell kRangeSigmas sqrt(V_k)),
//    sigma_k the largest range error the layer receives and V_k the outlier gate's floor variance
//    (range error and the steepest traversable plane across the cell): the layer's obstacle
//    height, more than the steepest traversable plane rises across a cell (0.36 w), and three
//    range errors; and, in the sampled walk, for a CCM cell also where the ray crosses it: its
//    least-squares plane plus sqrt(3) sigma_s stands above the ray by that margin at the ray's
//    entry or exit (below_surface), so a ray over the low side of a cell that also holds a rock
//    face contradicts nothing;
//  - a point confirms the surface of its cell (and cancels the evidence against it) when it lies
//    no more than kRangeSigmas sigma_k below the cell's mean (on_surface): in the sampled walk
//    the walked rays' points, with the viewshed table the points the frame folded in
//    (SightFeed, confirm_cell).
//
// The coupling to the front is one adapter, ray_end_of(): the fields of a FrontChunk entry this
// stage reads (routing code, finest cell and float position inside it, squared range), the
// position made U units (8 fraction bits, map/visibility/ray_walk.hpp) by ray_u().
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/cell/outlier_gate.hpp"
#include "ccmap/grid/ring_grid.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/map/update/front.hpp"
#include "ccmap/map/update/gate.hpp"
#include "ccmap/map/update/kalman_batch.hpp"
#include "ccmap/map/visibility/free_space_cell.hpp"
#include "ccmap/map/visibility/ray_walk.hpp"
#include "ccmap/map/visibility/sight_table.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap::detail {

/// Standard deviations of the range noise by which a ray is shortened before its point, and of
/// the margins (the outlier gate's default k).
inline constexpr float kRangeSigmas = 3.0F;
/// Cells whose first contradiction of a frame is remembered for the frame's end (beyond it, the
/// frame's further contradicted cells wait for a later frame).
inline constexpr std::size_t kMaxContradictedCells = 1024U;
/// Candidates per walked line of sight in the sampled walk (the presets'): the frame's even
/// subsample brings this many points per slot, and the slots of a batch walk the lines of sight
/// that prove most (score_candidate). A Config may set its own (WithRayCandidates).
inline constexpr std::size_t kRayCandidates = 4U;
template <typename Config, typename = void>
struct ConfigRayCandidates {
  static constexpr std::size_t value = kRayCandidates;
};
template <typename Config>
struct ConfigRayCandidates<Config, std::void_t<decltype(Config::kRayCandidates)>> {
  static constexpr std::size_t value = Config::kRayCandidates;
};
/// Cells (of a candidate's routed layer) before its point that are read for hidden ground and for
/// a known top above the line of sight.
inline constexpr int kHiddenCellsBack = 2;
/// Cells with evidence against them that a frame's candidates aim at.
inline constexpr std::uint32_t kMaxTargets = 16U;
/// Records find_targets reads as words at once (a multiple of 2: two 4-byte records a word).
inline constexpr std::size_t kAimGroup = 16U;
/// Level added to a candidate whose line of sight crosses such a cell, or passes below the top of a
/// known cell of the kHiddenCellsBack before its point by the clear margin and ends more than that
/// margin below the cell's mean (score_candidate).
inline constexpr std::uint32_t kTargetLevel = 3U;
/// Levels of a candidate: 0 refused, 1 routed, up to 1 + kHiddenCellsBack + kTargetLevel.
inline constexpr std::uint32_t kLevels = 8U;
inline constexpr std::uint8_t kLevelMask = 0x07U;
static_assert(kLevelMask + 1U == kLevels && 1U + static_cast<std::uint32_t>(kHiddenCellsBack) + kTargetLevel < kLevels,
              "a masked level indexes the level counts");
inline constexpr std::uint8_t kSlotPoint = 0x40U;  ///< the slot's own point (the even subsample)
inline constexpr std::uint8_t kChosen = 0x80U;
/// Unobserved cells of one run along a ray that a drop-off proved further along the run can mark
/// (the nearest ones first; a longer run's later cells are marked only by their own bound).
inline constexpr std::size_t kMaxRunCells = 64U;

/// The end of a sampled point's line of sight, as the front computed it.
struct RayEnd {
  std::int32_t code;  ///< routed layer, or kFrontNonFinite / kFrontOutOfRange / kFrontTooNoisy
  std::int64_t u[2];  ///< horizontal position in U units (ray_walk.hpp), valid when routed
  float z;            ///< map-frame height (m), valid when routed
  float range_sq;     ///< squared range from the sensor (m^2)
};

/// The adapter to the front's chunk representation: the only place this stage reads a FrontChunk.
[[nodiscard]] inline RayEnd ray_end_of(const FrontChunk& chunk, std::size_t i) noexcept {
  return RayEnd{chunk.code[i],
                {ray_u(chunk.ix0[i], chunk.fx[i]), ray_u(chunk.iy0[i], chunk.fy[i])},
                chunk.z[i],
                chunk.range_sq[i]};
}

/// The finest window the front is given here: none (this stage reads no Kalman slot).
inline constexpr FineWindow kNoFineWindow{CellIndex{0, 0}, 0, 0};

/// The sensor's horizontal position in U units (the pose's anchor cell and fraction).
inline void ray_origin_of(const FramePose& pose, std::int64_t* u) noexcept {
  u[0] = ray_u(pose.anchor.x, pose.anchor_fraction[0]);
  u[1] = ray_u(pose.anchor.y, pose.anchor_fraction[1]);
}

/// Per-frame constants of a layer (derived at init).
struct FreeSpaceLayerConstants {
  float clear_margin_m;  ///< a surface above the ray by more than this contradicts it
  float step_m;          ///< obstacle_fraction * w: the drop a drop-off must have
  float rise_margin_m;   ///< ground tracking: noise allowance of a known cell's height (sigma_k)
};

template <typename Config, bool kEnabled = kConfigFreeSpace<Config>>
class FreeSpace;

/// A Config without free space: no storage, no work, no drop-offs.
template <typename Config>
class FreeSpace<Config, false> {
 public:
  using Layers = LayerSet<Config>;
  static constexpr bool kEnabled = false;
  [[nodiscard]] Status init(const StackParams&, const float*, const Layers&) noexcept { return Status::kOk; }
  void set_constants(const StackParams&, const float*, const Layers&) noexcept {}
  void follow(int, CellIndex) noexcept {}
  [[nodiscard]] const SightFeed* begin_sight(const FramePose&, const KalmanFrameSum*) noexcept { return nullptr; }
  void run_map(Layers&, const StackParams&, const FrontConfig&, FrontChunk&, const PointXYZ*, const float*,
               std::size_t, const FramePose&, FrameCounters&) noexcept {}
  void run_sensor(Layers&, const StackParams&, const FrontConfig&, FrontChunk&, const PointXYZ*, std::size_t,
                  const FramePose&, FrameCounters&) noexcept {}
  [[nodiscard]] const RingGrid<FreeSpaceCell>* records(int) const noexcept { return nullptr; }
  [[nodiscard]] RingGrid<FreeSpaceCell>* records(int) noexcept { return nullptr; }
  [[nodiscard]] std::uint32_t frames() const noexcept { return 0U; }
  void set_frames(std::uint32_t) noexcept {}
  [[nodiscard]] const CellCheck* record_checks(int) const noexcept { return nullptr; }
  void reseal_records() noexcept {}
  [[nodiscard]] std::uint32_t scrub(std::uint32_t) noexcept { return 0U; }
  void hash_bindings(StateHasher&) const noexcept {}
  [[nodiscard]] bool clear_marked(std::uint32_t) const noexcept { return false; }
  template <typename Fn>
  void for_each_clear_mark(Fn&&) const noexcept {}
  void drop_clear_mark(std::uint32_t) noexcept {}
  void clear_all_marks() noexcept {}
  [[nodiscard]] bool record_at(int, CellIndex, FreeSpaceCell* out) const noexcept {
    *out = FreeSpaceCell{};
    return false;
  }
  void merge_drop_at(int, CellIndex, float, std::uint32_t) noexcept {}
  void raise_evidence_at(int, CellIndex, std::uint32_t) noexcept {}
  void reset_record_at(int, CellIndex) noexcept {}
  [[nodiscard]] std::uint32_t clear_frames() const noexcept { return 0U; }
};

template <typename Config>
class FreeSpace<Config, true> {
 public:
  using Layers = LayerSet<Config>;
  static constexpr bool kEnabled = true;
  static constexpr int kLayerCount = Layers::kLayerCount;
  static constexpr std::size_t kFineRecords = Layers::kHasFine ? Layers::kFineCellCount : 0U;
  static constexpr std::size_t kCcmRecords = Layers::kCcmLayerCount > 0 ? Layers::kCcmCellCount : 0U;
  static constexpr std::size_t kRecordCount = kFineRecords + kCcmRecords;
  static constexpr std::size_t kCandidates = ConfigRayCandidates<Config>::value;
  static_assert(kCandidates >= 1U && kCandidates <= kFrontChunkPoints, "candidates per line of sight: 1 .. a front chunk");

  /// Binds one record grid per layer (centred on the origin, every record empty, as init leaves
  /// the layers) and derives the margins. max_range_sq_m2: the routing table's squared ranges.
  [[nodiscard]] Status init(const StackParams& params, const float* max_range_sq_m2, const Layers& layers) noexcept {
    std::size_t offset = 0U;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const std::int32_t side = Layers::side(layer);
      if (grids_[layer].init(records_ + offset, side, layers.widths[layer], layers.centre(layer)) != Status::kOk) {
        return Status::kInvalidArgument;
      }
      offset_[layer] = offset;
      offset += static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
    }
    set_constants(params, max_range_sq_m2, layers);
    frames_ = 0U;
    contradicted_count_ = 0U;
    reseal_records();
    scrub_cursor_ = 0U;
    return Status::kOk;
  }

  /// The constants of init() alone (margins, ray count, clear frames, view axis); the records
  /// and the frame count kept (Stack::set_params).
  void set_constants(const StackParams& params, const float* max_range_sq_m2, const Layers& layers) noexcept {
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const float width = layers.widths[layer];
      const float sigma = layer_max_sigma(params, max_range_sq_m2[layer], width, Layers::is_ccm(layer));
      const float step = params.obstacle_fraction * width;
      float margin = kRangeSigmas * sigma;
      if (!Layers::is_ccm(layer)) {
        // A constant cell has no spread of its own: the gate's floor (range error and the
        // steepest traversable plane across the cell) stands for it.
        margin = kRangeSigmas * std::sqrt(gate_floor_variance(sigma, width, params.max_inclination));
      }
      consts_[layer] = FreeSpaceLayerConstants{margin > step ? margin : step, step, sigma};
    }
    max_inclination_ = params.max_inclination;
    rays_ = static_cast<std::uint32_t>(params.free_space_rays);
    sight_stride_ = kSight ? sight_stride_of_rays(params.free_space_rays) : 0;
    every_ = sight_stride_ > 0;
    // Square-root bins up to the farthest window corner (finest cells from the sensor, which
    // lies near the windows' centre: the half diagonal, 0.71 of the side, and a margin).
    float reach = 1.0F;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const float extent = static_cast<float>(Layers::side(layer)) * static_cast<float>(std::int32_t{1} << layer);
      reach = extent * 0.75F > reach ? extent * 0.75F : reach;
    }
    bin_scale_ = static_cast<float>(kSightBins) / std::sqrt(reach);
    const sensor::NoiseModel& noise = params.noise;
    // kSightRangeSigmas sigma(r) as c0 + c1 r + c2 r^2 from the model's values at 0, 1 and 2 m.
    const float s0 = noise.sigma_at_range_sq(0.0F), s1 = noise.sigma_at_range_sq(1.0F), s2 = noise.sigma_at_range_sq(4.0F);
    sigma_c_[0] = kSightRangeSigmas * s0;
    sigma_c_[2] = kSightRangeSigmas * 0.5F * (s2 - 2.0F * s1 + s0);
    sigma_c_[1] = kSightRangeSigmas * (s1 - s0) - sigma_c_[2];
    clear_frames_ = static_cast<std::uint32_t>(params.free_space_clear_frames);
    view_axis_[0] = params.sensor_view_axis[0];
    view_axis_[1] = params.sensor_view_axis[1];
    view_axis_[2] = params.sensor_view_axis[2];
    view_axis_set_ = !(view_axis_[0] >= 0.0F && view_axis_[0] <= 0.0F && view_axis_[1] >= 0.0F &&
                       view_axis_[1] <= 0.0F && view_axis_[2] >= 0.0F && view_axis_[2] <= 0.0F);
    cell_width_ = layers.widths[0];
  }

  /// The record grid of `layer` follows the layer's window to `centre` (Stack::move_to calls it
  /// after each layer's move): records that leave are cleared, as the cells are.
  void follow(int layer, CellIndex centre) noexcept {
    if (layer >= 0 && layer < kLayerCount) {
      const CellIndex old_min = grids_[layer].window_min();
      (void)grids_[layer].move_to(centre);  // cannot fail: the layer accepted the same centre
      // Integrity: the records the move cleared have check 0 again.
      clear_checks_after_move(checks_ + offset_[layer], Layers::side(layer), old_min, grids_[layer].window_min());
    }
  }

  /// Table mode (free_space_rays >= free_space_table_rays(kSightMaxStride)): empties the viewshed table
  /// and the cells' highest points for the frame and returns them for the update path to fill
  /// chunk by chunk (SightFeed); nullptr otherwise. fine_sums: the update path's Kalman frame
  /// batch (UpdatePath::frame_sums; nullptr without a Kalman finest layer), read by the
  /// confirmations after the frame.
  [[nodiscard]] const SightFeed* begin_sight(const FramePose& pose, const KalmanFrameSum* fine_sums) noexcept {
    if constexpr (!kSight) {
      (void)pose;
      (void)fine_sums;
      return nullptr;
    } else {
    if (!every_) {
      return nullptr;
    }
    for (float& top : sight_.tops) {
      top = -std::numeric_limits<float>::infinity();
    }
    sight_.fine_sums = fine_sums;
    sight_.feed.table = &sight_.table;
    sight_.feed.ccm_top = sight_.tops + kTopFine;
    sight_.feed.fine_top = kTopFine > 0U ? sight_.tops : nullptr;
    SightFrameConstants k{};
    k.sensor_u[0] = pose.anchor_fraction[0];
    k.sensor_u[1] = pose.anchor_fraction[1];
    k.z0 = pose.origin[2];
    k.bin_scale = bin_scale_;
    k.cell_width_m = cell_width_;
    k.sigma_c[0] = sigma_c_[0];
    k.sigma_c[1] = sigma_c_[1];
    k.sigma_c[2] = sigma_c_[2];
    k.view_axis[0] = view_axis_[0];
    k.view_axis[1] = view_axis_[1];
    k.view_axis[2] = view_axis_[2];
    k.view_axis_set = view_axis_set_;
    k.layers = kLayerCount;
    k.stride = sight_stride_;
    // The sampled groups move through their block frame by frame (strides 8 and 16), so that
    // every point of a steady camera's image casts its line of sight every few frames.
    k.phase = static_cast<std::int32_t>((frames_ * 9U) & 0x7FFFU);
    sight_.table.begin(k);
    sight_anchor_ = pose.anchor;
    return &sight_.feed;
    }
  }
  [[nodiscard]] CellIndex sight_anchor() const noexcept { return sight_anchor_; }

  /// The stage of a map-frame frame (after its points were folded in). weights: as update_frame.
  /// chunk: the front's scratch for the rays' ends, lent by the update path, whose frame is over
  /// (its content on entry is not read).
  void run_map(Layers& layers, const StackParams& params, const FrontConfig& front, FrontChunk& chunk,
               const PointXYZ* points, const float* weights, std::size_t n, const FramePose& pose,
               FrameCounters& frame) noexcept {
    run(layers, params, front, chunk, points, weights, n, pose, false, frame);
  }
  /// The stage of a sensor-frame frame: points in the sensor frame, pose made with a rotation.
  void run_sensor(Layers& layers, const StackParams& params, const FrontConfig& front, FrontChunk& chunk,
                  const PointXYZ* points, std::size_t n, const FramePose& pose, FrameCounters& frame) noexcept {
    run(layers, params, front, chunk, points, nullptr, n, pose, true, frame);
  }

  /// The record grid of a layer (queries, snapshots); nullptr for a bad layer.
  [[nodiscard]] const RingGrid<FreeSpaceCell>* records(int layer) const noexcept {
    return (layer >= 0 && layer < kLayerCount) ? &grids_[layer] : nullptr;
  }
  [[nodiscard]] RingGrid<FreeSpaceCell>* records(int layer) noexcept {
    return (layer >= 0 && layer < kLayerCount) ? &grids_[layer] : nullptr;
  }
  /// Frames this stage has seen since init (wraps at 2^32): its sampling phase and the records'
  /// frame stamps follow it. Map state (snapshots store it).
  [[nodiscard]] std::uint32_t frames() const noexcept { return frames_; }
  void set_frames(std::uint32_t frames) noexcept { frames_ = frames; }

  // ---- integrity of the records (map/detail/integrity.hpp, "Free-space records") ----
  /// The checks of `layer`'s records (side^2 of them, in buffer order); nullptr for a bad layer.
  [[nodiscard]] const CellCheck* record_checks(int layer) const noexcept {
    return (layer >= 0 && layer < kLayerCount) ? checks_ + offset_[layer] : nullptr;
  }
  /// True if a record of this stage's storage agrees with its check.
  [[nodiscard]] bool record_intact(const FreeSpaceCell& rec) const noexcept {
    return cell_signature(rec) == checks_[static_cast<std::size_t>(&rec - records_)];
  }
  /// The record as a reader that keeps the checks may use it: itself if intact, else no evidence.
  [[nodiscard]] FreeSpaceCell intact_or_empty(const FreeSpaceCell& rec) const noexcept {
    return record_intact(rec) ? rec : FreeSpaceCell{};
  }
  /// Recomputes every record's check (init, and after a snapshot load wrote the records).
  void reseal_records() noexcept {
    for (std::size_t i = 0; i < kRecordCount; ++i) {
      checks_[i] = cell_signature(records_[i]);
    }
  }
  /// The scrub's slice of this frame: checks `count` records from the cursor on (wrapping; the
  /// cursor clamped first), resets every corrupted one to no evidence and returns how many.
  [[nodiscard]] std::uint32_t scrub(std::uint32_t count) noexcept {
    return scrub_record_slice(records_, checks_, static_cast<std::uint32_t>(kRecordCount), &scrub_cursor_, count);
  }

  // ---- map exchange (persistence/exchange.hpp: free-space entries of a delta) ----
  /// True if clear_cell emptied record `record`'s cell since the mark was last dropped (map
  /// exchange sends the clear, persistence/exchange.hpp). The mark is two bits, one in each of
  /// two arrays, and reads as set only when both are: an upset can lose a clear (the team mates
  /// then keep the ghost, as without exchange) but not make one. Out of range: false.
  [[nodiscard]] bool clear_marked(std::uint32_t record) const noexcept {
    if (record >= kRecordCount) {
      return false;
    }
    const std::uint32_t bit = 1U << (record % 32U);
    return (clear_marks_[0][record / 32U] & clear_marks_[1][record / 32U] & bit) != 0U;
  }
  /// Calls fn(record) for every marked record (clear_marked), in record order.
  template <typename Fn>
  void for_each_clear_mark(Fn&& fn) const noexcept {
    for (std::uint32_t i = 0; i < (kRecordCount + 31U) / 32U; ++i) {
      std::uint32_t word = clear_marks_[0][i] & clear_marks_[1][i];
      while (word != 0U) {
        const auto bit = static_cast<std::uint32_t>(__builtin_ctz(word));
        const std::uint32_t record = 32U * i + bit;
        if (record < kRecordCount) {
          fn(record);
        }
        word &= word - 1U;
      }
    }
  }
  /// Drops the mark of one record (the exchange sent its clear, or the cell left the window).
  void drop_clear_mark(std::uint32_t record) noexcept {
    if (record < kRecordCount) {
      const std::uint32_t keep = ~(1U << (record % 32U));
      clear_marks_[0][record / 32U] &= keep;
      clear_marks_[1][record / 32U] &= keep;
    }
  }
  /// Drops every mark (an exchange bound to the stack starts afresh).
  void clear_all_marks() noexcept {
    for (auto& half : clear_marks_) {
      for (std::uint32_t& word : half) {
        word = 0U;
      }
    }
  }
  /// The record of `layer` at `index` (inside the window) into *out; false if its check fails
  /// (*out then no evidence) or the layer is bad.
  [[nodiscard]] bool record_at(int layer, CellIndex index, FreeSpaceCell* out) const noexcept {
    *out = FreeSpaceCell{};
    if (layer < 0 || layer >= kLayerCount || !grids_[layer].contains(index)) {
      return false;
    }
    const FreeSpaceCell& rec = grids_[layer].cell_unchecked(index);
    if (!record_intact(rec)) {
      return false;
    }
    *out = rec;
    return true;
  }
  /// A team mate's drop-off into the record (merge_drop: bound_z_m in this map's frame, NaN for
  /// none), through write_record: a record an upset changed stays detected.
  void merge_drop_at(int layer, CellIndex index, float bound_z_m, std::uint32_t rays) noexcept {
    if (layer >= 0 && layer < kLayerCount && grids_[layer].contains(index)) {
      write_record(grids_[layer].cell_unchecked(index), [&](FreeSpaceCell& r) { merge_drop(r, bound_z_m, rays); });
    }
  }
  /// Raises the record's evidence against its cell's surface to `evidence` (at most 255) if lower.
  void raise_evidence_at(int layer, CellIndex index, std::uint32_t evidence) noexcept {
    if (layer >= 0 && layer < kLayerCount && grids_[layer].contains(index)) {
      const auto e = static_cast<std::uint8_t>(evidence < 255U ? evidence : 255U);
      write_record(grids_[layer].cell_unchecked(index), [e](FreeSpaceCell& r) {
        r.evidence = r.evidence > e ? r.evidence : e;
      });
    }
  }
  /// The record of a cell the exchange emptied: no evidence, as clear_cell leaves it.
  void reset_record_at(int layer, CellIndex index) noexcept {
    if (layer >= 0 && layer < kLayerCount && grids_[layer].contains(index)) {
      reset_record(static_cast<std::uint32_t>(offset_[layer] + grid::buffer_offset(index, Layers::side(layer))));
    }
  }
  /// free_space_clear_frames (the evidence that empties a cell).
  [[nodiscard]] std::uint32_t clear_frames() const noexcept { return clear_frames_; }

  /// Integrity (map/detail/integrity.hpp): what the stack's seal covers of this stage, every value
  /// that indexes memory or sets how much work a frame does (the record grids' bindings and
  /// windows, the layer offsets and margins, the parameters). Not the records (each has its own
  /// check: record_intact, the scrub), not the scrub's cursor (clamped on use), not the frame counter (the sampling phase) nor the per-frame scratch (rewritten each frame,
  /// its indices checked where they are read).
  void hash_bindings(StateHasher& h) const noexcept {
    h.add_bytes<sizeof grids_>(reinterpret_cast<const unsigned char*>(grids_));
    h.add(offset_);
    h.add(consts_);
    h.add(max_inclination_);
    h.add(view_axis_);
    h.add(view_axis_set_);
    h.add(rays_);
    h.add(clear_frames_);
    hash_bool_bytes(h, every_);
    h.add(sight_stride_);
    h.add(bin_scale_);
    h.add(sigma_c_);
    h.add(cell_width_);
  }

 private:
  using CcmCellType = typename Layers::CcmCellType;
  using FineCell = typename Layers::FineCell;

  /// Weight, height (m) and height co-moment of a cell: a CCM cell's mean height and S_zz, a
  /// constant cell's height (and 0: a 4 cm cell is one surface).
  struct CellView {
    float weight;
    float height;
    float s_zz;
  };

  /// What one ray carries along its walk.
  struct RayState {
    float z0;            ///< sensor height (m)
    float dz;            ///< height change over the walked segment (m)
    float length_m;      ///< horizontal length of the walked segment (m)
    CellIndex end[kMaxLayers];  ///< the point's cell in every layer (never judged by its own ray)
    float ground_m;      ///< the last ground the ray crossed (m)
    float prev_h_m;      ///< height of the last known cell the walk layer crossed (m)
    float prev_s_m;      ///< where (horizontal distance from the sensor, m)
    bool has_ground;
    bool on_obstacle;    ///< the known cells rose faster than a traversable slope since the ground
    bool dirty;          ///< the ray passed below a known surface: it proves no bound beyond
    std::uint32_t run;   ///< unobserved cells since the last known stretch (entries of run_)
    float dx_m;          ///< horizontal x change over the walked segment (m, map frame)
    float dy_m;          ///< horizontal y change over the walked segment (m, map frame)
    // The coarser layers' cells visit() last read for an unobserved walk-layer cell, per layer:
    // the walk crosses several finer cells of each, and no cell changes during a frame's walks.
    CellIndex coarse_index[kMaxLayers];
    CellView coarse_view[kMaxLayers];  ///< weight 0 for a cell outside its window or empty
    bool coarse_read[kMaxLayers];      ///< coarse_index and coarse_view hold a cell of the layer
  };

  /// An unobserved cell of the current run (see mark_run).
  struct RunCell {
    FreeSpaceCell* record;
    std::int32_t layer;
    bool marked;  ///< this ray counted a drop-off in it already
  };

  [[nodiscard]] CellView view_of(const Layers& layers, int layer, CellIndex index) const noexcept {
    // Integrity: a cell an upset changed reads as never observed (map/detail/integrity.hpp).
    // Callers use nothing of a cell whose weight is not positive, so only such a cell pays for
    // its check (an empty cell, corrupted or not, reads as the empty cell does).
    if (Layers::is_ccm(layer)) {
      const CcmCellType& c = layers.ccm_grid(layer).cell_unchecked(index);
      if (!(c.weight > 0.0F) || !cell_intact(layers, c)) {
        return CellView{0.0F, 0.0F, 0.0F};
      }
      return CellView{c.weight, c.mean_z, c.s_zz};
    }
    if constexpr (Layers::kHasFine) {
      const FineCell& c = layers.fine.cell_unchecked(index);
      if (!(c.weight > 0.0F) || !cell_intact(layers, c)) {
        return CellView{0.0F, 0.0F, 0.0F};
      }
      return CellView{c.weight, c.height, 0.0F};
    } else {
      return CellView{0.0F, 0.0F, 0.0F};
    }
  }

  /// The cell as stored, unchecked (only to choose which lines of sight are walked: the walk reads
  /// the cell through view_of). Weight 0 for an empty cell.
  [[nodiscard]] CellView raw_view(const Layers& layers, int layer, CellIndex index) const noexcept {
    if (Layers::is_ccm(layer)) {
      const CcmCellType& c = layers.ccm_grid(layer).cell_unchecked(index);
      return CellView{c.weight, c.mean_z, c.s_zz};
    }
    if constexpr (Layers::kHasFine) {
      const FineCell& c = layers.fine.cell_unchecked(index);
      return CellView{c.weight, c.height, 0.0F};
    } else {
      return CellView{0.0F, 0.0F, 0.0F};
    }
  }

  /// The cell's weight as stored, unchecked: only to skip an empty cell early (view_of reads
  /// the cell through its check before anything of it is used).
  [[nodiscard]] float raw_weight(const Layers& layers, int layer, CellIndex index) const noexcept {
    return raw_view(layers, layer, index).weight;
  }

  /// True if the top of the cell's surface stands above height z (m) by more than the layer's
  /// clear margin. The top of a CCM cell is mean + sqrt(3) sigma_zz (sigma_zz^2 = S_zz / W): the
  /// highest point of heights spread evenly about the mean, so a vertical face whose cell also
  /// holds the ground in front of it (a rover seen from the side, mean half its height) counts
  /// with its top; a flat cell's top is its mean plus its noise, a plane's its uphill edge.
  /// Compared squared: no square root.
  [[nodiscard]] bool top_above(const CellView& cell, int layer, float z) const noexcept {
    const float gap = z + consts_[layer].clear_margin_m - cell.height;  // the top must exceed mean + gap
    return gap < 0.0F || gap * gap * cell.weight < 3.0F * cell.s_zz;
  }

  /// The walk's second test of a cell whose top stands above the ray (top_above): true if the
  /// ray passes below the cell's own surface where it crosses the cell. A CCM cell's surface at
  /// (x, y) is its least-squares plane (ccm_surface, ccm_height_at: z = mu_z + [a b] . (q - mu_xy),
  /// q relative to the cell centre, m) spread by its residual sigma_s^2 (normal_variance); its
  /// top there is the plane plus sqrt(3) sigma_s, compared with the ray's height plus the clear
  /// margin as top_above compares the cell's top. The ray's height and the plane are both linear
  /// along the ray, so their largest difference inside the cell is at the ray's entry or exit:
  /// those two are tested. So a ray over the low part of a cell whose other part holds a rock
  /// face (below the cell's top, above its ground there) contradicts nothing, while a vanished
  /// surface (a box, a rover: its face or top where the ray passes) still does. It only narrows
  /// top_above (it is asked only where top_above fired: an extrapolated plane adds no
  /// contradiction). A constant cell is one surface (its height): top_above alone decides.
  /// Float, no heap; a CCM cell pays ccm_surface (divisions by W and the 2 x 2 inverse) only here.
  [[nodiscard]] bool below_surface(const Layers& layers, int layer, const RayVisit& v, const RayState& ray) const noexcept {
    if (!Layers::is_ccm(layer)) {
      return true;
    }
    const CcmCellType& c = layers.ccm_grid(layer).cell_unchecked(v.index);
    const CcmSurface surface = ccm_surface(c);
    // The sensor relative to the cell centre (m): the centre in U units is
    // index 2^(layer + 8) + 2^(layer + 7); the difference is exact in int64, and in float for
    // any cell of a window (below 2^24 U).
    const std::int64_t cell_u = std::int64_t{256} << layer;
    const std::int64_t half_u = std::int64_t{128} << layer;
    const float metres_per_u = cell_width_ * 0.00390625F;
    const float ox = static_cast<float>(origin_u_[0] - (std::int64_t{v.index.x} * cell_u + half_u)) * metres_per_u;
    const float oy = static_cast<float>(origin_u_[1] - (std::int64_t{v.index.y} * cell_u + half_u)) * metres_per_u;
    const float margin = consts_[layer].clear_margin_m;
    // At the ray's fraction t of the walked segment: its top above the ray by the margin.
    const auto top_above_ray = [&](float t) {
      const float plane = ccm_height_at(c, surface, ox + t * ray.dx_m, oy + t * ray.dy_m);
      const float gap = ray.z0 + t * ray.dz + margin - plane;  // the top must exceed plane + gap
      return gap < 0.0F || gap * gap < 3.0F * surface.normal_variance;
    };
    return top_above_ray(v.t_in) || top_above_ray(v.t_out);
  }

  void run(Layers& layers, const StackParams& params, const FrontConfig& front, FrontChunk& chunk,
           const PointXYZ* points, const float* weights, std::size_t n, const FramePose& pose, bool sensor_frame,
           FrameCounters& frame) noexcept {
    ++frames_;
    // A frame the budget cut short (StackParams::frame_point_budget, frame_time_budget_us) casts
    // no line of sight: its time is spent.
    if (rays_ == 0U || n == 0U || frame.skipped_budget > 0U) {
      return;
    }
    stamp_ = static_cast<std::uint8_t>(frames_ & kStampMask);
    contradicted_count_ = 0U;
    // An evenly spread subsample: every stride-th point from a phase that moves every frame.
    const std::size_t stride = (n + rays_ - 1U) / rays_;
    // The phase: a 32-bit multiplicative hash of the frame count (wraps alike on every target).
    const std::uint32_t hashed = frames_ * 2654435761U;
    const std::size_t phase = stride > 1U ? static_cast<std::size_t>(hashed) % stride : 0U;
    const std::size_t sampled = (n - phase + stride - 1U) / stride;
    windows_.layers = kLayerCount;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      windows_.min[layer] = layers.window_min(layer);
      windows_.side[layer] = Layers::side(layer);
    }
    ray_origin_of(pose, origin_u_);
    origin_z_ = pose.origin[2];
    cell_width_ = front.width;
    bool held = false;
    for (int layer = 0; layer < kLayerCount && !held; ++layer) {
      const int shift = kRayFracBits + layer;
      held = windows_.contains(layer, CellIndex{static_cast<std::int32_t>(origin_u_[0] >> shift),
                                                static_cast<std::int32_t>(origin_u_[1] >> shift)});
    }
    if constexpr (kSight) {
      if (every_) {
        frame.free_rays_refused += sight_.table.refused();
        if (!held) {
          frame.free_rays_refused += sight_.table.points();
          return;
        }
        run_every(layers, frame);
        settle(layers, frame);
        return;
      }
    }
    if (!held) {
      frame.free_rays_refused += static_cast<std::uint32_t>(sampled);
      return;
    }
    find_targets();
    // Every slot (a point of the even subsample) brings `per` candidates spread over its stride:
    // the point itself first, then every gap-th point after it (kCandidates, fewer when the
    // stride is shorter). A batch of candidates fills one front chunk.
    const std::size_t per = stride < kCandidates ? stride : kCandidates;
    const std::size_t gap = stride / per;
    const std::size_t slots_per_batch = kFrontChunkPoints / per;
    std::size_t count = 0U;
    std::size_t slots = 0U;
    for (std::size_t idx = phase; idx < n; idx += stride) {
      for (std::size_t m = 0U; m < per && idx + m * gap < n; ++m) {
        batch_index_[count] = static_cast<std::uint32_t>(idx + m * gap);
        batch_points_[count] = points[idx + m * gap];
        batch_level_[count] = static_cast<std::uint8_t>(m == 0U ? kSlotPoint : 0U);
        ++count;
      }
      if (++slots == slots_per_batch) {
        run_batch(layers, params, front, chunk, weights, count, slots, pose, sensor_frame, frame);
        count = 0U;
        slots = 0U;
      }
    }
    if (slots > 0U) {
      run_batch(layers, params, front, chunk, weights, count, slots, pose, sensor_frame, frame);
    }
    settle(layers, frame);
  }

  /// Every line of sight (sight_table.hpp): the table is full (the update path fed it), swept
  /// here; every cell of every window then reads its bound from the sectors wholly inside its
  /// azimuth interval whose rays reach beyond its farthest corner.
  ///  - a known cell is contradicted when every such sector (at least two) passes below its
  ///    top by the clear margin (so a rock covering part of the cell, whose sectors end on it or
  ///    pass over it, is not), and counts the frame as kContradictionsPerFrame rays did, unless a
  ///    point of the frame lies on its surface (confirm_cell: the cell is confirmed instead, as
  ///    is every cell read here whose evidence is not zero);
  ///  - an unobserved cell of its walk layer (no finer window holds it) takes the lowest bound;
  ///    it is a drop-off when every such sector (at least kDropRays) passes more than the
  ///    layer's step below the ground that sector's points showed before the cell.
  void run_every(Layers& layers, FrameCounters& frame) noexcept {
    if constexpr (kSight) {
    sight_.table.sweep();
    sight_.table.track_ground(max_inclination_ * cell_width_, consts_[0].rise_margin_m);
    const SightFrameConstants& k = sight_.table.constants();
    const float unit_m = kSightSlopeUnit * cell_width_;  // height per slope unit per finest cell
    frame.free_rays += sight_.table.points();
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const CellIndex min = windows_.min[layer];
      const std::int32_t side = windows_.side[layer];
      const float cw = static_cast<float>(std::int32_t{1} << layer);
      const float step = consts_[layer].step_m;
      for (std::int32_t j = 0; j < side; ++j) {
        const std::int32_t gy = min.y + j;
        const float y0 = static_cast<float>((std::int64_t{gy} * (std::int64_t{1} << layer)) - sight_anchor_.y) - k.sensor_u[1];
        const float y1 = y0 + cw;
        // Only the columns the frame's rays can reach (reach and view: SightTable::row_span).
        const float bx = static_cast<float>((std::int64_t{min.x} * (std::int64_t{1} << layer)) - sight_anchor_.x) - k.sensor_u[0];
        std::int32_t first = 0, last = -1;
        if (!sight_.table.row_span(y0, y1, bx, cw, side, &first, &last)) {
          continue;
        }
        for (std::int32_t i = first; i <= last; ++i) {
          const std::int32_t gx = min.x + i;
          const CellIndex index{gx, gy};
          const bool walk_layer = !finer_holds(layer, index);
          if (!walk_layer && !(raw_weight(layers, layer, index) > 0.0F)) {
            continue;  // a coarser layer's empty cell under a finer window: the finer record speaks
          }
          const float x0 = static_cast<float>((std::int64_t{gx} * (std::int64_t{1} << layer)) - sight_anchor_.x) - k.sensor_u[0];
          const float x1 = x0 + cw;
          FreeSpaceCell& rec = grids_[layer].cell_unchecked(index);
          SightCell sc{};
          if (!sight_.table.read_cell(x0, x1, y0, y1, &sc)) {
            if (rec.evidence > 0U) {  // no bound here, but its points may confirm it
              (void)confirm_cell(layer, index, view_of(layers, layer, index), rec);
            }
            continue;
          }
          const CellView cell = view_of(layers, layer, index);
          if (!(cell.weight > 0.0F) && !walk_layer) {
            continue;  // empty after its check (an upset): as above
          }
          const int lo = sc.lo, hi = sc.hi, bin = sc.bin;
          const std::int32_t qmin = sc.qmin;
          bool all = true;  // every sector holding a ray agrees (sectors without one say nothing)
          const int covered = sc.covered;
          const float s_near = sc.s_near, s_far = sc.s_far;
          if (cell.weight > 0.0F) {
            // The sectors whose lowest ray passes clearly below the cell's top: two at least, and
            // every sector holding a ray (a rock over part of the cell stops the rays of the
            // sectors it covers, which then pass over it or end on it). The ray's height is
            // non-decreasing in its slope and top_above non-increasing in the height, so every
            // sector passes below exactly when the highest of them does.
            const std::int32_t qmax = sc.qmax;
            const bool contradicted =
                covered >= 2 &&
                top_above(cell, layer, k.z0 + static_cast<float>(qmax) * unit_m * (qmax < 0 ? s_near : s_far));
            // A point of the frame on the cell's surface confirms it: no evidence this frame, and
            // the evidence of earlier frames forgotten (as a walked ray's point, confirm_end).
            if ((contradicted || rec.evidence > 0U) && confirm_cell(layer, index, cell, rec)) {
              continue;
            }
            if (contradicted) {
              write_record(rec, [&](FreeSpaceCell& r) {
                (void)touch(r, stamp_);
                if (frame_contradictions(r) == 0U) {
                  remember(layer, index);
                }
                for (std::uint32_t c = 0; c < kContradictionsPerFrame; ++c) {
                  add_contradiction(r);
                }
              });
            }
            continue;
          }
          write_record(rec, [&](FreeSpaceCell& r) {
            lower_bound(r, k.z0 + static_cast<float>(qmin) * unit_m * (qmin < 0 ? s_near : s_far));
          });
          // Drop-off: every covered sector below its own ground by more than the step.
          const int near_bin = sight_.table.bin_of(s_near);
          int proving = 0;
          for (int s = lo; s < hi && all; ++s) {
            const std::int32_t q = sight_.table.slope(bin, s);
            if (q == kSightEmpty) {
              continue;
            }
            float ground = 0.0F;
            if (!sight_.table.ground(near_bin, s, &ground)) {
              all = false;
              break;
            }
            const float ray = static_cast<float>(q) * unit_m * (q < 0 ? s_near : s_far);  // from the sensor
            if (!(ray < ground - step)) {
              all = false;
              break;
            }
            ++proving;
          }
          if (all && proving >= static_cast<int>(kDropRays)) {
            bool now = false;
            write_record(rec, [&now](FreeSpaceCell& r) {
              for (std::uint32_t c = 0; c < kDropRays; ++c) {
                now = add_drop_ray(r) || now;
              }
            });
            frame.drop_cells += now ? 1U : 0U;
          }
        }
      }
    }
    } else {
      (void)layers;
      (void)frame;
    }
  }

  /// Table mode: the height (m) of the frame's points in the cell at buffer offset `slot` of
  /// `layer` that confirm_cell tests: the highest point the update path kept (a CCM or OMG cell;
  /// -infinity if none), or a Kalman finest cell's frame-batch mean. False (z untouched) for a
  /// Kalman cell that took no point this frame.
  [[nodiscard]] bool frame_height(int layer, std::size_t slot, float* z) const noexcept {
    if constexpr (kSight) {
      if (Layers::is_ccm(layer)) {
        *z = sight_.tops[kTopFine + (offset_[layer] - kFineRecords) + slot];
      } else if constexpr (kKalmanFine) {
        if (sight_.fine_sums == nullptr || sight_.fine_sums[slot].count == 0U) {
          return false;
        }
        const KalmanFrameSum& sum = sight_.fine_sums[slot];
        *z = static_cast<float>(sum.sum_height_q14) / (static_cast<float>(sum.count) * 16384.0F);
      } else {
        *z = sight_.tops[slot];
      }
      return true;
    } else {
      (void)layer;
      (void)slot;
      (void)z;
      return false;
    }
  }

  /// Table mode: true if a point of this frame folded into the known cell `cell` (at `index` of
  /// `layer`, its record `rec`) lies on its surface (on_surface, the rule of a walked ray's
  /// point); the cell is then confirmed (confirm: no evidence this frame, the earlier frames'
  /// forgotten). The frame's points of the cell: the highest of them, which the update path kept
  /// for a CCM or OMG cell (SightFeed); for a Kalman cell the mean of its frame batch (the points
  /// inside its gate), on the surface only if one of them is (so it confirms no cell its points
  /// would not; a highest point per Kalman cell would cost every point of the frame). An
  /// empty cell (or one that failed its check): false.
  bool confirm_cell(int layer, CellIndex index, const CellView& cell, FreeSpaceCell& rec) noexcept {
    if constexpr (kSight) {
      if (!(cell.weight > 0.0F)) {
        return false;
      }
      float z = 0.0F;
      if (!frame_height(layer, grid::buffer_offset(index, Layers::side(layer)), &z) || !on_surface(layer, cell, z)) {
        return false;
      }
      write_record(rec, [this](FreeSpaceCell& r) {
        (void)touch(r, stamp_);
        confirm(r);
      });
      return true;
    } else {
      (void)layer;
      (void)index;
      (void)cell;
      (void)rec;
      return false;
    }
  }

  /// True if a finer layer's window holds the cell `index` of `layer`.
  [[nodiscard]] bool finer_holds(int layer, CellIndex index) const noexcept {
    for (int j = 0; j < layer; ++j) {
      const int d = layer - j;
      if (windows_.contains(j, CellIndex{index.x * (1 << d), index.y * (1 << d)})) {
        return true;
      }
    }
    return false;
  }

  /// One batch of candidates (count of them, for `slots` slots): the front places them, each is
  /// scored (score_candidate), `slots` of them are chosen (choose) and walked in their order.
  void run_batch(Layers& layers, const StackParams& params, const FrontConfig& front, FrontChunk& chunk,
                 const float* weights, std::size_t count, std::size_t slots, const FramePose& pose,
                 bool sensor_frame, FrameCounters& frame) noexcept {
    if (sensor_frame) {
      front_sensor_chunk(batch_points_, count, pose, front, kNoFineWindow, chunk);
    } else {
      front_map_chunk(batch_points_, count, pose, front, kNoFineWindow, chunk);
    }
    for (std::size_t i = 0; i < count; ++i) {
      const RayEnd end = ray_end_of(chunk, i);
      bool refused = end.code >= std::int32_t{kFrontNonFinite} || end.code < 0;
      if (!refused && weights != nullptr) {
        refused = ccm_check_weight(weights[batch_index_[i]]) != Status::kOk;
      }
      if (!refused && sensor_frame && view_axis_set_) {
        const PointXYZ& s = batch_points_[i];
        refused = !(s.x * view_axis_[0] + s.y * view_axis_[1] + s.z * view_axis_[2] > 0.0F);
      }
      const std::uint32_t level = refused ? 0U : score_candidate(layers, end);
      batch_level_[i] = static_cast<std::uint8_t>((batch_level_[i] & kSlotPoint) | level);
    }
    choose(count, slots);
    for (std::size_t i = 0; i < count; ++i) {
      if ((batch_level_[i] & kChosen) == 0U) {
        continue;
      }
      if ((batch_level_[i] & kLevelMask) == 0U) {
        ++frame.free_rays_refused;
        continue;
      }
      ++frame.free_rays;
      cast(layers, params, ray_end_of(chunk, i), frame);
    }
  }

  /// Marks `slots` of the batch's `count` candidates chosen (kChosen): every candidate of the
  /// highest levels, then, from the level where the slots run out, the slots' own points of that
  /// level first, evenly spread, then its other candidates evenly spread. A batch whose
  /// candidates all score alike walks exactly the even subsample (the slots' own points).
  void choose(std::size_t count, std::size_t slots) noexcept {
    std::uint32_t at_level[kLevels]{};
    std::uint32_t own_at_level[kLevels]{};
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint32_t level = batch_level_[i] & kLevelMask;
      ++at_level[level];
      own_at_level[level] += (batch_level_[i] & kSlotPoint) != 0U ? 1U : 0U;
    }
    auto need = static_cast<std::uint32_t>(slots);
    std::uint32_t cut = kLevels - 1U;
    while (cut > 0U && at_level[cut] < need) {
      need -= at_level[cut];
      --cut;
    }
    // At the cut level: `need` of its candidates, its slots' own points first.
    const std::uint32_t own = own_at_level[cut];
    const std::uint32_t own_take = need < own ? need : own;
    const std::uint32_t other = at_level[cut] - own;
    const std::uint32_t other_take = need - own_take;
    std::uint32_t own_rank = 0U, own_picked = 0U, other_rank = 0U, other_picked = 0U;
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint32_t level = batch_level_[i] & kLevelMask;
      bool take = level > cut;
      if (level == cut) {
        // The t-th pick of a group of g candidates taking k is its rank floor(t g / k).
        if ((batch_level_[i] & kSlotPoint) != 0U) {
          take = own_picked < own_take && own_rank == own_picked * own / own_take;
          own_picked += take ? 1U : 0U;
          ++own_rank;
        } else {
          take = other_picked < other_take && other_rank == other_picked * other / other_take;
          other_picked += take ? 1U : 0U;
          ++other_rank;
        }
      }
      batch_level_[i] = static_cast<std::uint8_t>(batch_level_[i] | (take ? kChosen : 0U));
    }
  }

  /// The level of a routed candidate (1 .. kLevels - 1): 1, plus one for each of the cells one
  /// and two cells (of its routed layer) before its point towards the sensor that no point
  /// observed (its line of sight crosses hidden ground: a ditch, a crater, a shadow), plus
  /// kTargetLevel if, at one of those two places, the top of the finest known cell stands above
  /// the line of sight by the layer's clear margin (top_above) while the candidate's point lies
  /// more than that margin below the cell's mean (the line reached ground an obstacle's height
  /// below the surface the map holds just before it: a ghost, from the first frame it is gone,
  /// before any record holds evidence; a line grazing a rock's top ends on the rock, near the
  /// mean of the cells it passes, and is not promoted), or if it passes through a cell with
  /// evidence against its surface (find_targets). Reads cells unchecked: the level only chooses which
  /// lines of sight are walked; the walk reads every cell through its check.
  [[nodiscard]] std::uint32_t score_candidate(const Layers& layers, const RayEnd& end) const noexcept {
    std::uint32_t level = 1U;
    const float dx = static_cast<float>(end.u[0] - origin_u_[0]);
    const float dy = static_cast<float>(end.u[1] - origin_u_[1]);
    const float ax = dx < 0.0F ? -dx : dx;
    const float ay = dy < 0.0F ? -dy : dy;
    const float longest = ax > ay ? ax : ay;
    if (!(longest > 0.0F)) {
      return level;
    }
    const int routed = end.code;
    const float cell_u = static_cast<float>(std::int64_t{256} << routed);
    bool below = false;
    for (int back = 1; back <= kHiddenCellsBack; ++back) {
      const float f = static_cast<float>(back) * cell_u / longest;
      if (!(f < 1.0F)) {
        break;  // the cell before lies at or behind the sensor
      }
      // The step back through int32 (|dx f| < |dx|: within a window, far below 2^31 U): a float to
      // int64 conversion is a double-precision library call on a single-precision FPU (Cortex-M7:
      // link.no_soft_double); truncation alike, so the same cells.
      const std::int64_t u[2] = {end.u[0] - std::int64_t{static_cast<std::int32_t>(dx * f)},
                                 end.u[1] - std::int64_t{static_cast<std::int32_t>(dy * f)}};
      // Hidden: empty in the routed layer and in every finer layer whose window holds it (a
      // coarser layer's cell may hold the ground around a ditch: it does not see inside it).
      bool seen = false;
      for (int layer = 0; layer <= routed && !seen; ++layer) {
        const int shift = kRayFracBits + layer;
        const CellIndex c{static_cast<std::int32_t>(u[0] >> shift), static_cast<std::int32_t>(u[1] >> shift)};
        seen = windows_.contains(layer, c) && raw_weight(layers, layer, c) > 0.0F;
        if (seen && !below) {
          // A known cell whose top stands above the line of sight there by the clear margin, and
          // the line's point more than the margin below the cell's mean: it passes below a
          // surface and reaches ground beyond it (a ghost).
          // The point's test first: most candidates end on the surface of the cells before them.
          const CellView view = raw_view(layers, layer, c);
          if (end.z + consts_[layer].clear_margin_m < view.height) {
            // The line's height there (m, map frame): the fraction f of the way back to the sensor.
            const float z = end.z - f * (end.z - origin_z_);
            below = top_above(view, layer, z);
          }
        }
      }
      level += seen ? 0U : 1U;
    }
    if (below || crosses_target(dx, dy)) {
      level += kTargetLevel;
    }
    return level < kLevels ? level : kLevels - 1U;
  }

  /// True if the line of sight from the sensor to (dx, dy) (U units, relative to the sensor)
  /// passes within half a cell of the centre of a cell with evidence against it (find_targets),
  /// before its point.
  [[nodiscard]] bool crosses_target(float dx, float dy) const noexcept {
    const float dd = dx * dx + dy * dy;
    for (std::uint32_t k = 0; k < target_count_; ++k) {
      const float cx = targets_[k].centre[0];
      const float cy = targets_[k].centre[1];
      const float along = cx * dx + cy * dy;
      const float across = cx * dy - cy * dx;
      const float h = targets_[k].half;
      if (along > 0.0F && along < dd && across * across < h * h * dd) {
        return true;
      }
    }
    return false;
  }

  /// The cells the frame's candidates aim at (score_candidate): known cells whose record holds
  /// evidence against their surface, or whose record was contradicted in the last frame (one ray
  /// of it: a far ghost gets about one ray a frame, the evidence rule asks for two), up to
  /// kMaxTargets of them in record order; their centres relative to the sensor (U units).
  /// Cost: only a record whose evidence or contradiction bits are not all zero can be aimed, so
  /// the records are read kAimGroup at a time as words and a group with none of those bits set
  /// is passed with one test (most groups); the records of the other groups are judged one by one.
  void find_targets() noexcept {
    target_count_ = 0U;
    const auto last = static_cast<std::uint8_t>((frames_ - 1U) & kStampMask);
    // The bits of a record, as the word its 4 bytes make, that an aimed record has one of.
    const FreeSpaceCell aim_cell{0U, 0xFFU, kContradictionMask};
    std::uint32_t aim_bits = 0U;
    std::memcpy(&aim_bits, &aim_cell, sizeof aim_bits);
    const std::uint64_t aim_pair = (std::uint64_t{aim_bits} << 32U) | aim_bits;
    for (int layer = 0; layer < kLayerCount && target_count_ < kMaxTargets; ++layer) {
      const std::int32_t side = Layers::side(layer);
      const FreeSpaceCell* recs = records_ + offset_[layer];
      const auto cells = static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
      for (std::size_t group = 0; group < cells && target_count_ < kMaxTargets; group += kAimGroup) {
        const std::size_t group_end = cells - group < kAimGroup ? cells : group + kAimGroup;
        if (group_end - group == kAimGroup) {
          std::uint64_t words[kAimGroup / 2U];
          std::memcpy(words, recs + group, sizeof words);
          std::uint64_t any = 0U;
          for (const std::uint64_t w : words) {
            any |= w;
          }
          if ((any & aim_pair) == 0U) {
            continue;  // no record of the group can be aimed
          }
        }
        for (std::size_t slot = group; slot < group_end && target_count_ < kMaxTargets; ++slot) {
          const FreeSpaceCell& r = recs[slot];
          const bool aimed = r.evidence > 0U || ((r.state & kStampMask) == last && frame_contradictions(r) > 0U);
          if (!aimed) {
            continue;
          }
          // The global index of the slot: the window's index with that ring position.
          const CellIndex min = windows_.min[layer];
          const auto bx = static_cast<std::int32_t>(slot % static_cast<std::size_t>(side));
          const auto by = static_cast<std::int32_t>(slot / static_cast<std::size_t>(side));
          const std::int32_t gx = min.x + ((bx - min.x) & (side - 1));
          const std::int32_t gy = min.y + ((by - min.y) & (side - 1));
          const std::int64_t cell_u = std::int64_t{256} << layer;
          const std::int64_t half_u = std::int64_t{128} << layer;
          Target& t = targets_[target_count_++];
          t.centre[0] = static_cast<float>(static_cast<std::int64_t>(gx) * cell_u + half_u - origin_u_[0]);
          t.centre[1] = static_cast<float>(static_cast<std::int64_t>(gy) * cell_u + half_u - origin_u_[1]);
          t.half = static_cast<float>(half_u);
        }
      }
    }
  }

  /// One line of sight: its point confirms the surface it lies on, then the walk.
  void cast(Layers& layers, const StackParams& params, const RayEnd& end, FrameCounters& frame) noexcept {
    RayState ray{};
    const std::int64_t* end_u = end.u;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const int shift = kRayFracBits + layer;
      ray.end[layer] = CellIndex{static_cast<std::int32_t>(end_u[0] >> shift), static_cast<std::int32_t>(end_u[1] >> shift)};
    }
    const float end_z = end.z;
    confirm_end(layers, end.code, ray, end_z);
    // Shorten the ray by kRangeSigmas range errors: f = 1 - m / r of the segment is walked.
    const float range_sq = end.range_sq;
    const float range = std::sqrt(range_sq);
    const float margin = kRangeSigmas * params.noise.sigma_at_range_sq(range_sq);
    if (!(margin < range)) {
      return;  // the whole ray lies within the noise: it says nothing
    }
    float f = 1.0F - margin / range;
    const std::int64_t du[2] = {end_u[0] - origin_u_[0], end_u[1] - origin_u_[1]};
    // A ray longer than the walk takes is shortened to kMaxRayDeltaU (its far part lies beyond
    // every window of the presets).
    const std::int64_t longest = (du[0] < 0 ? -du[0] : du[0]) > (du[1] < 0 ? -du[1] : du[1])
                                     ? (du[0] < 0 ? -du[0] : du[0])
                                     : (du[1] < 0 ? -du[1] : du[1]);
    const float longest_f = static_cast<float>(longest);
    if (longest_f * f > static_cast<float>(kMaxRayDeltaU)) {
      f = static_cast<float>(kMaxRayDeltaU) / longest_f;
    }
    // |du * f| <= 2^27: int32 holds it; the conversion truncates towards the sensor.
    const RayU walk{{origin_u_[0], origin_u_[1]},
                    {static_cast<std::int32_t>(static_cast<float>(du[0]) * f),
                     static_cast<std::int32_t>(static_cast<float>(du[1]) * f)}};
    ray.z0 = origin_z_;
    const float full_dz = end_z - origin_z_;
    // U units to metres: w_0 / 256 (exact scale); |du| <= 2^39 is exact to float's 24 bits.
    const float metres_per_u = cell_width_ * 0.00390625F;
    const float full_dx = static_cast<float>(du[0]) * metres_per_u;
    const float full_dy = static_cast<float>(du[1]) * metres_per_u;
    // The walked fraction of the full ray, from the integer delta actually walked.
    const float walked = fraction_walked(end_u, walk);
    ray.dz = full_dz * walked;
    ray.length_m = std::sqrt(full_dx * full_dx + full_dy * full_dy) * walked;
    ray.dx_m = static_cast<float>(walk.delta[0]) * metres_per_u;
    ray.dy_m = static_cast<float>(walk.delta[1]) * metres_per_u;
    walk_ray(windows_, walk, [&](const RayVisit& v) {
      // About 40 % of the visits (CADRE) are a coarser layer's empty cell under a finer window,
      // which visit() passes by (it reads as empty through its check too): passed here, no call.
      if (!v.walk_layer && !(raw_weight(layers, v.layer, v.index) > 0.0F)) {
        return;
      }
      visit(layers, v, ray, frame);
    });
  }

  /// The share of the full ray (origin to point) the walk covers: |walked delta| / |full delta|
  /// on the longer axis (the walk's own rounding included, so heights follow the cells it names).
  [[nodiscard]] float fraction_walked(const std::int64_t* end_u, const RayU& walk) const noexcept {
    const std::int64_t fx = end_u[0] - origin_u_[0];
    const std::int64_t fy = end_u[1] - origin_u_[1];
    const bool use_x = (fx < 0 ? -fx : fx) >= (fy < 0 ? -fy : fy);
    const std::int64_t full = use_x ? fx : fy;
    const std::int64_t part = use_x ? walk.delta[0] : walk.delta[1];
    if (full == 0) {
      return 0.0F;
    }
    return static_cast<float>(part) / static_cast<float>(full);
  }

  /// True if a point at height z (m) lies on (or above) the surface of the known cell `cell` of
  /// `layer`: not below the cell's mean by more than kRangeSigmas range errors of the layer (a
  /// point on the ground beneath a vanished rover lies below it and confirms nothing).
  [[nodiscard]] bool on_surface(int layer, const CellView& cell, float z) const noexcept {
    return z > cell.height - consts_[layer].rise_margin_m * kRangeSigmas;
  }

  /// The point confirms the surface of the cell it was folded into (the first layer from its
  /// routed one whose window holds it) when it lies on it (on_surface).
  void confirm_end(const Layers& layers, std::int32_t code, const RayState& ray, float z) noexcept {
    for (int layer = code; layer < kLayerCount; ++layer) {
      if (!windows_.contains(layer, ray.end[layer])) {
        continue;
      }
      const CellView cell = view_of(layers, layer, ray.end[layer]);
      if (cell.weight > 0.0F) {
        if (on_surface(layer, cell, z)) {
          write_record(grids_[layer].cell_unchecked(ray.end[layer]), [this](FreeSpaceCell& rec) {
            (void)touch(rec, stamp_);
            confirm(rec);
          });
        }
      }
      return;
    }
  }

  /// One cell a ray crosses: contradiction of a surface (a cell of any layer holding points);
  /// bound and drop-off of an unobserved cell and ground tracking on the walk layer only (a
  /// coarser layer's empty cell under a finer window is skipped: the finer record speaks for the
  /// stretch, and rays from farther away bound the coarse cell once the finer window has moved on).
  void visit(Layers& layers, const RayVisit& v, RayState& ray, FrameCounters& frame) noexcept {
    const int layer = v.layer;
    if (v.index.x == ray.end[layer].x && v.index.y == ray.end[layer].y) {
      return;  // the ray ends in this cell: it says nothing about it
    }
    const CellView cell = view_of(layers, layer, v.index);
    if (!v.walk_layer && !(cell.weight > 0.0F)) {
      return;  // a coarser layer's empty cell under a finer window: the walk layer's record speaks
    }
    const float z_in = ray.z0 + v.t_in * ray.dz;
    const float z_out = ray.z0 + v.t_out * ray.dz;
    const float z_hi = z_in > z_out ? z_in : z_out;
    if (cell.weight > 0.0F) {
      if (top_above(cell, layer, z_hi) && below_surface(layers, layer, v, ray)) {
        write_record(grids_[layer].cell_unchecked(v.index), [&](FreeSpaceCell& r) {
          (void)touch(r, stamp_);
          if (frame_contradictions(r) == 0U) {
            remember(layer, v.index);  // listed once per frame: at its first contradiction
          }
          add_contradiction(r);
        });
        ray.dirty = true;
      }
      if (v.walk_layer) {
        track_ground(layer, cell.height, v.t_out, ray);
        ray.run = 0U;  // observed here: a new run starts after it
      }
      return;
    }
    if (v.walk_layer) {
      // The stack's view here: the first coarser layer holding data at this stretch.
      for (int j = layer + 1; j < kLayerCount; ++j) {
        const CellIndex c{v.index.x >> (j - layer), v.index.y >> (j - layer)};
        if (!ray.coarse_read[j] || c.x != ray.coarse_index[j].x || c.y != ray.coarse_index[j].y) {
          ray.coarse_view[j] = windows_.contains(j, c) ? view_of(layers, j, c) : CellView{0.0F, 0.0F, 0.0F};
          ray.coarse_index[j] = c;
          ray.coarse_read[j] = true;
        }
        const CellView& coarse = ray.coarse_view[j];
        if (coarse.weight > 0.0F) {
          track_ground(j, coarse.height, v.t_out, ray);
          // Observed here, at the coarser layer's resolution, where the ray passes at or above
          // that surface: a new run starts after it. A ray that dips below it inside the coarse
          // cell (just past a rim the coarse cell holds the ground before) keeps the run going.
          if (z_hi >= coarse.height) {
            ray.run = 0U;
          }
          break;
        }
      }
    }
    if (ray.dirty) {
      return;
    }
    const bool proves_drop = ray.has_ground && z_hi < ray.ground_m - consts_[layer].step_m;
    bool now = false;
    FreeSpaceCell& rec = grids_[layer].cell_unchecked(v.index);
    write_record(rec, [&](FreeSpaceCell& r) {
      lower_bound(r, z_hi);
      now = proves_drop && add_drop_ray(r);
    });
    if (ray.run < kMaxRunCells) {
      run_[ray.run++] = RunCell{&rec, layer, proves_drop};
    }
    if (proves_drop) {
      frame.drop_cells += now ? 1U : 0U;
      mark_run(layer, ray, frame);
    }
  }

  /// A drop-off proved in a cell of `layer` marks the unobserved cells of the same layer before
  /// it on the same run (the same stretch the ray crossed without meeting anything since the last
  /// ground): they lie behind the same rim, inside the same drop. The near edge of a ditch, whose
  /// bound is still within a step of the rim, is then a drop-off too, not an unknown gap.
  void mark_run(int layer, const RayState& ray, FrameCounters& frame) noexcept {
    for (std::uint32_t k = 0; k < ray.run; ++k) {
      RunCell& c = run_[k];
      if (c.layer == layer && !c.marked) {
        c.marked = true;
        bool now = false;
        write_record(*c.record, [&now](FreeSpaceCell& r) { now = add_drop_ray(r); });
        frame.drop_cells += now ? 1U : 0U;
      }
    }
  }

  /// The ground along the ray: the first known cell's height, then each known cell's unless the
  /// known cells rose faster than the steepest traversable slope from the one before (a rock, a
  /// rover): from there the ray is on an obstacle and the ground stays the level before it, until
  /// a known cell comes back within the noise of that level. So the shadow of a rock on flat
  /// ground, whose bound lies above the ground in front of the rock, is never a drop-off.
  void track_ground(int layer, float h, float t, RayState& ray) const noexcept {
    const float s = t * ray.length_m;
    const float noise = consts_[layer].rise_margin_m;
    if (!ray.has_ground) {
      ray.ground_m = h;
      ray.has_ground = true;
    } else if (!ray.on_obstacle) {
      if (h > ray.prev_h_m + max_inclination_ * (s - ray.prev_s_m) + noise) {
        ray.on_obstacle = true;
      } else {
        ray.ground_m = h;
      }
    } else if (h <= ray.ground_m + noise) {
      ray.on_obstacle = false;
      ray.ground_m = h;
    }
    ray.prev_h_m = h;
    ray.prev_s_m = s;
  }

  void remember(int layer, CellIndex index) noexcept {
    if (contradicted_count_ < kMaxContradictedCells) {
      contradicted_[contradicted_count_++] =
          static_cast<std::uint32_t>(offset_[layer] + grid::buffer_offset(index, Layers::side(layer)));
    }
  }

  /// The end of the frame: every cell contradicted this frame settles its evidence; those with
  /// free_space_clear_frames frames of it are emptied.
  void settle(Layers& layers, FrameCounters& frame) noexcept {
    const auto limit = static_cast<std::uint32_t>(kMaxContradictedCells);
    const std::uint32_t listed = contradicted_count_ < limit ? contradicted_count_ : limit;
    // cppcheck-suppress knownConditionTrueFalse ; remember() raises the count between run()'s reset and here
    for (std::uint32_t k = 0; k < listed; ++k) {
      const std::uint32_t record = contradicted_[k];
      if (record >= kRecordCount) {
        continue;  // integrity: only an upset of this frame's scratch gives such an index
      }
      FreeSpaceCell& rec = records_[record];
      // Integrity: the evidence decides a clearing, so it is used only when its record is intact;
      // a corrupted record is reset to no evidence and counted (it clears nothing).
      if (!record_intact(rec)) {
        reset_record(record);
        ++frame.corrupted_cells;
        continue;
      }
      std::uint32_t evidence = 0U;
      write_record(rec, [&evidence](FreeSpaceCell& r) { evidence = settle_frame(r); });
      if (evidence >= clear_frames_) {
        clear_cell(layers, record);
        ++frame.cleared_cells;
      }
    }
    contradicted_count_ = 0U;
  }

  void clear_cell(Layers& layers, std::uint32_t record) noexcept {
    int layer = kLayerCount - 1;
    while (layer > 0 && record < offset_[layer]) {
      --layer;
    }
    const std::size_t slot = record - offset_[layer];
    // Integrity: the check takes the change (an upset seen before stays seen: the scrub counts it).
    if (Layers::is_ccm(layer)) {
      write_cell(layers, layers.ccm_grid(layer).storage()[slot], [](CcmCellType& cell) { cell = CcmCellType{}; });
    } else {
      if constexpr (Layers::kHasFine) {
        write_cell(layers, layers.fine.storage()[slot], [](FineCell& cell) { cell = FineCell{}; });
      }
    }
    reset_record(record);
    const std::uint32_t bit = 1U << (record % 32U);  // map exchange sends the clear (clear_marked)
    clear_marks_[0][record / 32U] |= bit;
    clear_marks_[1][record / 32U] |= bit;
  }

  /// The one write of a record (every writer of this stage): write_delta (integrity.hpp) into
  /// the record's check, as write_cell is for cells. Precondition: `rec` is a record of records_.
  template <typename Write>
  void write_record(FreeSpaceCell& rec, Write&& fn) noexcept {
    checks_[static_cast<std::size_t>(&rec - records_)] ^= write_delta(rec, fn);
  }

  /// Record `record` is no evidence, its check consistent (check(0) = 0).
  void reset_record(std::uint32_t record) noexcept {
    records_[record] = FreeSpaceCell{};
    checks_[record] = 0U;
  }

  // ---- state (zero-initialised: a static stack lives in .bss) ----
  FreeSpaceCell records_[kRecordCount]{};
  CellCheck checks_[kRecordCount]{};  ///< checks_[i] belongs to records_[i] (integrity.hpp)
  std::uint32_t scrub_cursor_ = 0U;   ///< next record the scrub checks (clamped on use)
  /// Cells clear_cell emptied, one bit per record in each half (clear_marked); map state read
  /// and dropped by map exchange only (not in snapshots: a load retires the exchange).
  std::uint32_t clear_marks_[2][(kRecordCount + 31U) / 32U]{};
  RingGrid<FreeSpaceCell> grids_[Layers::kLayerSlots]{};
  std::size_t offset_[Layers::kLayerSlots]{};
  // ---- derived at init, scratch of a frame (not map state) ----
  FreeSpaceLayerConstants consts_[Layers::kLayerSlots]{};
  float max_inclination_ = 0.0F;
  float view_axis_[3]{};
  bool view_axis_set_ = false;
  std::uint32_t rays_ = 0U;
  std::uint32_t clear_frames_ = 0U;
  std::uint32_t frames_ = 0U;
  std::uint8_t stamp_ = 0U;
  RayWindows windows_{};
  std::int64_t origin_u_[2]{};
  float origin_z_ = 0.0F;
  float cell_width_ = 0.0F;  ///< w_0 (m)
  bool every_ = false;       ///< the viewshed table (free_space_rays >= free_space_table_rays(kSightMaxStride))
  std::int32_t sight_stride_ = 0;  ///< its stride: every sight_stride_-th point casts a ray (sight_stride_of_rays)
  float bin_scale_ = 0.0F;   ///< the viewshed table's square-root bins per sqrt(cell)
  float sigma_c_[3]{};       ///< kSightRangeSigmas sigma(r) = c0 + c1 r + c2 r^2 (m)
  CellIndex sight_anchor_{0, 0};
  static constexpr bool kSight = kConfigEveryLineOfSight<Config>;
  // The table's confirmations (SightFeed): per CCM cell, and per finest cell of an OMG layer,
  // the highest point of the frame (m); a Kalman finest layer's frame batch instead.
  static constexpr bool kKalmanFine = Config::kFineKind == FineKind::kKalman;
  static constexpr std::size_t kTopFine = (Layers::kHasFine && !kKalmanFine) ? kFineRecords : 0U;
  static constexpr std::size_t kTopCount = kTopFine + kCcmRecords > 0U ? kTopFine + kCcmRecords : 1U;
  /// What table mode keeps: the table, the frame's highest points, what the update path is fed.
  struct SightParts {
    SightTable table;
    float tops[kTopCount]{};
    SightFeed feed;
    const KalmanFrameSum* fine_sums = nullptr;  ///< the update path's Kalman frame batch (begin_sight)
  };
  std::conditional_t<kSight, SightParts, NoSightTable> sight_{};
  std::uint32_t contradicted_[kMaxContradictedCells]{};
  RunCell run_[kMaxRunCells]{};
  std::uint32_t contradicted_count_ = 0U;
  std::uint32_t batch_index_[kFrontChunkPoints]{};
  PointXYZ batch_points_[kFrontChunkPoints]{};
  /// Per candidate of a batch: its level (kLevelMask), kSlotPoint, kChosen.
  std::uint8_t batch_level_[kFrontChunkPoints]{};
  /// A cell the candidates aim at (find_targets): centre relative to the sensor, half width (U).
  struct Target {
    float centre[2];
    float half;
  };
  Target targets_[kMaxTargets]{};
  std::uint32_t target_count_ = 0U;
};

}  // namespace ccmap::detail
