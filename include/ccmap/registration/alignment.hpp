// Team alignment: the offset between another rover's map (a loaded stack, a snapshot or an
// exchange delta) and ours, so that a team can align before it merges (docs/design.md,
// "Registration", "Team alignment"). Distribution to distribution: each of their cells (its 3-D
// mean, the spread of its points about their plane) is a sample of the ground, matched against
// our cells as a frame's points are (registration/detail/solver.hpp), with the variance of their
// cell's mean height (sigma_s^2 / W; a constant cell's own variance) in place of a sensor's.
//
//   const ccmap::AlignmentResult a = ccmap::align_snapshot(ours, bytes, size, {dx_m, dy_m, dz_m}, params);
//   // a.correction (registration/types.hpp) applies to their map's points after the nominal
//   // offset, rotating about (a.centre_x_m, a.centre_y_m), our map frame.
//
// What is claimed, and the statuses, are registration's (registration/registration.hpp), plus:
//   kMisaligned      their finest cell width is not ours (bitwise): cells of another size
//   kCorrupt, kVersionMismatch   the snapshot's or delta's own checks (load_snapshot,
//                    MapExchange::merge_delta), before anything is read; kCorrupt also when
//                    either stack's state failed its check (Stack::state_status: an upset)
//   kOutOfRange      a non-finite or absurd nominal offset (beyond kMaxAbsCoordinateM)
// Their cells are those with weight >= our min_weight (CCM cells also covered, eq. 12; a loaded
// stack's cell an upset changed is none: Stack::cell_intact); at most
// max_points of them are used, every k-th in their storage order. Their cells are read again on
// every pass (a delta or snapshot is parsed max_iterations + 1 times): no copy, no heap.
// Merging with an offset that is not whole cells: docs/design.md says what is exact and what is
// not (the host tool's `ccmap merge --align`).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/persistence/exchange.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/registration/detail/solver.hpp"
#include "ccmap/registration/detail/stack_surface.hpp"
#include "ccmap/registration/types.hpp"

namespace ccmap {

/// Where the other map's frame lies in ours before alignment: their map-frame point p is at
/// p + (x_m, y_m, z_m) in ours (m), e.g. the difference of the two origins in the team frame.
struct MapOffset {
  float x_m;
  float y_m;
  float z_m;
};

/// The correction of their map in ours, about the centre of their cells.
struct AlignmentResult {
  RegistrationResult correction;  ///< applies to their points after the offset (registration/types.hpp)
  float centre_x_m;               ///< rotation centre, our map frame (m): the mean of their cells' positions
  float centre_y_m;
  std::uint32_t cells;            ///< their usable cells (before the subsample)
};

namespace detail {

/// Their cells as registration samples: every k-th usable cell (k = ceil(cells / max_points)),
/// its mean moved by the offset. Source::for_each_cell(fn) calls fn(layer, global index, cell)
/// for every stored cell, CCM or constant (the cell types of Stack<Config>).
template <typename Config, typename Source>
class CellSamples {
 public:
  using StackType = Stack<Config>;
  using CcmCellType = typename StackType::CcmCellType;

  CellSamples(const StackType& ours, const Source& source, const MapOffset& offset, std::uint32_t max_points) noexcept
      : ours_(ours), source_(source), offset_(offset) {
    // Count the usable cells and find their centre.
    float sum_x = 0.0F;
    float sum_y = 0.0F;
    source_.for_each_cell([&](int layer, CellIndex index, const auto& cell) {
      float x = 0.0F;
      float y = 0.0F;
      float z = 0.0F;
      float variance = 0.0F;
      if (usable(layer, index, cell, &x, &y, &z, &variance)) {
        ++count_;
        sum_x += x;
        sum_y += y;
      }
    });
    if (count_ > 0U) {
      centre_x_ = sum_x / static_cast<float>(count_);
      centre_y_ = sum_y / static_cast<float>(count_);
    }
    const std::uint32_t cap = max_points > 0U ? max_points : 1U;
    stride_ = (count_ + cap - 1U) / cap;
    stride_ = stride_ > 0U ? stride_ : 1U;
  }

