// Map exchange between rovers of a team: compact deltas of what a map gained since it last sent,
// and exact merging of deltas and snapshots from other rovers. CCM cells are sufficient
// statistics, so two cells of the same ground fed disjoint points merge to the cell fed all of
// them (ccm_merge, Chan et al.); Kalman cells merge in information form (kalman_merge), OMG
// cells as one-dimensional moments (omg_merge).
//
//   static ccmap::Stack<ccmap::CadreConfig> map;
//   static ccmap::MapExchange<ccmap::CadreConfig> exchange;  // what was sent: one copy of the cells
//   exchange.init(map, ccmap::ExchangeParams{rover_id, boot_count, origin_cells, origin_z_m});
//   // every N frames, into a radio packet:
//   std::size_t n = 0;
//   exchange.export_delta(packet, sizeof packet, ccmap::ExportOptions{}, &n, nullptr);
//   // on reception from a peer:
//   exchange.merge_delta(bytes, size, &report);
//
// What a delta carries, and why it never counts a point twice
//  - Only what this map's own points added since the cell was last sent: the exchange keeps,
//    per cell, the state it last sent (the "sent" copy). A cell's gain is its state minus the
//    sent copy (ccm_unmerge, kalman_unmerge, omg_unmerge: the inverse of the merge). Whatever is
//    merged from peers goes into both the cell and its sent copy, so it is never sent on: a
//    cell's full state would carry the peer's own points back to it, and sender ids and
//    sequence numbers cannot detect that.
//  - Changed cells are found by comparing each cell with its sent copy (bitwise): the update
//    path writes nothing extra per point. Moves: a cell that left a window was cleared; the
//    stack keeps the intersection of each layer's windows since the last export
//    (detail::KeptWindow), and every cell outside it has its sent copy cleared before anything is
//    compared, so a cell that left and came back sends only what arrived after its return.
//  - Saturated cells: once the weight limiter (CCM, OMG: W = W_l) or the variance floor (Kalman)
//    has acted on a cell, the state is no longer the sum of its parts and the gain is not
//    defined. Such a cell is sent whole ("saturated"; Kalman cells with only their own new
//    measurement count): the receiver merges it with its own limit, which for two saturated
//    cells is the equal-share average of the two estimates, i.e. limit(A (+) B). This re-sends
//    information the receiver may hold already; the limiter bounds the effect (the merged map's
//    heights and slopes stay within the bound stated in docs/design.md, tested).
//  - Every export gets the next sequence number; the receiver keeps, per sender, its session and
//    the last sequence merged, and refuses (kDuplicate) a delta it merged before, an older one,
//    one of an older session, and its own. A lost delta is a gap (counted); its gains are lost
//    for that receiver (they were committed as sent).
//  - Cells a receiver cannot place (outside its windows) are dropped and counted; the receiver
//    keeps no copy of them.
//  - Free space (map/visibility/free_space.hpp) travels as entries after the cells (of the
//    layers written: ExportOptions::finest_layer holds back a finer layer's entries too): a drop-off
//    the sender's rays proved in a cell it holds no point in (sent once; a drop-off merged from
//    a team mate is not sent on), and a clear of every cell its lines of sight emptied since the
//    last export (the stage marks them: FreeSpace::clear_marked). A clear goes in the same delta
//    as the cell's first gain after it or before it (a cleared cell's sent copy becomes empty,
//    so that gain is everything since the clear); a clear without room waits with its cell.
//    The receiver folds a drop-off into its record of an unobserved cell (its bound lowered to
//    the sender's, moved by the origins' z offset and rounded up, its drop rays raised: both
//    idempotent); a cell it observed answers with its own points. It applies a clear before the
//    cells (a gain after a clear is new ground) under this rule: the cell is emptied (with its
//    sent copy and record) when it holds no point of the receiver's own (everything in it came
//    from team mates, whose data the sender's lines of sight overruled as its own), or when the
//    receiver's own lines of sight contradicted it too (its record's evidence >= 1: a frame
//    since the surface was last confirmed); otherwise the cell stays and its evidence is raised
//    to free_space_clear_frames - 1, so that one frame of the receiver's own contradicting rays
//    empties it and a point of its own on the surface (a confirmation) forgets the clear. Limits:
//    a clear whose cell left the sender's window before the next export is not sent; "own
//    points" is known from a per-cell flag (set when a gain of the cell is exported) and from
//    the cell differing from its sent copy (unsent points), so a cell the motion pass rescaled
//    counts as own (the safe side). A delta that may hold a clear has each received cell also
//    merged into an empty one in the validation pass, so the commit after the clears cannot fail.
//  - Exported cells can be limited by a weight floor, by layer and by the buffer: cells whose
//    gain weighs less than the floor, of layers finer than ExportOptions::finest_layer, or for
//    which the buffer has no room, stay pending (not sent, not lost; a later export sends their
//    then larger gain). Layers are written coarsest first: per byte a coarse cell covers the most
//    ground, and reaches a team mate farthest away.
//
// Alignment: both maps must share the grid: the same finest cell width (bitwise) and origins
// (ExchangeParams::origin_cells, the map-frame origin in the team frame, in finest cells) whose
// offset is a whole number of the coarsest layer's cells, so that every layer's cells coincide
// and stay nested (kMisaligned otherwise). A cell then keeps its mean relative to its centre,
// and only the heights move by the origins' z offset.
//
// Delta format (version 3). Little-endian, field by field (the snapshot's writer and reader),
// floats as IEEE-754 binary32 bits; a core (header, layers, CRC-32) and a free-space section of
// entries that carry their own checks; sizes in bytes:
//   header       4  magic "CCMD" (0x43 0x43 0x4D 0x44)
//                2  format version (kDeltaFormatVersion), 2 free-space entries n (after the core)
//                4  size of the core, its CRC included (the delta is that plus 10 n bytes)
//               40  preset fingerprint, as in snapshots (fine kind, layer count, sides, cell bytes)
//                4  finest cell width (m)
//   sender       4  rover id, 4 session, 4 sequence (1, 2, ... per session)
//                4  accepted frames at the previous export, 4 at this one (Stack::accepted_frames:
//                   the delta covers the frames in between)
//               12  origin in the team frame: x, y (int32, finest cells), z (float, m)
//   per layer, coarsest first:
//                8  window centre (int32 x, y; global cell indices of the sender)
//                4  number of cells n
//                   n cells in window order (rows of increasing y, x increasing): the gap since
//                   the previous cell's window position (y - min_y) * side + (x - min_x), minus
//                   one (the first: its position), as a LEB128 varint (1 byte below 128), then
//                   the cell in the snapshot's cell codec (snapshot_write_cell: CCM 40 bytes
//                   for CcmCell with s_xy, 36 for CcmPaperCell; Kalman and OMG 12 bytes)
//   core's CRC   4  CRC-32 (IEEE 802.3 / zlib) of every byte of the core before it
//   section   10 n  free-space entries, clears first, then drop-offs, coarsest layer first
//                   (map/visibility/free_space_cell.hpp gives their 10 bytes: position in the
//                   layer's window above, layer, kind, bound, drop rays, CRC-16 of the entry)
// Size: 88 + 12 per layer + 4 bytes of frame (152 for CADRE: src/capi/capi.cpp asserts it), and
// per cell the varint (1 byte for a gap below 128 positions, 2 below 16,384: every gap of a
// 64 x 64 layer, 3 in a 256 x 256 one) and 40 bytes (CCM, full cell; 36 paper cell) or 12
// (Kalman, OMG), and 10 per free-space entry (at most kMaxDeltaEntries); docs/integration.md
// gives typical exchanges. Version history: 1 carried the 9-float CCM cell only; 2 the cell
// kinds (as snapshot version 2); 3 the free-space section in the header's reserved field and
// after the core. A version-2 delta merges as a version-3 one without entries (its size field is
// the whole delta: bytes beyond it are kCorrupt); version 1 and versions after 3 are refused with
// kVersionMismatch; a version-2 reader refuses version 3 with kVersionMismatch.
//
// Statuses of merge_delta, all before anything is written (on any refusal the map and the sent
// copy are bitwise unchanged; the refusal is counted in counters()). They judge the core; the
// free-space section never refuses a delta whose core merges: each entry is checked alone (its
// CRC-16, its fields, its layer and position) and a bad one is refused and counted
// (MergeReport::entries_refused, free_space_status kCorrupt, counters().sections_damaged), as
// are entries the header announces but the bytes do not hold, while the cells and every good
// entry merge; bytes beyond the announced entries make the section damaged (kCorrupt status in
// the report) and are ignored:
//   kNotInitialised   exchange not initialised, or its stack re-initialised since (init again)
//   kInvalidArgument  data == nullptr
//   kCorrupt          a core truncated or with trailing bytes, wrong magic, CRC mismatch, or content no export
//                     writes (an odd window centre, a cell position outside the window, a
//                     non-finite or negative statistic, a zero weight, a mean outside its cell);
//                     or the stack's own state failed its integrity check (Stack::state_status:
//                     a single-event upset, docs/integration.md), counted the same way
//   kVersionMismatch  another format version, or a delta of another preset
//   kMisaligned       another finest cell width, or an origin offset that is not a whole number
//                     of coarsest cells
//   kDuplicate        this rover's own delta, or a sequence (session) of that sender already
//                     merged or older
//   kBufferTooSmall   a new sender while the peer table (kMaxPeers) is full
//   kOutOfRange       the merge would leave a cell non-finite or a height beyond
//                     kMaxAbsCoordinateM (an absurd origin offset)
// merge_snapshot has the snapshot's statuses (load_snapshot), then kMisaligned and kOutOfRange.
//
// No heap, no exceptions. export O(cells of the stack); merge O(delta + cells in the windows).
// One exchange per stack: binding another one (init) retires the first (kNotInitialised).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/cell/constant_cell.hpp"
#include "ccmap/core/assert.hpp"
#include "ccmap/core/status.hpp"
#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/core/float_bits.hpp"
#include "ccmap/map/stack.hpp"

