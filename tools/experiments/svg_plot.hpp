// Tiny SVG line-plot writer for the experiment figures: axes with "nice" ticks, axis labels,
// a title, several series (lines, optional markers, dashed), reference lines and a legend.
// No dependencies; the output is a standalone .svg file.
#pragma once

#include <limits>
#include <string>
#include <vector>

namespace ccmap::experiments {

struct SvgSeries {
  std::string name;           ///< legend entry (empty: not in the legend)
  std::vector<double> x, y;   ///< same length; non-finite points break the line
  std::string color;          ///< CSS colour; empty = palette colour by index
  bool dashed = false;
  bool markers = false;
  double line_width = 2.0;
  bool dotted = false;  ///< drawn dotted (wins over dashed)
};

/// Horizontal (vertical = false: y = value) or vertical (x = value) reference line.
struct SvgRefLine {
  double value = 0.0;
  bool vertical = false;
  std::string label;
  std::string color = "#777777";
};

struct SvgPlot {
  std::string title, x_label, y_label;
  std::vector<SvgSeries> series;
  std::vector<SvgRefLine> ref_lines;
  int width_px = 760, height_px = 500;
  /// Axis ranges; NaN = from the data (padded to nice ticks).
  double x_min = std::numeric_limits<double>::quiet_NaN(), x_max = std::numeric_limits<double>::quiet_NaN();
  double y_min = std::numeric_limits<double>::quiet_NaN(), y_max = std::numeric_limits<double>::quiet_NaN();
  double x_scale = 1.0, y_scale = 1.0;  ///< tick labels show value * scale (e.g. 100 for %)
};

/// Round tick positions covering [lo, hi], about `target` of them (steps 1, 2, 5 x 10^k).
std::vector<double> nice_ticks(double lo, double hi, int target = 6);

/// Palette colour i (cycled).
const char* palette_color(int i);

std::string render_svg(const SvgPlot& plot);

/// Writes render_svg(plot) to path; false with a reason in *error.
bool write_svg(const std::string& path, const SvgPlot& plot, std::string* error = nullptr);

}  // namespace ccmap::experiments
