// Stack parameters with the normal-variance thresholds written out, for tests that initialise
// or load many stacks of one configuration and whose subject is not the thresholds.
//
// Stack::init() calibrates the threshold of every layer whose StackParams threshold is <= 0
// (Section IV-E, calibrate_normal_variance_threshold: ~140 evaluations of a 32 x 32-sample step
// cell per layer), and a snapshot load calls init(). A threshold > 0 in the parameters is taken
// as it is (layer_threshold, src/map/classify.cpp), so a stack initialised with the values
// another stack calibrated holds bit for bit the same thresholds, and classifies and updates
// exactly as a calibrating one; only the calibration's cost is left out (docs/integration.md
// section 3.1).
#pragma once

#include <cstddef>
#include <memory>

#include "ccmap/map/stack.hpp"

namespace ccmap::test {

/// `params` with each layer's threshold set to the one Stack<Config>::init(params) calibrates (or
/// takes) for it. Unchanged if init refuses `params` (the caller's own init then says why).
template <typename Config>
StackParams with_calibrated_thresholds(const StackParams& params) {
  StackParams out = params;
  auto stack = std::make_unique<Stack<Config>>();
  if (stack->init(params) != Status::kOk) {
    return out;
  }
  for (int layer = 0; layer < Stack<Config>::kLayerCount; ++layer) {
    out.normal_variance_threshold[static_cast<std::size_t>(layer)] = stack->normal_variance_threshold(layer);
  }
  return out;
}

}  // namespace ccmap::test