namespace ccmap {

/// Format version written by this library; merge_delta accepts it and kDeltaOldestFormatVersion.
inline constexpr std::uint16_t kDeltaFormatVersion = 3U;
/// The oldest version merge_delta accepts: version 2 is version 3 without free-space entries.
inline constexpr std::uint16_t kDeltaOldestFormatVersion = 2U;

/// Who this map is in the team and where its map frame lies in the team frame.
struct ExchangeParams {
  std::uint32_t rover_id;    ///< unique per rover of the team
  std::uint32_t session;     ///< new value on every restart of this rover's map (e.g. a boot counter):
                             ///< peers take a larger session for a fresh map, refuse smaller ones
  CellIndex origin_cells;    ///< map-frame origin in the team frame, finest-layer cells (x, y)
  float origin_z_m;          ///< map-frame origin height in the team frame (m)
};

/// How to export.
struct ExportOptions {
  /// Cells whose gain weighs less (CCM, OMG: weight; Kalman: new measurements) stay pending.
  /// 0: every changed cell. Negative or NaN: kInvalidArgument.
  float weight_floor;
  /// Layers finer than this one are not written (their gains stay pending): a receiver keeps
  /// only what falls inside its own windows, and a fine layer's window reaches a team mate only
  /// when the rovers are within a few metres (CADRE: 4 cm layer +-1.28 m). 0: every layer;
  /// beyond the last layer: kInvalidArgument.
  std::int32_t finest_layer;
};

/// What an export wrote.
struct ExportReport {
  std::uint32_t sequence;         ///< the delta's sequence number
  std::uint32_t cells_written;
  std::uint32_t cells_saturated;  ///< of those, sent whole (limiter or floor engaged: see the file comment)
  std::uint32_t cells_pending;    ///< changed, not written: gain below the floor, or no room in the buffer
  std::uint32_t drops_written;    ///< free-space entries: drop-offs
  std::uint32_t clears_written;   ///< free-space entries: cells this map's lines of sight emptied
  std::uint32_t drops_pending;    ///< drop-offs not written for want of room (sent later)
  std::size_t bytes;
};

/// What a merge did.
struct MergeReport {
  std::uint32_t sender_id;       ///< 0 for a snapshot
  std::uint32_t sequence;        ///< 0 for a snapshot
  std::uint32_t cells_merged;    ///< folded into this map
  std::uint32_t cells_outside;   ///< outside this map's windows: dropped
  std::uint32_t deltas_missed;   ///< sequence numbers of this sender skipped before this delta (lost)
  // The free-space section (delta format 3; zero for a snapshot and a version-2 delta):
  std::uint32_t drops_merged;     ///< drop-offs folded into this map's records (cells it observed: none)
  std::uint32_t cells_cleared;    ///< cells a team mate's clear emptied here (the rule in the file comment)
  std::uint32_t clears_deferred;  ///< clears of cells holding this map's own points: evidence raised only
  std::uint32_t entries_outside;  ///< entries outside this map's windows: dropped
  std::uint32_t entries_refused;  ///< entries that failed their check or a field check, or were missing
  /// kOk if the section was whole and every entry passed its checks; kCorrupt otherwise (the
  /// good entries merged all the same, the cells too).
  Status free_space_status;
};

/// The header of a delta (peek_delta).
struct DeltaInfo {
  std::uint32_t sender_id;
  std::uint32_t session;
  std::uint32_t sequence;
  std::uint32_t frames_from;  ///< the sender's accepted frames at its previous export
  std::uint32_t frames_to;    ///< ... and at this one
  CellIndex origin_cells;
  float origin_z_m;
  float finest_cell_width_m;
  std::uint32_t cells;        ///< cells in the delta, all layers
  std::uint32_t free_space_entries;  ///< entries the header announces (version 2: 0)
};

/// Life-time counters of an exchange (reset by init).
struct ExchangeCounters {
  std::uint32_t deltas_exported;
  std::uint32_t deltas_merged;
  std::uint32_t snapshots_merged;
  std::uint32_t refused;             ///< merges refused, any reason
  std::uint32_t refused_corrupt;     ///< kCorrupt
  std::uint32_t refused_duplicate;   ///< kDuplicate
  std::uint32_t refused_misaligned;  ///< kMisaligned
  std::uint32_t deltas_missed;       ///< sum of MergeReport::deltas_missed
  std::uint64_t bytes_exported;
  std::uint64_t bytes_merged;
  std::uint64_t cells_exported;
  std::uint64_t cells_merged;
  std::uint64_t cells_outside;
  std::uint64_t drops_exported;
  std::uint64_t clears_exported;
  std::uint64_t drops_merged;
  std::uint64_t cells_cleared;       ///< by team mates' clears
  std::uint64_t clears_deferred;
  std::uint64_t entries_refused;     ///< free-space entries refused (MergeReport::entries_refused)
  std::uint32_t sections_damaged;    ///< deltas merged whose free-space section was not whole or held a refused entry
};

namespace detail {

inline constexpr std::size_t kDeltaHeaderBytes = 12U + kSnapshotFingerprintBytes + 4U + std::size_t{5} * 4U + 12U;
inline constexpr std::size_t kDeltaLayerHeaderBytes = 12U;
inline constexpr std::size_t kDeltaTrailerBytes = 4U;
/// Free-space entries a delta can hold (the header's 16-bit count).
inline constexpr std::uint32_t kMaxDeltaEntries = 65535U;
static_assert(kDeltaHeaderBytes == 88U, "the delta header is documented as 88 bytes");

/// Bytes of the LEB128 varint of v (1..5).
[[nodiscard]] constexpr std::size_t varint_bytes(std::uint32_t v) noexcept {
  std::size_t n = 1U;
  while (v >= 0x80U) {
    v >>= 7U;
    ++n;
  }
  return n;
}

/// How a cell's gain since it was last sent is to be sent.
enum class GainKind : std::uint8_t {
  kNone = 0,       ///< nothing to send (unchanged, or a change that no gain describes yet)
  kGain = 1,       ///< the exact gain (merge inverse)
  kSaturated = 2,  ///< limiter or floor engaged: the whole cell (see the file comment)
};

// Per cell kind (src/persistence/exchange.cpp); CcmCell, CcmPaperCell, KalmanCell and OmgCell overloads, named alike
// so that the templates below compile for every cell kind.
/// The gain of `cell` over `sent` (its last sent state), written to *gain, and its weight.
[[nodiscard]] GainKind exchange_gain(const CcmCell& cell, const CcmCell& sent, const StackParams& params,
                                     float cell_width_m, CcmCell* gain) noexcept;
[[nodiscard]] GainKind exchange_gain(const CcmPaperCell& cell, const CcmPaperCell& sent, const StackParams& params,
                                     float cell_width_m, CcmPaperCell* gain) noexcept;
[[nodiscard]] GainKind exchange_gain(const KalmanCell& cell, const KalmanCell& sent, const StackParams& params,
                                     float cell_width_m, KalmanCell* gain) noexcept;
[[nodiscard]] GainKind exchange_gain(const OmgCell& cell, const OmgCell& sent, const StackParams& params,
                                     float cell_width_m, OmgCell* gain) noexcept;
/// Weight a gain is compared with the export floor by (CCM, OMG: weight; Kalman: measurements).
[[nodiscard]] float exchange_weight(const CcmCell& c) noexcept;
[[nodiscard]] float exchange_weight(const CcmPaperCell& c) noexcept;
[[nodiscard]] float exchange_weight(const KalmanCell& c) noexcept;
[[nodiscard]] float exchange_weight(const OmgCell& c) noexcept;
/// True if a received cell is one an export or a save of this library can write: every field
/// finite, weight > 0, second moments >= 0, |height| <= kMaxAbsCoordinateM, a CCM mean within
/// one cell width of the centre, a Kalman variance > 0 (the full cell's s_xy: finite, as s_xz).
[[nodiscard]] bool exchange_cell_valid(const CcmCell& c, float cell_width_m) noexcept;
[[nodiscard]] bool exchange_cell_valid(const CcmPaperCell& c, float cell_width_m) noexcept;
[[nodiscard]] bool exchange_cell_valid(const KalmanCell& c, float cell_width_m) noexcept;
[[nodiscard]] bool exchange_cell_valid(const OmgCell& c, float cell_width_m) noexcept;
/// Merges a received cell, its height moved by dz_m into this map's frame, into `cell` with
/// this map's limit or floor. False (cell unspecified: callers merge into a copy first) if the
/// merge is refused or its result is not a valid cell (exchange_cell_valid).
[[nodiscard]] bool exchange_merge(CcmCell& cell, const CcmCell& received, float dz_m, const StackParams& params,
                                  float cell_width_m) noexcept;
[[nodiscard]] bool exchange_merge(CcmPaperCell& cell, const CcmPaperCell& received, float dz_m,
                                  const StackParams& params, float cell_width_m) noexcept;
[[nodiscard]] bool exchange_merge(KalmanCell& cell, const KalmanCell& received, float dz_m, const StackParams& params,
                                  float cell_width_m) noexcept;
[[nodiscard]] bool exchange_merge(OmgCell& cell, const OmgCell& received, float dz_m, const StackParams& params,
                                  float cell_width_m) noexcept;

void delta_write_varint(SnapshotWriter& w, std::uint32_t v) noexcept;
/// False (and the reader !ok()) for more than 5 bytes or a value beyond 32 bits.
[[nodiscard]] bool delta_read_varint(SnapshotReader& r, std::uint32_t* v) noexcept;

/// The header fields after the fingerprint, and the core's size and the entries announced.
struct DeltaSender {
  float finest_cell_width_m;
  std::uint32_t rover_id, session, sequence, frames_from, frames_to;
  CellIndex origin_cells;
  float origin_z_m;
  std::uint32_t core_size;  ///< bytes of the header, the cells and the CRC (version 2: the delta)
  std::uint32_t entries;    ///< free-space entries after the core
};
/// Writes magic, version, placeholders for the entry count and the core's size, the fingerprint
/// and the sender fields.
void delta_write_header(SnapshotWriter& w, const SnapshotFingerprint& f, const DeltaSender& sender) noexcept;
/// Patches the entry count and the core's size (core_end + 4) and writes the core's CRC-32 at
/// core_end (the writer has already passed the 4 bytes there and the section).
void delta_finish(SnapshotWriter& w, std::size_t core_end, std::uint32_t entries) noexcept;
/// Magic, version (3, or 2: no section), the core's size (at most `size`; version 2: `size`),
/// the core's CRC; then the fingerprint (kVersionMismatch if it is not `expected`) and the
/// sender fields (kCorrupt for a non-finite z or non-zero reserved field). Replaces r by a
/// reader of the core without its CRC, positioned after the header.
[[nodiscard]] Status delta_read_header(const std::uint8_t* data, std::size_t size, const SnapshotFingerprint& expected,
                                       SnapshotReader& r, DeltaSender* sender) noexcept;

/// Offset (sender - receiver) in finest cells from two origins; kMisaligned unless both axes are
/// multiples of 2^(layers - 1) (whole coarsest cells).
[[nodiscard]] Status exchange_offset(CellIndex sender_origin, CellIndex receiver_origin, int layer_count,
                                     std::int64_t* offset_x, std::int64_t* offset_y) noexcept;
/// The same check for an offset given directly.
[[nodiscard]] bool exchange_offset_aligned(std::int64_t offset_x, std::int64_t offset_y, int layer_count) noexcept;

/// One sender a receiver has merged from.
struct PeerRecord {
  std::uint32_t rover_id;
  std::uint32_t session;
  std::uint32_t last_sequence;
  std::uint32_t used;  ///< 1 if this entry holds a sender
};

/// Everything with access to a Stack's private state for exchange (friend of Stack<Config>):
/// the export and merge passes over the cells, generic in the cell kinds.
template <typename Config>
struct ExchangeAccess {
  using StackType = Stack<Config>;
  using Layers = LayerSet<Config>;
  using FineCell = typename Layers::FineCell;
  static constexpr int kLayers = Layers::kLayerCount;

