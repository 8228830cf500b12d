// Statically sized ring-buffer 2-D grid layer.
//
// RingGrid<Cell> holds the logic once over caller-owned storage (ETL style: ivector<T>);
// RingLayer<Cell, kSide> owns its storage, so the capacity is in the type (vector<T, N>).
//
// The window
//  - holds the global indices [min, min + side) on each axis, min = centre - side/2: side/2
//    cells below the centre and side/2 - 1 above it;
//  - a cell's buffer slot is a pure function of its global index (grid::buffer_offset), so a
//    global index never "changes" when the window moves, and a move only changes the window and
//    clears exactly the cells that leave it (set to Cell{}), in time proportional to the cells
//    that leave: |dx|*side + |dy|*side - |dx*dy| cell writes for |dx|, |dy| < side. Every other
//    cell stays bitwise unchanged. A move of >= side on an axis clears all side*side cells.
//
// Life: two phases. init() binds storage and may fail; after it nothing allocates, throws or
// blocks. Before a successful init every accessor is safe: nullptr / false / 0 /
// Status::kNotInitialised (cell_unchecked excepted: precondition).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "ccmap/core/assert.hpp"
#include "ccmap/core/status.hpp"
#include "ccmap/grid/ring_index.hpp"

namespace ccmap {

/// Size-erased ring-buffer layer over caller-owned storage of side*side cells.
/// Cell must be trivially copyable (cells are cleared by assigning Cell{}, compared and
/// serialised bitwise) and default constructible; Cell{} is the "never observed" cell.
template <typename Cell>
class RingGrid {
  static_assert(std::is_trivially_copyable<Cell>::value,
                "RingGrid cells are cleared, copied and serialised bitwise");
  static_assert(std::is_default_constructible<Cell>::value, "Cell{} is the cleared cell");

 public:
  RingGrid() = default;
  ~RingGrid() = default;
  RingGrid(const RingGrid&) = delete;  // it points at storage
  RingGrid& operator=(const RingGrid&) = delete;
  RingGrid(RingGrid&&) = delete;
  RingGrid& operator=(RingGrid&&) = delete;

  /// Binds `storage` (side*side cells, owned by the caller, must outlive the grid), sets every
  /// cell to Cell{}, the cell width (metres) and the window centre (global index). May be
  /// called again to rebind.
  /// kInvalidArgument, grid left as it was: null storage; side not a power of two in
  /// [2, grid::kMaxSide]; cell width NaN, infinite, <= 0 or so small that 1/width is infinite;
  /// centre beyond +-grid::kMaxCellIndex on an axis.
  [[nodiscard]] Status init(Cell* storage, std::int32_t side, float cell_width_m,
                            CellIndex centre) noexcept {
    if (storage == nullptr || side < 2 || side > grid::kMaxSide || !grid::is_power_of_two(side)) {
      return Status::kInvalidArgument;
    }
    if (!std::isfinite(cell_width_m) || !(cell_width_m > 0.0F)) {
      return Status::kInvalidArgument;
    }
    const float inv_cell_width = 1.0F / cell_width_m;
    if (!std::isfinite(inv_cell_width)) {
      return Status::kInvalidArgument;
    }
    if (!centre_in_range(centre)) {
      return Status::kInvalidArgument;
    }
    storage_ = storage;
    side_ = side;
    cell_width_m_ = cell_width_m;
    inv_cell_width_ = inv_cell_width;
    set_window(centre);
    cleared_by_moves_ = 0U;
    clear();
    return Status::kOk;
  }

  [[nodiscard]] bool initialised() const noexcept { return storage_ != nullptr; }
  /// Cells per axis; 0 before init.
  [[nodiscard]] std::int32_t side() const noexcept { return side_; }
  /// side * side; 0 before init.
  [[nodiscard]] std::size_t cell_count() const noexcept {
    return static_cast<std::size_t>(side_) * static_cast<std::size_t>(side_);
  }
  /// Cell width w (metres); 0 before init.
  [[nodiscard]] float cell_width() const noexcept { return cell_width_m_; }
  /// 1 / w (per metre, rounded to float); 0 before init.
  [[nodiscard]] float inv_cell_width() const noexcept { return inv_cell_width_; }
  /// Global index of the window centre; {0, 0} before init.
  [[nodiscard]] CellIndex centre() const noexcept { return centre_; }
  /// Lowest global index of the window on each axis: centre - side/2.
  [[nodiscard]] CellIndex window_min() const noexcept { return min_; }
  /// Highest global index of the window on each axis (inclusive): window_min + side - 1.
  [[nodiscard]] CellIndex window_max() const noexcept {
    return CellIndex{min_.x + (side_ - 1), min_.y + (side_ - 1)};
  }

