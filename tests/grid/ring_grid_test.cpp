// RingGrid / RingLayer: random walks of moves against a brute-force model (every window cell
// compared bitwise after every move), exact clearing counts, window edges, for_each order,
// no drift over 10^5 moves, init arguments and use before init.
#include "ccmap/grid/ring_grid.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/grid/ring_index.hpp"
#include "support/reference.hpp"

namespace ccmap {

/// Defined in ring_grid_core_wall_test.cpp, which is compiled under the core warning wall.
std::uint32_t ring_grid_core_wall_check() noexcept;

namespace {

using test::Rng;

// ---------------------------------------------------------------------------------------------
// Cell types and stamps: Stamp<Cell>::make(v) is a cell unique to v (1 <= v < 2^24), never
// bitwise equal to Cell{}.
// ---------------------------------------------------------------------------------------------

struct PodCell {
  float height;
  float variance;
  float weight;
  float mean_x;
};
static_assert(sizeof(PodCell) == 4 * sizeof(float), "no padding: compared with memcmp");

struct ByteTriple {  // odd size, alignment 1
  std::uint8_t a;
  std::uint8_t b;
  std::uint8_t c;
};
static_assert(sizeof(ByteTriple) == 3, "no padding: compared with memcmp");

template <typename Cell>
struct Stamp;
template <>
struct Stamp<PodCell> {
  static PodCell make(std::uint32_t v) {
    const auto f = static_cast<float>(v);  // exact below 2^24
    return PodCell{f, -f, 0.5F * f, f + 0.25F};
  }
};
template <>
struct Stamp<std::uint32_t> {
  static std::uint32_t make(std::uint32_t v) { return v; }
};
template <>
struct Stamp<ByteTriple> {
  static ByteTriple make(std::uint32_t v) {
    return ByteTriple{static_cast<std::uint8_t>(v & 0xFFU),
                      static_cast<std::uint8_t>((v >> 8) & 0xFFU),
                      static_cast<std::uint8_t>((v >> 16) & 0xFFU)};
  }
};
template <>
struct Stamp<CcmCell> {
  static CcmCell make(std::uint32_t v) {
    CcmCell cell{};
    cell.weight = static_cast<float>(v);
    cell.mean_z = -static_cast<float>(v);
    cell.s_yz = 0.125F;
    return cell;
  }
};

template <typename Cell>
bool same_bits(const Cell& a, const Cell& b) {
  return std::memcmp(&a, &b, sizeof(Cell)) == 0;
}
template <typename Cell>
bool is_clear(const Cell& cell) {
  return same_bits(cell, Cell{});
}

std::string str(CellIndex i) {
  std::ostringstream s;
  s << "(" << i.x << ", " << i.y << ")";
  return s.str();
}

std::int64_t uniform_int(Rng& rng, std::int64_t lo, std::int64_t hi) {  // [lo, hi]
  return lo + static_cast<std::int64_t>(rng.next() % static_cast<std::uint64_t>(hi - lo + 1));
}

std::int32_t clamp_centre(std::int64_t v) {
  if (v > grid::kMaxCellIndex) return grid::kMaxCellIndex;
  if (v < -grid::kMaxCellIndex) return -grid::kMaxCellIndex;
  return static_cast<std::int32_t>(v);
}

// ---------------------------------------------------------------------------------------------
// The brute-force model: the window's cells in window order, moved "the slow obvious way"
// (every cell of the new window copied if it was in the old window, else Cell{}).
// ---------------------------------------------------------------------------------------------

template <typename Cell>
class Model {
 public:
  Model(std::int32_t side, CellIndex centre)
      : side_(side), min_(min_for(centre)), cells_(count(), Cell{}) {}

  /// Moves and returns how many cells left the window.
  std::size_t move_to(CellIndex centre) {
    const CellIndex new_min = min_for(centre);
    std::vector<Cell> moved(count(), Cell{});
    std::size_t kept = 0;
    for (std::int64_t y = new_min.y; y < std::int64_t{new_min.y} + side_; ++y) {
      for (std::int64_t x = new_min.x; x < std::int64_t{new_min.x} + side_; ++x) {
        const CellIndex index{static_cast<std::int32_t>(x), static_cast<std::int32_t>(y)};
        if (contains(index)) {
          moved[slot(index, new_min)] = at(index);
          ++kept;
        }
      }
    }
    cells_ = moved;
    min_ = new_min;
    return count() - kept;
  }
  bool contains(CellIndex i) const {
    const std::int64_t rx = std::int64_t{i.x} - min_.x;
    const std::int64_t ry = std::int64_t{i.y} - min_.y;
    return rx >= 0 && rx < side_ && ry >= 0 && ry < side_;
  }
  Cell& at(CellIndex i) { return cells_[slot(i, min_)]; }
  const Cell& at(CellIndex i) const { return cells_[slot(i, min_)]; }
  CellIndex min() const { return min_; }
  std::int32_t side() const { return side_; }