  static constexpr bool kFreeSpace = kConfigFreeSpace<Config>;
  /// Cells of every layer (one free-space record each), in record order: layer 0's, then 1's...
  static constexpr std::size_t kCellCount =
      (Layers::kHasFine ? Layers::kFineCellCount : 0U) + (Layers::kCcmLayerCount > 0 ? Layers::kCcmCellCount : 0U);
  /// Per cell: what this exchange knows of it beyond the sent copy (free space only).
  static constexpr std::size_t kFlagCount = kFreeSpace ? kCellCount : 1U;
  /// Any of these bits set: the cell holds points of this map's own (a gain of it was exported,
  /// or it differed from its sent copy at a merge). Four bits, so that an upset can only set
  /// the flag (the safe side: a team mate's clear then does not empty the cell at once).
  static constexpr std::uint8_t kOwnBits = 0x0FU;
  /// The record's drop-off was sent (or merged from a team mate: not sent on).
  static constexpr std::uint8_t kDropSentBit = 0x10U;
  /// A clear of the cell is in the delta being written (between write_layers and write_section).
  static constexpr std::uint8_t kClearingBit = 0x20U;

  /// The sent copies, in the stack's slot layout (slot of global index i: buffer_offset(i, side)),
  /// and the per-cell flags (record order).
  struct SentCells {
    FineCell fine[Layers::kFineCellCount];
    typename Layers::CcmCellType ccm[Layers::kCcmCellCount];
    std::uint8_t flags[kFlagCount];
  };

  [[nodiscard]] static std::uint32_t next_generation(StackType& stack) noexcept {
    ++stack.generation_;
    stack.seal_state();  // integrity: the generation is sealed bookkeeping
    return stack.generation_;
  }
  [[nodiscard]] static std::uint32_t generation(const StackType& stack) noexcept { return stack.generation_; }
  [[nodiscard]] static const StackParams& params(const StackType& stack) noexcept { return stack.params_; }

  [[nodiscard]] static constexpr std::size_t ccm_offset(int layer) noexcept {
    std::size_t offset = 0U;
    for (int k = Layers::kFineLayerCount; k < layer; ++k) {
      offset += Layers::capacity(k);
    }
    return offset;
  }

  /// Calls fn(grid, sent_storage) for stack layer `layer` (grid: RingGrid<Cell>&, sent: Cell*).
  template <typename Fn>
  static void with_layer(StackType& stack, SentCells* sent, int layer, Fn&& fn) noexcept {
    if (Layers::is_ccm(layer)) {
      fn(stack.layers_.ccm_grid(layer), sent != nullptr ? sent->ccm + ccm_offset(layer) : nullptr);
    } else {
      if constexpr (Layers::kHasFine) {
        fn(stack.layers_.fine, sent != nullptr ? sent->fine : nullptr);
      }
    }
  }

  /// First record (and flag) of `layer`: the cells of the layers before it.
  [[nodiscard]] static constexpr std::size_t record_offset(int layer) noexcept {
    std::size_t offset = 0U;
    for (int k = 0; k < layer; ++k) {
      offset += Layers::capacity(k);
    }
    return offset;
  }

  static void clear(SentCells& sent) noexcept {
    for (FineCell& c : sent.fine) {
      c = FineCell{};
    }
    for (typename Layers::CcmCellType& c : sent.ccm) {
      c = typename Layers::CcmCellType{};
    }
    for (std::uint8_t& f : sent.flags) {
      f = 0U;
    }
  }

  /// Binding: no cell counts as cleared before it (the stage's marks dropped).
  static void drop_all_marks(StackType& stack) noexcept { stack.free_space_.clear_all_marks(); }

