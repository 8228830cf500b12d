// Versioned, CRC-protected binary snapshots of a map stack, for telemetry and replay.
//
//   std::uint8_t buffer[ccmap::snapshot_size<ccmap::CadreConfig>()];   // static storage
//   std::size_t written = 0;
//   ccmap::Status s = ccmap::save_snapshot(map, buffer, sizeof buffer, &written);
//   ...
//   s = ccmap::load_snapshot(map, buffer, written);   // all-or-nothing
//
// A snapshot holds the run-time parameters, each layer's window centre and raw cells and the
// life-time counters. Loading re-initialises the stack from the stored parameters and restores
// windows and cells, so the loaded stack answers every query and export bitwise identically to
// the saved one (routing table and thresholds are recomputed by init(), deterministically).
// Not stored: RingGrid::cells_cleared_by_moves() and Stack::accepted_frames() (restart at 0 on
// load), map exchange's bookkeeping (a load retires a bound MapExchange, persistence/exchange.hpp) and
// the outlier gate's held points awaiting the change rule (map/update/held_pool.hpp: at most
// Stack::kCcmHeldSlots / kFineHeldSlots cells; after a load such a cell needs change_min_points
// held points anew).
//
// Format (version 5: version 4, the frame budget's parameters and counter, with the
// single-event-upset counters and free space from lines of sight: its parameters, counters and
// per-cell records). Every field is little-endian, written byte by byte (never a memcpy of a
// struct), floats as their IEEE-754 binary32 bit pattern; sizes in bytes:
//
//   header       4  magic "CCMS" (0x43 0x43 0x4D 0x53)
//                2  format version (kSnapshotFormatVersion)
//                2  reserved, 0
//                4  total size of the snapshot, trailer included
//   fingerprint  1  fine kind (FineKind), 1 layer count, 2 reserved 0,
//               32  side of each layer, finest first (uint32 x kMaxLayers, 0 past the last layer)
//                2  bytes per fine cell on the wire (12), 2 bytes per CCM cell (40 for CcmCell,
//                   36 for CcmPaperCell: the cell kind is part of the shape)
//   free space   2  bytes per free-space record (4, or 0 for a Config without free space: part of
//                   the shape), 2 reserved 0
//                4  frames the free-space stage has seen (uint32; its sampling phase and the
//                   records' frame stamps follow it, so a loaded stack goes on as the saved one)
//   params      60  StackParams floats: finest_cell_width_m, weight_limit, coverage_tau,
//                   min_weight, obstacle_fraction, max_inclination, kalman_min_variance,
//                   normal_variance_threshold[0..7]
//                4  finest_max_sigma_m
//               12  outlier_gate_sigma, change_min_points, change_share
//                8  frame_point_budget, frame_time_budget_us (uint32 each)
//               20  free_space_rays, free_space_clear_frames, sensor_view_axis[0..2]
//               20  noise model: kind (u8), weight mode (u8), 2 reserved 0, stereo k = sigma_d/(f b)
//                   (1/m), lidar sigma0 (m), lidar sigma per m, reference range (m)
//   per layer    8  window centre (int32 x, int32 y; global cell indices), then
//                   side*side cells in window order: rows of increasing global y from the
//                   window's lowest y, x increasing inside a row (RingGrid::for_each order).
//                   Kalman cell: height, variance, weight. OMG cell: weight, height, s.
//                   CCM cell: weight, mean_x, mean_y, mean_z, s_xx, s_yy, s_zz, s_xz, s_yz, then
//                   s_xy for CcmCell (CcmPaperCell has none).
//   records         with free space, per layer (finest first) side*side free-space records in the
//                   same window order: bound code (uint16), evidence (uint8), state (uint8)
//                   (map/visibility/free_space_cell.hpp); nothing without free space
//   counters    88  total FrameCounters (22 x uint32, in declaration order)
//                8  rejected moves, rejected frames (uint32 each)
//                8  reserved, written 0 (ignored on load): a measured duration is not map state,
//                   so two maps fed the same frames save the same bytes; load leaves
//                   last_update_ns() at 0 (no frame since the load)
//   trailer      4  CRC-32 (IEEE 802.3 / zlib, reflected 0xEDB88320) of every byte before it
//
// Version history: 1 had only the 9-float CCM cell (36 bytes); version 2 added the cell kind
// (CcmCell with s_xy); version 3 the outlier gate's parameters and counters; version 4 the frame
// budget's; version 5 the counters corrupted_cells and corrupted_slots (docs/integration.md,
// "Radiation: single-event upsets") and free space (its shape field, parameters, counters and
// records). A version-1 snapshot is refused with kVersionMismatch: its 9-float cells hold no
// lateral covariance, and a full-cell map rebuilt from them would answer differently. Versions 2
// to 4 are refused likewise (a map without the records would answer no drop-off the saved one
// answered).
//
// Statuses of load_snapshot, checked in this order, before anything is written to the stack:
//   kInvalidArgument  data == nullptr
//   kCorrupt          shorter than the header, wrong magic, a non-zero reserved header field
//   kVersionMismatch  another format version (also version 1, before the cell kinds)
//   kCorrupt          size field != size (truncated or trailing bytes), CRC mismatch
//   kVersionMismatch  fingerprint of another stack configuration (another preset, another CCM
//                     cell kind, with or without free space): the data is intact but describes
//                     another map shape
//   kCorrupt          anything inside that a save could not have written: parameters that
//                     init() would refuse, a non-finite float (weight_limit may be +inf, the
//                     "no limit" value), a negative cell weight, an odd or out-of-range window
//                     centre, an unknown enum value, a non-zero reserved field.
// On any failure the stack is bitwise unchanged.
//
// No heap, no exceptions; save and load are O(snapshot size).
#pragma once

