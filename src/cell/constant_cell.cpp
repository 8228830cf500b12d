// The constant cells are header-only; this unit compiles their header under the core's
// warning wall.
#include "ccmap/cell/constant_cell.hpp"