  /// True if `index` (any int32 values) is inside the window. False before init.
  [[nodiscard]] bool contains(CellIndex index) const noexcept {
    // int64: index - min spans up to 2^31 + 2^30 for arbitrary int32 input.
    const std::int64_t rx = std::int64_t{index.x} - std::int64_t{min_.x};
    const std::int64_t ry = std::int64_t{index.y} - std::int64_t{min_.y};
    // Unsigned: a negative offset wraps above side, so one compare per axis.
    const auto side = static_cast<std::uint64_t>(side_);
    return static_cast<std::uint64_t>(rx) < side && static_cast<std::uint64_t>(ry) < side;
  }

  /// The cell at a global index; nullptr when outside the window (or not initialised).
  [[nodiscard]] Cell* cell(CellIndex index) noexcept {
    return contains(index) ? &storage_[grid::detail::buffer_offset_unchecked(index, side_)] : nullptr;
  }
  [[nodiscard]] const Cell* cell(CellIndex index) const noexcept {
    return contains(index) ? &storage_[grid::detail::buffer_offset_unchecked(index, side_)] : nullptr;
  }

  /// No nullptr answer, for hot loops. Precondition: contains(index) (hence initialised). A
  /// violation is reported to the assert hook and answered with the window cell in the same slot
  /// (the slot is wrapped: never memory outside the storage), or before init with a scratch cell
  /// that is no part of any map.
  // Always inlined: the hot loops (the free-space ray walk, the planner's region walk, the update
  // path) call it per cell, and gcc left an out-of-line copy for some of them (the flight cycle
  // counted 0.48 M more aarch64 instructions; docs/performance.md section 1.1).
  [[nodiscard]] __attribute__((always_inline)) Cell& cell_unchecked(CellIndex index) noexcept {
    CCMAP_ASSERT_OR_RETURN(contains(index), slot_or_scratch(index));
    return storage_[grid::detail::buffer_offset_unchecked(index, side_)];
  }
  [[nodiscard]] __attribute__((always_inline)) const Cell& cell_unchecked(CellIndex index) const noexcept {
    CCMAP_ASSERT_OR_RETURN(contains(index), slot_or_scratch(index));
    return storage_[grid::detail::buffer_offset_unchecked(index, side_)];
  }

  /// Global index of the cell holding the map-frame position (x, y) metres, if it is inside
  /// the window. False (and *out untouched) outside the window, for non-finite or huge
  /// positions, for out == nullptr and before init. Near cell boundaries the index may be off by
  /// one because of float rounding: see grid::index_of_position.
  [[nodiscard]] bool locate(float x, float y, CellIndex* out) const noexcept {
    CellIndex index{0, 0};
    if (out == nullptr || !grid::index_of_position(x, y, inv_cell_width_, &index) ||
        !contains(index)) {
      return false;
    }
    *out = index;
    return true;
  }

  /// The cell holding the map-frame position (x, y) metres; nullptr outside the window, for
  /// non-finite or huge positions and before init. Same rounding limit as locate().
  [[nodiscard]] Cell* cell_at(float x, float y) noexcept {
    CellIndex index{0, 0};
    return locate(x, y, &index) ? &storage_[grid::detail::buffer_offset_unchecked(index, side_)] : nullptr;
  }
  [[nodiscard]] const Cell* cell_at(float x, float y) const noexcept {
    CellIndex index{0, 0};
    return locate(x, y, &index) ? &storage_[grid::detail::buffer_offset_unchecked(index, side_)] : nullptr;
  }

