#include "experiments/canvas.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

namespace ccmap::experiments {

namespace {

struct Glyph {
  char c;
  std::uint8_t rows[7];  ///< 5 bits per row, bit 4 = leftmost pixel
};

// Classic 5 x 7 pixel font, row-major.
constexpr Glyph kFont[] = {
    {' ', {0, 0, 0, 0, 0, 0, 0}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x1E}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x0A, 0x04, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0, 0, 0, 0, 0, 0x0C, 0x0C}},
    {',', {0, 0, 0, 0, 0x0C, 0x04, 0x08}},
    {':', {0, 0x0C, 0x0C, 0, 0x0C, 0x0C, 0}},
    {';', {0, 0x0C, 0x0C, 0, 0x0C, 0x04, 0x08}},
    {'-', {0, 0, 0, 0x1F, 0, 0, 0}},
    {'+', {0, 0x04, 0x04, 0x1F, 0x04, 0x04, 0}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'/', {0, 0x01, 0x02, 0x04, 0x08, 0x10, 0}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'[', {0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E}},
    {']', {0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E}},
    {'=', {0, 0, 0x1F, 0, 0x1F, 0, 0}},
    {'_', {0, 0, 0, 0, 0, 0, 0x1F}},
    {'\'', {0x04, 0x04, 0x08, 0, 0, 0, 0}},
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},
    {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},
    {'^', {0x04, 0x0A, 0x11, 0, 0, 0, 0}},
    {'|', {0x04, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'#', {0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A}},
    {'*', {0, 0x04, 0x15, 0x0E, 0x15, 0x04, 0}},
    {'?', {0x0E, 0x11, 0x01, 0x02, 0x04, 0, 0x04}},
    {'!', {0x04, 0x04, 0x04, 0x04, 0x04, 0, 0x04}},
    {'~', {0, 0, 0x08, 0x15, 0x02, 0, 0}},
};

const Glyph& glyph(char c) {
  const char u = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  for (const Glyph& g : kFont) {
    if (g.c == u) return g;
  }
  for (const Glyph& g : kFont) {
    if (g.c == '?') return g;
  }
  return kFont[0];
}

void put(tools::RgbImage& img, int x, int y, Rgb c) {
  const std::uint8_t v[3] = {c.r, c.g, c.b};
  img.set(x, y, v);
}

}  // namespace

int text_width(const std::string& text, int scale) {
  return text.empty() ? 0 : static_cast<int>(text.size()) * 6 * scale - scale;
}

void draw_text(tools::RgbImage& img, int x, int y, const std::string& text, Rgb colour, int scale) {
  int pen = x;
  for (char ch : text) {
    const Glyph& g = glyph(ch);
    for (int r = 0; r < 7; ++r) {
      for (int c = 0; c < 5; ++c) {
        if ((g.rows[r] >> (4 - c)) & 1U) fill_rect(img, pen + c * scale, y + r * scale, scale, scale, colour);
      }
    }
    pen += 6 * scale;
  }
}

void fill_rect(tools::RgbImage& img, int x, int y, int w, int h, Rgb colour) {
  const int x0 = std::max(0, x), y0 = std::max(0, y);
  const int x1 = std::min(img.width, x + w), y1 = std::min(img.height, y + h);
  for (int yy = y0; yy < y1; ++yy)
    for (int xx = x0; xx < x1; ++xx) put(img, xx, yy, colour);
}

void draw_rect(tools::RgbImage& img, int x, int y, int w, int h, Rgb colour, int thickness) {
  fill_rect(img, x, y, w, thickness, colour);
  fill_rect(img, x, y + h - thickness, w, thickness, colour);
  fill_rect(img, x, y, thickness, h, colour);
  fill_rect(img, x + w - thickness, y, thickness, h, colour);
}

void draw_line(tools::RgbImage& img, double x0, double y0, double x1, double y1, Rgb colour, int thickness) {
  const double len = std::hypot(x1 - x0, y1 - y0);
  const int steps = std::max(1, static_cast<int>(std::ceil(len * 2.0)));
  const double r = 0.5 * thickness;
  for (int s = 0; s <= steps; ++s) {
    const double t = static_cast<double>(s) / steps;
    const double x = x0 + t * (x1 - x0), y = y0 + t * (y1 - y0);
    if (thickness <= 1) {
      put(img, static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y)), colour);
    } else {
      fill_disc(img, x, y, r, colour);
    }
  }
}

