// Non-template parts of the snapshot format (include/ccmap/persistence/snapshot.hpp): CRC-32, the
// little-endian field codec, header, fingerprint, parameters, cells and counters.
#include "ccmap/persistence/snapshot.hpp"

#include <cmath>
#include <cstring>
#include <limits>

#include "ccmap/core/crc32.hpp"
#include "ccmap/map/classify.hpp"
#include "ccmap/sensor/noise_model.hpp"

namespace ccmap {

namespace {

// The format (snapshot.hpp) lists every field of these types; a new field needs a new format
// version, not a silent omission.
static_assert(sizeof(FrameCounters) == 22U * sizeof(std::uint32_t),
              "FrameCounters changed: update the snapshot format and kSnapshotFormatVersion");
static_assert(sizeof(sensor::NoiseModel) == 4U + 5U * sizeof(float),
              "NoiseModel changed: update the snapshot format and kSnapshotFormatVersion");
static_assert(sizeof(StackParams) == (7U + static_cast<std::size_t>(kMaxLayers) + 1U + 3U + 2U + 5U) * sizeof(float) +
                                         sizeof(sensor::NoiseModel),
              "StackParams changed: update the snapshot format and kSnapshotFormatVersion");

constexpr std::uint8_t kMagic[4] = {0x43U, 0x43U, 0x4DU, 0x53U};  // "CCMS"

std::uint32_t float_bits(float v) noexcept {
  std::uint32_t bits = 0U;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}
float bits_float(std::uint32_t bits) noexcept {
  float v = 0.0F;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}
bool is_positive_infinity(float v) noexcept {
  return std::isinf(v) && !std::signbit(v);
}

}  // namespace

std::uint32_t crc32_update(std::uint32_t crc, const std::uint8_t* data, std::size_t size) noexcept {
  if (data == nullptr) {
    return crc;
  }
  return detail::crc32_continue(crc, data, size);
}

namespace detail {

// ---- writer ----
void SnapshotWriter::u8(std::uint8_t v) noexcept {
  if (position_ >= capacity_) {
    overflowed_ = true;
    return;
  }
  data_[position_] = v;
  ++position_;
}
void SnapshotWriter::u16(std::uint16_t v) noexcept {
  u8(static_cast<std::uint8_t>(v & 0xFFU));
  u8(static_cast<std::uint8_t>(v >> 8U));
}
void SnapshotWriter::u32(std::uint32_t v) noexcept {
  for (unsigned shift = 0U; shift < 32U; shift += 8U) {
    u8(static_cast<std::uint8_t>((v >> shift) & 0xFFU));
  }
}
void SnapshotWriter::u64(std::uint64_t v) noexcept {
  for (unsigned shift = 0U; shift < 64U; shift += 8U) {
    u8(static_cast<std::uint8_t>((v >> shift) & 0xFFU));
  }
}
void SnapshotWriter::i32(std::int32_t v) noexcept { u32(static_cast<std::uint32_t>(v)); }
void SnapshotWriter::f32(float v) noexcept {
  finite_ = finite_ && std::isfinite(v);
  u32(float_bits(v));
}
void SnapshotWriter::f32_or_inf(float v) noexcept {
  finite_ = finite_ && (std::isfinite(v) || is_positive_infinity(v));
  u32(float_bits(v));
}

// ---- reader ----
std::uint8_t SnapshotReader::u8() noexcept {
  if (position_ >= size_) {
    ok_ = false;
    return 0U;
  }
  const std::uint8_t v = data_[position_];
  ++position_;
  return v;
}
std::uint16_t SnapshotReader::u16() noexcept {
  const auto lo = static_cast<std::uint16_t>(u8());
  const auto hi = static_cast<std::uint16_t>(u8());
  return static_cast<std::uint16_t>(lo | static_cast<std::uint16_t>(hi << 8U));
}
std::uint32_t SnapshotReader::u32() noexcept {
  std::uint32_t v = 0U;
  for (unsigned shift = 0U; shift < 32U; shift += 8U) {
    v |= static_cast<std::uint32_t>(u8()) << shift;
  }
  return v;
}
std::uint64_t SnapshotReader::u64() noexcept {
  std::uint64_t v = 0U;
  for (unsigned shift = 0U; shift < 64U; shift += 8U) {
    v |= static_cast<std::uint64_t>(u8()) << shift;
  }
  return v;
}
std::int32_t SnapshotReader::i32() noexcept { return static_cast<std::int32_t>(u32()); }
float SnapshotReader::f32() noexcept { return bits_float(u32()); }
void SnapshotReader::seek(std::size_t position) noexcept {
  if (position > size_) {
    ok_ = false;
    position_ = size_;
    return;
  }
  position_ = position;
}

// ---- header, envelope, fingerprint ----
void snapshot_write_header(SnapshotWriter& w, std::size_t total_size, const SnapshotFingerprint& f) noexcept {
  for (const std::uint8_t b : kMagic) {
    w.u8(b);
  }
  w.u16(kSnapshotFormatVersion);
  w.u16(0U);
  w.u32(static_cast<std::uint32_t>(total_size));
  snapshot_write_fingerprint(w, f);
}

void snapshot_write_fingerprint(SnapshotWriter& w, const SnapshotFingerprint& f) noexcept {
  w.u8(f.fine_kind);
  w.u8(f.layer_count);
  w.u16(0U);
  for (const std::uint32_t side : f.sides) {
    w.u32(side);
  }
  w.u16(f.fine_cell_bytes);
  w.u16(f.ccm_cell_bytes);
}

Status check_envelope(const std::uint8_t* data, std::size_t size, const std::uint8_t (&magic)[4],
                      std::uint16_t version, std::size_t min_size) noexcept {
  if (data == nullptr) {
    return Status::kInvalidArgument;
  }
  if (size < min_size || size < kSnapshotHeaderBytes + kSnapshotTrailerBytes) {
    return Status::kCorrupt;
  }
  SnapshotReader r(data, size);
  for (const std::uint8_t b : magic) {
    if (r.u8() != b) {
      return Status::kCorrupt;
    }
  }
  if (r.u16() != version) {
    return Status::kVersionMismatch;
  }
  if (r.u16() != 0U) {
    return Status::kCorrupt;
  }
  const std::uint32_t stored_size = r.u32();
  if (static_cast<std::size_t>(stored_size) != size) {
    return Status::kCorrupt;
  }
  const std::size_t body = size - kSnapshotTrailerBytes;
  r.seek(body);
  const std::uint32_t stored_crc = r.u32();
  if (!r.ok() || crc32_update(0U, data, body) != stored_crc) {
    return Status::kCorrupt;
  }
  return Status::kOk;
}

Status snapshot_check_envelope(const std::uint8_t* data, std::size_t size) noexcept {
  return check_envelope(data, size, kMagic, kSnapshotFormatVersion, 0U);
}

Status snapshot_check_fingerprint(SnapshotReader& r, const SnapshotFingerprint& expected) noexcept {
  const std::uint8_t fine_kind = r.u8();
  const std::uint8_t layer_count = r.u8();
  const std::uint16_t reserved = r.u16();
  bool same = fine_kind == expected.fine_kind && layer_count == expected.layer_count;
  for (const std::uint32_t side : expected.sides) {
    same = (r.u32() == side) && same;
  }
  same = (r.u16() == expected.fine_cell_bytes) && same;
  same = (r.u16() == expected.ccm_cell_bytes) && same;
  if (!r.ok() || reserved != 0U) {
    return Status::kCorrupt;
  }
  return same ? Status::kOk : Status::kVersionMismatch;
}

// ---- parameters ----
void snapshot_write_params(SnapshotWriter& w, const StackParams& p) noexcept {
  w.f32(p.finest_cell_width_m);
  w.f32_or_inf(p.weight_limit);
  w.f32(p.coverage_tau);
  w.f32(p.min_weight);
  w.f32(p.obstacle_fraction);
  w.f32(p.max_inclination);
  w.f32(p.kalman_min_variance);
  for (const float t : p.normal_variance_threshold) {
    w.f32(t);
  }
  w.f32(p.finest_max_sigma_m);
  w.f32(p.outlier_gate_sigma);
  w.f32(p.change_min_points);
  w.f32(p.change_share);
  w.u32(p.frame_point_budget);
  w.u32(p.frame_time_budget_us);
  w.f32(p.free_space_rays);
  w.f32(p.free_space_clear_frames);
  for (const float a : p.sensor_view_axis) {
    w.f32(a);
  }
  w.u8(static_cast<std::uint8_t>(p.noise.kind()));
  w.u8(static_cast<std::uint8_t>(p.noise.weight_mode()));
  w.u16(0U);
  w.f32(p.noise.stereo_sigma_per_range_sq());
  w.f32(p.noise.lidar_sigma0_m());
  w.f32(p.noise.lidar_sigma_per_m());
  w.f32(p.noise.reference_range_m());
}

Status snapshot_read_params(SnapshotReader& r, int layer_count, bool has_fine, StackParams* out) noexcept {
  if (out == nullptr || layer_count < 1 || layer_count > kMaxLayers) {
    return Status::kInvalidArgument;
  }
  StackParams p{};
  bool finite = true;
  auto finite_f32 = [&r, &finite]() noexcept {
    const float v = r.f32();
    finite = finite && std::isfinite(v);
    return v;
  };
  p.finest_cell_width_m = finite_f32();
  p.weight_limit = r.f32();
  if (!std::isfinite(p.weight_limit) && !is_positive_infinity(p.weight_limit)) {
    finite = false;
  }
  p.coverage_tau = finite_f32();
  p.min_weight = finite_f32();
  p.obstacle_fraction = finite_f32();
  p.max_inclination = finite_f32();
  p.kalman_min_variance = finite_f32();
  for (float& t : p.normal_variance_threshold) {
    t = finite_f32();
  }
  p.finest_max_sigma_m = finite_f32();
  p.outlier_gate_sigma = finite_f32();
  p.change_min_points = finite_f32();
  p.change_share = finite_f32();
  p.frame_point_budget = r.u32();
  p.frame_time_budget_us = r.u32();
  p.free_space_rays = finite_f32();
  p.free_space_clear_frames = finite_f32();
  for (float& a : p.sensor_view_axis) {
    a = finite_f32();
  }
  const std::uint8_t kind = r.u8();
  const std::uint8_t mode = r.u8();
  const std::uint16_t reserved = r.u16();
  const float stereo_k = finite_f32();
  const float lidar_sigma0 = finite_f32();
  const float lidar_sigma_per_m = finite_f32();
  const float reference_range = finite_f32();
  if (!r.ok() || !finite || reserved != 0U) {
    return Status::kCorrupt;
  }
  // The model is rebuilt from the stored derived values. Stereo: k = sigma_d / (f * b) is
  // rebuilt as k / (1 * 1) = k exactly, so every sigma and weight is bitwise the saved one.
  if (kind == static_cast<std::uint8_t>(sensor::SensorKind::kStereo)) {
    if (float_bits(lidar_sigma0) != 0U || float_bits(lidar_sigma_per_m) != 0U) {
      return Status::kCorrupt;
    }
    p.noise = sensor::NoiseModel::stereo(sensor::StereoParams{1.0F, 1.0F, stereo_k});
  } else if (kind == static_cast<std::uint8_t>(sensor::SensorKind::kLidar)) {
    if (float_bits(stereo_k) != 0U) {
      return Status::kCorrupt;
    }
    p.noise = sensor::NoiseModel::lidar(sensor::LidarParams{lidar_sigma0, lidar_sigma_per_m});
  } else {
    return Status::kCorrupt;
  }
  if (mode == static_cast<std::uint8_t>(sensor::WeightMode::kConstant)) {
    p.noise.set_weight_mode(sensor::WeightMode::kConstant, reference_range);
  } else if (mode == static_cast<std::uint8_t>(sensor::WeightMode::kInverseVariance)) {
    p.noise.set_weight_mode(sensor::WeightMode::kInverseVariance, reference_range);
  } else {
    return Status::kCorrupt;
  }
  // What Stack::init checks, in the same order: parameters, ring-grid widths, routing table.
  if (validate_stack_params(p, layer_count) != Status::kOk) {
    return Status::kCorrupt;
  }
  if (!std::isfinite(1.0F / p.finest_cell_width_m)) {
    return Status::kCorrupt;
  }
  float widths[kMaxLayers] = {};
  float width = p.finest_cell_width_m;
  for (int layer = 0; layer < layer_count; ++layer) {
    widths[layer] = width;
    width *= 2.0F;
  }
  float max_range_sq[kMaxLayers] = {};
  if (sensor::detail::build_routing_table_impl(p.noise, widths, layer_count, has_fine, p.finest_max_sigma_m,
                                               max_range_sq) != Status::kOk) {
    return Status::kCorrupt;
  }
  *out = p;
  return Status::kOk;
}

// ---- layers ----
void snapshot_write_centre(SnapshotWriter& w, CellIndex centre) noexcept {
  w.i32(centre.x);
  w.i32(centre.y);
}

bool snapshot_read_centre(SnapshotReader& r, CellIndex* out) noexcept {
  const std::int32_t x = r.i32();
  const std::int32_t y = r.i32();
  *out = CellIndex{x, y};
  const bool in_range = x >= -grid::kMaxCellIndex && x <= grid::kMaxCellIndex && y >= -grid::kMaxCellIndex &&
                        y <= grid::kMaxCellIndex;
  // Stack::move_to snaps every centre to an even index (nesting of the layers).
  const bool even = (static_cast<std::uint32_t>(x) & 1U) == 0U && (static_cast<std::uint32_t>(y) & 1U) == 0U;
  return r.ok() && in_range && even;
}

void snapshot_write_cell(SnapshotWriter& w, const CcmCell& c) noexcept {
  const float fields[] = {c.weight, c.mean_x, c.mean_y, c.mean_z, c.s_xx, c.s_yy, c.s_zz, c.s_xz, c.s_yz, c.s_xy};
  for (const float v : fields) {
    w.f32(v);
  }
}
void snapshot_write_cell(SnapshotWriter& w, const CcmPaperCell& c) noexcept {
  const float fields[] = {c.weight, c.mean_x, c.mean_y, c.mean_z, c.s_xx, c.s_yy, c.s_zz, c.s_xz, c.s_yz};
  for (const float v : fields) {
    w.f32(v);
  }
}
void snapshot_write_cell(SnapshotWriter& w, const KalmanCell& c) noexcept {
  w.f32(c.height);
  w.f32(c.variance);
  w.f32(c.weight);
}
void snapshot_write_cell(SnapshotWriter& w, const OmgCell& c) noexcept {
  w.f32(c.weight);
  w.f32(c.height);
  w.f32(c.s);
}

namespace {
bool all_finite(const float* values, std::size_t n) noexcept {
  bool finite = true;
  for (std::size_t i = 0; i < n; ++i) {
    finite = finite && std::isfinite(values[i]);
  }
  return finite;
}
}  // namespace

bool snapshot_read_cell(SnapshotReader& r, CcmCell* out) noexcept {
  float f[10];
  for (float& v : f) {
    v = r.f32();
  }
  *out = CcmCell{f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8], f[9]};
  return r.ok() && all_finite(f, 10U) && f[0] >= 0.0F;
}
bool snapshot_read_cell(SnapshotReader& r, CcmPaperCell* out) noexcept {
  float f[9];
  for (float& v : f) {
    v = r.f32();
  }
  *out = CcmPaperCell{f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8]};
  return r.ok() && all_finite(f, 9U) && f[0] >= 0.0F;
}
bool snapshot_read_cell(SnapshotReader& r, KalmanCell* out) noexcept {
  float f[3];
  for (float& v : f) {
    v = r.f32();
  }
  *out = KalmanCell{f[0], f[1], f[2]};
  return r.ok() && all_finite(f, 3U) && f[2] >= 0.0F;
}
bool snapshot_read_cell(SnapshotReader& r, OmgCell* out) noexcept {
  float f[3];
  for (float& v : f) {
    v = r.f32();
  }
  *out = OmgCell{f[0], f[1], f[2]};
  return r.ok() && all_finite(f, 3U) && f[0] >= 0.0F;
}

