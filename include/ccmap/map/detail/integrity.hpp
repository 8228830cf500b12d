// Single-event upsets: what a flipped bit in RAM can do to a stack, and what stops it
// (docs/integration.md, "Radiation: single-event upsets", states the model and the figures).
// Integrators need not read it.
//
// Cells. Every cell of every layer has a 16-bit check in parallel arrays beside the layers'
// storage (CellChecks, a member of LayerSet): the cell types, snapshots' cell records and the C
// API's records are unchanged. The check is a linear function of the cell's bits (XOR, no carry),
// in one of two forms, chosen by the target's register width (kCheckLaneBits):
//
//   64-bit cores (x86-64, aarch64):
//   wide(cell)  = XOR over the cell's 64-bit lanes L_j (bytes 8j .. 8j+7; an odd last 32-bit word
//                 is a lane of its own, zero-extended) of ror64(L_j, 3j)
//   check(cell) = fold(wide(cell)): f = lo32 ^ ror32(hi32, 2), then lo16(f) ^ hi16(f)
//
//   32-bit cores (Cortex-M7, where a 64-bit rotation takes six instructions and a 32-bit one is
//   free in the XOR's operand):
//   wide(cell)  = XOR over the cell's 32-bit words w_k of ror32(w_k, 3k mod 32)
//   check(cell) = lo16(wide) ^ hi16(wide)
//
// Checks never leave the stack (snapshots, deltas and the C API's records hold none; a load
// recomputes them), so the two forms may differ between targets. In either form every bit of the
// cell lands on exactly one of the 16 check bits, and check(0) = 0: a static
// stack in .bss and every cleared cell are consistent with no work. Writers keep the check with
//   check ^= fold(wide(old) ^ wide(new))
// (no compare on the update path), which keeps D = check ^ check(cell) constant over writes: an
// upset between two writes (D != 0) stays visible after the cell is written again. Readers (the
// queries, pooling, planner queries, snapshots) use a cell only when D = 0; a cell with D != 0
// is distrusted (below: the place answers unknown, reason upset); the scrub (scrub_slice) checks
// a slice of the cells each frame and resets a cell with D != 0 to the distrusted cell, its
// check consistent, counting it (FrameCounters::corrupted_cells); the next point clears it.
//
// What the check sees (tests/map/integrity_test.cpp proves each against a brute-force
// recomputation): every single-bit upset of a cell or of its check; every odd number of upsets in
// one cell; every two upsets in adjacent bits of a cell (within a 32-bit word and across word
// boundaries) and in the same bit of two words up to three words apart (the rotations were
// chosen for that: SRAM interleaves the same bit of neighbouring words side by side). Two upsets
// that land on the same check bit cancel: of all pairs of bits of a 10-float CCM cell, 94 % are
// detected (both forms spread a cell's bits evenly over the 16 check bits).
//
// Free-space records (map/visibility/free_space.hpp, 4 B per cell of every layer) carry the same
// 16-bit check, one per record in an array beside them, kept by their one write
// (FreeSpace::write_record), verified before a record's evidence decides a clearing and before a
// query answers a drop-off, and scrubbed with the cells (scrub_record_slice); a failed record is
// reset to no evidence (all zero: no bound, no clearing, no drop-off) and counted in
// corrupted_cells (tests/map/free_space_upset_test.cpp).
//
// Bookkeeping (state_seal): the values that index memory or give the cells their meaning (the
// parameters, every derived constant, each grid's storage pointer, side, widths and window, the
// kept windows, the initialised word) are sealed by a 128-bit check word (StateHasher) computed
// whenever they change (init, load, move, exchange binding) and verified at the start of every
// call that reads or writes the map: a mismatch is refused with Status::kCorrupt, until init()
// or load_snapshot(). The update path's state that lives from frame to frame is restored or
// verified at each frame's start (UpdatePath::begin_frame: the Kalman frame records rewritten,
// the held-point slots verified against their seals, the walk's windows copied from the sealed
// grids), and every index that per-frame scratch holds is masked or bounded where it is used, so
// that an upset during a frame changes at most that frame's points, inside the storage.
// No heap, no exceptions.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "ccmap/grid/ring_index.hpp"
#include "ccmap/map/types.hpp"