#include <cstddef>
#include <cstdint>

#include "ccmap/core/status.hpp"
#include "ccmap/map/config.hpp"
#include "ccmap/map/stack.hpp"

namespace ccmap {

/// Format version written by this library; load_snapshot accepts exactly this version.
inline constexpr std::uint16_t kSnapshotFormatVersion = 5U;

/// CRC-32 (IEEE 802.3, as zlib's crc32): pass 0 as `crc` for the first block, the previous
/// result to continue. crc32_update(0, "123456789", 9) == 0xCBF43926. data may be nullptr
/// only with size 0.
[[nodiscard]] std::uint32_t crc32_update(std::uint32_t crc, const std::uint8_t* data,
                                         std::size_t size) noexcept;

namespace detail {

static_assert(kMaxLayers == 8, "snapshot format version 5 stores 8 sides and 8 thresholds");

inline constexpr std::size_t kSnapshotHeaderBytes = 12U;
static_assert(kSnapshotHeaderBytes == 4U + 2U + 2U + 4U, "header: magic, version, reserved, size");
inline constexpr std::size_t kSnapshotFingerprintBytes = 4U + 4U * static_cast<std::size_t>(kMaxLayers) + 4U;

inline constexpr std::size_t kSnapshotFreeSpaceShapeBytes = 8U;
inline constexpr std::size_t kSnapshotParamsBytes = 4U * (7U + static_cast<std::size_t>(kMaxLayers) + 1U + 3U + 2U + 5U) + 20U;
inline constexpr std::size_t kSnapshotLayerHeaderBytes = 8U;
inline constexpr std::size_t kSnapshotFreeSpaceRecordBytes = 4U;
inline constexpr std::size_t kSnapshotCountersBytes = 22U * 4U + 2U * 4U + 8U;
inline constexpr std::size_t kSnapshotTrailerBytes = 4U;
inline constexpr std::size_t kSnapshotFineCellBytes = std::size_t{3} * 4U;  // Kalman and OMG: 3 floats
/// Bytes of a CCM cell on the wire: 4 per float (10 for CcmCell, 9 for CcmPaperCell).
template <typename Cell>
inline constexpr std::size_t kSnapshotCcmCellBytes = sizeof(Cell) / sizeof(float) * 4U;
static_assert(kSnapshotCcmCellBytes<CcmCell> == 40U && kSnapshotCcmCellBytes<CcmPaperCell> == 36U,
              "CCM cells on the wire: 10 and 9 floats");

/// What a snapshot says about the shape of the stack it came from.
struct SnapshotFingerprint {
  std::uint8_t fine_kind;
  std::uint8_t layer_count;
  std::uint32_t sides[kMaxLayers];
  std::uint16_t fine_cell_bytes;
  std::uint16_t ccm_cell_bytes;
};

/// Little-endian byte writer over a buffer the caller sized (no bounds checks beyond the
/// capacity given; save_snapshot checks the capacity first). Records non-finite floats.
class SnapshotWriter {
 public:
  SnapshotWriter(std::uint8_t* data, std::size_t capacity) noexcept : data_(data), capacity_(capacity) {}
  void u8(std::uint8_t v) noexcept;
  void u16(std::uint16_t v) noexcept;
  void u32(std::uint32_t v) noexcept;
  void u64(std::uint64_t v) noexcept;
  void i32(std::int32_t v) noexcept;
  /// A float that must be finite (a non-finite one marks the writer not finite()).
  void f32(float v) noexcept;
  /// A float that may also be +inf (weight_limit: kNoWeightLimit).
  void f32_or_inf(float v) noexcept;
  [[nodiscard]] std::size_t position() const noexcept { return position_; }
  [[nodiscard]] bool finite() const noexcept { return finite_; }
  [[nodiscard]] bool overflowed() const noexcept { return overflowed_; }
  [[nodiscard]] std::uint8_t* data() const noexcept { return data_; }

