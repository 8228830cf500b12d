#include "experiments/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace ccmap::experiments {

namespace {

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f", v);
  return b;
}

std::string tick_label(double v, double step) {
  char b[32];
  const int decimals = step >= 1.0 ? 0 : std::min(6, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  if (std::fabs(v) < 1e-12 * std::max(1.0, step)) v = 0.0;
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target) {
  std::vector<double> ticks;
  if (!std::isfinite(lo) || !std::isfinite(hi)) return ticks;
  if (hi <= lo) hi = lo + 1.0;
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * mag;
    if (step >= raw) break;
  }
  const double start = std::floor(lo / step + 1e-9) * step;
  for (double t = start; t <= hi + step * 1e-9; t += step) {
    if (t >= lo - step * 1e-9) ticks.push_back(t);
  }
  return ticks;
}

const char* palette_color(int i) {
  static const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#17becf", "#7f7f7f"};
  return kColors[((i % 8) + 8) % 8];
}

std::string render_svg(const SvgPlot& p) {
  double x0 = p.x_min, x1 = p.x_max, y0 = p.y_min, y1 = p.y_max;
  double dx0 = 1e300, dx1 = -1e300, dy0 = 1e300, dy1 = -1e300;
  for (const SvgSeries& s : p.series) {
    for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
      dx0 = std::min(dx0, s.x[k]);
      dx1 = std::max(dx1, s.x[k]);
      dy0 = std::min(dy0, s.y[k]);
      dy1 = std::max(dy1, s.y[k]);
    }
  }
  for (const SvgRefLine& r : p.ref_lines) {
    if (r.vertical) { dx0 = std::min(dx0, r.value); dx1 = std::max(dx1, r.value); }
    else { dy0 = std::min(dy0, r.value); dy1 = std::max(dy1, r.value); }
  }
  if (dx0 > dx1) { dx0 = 0.0; dx1 = 1.0; }
  if (dy0 > dy1) { dy0 = 0.0; dy1 = 1.0; }
  if (!std::isfinite(x0)) x0 = dx0;
  if (!std::isfinite(x1)) x1 = dx1;
  if (!std::isfinite(y0)) y0 = dy0;
  if (!std::isfinite(y1)) y1 = dy1;
  if (x1 <= x0) x1 = x0 + 1.0;
  if (y1 <= y0) y1 = y0 + 1.0;
  std::vector<double> xt = nice_ticks(x0, x1), yt = nice_ticks(y0, y1);
  // Extend automatic ranges to the enclosing ticks.
  if (!std::isfinite(p.y_min) || !std::isfinite(p.y_max)) {
    const std::vector<double> t = nice_ticks(y0, y1);
    if (t.size() >= 2) {
      const double step = t[1] - t[0];
      if (!std::isfinite(p.y_min)) y0 = std::floor(y0 / step + 1e-9) * step;
      if (!std::isfinite(p.y_max)) y1 = std::ceil(y1 / step - 1e-9) * step;
      yt = nice_ticks(y0, y1);
    }
  }
  const double ml = 78, mr = 24, mt = 42, mb = 58;
  const double pw = p.width_px - ml - mr, ph = p.height_px - mt - mb;
  auto sx = [&](double v) { return ml + (v - x0) / (x1 - x0) * pw; };
  auto sy = [&](double v) { return mt + (1.0 - (v - y0) / (y1 - y0)) * ph; };
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << p.width_px << "\" height=\"" << p.height_px
    << "\" viewBox=\"0 0 " << p.width_px << ' ' << p.height_px << "\" font-family=\"Helvetica, Arial, sans-serif\">\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << "<text x=\"" << fmt(ml + pw / 2) << "\" y=\"24\" text-anchor=\"middle\" font-size=\"16\">" << escape(p.title) << "</text>\n";
  // Grid and ticks.
  const double xstep = xt.size() >= 2 ? xt[1] - xt[0] : 1.0, ystep = yt.size() >= 2 ? yt[1] - yt[0] : 1.0;
  for (double t : xt) {
    if (t < x0 - 1e-12 || t > x1 + 1e-12) continue;
    o << "<line x1=\"" << fmt(sx(t)) << "\" y1=\"" << fmt(mt) << "\" x2=\"" << fmt(sx(t)) << "\" y2=\"" << fmt(mt + ph)
      << "\" stroke=\"#e5e5e5\"/>\n";
    o << "<text x=\"" << fmt(sx(t)) << "\" y=\"" << fmt(mt + ph + 18) << "\" text-anchor=\"middle\" font-size=\"12\">"
      << tick_label(t * p.x_scale, xstep * p.x_scale) << "</text>\n";
  }
  for (double t : yt) {
    if (t < y0 - 1e-12 || t > y1 + 1e-12) continue;
    o << "<line x1=\"" << fmt(ml) << "\" y1=\"" << fmt(sy(t)) << "\" x2=\"" << fmt(ml + pw) << "\" y2=\"" << fmt(sy(t))
      << "\" stroke=\"#e5e5e5\"/>\n";
    o << "<text x=\"" << fmt(ml - 8) << "\" y=\"" << fmt(sy(t) + 4) << "\" text-anchor=\"end\" font-size=\"12\">"
      << tick_label(t * p.y_scale, ystep * p.y_scale) << "</text>\n";
  }
  o << "<rect x=\"" << fmt(ml) << "\" y=\"" << fmt(mt) << "\" width=\"" << fmt(pw) << "\" height=\"" << fmt(ph)
    << "\" fill=\"none\" stroke=\"black\"/>\n";
  o << "<text x=\"" << fmt(ml + pw / 2) << "\" y=\"" << fmt(p.height_px - 14.0) << "\" text-anchor=\"middle\" font-size=\"14\">"
    << escape(p.x_label) << "</text>\n";
  o << "<text transform=\"translate(18," << fmt(mt + ph / 2) << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"14\">"
    << escape(p.y_label) << "</text>\n";
  o << "<clipPath id=\"plot\"><rect x=\"" << fmt(ml) << "\" y=\"" << fmt(mt) << "\" width=\"" << fmt(pw) << "\" height=\""
    << fmt(ph) << "\"/></clipPath>\n<g clip-path=\"url(#plot)\">\n";
  for (const SvgRefLine& r : p.ref_lines) {
    if (r.vertical) {
      o << "<line x1=\"" << fmt(sx(r.value)) << "\" y1=\"" << fmt(mt) << "\" x2=\"" << fmt(sx(r.value)) << "\" y2=\""
        << fmt(mt + ph) << "\" stroke=\"" << r.color << "\" stroke-dasharray=\"4,3\"/>\n";
      o << "<text x=\"" << fmt(sx(r.value) + 4) << "\" y=\"" << fmt(mt + 14) << "\" font-size=\"11\" fill=\"" << r.color
        << "\">" << escape(r.label) << "</text>\n";
    } else {
      o << "<line x1=\"" << fmt(ml) << "\" y1=\"" << fmt(sy(r.value)) << "\" x2=\"" << fmt(ml + pw) << "\" y2=\""
        << fmt(sy(r.value)) << "\" stroke=\"" << r.color << "\" stroke-dasharray=\"4,3\"/>\n";
      o << "<text x=\"" << fmt(ml + 6) << "\" y=\"" << fmt(sy(r.value) - 4) << "\" font-size=\"11\" fill=\"" << r.color
        << "\">" << escape(r.label) << "</text>\n";
    }
  }
  for (std::size_t i = 0; i < p.series.size(); ++i) {
    const SvgSeries& s = p.series[i];
    const std::string color = s.color.empty() ? palette_color(static_cast<int>(i)) : s.color;
    std::string path;
    bool pen_down = false;
    for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k) {
      if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) {
        pen_down = false;
        continue;
      }
      path += (pen_down ? " L" : " M") + fmt(sx(s.x[k])) + "," + fmt(sy(s.y[k]));
      pen_down = true;
    }
    o << "<path d=\"" << path << "\" fill=\"none\" stroke=\"" << color << "\" stroke-width=\"" << fmt(s.line_width) << "\""
      << (s.dotted ? " stroke-dasharray=\"2,3\"" : (s.dashed ? " stroke-dasharray=\"7,4\"" : "")) << "/>\n";
    if (s.markers) {
      for (std::size_t k = 0; k < std::min(s.x.size(), s.y.size()); ++k) {
        if (!std::isfinite(s.x[k]) || !std::isfinite(s.y[k])) continue;
        o << "<circle cx=\"" << fmt(sx(s.x[k])) << "\" cy=\"" << fmt(sy(s.y[k])) << "\" r=\"3\" fill=\"" << color << "\"/>\n";
      }
    }
  }
  o << "</g>\n";
  // Legend (top right, inside the plot).
  int entries = 0;
  for (const SvgSeries& s : p.series) entries += s.name.empty() ? 0 : 1;
  if (entries > 0) {
    std::size_t longest = 0;
    for (const SvgSeries& s : p.series) longest = std::max(longest, s.name.size());
    const double lw = 44 + 6.6 * static_cast<double>(longest), lh = 8 + 18.0 * entries;
    const double lx = ml + pw - lw - 8, ly = mt + 8;
    o << "<rect x=\"" << fmt(lx) << "\" y=\"" << fmt(ly) << "\" width=\"" << fmt(lw) << "\" height=\"" << fmt(lh)
      << "\" fill=\"white\" fill-opacity=\"0.9\" stroke=\"#999999\"/>\n";
    int row = 0;
    for (std::size_t i = 0; i < p.series.size(); ++i) {
      const SvgSeries& s = p.series[i];
      if (s.name.empty()) continue;
      const std::string color = s.color.empty() ? palette_color(static_cast<int>(i)) : s.color;
      const double y = ly + 16 + 18.0 * row++;
      o << "<line x1=\"" << fmt(lx + 8) << "\" y1=\"" << fmt(y - 4) << "\" x2=\"" << fmt(lx + 34) << "\" y2=\"" << fmt(y - 4)
        << "\" stroke=\"" << color << "\" stroke-width=\"" << fmt(s.line_width) << "\""
        << (s.dotted ? " stroke-dasharray=\"2,3\"" : (s.dashed ? " stroke-dasharray=\"7,4\"" : "")) << "/>\n";
      o << "<text x=\"" << fmt(lx + 40) << "\" y=\"" << fmt(y) << "\" font-size=\"12\">" << escape(s.name) << "</text>\n";
    }
  }
  o << "</svg>\n";
  return o.str();
}

bool write_svg(const std::string& path, const SvgPlot& plot, std::string* error) {
  std::ofstream out(path);
  if (!out) {
    if (error != nullptr) *error = "cannot open " + path + " for writing";
    return false;
  }
  out << render_svg(plot);
  out.close();
  if (!out) {
    if (error != nullptr) *error = "cannot write " + path;
    return false;
  }
  return true;
}

}  // namespace ccmap::experiments
