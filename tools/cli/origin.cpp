#include "origin.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ccmap/cell/ccm_cell.hpp"

namespace ccmap::tools {
namespace {

bool within_world(double x, double y, double z) {
  return std::fabs(x) <= kMaxAbsWorldCoordinateM && std::fabs(y) <= kMaxAbsWorldCoordinateM &&
         std::fabs(z) <= kMaxAbsWorldCoordinateM;
}

/// Median of v (upper median for an even count); v is reordered. Precondition: !v.empty().
double median(std::vector<double>& v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

/// Per-axis medians of the qualifying points; false if none qualifies.
template <typename Accept>
bool axis_medians(const std::vector<const Cloud*>& clouds, Accept accept, double out[3]) {
  std::vector<double> axis[3];
  for (const Cloud* c : clouds) {
    for (std::size_t i = 0; i < c->size(); ++i) {
      if (accept(c->x[i], c->y[i], c->z[i])) {
        axis[0].push_back(c->x[i]);
        axis[1].push_back(c->y[i]);
        axis[2].push_back(c->z[i]);
      }
    }
  }
  if (axis[0].empty()) return false;
  for (int a = 0; a < 3; ++a) out[a] = median(axis[a]);
  return true;
}

}  // namespace

bool robust_origin(const std::vector<const Cloud*>& clouds, const AreaBounds& bounds, double coarsest_width,
                   LocalOrigin* origin, std::string* error) {
  if (!(coarsest_width > 0.0) || !std::isfinite(coarsest_width)) {
    *error = "internal: coarsest cell width must be positive";
    return false;
  }
  double guess[3] = {0.0, 0.0, 0.0};
  const bool any = axis_medians(
      clouds, [&](double x, double y, double z) { return within_world(x, y, z) && bounds.contains(x, y); }, guess);
  if (!any) {
    *error = bounds.set ? "no point inside --bounds (within +-1e9 m)"
                        : "no point with coordinates within +-1e9 m: nothing to map";
    return false;
  }
  const double range = static_cast<double>(kMaxAbsCoordinateM);
  double centre[3] = {guess[0], guess[1], guess[2]};
  (void)axis_medians(
      clouds,
      [&](double x, double y, double z) {
        return within_world(x, y, z) && bounds.contains(x, y) && std::fabs(x - guess[0]) <= range &&
               std::fabs(y - guess[1]) <= range && std::fabs(z - guess[2]) <= range;
      },
      centre);
  origin->coarsest_width = coarsest_width;
  for (int a = 0; a < 3; ++a) {
    // |centre| <= 1e9 m and coarsest_width >= 0.19 mm (the library's smallest finest cell):
    // the quotient stays below 2^43, exact in double and in int64.
    origin->cells[a] = std::llround(centre[a] / coarsest_width);
    origin->xyz[a] = static_cast<double>(origin->cells[a]) * coarsest_width;
  }
  return true;
}

float weight_to_float(double w) {
  constexpr double kMax = static_cast<double>(std::numeric_limits<float>::max());
  if (std::fabs(w) <= kMax || std::isnan(w)) return static_cast<float>(w);
  return w > 0.0 ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity();
}

PointFate classify_point(double x, double y, double z, const LocalOrigin& origin, const AreaBounds& bounds) {
  if (!within_world(x, y, z)) return PointFate::kOutOfRange;
  const double range = static_cast<double>(kMaxAbsCoordinateM);
  if (!(std::fabs(x - origin.xyz[0]) <= range && std::fabs(y - origin.xyz[1]) <= range &&
        std::fabs(z - origin.xyz[2]) <= range)) {
    return PointFate::kOutOfRange;
  }
  return bounds.contains(x, y) ? PointFate::kMapped : PointFate::kOutsideBounds;
}

}  // namespace ccmap::tools