  /// Scrolls so that the window is centred on new_centre (global index). Cells that leave the
  /// window are set to Cell{}; cells that stay keep their global index and their bits; cells
  /// that enter read Cell{}. Work: one write per leaving cell (see cells_cleared_by_moves()).
  /// kNotInitialised before init; kOutOfRange (nothing changed) if new_centre is beyond
  /// +-grid::kMaxCellIndex on an axis. Any move between valid centres is safe (deltas are int64).
  [[nodiscard]] Status move_to(CellIndex new_centre) noexcept {
    if (!initialised()) {
      return Status::kNotInitialised;
    }
    if (!centre_in_range(new_centre)) {
      return Status::kOutOfRange;
    }
    const CellIndex old_min = min_;
    const CellIndex new_min = window_min_for(new_centre, side_);
    const std::int64_t dx = std::int64_t{new_min.x} - std::int64_t{old_min.x};
    const std::int64_t dy = std::int64_t{new_min.y} - std::int64_t{old_min.y};
    const std::int64_t side = side_;
    if (dx >= side || dx <= -side || dy >= side || dy <= -side) {
      clear();
      cleared_by_moves_ += cell_count();
      set_window(new_centre);
      return Status::kOk;
    }
    // |dx|, |dy| < side <= 2^15 from here: int32 is safe.
    const std::int32_t shift_x = static_cast<std::int32_t>(dx);
    const std::int32_t shift_y = static_cast<std::int32_t>(dy);
    const std::int32_t leaving_cols = shift_x >= 0 ? shift_x : -shift_x;
    const std::int32_t leaving_rows = shift_y >= 0 ? shift_y : -shift_y;
    // Leaving rows: global y in [old_min.y, old_min.y + dy) for dy > 0, in
    // [old_min.y + side + dy, old_min.y + side) for dy < 0. Each is one contiguous buffer row.
    const std::int32_t first_leaving_row = shift_y >= 0 ? old_min.y : old_min.y + side_ + shift_y;
    for (std::int32_t k = 0; k < leaving_rows; ++k) {
      clear_row(first_leaving_row + k);
    }
    // Leaving columns, only in the rows that stay (the corner went with the rows): one write
    // per leaving cell. Staying rows: global y in [old_min.y, old_min.y + side) minus the above.
    if (leaving_cols > 0) {
      const std::int32_t first_leaving_col = shift_x >= 0 ? old_min.x : old_min.x + side_ + shift_x;
      const std::int32_t first_staying_row = shift_y >= 0 ? old_min.y + shift_y : old_min.y;
      const std::int32_t staying_rows = side_ - leaving_rows;
      for (std::int32_t r = 0; r < staying_rows; ++r) {
        Cell* const row = row_begin(first_staying_row + r);
        for (std::int32_t c = 0; c < leaving_cols; ++c) {
          row[grid::detail::wrap_unchecked(first_leaving_col + c, side_)] = Cell{};
        }
      }
    }
    const auto cols = static_cast<std::uint64_t>(leaving_cols);
    const auto rows = static_cast<std::uint64_t>(leaving_rows);
    const auto side_u = static_cast<std::uint64_t>(side_);
    cleared_by_moves_ += cols * side_u + rows * side_u - cols * rows;
    set_window(new_centre);
    return Status::kOk;
  }

  /// Sets every cell to Cell{}; the window does not move. Nothing before init.
  void clear() noexcept {
    const std::size_t n = cell_count();
    for (std::size_t i = 0; i < n; ++i) {
      storage_[i] = Cell{};
    }
  }

  /// Calls fn(CellIndex, Cell&) (fn(CellIndex, const Cell&) on a const grid) once for every
  /// window cell: rows of increasing global y, x increasing inside a row. Nothing before init.
  /// fn must not move, clear or re-init the grid.
  template <typename Fn>
  void for_each(Fn&& fn) {
    for (std::int32_t r = 0; r < side_; ++r) {
      const std::int32_t y = min_.y + r;
      Cell* const row = row_begin(y);
      for (std::int32_t c = 0; c < side_; ++c) {
        const std::int32_t x = min_.x + c;
        fn(CellIndex{x, y}, row[grid::detail::wrap_unchecked(x, side_)]);
      }
    }
  }
  template <typename Fn>
  void for_each(Fn&& fn) const {
    for (std::int32_t r = 0; r < side_; ++r) {
      const std::int32_t y = min_.y + r;
      const Cell* const row = row_begin(y);
      for (std::int32_t c = 0; c < side_; ++c) {
        const std::int32_t x = min_.x + c;
        fn(CellIndex{x, y}, row[grid::detail::wrap_unchecked(x, side_)]);
      }
    }
  }

