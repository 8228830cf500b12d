// The robot-centric, multi-size, multi-resolution map stack (paper Fig. 2, Sections IV-D..G).
//
// Data flows one way: points -> sensor noise model -> routing -> one cell update; queries read
// cells and pool finer layers on demand (Section IV-F). Every layer is a statically sized ring
// buffer inside this object: after init() nothing allocates, and every call is bounded:
//   update_frame   O(points)                       move_to   O(cells that leave)
//   query          O(4^layers) cells, independent of map size and point count
//   export_layer   O(side^2 * 4^layers)
//
// Positions are map-frame metres relative to the stack origin (see map/types.hpp).
//
// Usage (two-phase life):
//   static ccmap::Stack<ccmap::CadreConfig> map;     // ~0.5 MB, static storage
//   if (map.init(ccmap::default_stack_params(0.04F)) != ccmap::Status::kOk) { ...fault... }
//   map.move_to(robot_x, robot_y);
//   map.update_frame(points, n, sensor_position, &counters);
//   const ccmap::QueryResult q = map.query(x, y);
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/grid/ring_grid.hpp"
#include "ccmap/map/classify.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/frame_chunk.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/platform/platform.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap {

namespace detail {
template <std::size_t N>
constexpr std::size_t sum_of_squares(const std::array<std::int32_t, N>& sides) noexcept {
  std::size_t total = 0U;
  for (std::size_t i = 0; i < N; ++i) {
    total += static_cast<std::size_t>(sides[i]) * static_cast<std::size_t>(sides[i]);
  }
  return total;
}
template <std::size_t N>
constexpr bool all_valid_sides(const std::array<std::int32_t, N>& sides) noexcept {
  for (std::size_t i = 0; i < N; ++i) {
    // Power of two, >= 4 so that half a side is even: windows then start on even indices
    // and every coarse cell covers exactly 2 x 2 cells of the next finer layer.
    if (!grid::is_power_of_two(sides[i]) || sides[i] < 4) {
      return false;
    }
  }
  return true;
}
void accumulate(FrameCounters& total, const FrameCounters& frame) noexcept;
}  // namespace detail

// ---- snapshot access (map/snapshot.hpp) ----
namespace detail {
template <typename Config>
struct SnapshotAccess;  // defined in map/snapshot.hpp: save/load read and restore the raw state
}  // namespace detail

template <typename Config>
class Stack {
 public:
  static constexpr bool kHasFine = Config::kFineKind != FineKind::kNone;
  static constexpr int kFineLayerCount = kHasFine ? 1 : 0;
  static constexpr int kCcmLayerCount = static_cast<int>(Config::kCcmSides.size());
  static constexpr int kLayerCount = kFineLayerCount + kCcmLayerCount;
  using FineCell = std::conditional_t<Config::kFineKind == FineKind::kOmg, OmgCell, KalmanCell>;

  static_assert(kLayerCount >= 1 && kLayerCount <= kMaxLayers, "1..kMaxLayers layers");
  static_assert(!kHasFine || (grid::is_power_of_two(Config::kFineSide) && Config::kFineSide >= 4),
                "fine side must be a power of two >= 4");
  static_assert(kHasFine || Config::kFineSide == 0, "no fine layer: kFineSide must be 0");
  static_assert(detail::all_valid_sides(Config::kCcmSides), "CCM sides must be powers of two >= 4");

