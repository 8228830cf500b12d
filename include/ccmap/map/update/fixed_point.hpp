// The update path's fixed-point units: the front writes every point's height and squared range
// in them (map/update/front.hpp, FrontChunk), the Kalman frame batch sums and gates them in
// integers (map/update/kalman_batch.hpp), the gate keeps held Kalman points in them
// (map/update/gate.hpp). One home, so that writer and readers cannot disagree. Integrators need
// not read it.
#pragma once

namespace ccmap::detail {

/// Q14 heights: floor(z * kHeightQ14PerM) (units of 2^-14 m, about 61 um).
inline constexpr float kHeightQ14PerM = 16384.0F;        // 2^14
inline constexpr float kHeightMPerQ14 = 6.10351562e-5F;  // 2^-14
/// Range keys: floor(min(range_sq, kRangeKeyCapM2) * kRangeKeysPerM2) (units of 2^-12 m^2);
/// the cap keeps every key below 2^31.
inline constexpr float kRangeKeysPerM2 = 4096.0F;       // 2^12
inline constexpr float kRangeKeyM2 = 2.44140625e-4F;    // 2^-12
inline constexpr float kRangeKeyCapM2 = 524287.0F;      // 2^19 - 1

}  // namespace ccmap::detail
