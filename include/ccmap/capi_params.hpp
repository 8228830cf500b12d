// The C API's parameters (ccmap_params of ccmap/ccmap.h) and the C++ StackParams, for C++
// programs that speak both (the Python module, ground tools): the conversions ccmap_init and
// ccmap_get_params use, and the CRC of ccmap_health.params_crc.
#pragma once

#include <cstdint>

#include "ccmap/ccmap.h"
#include "ccmap/map/config.hpp"

namespace ccmap {

/// `params` as ccmap_get_params answers a map that runs with them and was given no C copy (a
/// loaded snapshot): the noise model as itself (stereo: focal 1 px, baseline 1 m, disparity
/// sigma k; converting back gives the same model bitwise).
void stack_params_to_c(const StackParams& params, ccmap_params* out) noexcept;
/// ccmap_init's conversion: kInvalidArgument for a sensor or weight mode outside its enum.
[[nodiscard]] Status stack_params_from_c(const ccmap_params& params, StackParams* out) noexcept;
/// CRC-32 (IEEE 802.3) of the bytes of `params` (ccmap_health.params_crc).
[[nodiscard]] std::uint32_t c_params_crc(const ccmap_params& params) noexcept;

}  // namespace ccmap
