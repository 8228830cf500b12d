// The board's CPU-fault path: an integer division by zero traps (start-up sets CCR.DIV_0_TRP)
// and the handler reports the UsageFault through semihosting, then exits with
// CCMAP_BOARD_EXIT_CPU_FAULT (test board.cpu_fault_is_reported).
#include <cstdint>

volatile std::uint32_t g_divisor = 0U;

int main() { return static_cast<int>(100U / g_divisor); }
