// The two CCM cell kinds as GoogleTest type lists, so that one test body checks both cells
// (CcmCell with the lateral covariance, CcmPaperCell as in the paper) and the test names say which.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <type_traits>

#include "ccmap/cell/ccm_cell.hpp"
#include "ccmap/map/config.hpp"

namespace ccmap::test {

using CcmCellKinds = ::testing::Types<CcmCell, CcmPaperCell>;

/// "Full" for CcmCell, "Paper" for CcmPaperCell; for stack Configs, by their cell kind.
struct CcmKindNames {
  template <typename T>
  static std::string GetName(int) {
    if constexpr (kIsCcmCell<T>) {
      return kHasLateralCovariance<T> ? "Full" : "Paper";
    } else {
      return kConfigCcmCell<T> == CcmCellKind::kFull ? "Full" : "Paper";
    }
  }
};

}  // namespace ccmap::test
