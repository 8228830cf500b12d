// Patches that outlive the window: the global map's memory beyond the robot-centric stack.
//
// A Stack's layers are windows that follow the robot; a move clears the cells that leave them.
// A PatchKeeper moves the stack instead of the caller and, before the move, saves those cells
// into patches; after it, it reads back the patches under the cells that entered and restores
// them. A patch is one tile of kTile x kTile cells of one layer at fixed global cell indices
// (tile (tx, ty) of layer l: cells [tx T, tx T + T) x [ty T, ty T + T)), holding the cells'
// moments (the snapshot's cell codec, bit-exact), stamped with the pose and pose uncertainty the
// caller gave for the move that wrote it. A cell comes back into the slot it left, and a cell
// that enters a window is always empty (the move cleared it), so the restore is exact: the
// stack after any drive equals, cell by cell and bitwise, a stack with windows wide enough never
// to scroll that was fed the same points (tests/global/patch_keeper_test.cpp proves it, and
// against a double-precision batch of the points).
//
// Storage: through the platform's PatchStorage table (platform/include/ccmap/platform/
// patch_storage.hpp: a caller-provided region on bare metal, a directory on POSIX). A patch is
// read, its evicted cells written into it, and written back only if a byte changed; nothing of
// the patch store is kept in the keeper but one patch buffer (kMaxPatchBytes).
//
// Bounds per move_to (S_l the side of layer l, T = kTile; the window minimum is even, so a
// window covers at most S_l / T + 1 tiles per axis):
//   patch writes <= max_writes_per_move()      = sum_l (S_l / T + 1)^2     (the window left whole)
//               <= max_writes_per_step()       = sum_l 4 (S_l / T + 1)      (each layer moved <= T cells)
//   patch reads  <= 2 x the same (the tiles left and the tiles entered)
//   cells visited: the cells of the tiles touched (<= (T + S_l)^2 per layer).
// A rover moving less than T - 2 finest cells per move_to stays within max_writes_per_step().
//
// Patch format (version kPatchFormatVersion; little-endian, floats IEEE-754 binary32):
//    0  magic "CCMP" (4), format version (u16), cell kind (u8: 1 Kalman, 2 OMG, 3 CCM full,
//       4 CCM paper), tile side T (u8)
//    8  total size (u32, trailer included)
//   12  layer, tile x, tile y (i32 each)
//   24  cell width (m)
//   28  pose of the writing move: x, y (m, map frame), yaw (rad), position sigma (m, 1-sigma),
//       yaw sigma (rad, 1-sigma)
//   48  write sequence (u32: the keeper's patch writes since init, this one included)
//   52  corrected pose: x, y (m, map frame), yaw (rad): where a loop closure put the writing
//       pose (PatchStitcher, global/patch_stitcher.hpp); the pose at 28 when never corrected.
//       The patch's cells belong at C W^-1 m, m their map-frame position, W the pose at 28
//       and C this one (rigid in the plane; heights unchanged).
//   64  T x T cells, rows of increasing y, x increasing (empty cells: all zero)
//  end  CRC-32 (IEEE, as snapshots) of every byte before it
// A patch that fails any check (magic, version, kind, side, size, key, width, CRC, a cell no
// export could write) is not used: counted (patches_refused), its cells are lost; an eviction
// onto it starts a fresh patch.
//
// What it does not do: free-space records (drop-offs seen through lines of sight) are not
// patched; an uncertain move (Stack::move_to with a sigma) is not offered here; a MapExchange
// sees restored cells as gains of this rover (it sends them again).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "ccmap/core/status.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/persistence/exchange.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/platform/patch_storage.hpp"

