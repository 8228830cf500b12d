#include "ccmap/map/types.hpp"

namespace ccmap {

const char* to_string(CellClass cell_class) noexcept {
  switch (cell_class) {
    case CellClass::kUnknown: return "unknown";
    case CellClass::kTraversable: return "traversable";
    case CellClass::kObstacle: return "obstacle";
    case CellClass::kSteep: return "steep";
    case CellClass::kDropOff: return "drop";
  }
  return "unknown";
}

}  // namespace ccmap
