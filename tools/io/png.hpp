// Host-side PNG and colour-map helpers for pictures of map layers and experiments.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace ccmap::tools {

/// 8-bit RGB image, row-major, row 0 at the top.
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // 3 * width * height
  RgbImage() = default;
  RgbImage(int w, int h, std::uint8_t grey = 0)
      : width(w), height(h), rgb(static_cast<std::size_t>(3 * w * h), grey) {}
  void set(int x, int y, const std::uint8_t c[3]) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    const std::size_t o = 3U * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x));
    rgb[o] = c[0];
    rgb[o + 1] = c[1];
    rgb[o + 2] = c[2];
  }
};

/// Writes `image` as an 8-bit RGB PNG. Returns false (and a message in *error) on failure.
bool write_png(const std::string& path, const RgbImage& image, std::string* error = nullptr);

/// Viridis-like perceptual colour map, t clamped to [0, 1].
void colormap_viridis(double t, std::uint8_t out[3]);
/// Blue-white-red diverging colour map, t clamped to [-1, 1] (0 = white).
void colormap_diverging(double t, std::uint8_t out[3]);
/// Grey shading of a height field from its gradient (light from the north-west), in [0, 1].
double hillshade(double dzdx, double dzdy);

}  // namespace ccmap::tools