 private:
  std::uint8_t* data_;
  std::size_t capacity_;
  std::size_t position_ = 0U;
  bool finite_ = true;
  bool overflowed_ = false;
};

/// Little-endian byte reader; reading past the end gives 0 and marks the reader !ok().
class SnapshotReader {
 public:
  SnapshotReader(const std::uint8_t* data, std::size_t size) noexcept : data_(data), size_(size) {}
  [[nodiscard]] std::uint8_t u8() noexcept;
  [[nodiscard]] std::uint16_t u16() noexcept;
  [[nodiscard]] std::uint32_t u32() noexcept;
  [[nodiscard]] std::uint64_t u64() noexcept;
  [[nodiscard]] std::int32_t i32() noexcept;
  [[nodiscard]] float f32() noexcept;
  void seek(std::size_t position) noexcept;
  [[nodiscard]] std::size_t position() const noexcept { return position_; }
  [[nodiscard]] bool ok() const noexcept { return ok_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t position_ = 0U;
  bool ok_ = true;
};

// Non-template pieces of the format (src/persistence/snapshot.cpp).
void snapshot_write_header(SnapshotWriter& w, std::size_t total_size, const SnapshotFingerprint& f) noexcept;
/// The fingerprint alone (kSnapshotFingerprintBytes): also the preset field of exchange deltas.
void snapshot_write_fingerprint(SnapshotWriter& w, const SnapshotFingerprint& f) noexcept;
/// The envelope shared by snapshots and exchange deltas: 4 magic bytes, a 16-bit format version,
/// 16 reserved zero bits, a 32-bit total size, ..., a CRC-32 trailer. kInvalidArgument for null
/// data; kCorrupt for fewer than min_size bytes, another magic, a non-zero reserved field, a size
/// field other than size, a CRC mismatch; kVersionMismatch for another version. Reads nothing else.
[[nodiscard]] Status check_envelope(const std::uint8_t* data, std::size_t size, const std::uint8_t (&magic)[4],
                                    std::uint16_t version, std::size_t min_size) noexcept;
/// check_envelope with the snapshot's magic "CCMS" and kSnapshotFormatVersion.
[[nodiscard]] Status snapshot_check_envelope(const std::uint8_t* data, std::size_t size) noexcept;
/// Reads the fingerprint (reader positioned after the header): kVersionMismatch if it differs
/// from `expected`, kCorrupt for a non-zero reserved field.
[[nodiscard]] Status snapshot_check_fingerprint(SnapshotReader& r, const SnapshotFingerprint& expected) noexcept;
void snapshot_write_params(SnapshotWriter& w, const StackParams& params) noexcept;
/// Reads and validates parameters as init() of a stack with `layer_count` layers (finest
/// layer piece-wise constant if has_fine) would: kCorrupt if init() could refuse them.
[[nodiscard]] Status snapshot_read_params(SnapshotReader& r, int layer_count, bool has_fine,
                                          StackParams* out) noexcept;
void snapshot_write_centre(SnapshotWriter& w, CellIndex centre) noexcept;
/// False for an odd or out-of-range centre (windows always start on even indices).
[[nodiscard]] bool snapshot_read_centre(SnapshotReader& r, CellIndex* out) noexcept;
void snapshot_write_cell(SnapshotWriter& w, const CcmCell& c) noexcept;
void snapshot_write_cell(SnapshotWriter& w, const CcmPaperCell& c) noexcept;
void snapshot_write_cell(SnapshotWriter& w, const KalmanCell& c) noexcept;
void snapshot_write_cell(SnapshotWriter& w, const OmgCell& c) noexcept;
/// False for a non-finite field or a negative weight (*out is written either way).
[[nodiscard]] bool snapshot_read_cell(SnapshotReader& r, CcmCell* out) noexcept;
[[nodiscard]] bool snapshot_read_cell(SnapshotReader& r, CcmPaperCell* out) noexcept;
[[nodiscard]] bool snapshot_read_cell(SnapshotReader& r, KalmanCell* out) noexcept;
[[nodiscard]] bool snapshot_read_cell(SnapshotReader& r, OmgCell* out) noexcept;
void snapshot_write_record(SnapshotWriter& w, const FreeSpaceCell& c) noexcept;
/// Every bit pattern of a record is one a stack can hold: never refused.
void snapshot_read_record(SnapshotReader& r, FreeSpaceCell* out) noexcept;
/// The counters block, its 8 reserved bytes written 0 and skipped on read.
void snapshot_write_counters(SnapshotWriter& w, const FrameCounters& totals, std::uint32_t rejected_moves,
                             std::uint32_t rejected_frames) noexcept;
void snapshot_read_counters(SnapshotReader& r, FrameCounters* totals, std::uint32_t* rejected_moves,
                            std::uint32_t* rejected_frames) noexcept;
/// Appends the CRC-32 of data[0..w.position()).
void snapshot_write_trailer(SnapshotWriter& w) noexcept;

/// The only code with access to a Stack's private state (friend of Stack<Config>).
template <typename Config>
struct SnapshotAccess {
  using StackType = Stack<Config>;
  using CcmCellType = typename StackType::CcmCellType;
  static constexpr int kLayers = StackType::kLayerCount;
  static constexpr std::size_t kCcmCellBytes = kSnapshotCcmCellBytes<CcmCellType>;
  static constexpr bool kFreeSpace = kConfigFreeSpace<Config>;
  static constexpr std::uint16_t kRecordBytes = kFreeSpace ? static_cast<std::uint16_t>(kSnapshotFreeSpaceRecordBytes) : 0U;