 private:
  std::size_t count() const {
    return static_cast<std::size_t>(side_) * static_cast<std::size_t>(side_);
  }
  CellIndex min_for(CellIndex centre) const {
    return CellIndex{static_cast<std::int32_t>(std::int64_t{centre.x} - side_ / 2),
                     static_cast<std::int32_t>(std::int64_t{centre.y} - side_ / 2)};
  }
  std::size_t slot(CellIndex i, CellIndex min) const {
    return static_cast<std::size_t>((std::int64_t{i.y} - min.y) * side_ +
                                    (std::int64_t{i.x} - min.x));
  }

  std::int32_t side_;
  CellIndex min_;
  std::vector<Cell> cells_;
};

/// Every window cell bitwise equal to the model; the ring just outside the window refused.
template <typename Cell>
testing::AssertionResult matches_model(const RingGrid<Cell>& grid, const Model<Cell>& model) {
  if (grid.window_min() != model.min()) {
    return testing::AssertionFailure()
           << "window min " << str(grid.window_min()) << ", model " << str(model.min());
  }
  const std::int32_t side = model.side();
  const CellIndex min = model.min();
  for (std::int32_t r = 0; r < side; ++r) {
    for (std::int32_t c = 0; c < side; ++c) {
      const CellIndex index{min.x + c, min.y + r};
      const Cell* cell = grid.cell(index);
      if (cell == nullptr) {
        return testing::AssertionFailure() << "window cell " << str(index) << " returned nullptr";
      }
      if (cell != &grid.cell_unchecked(index)) {
        return testing::AssertionFailure() << "cell and cell_unchecked disagree at " << str(index);
      }
      if (!same_bits(*cell, model.at(index))) {
        return testing::AssertionFailure()
               << "cell " << str(index) << " differs from the model ("
               << (is_clear(*cell) ? "cleared" : "stamped") << " in the grid, "
               << (is_clear(model.at(index)) ? "cleared" : "stamped") << " in the model)";
      }
    }
  }
  // Just outside each edge (int64: the window may touch +-(2^30 + side/2)).
  for (std::int32_t k = 0; k < side; ++k) {
    const CellIndex outside[] = {{min.x - 1, min.y + k},
                                 {min.x + side, min.y + k},
                                 {min.x + k, min.y - 1},
                                 {min.x + k, min.y + side}};
    for (const CellIndex index : outside) {
      if (grid.cell(index) != nullptr || grid.contains(index)) {
        return testing::AssertionFailure()
               << "cell " << str(index) << " outside the window is served";
      }
    }
  }
  return testing::AssertionSuccess();
}

// ---------------------------------------------------------------------------------------------
// Typed tests: the same behaviour for every cell type
// ---------------------------------------------------------------------------------------------

template <typename Cell>
class RingGridTyped : public testing::Test {};

using CellTypes = testing::Types<PodCell, std::uint32_t, ByteTriple, CcmCell>;
struct CellTypeNames {
  template <typename T>
  static std::string GetName(int) {
    if (std::is_same<T, PodCell>::value) return "PodCell";
    if (std::is_same<T, std::uint32_t>::value) return "Uint32";
    if (std::is_same<T, ByteTriple>::value) return "ByteTriple";
    return "CcmCell";
  }
};
TYPED_TEST_SUITE(RingGridTyped, CellTypes, CellTypeNames);

/// A random move: zero, small, medium (< side), about side, large, single axis, huge, extreme.
CellIndex random_centre(Rng& rng, CellIndex centre, std::int32_t side) {
  const std::int64_t kind = uniform_int(rng, 0, 11);
  std::int64_t x = centre.x;
  std::int64_t y = centre.y;
  switch (kind) {
    case 0:
      break;  // no move
    case 1:
    case 2:
    case 3:
      x += uniform_int(rng, -3, 3);
      y += uniform_int(rng, -3, 3);
      break;
    case 4:
    case 5:
      x += uniform_int(rng, -(side - 1), side - 1);
      y += uniform_int(rng, -(side - 1), side - 1);
      break;
    case 6: {
      const std::int64_t d =
          (uniform_int(rng, 0, 1) == 0 ? 1 : -1) * (side + uniform_int(rng, -1, 1));
      (uniform_int(rng, 0, 1) == 0 ? x : y) += d;
      break;
    }
    case 7:
      x += uniform_int(rng, -4 * side, 4 * side);
      y += uniform_int(rng, -4 * side, 4 * side);
      break;
    case 8:
      (uniform_int(rng, 0, 1) == 0 ? x : y) += uniform_int(rng, -(side - 1), side - 1);
      break;
    case 9:
      x = uniform_int(rng, -grid::kMaxCellIndex, grid::kMaxCellIndex);
      y = uniform_int(rng, -grid::kMaxCellIndex, grid::kMaxCellIndex);
      break;
    case 10:  // a corner of the index range: moves of up to 2^31 cells per axis
      x = uniform_int(rng, 0, 1) == 0 ? -grid::kMaxCellIndex : grid::kMaxCellIndex;
      y = uniform_int(rng, 0, 1) == 0 ? -grid::kMaxCellIndex : grid::kMaxCellIndex;
      break;
    default:  // near zero, where indices change sign
      x = uniform_int(rng, -side, side);
      y = uniform_int(rng, -side, side);
      break;
  }
  return CellIndex{clamp_centre(x), clamp_centre(y)};
}

template <typename Cell>
void random_walk_against_model(std::int32_t side, int moves, std::uint64_t seed) {
  SCOPED_TRACE("side " + std::to_string(side));
  Rng rng(seed);
  std::vector<Cell> storage(static_cast<std::size_t>(side) * static_cast<std::size_t>(side));
  std::memset(static_cast<void*>(storage.data()), 0xA5, storage.size() * sizeof(Cell));  // garbage
  RingGrid<Cell> grid;
  const CellIndex start{-3, 2};
  ASSERT_EQ(grid.init(storage.data(), side, 0.25F, start), Status::kOk);
  Model<Cell> model(side, start);
  ASSERT_TRUE(matches_model(grid, model)) << "after init (storage held garbage)";

  std::uint32_t next_stamp = 1;
  std::uint64_t stamps_surviving_moves = 0;
  for (int move = 0; move < moves; ++move) {
    // Stamp a few window cells with unique values, in the grid and in the model.
    const std::int64_t stamps = uniform_int(rng, 0, side);
    for (std::int64_t s = 0; s < stamps; ++s) {
      const CellIndex index{
          static_cast<std::int32_t>(model.min().x + uniform_int(rng, 0, side - 1)),
          static_cast<std::int32_t>(model.min().y + uniform_int(rng, 0, side - 1))};
      const Cell value = Stamp<Cell>::make(next_stamp++);
      Cell* cell = grid.cell(index);
      ASSERT_NE(cell, nullptr);
      *cell = value;
      model.at(index) = value;
    }
    const CellIndex before = grid.centre();
    const CellIndex target = random_centre(rng, before, side);
    const std::uint64_t cleared_before = grid.cells_cleared_by_moves();
    ASSERT_EQ(grid.move_to(target), Status::kOk) << "move " << move << " to " << str(target);
    const std::size_t left = model.move_to(target);
    ASSERT_EQ(grid.centre(), target);
    ASSERT_EQ(grid.cells_cleared_by_moves() - cleared_before, left)
        << "move " << move << " from " << str(before) << " to " << str(target)
        << " wrote a different number of cells than left the window";
    ASSERT_TRUE(matches_model(grid, model))
        << "after move " << move << " from " << str(before) << " to " << str(target);
    grid.for_each(
        [&](CellIndex, const Cell& cell) { stamps_surviving_moves += is_clear(cell) ? 0U : 1U; });

    // Now and then an out-of-range centre: refused, nothing changes.
    if (uniform_int(rng, 0, 15) == 0) {
      const CellIndex bad{grid::kMaxCellIndex + 1, 0};
      ASSERT_EQ(grid.move_to(bad), Status::kOutOfRange);
      ASSERT_EQ(grid.move_to(CellIndex{0, std::numeric_limits<std::int32_t>::min()}),
                Status::kOutOfRange);
      ASSERT_EQ(grid.centre(), target);
      ASSERT_TRUE(matches_model(grid, model)) << "a refused move changed the grid";
    }
  }
  EXPECT_GT(stamps_surviving_moves, static_cast<std::uint64_t>(moves / 4))
      << "the walk never kept stamped cells across moves: it tests nothing";
}

TYPED_TEST(RingGridTyped, RandomWalkMatchesBruteForceModel) {
  random_walk_against_model<TypeParam>(2, 3000, 11);
  random_walk_against_model<TypeParam>(8, 3000, 12);
  random_walk_against_model<TypeParam>(16, 1500, 13);
  random_walk_against_model<TypeParam>(64, 250, 14);
}

TYPED_TEST(RingGridTyped, OwningLayerMatchesModelAndHasItsCapacityInTheType) {
  using Layer = RingLayer<TypeParam, 32>;
  static_assert(Layer::kSideCells == 32, "capacity in the type");
  static_assert(Layer::kCellCount == 1024U, "capacity in the type");
  static_assert(sizeof(Layer) >= 1024U * sizeof(TypeParam), "storage in place");
  static_assert(
      !std::is_copy_constructible<Layer>::value && !std::is_move_constructible<Layer>::value,
      "a layer is not copied: its base points at its storage");
  static_assert(!std::is_copy_assignable<RingGrid<TypeParam>>::value, "non-copyable base");
  auto layer = std::make_unique<Layer>();
  ASSERT_EQ(layer->init(0.1F, CellIndex{100, -100}), Status::kOk);
  EXPECT_EQ(layer->side(), 32);
  EXPECT_EQ(layer->cell_count(), 1024U);
  EXPECT_EQ(layer->cell_width(), 0.1F);
  EXPECT_EQ(layer->inv_cell_width(), 1.0F / 0.1F);
  EXPECT_EQ(layer->window_min(), (CellIndex{84, -116}));
  EXPECT_EQ(layer->window_max(), (CellIndex{115, -85}));
  Model<TypeParam> model(32, CellIndex{100, -100});
  Rng rng(5);
  std::uint32_t stamp = 1;
  for (int move = 0; move < 300; ++move) {
    layer->for_each([&](CellIndex index, TypeParam& cell) {
      if (rng.next() % 4 == 0) {
        cell = Stamp<TypeParam>::make(stamp);
        model.at(index) = Stamp<TypeParam>::make(stamp);
        ++stamp;
      }
    });
    const CellIndex target = random_centre(rng, layer->centre(), 32);
    ASSERT_EQ(layer->move_to(target), Status::kOk);
    model.move_to(target);
    ASSERT_TRUE(matches_model<TypeParam>(*layer, model))
        << "after move " << move << " to " << str(target);
  }
}

// ---------------------------------------------------------------------------------------------
// Clearing: exactly the cells that leave
// ---------------------------------------------------------------------------------------------

/// A unique non-zero stamp per global index near the window (|x|, |y| < 2^11 around `base`).
std::uint32_t index_stamp(CellIndex i, CellIndex base) {
  const auto x = static_cast<std::uint32_t>(std::int64_t{i.x} - base.x + 2048);
  const auto y = static_cast<std::uint32_t>(std::int64_t{i.y} - base.y + 2048);
  return 1U + x + 4096U * y;
}

TEST(RingGrid, MoveClearsExactlyTheCellsThatLeave) {
  constexpr std::int32_t kSide = 16;
  auto layer = std::make_unique<RingLayer<std::uint32_t, kSide>>();
  const CellIndex centres[] = {
      {0, 0}, {-1, -1}, {7, -9}, {grid::kMaxCellIndex - 20, -grid::kMaxCellIndex + 20}};
  for (const CellIndex centre : centres) {
    for (std::int32_t dy = -(kSide - 1); dy <= kSide - 1; ++dy) {
      for (std::int32_t dx = -(kSide - 1); dx <= kSide - 1; ++dx) {
        ASSERT_EQ(layer->init(0.5F, centre), Status::kOk);
        layer->for_each([&](CellIndex i, std::uint32_t& cell) { cell = index_stamp(i, centre); });
        const CellIndex target{centre.x + dx, centre.y + dy};
        ASSERT_EQ(layer->move_to(target), Status::kOk);
        const std::int32_t adx = std::abs(dx);
        const std::int32_t ady = std::abs(dy);
        const auto expected = static_cast<std::uint64_t>(adx * kSide + ady * kSide - adx * ady);
        std::uint64_t cleared = 0;
        bool intact = true;
        const std::int64_t old_min_x = std::int64_t{centre.x} - kSide / 2;
        const std::int64_t old_min_y = std::int64_t{centre.y} - kSide / 2;
        layer->for_each([&](CellIndex i, const std::uint32_t& cell) {
          const bool was_in_window = i.x >= old_min_x && i.x < old_min_x + kSide &&
                                     i.y >= old_min_y && i.y < old_min_y + kSide;
          if (cell == 0U) {
            ++cleared;
            intact = intact && !was_in_window;
          } else {
            intact = intact && was_in_window && cell == index_stamp(i, centre);
          }
        });
        ASSERT_EQ(cleared, expected) << "move by (" << dx << ", " << dy << ") from " << str(centre);
        ASSERT_TRUE(intact) << "move by (" << dx << ", " << dy << ") from " << str(centre)
                            << " cleared a staying cell or kept a wrong value";
        ASSERT_EQ(layer->cells_cleared_by_moves(), expected)
            << "move by (" << dx << ", " << dy << ") did work beyond the leaving cells";
      }
    }
  }
}

TEST(RingGrid, MoveOfSideOrMoreOnAnAxisClearsEverything) {
  constexpr std::int32_t kSide = 8;
  auto layer = std::make_unique<RingLayer<std::uint32_t, kSide>>();
  const std::int64_t deltas[] = {kSide, kSide + 1, 2 * kSide, 1000, -kSide, -kSide - 1, -12345};
  for (const std::int64_t d : deltas) {
    for (int axes = 0; axes < 3; ++axes) {  // x only, y only, both
      ASSERT_EQ(layer->init(1.0F, CellIndex{3, -4}), Status::kOk);
      layer->for_each([](CellIndex, std::uint32_t& cell) { cell = 0xDEADBEEFU; });
      const CellIndex target{static_cast<std::int32_t>(3 + (axes != 1 ? d : 1)),
                             static_cast<std::int32_t>(-4 + (axes != 0 ? d : -1))};
      ASSERT_EQ(layer->move_to(target), Status::kOk);
      int stamped = 0;
      layer->for_each([&](CellIndex, const std::uint32_t& cell) { stamped += cell != 0U ? 1 : 0; });
      EXPECT_EQ(stamped, 0) << "move by " << d << " on axes " << axes << " kept cells";
      EXPECT_EQ(layer->cells_cleared_by_moves(), static_cast<std::uint64_t>(kSide * kSide));
    }
  }
}

TEST(RingGrid, MoveByZeroChangesNothing) {
  auto layer = std::make_unique<RingLayer<PodCell, 16>>();
  ASSERT_EQ(layer->init(0.2F, CellIndex{-5, 5}), Status::kOk);
  std::uint32_t v = 1;
  layer->for_each([&](CellIndex, PodCell& cell) { cell = Stamp<PodCell>::make(v++); });
  std::vector<unsigned char> before(layer->cell_count() * sizeof(PodCell));
  std::memcpy(before.data(), layer->storage(), before.size());
  for (int i = 0; i < 10; ++i) {
    ASSERT_EQ(layer->move_to(CellIndex{-5, 5}), Status::kOk);
  }
  EXPECT_EQ(std::memcmp(before.data(), layer->storage(), before.size()), 0)
      << "a null move changed bits";
  EXPECT_EQ(layer->cells_cleared_by_moves(), 0U);
  EXPECT_EQ(layer->centre(), (CellIndex{-5, 5}));
}

TEST(RingGrid, HugeMovesAcrossTheWholeIndexRangeDoNotOverflow) {
  constexpr std::int32_t kSide = 16;
  auto layer = std::make_unique<RingLayer<std::uint32_t, kSide>>();
  const std::int32_t m = grid::kMaxCellIndex;
  ASSERT_EQ(layer->init(0.1F, CellIndex{-m, -m}), Status::kOk);
  EXPECT_EQ(layer->window_min(), (CellIndex{-m - kSide / 2, -m - kSide / 2}));
  const CellIndex path[] = {{m, m}, {-m, m}, {m, -m}, {-m, -m}, {m, m}, {m - 1, m}, {m, m - 3}};
  for (const CellIndex target : path) {
    *layer->cell(layer->centre()) = 42U;
    ASSERT_EQ(layer->move_to(target), Status::kOk);
    EXPECT_EQ(layer->centre(), target);
    EXPECT_EQ(*layer->cell(target), 0U) << "the new centre " << str(target) << " was never stamped";
    EXPECT_EQ(layer->window_min(), (CellIndex{target.x - kSide / 2, target.y - kSide / 2}));
    EXPECT_EQ(layer->window_max(), (CellIndex{target.x + kSide / 2 - 1, target.y + kSide / 2 - 1}));
    EXPECT_TRUE(layer->contains(layer->window_min()));
    EXPECT_TRUE(layer->contains(layer->window_max()));
    ASSERT_NE(layer->cell(layer->window_max()), nullptr);
    EXPECT_EQ(layer->cell(CellIndex{std::numeric_limits<std::int32_t>::max(), target.y}), nullptr);
    EXPECT_EQ(layer->cell(CellIndex{std::numeric_limits<std::int32_t>::min(), target.y}), nullptr);
  }
  // The last two moves were by a few cells: the stamps at (m, m) and (m - 1, m) stayed inside.
  EXPECT_EQ(*layer->cell(CellIndex{m, m}), 42U) << "stamp at an earlier centre lost";
  EXPECT_EQ(*layer->cell(CellIndex{m - 1, m}), 42U) << "stamp at the previous centre lost";
}

// ---------------------------------------------------------------------------------------------
// Window edges, positions, iteration
// ---------------------------------------------------------------------------------------------

TEST(RingGrid, CellsOutsideTheWindowAreNullptr) {
  auto layer = std::make_unique<RingLayer<std::uint32_t, 8>>();
  ASSERT_EQ(layer->init(0.25F, CellIndex{-2, 3}), Status::kOk);  // window x [-6, 1], y [-1, 6]
  const RingGrid<std::uint32_t>& view = *layer;
  const std::int32_t lo = std::numeric_limits<std::int32_t>::min();
  const std::int32_t hi = std::numeric_limits<std::int32_t>::max();
  const CellIndex outside[] = {{-7, 0},  {2, 0},   {0, -2},     {0, 7},     {-7, -2},
                               {2, 7},   {lo, 0},  {hi, 0},     {0, lo},    {0, hi},
                               {lo, lo}, {hi, hi}, {-6 + 8, 3}, {-6 - 8, 3}};
  for (const CellIndex index : outside) {
    EXPECT_FALSE(layer->contains(index)) << str(index);
    EXPECT_EQ(layer->cell(index), nullptr) << str(index);
    EXPECT_EQ(view.cell(index), nullptr) << str(index);
  }
  EXPECT_NE(layer->cell(CellIndex{-6, -1}), nullptr);
  EXPECT_NE(layer->cell(CellIndex{1, 6}), nullptr);

  // Positions: the window covers [-6 * 0.25, 2 * 0.25) x [-1 * 0.25, 7 * 0.25) metres.
  CellIndex index{99, 99};
  EXPECT_TRUE(layer->locate(-1.5F, -0.25F, &index));
  EXPECT_EQ(index, (CellIndex{-6, -1}));
  EXPECT_EQ(layer->cell_at(-1.5F, -0.25F), layer->cell(CellIndex{-6, -1}));
  EXPECT_EQ(view.cell_at(0.49F, 1.74F), layer->cell(CellIndex{1, 6}));
  const CellIndex sentinel{99, 99};
  index = sentinel;
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float bad[][2] = {{0.5F, 0.0F},   {std::nextafter(-1.5F, -inf), 0.0F},
                          {0.0F, 1.75F},  {0.0F, std::nextafter(-0.25F, -inf)},
                          {nan, 0.0F},    {0.0F, inf},
                          {1.0e30F, 0.0F}};
  for (const auto& p : bad) {
    EXPECT_FALSE(layer->locate(p[0], p[1], &index)) << "(" << p[0] << ", " << p[1] << ") m";
    EXPECT_EQ(index, sentinel) << "locate wrote its output on refusal";
    EXPECT_EQ(layer->cell_at(p[0], p[1]), nullptr) << "(" << p[0] << ", " << p[1] << ") m";
    EXPECT_EQ(view.cell_at(p[0], p[1]), nullptr) << "(" << p[0] << ", " << p[1] << ") m";
  }
  EXPECT_FALSE(layer->locate(0.0F, 0.0F, nullptr));
}

TEST(RingGrid, CellAtAgreesWithIndexOfPositionForRandomPositions) {
  auto layer = std::make_unique<RingLayer<std::uint32_t, 64>>();
  ASSERT_EQ(layer->init(0.1F, CellIndex{-40, 25}), Status::kOk);
  Rng rng(21);
  for (int i = 0; i < 20000; ++i) {
    const auto x = static_cast<float>(rng.uniform(-8.0, 4.0));
    const auto y = static_cast<float>(rng.uniform(-2.0, 7.0));
    CellIndex expected{0, 0};
    ASSERT_TRUE(grid::index_of_position(x, y, layer->inv_cell_width(), &expected));
    const std::uint32_t* cell = layer->cell_at(x, y);
    ASSERT_EQ(cell, layer->cell(expected)) << "(" << x << ", " << y << ") m";
    ASSERT_EQ(cell != nullptr, layer->contains(expected));
  }
}

TEST(RingGrid, ForEachVisitsEveryWindowCellOnceInRowOrder) {
  auto layer = std::make_unique<RingLayer<std::uint32_t, 16>>();
  for (const CellIndex centre :
       {CellIndex{0, 0}, CellIndex{-3, 11}, CellIndex{-grid::kMaxCellIndex, grid::kMaxCellIndex}}) {
    ASSERT_EQ(layer->init(1.0F, centre), Status::kOk);
    ASSERT_EQ(layer->move_to(CellIndex{centre.x + 5, centre.y - 7}), Status::kOk);  // ring wrapped
    std::vector<CellIndex> order;
    std::set<const std::uint32_t*> slots;
    bool same_cell = true;
    layer->for_each([&](CellIndex i, std::uint32_t& cell) {
      order.push_back(i);
      slots.insert(&cell);
      same_cell = same_cell && &cell == layer->cell(i);
    });
    ASSERT_EQ(order.size(), 256U);
    EXPECT_EQ(slots.size(), 256U) << "a slot was visited twice";
    EXPECT_TRUE(same_cell) << "for_each passed a cell other than cell(index)";
    const CellIndex min = layer->window_min();
    for (std::size_t k = 0; k < order.size(); ++k) {
      const CellIndex expected{min.x + static_cast<std::int32_t>(k % 16),
                               min.y + static_cast<std::int32_t>(k / 16)};
      ASSERT_EQ(order[k], expected)
          << "visit " << k << ": rows of increasing y, x increasing in a row";
    }
    // The const overload: same order, same cells.
    const RingGrid<std::uint32_t>& view = *layer;
    std::size_t k = 0;
    bool const_ok = true;
    view.for_each([&](CellIndex i, const std::uint32_t& cell) {
      const_ok = const_ok && k < order.size() && i == order[k] && &cell == view.cell(i);
      ++k;
    });
    EXPECT_TRUE(const_ok);
    EXPECT_EQ(k, 256U);
  }
}

TEST(RingGrid, HundredThousandUnitMovesBackAndForthDoNotDrift) {
  constexpr std::int32_t kSide = 16;
  auto layer = std::make_unique<RingLayer<std::uint32_t, kSide>>();
  const CellIndex start{-1, 0};
  ASSERT_EQ(layer->init(0.32F, start), Status::kOk);
  const CellIndex min0 = layer->window_min();
  layer->for_each([&](CellIndex i, std::uint32_t& cell) { cell = index_stamp(i, start); });

  // 10^5 moves of +-1 cell, alternating axes, each axis a random back-and-forth walk
  // reflected at 3 cells from the start, then +-1 moves home. Track the centres visited.
  Rng rng(99);
  std::int64_t x = start.x, y = start.y;
  std::int64_t min_x = x, max_x = x, min_y = y, max_y = y;
  auto step_to = [&](std::int64_t nx, std::int64_t ny) {
    x = nx, y = ny;
    min_x = std::min(min_x, x), max_x = std::max(max_x, x);
    min_y = std::min(min_y, y), max_y = std::max(max_y, y);
    return layer->move_to(CellIndex{static_cast<std::int32_t>(x), static_cast<std::int32_t>(y)});
  };
  int moves = 0;
  for (; moves < 100000; ++moves) {
    const bool along_x = (moves % 2) == 0;
    const std::int64_t v = along_x ? x : y;
    const std::int64_t origin = along_x ? start.x : start.y;
    std::int64_t step = (rng.next() % 2 == 0) ? 1 : -1;
    if (v + step > origin + 3 || v + step < origin - 3) step = -step;
    ASSERT_EQ(along_x ? step_to(x + step, y) : step_to(x, y + step), Status::kOk);
  }
  while (x != start.x || y != start.y) {
    ASSERT_EQ(x != start.x ? step_to(x + (x < start.x ? 1 : -1), y)
                           : step_to(x, y + (y < start.y ? 1 : -1)),
              Status::kOk);
    ++moves;
  }
  ASSERT_GE(moves, 100000);
  EXPECT_EQ(layer->centre(), start);
  EXPECT_EQ(layer->window_min(), min0) << "the window drifted";
  ASSERT_EQ(max_x - min_x, 6) << "the walk should use its whole excursion";
  ASSERT_EQ(max_y - min_y, 6) << "the walk should use its whole excursion";
  // Cells inside every window visited kept their stamp; every other cell left at some time and
  // must read cleared.
  int kept = 0, cleared = 0;
  bool exact = true;
  layer->for_each([&](CellIndex i, const std::uint32_t& cell) {
    const bool always_inside = i.x >= max_x - kSide / 2 && i.x <= min_x + kSide / 2 - 1 &&
                               i.y >= max_y - kSide / 2 && i.y <= min_y + kSide / 2 - 1;
    if (always_inside) {
      exact = exact && cell == index_stamp(i, start);
      ++kept;
    } else {
      exact = exact && cell == 0U;
      ++cleared;
    }
  });
  EXPECT_TRUE(exact) << "content changed after 10^5 back-and-forth moves";
  EXPECT_EQ(kept, (kSide - 6) * (kSide - 6));
  EXPECT_EQ(cleared, kSide * kSide - (kSide - 6) * (kSide - 6));
}

// ---------------------------------------------------------------------------------------------
// Init and use before init
// ---------------------------------------------------------------------------------------------

TEST(RingGrid, BadInitArgumentsAreRefusedAndLeaveTheGridAsItWas) {
  std::vector<std::uint32_t> storage(64 * 64, 7U);
  RingGrid<std::uint32_t> grid;
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::int32_t lo = std::numeric_limits<std::int32_t>::min();
  const std::int32_t hi = std::numeric_limits<std::int32_t>::max();
  auto all_bad = [&]() {
    EXPECT_EQ(grid.init(nullptr, 8, 0.1F, CellIndex{0, 0}), Status::kInvalidArgument)
        << "null storage";
    for (const std::int32_t side : {0, 1, 3, 6, 12, -8, lo, hi, grid::kMaxSide * 2}) {
      EXPECT_EQ(grid.init(storage.data(), side, 0.1F, CellIndex{0, 0}), Status::kInvalidArgument)
          << "side " << side;
    }
    for (const float width :
         {0.0F, -0.0F, -0.1F, nan, inf, -inf, std::numeric_limits<float>::denorm_min()}) {
      EXPECT_EQ(grid.init(storage.data(), 8, width, CellIndex{0, 0}), Status::kInvalidArgument)
          << "cell width " << width << " m";
    }
    const std::int32_t over = grid::kMaxCellIndex + 1;
    for (const CellIndex centre :
         {CellIndex{over, 0}, CellIndex{0, -over}, CellIndex{lo, 0}, CellIndex{0, hi}}) {
      EXPECT_EQ(grid.init(storage.data(), 8, 0.1F, centre), Status::kInvalidArgument)
          << "centre " << str(centre);
    }
  };
  all_bad();
  EXPECT_FALSE(grid.initialised()) << "a refused init must not half-initialise";
  EXPECT_EQ(storage[0], 7U) << "a refused init must not touch the storage";

  ASSERT_EQ(grid.init(storage.data(), 4, 0.5F, CellIndex{1, 1}), Status::kOk);
  *grid.cell(CellIndex{1, 1}) = 5U;
  all_bad();
  EXPECT_TRUE(grid.initialised());
  EXPECT_EQ(grid.side(), 4);
  EXPECT_EQ(grid.cell_width(), 0.5F);
  EXPECT_EQ(grid.centre(), (CellIndex{1, 1}));
  EXPECT_EQ(*grid.cell(CellIndex{1, 1}), 5U) << "a refused re-init changed the content";

  // Accepted extremes: side 2 and kMaxSide-sized indices, centre at +-kMaxCellIndex.
  EXPECT_EQ(
      grid.init(storage.data(), 2, 1.0e-30F, CellIndex{-grid::kMaxCellIndex, grid::kMaxCellIndex}),
      Status::kOk);
  EXPECT_EQ(grid.window_min(), (CellIndex{-grid::kMaxCellIndex - 1, grid::kMaxCellIndex - 1}));
  EXPECT_EQ(grid.init(storage.data(), 64, 0.1F, CellIndex{0, 0}), Status::kOk);
  bool all_clear = true;
  for (const std::uint32_t v : storage) all_clear = all_clear && v == 0U;
  EXPECT_TRUE(all_clear) << "init must clear the storage";

  auto layer = std::make_unique<RingLayer<std::uint32_t, 4>>();
  EXPECT_EQ(layer->init(nan, CellIndex{0, 0}), Status::kInvalidArgument);
  EXPECT_EQ(layer->init(0.0F, CellIndex{0, 0}), Status::kInvalidArgument);
  EXPECT_EQ(layer->init(0.1F, CellIndex{lo, 0}), Status::kInvalidArgument);
  EXPECT_FALSE(layer->initialised());
}

TEST(RingGrid, UseBeforeInitIsSafe) {
  RingGrid<PodCell> grid;
  const RingGrid<PodCell>& view = grid;
  EXPECT_FALSE(grid.initialised());
  EXPECT_EQ(grid.side(), 0);
  EXPECT_EQ(grid.cell_count(), 0U);
  EXPECT_EQ(grid.cell_width(), 0.0F);
  EXPECT_EQ(grid.inv_cell_width(), 0.0F);
  EXPECT_EQ(grid.storage(), nullptr);
  EXPECT_EQ(view.storage(), nullptr);
  for (const CellIndex index : {CellIndex{0, 0}, CellIndex{-1, -1}, CellIndex{1, 0}}) {
    EXPECT_FALSE(grid.contains(index));
    EXPECT_EQ(grid.cell(index), nullptr);
    EXPECT_EQ(view.cell(index), nullptr);
  }
  CellIndex index{3, 3};
  EXPECT_FALSE(grid.locate(0.0F, 0.0F, &index));
  EXPECT_EQ(index, (CellIndex{3, 3}));
  EXPECT_EQ(grid.cell_at(0.0F, 0.0F), nullptr);
  EXPECT_EQ(view.cell_at(0.0F, 0.0F), nullptr);
  EXPECT_EQ(grid.move_to(CellIndex{1, 1}), Status::kNotInitialised);
  grid.clear();
  int visits = 0;
  grid.for_each([&](CellIndex, PodCell&) { ++visits; });
  view.for_each([&](CellIndex, const PodCell&) { ++visits; });
  EXPECT_EQ(visits, 0);

  auto layer = std::make_unique<RingLayer<PodCell, 8>>();
  EXPECT_FALSE(layer->initialised());
  EXPECT_EQ(layer->cell(CellIndex{0, 0}), nullptr);
  EXPECT_EQ(layer->move_to(CellIndex{0, 0}), Status::kNotInitialised);
}

TEST(RingGrid, HeadersCompileAndRunUnderTheCoreWarningWall) {
  // ring_grid_core_wall_test.cpp exercises every member (for_each included) with the core
  // flags; here we only check that it computed what it should.
  EXPECT_EQ(ring_grid_core_wall_check(), 0U) << "the core-wall translation unit found a mismatch";
}

}  // namespace
}  // namespace ccmap