void fill_disc(tools::RgbImage& img, double cx, double cy, double radius, Rgb colour) {
  const int x0 = static_cast<int>(std::floor(cx - radius)), x1 = static_cast<int>(std::ceil(cx + radius));
  const int y0 = static_cast<int>(std::floor(cy - radius)), y1 = static_cast<int>(std::ceil(cy + radius));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
      if (dx * dx + dy * dy <= radius * radius) put(img, x, y, colour);
    }
}

void blit(tools::RgbImage& dst, const tools::RgbImage& src, int x, int y) {
  for (int r = 0; r < src.height; ++r)
    for (int c = 0; c < src.width; ++c) {
      const std::size_t o = 3U * (static_cast<std::size_t>(r) * static_cast<std::size_t>(src.width) + static_cast<std::size_t>(c));
      dst.set(x + c, y + r, &src.rgb[o]);
    }
}

tools::RgbImage upscale(const tools::RgbImage& src, int factor) {
  factor = std::max(1, factor);
  tools::RgbImage out(src.width * factor, src.height * factor, 0);
  for (int r = 0; r < out.height; ++r)
    for (int c = 0; c < out.width; ++c) {
      const std::size_t o = 3U * (static_cast<std::size_t>(r / factor) * static_cast<std::size_t>(src.width) +
                                  static_cast<std::size_t>(c / factor));
      out.set(c, r, &src.rgb[o]);
    }
  return out;
}

void colour_bar(tools::RgbImage& img, int x, int y, int w, int h, const std::function<Rgb(double)>& colour,
                const std::string& lo_label, const std::string& hi_label, const std::string& title) {
  draw_text(img, x, y - 11, title, kBlack);
  for (int i = 0; i < w; ++i) fill_rect(img, x + i, y, 1, h, colour((i + 0.5) / w));
  draw_rect(img, x - 1, y - 1, w + 2, h + 2, kBlack);
  draw_text(img, x, y + h + 4, lo_label, kBlack);
  draw_text(img, x + w - text_width(hi_label), y + h + 4, hi_label, kBlack);
}

int legend_entry(tools::RgbImage& img, int x, int y, Rgb swatch, const std::string& label, int scale) {
  const int s = 7 * scale + 2;
  fill_rect(img, x, y - 1, s, s, swatch);
  draw_rect(img, x, y - 1, s, s, kBlack);
  draw_text(img, x + s + 4, y, label, kBlack, scale);
  return x + s + 4 + text_width(label, scale) + 12;
}

void scale_bar(tools::RgbImage& img, int x, int y, double pixels_per_m, double metres, Rgb colour) {
  const int len = static_cast<int>(std::lround(pixels_per_m * metres));
  fill_rect(img, x, y, len, 3, colour);
  fill_rect(img, x, y - 4, 2, 10, colour);
  fill_rect(img, x + len - 2, y - 4, 2, 10, colour);
  char label[32];
  std::snprintf(label, sizeof label, "%g M", metres);
  draw_text(img, x + len / 2 - text_width(label) / 2, y + 9, label, colour);
}

void north_arrow(tools::RgbImage& img, int x, int y, Rgb colour) {
  draw_text(img, x - 2, y, "N", colour);
  draw_line(img, x + 0.5, y + 10, x + 0.5, y + 30, colour, 2);
  draw_line(img, x + 0.5, y + 10, x - 4.5, y + 17, colour, 2);
  draw_line(img, x + 0.5, y + 10, x + 5.5, y + 17, colour, 2);
}

Rgb viridis(double t) {
  std::uint8_t c[3];
  tools::colormap_viridis(t, c);
  return Rgb{c[0], c[1], c[2]};
}

Rgb diverging(double t) {
  std::uint8_t c[3];
  tools::colormap_diverging(t, c);
  return Rgb{c[0], c[1], c[2]};
}

}  // namespace ccmap::experiments
