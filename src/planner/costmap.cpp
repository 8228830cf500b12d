// Non-template parts of the cost raster (planner/costmap.hpp): validation, the cost function,
// rank conversion, inflation (also for rasters the caller assembles) and counting.
#include "ccmap/planner/costmap.hpp"

#include <cmath>

#include "ccmap/map/classify.hpp"

namespace ccmap {

std::uint8_t traversable_cost(float inclination, float max_inclination, float normal_variance, float threshold) noexcept {
  float ratio = max_inclination > 0.0F ? inclination / max_inclination : 0.0F;
  const float relief = threshold > 0.0F && normal_variance > 0.0F ? std::sqrt(normal_variance / threshold) : 0.0F;
  ratio = relief > ratio ? relief : ratio;
  // NaN (not produced by the library) and anything above 1 saturate at the traversable maximum.
  if (!(ratio < 1.0F)) {
    return kCostMaxTraversable;
  }
  const float scaled = 252.0F * ratio + 0.5F;  // ratio >= 0: round half up
  return static_cast<std::uint8_t>(scaled >= 252.0F ? 252.0F : (scaled > 0.0F ? scaled : 0.0F));
}

namespace detail {

Status check_costmap_spec(const CostmapSpec& spec) noexcept {
  const float values[] = {spec.centre_x, spec.centre_y, spec.resolution_m, spec.inflation_radius_m};
  for (const float v : values) {
    if (!std::isfinite(v)) {
      return Status::kNonFiniteInput;
    }
  }
  if (!(spec.resolution_m > 0.0F) || spec.side == 0U || spec.side > kMaxCostmapSide || spec.inflation_radius_m < 0.0F) {
    return Status::kInvalidArgument;
  }
  const float half = 0.5F * static_cast<float>(spec.side) * spec.resolution_m;
  if (!(std::fabs(spec.centre_x) + half <= kMaxAbsCoordinateM) || !(std::fabs(spec.centre_y) + half <= kMaxAbsCoordinateM)) {
    return Status::kOutOfRange;
  }
  if (spec.inflation_radius_m > static_cast<float>(kMaxInflationPixels) * spec.resolution_m) {
    return Status::kOutOfRange;
  }
  return Status::kOk;
}

void ranks_to_costs(std::size_t pixels, std::uint8_t* cost) noexcept {
  for (std::size_t i = 0; i < pixels; ++i) {
    cost[i] = cost[i] == kRankUnknown ? kCostUnknown : cost[i];  // kRankLethal == kCostLethal
  }
}

void count_costs(std::size_t pixels, const std::uint8_t* cost, CostmapStats* stats) noexcept {
  CostmapStats s = *stats;
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::uint8_t c = cost[i];
    s.free += c == kCostFree ? 1U : 0U;
    s.cost += (c > kCostFree && c <= kCostMaxTraversable) ? 1U : 0U;
    s.inscribed += c == kCostInscribed ? 1U : 0U;
    s.lethal += c == kCostLethal ? 1U : 0U;
    s.unknown += c == kCostUnknown ? 1U : 0U;
  }
  *stats = s;
}

void inflate_lethal(std::uint32_t width, std::uint32_t height, float radius_pixels, std::uint8_t* cost) noexcept {
  static_assert(kRankLethal == kCostLethal, "the lethal rank is the lethal cost");
  const float radius = radius_pixels;  // <= kMaxInflationPixels (callers check)
  auto reach = static_cast<std::int32_t>(std::floor(radius));
  reach = reach < kMaxInflationPixels ? reach : kMaxInflationPixels;  // the table's size, whatever the rounding
  // half[d]: the largest dx with dx^2 + d^2 <= radius^2 (pixel centres), in integers from one
  // float square root per row offset (+ 1e-4 px: a centre exactly on the circle is inside).
  std::int32_t half[kMaxInflationPixels + 1];
  for (std::int32_t d = 0; d <= reach; ++d) {
    const float rest = radius * radius - static_cast<float>(d * d);
    half[d] = rest >= 0.0F ? static_cast<std::int32_t>(std::floor(std::sqrt(rest) + 1.0e-4F)) : -1;
  }
  const auto cols = static_cast<std::int32_t>(width);
  const auto rows = static_cast<std::int32_t>(height);
  for (std::int32_t y = 0; y < rows; ++y) {
    std::uint8_t* target = cost + static_cast<std::size_t>(y) * width;
    for (std::int32_t d = -reach; d <= reach; ++d) {
      const std::int32_t source_y = y + d;
      const std::int32_t h = half[d < 0 ? -d : d];
      if (source_y < 0 || source_y >= rows || h < 0) {
        continue;
      }
      const std::uint8_t* source = cost + static_cast<std::size_t>(source_y) * width;
      // Sliding count of lethal pixels of the source row in [x - h, x + h]. Marking writes 253
      // into cost pixels only, so lethal pixels (the only ones counted) never change.
      std::int32_t count = 0;
      for (std::int32_t x = 0; x < h && x < cols; ++x) {
        count += source[x] == kCostLethal ? 1 : 0;
      }
      for (std::int32_t x = 0; x < cols; ++x) {
        const std::int32_t enter = x + h;
        const std::int32_t leave = x - h - 1;
        count += (enter < cols && source[enter] == kCostLethal) ? 1 : 0;
        count -= (leave >= 0 && source[leave] == kCostLethal) ? 1 : 0;
        if (count > 0 && target[x] <= kCostMaxTraversable) {
          target[x] = kCostInscribed;
        }
      }
    }
  }
}

}  // namespace detail

Status inflate_costmap(std::uint8_t* cost, std::size_t capacity, std::uint32_t width, std::uint32_t height,
                       float radius_pixels) noexcept {
  if (cost == nullptr || width == 0U || height == 0U || width > kMaxCostmapSide || height > kMaxCostmapSide ||
      capacity < static_cast<std::size_t>(width) * height) {
    return Status::kInvalidArgument;
  }
  if (!std::isfinite(radius_pixels)) {
    return Status::kNonFiniteInput;
  }
  if (radius_pixels < 0.0F || radius_pixels > static_cast<float>(kMaxInflationPixels)) {
    return Status::kOutOfRange;
  }
  detail::inflate_lethal(width, height, radius_pixels, cost);
  return Status::kOk;
}

}  // namespace ccmap