  [[nodiscard]] static constexpr std::size_t size() noexcept {
    std::size_t total = kSnapshotHeaderBytes + kSnapshotFingerprintBytes + kSnapshotFreeSpaceShapeBytes +
                        kSnapshotParamsBytes + kSnapshotCountersBytes + kSnapshotTrailerBytes;
    for (int layer = 0; layer < kLayers; ++layer) {
      const std::size_t cell_bytes = StackType::layer_is_ccm(layer) ? kCcmCellBytes : kSnapshotFineCellBytes;
      total += kSnapshotLayerHeaderBytes + StackType::layer_capacity(layer) * (cell_bytes + kRecordBytes);
    }
    return total;
  }

  [[nodiscard]] static SnapshotFingerprint fingerprint() noexcept {
    SnapshotFingerprint f{};
    f.fine_kind = static_cast<std::uint8_t>(Config::kFineKind);
    f.layer_count = static_cast<std::uint8_t>(kLayers);
    for (int layer = 0; layer < kLayers; ++layer) {
      f.sides[layer] = static_cast<std::uint32_t>(StackType::layer_side(layer));
    }
    f.fine_cell_bytes = static_cast<std::uint16_t>(kSnapshotFineCellBytes);
    f.ccm_cell_bytes = static_cast<std::uint16_t>(kCcmCellBytes);
    return f;
  }