namespace ccmap {

inline constexpr std::uint16_t kPatchFormatVersion = 2U;

/// The pose stamp of the patches a move writes.
struct PatchPose {
  float x_m;            ///< rover position, map frame (m)
  float y_m;
  float yaw_rad;        ///< rover heading (rad)
  float sigma_xy_m;     ///< position uncertainty, 1-sigma (m), >= 0
  float sigma_yaw_rad;  ///< heading uncertainty, 1-sigma (rad), >= 0
};

/// A pose in the plane: where a loop closure puts a patch's writing pose.
struct PlanarPose {
  float x_m;      ///< map frame (m)
  float y_m;
  float yaw_rad;  ///< rad
};

/// What one move_to did.
struct PatchMoveReport {
  std::uint32_t patches_written;
  std::uint32_t patches_read;
  std::uint32_t cells_saved;     ///< observed cells written into patches
  std::uint32_t cells_restored;  ///< cells read back into the windows
  std::uint32_t cells_lost;      ///< observed cells that left with no patch written (storage refused)
};

/// Life-time counters (reset by init).
struct PatchCounters {
  std::uint32_t moves;
  std::uint32_t patches_written;
  std::uint32_t patches_read;
  std::uint32_t patches_refused;  ///< read back but failed a check (not used)
  std::uint32_t write_failures;   ///< the storage refused a write (full, I/O)
  std::uint64_t cells_saved;
  std::uint64_t cells_restored;
  std::uint64_t cells_lost;
};

/// What a patch's header says (read_patch_header).
struct PatchHeader {
  std::uint8_t cell_kind;
  std::int32_t tile_side;
  platform::PatchKey key;
  float cell_width_m;
  PatchPose pose;
  std::uint32_t sequence;
  PlanarPose corrected;  ///< the pose's correction by a loop closure (== pose's x, y, yaw if none)
};

namespace detail {

inline constexpr std::size_t kPatchHeaderBytes = 64U;
inline constexpr std::size_t kPatchCorrectedOffset = 52U;
inline constexpr std::uint8_t kPatchMagic[4] = {0x43U, 0x43U, 0x4DU, 0x50U};  // "CCMP"

template <typename Cell>
[[nodiscard]] constexpr std::uint8_t patch_cell_kind() noexcept {
  if constexpr (std::is_same_v<Cell, KalmanCell>) {
    return 1U;
  } else if constexpr (std::is_same_v<Cell, OmgCell>) {
    return 2U;
  } else if constexpr (std::is_same_v<Cell, CcmCell>) {
    return 3U;
  } else {
    return 4U;
  }
}
template <typename Cell>
inline constexpr std::size_t kPatchCellBytes = std::is_same_v<Cell, KalmanCell> || std::is_same_v<Cell, OmgCell>
                                                   ? kSnapshotFineCellBytes
                                                   : kSnapshotCcmCellBytes<Cell>;

/// Bytes of a patch of tile side T with cells of cell_bytes.
[[nodiscard]] constexpr std::size_t patch_bytes(std::int32_t tile, std::size_t cell_bytes) noexcept {
  return kPatchHeaderBytes + static_cast<std::size_t>(tile) * static_cast<std::size_t>(tile) * cell_bytes + 4U;
}

/// floor(a / b) for b > 0.
[[nodiscard]] constexpr std::int32_t floor_div(std::int32_t a, std::int32_t b) noexcept {
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/// Checks the envelope and header of a patch of `expected_size` bytes; fills *header.
[[nodiscard]] inline bool patch_read_header(const std::uint8_t* data, std::size_t size, std::size_t expected_size,
                                            PatchHeader* header) noexcept {
  if (data == nullptr || size != expected_size || size < kPatchHeaderBytes + 4U ||
      std::memcmp(data, kPatchMagic, 4U) != 0) {
    return false;
  }
  SnapshotReader r(data, size);
  r.seek(size - 4U);
  const std::uint32_t stored_crc = r.u32();
  if (crc32_update(0U, data, size - 4U) != stored_crc) {
    return false;
  }
  r.seek(4U);
  const std::uint16_t version = r.u16();
  PatchHeader h{};
  h.cell_kind = r.u8();
  h.tile_side = r.u8();
  const std::uint32_t total = r.u32();
  h.key.layer = r.i32();
  h.key.tile_x = r.i32();
  h.key.tile_y = r.i32();
  h.cell_width_m = r.f32();
  h.pose = PatchPose{r.f32(), r.f32(), r.f32(), r.f32(), r.f32()};
  h.sequence = r.u32();
  h.corrected = PlanarPose{r.f32(), r.f32(), r.f32()};
  if (!r.ok() || version != kPatchFormatVersion || total != size) {
    return false;
  }
  *header = h;
  return true;
}

/// Writes the header fields (all but the CRC) into data[0, kPatchHeaderBytes).
inline void patch_write_header(std::uint8_t* data, std::size_t size, const PatchHeader& h) noexcept {
  SnapshotWriter w(data, kPatchHeaderBytes);
  for (const std::uint8_t b : kPatchMagic) {
    w.u8(b);
  }
  w.u16(kPatchFormatVersion);
  w.u8(h.cell_kind);
  w.u8(static_cast<std::uint8_t>(h.tile_side));
  w.u32(static_cast<std::uint32_t>(size));
  w.i32(h.key.layer);
  w.i32(h.key.tile_x);
  w.i32(h.key.tile_y);
  w.f32(h.cell_width_m);
  w.f32(h.pose.x_m);
  w.f32(h.pose.y_m);
  w.f32(h.pose.yaw_rad);
  w.f32(h.pose.sigma_xy_m);
  w.f32(h.pose.sigma_yaw_rad);
  w.u32(h.sequence);
  w.f32(h.corrected.x_m);
  w.f32(h.corrected.y_m);
  w.f32(h.corrected.yaw_rad);
}

/// Rewrites the corrected pose of a patch whose header was checked (patch_read_header).
inline void patch_write_corrected(std::uint8_t* data, const PlanarPose& corrected) noexcept {
  SnapshotWriter w(data + kPatchCorrectedOffset, kPatchHeaderBytes - kPatchCorrectedOffset);
  w.f32(corrected.x_m);
  w.f32(corrected.y_m);
  w.f32(corrected.yaw_rad);
}

/// Appends the CRC of data[0, size - 4) at size - 4.
inline void patch_seal(std::uint8_t* data, std::size_t size) noexcept {
  SnapshotWriter w(data + size - 4U, 4U);
  w.u32(crc32_update(0U, data, size - 4U));
}

/// The half-open rectangle of a window [min, min + side).
struct WindowRect {
  CellIndex min;
  std::int32_t side;
  [[nodiscard]] bool contains(std::int32_t x, std::int32_t y) const noexcept {
    return x >= min.x && y >= min.y && x - min.x < side && y - min.y < side;
  }
};

/// The keeper's access to a Stack's private state (friend of Stack<Config>).
template <typename Config>
struct GlobalAccess {
  using StackType = Stack<Config>;
  using Layers = LayerSet<Config>;

  /// fn(grid): the layer's RingGrid (CCM or fine).
  template <typename Fn>
  static void with_grid(StackType& stack, int layer, Fn&& fn) noexcept {
    if (Layers::is_ccm(layer)) {
      fn(stack.layers_.ccm_grid(layer));
    } else {
      if constexpr (Layers::kHasFine) {
        fn(stack.layers_.fine);
      }
    }
  }
  [[nodiscard]] static WindowRect window(const StackType& stack, int layer) noexcept {
    return WindowRect{stack.layers_.window_min(layer), Layers::side(layer)};
  }
  /// The window a move_to(x, y) will give the layer (Stack::move_to's snapping).
  [[nodiscard]] static WindowRect window_after(const StackType& stack, int layer, float x, float y) noexcept {
    const CellIndex centre = StackType::snapped_centre(x, y, stack.layers_.widths[layer]);
    const std::int32_t side = Layers::side(layer);
    return WindowRect{CellIndex{centre.x - side / 2, centre.y - side / 2}, side};
  }
  [[nodiscard]] static float width(const StackType& stack, int layer) noexcept { return stack.layers_.widths[layer]; }
  [[nodiscard]] static const StackParams& params(const StackType& stack) noexcept { return stack.params_; }
  /// The cell as a patch may keep it: itself if intact, else the distrusted cell (an upset's
  /// mark travels through the patch, so the place answers unknown when it comes back).
  template <typename Cell>
  [[nodiscard]] static Cell intact_or_distrusted(const StackType& stack, const Cell& cell) noexcept {
    return detail::intact_or_distrusted(stack.layers_, cell);
  }
  /// Writes `value` into `cell` (a cell of the stack) and carries the change into its check.
  template <typename Cell>
  static void write_cell(StackType& stack, Cell& cell, const Cell& value) noexcept {
    detail::write_cell(stack.layers_, cell, [&](Cell& written) { written = value; });
  }
};

}  // namespace detail

/// The patch keeper of one Stack<Config>: place it in static storage beside the stack; init()
/// binds it. Every move of the stack then goes through move_to().
template <typename Config, std::int32_t kTile = 16>
class PatchKeeper {
  using Access = detail::GlobalAccess<Config>;

