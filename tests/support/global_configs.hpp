// Stack configurations of the global map's tests and host tools (include/ccmap/global/).
#pragma once

#include <array>
#include <cstdint>

#include "ccmap/map/config.hpp"

namespace ccmap::test {

/// CCM layers of 4, 8 and 16 cm, 64 cells a side (+-1.28, +-2.56, +-5.12 m): the coarse search
/// has a 32 cm level (16 cm pooled) and two layers below it.
struct ThreeCcmConfig {
  static constexpr FineKind kFineKind = FineKind::kNone;
  static constexpr CcmCellKind kCcmCell = CcmCellKind::kFull;
  static constexpr std::int32_t kFineSide = 0;
  static constexpr std::array<std::int32_t, 3> kCcmSides{{64, 64, 64}};
  static constexpr float kDefaultFinestCellWidthM = 0.04F;
};

}  // namespace ccmap::test
