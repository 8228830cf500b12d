// Annotated raster figures for the experiments and the traverse demo: a built-in 5 x 7 pixel
// font (upper case, digits, common punctuation; lower case is drawn as upper case), lines,
// rectangles, colour bars, a scale bar and a north arrow on a tools::RgbImage.
//
// Coordinates are image pixels (x right, y down, row 0 at the top). Drawing outside the image
// is clipped. No dependencies beyond png.hpp; host only.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "png.hpp"

namespace ccmap::experiments {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

inline constexpr Rgb kBlack{0, 0, 0};
inline constexpr Rgb kWhite{255, 255, 255};

/// Width in pixels of `text` drawn at `scale` (each glyph 6 * scale wide including spacing).
int text_width(const std::string& text, int scale = 1);
/// Glyph height in pixels at `scale` (7 * scale).
inline int text_height(int scale = 1) { return 7 * scale; }

/// Draws `text` with its top-left corner at (x, y). Unknown characters are drawn as '?'.
void draw_text(tools::RgbImage& img, int x, int y, const std::string& text, Rgb colour, int scale = 1);

void fill_rect(tools::RgbImage& img, int x, int y, int w, int h, Rgb colour);
void draw_rect(tools::RgbImage& img, int x, int y, int w, int h, Rgb colour, int thickness = 1);
/// Line from (x0, y0) to (x1, y1) in pixel coordinates (may be fractional), `thickness` px.
void draw_line(tools::RgbImage& img, double x0, double y0, double x1, double y1, Rgb colour, int thickness = 1);
void fill_disc(tools::RgbImage& img, double cx, double cy, double radius, Rgb colour);

/// Copies `src` into `dst` with src's top-left pixel at (x, y).
void blit(tools::RgbImage& dst, const tools::RgbImage& src, int x, int y);
/// Nearest-neighbour upscale by an integer factor.
tools::RgbImage upscale(const tools::RgbImage& src, int factor);

/// Horizontal colour bar of w x h pixels at (x, y): colour(t) for t in [0, 1] from left to
/// right, framed, with `lo_label` under its left end, `hi_label` under its right end and
/// `title` above it.
void colour_bar(tools::RgbImage& img, int x, int y, int w, int h, const std::function<Rgb(double)>& colour,
                const std::string& lo_label, const std::string& hi_label, const std::string& title);

/// Legend entry: a swatch and its label; returns the x just after the label (+ a gap).
int legend_entry(tools::RgbImage& img, int x, int y, Rgb swatch, const std::string& label, int scale = 1);

/// Scale bar of `metres` at `pixels_per_m`, left end at (x, y) (bar top), labelled "<metres> M".
void scale_bar(tools::RgbImage& img, int x, int y, double pixels_per_m, double metres, Rgb colour);

/// Small north arrow ("N" above an upward arrow) with its top at (x, y).
void north_arrow(tools::RgbImage& img, int x, int y, Rgb colour);

/// Colour maps as Rgb (wrappers of png.hpp's).
Rgb viridis(double t);
Rgb diverging(double t);

}  // namespace ccmap::experiments
