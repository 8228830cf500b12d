// Board side of the portable harness: output through semihosting, the filter from QEMU's
// -append "..." (platform/boards/<board>/board.h).
#include "board.h"
#include "harness.hpp"

extern "C" void ccmap_test_write(const char* text) { ccmap_board_write(text); }

int main() {
  static char filter[256];
  if (ccmap_board_arguments(filter, sizeof filter) == CCMAP_BOARD_ARGUMENTS_ERROR) {
    ccmap_board_write("cannot read the arguments (QEMU -append) of this image\n");
    return 2;
  }
  return ccmap::bmtest::run(filter);
}