  [[nodiscard]] static Status save(const StackType& stack, std::uint8_t* buffer, std::size_t capacity,
                                   std::size_t* written) noexcept {
    if (written != nullptr) {
      *written = 0U;
    }
    if (buffer == nullptr || written == nullptr) {
      return Status::kInvalidArgument;
    }
    const Status state = stack.state_status();  // integrity: a corrupted state is not saved
    if (state != Status::kOk) {
      return state;
    }
    if (capacity < size()) {
      return Status::kBufferTooSmall;
    }
    SnapshotWriter w(buffer, capacity);
    snapshot_write_header(w, size(), fingerprint());
    w.u16(kRecordBytes);
    w.u16(0U);
    w.u32(stack.free_space_.frames());
    snapshot_write_params(w, stack.params_);
    for (int layer = 0; layer < kLayers; ++layer) {
      if (StackType::layer_is_ccm(layer)) {
        const RingGrid<CcmCellType>& grid = stack.layers_.ccm_grid(layer);
        snapshot_write_centre(w, grid.centre());
        // Integrity: a cell an upset changed is saved as the distrusted cell (map/detail/integrity.hpp).
        grid.for_each([&w, &stack](CellIndex, const CcmCellType& cell) {
          snapshot_write_cell(w, intact_or_distrusted(stack.layers_, cell));
        });
      } else {
        snapshot_write_centre(w, stack.layers_.fine.centre());
        stack.layers_.fine.for_each([&w, &stack](CellIndex, const typename StackType::FineCell& cell) {
          snapshot_write_cell(w, intact_or_distrusted(stack.layers_, cell));
        });
      }
    }
    if constexpr (kFreeSpace) {
      for (int layer = 0; layer < kLayers; ++layer) {
        // Integrity: a corrupted record is saved as no evidence (it is one until the scrub resets it).
        stack.free_space_.records(layer)->for_each(
            [&w, &stack](CellIndex, const FreeSpaceCell& c) { snapshot_write_record(w, stack.free_space_.intact_or_empty(c)); });
      }
    }
    snapshot_write_counters(w, stack.totals_, stack.rejected_moves_, stack.rejected_frames_);
    snapshot_write_trailer(w);
    if (w.overflowed() || w.position() != size()) {
      return Status::kInvalidArgument;  // cannot happen: the layout and size() disagree
    }
    if (!w.finite()) {
      return Status::kNonFiniteInput;  // a NaN/Inf in the state: the snapshot would not load
    }
    *written = w.position();
    return Status::kOk;
  }