  /// Validates a snapshot and merges it (two passes: nothing changes unless all of it merges)
  /// into the stack and, if sent != nullptr, the sent copies.
  [[nodiscard]] static Status merge_snapshot(StackType& stack, SentCells* sent, const std::uint8_t* data,
                                             std::size_t size, CellIndex offset_cells, float offset_z_m,
                                             MergeReport& report) noexcept {
    const Status state = stack.verify_state();  // integrity: kNotInitialised or kCorrupt
    if (state != Status::kOk) {
      return state;
    }
    if (data == nullptr) {
      return Status::kInvalidArgument;
    }
    StackParams stored{};
    std::size_t layers_begin = 0U;
    const Status valid = SnapshotAccess<Config>::validate(data, size, &stored, &layers_begin);
    if (valid != Status::kOk) {
      return valid;
    }
    if (!same_float_bits(stored.finest_cell_width_m, stack.params_.finest_cell_width_m) ||
        !exchange_offset_aligned(offset_cells.x, offset_cells.y, kLayers)) {
      return Status::kMisaligned;
    }
    if (!std::isfinite(offset_z_m)) {
      return Status::kInvalidArgument;
    }
    const Status status = merge_snapshot_cells(stack, sent, data, size, layers_begin, offset_cells.x,
                                               offset_cells.y, offset_z_m, false, report);
    if (status != Status::kOk) {
      return status;
    }
    if (sent != nullptr) {
      settle(stack, *sent);  // after validation: a refused snapshot changes nothing at all
    }
    return merge_snapshot_cells(stack, sent, data, size, layers_begin, offset_cells.x, offset_cells.y, offset_z_m,
                                true, report);
  }

  /// Clears the sent copy of every cell that a move cleared since the last call (outside the
  /// grid's kept rectangle), then marks the windows: afterwards every sent copy describes the
  /// cell in its slot. Changes no cell of the map.
  static void settle(StackType& stack, SentCells& sent) noexcept {
    for (int layer = 0; layer < kLayers; ++layer) {
      KeptWindow& kept = stack.layers_.kept[layer];
      const std::size_t first = record_offset(layer);
      with_layer(stack, &sent, layer, [&](auto& grid, auto* copies) {
        using Cell = std::remove_reference_t<decltype(*copies)>;
        const std::int32_t side = grid.side();
        grid.for_each([&](CellIndex index, const Cell&) {
          if (!kept.contains(index)) {
            const std::size_t slot = grid::buffer_offset(index, side);
            copies[slot] = Cell{};
            if constexpr (kFreeSpace) {
              // The slot holds another cell now: its flags and the stage's clear mark go with the old one.
              sent.flags[first + slot] = 0U;
              stack.free_space_.drop_clear_mark(static_cast<std::uint32_t>(first + slot));
            }
          }
        });
        kept.mark(grid.window_min(), side);
      });
    }
    stack.seal_state();  // integrity: the kept windows are sealed bookkeeping
  }

  /// True if settle() ran since the last move: every layer's kept rectangle is its window.
  [[nodiscard]] static bool settled(const StackType& stack) noexcept {
    for (int layer = 0; layer < kLayers; ++layer) {
      const KeptWindow& kept = stack.layers_.kept[layer];
      const CellIndex min = stack.layers_.window_min(layer);
      const std::int32_t side = StackType::layer_side(layer);
      if (kept.min != min || kept.end != CellIndex{min.x + side, min.y + side}) {
        return false;
      }
    }
    return true;
  }

  /// Writes the gains of every layer (coarsest first) after the header; updates the sent copies
  /// of what it wrote. Precondition: settle() ran, the writer has room for the layer headers
  /// and the trailer (capacity checked by the caller); a violation is reported to the assert
  /// hook and writes nothing (no cell counts as sent).
  ///
  /// A cell the free-space stage emptied since the last export (FreeSpace::clear_marked) sends a
  /// clear in the free-space section, before or with its first gain after it: clears are
  /// reserved first, as many as the buffer holds beside the layer headers (written by
  /// write_section); a reserved one empties the cell's sent copy (its gain is then all its points
  /// since) and resets its flags; a cell whose clear did not fit waits with it. Returns the
  /// clears reserved.
  static std::uint32_t write_layers(StackType& stack, SentCells& sent, SnapshotWriter& w, std::size_t capacity,
                                    const ExportOptions& options, ExportReport& report) noexcept {
    CCMAP_ASSERT_OR_RETURN(settled(stack) && w.position() + static_cast<std::size_t>(kLayers) * kDeltaLayerHeaderBytes +
                                                     kDeltaTrailerBytes <= capacity, 0U);
    const StackParams& params = stack.params_;
    // The clears first, as many as the buffer holds beside the layer headers (10 bytes each):
    // those reserved empty their sent copies; a cell whose clear did not fit waits with it.
    std::uint32_t clears = 0U;
    std::uint32_t left_out = 0U;
    if constexpr (kFreeSpace) {
      const std::size_t fixed = w.position() + static_cast<std::size_t>(kLayers) * kDeltaLayerHeaderBytes + kDeltaTrailerBytes;
      const std::size_t room = (capacity - fixed) / kFreeSpaceEntryBytes;
      const std::size_t most = room < kMaxDeltaEntries ? room : kMaxDeltaEntries;
      stack.free_space_.for_each_clear_mark([&](std::uint32_t record) {
        int layer = kLayers - 1;
        while (layer > 0 && record < record_offset(layer)) {
          --layer;
        }
        if (layer < options.finest_layer) {
          return;  // not written: the mark waits with the cell
        }
        if (clears >= most) {
          ++left_out;
          return;
        }
        const std::size_t slot = record - record_offset(layer);
        with_layer(stack, &sent, layer, [&](auto&, auto* copies) {
          using Cell = std::remove_reference_t<decltype(*copies)>;
          copies[slot] = Cell{};
        });
        sent.flags[record] = kClearingBit;  // own and drop-sent reset: the cell starts again
        ++clears;
      });
    }
    const std::size_t entries_reserved = static_cast<std::size_t>(clears) * kFreeSpaceEntryBytes;
    for (int layer = kLayers - 1; layer >= 0; --layer) {
      const bool skipped = layer < options.finest_layer;
      const float width = stack.layers_.widths[layer];
      const std::size_t first = record_offset(layer);
      // Room that must stay free for the headers of the layers still to come and the trailer.
      const std::size_t reserve = static_cast<std::size_t>(layer) * kDeltaLayerHeaderBytes + kDeltaTrailerBytes;
      with_layer(stack, &sent, layer, [&](auto& grid, auto* copies) {
        using Cell = std::remove_reference_t<decltype(*copies)>;
        const std::int32_t side = grid.side();
        const CellIndex min = grid.window_min();
        snapshot_write_centre(w, grid.centre());
        const std::size_t count_at = w.position();
        w.u32(0U);
        std::uint32_t count = 0U;
        std::int64_t previous = -1;
        grid.for_each([&](CellIndex index, const Cell& cell) {
          if (!cell_intact(stack.layers_, cell)) {  // integrity: an upset's cell is not sent (the scrub resets it)
            ++report.cells_pending;
            return;
          }
          const std::size_t slot = grid::buffer_offset(index, side);
          Cell& copy = copies[slot];
          if constexpr (kFreeSpace) {
            if (left_out > 0U && (sent.flags[first + slot] & kClearingBit) == 0U &&
                stack.free_space_.clear_marked(static_cast<std::uint32_t>(first + slot))) {
              ++report.cells_pending;  // its clear did not fit: the cell waits with it
              return;
            }
          }
          Cell gain{};
          const GainKind kind = exchange_gain(cell, copy, params, width, &gain);
          if (kind == GainKind::kNone) {
            return;
          }
          const std::int64_t position = static_cast<std::int64_t>(index.y - min.y) * side + (index.x - min.x);
          const auto skip = static_cast<std::uint32_t>(position - previous - 1);
          const std::size_t bytes = varint_bytes(skip) + sizeof(Cell);
          if (skipped || exchange_weight(gain) < options.weight_floor ||
              w.position() + bytes + reserve + entries_reserved > capacity) {
            ++report.cells_pending;
            return;
          }
          delta_write_varint(w, skip);
          snapshot_write_cell(w, gain);
          copy = cell;
          if constexpr (kFreeSpace) {
            sent.flags[first + slot] |= kOwnBits;  // a gain is this map's own points
          }
          previous = position;
          ++count;
          report.cells_saturated += kind == GainKind::kSaturated ? 1U : 0U;
        });
        patch_u32(w, count_at, count);
        report.cells_written += count;
      });
    }
    return clears;
  }

