// The robot-centric, multi-size, multi-resolution map stack (paper Fig. 2, Sections IV-D..G):
// the public class that flight software links against.
//
// Data flows one way: points -> sensor noise model -> routing -> one cell update; queries read
// cells and pool finer layers on demand (Section IV-F). Every layer is a statically sized ring
// buffer inside this object: after init() nothing allocates, and every call is bounded:
//   update_frame(_sensor)   O(points)                  move_to   O(cells that leave)
//   move_to with a position uncertainty: + one pass over every cell
//   query                   O(4^layers) cells, independent of map size and point count
//   export_layer            O(side^2 * 4^layers)
//
// Where the work is done (integrators need not read these):
//   map/detail/layers.hpp       the layers' storage and windows
//   map/update/front.hpp        the float front: validation, transform, range, routing, index
//   map/update/update_path.hpp  the chunk loop; the Kalman batch, the walk, the gate beside it
//   map/query/pooling.hpp       pooling at query time
//   map/query/answers.hpp       answers, classes, the roughness filter baseline
//   map/detail/motion.hpp       what an uncertain move does to the cells
//   map/visibility/free_space.hpp  lines of sight: ghosts cleared, drop-offs marked
//
// Positions are map-frame metres relative to the stack origin (see map/types.hpp).
//
// Usage (two-phase life):
//   static ccmap::Stack<ccmap::CadreConfig> map;     // static storage (.bss); sizes: docs/integration.md section 7
//   if (map.init(ccmap::default_stack_params(0.04F)) != ccmap::Status::kOk) { ...fault... }
//   map.move_to(robot_x, robot_y);
//   map.update_frame_sensor(points, n, camera_pose, &counters);
//   const ccmap::QueryResult q = map.query(x, y);
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iterator>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/core/assert.hpp"
#include "ccmap/grid/ring_grid.hpp"
#include "ccmap/map/classify.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/param_fields.hpp"
#include "ccmap/map/query/answers.hpp"
#include "ccmap/map/update/front.hpp"
#include "ccmap/map/detail/integrity.hpp"
#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/detail/motion.hpp"
#include "ccmap/map/query/pooling.hpp"
#include "ccmap/map/update/update_path.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/map/visibility/free_space.hpp"
#include "ccmap/platform/platform.hpp"
#include "ccmap/registration/types.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap {

namespace detail {
void accumulate(FrameCounters& total, const FrameCounters& frame) noexcept;
template <typename Config>
struct SnapshotAccess;  // persistence/snapshot.hpp: save/load read and restore the raw state
template <typename Config>
struct PlannerAccess;   // planner/detail/region_walk.hpp: the planner queries read the query view
template <typename Config>
struct ExchangeAccess;  // persistence/exchange.hpp: delta export and merge read and fold cells
template <typename Config>
struct GlobalAccess;  // global/patch_keeper.hpp: cells leaving a window saved as patches, restored on return
}  // namespace detail

template <typename Config>
class Stack {
  using Layers = detail::LayerSet<Config>;
  /// Cells the scrub checks per frame: every cell within detail::ConfigScrubFrames<Config> frames.
  static constexpr std::uint32_t kScrubCellsPerFrame = detail::scrub_cells_per_frame<Config, Layers>();
  /// Free-space records the scrub checks per frame: one record per cell, so as many as cells
  /// (every record within the same frames); none without free space.
  static constexpr std::uint32_t kScrubRecordsPerFrame = detail::FreeSpace<Config>::kEnabled ? kScrubCellsPerFrame : 0U;

 public:
  static constexpr bool kHasFine = Layers::kHasFine;
  static constexpr int kFineLayerCount = Layers::kFineLayerCount;
  static constexpr int kCcmLayerCount = Layers::kCcmLayerCount;
  static constexpr int kLayerCount = Layers::kLayerCount;
  using FineCell = typename Layers::FineCell;
  /// The CCM cell of this stack's CCM layers: CcmCell (10 floats, the full lateral covariance)
  /// or CcmPaperCell (the paper's 9), chosen by Config::kCcmCell (map/config.hpp). Every cell
  /// function (ccm_surface, ccm_merge, ccm_pool4, ccm_is_covered, ...) takes both.
  using CcmCellType = typename Layers::CcmCellType;
  static constexpr CcmCellKind kCcmCellKind = kConfigCcmCell<Config>;
  /// Held-point slots of the outlier gate's pools (CCM layers, finest layer; 0 without the gate
  /// compiled in): a frame judges at most this many cells of each (docs/design.md section 9).
  static constexpr std::size_t kCcmHeldSlots = detail::OutlierGate<Config>::kCcmSlots;
  static constexpr std::size_t kFineHeldSlots = Layers::kHasFine ? detail::OutlierGate<Config>::kFineSlots : std::size_t{0};

  Stack() noexcept = default;
  Stack(const Stack&) = delete;
  Stack& operator=(const Stack&) = delete;
  Stack(Stack&&) = delete;
  Stack& operator=(Stack&&) = delete;
  ~Stack() = default;