  [[nodiscard]] std::uint32_t count() const noexcept { return count_; }
  [[nodiscard]] float centre_x() const noexcept { return centre_x_; }
  [[nodiscard]] float centre_y() const noexcept { return centre_y_; }

  template <typename Fn>
  SampleRefusals for_each(Fn&& fn) const noexcept {
    SampleRefusals refused{};
    std::uint32_t k = 0U;
    source_.for_each_cell([&](int layer, CellIndex index, const auto& cell) {
      float x = 0.0F;
      float y = 0.0F;
      float z = 0.0F;
      float variance = 0.0F;
      if (!usable(layer, index, cell, &x, &y, &z, &variance)) {
        return;
      }
      if (k++ % stride_ != 0U) {
        return;
      }
      if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) || !std::isfinite(variance)) {
        ++refused.non_finite;
        return;
      }
      fn(RegistrationSample{x, y, z, 0.0F, variance, layer});
    });
    return refused;
  }

 private:
  /// A cell that says where the ground is: its mean (our frame) and that mean's height variance.
  template <typename Cell>
  bool usable(int layer, CellIndex index, const Cell& cell, float* x, float* y, float* z, float* variance) const noexcept {
    const StackParams& params = ours_.params();
    const float width = ours_.layer_cell_width(layer);
    if (!(cell.weight >= params.min_weight) || !(cell.weight > 0.0F)) {
      return false;
    }
    if constexpr (std::is_same_v<Cell, CcmCellType>) {
      if (!ccm_is_covered(cell, width, params.coverage_tau, params.min_weight)) {
        return false;
      }
      *x = grid::cell_centre(index.x, width) + cell.mean_x + offset_.x_m;
      *y = grid::cell_centre(index.y, width) + cell.mean_y + offset_.y_m;
      *z = cell.mean_z + offset_.z_m;
      *variance = ccm_surface(cell).normal_variance / cell.weight;
    } else {
      *x = grid::cell_centre(index.x, width) + offset_.x_m;
      *y = grid::cell_centre(index.y, width) + offset_.y_m;
      *z = cell.height + offset_.z_m;
      *variance = constant_height_variance(cell);
    }
    return true;
  }

  const StackType& ours_;
  const Source& source_;
  MapOffset offset_;
  std::uint32_t count_ = 0U;
  std::uint32_t stride_ = 1U;
  float centre_x_ = 0.0F;
  float centre_y_ = 0.0F;
};

/// Cells of a loaded stack.
template <typename Config>
struct StackCells {
  const Stack<Config>& stack;
  template <typename Fn>
  void for_each_cell(Fn&& fn) const noexcept {
    using S = Stack<Config>;
    if constexpr (S::kHasFine) {
      // Integrity: a cell an upset changed is read as never observed (Stack::cell_intact).
      stack.fine_layer().for_each([&](CellIndex index, const typename S::FineCell& cell) {
        fn(0, index, stack.cell_intact(cell) ? cell : typename S::FineCell{});
      });
    }
    for (int c = 0; c < S::kCcmLayerCount; ++c) {
      stack.ccm_layer(c).for_each([&](CellIndex index, const typename S::CcmCellType& cell) {
        fn(c + S::kFineLayerCount, index, stack.cell_intact(cell) ? cell : typename S::CcmCellType{});
      });
    }
  }
};

/// Cells of a snapshot that SnapshotAccess<Config>::validate accepted.
template <typename Config>
struct SnapshotCells {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t layers_begin;
  template <typename Fn>
  void for_each_cell(Fn&& fn) const noexcept {
    SnapshotAccess<Config>::for_each_stored_cell(data, size, layers_begin, fn);
  }
};

/// Cells of an exchange delta whose header and cells validated (DeltaCells::validate).
template <typename Config>
struct DeltaCells {
  using S = Stack<Config>;
  const std::uint8_t* data;
  std::size_t size;         ///< the core's size (DeltaSender::core_size), its CRC included
  std::size_t cells_begin;  ///< offset after the header
  float finest_width;

