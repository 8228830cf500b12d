// The line-of-sight check of the outlier gate (docs/design.md, "Outlier gate and change"): a
// stereo point whose line of sight from the camera passes under known ground at its middle
// cannot have been seen: its range is too long for its ray (a stereo mismatch far along a steep
// near ray). Stereo only: a stereo frame's origin is its camera; map-frame lidar clouds may come
// with a nominal origin. Integrators need not read it.
//
// At the midpoint of the camera and the point (in finest cells, from the front's index and
// fraction: map/update/front.hpp), the finest layer up to the point's own whose window holds it
// and whose cell there holds points gives the ground height (a CCM cell's mean, a constant
// cell's height); the point is occluded if that ground lies above the line's height there by
// more than the margin k sqrt(V) of the point's layer. O(layers) per point, no heap.
#pragma once

#include <cstdint>

#include "ccmap/map/detail/layers.hpp"
#include "ccmap/map/update/front.hpp"
#include "ccmap/map/update/layer_walk.hpp"

namespace ccmap::detail {

template <typename Config>
class LineOfSight {
 public:
  using Layers = LayerSet<Config>;

  /// The camera of this frame: its anchor cell and fraction (map/update/front.hpp) and height.
  void begin_frame(const FramePose& pose) noexcept {
    anchor_ = pose.anchor;
    fraction_x_ = pose.anchor_fraction[0];
    fraction_y_ = pose.anchor_fraction[1];
    height_ = pose.origin[2];
  }

  /// True if the line from the camera to the point (finest index ix0, iy0 and fraction fx, fy;
  /// height z, m) passes more than `margin` (m) under the ground known at its midpoint in the
  /// layers 0 .. `layer`.
  [[nodiscard]] bool occluded(const Layers& layers, const LayerWalk<Config>& walk, int layer, std::int32_t ix0,
                              std::int32_t iy0, float fx, float fy, float z, float margin) const noexcept {
    // Midpoint in cells from the anchor's corner: the point's offset (in int64: any two indices
    // differ by less than 2^32) plus the camera's fraction, halved.
    const float ux = 0.5F * (static_cast<float>(std::int64_t{ix0} - anchor_.x) + fx + fraction_x_);
    const float uy = 0.5F * (static_cast<float>(std::int64_t{iy0} - anchor_.y) + fy + fraction_y_);
    const std::int32_t mx = anchor_.x + floor_to_int32(ux);
    const std::int32_t my = anchor_.y + floor_to_int32(uy);
    const float line = 0.5F * (z + height_);
    for (int k = 0; k <= layer; ++k) {
      std::uint32_t number = 0U;
      if (!walk.holds(k, mx, my, &number)) {
        continue;
      }
      float ground = 0.0F;
      bool known = false;
      if (Layers::is_ccm(k)) {
        const auto& cell = layers.ccm_storage[number];
        known = cell.weight > 0.0F;
        ground = cell.mean_z;
      } else if constexpr (Layers::kHasFine) {
        const auto& cell = layers.fine_storage[number];
        known = cell.weight > 0.0F;
        ground = cell.height;
      }
      if (known) {
        return ground - line > margin;
      }
    }
    return false;
  }

 private:
  CellIndex anchor_{0, 0};
  float fraction_x_ = 0.0F;
  float fraction_y_ = 0.0F;
  float height_ = 0.0F;
};

}  // namespace ccmap::detail
