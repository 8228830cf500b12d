// The grid layer is header-only (templates and inline index math). This translation unit
// compiles the headers under the core warning wall (-Wconversion, -Wsign-conversion,
// -Wdouble-promotion, -Wold-style-cast, ... -Werror, no exceptions, no RTTI) and instantiates
// every non-template member for representative cell types, so a warning in any of them fails
// the library build, not only a user's build. (The member templates for_each are checked the
// same way by tests/grid/ring_grid_core_wall_test.cpp.)
#include "ccmap/grid/ring_grid.hpp"

#include <cstdint>

#include "ccmap/grid/ring_index.hpp"

namespace ccmap {

namespace {
/// A padding-free POD of mixed members, like a map cell.
struct WallCheckCell {
  float height;
  float variance;
  std::uint32_t count;
};
}  // namespace

template class RingGrid<std::uint32_t>;
template class RingGrid<float>;
template class RingGrid<WallCheckCell>;
template class RingLayer<std::uint8_t, 2>;

static_assert(grid::wrap(-1, 8) == 7, "wrap must give the mathematical remainder");
static_assert(grid::buffer_offset(CellIndex{-1, -1}, 4) == 15U, "last slot of a 4x4 buffer");

}  // namespace ccmap