  /// Reads every layer (coarsest first, the delta's order) and calls fn(layer, index, cell) for
  /// every cell; false for anything an export does not write (the MapExchange::merge_delta checks).
  template <typename Fn>
  bool read(Fn&& fn) const noexcept {
    SnapshotReader r(data, size - kDeltaTrailerBytes);
    r.seek(cells_begin);
    for (int layer = S::kLayerCount - 1; layer >= 0; --layer) {
      const float width = finest_width * static_cast<float>(std::uint32_t{1} << static_cast<unsigned>(layer));
      CellIndex centre{};
      if (!snapshot_read_centre(r, &centre)) {
        return false;
      }
      const std::uint32_t count = r.u32();
      const auto side = static_cast<std::uint64_t>(S::layer_side(layer));
      if (!r.ok() || count > side * side) {
        return false;
      }
      const std::int64_t min_x = static_cast<std::int64_t>(centre.x) - static_cast<std::int64_t>(side / 2U);
      const std::int64_t min_y = static_cast<std::int64_t>(centre.y) - static_cast<std::int64_t>(side / 2U);
      std::uint64_t position = 0U;
      for (std::uint32_t i = 0; i < count; ++i) {
        std::uint32_t skip = 0U;
        if (!delta_read_varint(r, &skip)) {
          return false;
        }
        position += skip;
        if (position >= side * side) {
          return false;
        }
        const CellIndex index{static_cast<std::int32_t>(min_x + static_cast<std::int64_t>(position % side)),
                              static_cast<std::int32_t>(min_y + static_cast<std::int64_t>(position / side))};
        ++position;
        bool ok = false;
        if (S::layer_is_ccm(layer)) {
          typename S::CcmCellType cell{};
          ok = snapshot_read_cell(r, &cell) && exchange_cell_valid(cell, width);
          if (ok) {
            fn(layer, index, cell);
          }
        } else {
          if constexpr (S::kHasFine) {
            typename S::FineCell cell{};
            ok = snapshot_read_cell(r, &cell) && exchange_cell_valid(cell, width);
            if (ok) {
              fn(layer, index, cell);
            }
          }
        }
        if (!ok) {
          return false;
        }
      }
    }
    return r.ok() && r.position() == size - kDeltaTrailerBytes;
  }
  template <typename Fn>
  void for_each_cell(Fn&& fn) const noexcept {
    (void)read(fn);
  }
};

/// The alignment itself, once their cells are a source.
template <typename Config, typename Source>
[[nodiscard]] AlignmentResult align_cells(const Stack<Config>& ours, const Source& source, const MapOffset& offset,
                                          const RegistrationParams& params) noexcept {
  AlignmentResult out{};
  const CellSamples<Config, Source> samples(ours, source, offset, params.max_points);
  out.cells = samples.count();
  out.centre_x_m = samples.centre_x();
  out.centre_y_m = samples.centre_y();
  const StackSurface<Config> surface(ours);
  out.correction = solve_registration(samples, surface, samples.centre_x(), samples.centre_y(), 0.0F, params,
                                      ours.layer_cell_width(0), ours.layer_cell_width(Stack<Config>::kLayerCount - 1));
  return out;
}

/// The checks every alignment makes first.
template <typename Config>
[[nodiscard]] Status check_alignment(const Stack<Config>& ours, const MapOffset& offset,
                                     const RegistrationParams& params) noexcept {
  const Status state = ours.state_status();  // kNotInitialised, or kCorrupt after an upset
  if (state != Status::kOk) {
    return state;
  }
  if (validate_registration_params(params) != Status::kOk) {
    return Status::kInvalidArgument;
  }
  if (!std::isfinite(offset.x_m) || !std::isfinite(offset.y_m) || !std::isfinite(offset.z_m) ||
      !(std::fabs(offset.x_m) <= kMaxAbsCoordinateM && std::fabs(offset.y_m) <= kMaxAbsCoordinateM &&
        std::fabs(offset.z_m) <= kMaxAbsCoordinateM)) {
    return Status::kOutOfRange;
  }
  return Status::kOk;
}

[[nodiscard]] inline AlignmentResult refused_alignment(Status status) noexcept {
  AlignmentResult out{};
  out.correction = unclaimed_result(status);
  return out;
}

}  // namespace detail

