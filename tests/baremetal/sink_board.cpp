// Board side of the portable harness: output through semihosting, the filter from QEMU's
// -append "..." (platform/boards/<board>/board.h).
#include "board.h"
#include "harness.hpp"

extern "C" void ccmap_test_write(const char* text) { ccmap_board_write(text); }

int main() {
  static char filter[256];
  (void)ccmap_board_arguments(filter, sizeof filter);
  return ccmap::bmtest::run(filter);
}
