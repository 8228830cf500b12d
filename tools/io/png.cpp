#include "png.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace ccmap::tools {

bool write_png(const std::string& path, const RgbImage& image, std::string* error) {
  auto fail = [error](const std::string& message) {
    if (error != nullptr) *error = message;
    return false;
  };
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != static_cast<std::size_t>(3 * image.width * image.height)) {
    return fail("bad image size");
  }
  FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return fail("cannot open " + path + " for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return fail("libpng initialisation failed");
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return fail("libpng failed writing " + path);
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height), 8,
               PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y) {
    png_write_row(png, image.rgb.data() + static_cast<std::size_t>(3 * image.width * y));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return std::fclose(file) == 0 ? true : fail("cannot close " + path);
}

void colormap_viridis(double t, std::uint8_t out[3]) {
  // Piece-wise linear through 6 viridis anchor colours.
  static const double kAnchors[6][3] = {{68, 1, 84},   {65, 68, 135}, {42, 120, 142},
                                        {34, 168, 132}, {122, 209, 81}, {253, 231, 37}};
  if (!std::isfinite(t)) t = 0.0;
  t = std::clamp(t, 0.0, 1.0) * 5.0;
  const int i = std::min(4, static_cast<int>(t));
  const double f = t - i;
  for (int c = 0; c < 3; ++c) {
    out[c] = static_cast<std::uint8_t>(std::lround(kAnchors[i][c] * (1.0 - f) + kAnchors[i + 1][c] * f));
  }
}

void colormap_diverging(double t, std::uint8_t out[3]) {
  if (!std::isfinite(t)) t = 0.0;
  t = std::clamp(t, -1.0, 1.0);
  const double a = std::fabs(t);
  const double hi = 255.0, lo = 255.0 * (1.0 - a);
  out[0] = static_cast<std::uint8_t>(std::lround(t >= 0 ? hi : lo));
  out[1] = static_cast<std::uint8_t>(std::lround(lo));
  out[2] = static_cast<std::uint8_t>(std::lround(t >= 0 ? lo : hi));
}

double hillshade(double dzdx, double dzdy) {
  // Lambert shading with the sun at 45 deg elevation from the north-west.
  const double nx = -dzdx, ny = -dzdy, nz = 1.0;
  const double norm = std::sqrt(nx * nx + ny * ny + nz * nz);
  const double lx = -0.5, ly = 0.5, lz = 0.7071067811865476;
  const double v = (nx * lx + ny * ly + nz * lz) / norm;
  return std::clamp(v, 0.0, 1.0);
}

}  // namespace ccmap::tools