namespace ccmap::detail {

/// Check of one cell (16 bits), kept in CellChecks beside the cells.
using CellCheck = std::uint16_t;

/// Lane width of the signatures on this target: 64 where pointers are 64-bit (the core has
/// 64-bit registers), else 32 (the file comment gives both forms).
inline constexpr unsigned kCheckLaneBits = UINTPTR_MAX > 0xFFFFFFFFU ? 64U : 32U;
/// The wide signature of one form (64 or 32 bits), and this target's.
template <unsigned kLaneBits>
using SignatureOf = std::conditional_t<kLaneBits == 64U, std::uint64_t, std::uint32_t>;
using WideSignature = SignatureOf<kCheckLaneBits>;

[[nodiscard]] constexpr std::uint64_t rotr64(std::uint64_t v, unsigned r) noexcept {
  return (v >> (r & 63U)) | (v << ((64U - r) & 63U));
}
[[nodiscard]] constexpr std::uint32_t rotr32(std::uint32_t v, unsigned r) noexcept {
  return (v >> (r & 31U)) | (v << ((32U - r) & 31U));
}

/// The wide signature of `kBytes` bytes (a multiple of 4), form kLaneBits. 64: lane j (bytes
/// 8j .. 8j+7, or a last lone 32-bit word, zero-extended) rotated right by 3j bits, XORed; 32:
/// word k rotated right by 3k mod 32 bits, XORed. Linear over XOR: wide(a ^ b) = wide(a) ^
/// wide(b), and wide(0) = 0. Every bit maps to one bit.
template <std::size_t kBytes, unsigned kLaneBits = kCheckLaneBits>
[[nodiscard]] inline SignatureOf<kLaneBits> bytes_signature_wide(const unsigned char* bytes) noexcept {
  static_assert(kBytes % 4U == 0U, "signatures run over whole 32-bit words");
  static_assert(kLaneBits == 64U || kLaneBits == 32U, "a signature runs over 64- or 32-bit lanes");
  if constexpr (kLaneBits == 64U) {
    constexpr std::size_t kLanes = kBytes / 8U;
    std::uint64_t s = 0U;
    for (std::size_t lane = 0; lane < kLanes; ++lane) {
      std::uint64_t u = 0U;
      std::memcpy(&u, bytes + 8U * lane, sizeof u);
      s ^= rotr64(u, static_cast<unsigned>(3U * lane));
    }
    if constexpr (kBytes % 8U != 0U) {
      std::uint32_t w = 0U;
      std::memcpy(&w, bytes + 8U * kLanes, sizeof w);
      s ^= rotr64(std::uint64_t{w}, static_cast<unsigned>(3U * kLanes));
    }
    return s;
  } else {
    std::uint32_t s = 0U;
    for (std::size_t word = 0; word < kBytes / 4U; ++word) {
      std::uint32_t w = 0U;
      std::memcpy(&w, bytes + 4U * word, sizeof w);
      s ^= rotr32(w, static_cast<unsigned>((3U * word) % 32U));
    }
    return s;
  }
}

/// The wide signature of a cell (any trivially copyable type of whole 32-bit words), form
/// kLaneBits (this target's unless named).
template <unsigned kLaneBits = kCheckLaneBits, typename T>
[[nodiscard]] inline SignatureOf<kLaneBits> cell_signature_wide(const T& value) noexcept {
  static_assert(std::is_trivially_copyable<T>::value, "signatures read the bytes of a value");
  return bytes_signature_wide<sizeof(T), kLaneBits>(reinterpret_cast<const unsigned char*>(&value));
}

/// The 16-bit check of a wide signature. 64-bit form: lo32 ^ ror32(hi32, 2), then lo16 ^ hi16;
/// 32-bit form: lo16 ^ hi16 (linear, and a single changed bit of the wide signature changes
/// exactly one bit of the check).
[[nodiscard]] constexpr CellCheck fold_signature(std::uint64_t wide) noexcept {
  const std::uint32_t f = static_cast<std::uint32_t>(wide) ^ rotr32(static_cast<std::uint32_t>(wide >> 32U), 2U);
  return static_cast<CellCheck>((f ^ (f >> 16U)) & 0xFFFFU);
}
[[nodiscard]] constexpr CellCheck fold_signature(std::uint32_t wide) noexcept {
  return static_cast<CellCheck>((wide ^ (wide >> 16U)) & 0xFFFFU);
}

/// The check a consistent cell has (form kLaneBits: this target's unless named).
template <unsigned kLaneBits = kCheckLaneBits, typename T>
[[nodiscard]] inline CellCheck cell_signature(const T& value) noexcept {
  return fold_signature(cell_signature_wide<kLaneBits>(value));
}

/// The per-cell checks of a LayerSet: fine[i] belongs to fine_storage[i], ccm[i] to
/// ccm_storage[i]. All zero: every cell never observed (a static stack lives in .bss).
template <std::size_t kFineCells, std::size_t kCcmCells>
struct CellChecks {
  CellCheck fine[kFineCells]{};
  CellCheck ccm[kCcmCells]{};
};

// ---- cells of a LayerSet (Layers: detail::LayerSet<Config>, map/detail/layers.hpp) ----------
// Preconditions of every function below: `cell` is a cell of the layers' own storage (a
// reference from one of its grids), never a copy.

template <typename Layers>
[[nodiscard]] inline CellCheck& check_of(Layers& layers, const typename Layers::CcmCellType& cell) noexcept {
  return layers.checks.ccm[static_cast<std::size_t>(&cell - layers.ccm_storage)];
}
template <typename Layers>
[[nodiscard]] inline CellCheck& check_of(Layers& layers, const typename Layers::FineCell& cell) noexcept {
  return layers.checks.fine[static_cast<std::size_t>(&cell - layers.fine_storage)];
}
template <typename Layers>
[[nodiscard]] inline CellCheck check_of(const Layers& layers, const typename Layers::CcmCellType& cell) noexcept {
  return layers.checks.ccm[static_cast<std::size_t>(&cell - layers.ccm_storage)];
}
template <typename Layers>
[[nodiscard]] inline CellCheck check_of(const Layers& layers, const typename Layers::FineCell& cell) noexcept {
  return layers.checks.fine[static_cast<std::size_t>(&cell - layers.fine_storage)];
}

/// True if the cell's bits agree with its check (no upset seen).
template <typename Layers, typename Cell>
[[nodiscard]] inline bool cell_intact(const Layers& layers, const Cell& cell) noexcept {
  return cell_signature(cell) == check_of(layers, cell);
}

/// Carries a write into the cell's check: `before` was the cell's wide signature before the
/// write (check ^= fold(before ^ wide(now))). CheckRun pairs it with the signature it took when
/// it opened the run; nothing else calls it (the other writers use write_delta).
template <typename Layers, typename Cell>
inline void rewrite_check(Layers& layers, const Cell& cell, WideSignature before) noexcept {
  check_of(layers, cell) ^= fold_signature(before ^ cell_signature_wide(cell));
}

/// The one checked write of a value whose 16-bit check is kept apart from it (a cell of a
/// LayerSet through write_cell; a free-space record, free_space.hpp): takes the value's wide
/// signature, runs write(value), and returns what the value's check must be XORed with,
/// fold(wide(before) ^ wide(after)), so that an upset seen before the write stays seen after it.
/// Callers write `check ^= write_delta(value, fn)`: C++17 evaluates a compound assignment's right
/// operand first, so the check's address is taken after the write (taking it before costs the
/// flight cycle registers across the write).
template <typename T, typename Write>
[[nodiscard]] inline CellCheck write_delta(T& value, Write&& fn) noexcept {
  const WideSignature before = cell_signature_wide(value);
  fn(value);
  return fold_signature(before ^ cell_signature_wide(value));
}

/// The one write of a cell of a LayerSet (every writer but the update path's per-point runs,
/// CheckRun::write): write_delta into the cell's own check.
/// Precondition: `cell` is a cell of the layers' own storage.
template <typename Layers, typename Cell, typename Write>
inline void write_cell(Layers& layers, Cell& cell, Write&& fn) noexcept {
  check_of(layers, cell) ^= write_delta(cell, fn);
}

/// The cell write of the per-point updates (the update path's back half): a run of writes to
/// one cell pays for its check once. open(cell) closes the open run (its check takes the
/// change) and opens one on `cell` with its signature as it is now; write(fn) runs fn on the
/// open run's cell; write(cell, fn) opens a run when `cell` is not the open one, then writes;
/// close() after the last write of the chunk. Consecutive points of a frame mostly fall into
/// the same cell, so this costs a compare per point and two signatures per run. The run lives
/// in registers or on the call stack, never in the map's storage: a run is open for at most one
/// chunk of the update (kFrontChunkPoints points), and an upset in the open cell during that
/// time is taken into its check (docs/integration.md).
template <typename Cell>
class CheckRun {
 public:
  template <typename Layers>
  void open(Layers& layers, Cell& cell) noexcept {
    close(layers);
    cell_ = &cell;
    before_ = cell_signature_wide(cell);
  }
  /// fn(cell) on the open run's cell. Precondition: a run is open (open() since close()).
  template <typename Write>
  void write(Write&& fn) noexcept {
    fn(*cell_);
  }
  template <typename Layers, typename Write>
  void write(Layers& layers, Cell& cell, Write&& fn) noexcept {
    if (&cell != cell_) {
      open(layers, cell);
    }
    fn(cell);
  }
  template <typename Layers>
  void close(Layers& layers) noexcept {
    if (cell_ != nullptr) {
      rewrite_check(layers, *cell_, before_);
      cell_ = nullptr;
    }
  }