  /// The free-space section after the core (the writer after the core's CRC placeholder): the
  /// clears write_layers reserved, then the drop-offs not yet sent of cells this map holds no
  /// point in (intact records; a drop-off merged from a team mate is not sent on), as many as
  /// fit (the rest wait: drops_pending). Coarsest layer first. Returns the entries written.
  static std::uint32_t write_section(StackType& stack, SentCells& sent, SnapshotWriter& w, std::size_t capacity,
                                     std::uint32_t clears, std::int32_t finest_layer, ExportReport& report) noexcept {
    std::uint32_t entries = 0U;
    if constexpr (kFreeSpace) {
      std::uint8_t entry[kFreeSpaceEntryBytes] = {};
      const auto put = [&](const FreeSpaceEntry& e) {
        encode_free_space_entry(e, entry);
        for (const std::uint8_t b : entry) {
          w.u8(b);
        }
        ++entries;
      };
      // Storage order (slot by slot): the global index is computed only for an entry written.
      for (int pass = clears > 0U ? 0 : 1; pass < 2; ++pass) {  // 0: the reserved clears, 1: drop-offs
        for (int layer = kLayers - 1; layer >= finest_layer; --layer) {
          const std::size_t first = record_offset(layer);
          const RingGrid<FreeSpaceCell>* record_grid = stack.free_space_.records(layer);
          if (record_grid == nullptr) {
            continue;  // not reached: every layer has its records
          }
          const FreeSpaceCell* records = record_grid->storage();
          with_layer(stack, &sent, layer, [&](auto& grid, auto*) {
            const std::int32_t side = grid.side();
            const CellIndex min = grid.window_min();
            const auto* cells = grid.storage();
            const auto mask = static_cast<std::uint32_t>(side - 1);
            const auto slots = static_cast<std::uint32_t>(side) * static_cast<std::uint32_t>(side);
            const auto index_of = [&](std::uint32_t slot) {
              const std::uint32_t dx = ((slot & mask) - static_cast<std::uint32_t>(min.x)) & mask;
              const std::uint32_t dy = ((slot / static_cast<std::uint32_t>(side)) - static_cast<std::uint32_t>(min.y)) & mask;
              return CellIndex{min.x + static_cast<std::int32_t>(dx), min.y + static_cast<std::int32_t>(dy)};
            };
            const auto position_of = [&](CellIndex index) {
              return static_cast<std::uint32_t>((index.y - min.y) * side + (index.x - min.x));
            };
            for (std::uint32_t slot = 0; slot < slots; ++slot) {
              std::uint8_t& flags = sent.flags[first + slot];
              if (pass == 0) {
                if ((flags & kClearingBit) != 0U) {
                  const CellIndex index = index_of(slot);
                  put(FreeSpaceEntry{FreeSpaceEntryKind::kCleared, static_cast<std::uint8_t>(layer), position_of(index),
                                     0U, 0U});
                  flags = static_cast<std::uint8_t>(flags & ~kClearingBit);
                  stack.free_space_.drop_clear_mark(static_cast<std::uint32_t>(first + slot));
                  ++report.clears_written;
                }
                continue;
              }
              if (!is_drop(records[slot])) {
                continue;  // (the flag of a record that was reset went with it: a clear or a move resets it)
              }
              const auto& cell = cells[slot];
              if ((flags & kDropSentBit) != 0U || cell.weight > 0.0F || distrust_mark(cell)) {
                continue;  // sent, or observed here, or distrusted
              }
              const CellIndex index = index_of(slot);
              FreeSpaceCell rec{};
              if (!stack.free_space_.record_at(layer, index, &rec)) {
                continue;  // an upset's record: the scrub resets it
              }
              if (entries >= kMaxDeltaEntries || w.position() + kFreeSpaceEntryBytes > capacity) {
                ++report.drops_pending;
                continue;
              }
              put(drop_entry_of(rec, layer, position_of(index)));
              flags |= kDropSentBit;
              ++report.drops_written;
            }
          });
        }
      }
    } else {
      (void)stack;
      (void)sent;
      (void)w;
      (void)capacity;
      (void)clears;
      (void)finest_layer;
      (void)report;
    }
    return entries;
  }

  /// Pass 1 (commit == false: reads, merges into copies only, returns the first refusal) or
  /// pass 2 (commit: merges into the map and the sent copies) over the cells of a delta whose
  /// header validated; r is positioned after the header. offset: sender origin - this origin,
  /// finest cells, a multiple of the coarsest layer's factor.
  /// centres (may be nullptr): the sender's window centre of each layer, as read.
  [[nodiscard]] static Status merge_delta_cells(StackType& stack, SentCells* sent, SnapshotReader& r,
                                                std::int64_t offset_x, std::int64_t offset_y, float dz_m, bool commit,
                                                MergeReport& report, CellIndex* centres = nullptr,
                                                bool clears = false) noexcept {
    const StackParams& params = stack.params_;
    Status status = Status::kOk;
    for (int layer = kLayers - 1; layer >= 0 && status == Status::kOk; --layer) {
      const float width = stack.layers_.widths[layer];
      const KeptWindow& kept = stack.layers_.kept[layer];
      with_layer(stack, sent, layer, [&](auto& grid, auto* copies) {
        using Cell = std::remove_reference_t<decltype(grid.cell_unchecked(CellIndex{}))>;
        const std::int32_t side = grid.side();
        CellIndex centre{};
        if (!snapshot_read_centre(r, &centre)) {
          status = Status::kCorrupt;
          return;
        }
        if (centres != nullptr) {
          centres[layer] = centre;
        }
        const std::uint32_t count = r.u32();
        const std::uint64_t cells = static_cast<std::uint64_t>(side) * static_cast<std::uint64_t>(side);
        if (!r.ok() || count > cells) {
          status = Status::kCorrupt;
          return;
        }
        const std::int64_t min_x = static_cast<std::int64_t>(centre.x) - side / 2;
        const std::int64_t min_y = static_cast<std::int64_t>(centre.y) - side / 2;
        std::uint64_t position = 0U;
        for (std::uint32_t i = 0; i < count; ++i) {
          std::uint32_t skip = 0U;
          Cell received{};
          if (!delta_read_varint(r, &skip) || !snapshot_read_cell(r, &received) ||
              !exchange_cell_valid(received, width)) {
            status = Status::kCorrupt;
            return;
          }
          position += skip;
          if (position >= cells) {
            status = Status::kCorrupt;
            return;
          }
          const std::int64_t x = min_x + static_cast<std::int64_t>(position % static_cast<std::uint64_t>(side));
          const std::int64_t y = min_y + static_cast<std::int64_t>(position / static_cast<std::uint64_t>(side));
          ++position;
          status = merge_one(stack.layers_, grid, copies, kept, x + (offset_x >> layer), y + (offset_y >> layer),
                             received, dz_m, params, width, commit, report, clears);
          if (status != Status::kOk) {
            return;
          }
        }
      });
    }
    return status;
  }

  /// Pass 1 or 2 over the cells of a snapshot that SnapshotAccess<Config>::validate accepted.
  [[nodiscard]] static Status merge_snapshot_cells(StackType& stack, SentCells* sent, const std::uint8_t* data,
                                                   std::size_t size, std::size_t layers_begin, std::int64_t offset_x,
                                                   std::int64_t offset_y, float dz_m, bool commit,
                                                   MergeReport& report) noexcept {
    const StackParams& params = stack.params_;
    Status status = Status::kOk;
    SnapshotAccess<Config>::for_each_stored_cell(data, size, layers_begin, [&](int layer, CellIndex index, const auto& cell) {
      if (status != Status::kOk || !(cell.weight > 0.0F)) {
        return;
      }
      const float width = stack.layers_.widths[layer];
      const KeptWindow& kept = stack.layers_.kept[layer];
      with_layer(stack, sent, layer, [&](auto& grid, auto* copies) {
        using Cell = std::remove_reference_t<decltype(grid.cell_unchecked(CellIndex{}))>;
        using Stored = std::remove_cv_t<std::remove_reference_t<decltype(cell)>>;
        if constexpr (std::is_same_v<Cell, Stored>) {
          if (!exchange_cell_valid(cell, width)) {
            status = Status::kCorrupt;
            return;
          }
          status = merge_one(stack.layers_, grid, copies, kept, static_cast<std::int64_t>(index.x) + (offset_x >> layer),
                             static_cast<std::int64_t>(index.y) + (offset_y >> layer), cell, dz_m, params, width,
                             commit, report, false);
        }
      });
    });
    return status;
  }

  /// True if an entry of the section may be a clear (its kind field, unchecked: a damaged entry
  /// may only make this true, the safe side).
  [[nodiscard]] static bool may_clear(const std::uint8_t* section, std::size_t available, std::uint32_t announced) noexcept {
    const std::size_t present = available / kFreeSpaceEntryBytes;
    const std::size_t n = present < announced ? present : announced;
    bool any = false;
    for (std::size_t i = 0; i < n; ++i) {
      any = any || (section[i * kFreeSpaceEntryBytes + 3U] >> 4U) == static_cast<std::uint8_t>(FreeSpaceEntryKind::kCleared);
    }
    return any;
  }

