// Non-template parts of map exchange (include/ccmap/persistence/exchange.hpp): the per-cell gain and
// merge rules of each cell kind, the varint and the delta header.
#include "ccmap/persistence/exchange.hpp"

#include <cmath>
#include <cstring>
#include <initializer_list>

namespace ccmap::detail {

namespace {

constexpr std::uint8_t kDeltaMagic[4] = {0x43U, 0x43U, 0x4DU, 0x44U};  // "CCMD"
constexpr std::size_t kDeltaEntriesAt = 6U;  // version 3: free-space entries (version 2: reserved 0)
constexpr std::size_t kDeltaSizeAt = 8U;     // version 3: the core's size (version 2: the delta's)

/// True if two cells (packed floats) have the same bits: a cell is unchanged since it was sent.
template <typename Cell>
bool same_bits(const Cell& a, const Cell& b) noexcept {
  static_assert(sizeof(Cell) % sizeof(std::uint32_t) == 0U, "cells are packed floats");
  constexpr std::size_t kWords = sizeof(Cell) / sizeof(std::uint32_t);
  std::uint32_t wa[kWords] = {};
  std::uint32_t wb[kWords] = {};
  std::memcpy(wa, &a, sizeof(Cell));
  std::memcpy(wb, &b, sizeof(Cell));
  bool same = true;
  for (std::size_t i = 0; i < kWords; ++i) {
    same = same && wa[i] == wb[i];
  }
  return same;
}

bool finite_all(std::initializer_list<float> values) noexcept {
  bool finite = true;
  for (const float v : values) {
    finite = finite && std::isfinite(v);
  }
  return finite;
}

bool height_in_range(float z) noexcept { return std::fabs(z) <= kMaxAbsCoordinateM; }

/// The gain of a weight-limited cell (CCM, OMG): the whole cell once the limiter has acted on it
/// (W = W_l: no gain is defined, exchange.hpp), else the unmerge of its sent copy; kNone if that
/// is refused (the weight did not grow in float: pending until it does) or not a valid cell.
template <typename Cell>
GainKind limited_gain(const Cell& cell, const Cell& sent, float weight_limit, float cell_width_m, Cell* gain,
                      Status (*unmerge)(const Cell&, const Cell&, Cell*) noexcept) noexcept {
  if (same_bits(cell, sent) || !(cell.weight > 0.0F)) {
    return GainKind::kNone;
  }
  GainKind kind = GainKind::kGain;
  if (cell.weight >= weight_limit) {
    *gain = cell;
    kind = GainKind::kSaturated;
  } else if (unmerge(cell, sent, gain) != Status::kOk) {
    return GainKind::kNone;
  }
  return exchange_cell_valid(*gain, cell_width_m) ? kind : GainKind::kNone;
}

}  // namespace

// ---- CCM cells (both kinds: one template each, s_xy compiled in for CcmCell) ----
namespace {
template <typename Cell>
bool ccm_cell_valid(const Cell& c, float cell_width_m) noexcept {
  bool valid = finite_all({c.weight, c.mean_x, c.mean_y, c.mean_z, c.s_xx, c.s_yy, c.s_zz, c.s_xz, c.s_yz}) &&
               c.weight > 0.0F && c.s_xx >= 0.0F && c.s_yy >= 0.0F && c.s_zz >= 0.0F &&
               std::fabs(c.mean_x) <= cell_width_m && std::fabs(c.mean_y) <= cell_width_m && height_in_range(c.mean_z);
  if constexpr (kHasLateralCovariance<Cell>) {
    valid = valid && std::isfinite(c.s_xy);  // an off-diagonal co-moment, as s_xz and s_yz
  }
  return valid;
}

template <typename Cell>
bool ccm_exchange_merge(Cell& cell, const Cell& received, float dz_m, const StackParams& params,
                        float cell_width_m) noexcept {
  Cell shifted = received;
  shifted.mean_z += dz_m;  // same cell centre (aligned grids): only heights change frame
  return ccm_merge(cell, shifted, params.weight_limit) == Status::kOk && exchange_cell_valid(cell, cell_width_m);
}
}  // namespace

GainKind exchange_gain(const CcmCell& cell, const CcmCell& sent, const StackParams& params, float cell_width_m,
                       CcmCell* gain) noexcept {
  return limited_gain<CcmCell>(cell, sent, params.weight_limit, cell_width_m, gain, &ccm_unmerge);
}
GainKind exchange_gain(const CcmPaperCell& cell, const CcmPaperCell& sent, const StackParams& params,
                       float cell_width_m, CcmPaperCell* gain) noexcept {
  return limited_gain<CcmPaperCell>(cell, sent, params.weight_limit, cell_width_m, gain, &ccm_unmerge);
}

float exchange_weight(const CcmCell& c) noexcept { return c.weight; }
float exchange_weight(const CcmPaperCell& c) noexcept { return c.weight; }

bool exchange_cell_valid(const CcmCell& c, float cell_width_m) noexcept { return ccm_cell_valid(c, cell_width_m); }
bool exchange_cell_valid(const CcmPaperCell& c, float cell_width_m) noexcept {
  return ccm_cell_valid(c, cell_width_m);
}

bool exchange_merge(CcmCell& cell, const CcmCell& received, float dz_m, const StackParams& params,
                    float cell_width_m) noexcept {
  return ccm_exchange_merge(cell, received, dz_m, params, cell_width_m);
}
bool exchange_merge(CcmPaperCell& cell, const CcmPaperCell& received, float dz_m, const StackParams& params,
                    float cell_width_m) noexcept {
  return ccm_exchange_merge(cell, received, dz_m, params, cell_width_m);
}

// ---- Kalman cells ----
GainKind exchange_gain(const KalmanCell& cell, const KalmanCell& sent, const StackParams& params, float cell_width_m,
                       KalmanCell* gain) noexcept {
  if (same_bits(cell, sent) || !(cell.weight > 0.0F)) {
    return GainKind::kNone;
  }
  GainKind kind = GainKind::kGain;
  if (cell.variance <= params.kalman_min_variance) {
    // The floor has acted: send the estimate whole, with only the new measurement count.
    *gain = KalmanCell{cell.height, cell.variance, cell.weight - sent.weight};
    kind = GainKind::kSaturated;
  } else if (kalman_unmerge(cell, sent, gain) != Status::kOk) {
    return GainKind::kNone;
  }
  return exchange_cell_valid(*gain, cell_width_m) ? kind : GainKind::kNone;
}

float exchange_weight(const KalmanCell& c) noexcept { return c.weight; }

bool exchange_cell_valid(const KalmanCell& c, float /*cell_width_m*/) noexcept {
  return finite_all({c.height, c.variance, c.weight}) && c.weight > 0.0F && c.variance > 0.0F &&
         height_in_range(c.height);
}

bool exchange_merge(KalmanCell& cell, const KalmanCell& received, float dz_m, const StackParams& params,
                    float cell_width_m) noexcept {
  KalmanCell shifted = received;
  shifted.height += dz_m;
  return kalman_merge(cell, shifted, params.kalman_min_variance) == Status::kOk &&
         exchange_cell_valid(cell, cell_width_m);
}

// ---- OMG cells ----
GainKind exchange_gain(const OmgCell& cell, const OmgCell& sent, const StackParams& params, float cell_width_m,
                       OmgCell* gain) noexcept {
  return limited_gain(cell, sent, params.weight_limit, cell_width_m, gain, &omg_unmerge);
}

float exchange_weight(const OmgCell& c) noexcept { return c.weight; }

bool exchange_cell_valid(const OmgCell& c, float /*cell_width_m*/) noexcept {
  return finite_all({c.weight, c.height, c.s}) && c.weight > 0.0F && c.s >= 0.0F && height_in_range(c.height);
}

bool exchange_merge(OmgCell& cell, const OmgCell& received, float dz_m, const StackParams& params,
                    float cell_width_m) noexcept {
  OmgCell shifted = received;
  shifted.height += dz_m;
  return omg_merge(cell, shifted, params.weight_limit) == Status::kOk && exchange_cell_valid(cell, cell_width_m);
}

// ---- varint ----
void delta_write_varint(SnapshotWriter& w, std::uint32_t v) noexcept {
  while (v >= 0x80U) {
    w.u8(static_cast<std::uint8_t>((v & 0x7FU) | 0x80U));
    v >>= 7U;
  }
  w.u8(static_cast<std::uint8_t>(v));
}

bool delta_read_varint(SnapshotReader& r, std::uint32_t* v) noexcept {
  std::uint64_t value = 0U;
  for (unsigned shift = 0U; shift < 35U; shift += 7U) {
    const std::uint8_t byte = r.u8();
    value |= static_cast<std::uint64_t>(byte & 0x7FU) << shift;
    if ((byte & 0x80U) == 0U) {
      *v = static_cast<std::uint32_t>(value);
      return r.ok() && value <= 0xFFFFFFFFULL;
    }
  }
  return false;  // more than 5 bytes
}

// ---- header ----
void delta_write_header(SnapshotWriter& w, const SnapshotFingerprint& f, const DeltaSender& sender) noexcept {
  for (const std::uint8_t b : kDeltaMagic) {
    w.u8(b);
  }
  w.u16(kDeltaFormatVersion);
  w.u16(0U);  // free-space entries, patched by delta_finish
  w.u32(0U);  // the core's size, patched by delta_finish
  snapshot_write_fingerprint(w, f);
  w.f32(sender.finest_cell_width_m);
  w.u32(sender.rover_id);
  w.u32(sender.session);
  w.u32(sender.sequence);
  w.u32(sender.frames_from);
  w.u32(sender.frames_to);
  w.i32(sender.origin_cells.x);
  w.i32(sender.origin_cells.y);
  w.f32(sender.origin_z_m);
}

void delta_finish(SnapshotWriter& w, std::size_t core_end, std::uint32_t entries) noexcept {
  std::uint8_t* data = w.data();
  const auto core = static_cast<std::uint32_t>(core_end + kDeltaTrailerBytes);
  data[kDeltaEntriesAt] = static_cast<std::uint8_t>(entries & 0xFFU);
  data[kDeltaEntriesAt + 1U] = static_cast<std::uint8_t>((entries >> 8U) & 0xFFU);
  for (unsigned byte = 0U; byte < 4U; ++byte) {
    data[kDeltaSizeAt + byte] = static_cast<std::uint8_t>((core >> (8U * byte)) & 0xFFU);
  }
  const std::uint32_t crc = crc32_update(0U, data, core_end);
  for (unsigned byte = 0U; byte < 4U; ++byte) {
    data[core_end + byte] = static_cast<std::uint8_t>((crc >> (8U * byte)) & 0xFFU);
  }
}

Status delta_read_header(const std::uint8_t* data, std::size_t size, const SnapshotFingerprint& expected,
                         SnapshotReader& r, DeltaSender* sender) noexcept {
  if (data == nullptr) {
    return Status::kInvalidArgument;
  }
  constexpr std::size_t kMinCore = kDeltaHeaderBytes + kDeltaTrailerBytes;
  if (size < kMinCore) {
    return Status::kCorrupt;
  }
  SnapshotReader e(data, size);
  for (const std::uint8_t b : kDeltaMagic) {
    if (e.u8() != b) {
      return Status::kCorrupt;
    }
  }
  const std::uint16_t version = e.u16();
  if (version != kDeltaFormatVersion && version != kDeltaOldestFormatVersion) {
    return Status::kVersionMismatch;
  }
  const std::uint16_t entries = e.u16();  // version 2: reserved, 0
  const std::uint32_t core = e.u32();
  // Version 2 has no free-space section: its size field is the whole delta.
  if (core < kMinCore || core > size || (version == kDeltaOldestFormatVersion && (entries != 0U || core != size))) {
    return Status::kCorrupt;
  }
  e.seek(core - kDeltaTrailerBytes);
  const std::uint32_t stored_crc = e.u32();
  if (!e.ok() || crc32_update(0U, data, core - kDeltaTrailerBytes) != stored_crc) {
    return Status::kCorrupt;
  }
  r = SnapshotReader(data, core - kDeltaTrailerBytes);
  r.seek(kSnapshotHeaderBytes);  // past the envelope's magic, version, reserved and size
  const Status shape = snapshot_check_fingerprint(r, expected);
  if (shape != Status::kOk) {
    return shape;
  }
  DeltaSender s{};
  s.finest_cell_width_m = r.f32();
  s.rover_id = r.u32();
  s.session = r.u32();
  s.sequence = r.u32();
  s.frames_from = r.u32();
  s.frames_to = r.u32();
  s.origin_cells.x = r.i32();
  s.origin_cells.y = r.i32();
  s.origin_z_m = r.f32();
  if (!r.ok() || !std::isfinite(s.origin_z_m) || !height_in_range(s.origin_z_m) || s.sequence == 0U) {
    return Status::kCorrupt;
  }
  s.core_size = core;
  s.entries = entries;
  *sender = s;
  return Status::kOk;
}

// ---- alignment ----
bool exchange_offset_aligned(std::int64_t offset_x, std::int64_t offset_y, int layer_count) noexcept {
  if (layer_count < 1 || layer_count > kMaxLayers) {
    return false;
  }
  const std::int64_t factor = std::int64_t{1} << (layer_count - 1);
  return offset_x % factor == 0 && offset_y % factor == 0;
}

Status exchange_offset(CellIndex sender_origin, CellIndex receiver_origin, int layer_count, std::int64_t* offset_x,
                       std::int64_t* offset_y) noexcept {
  const std::int64_t x = std::int64_t{sender_origin.x} - std::int64_t{receiver_origin.x};
  const std::int64_t y = std::int64_t{sender_origin.y} - std::int64_t{receiver_origin.y};
  if (!exchange_offset_aligned(x, y, layer_count)) {
    return Status::kMisaligned;
  }
  *offset_x = x;
  *offset_y = y;
  return Status::kOk;
}

}  // namespace ccmap::detail