/// Aligns a loaded stack of the same configuration (their map) with ours.
template <typename Config>
[[nodiscard]] AlignmentResult align_maps(const Stack<Config>& ours, const Stack<Config>& theirs, const MapOffset& offset,
                                         const RegistrationParams& params) noexcept {
  const Status status = detail::check_alignment(ours, offset, params);
  if (status != Status::kOk) {
    return detail::refused_alignment(status);
  }
  const Status their_state = theirs.state_status();  // kNotInitialised, or kCorrupt after an upset
  if (their_state != Status::kOk) {
    return detail::refused_alignment(their_state);
  }
  if (!detail::same_float_bits(theirs.layer_cell_width(0), ours.layer_cell_width(0))) {
    return detail::refused_alignment(Status::kMisaligned);
  }
  const detail::StackCells<Config> source{theirs};
  return detail::align_cells(ours, source, offset, params);
}

/// Aligns the map of a snapshot (persistence/snapshot.hpp, the same configuration) with ours.
template <typename Config>
[[nodiscard]] AlignmentResult align_snapshot(const Stack<Config>& ours, const std::uint8_t* data, std::size_t size,
                                             const MapOffset& offset, const RegistrationParams& params) noexcept {
  Status status = detail::check_alignment(ours, offset, params);
  if (status != Status::kOk) {
    return detail::refused_alignment(status);
  }
  StackParams stored{};
  std::size_t layers_begin = 0U;
  status = detail::SnapshotAccess<Config>::validate(data, size, &stored, &layers_begin);
  if (status != Status::kOk) {
    return detail::refused_alignment(status);
  }
  if (!detail::same_float_bits(stored.finest_cell_width_m, ours.layer_cell_width(0))) {
    return detail::refused_alignment(Status::kMisaligned);
  }
  const detail::SnapshotCells<Config> source{data, size, layers_begin};
  return detail::align_cells(ours, source, offset, params);
}

/// Aligns the cells of an exchange delta (persistence/exchange.hpp, the same configuration) with
/// ours. The nominal offset is that of the two origins in the team frame: the delta's
/// (origin_cells, origin_z_m) less ours, finest cells times our finest width. What a delta holds
/// is gains (what the sender's own points added since its last export): few cells, recent ground.
template <typename Config>
[[nodiscard]] AlignmentResult align_delta(const Stack<Config>& ours, const std::uint8_t* data, std::size_t size,
                                          CellIndex our_origin_cells, float our_origin_z_m,
                                          const RegistrationParams& params) noexcept {
  Status status = detail::check_alignment(ours, MapOffset{0.0F, 0.0F, our_origin_z_m}, params);
  if (status != Status::kOk) {
    return detail::refused_alignment(status);
  }
  if (data == nullptr) {
    return detail::refused_alignment(Status::kInvalidArgument);
  }
  detail::SnapshotReader r(data, 0U);
  detail::DeltaSender sender{};
  status = detail::delta_read_header(data, size, detail::SnapshotAccess<Config>::fingerprint(), r, &sender);
  if (status != Status::kOk) {
    return detail::refused_alignment(status);
  }
  if (!detail::same_float_bits(sender.finest_cell_width_m, ours.layer_cell_width(0))) {
    return detail::refused_alignment(Status::kMisaligned);
  }
  // The core only (the free-space section after it holds no cells).
  const detail::DeltaCells<Config> source{data, sender.core_size, r.position(), sender.finest_cell_width_m};
  if (!source.read([](int, CellIndex, const auto&) {})) {
    return detail::refused_alignment(Status::kCorrupt);
  }
  const float w = ours.layer_cell_width(0);
  const MapOffset offset{
      static_cast<float>(static_cast<std::int64_t>(sender.origin_cells.x) - our_origin_cells.x) * w,
      static_cast<float>(static_cast<std::int64_t>(sender.origin_cells.y) - our_origin_cells.y) * w,
      sender.origin_z_m - our_origin_z_m};
  status = detail::check_alignment(ours, offset, params);
  if (status != Status::kOk) {
    return detail::refused_alignment(status);
  }
  return detail::align_cells(ours, source, offset, params);
}

}  // namespace ccmap
