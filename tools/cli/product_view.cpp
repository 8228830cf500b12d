#include "product_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <vector>

#include "ccmap/core/status.hpp"
#include "ccmap/map/types.hpp"
#include "ccmap/product/product_format.hpp"
#include "layer_images.hpp"
#include "png.hpp"

namespace ccmap::tools {
namespace {

/// Pixels per cell so that the picture is at least kMinImageSide wide (square pixels).
int scale_of(int side) { return side >= kMinImageSide ? 1 : (kMinImageSide + side - 1) / side; }

bool write_picture(const std::string& path, const ProductHeader& h, const std::uint8_t* data,
                   void (*colour)(const ProductCell&, float, float, std::uint8_t*), float lo, float hi,
                   std::string* error) {
  const int sx = h.side_x;
  const int sy = h.side_y;
  const int s = scale_of(std::max(sx, sy));
  RgbImage image(sx * s, sy * s);
  for (int iy = 0; iy < sy; ++iy) {
    for (int ix = 0; ix < sx; ++ix) {
      const ProductCell c = decode_product_cell(data, static_cast<std::size_t>(iy) * static_cast<std::size_t>(sx) +
                                                          static_cast<std::size_t>(ix));
      std::uint8_t rgb[3];
      colour(c, lo, hi, rgb);
      for (int py = 0; py < s; ++py) {
        for (int px = 0; px < s; ++px) image.set(ix * s + px, (sy - 1 - iy) * s + py, rgb);  // north up
      }
    }
  }
  return write_png(path, image, error);
}

void class_rgb(const ProductCell& c, float, float, std::uint8_t* rgb) {
  class_colour(to_string(static_cast<CellClass>(c.cell_class <= 4U ? c.cell_class : 0U)), rgb);
}
void cost_rgb(const ProductCell& c, float, float, std::uint8_t* rgb) {
  rgb[0] = rgb[1] = rgb[2] = c.cost;
}
void height_rgb(const ProductCell& c, float lo, float hi, std::uint8_t* rgb) {
  if (c.status != static_cast<std::uint8_t>(Status::kOk)) {
    rgb[0] = rgb[1] = rgb[2] = 0U;
    return;
  }
  colormap_viridis(hi > lo ? (static_cast<double>(c.height_m) - lo) / (static_cast<double>(hi) - lo) : 0.5, rgb);
}

}  // namespace

int view_product(const std::string& path, bool cells, const std::string& png_prefix, std::ostream& out,
                 std::string* error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *error = "cannot read '" + path + "'";
    return 1;
  }
  const std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ProductHeader h{};
  const Status status = decode_product_header(data.data(), data.size(), &h);
  if (status != Status::kOk) {
    *error = "'" + path + "' is not a whole map product (" + to_string(status) + ")";
    return 1;
  }
  out << "version " << h.version << "\ntotal_bytes " << h.total_bytes << "\nproduct_sequence " << h.product_sequence
      << "\nmap_sequence " << h.map_sequence << "\nparams_crc " << h.params_crc << "\npreset " << h.preset
      << "\nlayer " << h.layer << "\nanswer " << (h.answer == 0U ? "stack" : "layer") << "\nside_x " << h.side_x
      << "\nside_y " << h.side_y << "\ncell_width_m " << h.cell_width_m << "\nmin_index_x " << h.min_index_x
      << "\nmin_index_y " << h.min_index_y << "\nmin_corner_x_m " << h.min_corner_x_m << "\nmin_corner_y_m "
      << h.min_corner_y_m << "\ncentre_x_m " << h.centre_x_m << "\ncentre_y_m " << h.centre_y_m << "\npose_x "
      << h.pose_x << "\npose_y " << h.pose_y << "\npose_z " << h.pose_z << "\npose_yaw " << h.pose_yaw << "\ntag "
      << h.tag << "\n";
  const std::size_t count = std::size_t{h.side_x} * h.side_y;
  std::size_t per_class[5] = {0, 0, 0, 0, 0};
  std::size_t known = 0U;
  float lo = INFINITY, hi = -INFINITY;
  for (std::size_t i = 0; i < count; ++i) {
    const ProductCell c = decode_product_cell(data.data(), i);
    per_class[c.cell_class <= 4U ? c.cell_class : 0U] += 1U;
    if (c.status == static_cast<std::uint8_t>(Status::kOk)) {
      ++known;
      lo = std::min(lo, c.height_m);
      hi = std::max(hi, c.height_m);
    }
  }
  out << "cells " << count << "\nknown " << known;
  for (int k = 0; k < 5; ++k) out << "\nclass_" << to_string(static_cast<CellClass>(k)) << " " << per_class[k];
  out << "\n";
  if (cells) {
    out << "ix iy class cost status layer height_m inclination\n";
    for (std::size_t i = 0; i < count; ++i) {
      const ProductCell c = decode_product_cell(data.data(), i);
      out << h.min_index_x + static_cast<std::int32_t>(i % h.side_x) << " "
          << h.min_index_y + static_cast<std::int32_t>(i / h.side_x) << " "
          << to_string(static_cast<CellClass>(c.cell_class <= 4U ? c.cell_class : 0U)) << " " << int{c.cost} << " "
          << to_string(static_cast<Status>(c.status <= static_cast<std::uint8_t>(Status::kBusy) ? c.status : 6U))
          << " " << (c.layer == kProductNoLayer ? -1 : int{c.layer}) << " " << c.height_m << " " << c.inclination
          << "\n";
    }
  }
  if (!png_prefix.empty()) {
    if (!write_picture(png_prefix + "_class.png", h, data.data(), &class_rgb, lo, hi, error) ||
        !write_picture(png_prefix + "_cost.png", h, data.data(), &cost_rgb, lo, hi, error) ||
        !write_picture(png_prefix + "_height.png", h, data.data(), &height_rgb, lo, hi, error)) {
      return 1;
    }
  }
  return 0;
}

}  // namespace ccmap::tools
