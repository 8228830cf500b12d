// The map product's byte format and a standalone decoder (header-only: needs no map, no
// library to link; a ground tool or a planner in another process includes this file alone).
//
// A product is little-endian bytes:
//   header, kProductHeaderSize bytes (offsets below, ProductHeader names each field);
//   side_x * side_y cells of kProductCellSize bytes, x fastest, row 0 at the lowest y:
//     +0 u8 class (CellClass), +1 u8 cost (costmap_2d), +2 u8 status (Status of the query at the
//     cell centre), +3 u8 answering layer (255: none), +4 f32 height_m, +8 f32 inclination (dz/dxy);
//   CRC-32 (IEEE 802.3, as zlib's crc32) of every byte before it.
// Every field, with units: docs/icd.md. The writer: product/publish.hpp; the double buffer that
// carries products between threads: product/product_buffers.hpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "ccmap/core/crc32.hpp"
#include "ccmap/core/status.hpp"

namespace ccmap {

inline constexpr std::uint32_t kProductMagic = 0x504D4343U;  // bytes 'C' 'C' 'M' 'P'
inline constexpr std::uint16_t kProductVersion = 1U;
inline constexpr std::uint32_t kProductHeaderSize = 88U;
inline constexpr std::uint32_t kProductCellSize = 12U;
inline constexpr std::uint32_t kProductCrcSize = 4U;
inline constexpr std::uint32_t kProductMaxSide = 256U;
inline constexpr std::uint8_t kProductNoLayer = 255U;

/// Bytes of a product of side_x * side_y cells.
[[nodiscard]] constexpr std::uint32_t product_size(std::uint32_t side_x, std::uint32_t side_y) noexcept {
  return kProductHeaderSize + kProductCellSize * side_x * side_y + kProductCrcSize;
}

/// The header, decoded (host order). Byte offsets in the product in the comments.
struct ProductHeader {
  std::uint32_t magic = 0U;             ///< +0  kProductMagic
  std::uint16_t version = 0U;           ///< +4  kProductVersion
  std::uint16_t header_bytes = 0U;      ///< +6  kProductHeaderSize
  std::uint32_t total_bytes = 0U;       ///< +8  the whole product, CRC included
  std::uint32_t product_sequence = 0U;  ///< +12 1 for the first product of its buffers, +1 per publish
  std::uint32_t map_sequence = 0U;      ///< +16 frame updates the map had folded in (since init or load)
  std::uint32_t params_crc = 0U;        ///< +20 CRC-32 of the C parameters the map ran with (ccmap_health)
  std::uint16_t preset = 0U;            ///< +24 ccmap_preset
  std::int16_t layer = 0;               ///< +26 the layer whose window and cells these are
  std::uint16_t answer = 0U;            ///< +28 0: the stack's answer at each cell centre; 1: the layer's own
  std::uint16_t cell_bytes = 0U;        ///< +30 kProductCellSize
  std::uint16_t side_x = 0U;            ///< +32 cells along x
  std::uint16_t side_y = 0U;            ///< +34 cells along y
  float cell_width_m = 0.0F;            ///< +36
  std::int32_t min_index_x = 0;         ///< +40 global cell index (of `layer`) of cell (0, 0)
  std::int32_t min_index_y = 0;         ///< +44
  float min_corner_x_m = 0.0F;          ///< +48 map-frame corner (lowest x and y) of cell (0, 0)
  float min_corner_y_m = 0.0F;          ///< +52
  float centre_x_m = 0.0F;              ///< +56 the layer's window centre (map frame, m)
  float centre_y_m = 0.0F;              ///< +60
  float pose_x = 0.0F;                  ///< +64 the caller's robot pose (map frame, m, rad), echoed
  float pose_y = 0.0F;                  ///< +68
  float pose_z = 0.0F;                  ///< +72
  float pose_yaw = 0.0F;                ///< +76
  std::uint32_t tag = 0U;               ///< +80 the caller's tag, echoed
                                        ///< +84 reserved: 0
};

/// One cell, decoded.
struct ProductCell {
  std::uint8_t cell_class = 0U;  ///< CellClass
  std::uint8_t cost = 0U;        ///< costmap_2d value (0 free .. 252, 253 inscribed, 254 lethal, 255 unknown)
  std::uint8_t status = 0U;      ///< Status of the query at the cell centre
  std::uint8_t layer = 0U;       ///< answering layer, kProductNoLayer if none
  float height_m = 0.0F;         ///< 0 unless status is kOk
  float inclination = 0.0F;      ///< dz/dxy; 0 unless status is kOk
};

namespace product_detail {

inline void put_u16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v & 0xFFU);
  p[1] = static_cast<std::uint8_t>(v >> 8U);
}
inline void put_u32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) {
    p[i] = static_cast<std::uint8_t>((v >> (8U * static_cast<std::uint32_t>(i))) & 0xFFU);
  }
}
inline void put_f32(std::uint8_t* p, float v) noexcept {
  std::uint32_t bits = 0U;
  std::memcpy(&bits, &v, sizeof bits);
  put_u32(p, bits);
}
[[nodiscard]] inline std::uint16_t get_u16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8U));
}
[[nodiscard]] inline std::uint32_t get_u32(const std::uint8_t* p) noexcept {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8U) |
         (static_cast<std::uint32_t>(p[2]) << 16U) | (static_cast<std::uint32_t>(p[3]) << 24U);
}
[[nodiscard]] inline float get_f32(const std::uint8_t* p) noexcept {
  const std::uint32_t bits = get_u32(p);
  float v = 0.0F;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

}  // namespace product_detail

