#include "traverse/dropoff_truth.hpp"

#include <algorithm>

#include "traverse/ghosts.hpp"

namespace ccmap::traverse {

DropoffTruth::DropoffTruth(double x0, double x1, double y0, double y1, const std::vector<double>& widths_m,
                           const std::vector<double>& steps_m)
    : x0_(x0), x1_(x1), y0_(y0), y1_(y1) {
  for (std::size_t k = 0; k < widths_m.size() && k < steps_m.size(); ++k) {
    Layer l;
    l.width_m = widths_m[k];
    l.step_m = steps_m[k];
    l.i0 = static_cast<std::int64_t>(std::ceil(x0 / l.width_m));
    l.j0 = static_cast<std::int64_t>(std::ceil(y0 / l.width_m));
    l.ni = std::max(0, static_cast<int>(static_cast<std::int64_t>(std::floor(x1 / l.width_m)) - l.i0));
    l.nj = std::max(0, static_cast<int>(static_cast<std::int64_t>(std::floor(y1 / l.width_m)) - l.j0));
    const std::size_t n = static_cast<std::size_t>(l.ni) * static_cast<std::size_t>(l.nj);
    l.hit.assign(n, 0);
    l.below.assign(n, std::numeric_limits<double>::infinity());
    layers_.push_back(std::move(l));
  }
}

void DropoffTruth::add_point(double x, double y) {
  for (Layer& l : layers_) {
    const std::int64_t i = static_cast<std::int64_t>(std::floor(x / l.width_m)) - l.i0;
    const std::int64_t j = static_cast<std::int64_t>(std::floor(y / l.width_m)) - l.j0;
    if (i < 0 || j < 0 || i >= l.ni || j >= l.nj) continue;
    l.hit[static_cast<std::size_t>(j) * static_cast<std::size_t>(l.ni) + static_cast<std::size_t>(i)] = 1;
  }
}

namespace {

/// Liang-Barsky: narrows [*t0, *t1] to where p + t d lies within [lo, hi] on one axis; false if empty.
bool clip_axis(double p, double d, double lo, double hi, double* t0, double* t1) {
  if (d == 0.0) return p >= lo && p <= hi;
  double a = (lo - p) / d, b = (hi - p) / d;
  if (a > b) std::swap(a, b);
  *t0 = std::max(*t0, a);
  *t1 = std::min(*t1, b);
  return *t0 < *t1;
}

}  // namespace

void DropoffTruth::add_ray(const sim::Point3& from, const sim::Point3& to, double rim_ground_m) {
  const double dx = to.x - from.x, dy = to.y - from.y, dz = to.z - from.z;
  double r0 = 0.0, r1 = 1.0;
  if (!clip_axis(from.x, dx, x0_, x1_, &r0, &r1) || !clip_axis(from.y, dy, y0_, y1_, &r0, &r1)) return;
  for (Layer& l : layers_) {
    const double w = l.width_m;
    // The cells the clipped stretch's bounding box touches; each is clipped exactly below.
    const double xa = from.x + r0 * dx, xb = from.x + r1 * dx, ya = from.y + r0 * dy, yb = from.y + r1 * dy;
    const std::int64_t ia = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::floor(std::min(xa, xb) / w)) - l.i0);
    const std::int64_t ib = std::min<std::int64_t>(l.ni - 1, static_cast<std::int64_t>(std::floor(std::max(xa, xb) / w)) - l.i0);
    const std::int64_t ja = std::max<std::int64_t>(0, static_cast<std::int64_t>(std::floor(std::min(ya, yb) / w)) - l.j0);
    const std::int64_t jb = std::min<std::int64_t>(l.nj - 1, static_cast<std::int64_t>(std::floor(std::max(ya, yb) / w)) - l.j0);
    for (std::int64_t j = ja; j <= jb; ++j) {
      for (std::int64_t i = ia; i <= ib; ++i) {
        double t0 = r0, t1 = r1;
        const double cx0 = static_cast<double>(l.i0 + i) * w, cy0 = static_cast<double>(l.j0 + j) * w;
        if (!clip_axis(from.x, dx, cx0, cx0 + w, &t0, &t1) || !clip_axis(from.y, dy, cy0, cy0 + w, &t0, &t1)) continue;
        const double low = std::min(from.z + t0 * dz, from.z + t1 * dz) - rim_ground_m;
        double& b = l.below[static_cast<std::size_t>(j) * static_cast<std::size_t>(l.ni) + static_cast<std::size_t>(i)];
        b = std::min(b, low);
      }
    }
  }
}

