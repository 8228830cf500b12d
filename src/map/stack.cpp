#include "ccmap/map/stack.hpp"

#include <cstdint>

namespace ccmap {

namespace detail {
namespace {
std::uint32_t saturating_add(std::uint32_t a, std::uint32_t b) noexcept {
  return (a > 0xFFFFFFFFU - b) ? 0xFFFFFFFFU : a + b;
}
}  // namespace

void accumulate(FrameCounters& total, const FrameCounters& frame) noexcept {
  total.received = saturating_add(total.received, frame.received);
  total.used = saturating_add(total.used, frame.used);
  total.rejected_non_finite = saturating_add(total.rejected_non_finite, frame.rejected_non_finite);
  total.rejected_out_of_range = saturating_add(total.rejected_out_of_range, frame.rejected_out_of_range);
  total.rejected_weight = saturating_add(total.rejected_weight, frame.rejected_weight);
  total.outside_map = saturating_add(total.outside_map, frame.outside_map);
  total.too_noisy = saturating_add(total.too_noisy, frame.too_noisy);
  total.gated_finer = saturating_add(total.gated_finer, frame.gated_finer);
  total.gated_occluded = saturating_add(total.gated_occluded, frame.gated_occluded);
  total.gated_held = saturating_add(total.gated_held, frame.gated_held);
  total.gated_pool_full = saturating_add(total.gated_pool_full, frame.gated_pool_full);
  total.gated_admitted = saturating_add(total.gated_admitted, frame.gated_admitted);
  total.gated_dropped = saturating_add(total.gated_dropped, frame.gated_dropped);
  total.reseeded_cells = saturating_add(total.reseeded_cells, frame.reseeded_cells);
  total.merged_cells = saturating_add(total.merged_cells, frame.merged_cells);
  total.skipped_budget = saturating_add(total.skipped_budget, frame.skipped_budget);
  total.corrupted_cells = saturating_add(total.corrupted_cells, frame.corrupted_cells);
  total.corrupted_slots = saturating_add(total.corrupted_slots, frame.corrupted_slots);
  total.free_rays = saturating_add(total.free_rays, frame.free_rays);
  total.free_rays_refused = saturating_add(total.free_rays_refused, frame.free_rays_refused);
  total.cleared_cells = saturating_add(total.cleared_cells, frame.cleared_cells);
  total.drop_cells = saturating_add(total.drop_cells, frame.drop_cells);
}
}  // namespace detail

}  // namespace ccmap