  static constexpr std::size_t kFineCellCount =
      kHasFine ? static_cast<std::size_t>(Config::kFineSide) * static_cast<std::size_t>(Config::kFineSide) : 1U;
  static constexpr std::size_t kCcmCellCount =
      kCcmLayerCount > 0 ? detail::sum_of_squares(Config::kCcmSides) : 1U;

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
  /// routing table and calibrates the normal-variance thresholds. May be called again to reset.
  /// On failure the stack is left uninitialised and every other call answers kNotInitialised.
  [[nodiscard]] Status init(const StackParams& params) noexcept {
    initialised_ = false;
    const Status status = validate_stack_params(params, kLayerCount);
    if (status != Status::kOk) {
      return status;
    }
    params_ = params;
    float width = params.finest_cell_width_m;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      widths_[layer] = width;
      width *= 2.0F;
    }
    const CellIndex origin{0, 0};
    if constexpr (kHasFine) {
      if (fine_.init(fine_storage_, Config::kFineSide, widths_[0], origin) != Status::kOk) {
        return Status::kInvalidArgument;
      }
    }
    std::size_t offset = 0U;
    for (int c = 0; c < kCcmLayerCount; ++c) {
      const std::int32_t side = Config::kCcmSides[static_cast<std::size_t>(c)];
      if (ccm_[c].init(ccm_storage_ + offset, side, widths_[c + kFineLayerCount], origin) != Status::kOk) {
        return Status::kInvalidArgument;
      }
      offset += static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
    }
    const Status routing_status =
        kHasFine ? sensor::build_routing_table(params_.noise, widths_, params_.finest_max_sigma_m, &routing_)
                 : sensor::build_routing_table(params_.noise, widths_, &routing_);
    if (routing_status != Status::kOk) {
      return routing_status;
    }
    for (int layer = 0; layer < kLayerCount; ++layer) {
      thresholds_[layer] = layer_threshold(params_, layer, widths_[layer]);
    }
    if (init_update_path() != Status::kOk) {
      return Status::kInvalidArgument;
    }
    totals_ = FrameCounters{};
    rejected_moves_ = 0U;
    rejected_frames_ = 0U;
    last_update_ns_ = 0U;
    initialised_ = true;
    return Status::kOk;
  }

  [[nodiscard]] bool initialised() const noexcept { return initialised_; }

  // -------------------------------------------------------------------------------------------
  // Run phase
  // -------------------------------------------------------------------------------------------

  /// Re-centres every layer on the robot at (x, y) (map frame, m). Each layer snaps its centre
  /// to an even cell index (the nearest multiple of twice its cell width), so every window
  /// starts on a coarse-cell boundary: each coarse cell covers exactly 2 x 2 finer cells after
  /// every move. Cells that leave a window are cleared; others stay bitwise unchanged.
  /// Refused (counted, map unchanged): non-finite or out-of-range position.
  [[nodiscard]] Status move_to(float x, float y) noexcept {
    if (!initialised_) {
      return Status::kNotInitialised;
    }
    const Status status = check_position(x, y);
    if (status != Status::kOk) {
      ++rejected_moves_;
      return status;
    }
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const CellIndex centre = snapped_centre(x, y, widths_[layer]);
      const Status moved = layer_is_ccm(layer) ? ccm_[layer - kFineLayerCount].move_to(centre)
                                               : move_fine(centre);
      if (moved != Status::kOk) {
        return moved;
      }
    }
    return Status::kOk;
  }

  /// Folds one frame of points given in the map frame. `sensor_origin` is the sensor's
  /// position in the map frame (the noise model needs the range). Each point goes to the finest
  /// layer whose window holds it and whose cell width satisfies Section IV-G for its range
  /// noise; rejected points are counted by reason in `counters` (may be nullptr) and in
  /// total_counters(). Refused as a whole: null points with n > 0 (kInvalidArgument),
  /// non-finite sensor origin (kNonFiniteInput).
  /// The frame is processed in chunks of detail::kFrameChunkPoints (scratch inside the stack,
  /// no heap); the cells end bitwise as update_frame_sequential leaves them
  /// (tests/map/update_path_test.cpp).
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
    std::uint64_t start = 0U;
    const Status status = begin_frame(points, n, sensor_origin, true, frame, counters, &start);
    if (status != Status::kOk) {
      return status;
    }
    run_frame(points, weights, n, sensor_origin, nullptr, frame);
    finish_frame(frame, start, counters);
    return Status::kOk;
  }

  /// Same for points in the sensor frame: p_map = R p + t with the sensor pose (R, t).
  [[nodiscard]] Status update_frame_sensor(const PointXYZ* points, std::size_t n, const Pose& sensor_pose,
                                           FrameCounters* counters) noexcept {
    FrameCounters frame{};
    const PointXYZ origin{sensor_pose.translation.x(), sensor_pose.translation.y(), sensor_pose.translation.z()};
    std::uint64_t start = 0U;
    const Status status = begin_frame(points, n, origin, sensor_pose.rotation.allFinite(), frame, counters, &start);
    if (status != Status::kOk) {
      return status;
    }
    const Eigen::Matrix3f& r = sensor_pose.rotation;
    const detail::ChunkTransform transform{{r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)},
                                           {origin.x, origin.y, origin.z}};
    run_frame(points, nullptr, n, origin, &transform, frame);
    finish_frame(frame, start, counters);
    return Status::kOk;
  }

  /// The reference update: the same contract as update_frame (weights may be nullptr), one
  /// point after the other through the same front and cell functions, without the chunked
  /// sensor-frame scratch; tests/map/update_path_test.cpp holds the two paths bitwise equal.
  [[nodiscard]] Status update_frame_sequential(const PointXYZ* points, const float* weights, std::size_t n,
                                               const PointXYZ& sensor_origin, FrameCounters* counters) noexcept {
    FrameCounters frame{};
    std::uint64_t start = 0U;
    const Status status = begin_frame(points, n, sensor_origin, true, frame, counters, &start);
    if (status != Status::kOk) {
      return status;
    }
    detail::set_front_origin(front_, sensor_origin);
    for (std::size_t i = 0; i < n; ++i) {
      insert_point(points[i], weights != nullptr ? weights + i : nullptr, frame);
    }
    finish_fine_frame();
    finish_frame(frame, start, counters);
    return Status::kOk;
  }

  // -------------------------------------------------------------------------------------------
  // Queries (const, constant time in map size and point count)
  // -------------------------------------------------------------------------------------------

  /// Answer from the finest layer that knows the cell at (x, y): a piece-wise constant cell
  /// with at least min_weight, or a (pooled) CCM cell that passes the coverage test (eq. 12)
  /// or is an obstacle (see classify_ccm).
  /// For an answer from the piece-wise constant layer, height and elevation variance come from
  /// it and slope, normal variance and class from the first CCM layer's pooled cell there when
  /// that is covered (hazards are a CCM matter); otherwise the roughness filter classifies.
  /// kOutsideMap if no layer holds (x, y); kUnknown if none knows it.
  [[nodiscard]] QueryResult query(float x, float y) const noexcept {
    QueryResult result = empty_result(Status::kOutsideMap, -1);
    if (!initialised_) {
      result.status = Status::kNotInitialised;
      return result;
    }
    for (int layer = 0; layer < kLayerCount; ++layer) {
      CellIndex index{};
      if (!locate(layer, x, y, &index)) {
        continue;
      }
      if (result.status == Status::kOutsideMap) {
        result = empty_result(Status::kUnknown, layer);
      }
      QueryResult answer = answer_at(layer, index, x, y);
      if (answer.status != Status::kOk) {
        continue;
      }
      if (!layer_is_ccm(layer) && kCcmLayerCount > 0) {
        refine_with_ccm(x, y, answer);
      }
      return answer;
    }
    return result;
  }

  /// Answer of one named layer (0 = finest). kInvalidArgument for a bad layer, kOutsideMap if
  /// the layer does not hold (x, y), kUnknown if its cell is not known there.
  [[nodiscard]] QueryResult query_layer(int layer, float x, float y) const noexcept {
    if (!initialised_) {
      return empty_result(Status::kNotInitialised, -1);
    }
    if (layer < 0 || layer >= kLayerCount) {
      return empty_result(Status::kInvalidArgument, -1);
    }
    CellIndex index{};
    if (!locate(layer, x, y, &index)) {
      return empty_result(Status::kOutsideMap, -1);
    }
    return answer_at(layer, index, x, y);
  }

  /// The CCM statistics of a CCM layer's cell as a query sees them: the cell's own points
  /// merged with the pooled finer layers (Section IV-F), recursively. Zero cell outside.
  [[nodiscard]] CcmCell pooled_cell(int layer, CellIndex index) const noexcept {
    // Outside the window: the zero cell, before pooled() forms the child index 2 * index (an
    // arbitrary index would overflow int32 and alias cells near the origin).
    if (!initialised_ || layer < kFineLayerCount || layer >= kLayerCount ||
        !ccm_[layer - kFineLayerCount].contains(index)) {
      return CcmCell{};
    }
    return pooled(layer, index);
  }

  /// Writes every observed cell (weight > 0) of `layer` into out[0..*written), rows of
  /// increasing y. kBufferTooSmall (nothing written) if capacity < layer_capacity(layer).
  [[nodiscard]] Status export_layer(int layer, CellRecord* out, std::size_t capacity,
                                    std::size_t* written) const noexcept {
    if (written != nullptr) {
      *written = 0U;
    }
    if (!initialised_) {
      return Status::kNotInitialised;
    }
    if (layer < 0 || layer >= kLayerCount || out == nullptr || written == nullptr) {
      return Status::kInvalidArgument;
    }
    if (capacity < layer_capacity(layer)) {
      return Status::kBufferTooSmall;
    }
    std::size_t count = 0U;
    const float width = widths_[layer];
    auto emit = [&](CellIndex index) {
      const QueryResult q = answer_at(layer, index, grid::cell_centre(index.x, width),
                                      grid::cell_centre(index.y, width), /*require_known=*/false);
      if (q.weight > 0.0F) {
        out[count] = CellRecord{index, grid::cell_centre(index.x, width), grid::cell_centre(index.y, width),
                                q.weight, q.height_m, q.slope_x, q.slope_y, q.normal_variance,
                                q.elevation_variance, q.cell_class};
        ++count;
      }
    };
    if (layer_is_ccm(layer)) {
      ccm_[layer - kFineLayerCount].for_each([&](CellIndex index, const CcmCell&) { emit(index); });
    } else {
      fine_.for_each([&](CellIndex index, const FineCell&) { emit(index); });
    }
    *written = count;
    return Status::kOk;
  }

  // -------------------------------------------------------------------------------------------
  // Introspection
  // -------------------------------------------------------------------------------------------

  [[nodiscard]] static constexpr std::int32_t layer_side(int layer) noexcept {
    if (layer < 0 || layer >= kLayerCount) {
      return 0;
    }
    if (kHasFine && layer == 0) {
      return Config::kFineSide;
    }
    return Config::kCcmSides[static_cast<std::size_t>(layer - kFineLayerCount)];
  }
  [[nodiscard]] static constexpr std::size_t layer_capacity(int layer) noexcept {
    return static_cast<std::size_t>(layer_side(layer)) * static_cast<std::size_t>(layer_side(layer));
  }
  [[nodiscard]] static constexpr bool layer_is_ccm(int layer) noexcept {
    return layer >= kFineLayerCount && layer < kLayerCount;
  }
  [[nodiscard]] float layer_cell_width(int layer) const noexcept {
    return (layer >= 0 && layer < kLayerCount) ? widths_[layer] : 0.0F;
  }
  /// Largest squared sensor range (m^2) routed to `layer` (Section IV-G).
  [[nodiscard]] float layer_max_range_sq(int layer) const noexcept {
    return (layer >= 0 && layer < kLayerCount) ? routing_.max_range_sq[layer] : 0.0F;
  }
  [[nodiscard]] float normal_variance_threshold(int layer) const noexcept {
    return (layer >= 0 && layer < kLayerCount) ? thresholds_[layer] : 0.0F;
  }
  /// Window centre of a layer (global cell index).
  [[nodiscard]] CellIndex layer_centre(int layer) const noexcept {
    if (layer_is_ccm(layer)) {
      return ccm_[layer - kFineLayerCount].centre();
    }
    if constexpr (kHasFine) {
      if (layer == 0) {
        return fine_.centre();
      }
    }
    return CellIndex{0, 0};
  }
  [[nodiscard]] const StackParams& params() const noexcept { return params_; }
  [[nodiscard]] const FrameCounters& total_counters() const noexcept { return totals_; }
  [[nodiscard]] std::uint32_t rejected_moves() const noexcept { return rejected_moves_; }
  [[nodiscard]] std::uint32_t rejected_frames() const noexcept { return rejected_frames_; }
  /// Duration of the last accepted update_frame call (platform clock, ns).
  [[nodiscard]] std::uint64_t last_update_ns() const noexcept { return last_update_ns_; }
  /// Raw layers (read-only), for serialisation, pictures and tests.
  [[nodiscard]] const RingGrid<CcmCell>& ccm_layer(int ccm_index) const noexcept { return ccm_[ccm_index]; }
  [[nodiscard]] const RingGrid<FineCell>& fine_layer() const noexcept { return fine_; }

  // ---- snapshot access (map/snapshot.hpp) ----
  // save_snapshot / load_snapshot read and restore the private state through this friend only;
  // a new state member must be added to the snapshot format (map/snapshot.hpp) as well.
  friend struct detail::SnapshotAccess<Config>;
  // ---- end of snapshot access ----

 private:
  // ---- frame helpers ----
  [[nodiscard]] Status check_frame(const PointXYZ* points, std::size_t n, const PointXYZ& origin) const noexcept {
    if (!initialised_) {
      return Status::kNotInitialised;
    }
    if (points == nullptr && n > 0U) {
      return Status::kInvalidArgument;
    }
    // Frame counters are 32-bit. A 32-bit size_t (Cortex-M) cannot exceed them, and there the
    // comparison would be always false (-Wtype-limits under the warning wall).
    if constexpr (sizeof(std::size_t) > sizeof(std::uint32_t)) {
      if (n > 0xFFFFFFFFULL) {
        return Status::kInvalidArgument;
      }
    }
    return ccm_check_point(origin.x, origin.y, origin.z);
  }

  /// Prologue of every frame update: a refused frame (bad arguments, non-finite origin or
  /// rotation) is counted and answered; an accepted one starts its clock and counters.
  [[nodiscard]] Status begin_frame(const PointXYZ* points, std::size_t n, const PointXYZ& origin, bool rotation_finite,
                                   FrameCounters& frame, FrameCounters* counters, std::uint64_t* start) noexcept {
    Status status = check_frame(points, n, origin);
    if (status == Status::kOk && !rotation_finite) {
      status = Status::kNonFiniteInput;
    }
    if (status != Status::kOk) {
      ++rejected_frames_;
      write_counters(frame, counters);
      return status;
    }
    *start = platform::monotonic_ns();
    frame.received = static_cast<std::uint32_t>(n);
    return Status::kOk;
  }

  void finish_frame(const FrameCounters& frame, std::uint64_t start, FrameCounters* counters) noexcept {
    detail::accumulate(totals_, frame);
    const std::uint64_t end = platform::monotonic_ns();
    last_update_ns_ = end >= start ? end - start : 0U;
    write_counters(frame, counters);
  }

  static void write_counters(const FrameCounters& frame, FrameCounters* counters) noexcept {
    if (counters != nullptr) {
      *counters = frame;
    }
  }

  /// The per-point path (update_frame_sequential): `weight` points at the caller's weight for
  /// this point, or is nullptr for the noise model's weight.
  void insert_point(const PointXYZ& p, const float* weight_in, FrameCounters& frame) noexcept {
    const detail::PointFront front = detail::update_point_front(p.x, p.y, p.z, front_);
    apply_point(p, front, weight_in, weight_in == nullptr && constant_weight_, frame);
  }

  // ---- the chunked update path (update_frame, update_frame_sensor) ----
  /// Front half per chunk (detail::prepare_chunk: transform, validation, range, routing,
  /// finest index), back half (apply_point: window walk and one cell update per point), then
  /// the frame's piece-wise constant batches (finish_fine_frame).
  void run_frame(const PointXYZ* points, const float* weights, std::size_t n, const PointXYZ& origin,
                 const detail::ChunkTransform* transform, FrameCounters& frame) noexcept {
    detail::set_front_origin(front_, origin);
    const bool unit_weights = weights == nullptr && constant_weight_;
    if (transform == nullptr) {
      // Map-frame input: one pass, front and cell per point, no scratch traffic.
      for (std::size_t i = 0; i < n; ++i) {
        const PointXYZ& p = points[i];
        apply_point(p, detail::update_point_front(p.x, p.y, p.z, front_), weights != nullptr ? weights + i : nullptr,
                    unit_weights, frame);
      }
    } else {
      for (std::size_t begin = 0; begin < n; begin += detail::kFrameChunkPoints) {
        const std::size_t remaining = n - begin;
        const std::size_t count = remaining < detail::kFrameChunkPoints ? remaining : detail::kFrameChunkPoints;
        detail::prepare_chunk(points + begin, count, transform, front_, chunk_);
        // begin < n, so count >= 1; cppcheck 2.10 loses that through the loop bound.
        // cppcheck-suppress knownConditionTrueFalse
        for (std::size_t i = 0; i < count; ++i) {
          const detail::PointFront front{chunk_.code[i], chunk_.ix[i], chunk_.iy[i], chunk_.range_units_sq[i],
                                         chunk_.z_units[i]};
          apply_point(PointXYZ{chunk_.x[i], chunk_.y[i], chunk_.z[i]}, front,
                      weights != nullptr ? weights + begin + i : nullptr, unit_weights, frame);
        }
      }
    }
    finish_fine_frame();
  }

  /// Back half for one routed point. The layer walk uses index_k = index_0 >> k (floor
  /// division by 2^k): widths are w_0 * 2^k exactly and 1/w_k = (1/w_0) * 2^-k exactly in
  /// float, so floor(x / w_k) = floor(floor(x / w_0) / 2^k), the index locate() computes. (>>
  /// of a negative int32 is an arithmetic shift with gcc and clang, the floor division; C++20
  /// makes it standard.)
  void apply_point(const PointXYZ& p, const detail::PointFront& front, const float* weight_in, bool unit_weights,
                   FrameCounters& frame) noexcept {
    const std::uint32_t code = front.code;
    if (code >= detail::kChunkNonFinite) {
      frame.rejected_non_finite += code == detail::kChunkNonFinite ? 1U : 0U;
      frame.rejected_out_of_range += code == detail::kChunkOutOfRange ? 1U : 0U;
      frame.too_noisy += code == detail::kChunkTooNoisy ? 1U : 0U;
      return;
    }
    float weight = 1.0F;  // the constant model's weight: always valid
    if (!unit_weights) {
      weight = weight_in != nullptr ? *weight_in
                                    : params_.noise.weight_at_range_sq(detail::to_range_sq_m2(front.range_units_sq, front_));
      if (ccm_check_weight(weight) != Status::kOk) {
        ++frame.rejected_weight;
        return;
      }
    }
    for (int layer = static_cast<int>(code); layer < kLayerCount; ++layer) {
      const CellIndex index{front.ix0 >> layer, front.iy0 >> layer};
      if (layer_is_ccm(layer)) {
        RingGrid<CcmCell>& layer_grid = ccm_[layer - kFineLayerCount];
        if (!layer_grid.contains(index)) {
          continue;
        }
        const float width = widths_[layer];
        detail::ccm_update_unchecked(layer_grid.cell_unchecked(index), p.x - grid::cell_centre(index.x, width),
                                     p.y - grid::cell_centre(index.y, width), p.z, weight, params_.weight_limit);
      } else {
        if constexpr (kHasFine) {
          if (!fine_.contains(index)) {
            continue;
          }
        }
        fine_point(index, p.z, front, weight);
      }
      ++frame.used;
      return;
    }
    ++frame.outside_map;
  }

  /// Measurement variance (m^2) of the piece-wise constant layer at squared range r^2 (m^2):
  /// sigma_m(r)^2, at least kalman_min_variance (which also catches NaN).
  [[nodiscard]] float fine_measurement_variance(float range_sq) const noexcept {
    // Stereo: sigma = k r^2 inline, the value sigma_at_range_sq returns for the finite
    // positive ranges that routing lets through; other models call it.
    const float sigma = stereo_k_ >= 0.0F ? stereo_k_ * range_sq : params_.noise.sigma_at_range_sq(range_sq);
    const float variance = sigma * sigma;
    return variance >= params_.kalman_min_variance ? variance : params_.kalman_min_variance;
  }

  /// One point for the piece-wise constant layer. Kalman: the frame's points of a cell are
  /// collected in integers (count, heights and squared ranges in FixedFront units: no float
  /// operation per point) and fused once per frame by finish_fine_frame: n measurements of the
  /// variance at the cell's mean squared range, i.e. one update with their mean and R / n
  /// (docs/design.md, "Frame batches"). OMG: one update per point.
  void fine_point(CellIndex index, float z, const detail::PointFront& front, float weight) noexcept {
    if constexpr (Config::kFineKind == FineKind::kKalman) {
      const std::size_t slot = grid::buffer_offset(index, Config::kFineSide);
      FineFrameSum& sum = fine_sums_[slot];
      if (sum.count == 0U) {
        sum.z_ref_units = front.z_units;
        sum.sum_dz_units = 0;
        sum.sum_range_units_sq = 0U;
        fine_touched_[fine_touched_count_++] = static_cast<std::uint32_t>(slot);
      }
      ++sum.count;
      sum.sum_dz_units += front.z_units - sum.z_ref_units;  // |each| <= 2^31: no overflow in 2^32 points
      const auto r = static_cast<std::uint64_t>(front.range_units_sq);
      sum.sum_range_units_sq = sum.sum_range_units_sq > UINT64_MAX - r ? UINT64_MAX : sum.sum_range_units_sq + r;
      (void)z;
      (void)weight;
    } else if constexpr (Config::kFineKind == FineKind::kOmg) {
      const float variance = fine_measurement_variance(detail::to_range_sq_m2(front.range_units_sq, front_));
      detail::omg_update_unchecked(fine_.cell_unchecked(index), z, variance, weight, params_.weight_limit);
    } else {
      (void)index;
      (void)z;
      (void)front;
      (void)weight;
    }
  }

  /// Fuses each touched Kalman cell's batch of this frame and clears the batches.
  void finish_fine_frame() noexcept {
    if constexpr (Config::kFineKind == FineKind::kKalman) {
      KalmanCell* cells = fine_.storage();
      for (std::uint32_t t = 0; t < fine_touched_count_; ++t) {
        const std::uint32_t slot = fine_touched_[t];
        FineFrameSum& sum = fine_sums_[slot];
        const float count = static_cast<float>(sum.count);
        // Heights were floored to the unit: + 0.5 unit removes that bias (the quantisation
        // error is uniform, sigma = unit / sqrt(12) = 0.045 mm for 4 cm cells). Exact while
        // |z| < 2^24 units (2.6 km above the stack origin for 4 cm cells).
        const float mean_z = (static_cast<float>(sum.z_ref_units) + static_cast<float>(sum.sum_dz_units) / count + 0.5F) *
                             front_.range_unit_m;
        const std::uint64_t mean_units = sum.sum_range_units_sq / sum.count;
        const float variance = fine_measurement_variance(
            detail::to_range_sq_m2(static_cast<std::int64_t>(mean_units > INT64_MAX ? INT64_MAX : mean_units), front_));
        detail::kalman_update_batch_unchecked(cells[slot], mean_z, variance, sum.count, params_.kalman_min_variance);
        sum.count = 0U;
      }
      fine_touched_count_ = 0U;
    }
  }

  /// Derived at init for both update paths: the fixed-point front (scale and routing bounds),
  /// constant weights, the stereo sigma factor.
  [[nodiscard]] Status init_update_path() noexcept {
    const Status status = detail::make_fixed_front(widths_[0], routing_.max_range_sq, kLayerCount, &front_);
    constant_weight_ = params_.noise.weight_mode() == sensor::WeightMode::kConstant;
    const bool stereo = params_.noise.kind() == sensor::SensorKind::kStereo && params_.noise.validate() == Status::kOk;
    stereo_k_ = stereo ? params_.noise.stereo_sigma_per_range_sq() : -1.0F;
    return status;
  }

  [[nodiscard]] Status move_fine(CellIndex centre) noexcept {
    if constexpr (kHasFine) {
      return fine_.move_to(centre);
    } else {
      (void)centre;
      return Status::kOk;
    }
  }

  // ---- lookup ----
  [[nodiscard]] bool locate(int layer, float x, float y, CellIndex* index) const noexcept {
    if (layer_is_ccm(layer)) {
      return ccm_[layer - kFineLayerCount].locate(x, y, index);
    }
    if constexpr (kHasFine) {
      return fine_.locate(x, y, index);
    } else {
      return false;
    }
  }

  // ---- pooling (Section IV-F) ----
  /// Own statistics of a CCM-layer cell merged with the pool of its four children when the
  /// children lie inside the next finer layer (windows are aligned, so either all four do or
  /// none does). Recursion depth <= kLayerCount.
  [[nodiscard]] CcmCell pooled(int layer, CellIndex index) const noexcept {
    const RingGrid<CcmCell>& grid = ccm_[layer - kFineLayerCount];
    const CcmCell* own = grid.cell(index);
    CcmCell result = own != nullptr ? *own : CcmCell{};
    if (layer == 0) {
      return result;
    }
    const int child_layer = layer - 1;
    const CellIndex first{index.x * 2, index.y * 2};
    CcmCell children[4] = {};
    bool any = false;
    if (layer_is_ccm(child_layer)) {
      if (!ccm_[child_layer - kFineLayerCount].contains(first)) {
        return result;
      }
      for (int i = 0; i < 4; ++i) {
        children[i] = pooled(child_layer, CellIndex{first.x + (i & 1), first.y + (i >> 1)});
        any = any || children[i].weight > 0.0F;
      }
    } else {
      if constexpr (kHasFine) {
        if (!fine_.contains(first)) {
          return result;
        }
        for (int i = 0; i < 4; ++i) {
          const FineCell& c = fine_.cell_unchecked(CellIndex{first.x + (i & 1), first.y + (i >> 1)});
          children[i] = ccm_from_constant(fine_height(c), fine_variance(c), c.weight, widths_[child_layer]);
          any = any || children[i].weight > 0.0F;
        }
      }
    }
    if (!any) {
      return result;
    }
    CcmCell merged = ccm_pool4(children, widths_[child_layer], params_.weight_limit);
    if (result.weight > 0.0F) {
      (void)ccm_merge(merged, result, params_.weight_limit);
    }
    return merged;
  }

  // ---- answers ----
  [[nodiscard]] static QueryResult empty_result(Status status, int layer) noexcept {
    return QueryResult{status, layer, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, CellClass::kUnknown};
  }

  [[nodiscard]] static float fine_height(const FineCell& cell) noexcept { return cell.height; }
  [[nodiscard]] static float fine_variance(const FineCell& cell) noexcept {
    if constexpr (std::is_same_v<FineCell, OmgCell>) {
      return omg_variance(cell);
    } else {
      return cell.variance;
    }
  }

  /// The answer of `layer` at `index` for the point (x, y) inside that cell. With
  /// require_known, a cell that is not known gives kUnknown.
  [[nodiscard]] QueryResult answer_at(int layer, CellIndex index, float x, float y,
                                      bool require_known = true) const noexcept {
    const float width = widths_[layer];
    QueryResult out = empty_result(Status::kOk, layer);
    out.cell_width_m = width;
    if (layer_is_ccm(layer)) {
      const CcmCell cell = pooled(layer, index);
      // Known: covered (eq. 12), or an obstacle already (classify_ccm: obstacle evidence wins).
      const CellClass cell_class = classify_ccm(cell, width, params_, thresholds_[layer]);
      const bool known = cell_class != CellClass::kUnknown;
      if (require_known && !known) {
        return empty_result(Status::kUnknown, layer);
      }
      const float qx = x - grid::cell_centre(index.x, width);
      const float qy = y - grid::cell_centre(index.y, width);
      const CcmSurface surface = ccm_surface(cell);
      out.weight = cell.weight;
      out.height_m = ccm_height_at(cell, surface, qx, qy);
      out.slope_x = surface.slope_x;
      out.slope_y = surface.slope_y;
      out.inclination = ccm_inclination(surface);
      out.normal_variance = surface.normal_variance;
      out.elevation_variance = ccm_elevation_variance(cell, surface, qx, qy);
      out.cell_class = cell_class;
      return out;
    }
    if constexpr (kHasFine) {
      const FineCell& cell = fine_.cell_unchecked(index);
      const bool known = cell.weight >= params_.min_weight && cell.weight > 0.0F;
      if (require_known && !known) {
        return empty_result(Status::kUnknown, layer);
      }
      out.weight = cell.weight;
      out.height_m = cell.height;
      out.normal_variance = fine_variance(cell);
      out.elevation_variance = out.normal_variance;
      out.cell_class = known ? roughness_class(index) : CellClass::kUnknown;
    }
    return out;
  }

  /// Roughness filter of the piece-wise constant layer (the baseline of Section V-B): the
  /// cell is an obstacle if any known neighbour differs in height by more than the maximum
  /// inclination times their distance. It cannot tell slopes from steps.
  [[nodiscard]] CellClass roughness_class(CellIndex index) const noexcept {
    if constexpr (kHasFine) {
      const FineCell& centre = fine_.cell_unchecked(index);
      const float step = params_.max_inclination * widths_[0];
      for (std::int32_t dy = -1; dy <= 1; ++dy) {
        for (std::int32_t dx = -1; dx <= 1; ++dx) {
          const FineCell* n = fine_.cell(CellIndex{index.x + dx, index.y + dy});
          if (n == nullptr || (dx == 0 && dy == 0) || !(n->weight >= params_.min_weight)) {
            continue;
          }
          const float limit = (dx != 0 && dy != 0) ? step * 1.41421356F : step;
          if (std::fabs(n->height - centre.height) > limit) {
            return CellClass::kObstacle;
          }
        }
      }
      return CellClass::kTraversable;
    } else {
      (void)index;
      return CellClass::kUnknown;
    }
  }

  /// Replaces slope, normal variance and class of a constant-layer answer with those of the
  /// first CCM layer's pooled cell at (x, y), when that cell is covered.
  void refine_with_ccm(float x, float y, QueryResult& answer) const noexcept {
    const int layer = kFineLayerCount;
    CellIndex index{};
    if (!locate(layer, x, y, &index)) {
      return;
    }
    const QueryResult ccm = answer_at(layer, index, x, y);
    if (ccm.status != Status::kOk) {
      return;
    }
    answer.slope_x = ccm.slope_x;
    answer.slope_y = ccm.slope_y;
    answer.inclination = ccm.inclination;
    answer.normal_variance = ccm.normal_variance;
    answer.cell_class = ccm.cell_class;
  }

  [[nodiscard]] static CellIndex snapped_centre(float x, float y, float width) noexcept {
    const float inv_double_width = 0.5F / width;
    return CellIndex{2 * static_cast<std::int32_t>(std::floor(x * inv_double_width + 0.5F)),
                     2 * static_cast<std::int32_t>(std::floor(y * inv_double_width + 0.5F))};
  }

  // ---- state ----
  FineCell fine_storage_[kFineCellCount]{};
  CcmCell ccm_storage_[kCcmCellCount]{};
  RingGrid<FineCell> fine_{};
  static constexpr std::size_t kLayerSlots = static_cast<std::size_t>(kLayerCount);
  static constexpr std::size_t kCcmSlots = kCcmLayerCount > 0 ? static_cast<std::size_t>(kCcmLayerCount) : 1U;
  RingGrid<CcmCell> ccm_[kCcmSlots]{};
  StackParams params_{};
  float widths_[kLayerSlots]{};
  sensor::RoutingTable<kLayerCount> routing_{};
  float thresholds_[kLayerSlots]{};
  FrameCounters totals_{};
  std::uint32_t rejected_moves_ = 0U;
  std::uint32_t rejected_frames_ = 0U;
  std::uint64_t last_update_ns_ = 0U;
  bool initialised_ = false;
  // ---- update-path scratch and derived constants (not map state: not in snapshots) ----
  detail::FrameChunk chunk_{};
  detail::FixedFront front_{};
  /// Per-frame batch of a Kalman cell (all zero between frames).
  struct FineFrameSum {
    std::uint32_t count;
    std::int64_t z_ref_units;          ///< first height of the frame in the cell (range units)
    std::int64_t sum_dz_units;         ///< sum of (z - z_ref) in range units
    std::uint64_t sum_range_units_sq;  ///< saturating sum of squared ranges (range units^2)
  };
  static constexpr std::size_t kFineBatchSlots = Config::kFineKind == FineKind::kKalman ? kFineCellCount : 1U;
  FineFrameSum fine_sums_[kFineBatchSlots]{};
  std::uint32_t fine_touched_[kFineBatchSlots]{};
  std::uint32_t fine_touched_count_ = 0U;
  // Zero until init_update_path() sets them, like every member: a static Stack is then all zero
  // bytes and lands in .bss (zero-filled at start-up, no flash) instead of .data.
  bool constant_weight_ = false;
  float stereo_k_ = 0.0F;  ///< stereo sigma per range^2 (1/m), -1 for other models (set by init)
};

}  // namespace ccmap
