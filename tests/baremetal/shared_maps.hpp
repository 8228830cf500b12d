// Static storage shared by the cases of one test image (they run one after another; each case
// initialises what it uses): two CADRE stacks, a snapshot buffer, a frame buffer. On the board
// 4 MiB of RAM would not hold a copy per case.
#pragma once

#include <cstddef>
#include <cstdint>

#include "ccmap/persistence/snapshot.hpp"
#include "ccmap/map/stack.hpp"

namespace ccmap::bmtest {

using CadreStack = Stack<CadreConfig>;

inline constexpr std::size_t kCadreSnapshotBytes = snapshot_size<CadreConfig>();
inline constexpr std::size_t kFramePoints = 10000U;  ///< a 125 x 80 px CADRE frame

/// Stack 0 or 1 (static, zero-initialised: not initialised until a case calls init()).
CadreStack& cadre_stack(int which) noexcept;
/// kCadreSnapshotBytes bytes.
std::uint8_t* snapshot_buffer() noexcept;
/// kFramePoints points each: map frame, sensor frame.
PointXYZ* frame_map_points() noexcept;
PointXYZ* frame_sensor_points() noexcept;

/// A deterministic frame of terrain points around (rx, ry) in the map frame into
/// frame_map_points()[0..n) (n <= kFramePoints), seen from (rx, ry, 0.5 m).
void terrain_frame(int frame, float rx, float ry, std::size_t n) noexcept;

}  // namespace ccmap::bmtest