// ---- free-space records ----
void snapshot_write_record(SnapshotWriter& w, const FreeSpaceCell& c) noexcept {
  w.u16(c.bound_code);
  w.u8(c.evidence);
  w.u8(c.state);
}
void snapshot_read_record(SnapshotReader& r, FreeSpaceCell* out) noexcept {
  out->bound_code = r.u16();
  out->evidence = r.u8();
  out->state = r.u8();
}

// ---- counters, trailer ----
void snapshot_write_counters(SnapshotWriter& w, const FrameCounters& t, std::uint32_t rejected_moves,
                             std::uint32_t rejected_frames) noexcept {
  const std::uint32_t values[] = {t.received,        t.used,           t.rejected_non_finite,
                                  t.rejected_out_of_range, t.rejected_weight, t.outside_map,
                                  t.too_noisy,       t.gated_finer,    t.gated_occluded,
                                  t.gated_held,      t.gated_pool_full, t.gated_admitted,
                                  t.gated_dropped,   t.reseeded_cells, t.merged_cells,
                                  t.skipped_budget,  t.corrupted_cells, t.corrupted_slots,
                                  // free space from lines of sight (format 5), a block of its own
                                  t.free_rays,       t.free_rays_refused, t.cleared_cells,
                                  t.drop_cells,
                                  rejected_moves,    rejected_frames};
  for (const std::uint32_t v : values) {
    w.u32(v);
  }
  w.u64(0U);  // reserved (snapshot.hpp): no measured time, so equal maps save equal bytes
}