/// CRC-32 (IEEE 802.3, as zlib's crc32) of data[0, size): product_crc32("123456789", 9) == 0xCBF43926.
[[nodiscard]] inline std::uint32_t product_crc32(const std::uint8_t* data, std::size_t size) noexcept {
  return detail::crc32_continue(0U, data, size);
}

/// Writes `h` into the first kProductHeaderSize bytes of `out` (magic, version, header_bytes and
/// cell_bytes as this version writes them, whatever h holds).
inline void encode_product_header(const ProductHeader& h, std::uint8_t* out) noexcept {
  using namespace product_detail;
  put_u32(out + 0, kProductMagic);
  put_u16(out + 4, kProductVersion);
  put_u16(out + 6, static_cast<std::uint16_t>(kProductHeaderSize));
  put_u32(out + 8, h.total_bytes);
  put_u32(out + 12, h.product_sequence);
  put_u32(out + 16, h.map_sequence);
  put_u32(out + 20, h.params_crc);
  put_u16(out + 24, h.preset);
  put_u16(out + 26, static_cast<std::uint16_t>(h.layer));
  put_u16(out + 28, h.answer);
  put_u16(out + 30, static_cast<std::uint16_t>(kProductCellSize));
  put_u16(out + 32, h.side_x);
  put_u16(out + 34, h.side_y);
  put_f32(out + 36, h.cell_width_m);
  put_u32(out + 40, static_cast<std::uint32_t>(h.min_index_x));
  put_u32(out + 44, static_cast<std::uint32_t>(h.min_index_y));
  put_f32(out + 48, h.min_corner_x_m);
  put_f32(out + 52, h.min_corner_y_m);
  put_f32(out + 56, h.centre_x_m);
  put_f32(out + 60, h.centre_y_m);
  put_f32(out + 64, h.pose_x);
  put_f32(out + 68, h.pose_y);
  put_f32(out + 72, h.pose_z);
  put_f32(out + 76, h.pose_yaw);
  put_u32(out + 80, h.tag);
  put_u32(out + 84, 0U);
}

/// Checks a product's bytes (size, magic, version, sizes, CRC) and decodes its header into *out.
/// kCorrupt: too short, bad magic, sizes that disagree with `size` or each other, a CRC
/// mismatch; kVersionMismatch: another version (magic right); kInvalidArgument: nullptr.
[[nodiscard]] inline Status decode_product_header(const std::uint8_t* data, std::size_t size, ProductHeader* out) noexcept {
  using namespace product_detail;
  if (data == nullptr || out == nullptr) {
    return Status::kInvalidArgument;
  }
  if (size < kProductHeaderSize + kProductCrcSize || get_u32(data) != kProductMagic) {
    return Status::kCorrupt;
  }
  ProductHeader h{};
  h.magic = get_u32(data);
  h.version = get_u16(data + 4);
  if (h.version != kProductVersion) {
    return Status::kVersionMismatch;
  }
  h.header_bytes = get_u16(data + 6);
  h.total_bytes = get_u32(data + 8);
  h.product_sequence = get_u32(data + 12);
  h.map_sequence = get_u32(data + 16);
  h.params_crc = get_u32(data + 20);
  h.preset = get_u16(data + 24);
  h.layer = static_cast<std::int16_t>(get_u16(data + 26));
  h.answer = get_u16(data + 28);
  h.cell_bytes = get_u16(data + 30);
  h.side_x = get_u16(data + 32);
  h.side_y = get_u16(data + 34);
  h.cell_width_m = get_f32(data + 36);
  h.min_index_x = static_cast<std::int32_t>(get_u32(data + 40));
  h.min_index_y = static_cast<std::int32_t>(get_u32(data + 44));
  h.min_corner_x_m = get_f32(data + 48);
  h.min_corner_y_m = get_f32(data + 52);
  h.centre_x_m = get_f32(data + 56);
  h.centre_y_m = get_f32(data + 60);
  h.pose_x = get_f32(data + 64);
  h.pose_y = get_f32(data + 68);
  h.pose_z = get_f32(data + 72);
  h.pose_yaw = get_f32(data + 76);
  h.tag = get_u32(data + 80);
  if (h.header_bytes != kProductHeaderSize || h.cell_bytes != kProductCellSize || h.side_x > kProductMaxSide ||
      h.side_y > kProductMaxSide || h.total_bytes != size || h.total_bytes != product_size(h.side_x, h.side_y)) {
    return Status::kCorrupt;
  }
  if (product_crc32(data, size - kProductCrcSize) != get_u32(data + size - kProductCrcSize)) {
    return Status::kCorrupt;
  }
  *out = h;
  return Status::kOk;
}

/// Cell `i` (x fastest) of a product whose header decode_product_header accepted; i must be
/// below side_x * side_y.
[[nodiscard]] inline ProductCell decode_product_cell(const std::uint8_t* data, std::size_t i) noexcept {
  using namespace product_detail;
  const std::uint8_t* p = data + kProductHeaderSize + kProductCellSize * i;
  ProductCell c{};
  c.cell_class = p[0];
  c.cost = p[1];
  c.status = p[2];
  c.layer = p[3];
  c.height_m = get_f32(p + 4);
  c.inclination = get_f32(p + 8);
  return c;
}

/// Writes cell `i` of a product under construction.
inline void encode_product_cell(const ProductCell& c, std::uint8_t* data, std::size_t i) noexcept {
  using namespace product_detail;
  std::uint8_t* p = data + kProductHeaderSize + kProductCellSize * i;
  p[0] = c.cell_class;
  p[1] = c.cost;
  p[2] = c.status;
  p[3] = c.layer;
  put_f32(p + 4, c.height_m);
  put_f32(p + 8, c.inclination);
}

}  // namespace ccmap