 private:
  Cell* cell_ = nullptr;
  WideSignature before_ = 0U;
};

/// The runs of one chunk: CCM cells and piece-wise constant (OMG) cells.
template <typename Layers>
struct CheckRuns {
  CheckRun<typename Layers::CcmCellType> ccm;
  CheckRun<typename Layers::FineCell> fine;
  void close(Layers& layers) noexcept {
    ccm.close(layers);
    fine.close(layers);
  }
};

// ---- distrust: what the scrub leaves in a cell it reset --------------------------------------
// A cell whose check failed lost what it knew: the place it covers may hold a hazard. The scrub
// (and the motion pass) therefore do not reset it to never observed but to the *distrusted* cell:
// every field 0 and the weight -0.0F (its sign bit: no extra memory, no heap; the mark lives in
// the cell's own bits and so in its check, which stays consistent). Readers treat a distrusted
// cell (cell_distrusted: a failed check, or the mark) as unknown and stop there: the place
// answers unknown with the reason "upset" (QueryResult::upset), never another layer's answer,
// and a pooled cell with a distrusted cell below it is distrusted too (map/query/pooling.hpp).
// The next point folded into the cell clears the mark with no extra work: every update adds to
// the weight (-0 + w = w > 0; Kalman: an empty cell takes the point's weight), and every test of
// "observed" on the update path reads weight > 0, false for -0 as for 0. No writer produces -0
// otherwise (weights only grow, or scale by a positive factor, from +0), so a map without upsets
// holds no mark and its answers and bits are those of a map without this rule.

/// True if `cell` (a value) is the distrusted cell's mark: its weight's sign bit.
template <typename Cell>
[[nodiscard]] inline bool distrust_mark(const Cell& cell) noexcept {
  return std::signbit(cell.weight);
}

/// The distrusted cell: all zero but the weight, -0.0F.
template <typename Cell>
[[nodiscard]] inline Cell distrusted_cell() noexcept {
  Cell cell{};
  cell.weight = -0.0F;
  return cell;
}

/// True if a cell of the layers' storage must not be used: its bits disagree with its check, or
/// the scrub left it distrusted.
template <typename Layers, typename Cell>
[[nodiscard]] inline bool cell_distrusted(const Layers& layers, const Cell& cell) noexcept {
  return distrust_mark(cell) || !cell_intact(layers, cell);
}

/// The cell as a reader that keeps the distrust may use it: itself if intact, else the
/// distrusted cell (a snapshot saves that, so the distrust survives save and load).
template <typename Layers, typename Cell>
[[nodiscard]] inline Cell intact_or_distrusted(const Layers& layers, const Cell& cell) noexcept {
  return cell_intact(layers, cell) ? cell : distrusted_cell<Cell>();
}

/// Sets a cell whose check failed to the distrusted cell, its check consistent with it.
template <typename Layers, typename Cell>
inline void reset_cell(Layers& layers, Cell& cell) noexcept {
  cell = distrusted_cell<Cell>();
  check_of(layers, cell) = cell_signature(cell);
}

/// Recomputes every check from its cell (after a snapshot load wrote the cells).
template <typename Layers>
inline void reseal_all_cells(Layers& layers) noexcept {
  if constexpr (Layers::kHasFine) {
    for (std::size_t i = 0; i < Layers::kFineCellCount; ++i) {
      layers.checks.fine[i] = cell_signature(layers.fine_storage[i]);
    }
  }
  if constexpr (Layers::kCcmLayerCount > 0) {
    for (std::size_t i = 0; i < Layers::kCcmCellCount; ++i) {
      layers.checks.ccm[i] = cell_signature(layers.ccm_storage[i]);
    }
  }
}

/// Every check 0 (the layers' cells were all cleared).
template <typename Layers>
inline void clear_all_checks(Layers& layers) noexcept {
  for (CellCheck& c : layers.checks.fine) {
    c = 0U;
  }
  for (CellCheck& c : layers.checks.ccm) {
    c = 0U;
  }
}

/// Cells the scrub walks: the finest layer's, then the CCM layers' (storage order).
template <typename Layers>
[[nodiscard]] constexpr std::uint32_t scrubbed_cells() noexcept {
  return static_cast<std::uint32_t>((Layers::kHasFine ? Layers::kFineCellCount : 0U) +
                                    (Layers::kCcmLayerCount > 0 ? Layers::kCcmCellCount : 0U));
}

/// Frames in which the scrub checks every cell of a stack (default; a Config may set its own
/// `static constexpr std::uint32_t kScrubFrames`, >= 1).
inline constexpr std::uint32_t kDefaultScrubFrames = 8U;

template <typename Config, typename = void>
struct ConfigScrubFrames {
  static constexpr std::uint32_t value = kDefaultScrubFrames;
};
template <typename Config>
struct ConfigScrubFrames<Config, std::void_t<decltype(Config::kScrubFrames)>> {
  static constexpr std::uint32_t value = Config::kScrubFrames;
};

/// Cells the scrub checks per frame: ceil(scrubbed cells / frames), so that every cell is
/// checked within kScrubFrames frames.
template <typename Config, typename Layers>
[[nodiscard]] constexpr std::uint32_t scrub_cells_per_frame() noexcept {
  constexpr std::uint32_t kFrames = ConfigScrubFrames<Config>::value;
  static_assert(kFrames >= 1U, "the scrub needs at least one frame per pass");
  return (scrubbed_cells<Layers>() + kFrames - 1U) / kFrames;
}

/// Checks `count` cells from *cursor on (wrapping; *cursor is clamped first, so an upset in it
/// cannot index outside the storage), resets every corrupted one to the distrusted cell and
/// returns how many it reset.
template <typename Layers>
[[nodiscard]] inline std::uint32_t scrub_slice(Layers& layers, std::uint32_t* cursor, std::uint32_t count) noexcept {
  constexpr std::uint32_t kTotal = scrubbed_cells<Layers>();
  constexpr std::uint32_t kFine = Layers::kHasFine ? static_cast<std::uint32_t>(Layers::kFineCellCount) : 0U;
  std::uint32_t at = *cursor < kTotal ? *cursor : 0U;
  std::uint32_t reset = 0U;
  for (std::uint32_t k = 0; k < count && k < kTotal; ++k) {
    if (at < kFine) {
      if constexpr (Layers::kHasFine) {
        auto& cell = layers.fine_storage[at];
        if (cell_signature(cell) != layers.checks.fine[at]) {
          reset_cell(layers, cell);
          ++reset;
        }
      }
    } else {
      if constexpr (Layers::kCcmLayerCount > 0) {
        auto& cell = layers.ccm_storage[at - kFine];
        if (cell_signature(cell) != layers.checks.ccm[at - kFine]) {
          reset_cell(layers, cell);
          ++reset;
        }
      }
    }
    at = at + 1U < kTotal ? at + 1U : 0U;
  }
  *cursor = at;
  return reset;
}

/// The scrub over the free-space records (map/visibility/free_space.hpp): checks `count` of the
/// `total` records from *cursor on (wrapping; *cursor clamped first), resets every one whose
/// signature disagrees with its check to no evidence (all zero, check 0) and returns how many.
template <typename Record>
[[nodiscard]] inline std::uint32_t scrub_record_slice(Record* records, CellCheck* checks, std::uint32_t total,
                                                      std::uint32_t* cursor, std::uint32_t count) noexcept {
  std::uint32_t at = *cursor < total ? *cursor : 0U;
  std::uint32_t reset = 0U;
  for (std::uint32_t k = 0; k < count && k < total; ++k) {
    if (cell_signature(records[at]) != checks[at]) {
      records[at] = Record{};
      checks[at] = 0U;
      ++reset;
    }
    at = at + 1U < total ? at + 1U : 0U;
  }
  *cursor = at;
  return reset;
}

/// After RingGrid::move_to moved a window of `side` cells (a power of two) whose lowest global
/// index was `old_min` to one whose lowest index is `new_min`: zeroes the checks (checks[slot],
/// side * side of them, slot = grid::buffer_offset) of exactly the cells the move cleared, as
/// RingGrid::move_to chooses them (a move of a side or more on an axis clears every cell).
inline void clear_checks_after_move(CellCheck* checks, std::int32_t side, CellIndex old_min, CellIndex new_min) noexcept {
  const std::int64_t dx = std::int64_t{new_min.x} - std::int64_t{old_min.x};
  const std::int64_t dy = std::int64_t{new_min.y} - std::int64_t{old_min.y};
  const auto count = static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
  if (dx >= side || dx <= -side || dy >= side || dy <= -side) {
    for (std::size_t i = 0; i < count; ++i) {
      checks[i] = 0U;
    }
    return;
  }
  const auto shift_x = static_cast<std::int32_t>(dx);
  const auto shift_y = static_cast<std::int32_t>(dy);
  const std::int32_t leaving_cols = shift_x >= 0 ? shift_x : -shift_x;
  const std::int32_t leaving_rows = shift_y >= 0 ? shift_y : -shift_y;
  const auto row_of = [side](std::int32_t global_y) {
    return static_cast<std::size_t>(grid::wrap(global_y, side)) * static_cast<std::size_t>(side);
  };
  const std::int32_t first_leaving_row = shift_y >= 0 ? old_min.y : old_min.y + side + shift_y;
  for (std::int32_t k = 0; k < leaving_rows; ++k) {
    const std::size_t row = row_of(first_leaving_row + k);
    for (std::int32_t c = 0; c < side; ++c) {
      checks[row + static_cast<std::size_t>(c)] = 0U;
    }
  }
  if (leaving_cols > 0) {
    const std::int32_t first_leaving_col = shift_x >= 0 ? old_min.x : old_min.x + side + shift_x;
    const std::int32_t first_staying_row = shift_y >= 0 ? old_min.y + shift_y : old_min.y;
    for (std::int32_t r = 0; r < side - leaving_rows; ++r) {
      const std::size_t row = row_of(first_staying_row + r);
      for (std::int32_t c = 0; c < leaving_cols; ++c) {
        checks[row + static_cast<std::size_t>(grid::wrap(first_leaving_col + c, side))] = 0U;
      }
    }
  }
}

// ---- bookkeeping ------------------------------------------------------------------------------

/// A 128-bit check word over bookkeeping values: two 64-bit lanes, x = rotl(x, 7) ^ w and
/// sum = sum + w (mod 2^64) per 64-bit word w of the bytes added. Any single changed bit changes
/// both lanes. Values are added byte for byte (a bool or pointer is read as bytes, never loaded
/// as its type), so a corrupted value is seen without being used.
struct StateSeal {
  std::uint64_t x;
  std::uint64_t sum;
};
[[nodiscard]] constexpr bool operator==(const StateSeal& a, const StateSeal& b) noexcept {
  return a.x == b.x && a.sum == b.sum;
}
[[nodiscard]] constexpr bool operator!=(const StateSeal& a, const StateSeal& b) noexcept { return !(a == b); }

class StateHasher {
 public:
  /// Adds the bytes of a value (its object representation, padding included: sealed values are
  /// written field by field, so their padding never changes). Sizes are compile-time constants:
  /// the loop unrolls into a load and two operations per 8 bytes.
  template <typename T>
  void add(const T& value) noexcept {
    add_bytes<sizeof(T)>(reinterpret_cast<const unsigned char*>(&value));
  }
  template <std::size_t kBytes>
  void add_bytes(const unsigned char* bytes) noexcept {
    for (std::size_t i = 0; i + 8U <= kBytes; i += 8U) {
      std::uint64_t w = 0U;
      std::memcpy(&w, bytes + i, sizeof w);
      word(w);
    }
    if constexpr (kBytes % 8U != 0U) {
      std::uint64_t w = 0U;
      std::memcpy(&w, bytes + (kBytes - kBytes % 8U), kBytes % 8U);
      word(w);
    }
  }
  [[nodiscard]] StateSeal seal() const noexcept { return StateSeal{x_, sum_}; }

