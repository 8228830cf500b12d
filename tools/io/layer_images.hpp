// Pictures of one exported map layer: shaded height, inclination, normal variance, class.
// North (+y) is up, +x to the right; unobserved cells are black; small layers are scaled up
// with square pixels so that the picture is at least kMinImageSide pixels wide.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "csv_writer.hpp"
#include "png.hpp"

namespace ccmap::tools {

inline constexpr int kMinImageSide = 512;

/// Cell window drawn for a layer (map-frame global indices, inclusive minimum, nx * ny cells).
/// nx == 0 means "the bounding box of the rows".
struct LayerWindow {
  std::int64_t ix_min = 0;
  std::int64_t iy_min = 0;
  int nx = 0;
  int ny = 0;
};

/// Largest picture side in cells: larger layers are not drawn (render_layer_images refuses them).
inline constexpr int kMaxImageCells = 8192;

/// Cells drawn for `rows` with `window`: the window itself, or (nx == 0) the rows' bounding box
/// (1 x 1 for no rows). nx, ny saturate at kMaxImageCells + 1 for larger extents.
[[nodiscard]] LayerWindow layer_extent(const std::vector<LayerCellRow>& rows, LayerWindow window);

/// Fixed class colours: unknown grey, traversable green, obstacle red, steep orange.
void class_colour(const std::string& cell_class, std::uint8_t out[3]);

/// The four pictures as images (for tests): index 0 height, 1 slope, 2 normal_var, 3 class.
[[nodiscard]] bool render_layer_images(const std::vector<LayerCellRow>& rows, LayerWindow window,
                                       RgbImage images[4], std::string* error);

/// Writes <prefix>_height.png, <prefix>_slope.png, <prefix>_normal_var.png, <prefix>_class.png.
[[nodiscard]] bool write_layer_images(const std::string& prefix, const std::vector<LayerCellRow>& rows,
                                      LayerWindow window, std::string* error);

}  // namespace ccmap::tools