double rim_ground(const sim::HeightRaster& raster, const sim::Point3& from, const sim::Point3& to, double rim_x) {
  constexpr double kHalf = 0.1, kStep = 0.005;
  const double dx = to.x - from.x;
  if (!(std::fabs(dx) > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double xa = std::max(std::min(from.x, to.x), rim_x - kHalf), xb = std::min(std::max(from.x, to.x), rim_x + kHalf);
  if (!(xa <= xb)) return std::numeric_limits<double>::quiet_NaN();
  double best = -std::numeric_limits<double>::infinity();
  const int n = static_cast<int>(std::ceil((xb - xa) / kStep));
  for (int s = 0; s <= n; ++s) {
    const double x = std::min(xb, xa + s * kStep);
    const double y = from.y + (x - from.x) / dx * (to.y - from.y);
    best = std::max(best, raster.height(x, y));
  }
  return best;
}

bool truly_deep(const sim::HeightRaster& raster, double rim_x, double x0, double y0, double w, double step_m) {
  const double yc = y0 + 0.5 * w;
  const double g = rim_ground(raster, sim::Point3{rim_x - 0.1, yc, 0.0}, sim::Point3{rim_x + 0.1, yc, 0.0}, rim_x);
  const int n = std::max(1, static_cast<int>(std::lround(w / 0.01)));
  for (int b = 0; b <= n; ++b) {
    for (int a = 0; a <= n; ++a) {
      if (raster.height(x0 + w * a / n, y0 + w * b / n) >= g - step_m) return false;
    }
  }
  return true;
}

void log_truth_row(std::FILE* log, const std::string& name, const DropTruthRow& row) {
  std::fprintf(log, "drop-off truth: %s, rim %.1f m: hidden %d, provable %d, answered drop %d, drop not provable %d (truly deep %d, seen %d)\n",
               name.c_str(), row.range_m, row.hidden, row.provable, row.answered, row.drop_not_provable,
               row.not_provable_deep, row.not_provable_seen);
}

std::string drop_truth_report(const std::vector<DropCase>& cases) {
  using experiments::format;
  std::string s =
      "\nDrop-offs against the reference (dropoff_truth.hpp): the walk layers' cells of the 0.6 m swath from 0.5 m\n"
      "before the rim to 0.5 m beyond the far edge; provable = hidden and passed over by a line of sight more than\n"
      "the layer's step below its rim ground; answered = of them the stack query answers drop-off\n\n";
  experiments::Table t({"obstacle", "rim at", "hidden", "provable (4/8/16/32 cm)", "answered drop (4/8/16/32 cm)",
                        "share", "drop not provable (truly deep, seen)"});
  for (const DropCase& dc : cases) {
    for (const DropTruthRow& r : dc.truth) {
      bool listed = false;
      for (double at : {2.0, 1.5, 1.2, 0.9, 0.6, 0.3}) listed = listed || std::fabs(r.range_m - at) < 0.05;
      if (!listed) continue;
      t.add_row({dc.name, format("%.1f m", r.range_m), format("%d", r.hidden),
                 format("%d (%d/%d/%d/%d)", r.provable, r.provable_by_layer[0], r.provable_by_layer[1],
                        r.provable_by_layer[2], r.provable_by_layer[3]),
                 format("%d (%d/%d/%d/%d)", r.answered, r.answered_by_layer[0], r.answered_by_layer[1],
                        r.answered_by_layer[2], r.answered_by_layer[3]),
                 r.provable > 0 ? format("%.0f %%", 100.0 * r.answered / r.provable) : "-",
                 format("%d (%d, %d)", r.drop_not_provable, r.not_provable_deep, r.not_provable_seen)});
    }
  }
  return s + t.str();
}

}  // namespace ccmap::traverse
