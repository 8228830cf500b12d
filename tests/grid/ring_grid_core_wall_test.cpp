// Compiled with the core warning wall (ccmap_core_flags: -Wconversion -Wsign-conversion
// -Wdouble-promotion -Wold-style-cast -Wfloat-equal ... -Werror, -fno-exceptions, -fno-rtti),
// not with the lighter test flags: it instantiates every member of RingGrid / RingLayer,
// for_each and the const overloads included, the way flight code would. No GoogleTest here;
// ring_grid_test.cpp calls ring_grid_core_wall_check() and expects 0 mismatches.
#include <cstdint>

#include "ccmap/grid/ring_grid.hpp"
#include "ccmap/grid/ring_index.hpp"

namespace ccmap {

namespace {

struct WallCell {
  float height;
  std::uint32_t count;
};

RingLayer<WallCell, 8> g_layer;  // static storage, as in flight code

std::uint32_t check(RingLayer<WallCell, 8>& layer) noexcept {
  std::uint32_t mismatches = 0U;
  if (layer.init(0.25F, CellIndex{-3, 4}) != Status::kOk) {
    return 1000U;
  }
  layer.for_each([](CellIndex index, WallCell& cell) {
    cell.height = static_cast<float>(index.x) * 0.5F;
    cell.count = static_cast<std::uint32_t>(index.y + 100);
  });
  const RingGrid<WallCell>& view = layer;
  std::uint32_t visited = 0U;
  view.for_each([&](CellIndex index, const WallCell& cell) {
    ++visited;
    if (cell.count != static_cast<std::uint32_t>(index.y + 100)) {
      ++mismatches;
    }
  });
  mismatches += visited == 64U ? 0U : 1U;
  if (layer.move_to(CellIndex{-1, 4}) != Status::kOk) {  // two columns leave
    ++mismatches;
  }
  mismatches += layer.cells_cleared_by_moves() == 16U ? 0U : 1U;
  CellIndex located{0, 0};
  if (!view.locate(-0.3F, 1.1F, &located) || located != CellIndex{-2, 4}) {
    ++mismatches;
  }
  const WallCell* by_position = view.cell_at(-0.3F, 1.1F);
  const WallCell* by_index = view.cell(located);
  if (by_position == nullptr || by_position != by_index ||
      by_position != &view.cell_unchecked(located)) {
    ++mismatches;
  }
  if (by_position != nullptr && !(by_position->height < -0.99F && by_position->height > -1.01F)) {
    ++mismatches;  // cell -2 kept its stamp -2 * 0.5
  }
  WallCell* mutable_cell = layer.cell_at(-0.3F, 1.1F);
  if (mutable_cell == nullptr || mutable_cell != &layer.cell_unchecked(located) ||
      mutable_cell != layer.cell(located)) {
    ++mismatches;
  }
  const WallCell* entered = view.cell(CellIndex{2, 4});  // entered with the move
  if (entered == nullptr || entered->count != 0U) {
    ++mismatches;
  }
  mismatches += view.contains(CellIndex{-6, 4}) ? 1U : 0U;
  mismatches += view.window_max() == CellIndex{2, 7} ? 0U : 1U;
  mismatches += view.storage() == layer.storage() && view.cell_count() == 64U ? 0U : 1U;
  mismatches += view.side() == 8 && view.centre() == CellIndex{-1, 4} ? 0U : 1U;
  mismatches += view.cell_width() > 0.24F && view.inv_cell_width() > 3.99F ? 0U : 1U;
  layer.clear();
  const WallCell* cleared = layer.cell(CellIndex{0, 4});
  mismatches += cleared != nullptr && cleared->count == 0U ? 0U : 1U;
  mismatches += layer.initialised() ? 0U : 1U;
  CellIndex index{0, 0};
  mismatches +=
      grid::index_of_position(-0.3F, 1.1F, 4.0F, &index) && index == CellIndex{-2, 4} ? 0U : 1U;
  mismatches +=
      grid::cell_centre(-2, 0.25F) < -0.374F && grid::cell_centre(-2, 0.25F) > -0.376F ? 0U : 1U;
  return mismatches;
}

}  // namespace

std::uint32_t ring_grid_core_wall_check() noexcept { return check(g_layer); }

}  // namespace ccmap