  /// Raw storage for serialisation: cell_count() cells in buffer order (the cell of global
  /// index i is at grid::detail::buffer_offset_unchecked(i, side())); to restore, also restore the window
  /// (move_to on an empty grid, then copy). nullptr before init.
  [[nodiscard]] const Cell* storage() const noexcept { return storage_; }
  [[nodiscard]] Cell* storage() noexcept { return storage_; }

  /// Number of cells cleared by move_to since init (telemetry; also lets tests prove that a
  /// move writes only the cells that leave).
  [[nodiscard]] std::uint64_t cells_cleared_by_moves() const noexcept { return cleared_by_moves_; }

 private:
  /// cell_unchecked's answer to an index outside the window: its wrapped slot, or before init
  /// (no storage) a zeroed scratch cell shared by the grids of this cell type, no part of a map.
  [[nodiscard]] Cell& slot_or_scratch(CellIndex index) noexcept {
    return storage_ != nullptr ? storage_[grid::detail::buffer_offset_unchecked(index, side_)] : scratch_cell();
  }
  [[nodiscard]] const Cell& slot_or_scratch(CellIndex index) const noexcept {
    return storage_ != nullptr ? storage_[grid::detail::buffer_offset_unchecked(index, side_)] : scratch_cell();
  }
  [[nodiscard]] static Cell& scratch_cell() noexcept {
    static Cell scratch{};  // constant-initialised (zeroed, .bss): no guard, no heap
    return scratch;
  }
  [[nodiscard]] static bool centre_in_range(CellIndex centre) noexcept {
    return centre.x >= -grid::kMaxCellIndex && centre.x <= grid::kMaxCellIndex &&
           centre.y >= -grid::kMaxCellIndex && centre.y <= grid::kMaxCellIndex;
  }
  /// centre - side/2; no overflow for |centre| <= kMaxCellIndex and side <= kMaxSide.
  [[nodiscard]] static CellIndex window_min_for(CellIndex centre, std::int32_t side) noexcept {
    return CellIndex{centre.x - side / 2, centre.y - side / 2};
  }
  void set_window(CellIndex centre) noexcept {
    centre_ = centre;
    min_ = window_min_for(centre, side_);
  }
  [[nodiscard]] Cell* row_begin(std::int32_t global_y) noexcept {
    return storage_ +
           static_cast<std::size_t>(grid::detail::wrap_unchecked(global_y, side_)) * static_cast<std::size_t>(side_);
  }
  [[nodiscard]] const Cell* row_begin(std::int32_t global_y) const noexcept {
    return storage_ +
           static_cast<std::size_t>(grid::detail::wrap_unchecked(global_y, side_)) * static_cast<std::size_t>(side_);
  }
  void clear_row(std::int32_t global_y) noexcept {
    Cell* const row = row_begin(global_y);
    for (std::int32_t c = 0; c < side_; ++c) {
      row[c] = Cell{};
    }
  }

  Cell* storage_ = nullptr;
  std::int32_t side_ = 0;
  float cell_width_m_ = 0.0F;
  float inv_cell_width_ = 0.0F;
  CellIndex centre_{0, 0};
  CellIndex min_{0, 0};
  std::uint64_t cleared_by_moves_ = 0U;
};

/// A layer that owns its storage: capacity in the type (kSide x kSide cells, in place, no heap).
/// Large layers belong in static storage or inside an owning object, not on a small stack.
template <typename Cell, std::int32_t kSide>
class RingLayer : public RingGrid<Cell> {
  static_assert(grid::is_power_of_two(kSide) && kSide >= 2,
                "RingLayer side must be a power of two >= 2");
  static_assert(kSide <= grid::kMaxSide, "RingLayer side must be <= grid::kMaxSide");

 public:
  static constexpr std::int32_t kSideCells = kSide;
  static constexpr std::size_t kCellCount =
      static_cast<std::size_t>(kSide) * static_cast<std::size_t>(kSide);

  /// Binds the layer's own storage (RingGrid::init with side kSide). kInvalidArgument for a
  /// NaN, infinite or <= 0 width or a centre beyond +-grid::kMaxCellIndex.
  [[nodiscard]] Status init(float cell_width_m, CellIndex centre) noexcept {
    return RingGrid<Cell>::init(storage_, kSide, cell_width_m, centre);
  }

 private:
  Cell storage_[kCellCount]{};
};

}  // namespace ccmap