 private:
  void word(std::uint64_t w) noexcept {
    x_ = rotr64(x_, 57U) ^ w;  // rotl 7
    sum_ += w;
  }
  std::uint64_t x_ = 0x9E3779B97F4A7C15ULL;
  std::uint64_t sum_ = 0U;
};

/// Adds a bool to a seal as its byte (never loaded as a bool: a bool an upset changed to a value
/// other than 0 or 1 is undefined behaviour when loaded, and is refused before it is).
inline void hash_bool_bytes(StateHasher& h, const bool& value) noexcept {
  unsigned char byte = 0U;
  std::memcpy(&byte, &value, 1U);
  h.add(byte);
}

/// Adds the bookkeeping of a LayerSet to a seal: every grid's bytes (storage address, side, cell
/// width and its inverse, window centre and lowest index; also the move telemetry, resealed with
/// every move), the widths and the kept windows. Addresses are hashed as numbers, never followed.
template <typename Layers>
inline void hash_layer_bindings(StateHasher& h, const Layers& layers) noexcept {
  if constexpr (Layers::kHasFine) {
    h.add_bytes<sizeof layers.fine>(reinterpret_cast<const unsigned char*>(&layers.fine));
  }
  if constexpr (Layers::kCcmLayerCount > 0) {
    h.add_bytes<sizeof layers.ccm>(reinterpret_cast<const unsigned char*>(&layers.ccm));
  }
  h.add(layers.widths);
  h.add(layers.kept);
}

/// The checks of stack layer `layer` (side^2 of them, in buffer order).
template <typename Layers>
[[nodiscard]] inline CellCheck* layer_checks(Layers& layers, int layer) noexcept {
  if (!Layers::is_ccm(layer)) {
    return layers.checks.fine;
  }
  std::size_t offset = 0U;
  for (int k = Layers::kFineLayerCount; k < layer; ++k) {
    offset += Layers::capacity(k);
  }
  return layers.checks.ccm + offset;
}

/// The word that says a stack is initialised (any other non-zero value: corrupted).
inline constexpr std::uint32_t kStackReady = 0x5EA1AB1EU;
/// The word a stack records when a call found its state corrupted (Stack::verify_state).
inline constexpr std::uint32_t kStackCorrupt = 0xC0A2A5EDU;

}  // namespace ccmap::detail