  // -------------------------------------------------------------------------------------------
  // Set-up
  // -------------------------------------------------------------------------------------------

  /// Validates `params`, binds the layers (centred on the origin, all cells empty), builds the
  /// routing table and calibrates the normal-variance thresholds. May be called again to reset,
  /// also after kCorrupt (docs/integration.md, "Radiation: single-event upsets").
  /// On failure the stack is left uninitialised and every other call answers kNotInitialised.
  [[nodiscard]] Status init(const StackParams& params) noexcept {
    ready_ = 0U;
    seal_ = detail::StateSeal{};
    update_seal_ = detail::StateSeal{};
    sensor::RoutingTable<kLayerCount> routing{};
    const Status status = derive(params, &routing);
    if (status != Status::kOk) {
      return status;
    }
    params_ = params;
    if (layers_.init(params.finest_cell_width_m) != Status::kOk) {
      return Status::kInvalidArgument;
    }
    detail::clear_all_checks(layers_);  // integrity: every cell cleared, every check 0
    routing_ = routing;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      thresholds_[layer] = layer_threshold(params_, layer, layers_.widths[layer]);
    }
    if (update_.init(params_, routing_.max_range_sq, layers_) != Status::kOk) {
      return Status::kInvalidArgument;
    }
    // [free-space hook 1/4] records bound beside the layers, margins derived.
    if (free_space_.init(params_, routing_.max_range_sq, layers_) != Status::kOk) {
      return Status::kInvalidArgument;
    }
    for (int layer = 0; layer < kLayerCount; ++layer) {
      drops_.layer[layer] = free_space_.records(layer);
      drops_.checks[layer] = free_space_.record_checks(layer);
    }
    totals_ = FrameCounters{};
    rejected_moves_ = 0U;
    rejected_frames_ = 0U;
    last_update_ns_ = 0U;
    accepted_frames_ = 0U;
    counted_frames_ = 0U;
    params_changes_ = 0U;
    last_frame_ = FrameCounters{};
    scrub_cursor_ = 0U;
    ++generation_;
    ready_ = detail::kStackReady;
    seal_state();
    return Status::kOk;
  }

  /// Exactly init()'s checks of `params` for a stack of this Config, nothing touched (no stack
  /// needed: a ground tool or a table-validation callback runs it): kOk if init(params) would
  /// succeed, else the status init() would answer.
  [[nodiscard]] static Status validate_params(const StackParams& params) noexcept {
    sensor::RoutingTable<kLayerCount> routing{};
    return derive(params, &routing);
  }

  /// Changes the parameters of an initialised stack and keeps every cell (a parameter command):
  /// after kOk the stack is the one init(params) followed by the same frames and moves would
  /// have built, as far as the changed fields allow: classification, coverage, thresholds
  /// (calibrated again when <= 0), the gate and change rule (held points kept, judged under the
  /// new gate at the next frame's end), budgets, free space, weight limit, Kalman floor, and a
  /// noise model or finest_max_sigma_m whose routing table equals the current one. Cells already
  /// folded keep the points they took.
  /// Refused, the stack bitwise unchanged: validate_params' refusals (its status); a change that
  /// needs a re-init (kInvalidArgument; *needs_reinit, when not nullptr, gets the param_field
  /// mask of the fields: the cell width, or the noise model / finest_max_sigma_m when they
  /// change the routing); kNotInitialised; kCorrupt (state_status). *needs_reinit is 0 otherwise.
  [[nodiscard]] Status set_params(const StackParams& params, std::uint32_t* needs_reinit) noexcept {
    if (needs_reinit != nullptr) {
      *needs_reinit = 0U;
    }
    const Status state = verify_state();
    if (state != Status::kOk) {
      return state;
    }
    sensor::RoutingTable<kLayerCount> routing{};
    const Status status = derive(params, &routing);
    if (status != Status::kOk) {
      return status;
    }
    const std::uint32_t changed = changed_param_fields(params_, params);
    std::uint32_t reinit = changed & param_field::kReinitAlways;
    if (!detail::same_float_bits(routing.max_range_sq, routing_.max_range_sq, std::size(routing.max_range_sq))) {
      reinit |= changed & (param_field::kNoise | param_field::kFinestMaxSigma);
    }
    if (reinit != 0U) {
      if (needs_reinit != nullptr) {
        *needs_reinit = reinit;
      }
      return Status::kInvalidArgument;
    }
    float thresholds[Layers::kLayerSlots]{};
    for (int layer = 0; layer < kLayerCount; ++layer) {
      thresholds[layer] = layer_threshold(params, layer, layers_.widths[layer]);
    }
    // Refuses only what derive() refused: nothing is changed before it has answered.
    if (update_.set_constants(params, routing_.max_range_sq, layers_) != Status::kOk) {
      return Status::kInvalidArgument;
    }
    params_ = params;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      thresholds_[layer] = thresholds[layer];
    }
    free_space_.set_constants(params_, routing_.max_range_sq, layers_);
    params_changes_ = params_changes_ == UINT32_MAX ? params_changes_ : params_changes_ + 1U;
    seal_state();
    return Status::kOk;
  }

  /// Zeroes the counters (total_counters, rejected_moves, rejected_frames, frames_since_reset,
  /// params_changes); no cell, parameter or accepted_frames() (map exchange numbers its deltas
  /// by it) changes. kNotInitialised; kCorrupt (state_status).
  [[nodiscard]] Status reset_counters() noexcept {
    const Status state = verify_state();
    if (state != Status::kOk) {
      return state;
    }
    totals_ = FrameCounters{};
    rejected_moves_ = 0U;
    rejected_frames_ = 0U;
    counted_frames_ = 0U;
    params_changes_ = 0U;
    return Status::kOk;
  }

  /// True after a successful init() or load_snapshot() (whether or not the state is intact:
  /// state_status() says that).
  [[nodiscard]] bool initialised() const noexcept { return ready_ == detail::kStackReady; }

  /// kOk if initialised and the bookkeeping (parameters, derived constants, every grid's storage
  /// binding and window) matches the seals taken when it last changed; kNotInitialised before
  /// init; kCorrupt if an upset changed any of it (every call then answers kCorrupt, changing
  /// nothing, until init() or load_snapshot()). Every call that reads or writes cells checks it
  /// first (docs/performance.md section 12: its cost).
  [[nodiscard]] Status state_status() const noexcept {
    const Status status = query_status();
    if (status != Status::kOk || update_seal() == update_seal_) {
      return status;
    }
    return Status::kCorrupt;
  }

  /// state_status() for a caller that may change the map (every mutating call runs it first): a
  /// corruption it finds is recorded in the initialised word, so that every later call, the
  /// queries included (they verify only what they use), answers kCorrupt too.
  [[nodiscard]] Status verify_state() noexcept {
    const Status status = state_status();
    if (status == Status::kCorrupt) {
      ready_ = detail::kStackCorrupt;
    }
    return status;
  }

  // -------------------------------------------------------------------------------------------
  // Run phase
  // -------------------------------------------------------------------------------------------

  /// Re-centres every layer on the robot at (x, y) (map frame, m). Each layer snaps its centre
  /// to an even cell index (the nearest multiple of twice its cell width), so every window
  /// starts on a coarse-cell boundary: each coarse cell covers exactly 2 x 2 finer cells after
  /// every move. Cells that leave a window are cleared; others stay bitwise unchanged.
  /// Refused (counted, map unchanged): non-finite or out-of-range position. kCorrupt (map
  /// unchanged) when the state failed its check (state_status), as every call below.
  [[nodiscard]] Status move_to(float x, float y) noexcept {
    const Status state = verify_state();
    if (state != Status::kOk) {
      return state;
    }
    const Status status = check_position(x, y);
    if (status != Status::kOk) {
      ++rejected_moves_;
      return status;
    }
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const CellIndex old_min = layers_.window_min(layer);
      const Status moved = layers_.move_layer(layer, snapped_centre(x, y, layers_.widths[layer]));
      if (moved != Status::kOk) {
        seal_state();
        return moved;  // not reachable: check_position bounds every centre
      }
      // Integrity: the cells the move cleared have check 0 again.
      detail::clear_checks_after_move(detail::layer_checks(layers_, layer), Layers::side(layer), old_min,
                                      layers_.window_min(layer));
      free_space_.follow(layer, layers_.centre(layer));  // [free-space hook 2/4] records move with the window
    }
    seal_state();
    return Status::kOk;
  }

  /// The same move for a pose that is known only to `position_sigma_m` (m, 1-sigma, isotropic
  /// in x and y): the odometry's uncertainty of the position change since the last move. After
  /// the window move, every observed cell accounts for it (map/detail/motion.hpp): a CCM cell's
  /// height-estimate variance at its mean grows by inclination^2 sigma^2 through a smaller
  /// weight (its statistics scaled as the weight limiter scales them, never below min_weight:
  /// new points then count more), a constant cell's height variance grows by gradient^2 sigma^2.
  /// One pass over every cell (CADRE: 14,336); position_sigma_m = 0 is move_to(x, y) exactly.
  /// Refused (counted, map unchanged): as move_to(x, y); a position_sigma_m that is not finite
  /// (kNonFiniteInput), negative (kInvalidArgument) or above kMaxAbsCoordinateM (kOutOfRange).
  [[nodiscard]] Status move_to(float x, float y, float position_sigma_m) noexcept {
    const Status state = verify_state();
    if (state != Status::kOk) {
      return state;
    }
    Status status = check_position(x, y);
    if (status == Status::kOk) {
      status = !std::isfinite(position_sigma_m) ? Status::kNonFiniteInput
               : position_sigma_m < 0.0F        ? Status::kInvalidArgument
               : position_sigma_m > kMaxAbsCoordinateM ? Status::kOutOfRange
                                                       : Status::kOk;
    }
    if (status != Status::kOk) {
      ++rejected_moves_;
      return status;
    }
    status = move_to(x, y);
    if (status == Status::kOk && position_sigma_m > 0.0F) {
      // The pass reads every cell: it resets (and counts) those an upset changed.
      const std::uint32_t corrupted = detail::forget_for_motion(layers_, params_, position_sigma_m * position_sigma_m);
      FrameCounters found{};
      found.corrupted_cells = corrupted;
      detail::accumulate(totals_, found);
    }
    return status;
  }

  /// Folds one frame of points given in the map frame. `sensor_origin` is the sensor's
  /// position in the map frame (the noise model needs the range). Each point goes to the finest
  /// layer whose window holds it and whose cell width satisfies Section IV-G for its range
  /// noise; rejected points are counted by reason in `counters` (may be nullptr) and in
  /// total_counters(). Refused as a whole (counted in rejected_frames(), map unchanged): null
  /// points with n > 0 or n >= 2^32 (kInvalidArgument), a non-finite (kNonFiniteInput) or
  /// out-of-range (kOutOfRange) sensor origin; kCorrupt (state_status). Each accepted frame, with
  /// points or none, also runs the scrub's slice (map/detail/integrity.hpp): counters->corrupted_cells.
  [[nodiscard]] Status update_frame(const PointXYZ* points, std::size_t n, const PointXYZ& sensor_origin,
                                    FrameCounters* counters) noexcept {
    return update_frame(points, nullptr, n, sensor_origin, counters);
  }

  /// Same, with a weight per point (the w_t of eq. (1), e.g. from a PLY's confidence):
  /// weights[i] replaces the noise model's weight for points[i]; weights == nullptr means the
  /// noise model's weight. A weight that is not in (0, kMaxMeasurementWeight] (NaN included)
  /// refuses its point, counted as rejected_weight. Kalman cells ignore weights (their gain comes
  /// from the range variance); CCM and OMG cells use them.
  [[nodiscard]] Status update_frame(const PointXYZ* points, const float* weights, std::size_t n,
                                    const PointXYZ& sensor_origin, FrameCounters* counters) noexcept {
    FrameCounters frame{};
    detail::FramePose pose{};
    std::uint64_t start = 0U;
    const Status status = begin_frame(points, n, sensor_origin, nullptr, &pose, frame, counters, &start);
    if (status != Status::kOk) {
      return status;
    }
    update_.run_map(layers_, params_, points, weights, n, pose, frame, free_space_.begin_sight(pose, update_.frame_sums()));
    // [free-space hook 3/4] lines of sight over the updated layers.
    free_space_.run_map(layers_, params_, update_.front(), update_.scratch(), points, weights, n, pose, frame);
    finish_frame(frame, start, counters);
    return Status::kOk;
  }

  /// Same for points in the sensor frame: p_map = R p + t with the sensor pose (R, t), the
  /// path a rover flies. The transform runs in float (map/update/front.hpp): position error
  /// against the double-precision transform below 3 um per axis within 10 m of the sensor
  /// (docs/design.md section 4.4). Sensor-frame coordinates of 2^11 m or more are refused as out of range.
  /// Also refused as a whole: a non-finite rotation (kNonFiniteInput) or one that is not a
  /// rotation (|r_ij| > 1.001 or R^T R off the identity by more than 1e-3: kInvalidArgument).
  [[nodiscard]] Status update_frame_sensor(const PointXYZ* points, std::size_t n, const Pose& sensor_pose,
                                           FrameCounters* counters) noexcept {
    FrameCounters frame{};
    detail::FramePose pose{};
    std::uint64_t start = 0U;
    const Status status =
        begin_frame(points, n, sensor_pose.translation, &sensor_pose.rotation[0][0], &pose, frame, counters, &start);
    if (status != Status::kOk) {
      return status;
    }
    update_.run_sensor(layers_, params_, points, n, pose, frame, free_space_.begin_sight(pose, update_.frame_sums()));
    // [free-space hook 4/4] lines of sight over the updated layers.
    free_space_.run_sensor(layers_, params_, update_.front(), update_.scratch(), points, n, pose, frame);
    finish_frame(frame, start, counters);
    return Status::kOk;
  }

  // -------------------------------------------------------------------------------------------
  // Queries (const, constant time in map size and point count)
  // -------------------------------------------------------------------------------------------

  /// Answer from the finest layer that knows the cell at (x, y): a piece-wise constant cell
  /// with at least min_weight, or a (pooled) CCM cell that passes the coverage test (ccm_is_covered)
  /// or is an obstacle (see classify_ccm).
  /// For an answer from the piece-wise constant layer, height and elevation variance come from
  /// it and slope, normal variance and class from the first CCM layer's pooled cell there when
  /// that is known (hazards are a CCM matter); otherwise the roughness filter classifies.
  /// A cell that lines of sight proved a drop-off (docs/design.md, "Free space from lines of
  /// sight"), unobserved and with no finer point below it, answers in that order like a known
  /// cell: kOk with class kDropOff, weight 0 and height_m the upper bound of the terrain there.
  /// kOutsideMap if no layer holds (x, y); kUnknown if none knows it; kNotInitialised; kCorrupt.
  /// A distrusted cell on the way (its bits disagree with its check, or the scrub reset it, and
  /// no point has landed in it since; for a CCM cell, also one pooled into it) answers kUnknown
  /// with upset set, and no coarser layer is asked (map/detail/integrity.hpp, "distrust").
  [[nodiscard]] QueryResult query(float x, float y) const noexcept {
    const Status state = query_status();
    if (state != Status::kOk) {
      return detail::empty_result(state, -1);
    }
    return view().query(x, y);
  }

  /// Answer of one named layer (0 = finest). kInvalidArgument for a bad layer, kOutsideMap if
  /// the layer does not hold (x, y), kUnknown if its cell is not known there.
  [[nodiscard]] QueryResult query_layer(int layer, float x, float y) const noexcept {
    const Status state = query_status();
    if (state != Status::kOk) {
      return detail::empty_result(state, -1);
    }
    if (layer < 0 || layer >= kLayerCount) {
      return detail::empty_result(Status::kInvalidArgument, -1);
    }
    CellIndex index{};
    if (!layers_.locate(layer, x, y, &index)) {
      return detail::empty_result(Status::kOutsideMap, -1);
    }
    return view().answer_at(layer, index, x, y, true);
  }

  /// The CCM statistics of a CCM layer's cell as a query sees them: the cell's own points
  /// merged with the pooled finer layers (Section IV-F), recursively. The zero cell for a bad
  /// layer, an index outside the layer's window, or before init; the distrusted cell (weight
  /// -0.0F: std::signbit) if it or a cell pooled into it is distrusted (map/detail/integrity.hpp).
  [[nodiscard]] CcmCellType pooled_cell(int layer, CellIndex index) const noexcept {
    // Outside the window: the zero cell, before pooled() forms the child index 2 * index (an
    // arbitrary index would overflow int32 and alias cells near the origin).
    if (!layer_is_ccm(layer) || query_status() != Status::kOk || !layers_.contains(layer, index)) {
      return CcmCellType{};
    }
    return detail::pooled(layers_, params_.weight_limit, layer, index);
  }

  /// Writes every observed cell (weight > 0) of `layer`, and every unobserved drop-off cell
  /// (weight 0, height its upper bound, class kDropOff), into out[0..*written), rows of
  /// increasing y. kBufferTooSmall (nothing written) if capacity < layer_capacity(layer).
  [[nodiscard]] Status export_layer(int layer, CellRecord* out, std::size_t capacity,
                                    std::size_t* written) const noexcept {
    if (written != nullptr) {
      *written = 0U;
    }
    const Status state = query_status();
    if (state != Status::kOk) {
      return state;
    }
    if (layer < 0 || layer >= kLayerCount || out == nullptr || written == nullptr) {
      return Status::kInvalidArgument;
    }
    if (capacity < layer_capacity(layer)) {
      return Status::kBufferTooSmall;
    }
    std::size_t count = 0U;
    const float width = layers_.widths[layer];
    const detail::QueryView<Config> answers = view();
    auto emit = [&](CellIndex index) {
      const float cx = grid::cell_centre(index.x, width);
      const float cy = grid::cell_centre(index.y, width);
      const QueryResult q = answers.answer_at(layer, index, cx, cy, /*require_known=*/false);
      if (q.weight > 0.0F || q.cell_class == CellClass::kDropOff) {
        out[count] = CellRecord{index, cx, cy, q.weight, q.height_m, q.slope_x, q.slope_y,
                                q.normal_variance, q.elevation_variance, q.cell_class};
        ++count;
      }
    };
    if (layer_is_ccm(layer)) {
      layers_.ccm_grid(layer).for_each([&](CellIndex index, const CcmCellType&) { emit(index); });
    } else {
      layers_.fine.for_each([&](CellIndex index, const FineCell&) { emit(index); });
    }
    *written = count;
    return Status::kOk;
  }

  // -------------------------------------------------------------------------------------------
  // Introspection
  // -------------------------------------------------------------------------------------------

  /// Cells per axis of a layer; 0 for a bad layer.
  [[nodiscard]] static constexpr std::int32_t layer_side(int layer) noexcept { return Layers::side(layer); }
  /// Cells of a layer (side^2): the export buffer a layer needs; 0 for a bad layer.
  [[nodiscard]] static constexpr std::size_t layer_capacity(int layer) noexcept { return Layers::capacity(layer); }
  [[nodiscard]] static constexpr bool layer_is_ccm(int layer) noexcept { return Layers::is_ccm(layer); }
  /// Cell width of a layer (m); 0 for a bad layer or before init.
  [[nodiscard]] float layer_cell_width(int layer) const noexcept {
    return (layer >= 0 && layer < kLayerCount) ? layers_.widths[layer] : 0.0F;
  }
  /// Largest squared sensor range (m^2) routed to `layer` (Section IV-G).
  [[nodiscard]] float layer_max_range_sq(int layer) const noexcept {
    return (layer >= 0 && layer < kLayerCount) ? routing_.max_range_sq[layer] : 0.0F;
  }
  [[nodiscard]] float normal_variance_threshold(int layer) const noexcept {
    return (layer >= 0 && layer < kLayerCount) ? thresholds_[layer] : 0.0F;
  }
  /// Window centre of a layer (global cell index); {0, 0} for a bad layer.
  [[nodiscard]] CellIndex layer_centre(int layer) const noexcept { return layers_.centre(layer); }
  [[nodiscard]] const StackParams& params() const noexcept { return params_; }
  [[nodiscard]] const FrameCounters& total_counters() const noexcept { return totals_; }
  [[nodiscard]] std::uint32_t rejected_moves() const noexcept { return rejected_moves_; }
  [[nodiscard]] std::uint32_t rejected_frames() const noexcept { return rejected_frames_; }
  /// Duration of the last accepted frame update (platform monotonic clock, ns).
  [[nodiscard]] std::uint64_t last_update_ns() const noexcept { return last_update_ns_; }
  /// Cells whose points outside the outlier gate await the change rule (docs/design.md,
  /// "Outlier gate and change"); 0 with the gate off. Not map state: not in snapshots.
  [[nodiscard]] std::uint32_t held_cells() const noexcept {
    return update_.gate().pending_ccm_cells() + update_.gate().pending_fine_cells();
  }
  /// Cells with held points at the end of the last frame, before the change rule decided (the
  /// held-point slots it took; at most kCcmHeldSlots + kFineHeldSlots).
  [[nodiscard]] std::uint32_t last_frame_held_cells() const noexcept { return update_.gate().last_frame_slots(); }
  /// Frame updates accepted since init, load_snapshot() or reset_counters() (saturating).
  [[nodiscard]] std::uint32_t frames_since_reset() const noexcept { return counted_frames_; }
  /// set_params() accepted since init, load_snapshot() or reset_counters() (saturating).
  [[nodiscard]] std::uint32_t params_changes() const noexcept { return params_changes_; }
  /// Counters of the last accepted frame update (zero before the first).
  [[nodiscard]] const FrameCounters& last_frame() const noexcept { return last_frame_; }
  /// Cells of `layer` holding points (weight > 0) whose bits agree with their check; 0 for a bad
  /// layer or a stack whose state failed its check. One pass over the layer.
  [[nodiscard]] std::uint32_t observed_cells(int layer) const noexcept {
    if (layer < 0 || layer >= kLayerCount || query_status() != Status::kOk) {
      return 0U;
    }
    std::uint32_t count = 0U;
    auto tally = [this, &count](CellIndex, const auto& cell) {
      count += (cell.weight > 0.0F && detail::cell_intact(layers_, cell)) ? 1U : 0U;
    };
    if (layer_is_ccm(layer)) {
      layers_.ccm_grid(layer).for_each(tally);
    } else {
      layers_.fine.for_each(tally);
    }
    return count;
  }
  /// Frame updates accepted since init (wraps at 2^32): the sequence number that map exchange
  /// (persistence/exchange.hpp) puts in its deltas. Restarts at 0 with init() and load_snapshot().
  [[nodiscard]] std::uint32_t accepted_frames() const noexcept { return accepted_frames_; }
  /// Raw CCM layer `ccm_index` (0 = first CCM layer), read-only, for serialisation, pictures and
  /// tests. Contract: 0 <= ccm_index < kCcmLayerCount; a violation is reported to the assert
  /// hook and answered with an empty, uninitialised grid (every accessor safe, no cells).
  [[nodiscard]] const RingGrid<CcmCellType>& ccm_layer(int ccm_index) const noexcept {
    CCMAP_ASSERT_OR_RETURN(ccm_index >= 0 && ccm_index < kCcmLayerCount, kNoGrid);
    return layers_.ccm[ccm_index];
  }
  /// Raw piece-wise constant layer (uninitialised when the configuration has none).
  [[nodiscard]] const RingGrid<FineCell>& fine_layer() const noexcept { return layers_.fine; }
  /// For readers of the raw layers (registration, tools): true if `cell`, a cell of this stack's
  /// layers (a reference from ccm_layer() or fine_layer(), never a copy), agrees with its check
  /// (map/detail/integrity.hpp). A cell that does not was changed by an upset: it is unknown, as
  /// every query answers it (a cell the scrub reset agrees with its check and has weight -0.0F:
  /// unknown too). A reference outside the layers is reported to the assert hook and answered false.
  [[nodiscard]] bool cell_intact(const CcmCellType& cell) const noexcept {
    const std::size_t at = storage_index(&cell, layers_.ccm_storage, Layers::kCcmCellCount);
    CCMAP_ASSERT_OR_RETURN(at < Layers::kCcmCellCount, false);
    return detail::cell_signature(cell) == layers_.checks.ccm[at];
  }
  [[nodiscard]] bool cell_intact(const FineCell& cell) const noexcept {
    const std::size_t at = storage_index(&cell, layers_.fine_storage, Layers::kFineCellCount);
    CCMAP_ASSERT_OR_RETURN(kHasFine && at < Layers::kFineCellCount, false);
    return detail::cell_signature(cell) == layers_.checks.fine[at];
  }

  // save_snapshot / load_snapshot read and restore the private state through this friend only;
  // a new map-state member must be added to the snapshot format (persistence/snapshot.hpp) as well.
  // Bookkeeping (accepted_frames_, generation_, the layers' KeptWindows, the grids' move
  // telemetry) is not map state.
  friend struct detail::SnapshotAccess<Config>;
  // The planner queries (planner/footprint.hpp, planner/path_query.hpp, planner/costmap.hpp) read the layers
  // through the query view, and only that, through this friend.
  friend struct detail::PlannerAccess<Config>;
  // Map exchange reads and folds cells through this friend (persistence/exchange.hpp).
  friend struct detail::ExchangeAccess<Config>;
  // The global map saves the cells a move clears and restores them on return, through this friend.
  friend struct detail::GlobalAccess<Config>;

 private:
  /// Index of `cell` in `storage` (`count` cells), or `count` if it is not one of them (compared
  /// as addresses: no pointer arithmetic across objects).
  template <typename Cell>
  [[nodiscard]] static std::size_t storage_index(const Cell* cell, const Cell* storage, std::size_t count) noexcept {
    const auto at = reinterpret_cast<std::uintptr_t>(cell);
    const auto begin = reinterpret_cast<std::uintptr_t>(storage);
    if (at < begin || (at - begin) % sizeof(Cell) != 0U || (at - begin) / sizeof(Cell) >= count) {
      return count;
    }
    return (at - begin) / sizeof(Cell);
  }

  [[nodiscard]] detail::QueryView<Config> view() const noexcept {
    return detail::QueryView<Config>(layers_, params_, thresholds_, &drops_);
  }

  /// Prologue of every frame update: a refused frame (bad arguments, bad origin or rotation) is
  /// counted and answered; an accepted one gets its frame pose (detail::FramePose), clock and counters.
  [[nodiscard]] Status begin_frame(const PointXYZ* points, std::size_t n, const PointXYZ& origin, const float* rotation,
                                   detail::FramePose* pose, FrameCounters& frame, FrameCounters* counters,
                                   std::uint64_t* start) noexcept {
    const Status state = verify_state();
    if (state != Status::kOk) {
      rejected_frames_ += state == Status::kCorrupt ? 1U : 0U;
      write_counters(frame, counters);
      return state;
    }
    bool too_many = false;
    // Frame counters are 32-bit. A 32-bit size_t (Cortex-M) cannot exceed them, and there the
    // comparison would be always false (-Wtype-limits under the warning wall).
    if constexpr (sizeof(std::size_t) > sizeof(std::uint32_t)) {
      too_many = n > 0xFFFFFFFFULL;
    }
    const Status status = ((points == nullptr && n > 0U) || too_many) ? Status::kInvalidArgument
                                                                      : detail::make_frame_pose(origin, rotation, update_.front(), pose);
    if (status != Status::kOk) {
      ++rejected_frames_;
      write_counters(frame, counters);
      return status;
    }
    *start = platform::monotonic_ns();
    frame.received = static_cast<std::uint32_t>(n);
    // Integrity: the scrub's slice of this frame (map/detail/integrity.hpp).
    frame.corrupted_cells += detail::scrub_slice(layers_, &scrub_cursor_, kScrubCellsPerFrame);
    // ... and of the free-space records (a record reset to no evidence counts as a corrupted cell).
    frame.corrupted_cells += free_space_.scrub(kScrubRecordsPerFrame);
    return Status::kOk;
  }

  /// The seal of the bookkeeping (state_status): every value that indexes memory or gives the
  /// cells their meaning. Counters, telemetry and per-frame scratch are not in it.
  [[nodiscard]] detail::StateSeal state_seal() const noexcept {
    detail::StateHasher h;
    h.add(ready_);
    h.add(params_);
    h.add(routing_);
    h.add(thresholds_);
    h.add(generation_);
    detail::hash_layer_bindings(h, layers_);
    free_space_.hash_bindings(h);
    h.add(drops_);
    return h.seal();
  }
  /// The constants only the update path uses (its front, widths in Q40, gates): the queries need
  /// not verify them.
  [[nodiscard]] detail::StateSeal update_seal() const noexcept {
    detail::StateHasher h;
    update_.hash_constants(h);
    return h.seal();
  }
  /// state_status() without the update path's constants: what a query uses.
  [[nodiscard]] Status query_status() const noexcept {
    if (ready_ == 0U && seal_ == detail::StateSeal{}) {
      return Status::kNotInitialised;
    }
    if (ready_ != detail::kStackReady || state_seal() != seal_) {
      return Status::kCorrupt;
    }
    return Status::kOk;
  }
  /// Seals the bookkeeping after a legitimate change (init, move, load, exchange binding).
  void seal_state() noexcept {
    seal_ = state_seal();
    update_seal_ = update_seal();
  }

  /// init()'s checks of `params` (validate_params, set_params): the routing table they build in
  /// *routing. Nothing of the stack is touched.
  [[nodiscard]] static Status derive(const StackParams& params, sensor::RoutingTable<kLayerCount>* routing) noexcept {
    const Status status = validate_stack_params(params, kLayerCount);
    if (status != Status::kOk) {
      return status;
    }
    if (!kConfigOutlierGate<Config> && params.outlier_gate_sigma > 0.0F) {
      return Status::kInvalidArgument;  // the gate is not compiled into this Config (map/config.hpp)
    }
    float widths[Layers::kLayerSlots]{};
    float width = params.finest_cell_width_m;
    for (float& w : widths) {  // the widths LayerSet::init binds
      w = width;
      width *= 2.0F;
    }
    const Status routing_status =
        kHasFine ? sensor::build_routing_table(params.noise, widths, params.finest_max_sigma_m, routing)
                 : sensor::build_routing_table(params.noise, widths, routing);
    if (routing_status != Status::kOk) {
      return routing_status;
    }
    detail::FrontConfig front{};
    return detail::make_front_config(widths[0], routing->max_range_sq, kLayerCount, &front) == Status::kOk
               ? Status::kOk
               : Status::kInvalidArgument;
  }

  void finish_frame(const FrameCounters& frame, std::uint64_t start, FrameCounters* counters) noexcept {
    detail::accumulate(totals_, frame);
    ++accepted_frames_;
    counted_frames_ = counted_frames_ == UINT32_MAX ? counted_frames_ : counted_frames_ + 1U;
    last_frame_ = frame;
    const std::uint64_t end = platform::monotonic_ns();
    last_update_ns_ = end >= start ? end - start : 0U;
    write_counters(frame, counters);
  }

  static void write_counters(const FrameCounters& frame, FrameCounters* counters) noexcept {
    if (counters != nullptr) {
      *counters = frame;
    }
  }

  /// The window centre of a layer of width `width` for the robot at (x, y): the nearest even
  /// index. |x|, |y| <= kMaxAbsCoordinateM and width >= 0.19 mm keep it within +-2^30.
  [[nodiscard]] static CellIndex snapped_centre(float x, float y, float width) noexcept {
    const float inv_double_width = 0.5F / width;
    return CellIndex{2 * static_cast<std::int32_t>(std::floor(x * inv_double_width + 0.5F)),
                     2 * static_cast<std::int32_t>(std::floor(y * inv_double_width + 0.5F))};
  }

  // ---- state: every member zero-initialised, so a static stack lives in .bss ----
  Layers layers_{};
  StackParams params_{};
  sensor::RoutingTable<kLayerCount> routing_{};
  float thresholds_[Layers::kLayerSlots]{};
  FrameCounters totals_{};
  std::uint32_t rejected_moves_ = 0U;
  std::uint32_t rejected_frames_ = 0U;
  std::uint64_t last_update_ns_ = 0U;
  std::uint32_t accepted_frames_ = 0U;  ///< accepted frame updates since init (bookkeeping)
  std::uint32_t counted_frames_ = 0U;   ///< accepted frame updates since init or reset_counters()
  std::uint32_t params_changes_ = 0U;   ///< set_params() accepted since init or reset_counters()
  FrameCounters last_frame_{};          ///< counters of the last accepted frame
  /// Changes on every init() and every binding of a MapExchange: an exchange bound to an older
  /// generation refuses to run (its record of what was sent no longer describes these cells).
  std::uint32_t generation_ = 0U;
  /// detail::kStackReady once initialised, 0 before (any other value: an upset). A word, not a
  /// bool: an upset in a bool is undefined behaviour when it is loaded.
  std::uint32_t ready_ = 0U;
  detail::StateSeal seal_{};        ///< integrity: seal of the bookkeeping (state_status)
  detail::StateSeal update_seal_{}; ///< integrity: seal of the update path's constants
  std::uint32_t scrub_cursor_ = 0U; ///< integrity: next cell the scrub checks (clamped on use)
  /// The safe answer of ccm_layer() to a bad index: a constant, outside the stack's storage (no
  /// upset can give it a storage pointer).
  static constexpr RingGrid<CcmCellType> kNoGrid{};
  // ---- update-path scratch and derived constants (not map state: not in snapshots) ----
  detail::UpdatePath<Config> update_{};
  // ---- free space from lines of sight: records per cell (map state: in snapshots), its scratch ----
  detail::FreeSpace<Config> free_space_{};
  detail::DropRecords drops_{};  ///< the record grids queries read (all nullptr without free space)
};

}  // namespace ccmap