  /// The free-space section of a delta whose core merged checks (pass 1 accepted it): entries
  /// [0, announced) of 10 bytes from `section` (`available` bytes). Pass 0 applies the clears
  /// (before the cells commit: a gain sent after a clear is new ground), pass 1 the drop-offs
  /// (after: a cell the delta fills is observed) and counts what was refused. centres: the
  /// sender's window centres; offset: sender - this map (finest cells); dz_m: heights.
  ///
  /// A team mate's clear empties this map's cell (and its sent copy and record: never sent on)
  /// when the cell holds no point of this map's own (kOwnBits clear and the cell equal to its
  /// sent copy: everything in it came from team mates, whose data the sender's lines of sight
  /// overruled as its own), or when this map's own lines of sight contradicted it too (its
  /// intact record's evidence >= 1: at least one frame since its surface was last confirmed).
  /// Otherwise the cell stays, and its evidence is raised to free_space_clear_frames - 1: one
  /// frame of this map's own contradicting rays then empties it, and a point of its own on the
  /// surface (a confirmation) forgets it. A distrusted or upset cell is left to the scrub.
  static void merge_section(StackType& stack, SentCells* sent, int pass, const std::uint8_t* section,
                            std::size_t available, std::uint32_t announced, const CellIndex* centres,
                            std::int64_t offset_x, std::int64_t offset_y, float dz_m, MergeReport& report) noexcept {
    const std::size_t present = available / kFreeSpaceEntryBytes;
    const std::uint32_t n = present < announced ? static_cast<std::uint32_t>(present) : announced;
    for (std::uint32_t i = 0; i < n; ++i) {
      FreeSpaceEntry e{};
      const bool valid = decode_free_space_entry(section + static_cast<std::size_t>(i) * kFreeSpaceEntryBytes, &e) &&
                         e.layer < kLayers &&
                         e.position < static_cast<std::uint32_t>(Layers::capacity(e.layer));
      if (!valid) {
        report.entries_refused += pass == 1 ? 1U : 0U;
        continue;
      }
      const bool clear = e.kind == FreeSpaceEntryKind::kCleared;
      if (clear != (pass == 0)) {
        continue;
      }
      const int layer = e.layer;
      const std::int32_t side = Layers::side(layer);
      const std::int64_t x = static_cast<std::int64_t>(centres[layer].x) - side / 2 +
                             static_cast<std::int64_t>(e.position % static_cast<std::uint32_t>(side)) + (offset_x >> layer);
      const std::int64_t y = static_cast<std::int64_t>(centres[layer].y) - side / 2 +
                             static_cast<std::int64_t>(e.position / static_cast<std::uint32_t>(side)) + (offset_y >> layer);
      constexpr std::int64_t kLimit = grid::kMaxCellIndex;
      const std::size_t first = record_offset(layer);
      with_layer(stack, sent, layer, [&](auto& grid, auto* copies) {
        using Cell = std::remove_reference_t<decltype(grid.cell_unchecked(CellIndex{}))>;
        const CellIndex index{static_cast<std::int32_t>(x >= -kLimit && x <= kLimit ? x : 0),
                              static_cast<std::int32_t>(y >= -kLimit && y <= kLimit ? y : 0)};
        if (x < -kLimit || x > kLimit || y < -kLimit || y > kLimit || !grid.contains(index)) {
          ++report.entries_outside;
          return;
        }
        const std::size_t slot = grid::buffer_offset(index, side);
        Cell& cell = grid.cell_unchecked(index);
        if (!(cell.weight > 0.0F) || !cell_intact(stack.layers_, cell)) {
          if (!clear && !distrust_mark(cell) && cell_intact(stack.layers_, cell)) {
            stack.free_space_.merge_drop_at(layer, index, e.bound_code != 0U ? bound_m(FreeSpaceCell{e.bound_code, 0U, 0U}) + dz_m
                                                                           : std::numeric_limits<float>::quiet_NaN(),
                                            e.drop_rays);
            if constexpr (kFreeSpace) {
              if (sent != nullptr) {
                sent->flags[first + slot] |= kDropSentBit;  // not sent on
              }
            }
            ++report.drops_merged;
          }
          return;  // a clear of an empty, distrusted or upset cell: nothing to empty
        }
        if (!clear) {
          return;  // observed here: this map's points answer, not a team mate's bound
        }
        bool own = copies != nullptr && !same_cell_bits(cell, copies[slot]);
        if constexpr (kFreeSpace) {
          own = own || (sent != nullptr && (sent->flags[first + slot] & kOwnBits) != 0U);
        }
        FreeSpaceCell rec{};
        const bool agrees = stack.free_space_.record_at(layer, index, &rec) && rec.evidence >= 1U;
        if (own && !agrees) {
          const std::uint32_t frames = stack.free_space_.clear_frames();
          stack.free_space_.raise_evidence_at(layer, index, frames > 1U ? frames - 1U : 0U);
          ++report.clears_deferred;
          return;
        }
        write_cell(stack.layers_, cell, [](Cell& written) { written = Cell{}; });  // the check follows
        if (copies != nullptr) {
          copies[slot] = Cell{};
        }
        if constexpr (kFreeSpace) {
          if (sent != nullptr) {
            sent->flags[first + slot] = 0U;
          }
        }
        stack.free_space_.reset_record_at(layer, index);
        ++report.cells_cleared;
      });
    }
    if (pass == 1) {
      report.entries_refused += announced - n;  // announced, not there (truncated)
      const bool whole = available == static_cast<std::size_t>(announced) * kFreeSpaceEntryBytes;
      report.free_space_status = whole && report.entries_refused == 0U ? Status::kOk : Status::kCorrupt;
    }
  }

 private:
  /// True if two cells have the same bits: a cell is changed since it was sent if any bit is
  /// (so +0 and -0 differ and a NaN equals its own bits, which a value comparison would not say).
  /// A cell is packed floats, no padding (each cell type asserts its size as its floats:
  /// cell/ccm_cell.hpp, cell/constant_cell.hpp), so no padding byte takes part in the comparison.
  template <typename Cell>
  [[nodiscard]] static bool same_cell_bits(const Cell& a, const Cell& b) noexcept {
    // NOLINTNEXTLINE(bugprone-suspicious-memory-comparison,cert-exp42-c,cert-flp37-c): the bits are what is compared (see above)
    return std::memcmp(&a, &b, sizeof(Cell)) == 0;
  }

  static void patch_u32(SnapshotWriter& w, std::size_t at, std::uint32_t v) noexcept {
    for (unsigned byte = 0U; byte < 4U; ++byte) {
      w.data()[at + byte] = static_cast<std::uint8_t>((v >> (8U * byte)) & 0xFFU);
    }
  }

  /// One received cell at this map's global index (x, y) of a layer. A sent copy outside the
  /// layer's KeptWindow counts as empty (what settle() makes it before the commit pass), so the
  /// validation pass computes exactly what the commit pass writes. clears: the delta may empty
  /// cells before the commit (merge_section), so the validation also merges into an empty cell.
  template <typename Grid, typename Cell>
  [[nodiscard]] static Status merge_one(Layers& layers, Grid& grid, Cell* copies, const KeptWindow& kept, std::int64_t x,
                                        std::int64_t y, const Cell& received, float dz_m, const StackParams& params,
                                        float width, bool commit, MergeReport& report, bool clears) noexcept {
    constexpr std::int64_t kLimit = grid::kMaxCellIndex;
    const bool representable = x >= -kLimit && x <= kLimit && y >= -kLimit && y <= kLimit;
    const CellIndex index{static_cast<std::int32_t>(representable ? x : 0), static_cast<std::int32_t>(representable ? y : 0)};
    if (!representable || !grid.contains(index)) {
      report.cells_outside += commit ? 1U : 0U;
      return Status::kOk;
    }
    Cell& cell = grid.cell_unchecked(index);
    Cell merged = cell;
    if (!exchange_merge(merged, received, dz_m, params, width)) {
      return Status::kOutOfRange;
    }
    Cell* copy = copies != nullptr ? &copies[grid::buffer_offset(index, grid.side())] : nullptr;
    Cell merged_copy = (copy != nullptr && kept.contains(index)) ? *copy : Cell{};
    // A team mate's clear (merge_section) may empty the cell and its copy before the commit:
    // the received cell must merge into an empty one too, so the commit cannot fail after it.
    Cell alone{};
    if (clears && !commit && !exchange_merge(alone, received, dz_m, params, width)) {
      return Status::kOutOfRange;
    }
    if (copy != nullptr && !exchange_merge(merged_copy, received, dz_m, params, width)) {
      return Status::kOutOfRange;
    }
    if (commit) {
      write_cell(layers, cell, [&](Cell& written) { written = merged; });  // the check follows
      if (copy != nullptr) {
        *copy = merged_copy;
      }
      ++report.cells_merged;
    }
    return Status::kOk;
  }
};

}  // namespace detail

/// Peer-to-peer port of one Stack<Config>: exports its gains, merges other rovers' deltas and
/// snapshots. Holds one copy of the stack's cells (what was last sent: sizes in
/// docs/integration.md), the peer table (kMaxPeers senders) and counters; place it in static
/// storage like the stack. Two-phase: init() binds it to a stack.
template <typename Config, std::size_t kMaxPeers = 8>
class MapExchange {
  using Access = detail::ExchangeAccess<Config>;