 public:
  static_assert(kTile >= 2 && kTile <= 128 && kTile % 2 == 0, "tile side: even, 2..128");
  using StackType = Stack<Config>;
  static constexpr int kLayerCount = StackType::kLayerCount;
  static constexpr std::int32_t kTileSide = kTile;
  /// Bytes of a patch of a CCM layer and of the fine layer.
  static constexpr std::size_t kCcmPatchBytes =
      detail::patch_bytes(kTile, detail::kPatchCellBytes<typename StackType::CcmCellType>);
  static constexpr std::size_t kFinePatchBytes = detail::patch_bytes(kTile, detail::kSnapshotFineCellBytes);
  static constexpr std::size_t kMaxPatchBytes = kCcmPatchBytes > kFinePatchBytes ? kCcmPatchBytes : kFinePatchBytes;

  [[nodiscard]] static constexpr std::size_t patch_size(int layer) noexcept {
    return StackType::layer_is_ccm(layer) ? kCcmPatchBytes : kFinePatchBytes;
  }
  /// Tiles a layer's window covers at most per axis.
  [[nodiscard]] static constexpr std::int32_t tiles_per_axis(int layer) noexcept {
    return StackType::layer_side(layer) / kTile + 1;
  }
  /// Patch writes of one move_to, any distance (see the file comment).
  [[nodiscard]] static constexpr std::uint32_t max_writes_per_move() noexcept {
    std::uint32_t n = 0U;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      n += static_cast<std::uint32_t>(tiles_per_axis(layer) * tiles_per_axis(layer));
    }
    return n;
  }
  /// Patch writes of one move_to that moves no layer more than kTile cells per axis.
  [[nodiscard]] static constexpr std::uint32_t max_writes_per_step() noexcept {
    std::uint32_t n = 0U;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const std::int32_t t = tiles_per_axis(layer);
      n += static_cast<std::uint32_t>(4 * t < t * t ? 4 * t : t * t);
    }
    return n;
  }