void snapshot_read_counters(SnapshotReader& r, FrameCounters* t, std::uint32_t* rejected_moves,
                            std::uint32_t* rejected_frames) noexcept {
  t->received = r.u32();
  t->used = r.u32();
  t->rejected_non_finite = r.u32();
  t->rejected_out_of_range = r.u32();
  t->rejected_weight = r.u32();
  t->outside_map = r.u32();
  t->too_noisy = r.u32();
  t->gated_finer = r.u32();
  t->gated_occluded = r.u32();
  t->gated_held = r.u32();
  t->gated_pool_full = r.u32();
  t->gated_admitted = r.u32();
  t->gated_dropped = r.u32();
  t->reseeded_cells = r.u32();
  t->merged_cells = r.u32();
  t->skipped_budget = r.u32();
  t->corrupted_cells = r.u32();
  t->corrupted_slots = r.u32();
  // free space from lines of sight (format 5), a block of its own
  t->free_rays = r.u32();
  t->free_rays_refused = r.u32();
  t->cleared_cells = r.u32();
  t->drop_cells = r.u32();
  *rejected_moves = r.u32();
  *rejected_frames = r.u32();
  (void)r.u64();  // reserved: a version-5 snapshot may hold a duration here; ignored
}

void snapshot_write_trailer(SnapshotWriter& w) noexcept {
  w.u32(crc32_update(0U, w.data(), w.position()));
}

}  // namespace detail
}  // namespace ccmap