 public:
  static_assert(kMaxPeers >= 1U && kMaxPeers <= 255U, "1..255 peers");
  using StackType = Stack<Config>;
  static constexpr int kLayerCount = StackType::kLayerCount;
  /// Bytes of one CCM cell on the wire (40 full cell, 36 paper cell).
  static constexpr std::size_t kCcmCellBytes = detail::kSnapshotCcmCellBytes<typename StackType::CcmCellType>;

  MapExchange() noexcept = default;
  MapExchange(const MapExchange&) = delete;
  MapExchange& operator=(const MapExchange&) = delete;
  MapExchange(MapExchange&&) = delete;
  MapExchange& operator=(MapExchange&&) = delete;
  ~MapExchange() = default;

  /// Largest delta of this configuration (every cell of every layer) and the smallest (no cell).
  [[nodiscard]] static constexpr std::size_t max_delta_size() noexcept {
    // Every cell written: each gap is 0, one varint byte per cell. Leaving a cell out saves its
    // 13, 37 or 41 bytes and lengthens one gap's varint by less than a byte per skipped position
    // (a varint grows by a byte per factor 128), so no subset is larger.
    // Free-space entries: a written cell holds points, so it is no drop-off: at most its clear
    // (10 bytes) beside it; a cell not written at most a clear and a drop-off (20 bytes, less
    // than a written cell and its clear). So at most 10 bytes per cell more, and at most
    // kMaxDeltaEntries entries.
    std::size_t total = min_delta_size();
    std::size_t cells = 0U;
    for (int layer = 0; layer < kLayerCount; ++layer) {
      const std::size_t cell_bytes =
          StackType::layer_is_ccm(layer) ? kCcmCellBytes : detail::kSnapshotFineCellBytes;
      total += StackType::layer_capacity(layer) * (cell_bytes + 1U);
      cells += StackType::layer_capacity(layer);
    }
    if (Access::kFreeSpace) {
      const std::size_t entries = cells < detail::kMaxDeltaEntries ? cells : detail::kMaxDeltaEntries;
      total += entries * detail::kFreeSpaceEntryBytes;
    }
    return total;
  }
  [[nodiscard]] static constexpr std::size_t min_delta_size() noexcept {
    return detail::kDeltaHeaderBytes + static_cast<std::size_t>(kLayerCount) * detail::kDeltaLayerHeaderBytes +
           detail::kDeltaTrailerBytes;
  }

  /// Binds the exchange to `stack` (initialised) and starts afresh: nothing counts as sent (the
  /// first export sends the whole map), no peer is known, counters are zero. Retires any other
  /// exchange bound to the stack. kNotInitialised: stack not initialised. kInvalidArgument:
  /// a non-finite origin height or one beyond kMaxAbsCoordinateM, an origin beyond
  /// +-grid::kMaxCellIndex.
  [[nodiscard]] Status init(StackType& stack, const ExchangeParams& params) noexcept {
    const Status state = stack.verify_state();  // integrity: kNotInitialised or kCorrupt
    if (state != Status::kOk) {
      return state;
    }
    if (!std::isfinite(params.origin_z_m) || std::fabs(params.origin_z_m) > kMaxAbsCoordinateM ||
        params.origin_cells.x < -grid::kMaxCellIndex || params.origin_cells.x > grid::kMaxCellIndex ||
        params.origin_cells.y < -grid::kMaxCellIndex || params.origin_cells.y > grid::kMaxCellIndex) {
      return Status::kInvalidArgument;
    }
    stack_ = &stack;
    generation_ = Access::next_generation(stack);
    params_ = params;
    sequence_ = 0U;
    frames_at_export_ = stack.accepted_frames();
    for (detail::PeerRecord& p : peers_) {
      p = detail::PeerRecord{};
    }
    counters_ = ExchangeCounters{};
    Access::clear(sent_);  // in place: a temporary would put the whole copy on the call stack
    Access::drop_all_marks(stack);
    Access::settle(stack, sent_);
    return Status::kOk;
  }

  /// True while bound to a stack that has not been re-initialised since.
  [[nodiscard]] bool initialised() const noexcept {
    return stack_ != nullptr && stack_->initialised() && Access::generation(*stack_) == generation_;
  }

  /// Writes a delta of the gains since the last export into buffer[0..*written) and counts them
  /// as sent. Writes as many changed cells as fit (coarsest layer first); the rest, and cells
  /// below options.weight_floor, stay pending. Always writes a delta (possibly without cells)
  /// and takes the next sequence number. kNotInitialised; kInvalidArgument: null buffer or
  /// written, a bad floor; kBufferTooSmall: capacity < min_delta_size() (nothing changes).
  [[nodiscard]] Status export_delta(std::uint8_t* buffer, std::size_t capacity, const ExportOptions& options,
                                    std::size_t* written, ExportReport* report) noexcept {
    if (written != nullptr) {
      *written = 0U;
    }
    ExportReport r{};
    if (report != nullptr) {
      *report = r;
    }
    if (!initialised()) {
      return Status::kNotInitialised;
    }
    const Status state = stack_->verify_state();  // integrity
    if (state != Status::kOk) {
      return state;
    }
    if (buffer == nullptr || written == nullptr || !(options.weight_floor >= 0.0F) || options.finest_layer < 0 ||
        options.finest_layer >= kLayerCount) {
      return Status::kInvalidArgument;
    }
    if (capacity < min_delta_size()) {
      return Status::kBufferTooSmall;
    }
    Access::settle(*stack_, sent_);
    const StackParams& params = Access::params(*stack_);
    detail::SnapshotWriter w(buffer, capacity);
    r.sequence = sequence_ + 1U;
    const detail::DeltaSender sender{params.finest_cell_width_m, params_.rover_id, params_.session, r.sequence,
                                     frames_at_export_, stack_->accepted_frames(), params_.origin_cells,
                                     params_.origin_z_m, 0U, 0U};
    detail::delta_write_header(w, detail::SnapshotAccess<Config>::fingerprint(), sender);
    const std::uint32_t clears = Access::write_layers(*stack_, sent_, w, capacity, options, r);
    const std::size_t core_end = w.position();
    w.u32(0U);  // the core's CRC, written by delta_finish
    const std::uint32_t entries = Access::write_section(*stack_, sent_, w, capacity, clears, options.finest_layer, r);
    detail::delta_finish(w, core_end, entries);
    sequence_ = r.sequence;
    frames_at_export_ = stack_->accepted_frames();
    r.bytes = w.position();
    *written = w.position();
    ++counters_.deltas_exported;
    counters_.bytes_exported += w.position();
    counters_.cells_exported += r.cells_written;
    counters_.drops_exported += r.drops_written;
    counters_.clears_exported += r.clears_written;
    if (report != nullptr) {
      *report = r;
    }
    return Status::kOk;
  }

  /// Folds another rover's delta into the map (and into the sent copies, so that it is never
  /// sent on). The core all-or-nothing, the free-space entries one by one: see the statuses in
  /// the file comment. report may be nullptr.
  [[nodiscard]] Status merge_delta(const std::uint8_t* data, std::size_t size, MergeReport* report) noexcept {
    MergeReport r{};
    const Status status = merge_delta_impl(data, size, r);
    return finish_merge(status, r, report, size, false);
  }

  /// Folds a snapshot of another map (save_snapshot) into this map, with the origin offset
  /// (sender - this map, finest cells; z in metres) given by the caller. A snapshot is a whole
  /// map: merge one only of a map that holds nothing of this one (built independently, no deltas
  /// exchanged), or its points count twice. All-or-nothing (see the file comment).
  [[nodiscard]] Status merge_snapshot(const std::uint8_t* data, std::size_t size, CellIndex offset_cells,
                                      float offset_z_m, MergeReport* report) noexcept {
    MergeReport r{};
    Status status = initialised() ? Status::kOk : Status::kNotInitialised;
    if (status == Status::kOk) {
      status = Access::merge_snapshot(*stack_, &sent_, data, size, offset_cells, offset_z_m, r);
    }
    return finish_merge(status, r, report, size, true);
  }