  /// Pass 1 of load_snapshot (and of merging a snapshot, persistence/exchange.hpp): validates
  /// data[0..data_size) completely, touching no stack. On kOk, *params holds the stored
  /// parameters and *layers_begin the offset of the first layer record (for for_each_stored_cell).
  [[nodiscard]] static Status validate(const std::uint8_t* data, std::size_t data_size, StackParams* params,
                                       std::size_t* layers_begin) noexcept {
    if (data == nullptr || params == nullptr || layers_begin == nullptr) {
      return Status::kInvalidArgument;
    }
    const Status envelope = snapshot_check_envelope(data, data_size);
    if (envelope != Status::kOk) {
      return envelope;
    }
    SnapshotReader r(data, data_size - kSnapshotTrailerBytes);
    r.seek(kSnapshotHeaderBytes);
    const Status shape = snapshot_check_fingerprint(r, fingerprint());
    if (shape != Status::kOk) {
      return shape;
    }
    const std::uint16_t record_bytes = r.u16();
    const std::uint16_t reserved = r.u16();
    const std::uint32_t frames = r.u32();
    if (!r.ok() || reserved != 0U) {
      return Status::kCorrupt;
    }
    if (record_bytes != kRecordBytes) {
      return Status::kVersionMismatch;  // saved by a stack with (or without) free space
    }
    if (!kFreeSpace && frames != 0U) {
      return Status::kCorrupt;  // a stack without free space counts no frames
    }
    if (data_size != size()) {
      return Status::kCorrupt;
    }
    const Status params_status = snapshot_read_params(r, kLayers, StackType::kHasFine, params);
    if (params_status != Status::kOk) {
      return params_status;
    }
    *layers_begin = r.position();
    bool valid = true;
    for (int layer = 0; layer < kLayers && valid; ++layer) {
      CellIndex centre{};
      valid = snapshot_read_centre(r, &centre);
      const std::size_t cells = StackType::layer_capacity(layer);
      for (std::size_t i = 0; i < cells && valid; ++i) {
        if (StackType::layer_is_ccm(layer)) {
          CcmCellType cell{};
          valid = snapshot_read_cell(r, &cell);
        } else {
          typename StackType::FineCell cell{};
          valid = snapshot_read_cell(r, &cell);
        }
      }
    }
    if constexpr (kFreeSpace) {
      for (int layer = 0; layer < kLayers; ++layer) {
        for (std::size_t i = 0; i < StackType::layer_capacity(layer); ++i) {
          FreeSpaceCell record{};
          snapshot_read_record(r, &record);
        }
      }
    }
    FrameCounters totals{};
    std::uint32_t rejected_moves = 0U;
    std::uint32_t rejected_frames = 0U;
    snapshot_read_counters(r, &totals, &rejected_moves, &rejected_frames);
    if (!valid || !r.ok() || r.position() != data_size - kSnapshotTrailerBytes) {
      return Status::kCorrupt;
    }
    return Status::kOk;
  }

  /// Calls fn(layer, CellIndex global_index, const Cell& cell) for every stored cell of a
  /// snapshot that validate() accepted (Cell: CcmCellType for CCM layers, the fine cell type for the
  /// finest layer), layer by layer, in window order.
  template <typename Fn>
  static void for_each_stored_cell(const std::uint8_t* data, std::size_t data_size, std::size_t layers_begin,
                                   Fn&& fn) noexcept {
    SnapshotReader r(data, data_size - kSnapshotTrailerBytes);
    r.seek(layers_begin);
    for (int layer = 0; layer < kLayers; ++layer) {
      CellIndex centre{};
      (void)snapshot_read_centre(r, &centre);
      const std::int32_t side = StackType::layer_side(layer);
      const CellIndex min{centre.x - side / 2, centre.y - side / 2};
      for (std::int32_t row = 0; row < side; ++row) {
        for (std::int32_t col = 0; col < side; ++col) {
          const CellIndex index{min.x + col, min.y + row};
          if (StackType::layer_is_ccm(layer)) {
            CcmCellType cell{};
            (void)snapshot_read_cell(r, &cell);
            fn(layer, index, cell);
          } else {
            typename StackType::FineCell cell{};
            (void)snapshot_read_cell(r, &cell);
            fn(layer, index, cell);
          }
        }
      }
    }
  }