  PatchKeeper() noexcept = default;
  PatchKeeper(const PatchKeeper&) = delete;
  PatchKeeper& operator=(const PatchKeeper&) = delete;
  PatchKeeper(PatchKeeper&&) = delete;
  PatchKeeper& operator=(PatchKeeper&&) = delete;
  ~PatchKeeper() = default;

  /// Binds the keeper to an initialised stack and a storage (both function pointers set), and
  /// reads back every patch under the stack's windows (merged into cells the stack observed
  /// already): afterwards every stored cell in a window is in the stack, so that no eviction
  /// overwrites a patch with a cell that was never restored (a restart over a kept directory, a
  /// second stack over the same storage to align against old patches). kNotInitialised /
  /// kCorrupt: the stack's state; kInvalidArgument: a storage without functions. report (may be
  /// nullptr): what the read-back did.
  [[nodiscard]] Status init(StackType& stack, const platform::PatchStorage& storage,
                            PatchMoveReport* report = nullptr) noexcept {
    stack_ = nullptr;
    const Status state = stack.verify_state();
    if (state != Status::kOk) {
      return state;
    }
    if (storage.write == nullptr || storage.read == nullptr) {
      return Status::kInvalidArgument;
    }
    stack_ = &stack;
    storage_ = storage;
    sequence_ = 0U;
    counters_ = PatchCounters{};
    PatchMoveReport r{};
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const detail::WindowRect window = Access::window(stack, layer);
      const detail::WindowRect none{window.min, 0};  // contains no cell: every cell "entered"
      Access::with_grid(stack, layer, [&](auto& grid) { restore_layer(grid, layer, window, none, r); });
    }
    counters_.patches_read += r.patches_read;
    counters_.cells_restored += r.cells_restored;
    counters_.cells_lost += r.cells_lost;
    if (report != nullptr) {
      *report = r;
    }
    return Status::kOk;
  }

  /// Moves the stack to (x, y) (Stack::move_to) and keeps what leaves: the observed cells
  /// leaving any window are written into their patches, stamped with `stamp`; the patches under
  /// the cells entering are read back into them. Statuses: kNotInitialised (keeper or stack);
  /// Stack::move_to's refusals (nothing written, the map unchanged); kInvalidArgument for a
  /// stamp with a non-finite field or a negative sigma (nothing changes). A storage that
  /// refuses a write does not stop the move: the cells are lost, counted (report, counters).
  /// report may be nullptr.
  [[nodiscard]] Status move_to(float x, float y, const PatchPose& stamp, PatchMoveReport* report) noexcept {
    PatchMoveReport r{};
    if (report != nullptr) {
      *report = r;
    }
    if (stack_ == nullptr) {
      return Status::kNotInitialised;
    }
    const Status state = stack_->verify_state();
    if (state != Status::kOk) {
      return state;
    }
    const Status position = check_position(x, y);
    if (position != Status::kOk) {
      return stack_->move_to(x, y);  // the stack refuses and counts it
    }
    if (!stamp_valid(stamp)) {
      return Status::kInvalidArgument;
    }
    detail::WindowRect before[kLayerCount > 0 ? kLayerCount : 1]{};
    for (int layer = 0; layer < kLayerCount; ++layer) {
      before[layer] = Access::window(*stack_, layer);
      const detail::WindowRect after = Access::window_after(*stack_, layer, x, y);
      Access::with_grid(*stack_, layer, [&](auto& grid) { save_layer(grid, layer, before[layer], after, stamp, r); });
    }
    const Status moved = stack_->move_to(x, y);
    if (moved != Status::kOk) {
      return moved;  // not reachable: the position was checked
    }
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const detail::WindowRect after = Access::window(*stack_, layer);
      Access::with_grid(*stack_, layer, [&](auto& grid) { restore_layer(grid, layer, after, before[layer], r); });
    }
    ++counters_.moves;
    counters_.patches_written += r.patches_written;
    counters_.patches_read += r.patches_read;
    counters_.cells_saved += r.cells_saved;
    counters_.cells_restored += r.cells_restored;
    counters_.cells_lost += r.cells_lost;
    if (report != nullptr) {
      *report = r;
    }
    return Status::kOk;
  }

  /// Reads the patch of key into buffer (capacity >= patch_size(key.layer)) and checks it: kOk
  /// with *header filled; kUnknown: no such patch; kCorrupt: a patch that fails a check;
  /// kInvalidArgument: bad arguments; kBufferTooSmall.
  [[nodiscard]] Status read_patch(const platform::PatchKey& key, std::uint8_t* buffer, std::size_t capacity,
                                  PatchHeader* header) noexcept {
    if (stack_ == nullptr) {
      return Status::kNotInitialised;
    }
    if (buffer == nullptr || header == nullptr || key.layer < 0 || key.layer >= kLayerCount) {
      return Status::kInvalidArgument;
    }
    if (capacity < patch_size(key.layer)) {
      return Status::kBufferTooSmall;
    }
    return load(key, buffer, header);
  }

  /// Re-stamps the stored patch of key with the corrected pose (a loop closure's: the format's
  /// offset 52): the patch is read, checked, changed there only, resealed and written back; its
  /// cells and writing pose are untouched. kOk; kUnknown: no such patch; kCorrupt: a patch that
  /// fails a check (counted in patches_refused, left as it is); kBufferTooSmall: the storage
  /// refused the write (counted in write_failures; the stored patch keeps its old stamp);
  /// kInvalidArgument: a bad layer or a non-finite pose; kNotInitialised.
  [[nodiscard]] Status restamp(const platform::PatchKey& key, const PlanarPose& corrected) noexcept {
    if (stack_ == nullptr) {
      return Status::kNotInitialised;
    }
    if (key.layer < 0 || key.layer >= kLayerCount || !std::isfinite(corrected.x_m) ||
        !std::isfinite(corrected.y_m) || !std::isfinite(corrected.yaw_rad)) {
      return Status::kInvalidArgument;
    }
    const Status loaded = load(key, buffer_);
    if (loaded != Status::kOk) {
      return loaded;
    }
    const std::size_t size = patch_size(key.layer);
    detail::patch_write_corrected(buffer_, corrected);
    detail::patch_seal(buffer_, size);
    if (storage_.write(storage_.context, key, buffer_, size) != platform::StorageResult::kOk) {
      ++counters_.write_failures;
      return Status::kBufferTooSmall;
    }
    return Status::kOk;
  }

  /// Called after every patch write of move_to with the patch's key and write sequence (a
  /// PatchStitcher's log); nullptr: none. Bound before moves; the call must be bounded and must
  /// not call the keeper.
  using WriteObserver = void (*)(void* context, const platform::PatchKey& key, std::uint32_t sequence);
  void set_write_observer(WriteObserver observer, void* context) noexcept {
    observer_ = observer;
    observer_context_ = context;
  }

  /// The map-frame centre of a patch's tile (m); false for a bad layer or an unbound keeper.
  [[nodiscard]] bool tile_centre(const platform::PatchKey& key, float* x, float* y) const noexcept {
    if (stack_ == nullptr || x == nullptr || y == nullptr || key.layer < 0 || key.layer >= kLayerCount) {
      return false;
    }
    const float side = static_cast<float>(kTile) * Access::width(*stack_, key.layer);
    *x = (static_cast<float>(key.tile_x) + 0.5F) * side;
    *y = (static_cast<float>(key.tile_y) + 0.5F) * side;
    return true;
  }

  [[nodiscard]] const PatchCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] bool initialised() const noexcept { return stack_ != nullptr; }

 private:
  [[nodiscard]] static bool stamp_valid(const PatchPose& p) noexcept {
    return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.yaw_rad) && p.sigma_xy_m >= 0.0F &&
           p.sigma_yaw_rad >= 0.0F && std::isfinite(p.sigma_xy_m) && std::isfinite(p.sigma_yaw_rad);
  }

  /// Reads and checks the patch of key into `into` (patch_size(key.layer) bytes of room).
  [[nodiscard]] Status load(const platform::PatchKey& key, std::uint8_t* into, PatchHeader* header = nullptr) noexcept {
    const std::size_t expected = patch_size(key.layer);
    std::size_t size = 0U;
    const platform::StorageResult got = storage_.read(storage_.context, key, into, expected, &size);
    if (got == platform::StorageResult::kNotFound) {
      return Status::kUnknown;
    }
    PatchHeader h{};
    const std::uint8_t kind = StackType::layer_is_ccm(key.layer)
                                  ? detail::patch_cell_kind<typename StackType::CcmCellType>()
                                  : detail::patch_cell_kind<typename StackType::FineCell>();
    if (got != platform::StorageResult::kOk || !detail::patch_read_header(into, size, expected, &h) ||
        h.cell_kind != kind || h.tile_side != kTile || !platform::same_key(h.key, key) ||
        !detail::same_float_bits(h.cell_width_m, Access::width(*stack_, key.layer))) {
      ++counters_.patches_refused;
      return Status::kCorrupt;
    }
    if (header != nullptr) {
      *header = h;
    }
    return Status::kOk;
  }

  /// Cells of tile (tx, ty) in `in` and not in `out`: the call visits each.
  template <typename Fn>
  static void for_each_cell(std::int32_t tx, std::int32_t ty, const detail::WindowRect& in,
                            const detail::WindowRect& out, Fn&& fn) noexcept {
    for (std::int32_t j = 0; j < kTile; ++j) {
      for (std::int32_t i = 0; i < kTile; ++i) {
        const std::int32_t x = tx * kTile + i;
        const std::int32_t y = ty * kTile + j;
        if (in.contains(x, y) && !out.contains(x, y)) {
          fn(x, y, static_cast<std::size_t>(j) * static_cast<std::size_t>(kTile) + static_cast<std::size_t>(i));
        }
      }
    }
  }
  /// True if some cell of tile (tx, ty) is in `in` and not in `out`.
  [[nodiscard]] static bool tile_differs(std::int32_t tx, std::int32_t ty, const detail::WindowRect& in,
                                         const detail::WindowRect& out) noexcept {
    // The tile's part of `in` is a rectangle; it lies inside `out` iff its corners do.
    const std::int32_t x0 = tx * kTile > in.min.x ? tx * kTile : in.min.x;
    const std::int32_t y0 = ty * kTile > in.min.y ? ty * kTile : in.min.y;
    const std::int32_t x1 = (tx + 1) * kTile < in.min.x + in.side ? (tx + 1) * kTile : in.min.x + in.side;
    const std::int32_t y1 = (ty + 1) * kTile < in.min.y + in.side ? (ty + 1) * kTile : in.min.y + in.side;
    if (x0 >= x1 || y0 >= y1) {
      return false;
    }
    return !(out.contains(x0, y0) && out.contains(x1 - 1, y1 - 1));
  }

  /// Calls fn(tx, ty) for every tile with a cell in `in` and not in `out`.
  template <typename Fn>
  static void for_each_tile(const detail::WindowRect& in, const detail::WindowRect& out, Fn&& fn) noexcept {
    const std::int32_t tx0 = detail::floor_div(in.min.x, kTile);
    const std::int32_t ty0 = detail::floor_div(in.min.y, kTile);
    const std::int32_t tx1 = detail::floor_div(in.min.x + in.side - 1, kTile);
    const std::int32_t ty1 = detail::floor_div(in.min.y + in.side - 1, kTile);
    for (std::int32_t ty = ty0; ty <= ty1; ++ty) {
      for (std::int32_t tx = tx0; tx <= tx1; ++tx) {
        if (tile_differs(tx, ty, in, out)) {
          fn(tx, ty);
        }
      }
    }
  }

  template <typename Grid>
  void save_layer(Grid& grid, int layer, const detail::WindowRect& before, const detail::WindowRect& after,
                  const PatchPose& stamp, PatchMoveReport& r) noexcept {
    using Cell = std::remove_reference_t<decltype(grid.cell_unchecked(CellIndex{}))>;
    constexpr std::size_t kCellBytes = detail::kPatchCellBytes<Cell>;
    const std::size_t size = patch_size(layer);
    for_each_tile(before, after, [&](std::int32_t tx, std::int32_t ty) {
      const platform::PatchKey key{layer, tx, ty};
      const Status loaded = load(key, buffer_);
      r.patches_read += loaded == Status::kOk ? 1U : 0U;
      const bool existed = loaded == Status::kOk;
      if (!existed) {
        std::memset(buffer_, 0, size);
      }
      bool changed = false;
      std::uint32_t observed = 0U;
      for_each_cell(tx, ty, before, after, [&](std::int32_t x, std::int32_t y, std::size_t slot) {
        const Cell cell = Access::intact_or_distrusted(*stack_, grid.cell_unchecked(CellIndex{x, y}));
        std::uint8_t bytes[kCellBytes]{};
        if (cell.weight > 0.0F || detail::distrust_mark(cell)) {  // the distrusted cell: weight -0
          detail::SnapshotWriter w(bytes, kCellBytes);
          detail::snapshot_write_cell(w, cell);
          observed += cell.weight > 0.0F ? 1U : 0U;
        }
        std::uint8_t* at = buffer_ + detail::kPatchHeaderBytes + slot * kCellBytes;
        if (std::memcmp(at, bytes, kCellBytes) != 0) {
          std::memcpy(at, bytes, kCellBytes);
          changed = true;
        }
      });
      if (!changed) {
        return;
      }
      const PatchHeader h{detail::patch_cell_kind<Cell>(), kTile, key, Access::width(*stack_, layer), stamp,
                          sequence_ + 1U, PlanarPose{stamp.x_m, stamp.y_m, stamp.yaw_rad}};
      detail::patch_write_header(buffer_, size, h);
      detail::patch_seal(buffer_, size);
      if (storage_.write(storage_.context, key, buffer_, size) == platform::StorageResult::kOk) {
        ++sequence_;
        ++r.patches_written;
        r.cells_saved += observed;
        if (observer_ != nullptr) {
          observer_(observer_context_, key, sequence_);
        }
      } else {
        ++counters_.write_failures;
        r.cells_lost += observed;
      }
    });
  }

  template <typename Grid>
  void restore_layer(Grid& grid, int layer, const detail::WindowRect& after, const detail::WindowRect& before,
                     PatchMoveReport& r) noexcept {
    using Cell = std::remove_reference_t<decltype(grid.cell_unchecked(CellIndex{}))>;
    const float width = Access::width(*stack_, layer);
    for_each_tile(after, before, [&](std::int32_t tx, std::int32_t ty) {
      if (load(platform::PatchKey{layer, tx, ty}, buffer_) != Status::kOk) {
        return;
      }
      ++r.patches_read;
      // Every stored cell of the patch must be one a save writes before any is restored.
      bool valid = true;
      for (std::size_t slot = 0; slot < static_cast<std::size_t>(kTile * kTile); ++slot) {
        const Cell cell = stored_cell<Cell>(slot);
        valid = valid && (cell.weight == 0.0F || detail::exchange_cell_valid(cell, width));
      }
      if (!valid) {
        ++counters_.patches_refused;
        return;
      }
      for_each_cell(tx, ty, after, before, [&](std::int32_t x, std::int32_t y, std::size_t slot) {
        const Cell stored = stored_cell<Cell>(slot);
        Cell& cell = grid.cell_unchecked(CellIndex{x, y});
        if (detail::distrust_mark(stored)) {
          // An upset had cost the place its cells: unknown (reason upset) until points observe
          // it again, unless something observed it meanwhile.
          if (!(Access::intact_or_distrusted(*stack_, cell).weight > 0.0F)) {
            Access::write_cell(*stack_, cell, detail::distrusted_cell<Cell>());
          }
          return;
        }
        if (!(stored.weight > 0.0F)) {
          return;
        }
        // A move cleared the cell: the merge of the stored moments into it is their copy. Only
        // init() finds observed cells under a patch (a stack fed before its keeper was bound).
        Cell merged = Access::intact_or_distrusted(*stack_, cell);
        if (merged.weight > 0.0F) {
          if (!detail::exchange_merge(merged, stored, 0.0F, Access::params(*stack_), width)) {
            ++r.cells_lost;
            return;
          }
        } else {
          merged = stored;
        }
        Access::write_cell(*stack_, cell, merged);
        ++r.cells_restored;
      });
    });
  }

  template <typename Cell>
  [[nodiscard]] Cell stored_cell(std::size_t slot) const noexcept {
    constexpr std::size_t kCellBytes = detail::kPatchCellBytes<Cell>;
    detail::SnapshotReader reader(buffer_ + detail::kPatchHeaderBytes + slot * kCellBytes, kCellBytes);
    Cell cell{};
    (void)detail::snapshot_read_cell(reader, &cell);
    return cell;
  }

  StackType* stack_ = nullptr;
  platform::PatchStorage storage_{};
  std::uint32_t sequence_ = 0U;
  PatchCounters counters_{};
  WriteObserver observer_ = nullptr;
  void* observer_context_ = nullptr;
  std::uint8_t buffer_[kMaxPatchBytes]{};
};

}  // namespace ccmap