  /// The header of a delta whose envelope (magic, version, size, CRC) and preset are intact.
  [[nodiscard]] static Status peek_delta(const std::uint8_t* data, std::size_t size, DeltaInfo* info) noexcept {
    if (data == nullptr || info == nullptr) {
      return Status::kInvalidArgument;
    }
    detail::SnapshotReader r(data, 0U);
    detail::DeltaSender sender{};
    const Status status =
        detail::delta_read_header(data, size, detail::SnapshotAccess<Config>::fingerprint(), r, &sender);
    if (status != Status::kOk) {
      return status;
    }
    std::uint32_t cells = 0U;
    for (int layer = 0; layer < kLayerCount && r.ok(); ++layer) {
      (void)r.u32();
      (void)r.u32();
      const std::uint32_t n = r.u32();
      cells += n;
      for (std::uint32_t i = 0; i < n && r.ok(); ++i) {
        std::uint32_t skip = 0U;
        (void)detail::delta_read_varint(r, &skip);
        // The cell bytes of the layer written (layers run coarsest first).
        const int stack_layer = kLayerCount - 1 - layer;
        r.seek(r.position() + (StackType::layer_is_ccm(stack_layer) ? kCcmCellBytes
                                                                    : detail::kSnapshotFineCellBytes));
      }
    }
    if (!r.ok()) {
      return Status::kCorrupt;
    }
    *info = DeltaInfo{sender.rover_id,   sender.session,    sender.sequence,
                      sender.frames_from, sender.frames_to, sender.origin_cells,
                      sender.origin_z_m, sender.finest_cell_width_m, cells,
                      sender.entries};
    return Status::kOk;
  }

  [[nodiscard]] const ExchangeCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const ExchangeParams& params() const noexcept { return params_; }
  /// Sequence number of the last export (0 before the first).
  [[nodiscard]] std::uint32_t sequence() const noexcept { return sequence_; }

 private:
  [[nodiscard]] Status merge_delta_impl(const std::uint8_t* data, std::size_t size, MergeReport& r) noexcept {
    if (!initialised()) {
      return Status::kNotInitialised;
    }
    const Status state = stack_->verify_state();  // integrity
    if (state != Status::kOk) {
      return state;
    }
    if (data == nullptr) {
      return Status::kInvalidArgument;
    }
    detail::SnapshotReader reader(data, 0U);
    detail::DeltaSender sender{};
    Status status = detail::delta_read_header(data, size, detail::SnapshotAccess<Config>::fingerprint(), reader, &sender);
    if (status != Status::kOk) {
      return status;
    }
    const StackParams& params = Access::params(*stack_);
    std::int64_t offset_x = 0;
    std::int64_t offset_y = 0;
    if (!detail::same_float_bits(sender.finest_cell_width_m, params.finest_cell_width_m) ||
        detail::exchange_offset(sender.origin_cells, params_.origin_cells, kLayerCount, &offset_x, &offset_y) !=
            Status::kOk) {
      return Status::kMisaligned;
    }
    r.sender_id = sender.rover_id;
    r.sequence = sender.sequence;
    std::size_t slot = 0U;
    status = check_sender(sender, &slot, &r.deltas_missed);
    if (status != Status::kOk) {
      return status;
    }
    const float dz = sender.origin_z_m - params_.origin_z_m;
    const std::size_t cells_begin = reader.position();
    CellIndex centres[StackType::kLayerCount]{};
    const std::uint8_t* section = data + sender.core_size;
    const std::size_t available = size - sender.core_size;
    const bool clears = Access::may_clear(section, available, sender.entries);
    status = Access::merge_delta_cells(*stack_, &sent_, reader, offset_x, offset_y, dz, false, r, centres, clears);
    if (status == Status::kOk && (!reader.ok() || reader.position() != sender.core_size - detail::kDeltaTrailerBytes)) {
      status = Status::kCorrupt;
    }
    if (status != Status::kOk) {
      return status;
    }
    Access::settle(*stack_, sent_);  // after validation: a refused delta changes nothing at all
    // The free-space section: entries checked one by one, a bad one refused alone (MergeReport).
    Access::merge_section(*stack_, &sent_, 0, section, available, sender.entries, centres, offset_x, offset_y, dz, r);
    reader.seek(cells_begin);
    (void)Access::merge_delta_cells(*stack_, &sent_, reader, offset_x, offset_y, dz, true, r);
    Access::merge_section(*stack_, &sent_, 1, section, available, sender.entries, centres, offset_x, offset_y, dz, r);
    peers_[slot] = detail::PeerRecord{sender.rover_id, sender.session, sender.sequence, 1U};
    return Status::kOk;
  }

  /// Dedupe: kDuplicate for this rover's own delta, an older session, or a sequence already
  /// merged; kBufferTooSmall for a new sender with a full table. *slot: the table entry to write.
  [[nodiscard]] Status check_sender(const detail::DeltaSender& sender, std::size_t* slot,
                                    std::uint32_t* missed) const noexcept {
    if (sender.rover_id == params_.rover_id) {
      return Status::kDuplicate;
    }
    std::size_t free_slot = kMaxPeers;
    for (std::size_t i = 0; i < kMaxPeers; ++i) {
      const detail::PeerRecord& p = peers_[i];
      if (p.used == 0U) {
        free_slot = free_slot == kMaxPeers ? i : free_slot;
        continue;
      }
      if (p.rover_id != sender.rover_id) {
        continue;
      }
      *slot = i;
      if (sender.session > p.session) {
        *missed = sender.sequence > 1U ? sender.sequence - 1U : 0U;
        return Status::kOk;
      }
      if (sender.session < p.session || sender.sequence <= p.last_sequence) {
        return Status::kDuplicate;
      }
      *missed = sender.sequence - p.last_sequence - 1U;
      return Status::kOk;
    }
    if (free_slot == kMaxPeers) {
      return Status::kBufferTooSmall;
    }
    *slot = free_slot;
    *missed = sender.sequence > 1U ? sender.sequence - 1U : 0U;
    return Status::kOk;
  }

  [[nodiscard]] Status finish_merge(Status status, const MergeReport& r, MergeReport* report, std::size_t size,
                                    bool snapshot) noexcept {
    if (status == Status::kOk) {
      if (snapshot) {
        ++counters_.snapshots_merged;
      } else {
        ++counters_.deltas_merged;
        counters_.deltas_missed += r.deltas_missed;
      }
      counters_.bytes_merged += size;
      counters_.cells_merged += r.cells_merged;
      counters_.cells_outside += r.cells_outside;
      counters_.drops_merged += r.drops_merged;
      counters_.cells_cleared += r.cells_cleared;
      counters_.clears_deferred += r.clears_deferred;
      counters_.entries_refused += r.entries_refused;
      counters_.sections_damaged += r.free_space_status != Status::kOk ? 1U : 0U;
    } else if (status != Status::kNotInitialised) {
      ++counters_.refused;
      counters_.refused_corrupt += status == Status::kCorrupt ? 1U : 0U;
      counters_.refused_duplicate += status == Status::kDuplicate ? 1U : 0U;
      counters_.refused_misaligned += status == Status::kMisaligned ? 1U : 0U;
    }
    if (report != nullptr) {
      *report = status == Status::kOk ? r : MergeReport{};
    }
    return status;
  }

  // ---- state: zero-initialised (static storage: .bss) ----
  StackType* stack_ = nullptr;
  std::uint32_t generation_ = 0U;
  ExchangeParams params_{};
  std::uint32_t sequence_ = 0U;
  std::uint32_t frames_at_export_ = 0U;
  detail::PeerRecord peers_[kMaxPeers]{};
  ExchangeCounters counters_{};
  typename Access::SentCells sent_{};
};

/// Folds a snapshot of another map into `stack` (no exchange: e.g. merging saved maps on the
/// ground). offset_cells: the snapshot map's origin minus this map's, in finest cells (a
/// multiple of the coarsest layer's cells); offset_z_m likewise in metres. The same rules and
/// statuses as MapExchange::merge_snapshot; report may be nullptr.
template <typename Config>
[[nodiscard]] Status merge_snapshot(Stack<Config>& stack, const std::uint8_t* data, std::size_t size,
                                    CellIndex offset_cells, float offset_z_m, MergeReport* report) noexcept {
  MergeReport r{};
  const Status status =
      detail::ExchangeAccess<Config>::merge_snapshot(stack, nullptr, data, size, offset_cells, offset_z_m, r);
  if (report != nullptr) {
    *report = status == Status::kOk ? r : MergeReport{};
  }
  return status;
}

}  // namespace ccmap