  [[nodiscard]] static Status load(StackType& stack, const std::uint8_t* data, std::size_t data_size) noexcept {
    // Pass 1: validate everything; the stack is not touched.
    StackParams params{};
    std::size_t layers_begin = 0U;
    const Status valid = validate(data, data_size, &params, &layers_begin);
    if (valid != Status::kOk) {
      return valid;
    }
    SnapshotReader r(data, data_size - kSnapshotTrailerBytes);
    // Pass 2: commit. init() accepts what snapshot_read_params accepted (same checks).
    const Status init_status = stack.init(params);
    if (init_status != Status::kOk) {
      return init_status;  // not reachable: the parameters were validated as init() does
    }
    r.seek(kSnapshotHeaderBytes + kSnapshotFingerprintBytes + 4U);
    stack.free_space_.set_frames(r.u32());
    r.seek(layers_begin);
    for (int layer = 0; layer < kLayers; ++layer) {
      CellIndex centre{};
      (void)snapshot_read_centre(r, &centre);
      if (StackType::layer_is_ccm(layer)) {
        RingGrid<CcmCellType>& grid = stack.layers_.ccm_grid(layer);
        (void)grid.init(grid.storage(), grid.side(), grid.cell_width(), centre);
        grid.for_each([&r](CellIndex, CcmCellType& cell) { (void)snapshot_read_cell(r, &cell); });
      } else {
        auto& grid = stack.layers_.fine;
        (void)grid.init(grid.storage(), grid.side(), grid.cell_width(), centre);
        grid.for_each([&r](CellIndex, typename StackType::FineCell& cell) { (void)snapshot_read_cell(r, &cell); });
      }
    }
    if constexpr (kFreeSpace) {
      for (int layer = 0; layer < kLayers; ++layer) {
        RingGrid<FreeSpaceCell>& records = *stack.free_space_.records(layer);
        (void)records.init(records.storage(), records.side(), records.cell_width(), stack.layers_.centre(layer));
        records.for_each([&r](CellIndex, FreeSpaceCell& c) { snapshot_read_record(r, &c); });
      }
    }
    snapshot_read_counters(r, &stack.totals_, &stack.rejected_moves_, &stack.rejected_frames_);
    stack.last_update_ns_ = 0U;  // no frame measured since the load
    reseal_all_cells(stack.layers_);  // integrity: the loaded cells' checks, the restored windows' seal
    stack.free_space_.reseal_records();  // and the loaded free-space records' checks
    stack.seal_state();
    return Status::kOk;
  }
};

}  // namespace detail

/// Bytes of a snapshot of a Stack<Config> (fixed by the configuration).
/// CadreConfig: CCMAP_CADRE_SNAPSHOT_SIZE of ccmap/ccmap.h (src/capi/capi.cpp asserts it);
/// docs/integration.md section 7 lists every preset.
template <typename Config>
[[nodiscard]] constexpr std::size_t snapshot_size() noexcept {
  return detail::SnapshotAccess<Config>::size();
}

/// Writes a snapshot of `stack` into buffer[0..*written) (*written = snapshot_size<Config>()).
/// kInvalidArgument: buffer or written nullptr. kNotInitialised: stack not initialised.
/// kBufferTooSmall: capacity < snapshot_size<Config>() (nothing written).
/// kNonFiniteInput: the state holds a NaN/Inf that load_snapshot would refuse (not produced by
/// this library's update paths). On failure *written = 0 and the buffer content is unspecified.
template <typename Config>
[[nodiscard]] Status save_snapshot(const Stack<Config>& stack, std::uint8_t* buffer, std::size_t capacity,
                                   std::size_t* written) noexcept {
  return detail::SnapshotAccess<Config>::save(stack, buffer, capacity, written);
}

/// Restores `stack` (initialised or not) from data[0..size): all-or-nothing, see the statuses in
/// the file comment. On kOk the stack answers every query and export bitwise as the saved one.
template <typename Config>
[[nodiscard]] Status load_snapshot(Stack<Config>& stack, const std::uint8_t* data, std::size_t size) noexcept {
  return detail::SnapshotAccess<Config>::load(stack, data, size);
}

}  // namespace ccmap
