// The writer of map products (product/product_format.hpp) into the lock-free double buffer
// (product/product_buffers.hpp): what a planner in another thread or the ground reads beside the
// mapper. Runs on the map's thread (it reads the map), never waits for a reader.
//
// The product covers one layer's window, cell for cell (index min .. min + side - 1 on each
// axis): each cell holds what Stack::query (ProductAnswer::kStack) or Stack::query_layer
// (ProductAnswer::kLayer) answers at the cell's centre, and the costmap_2d cost fill_costmap gives
// the cell's square (no inflation; planner/costmap.hpp). Cost: one query per cell and one
// costmap of the window, then one CRC pass and one copy into the slot.
#pragma once

#include <cmath>
#include <cstdint>

#include "ccmap/grid/ring_index.hpp"
#include "ccmap/map/stack.hpp"
#include "ccmap/planner/costmap.hpp"
#include "ccmap/product/product_buffers.hpp"
#include "ccmap/product/product_format.hpp"

namespace ccmap {

enum class ProductAnswer : std::uint8_t { kStack = 0, kLayer = 1 };

/// What to publish and what to stamp on it.
struct ProductSpec {
  int layer = 0;                           ///< whose window and cells, [0, kLayerCount)
  ProductAnswer answer = ProductAnswer::kStack;
  float pose_x = 0.0F;                     ///< the robot pose the product belongs to (map frame, m,
  float pose_y = 0.0F;                     ///< rad): echoed, finite
  float pose_z = 0.0F;
  float pose_yaw = 0.0F;
  std::uint32_t tag = 0U;                  ///< echoed (e.g. the frame's time tag)
  std::uint16_t preset = 0U;               ///< echoed: the C API's preset of the map
  std::uint32_t params_crc = 0U;           ///< echoed: CRC of the parameters (ccmap_health.params_crc)
};

/// Composes the product of spec.layer's window in the staging area and commits it. Refused,
/// nothing published: kInvalidArgument (buffers not set up, a bad layer or answer, a non-finite
/// pose), kBufferTooSmall (the product exceeds a slot), kNotInitialised, kCorrupt (state_status),
/// or fill_costmap's refusal of the window (kOutOfRange: a window beyond kMaxAbsCoordinateM).
template <typename Config>
[[nodiscard]] Status publish_product(const Stack<Config>& stack, const ProductSpec& spec,
                                     ProductBuffers& buffers) noexcept {
  using StackType = Stack<Config>;
  std::uint8_t* staging = product_staging(buffers);
  if (staging == nullptr || spec.layer < 0 || spec.layer >= StackType::kLayerCount ||
      (spec.answer != ProductAnswer::kStack && spec.answer != ProductAnswer::kLayer) ||
      !std::isfinite(spec.pose_x) || !std::isfinite(spec.pose_y) || !std::isfinite(spec.pose_z) ||
      !std::isfinite(spec.pose_yaw)) {
    return Status::kInvalidArgument;
  }
  const Status state = stack.state_status();
  if (state != Status::kOk) {
    return state;
  }
  const auto side = static_cast<std::uint32_t>(StackType::layer_side(spec.layer));
  const std::uint32_t bytes = product_size(side, side);
  if (side > kProductMaxSide || bytes > buffers.slot_bytes) {
    return Status::kBufferTooSmall;
  }
  const float width = stack.layer_cell_width(spec.layer);
  const CellIndex centre = stack.layer_centre(spec.layer);
  const std::int32_t half = static_cast<std::int32_t>(side / 2U);
  const CellIndex min{centre.x - half, centre.y - half};
  // Costs first, one byte per cell at the start of the cell area; each cell's record then
  // replaces them from the last to the first (record i starts at byte 12 i >= i).
  std::uint8_t* cells = staging + kProductHeaderSize;
  const CostmapSpec costmap{static_cast<float>(centre.x) * width, static_cast<float>(centre.y) * width, width, side,
                            0.0F};
  const Status costed = fill_costmap(stack, costmap, cells, std::size_t{side} * side, nullptr);
  if (costed != Status::kOk) {
    return costed;
  }
  for (std::uint32_t i = side * side; i-- > 0U;) {
    const std::uint8_t cost = cells[i];
    const std::int32_t ix = min.x + static_cast<std::int32_t>(i % side);
    const std::int32_t iy = min.y + static_cast<std::int32_t>(i / side);
    const float x = grid::cell_centre(ix, width);
    const float y = grid::cell_centre(iy, width);
    const QueryResult q = spec.answer == ProductAnswer::kStack ? stack.query(x, y) : stack.query_layer(spec.layer, x, y);
    ProductCell c{};
    c.cell_class = static_cast<std::uint8_t>(q.cell_class);
    c.cost = cost;
    c.status = static_cast<std::uint8_t>(q.status);
    c.layer = q.layer >= 0 && q.layer < 255 ? static_cast<std::uint8_t>(q.layer) : kProductNoLayer;
    c.height_m = q.status == Status::kOk ? q.height_m : 0.0F;
    c.inclination = q.status == Status::kOk ? q.inclination : 0.0F;
    encode_product_cell(c, staging, i);
  }
  ProductHeader h{};
  h.total_bytes = bytes;
  h.product_sequence = product_next_sequence(buffers);
  h.map_sequence = stack.accepted_frames();
  h.params_crc = spec.params_crc;
  h.preset = spec.preset;
  h.answer = static_cast<std::uint16_t>(spec.answer);
  h.layer = static_cast<std::int16_t>(spec.layer);
  h.side_x = static_cast<std::uint16_t>(side);
  h.side_y = static_cast<std::uint16_t>(side);
  h.cell_width_m = width;
  h.min_index_x = min.x;
  h.min_index_y = min.y;
  h.min_corner_x_m = static_cast<float>(min.x) * width;
  h.min_corner_y_m = static_cast<float>(min.y) * width;
  h.centre_x_m = static_cast<float>(centre.x) * width;
  h.centre_y_m = static_cast<float>(centre.y) * width;
  h.pose_x = spec.pose_x;
  h.pose_y = spec.pose_y;
  h.pose_z = spec.pose_z;
  h.pose_yaw = spec.pose_yaw;
  h.tag = spec.tag;
  encode_product_header(h, staging);
  product_detail::put_u32(staging + bytes - kProductCrcSize, product_crc32(staging, bytes - kProductCrcSize));
  return product_commit(buffers, bytes);
}

}  // namespace ccmap
