// Start-up of a bare-metal image on QEMU's mps2-an500 (Cortex-M7): the vector table, the reset
// handler, the fault handler and the board services of board.h.
//
// Reset, in order (nothing before step 1 may touch a floating-point register):
//  1. enable the FPU (CPACR: full access to CP10/CP11), then DSB/ISB;
//  2. copy .data from its load address in flash, zero .bss (the map: static Stack<..> objects
//     whose members all start at zero land here, costing no flash);
//  3. paint the unused main stack (ccmap_board_stack_used);
//  4. enable the MemManage, BusFault and UsageFault handlers and the divide-by-zero trap;
//  5. start timer 0 free-running (ccmap_board_ticks);
//  6. run the static constructors (.init_array), call main(), exit with its return value.
// A CPU fault prints the exception, the stacked PC and the fault status registers and exits
// with CCMAP_BOARD_EXIT_CPU_FAULT; no exception returns into a faulting program.
#include <array>
#include <cstddef>
#include <cstdint>

#include "board.h"
#include "semihosting.hpp"

// Linker-script symbols (mps2_an500.ld).
extern "C" {
extern std::uint32_t __data_start[];
extern std::uint32_t __data_end[];
extern const std::uint32_t __data_load[];
extern std::uint32_t __bss_start[];
extern std::uint32_t __bss_end[];
extern std::uint32_t __stack_limit[];
extern std::uint32_t __stack_top[];
using InitFunction = void (*)();
extern const InitFunction __init_array_start[];
extern const InitFunction __init_array_end[];
// The program's main(), under another C++ name (ISO C++ forbids calling main itself).
int ccmap_board_program_main() __asm__("main");
void ccmap_board_reset();
void ccmap_board_exception();
[[noreturn]] void ccmap_board_start();
[[noreturn]] void ccmap_board_report_fault(const std::uint32_t* frame, std::uint32_t exception);
}

namespace ccmap::board {
namespace {

volatile std::uint32_t& reg(std::uintptr_t address) noexcept {
  return *reinterpret_cast<volatile std::uint32_t*>(address);
}

// System control block (Armv7-M ARM, B3.2).
constexpr std::uintptr_t kScbCcr = 0xE000ED14U;    // configuration and control
constexpr std::uintptr_t kScbShcsr = 0xE000ED24U;  // system handler control and state
constexpr std::uintptr_t kScbCfsr = 0xE000ED28U;   // configurable fault status
constexpr std::uintptr_t kScbHfsr = 0xE000ED2CU;   // hard fault status
constexpr std::uintptr_t kScbMmfar = 0xE000ED34U;  // MemManage fault address
constexpr std::uintptr_t kScbBfar = 0xE000ED38U;   // BusFault address
constexpr std::uint32_t kCcrDivByZeroTrap = 1U << 4U;
constexpr std::uint32_t kShcsrFaultsEnabled = (1U << 16U) | (1U << 17U) | (1U << 18U);
// CMSDK APB timer 0 (mps2: 0x40000000, clocked at SYSCLK = 25 MHz), counting down.
constexpr std::uintptr_t kTimer0Ctrl = 0x40000000U;
constexpr std::uintptr_t kTimer0Value = 0x40000004U;
constexpr std::uintptr_t kTimer0Reload = 0x40000008U;

constexpr std::uint32_t kStackPaint = 0xC5C5C5C5U;

// Vector table: initial main stack pointer, then 15 system exceptions and 32 interrupts
// (none enabled). Every entry but reset reports and exits.
constexpr std::size_t kIrqCount = 32U;
using Handler = void (*)();
struct VectorTable {
  // Read by the processor at reset and on exceptions, never by code:
  // cppcheck-suppress unusedStructMember
  const std::uint32_t* initial_stack;
  // cppcheck-suppress unusedStructMember
  std::array<Handler, 15U + kIrqCount> handlers;
};

/// Elements between two linker-script symbols, in integers (they are not one C++ object, so
/// comparing or subtracting them as pointers would not be defined).
template <typename T>
std::size_t count_between(const T* begin, const T* end) noexcept {
  return (reinterpret_cast<std::uintptr_t>(end) - reinterpret_cast<std::uintptr_t>(begin)) / sizeof(T);
}

constexpr std::array<Handler, 15U + kIrqCount> make_handlers() {
  std::array<Handler, 15U + kIrqCount> handlers{};
  for (Handler& h : handlers) {
    h = &ccmap_board_exception;
  }
  handlers[0] = &ccmap_board_reset;
  for (std::size_t reserved : {6U, 7U, 8U, 9U, 12U}) {
    handlers[reserved] = nullptr;
  }
  return handlers;
}

__attribute__((section(".vectors"), used)) constexpr VectorTable kVectors{__stack_top, make_handlers()};

const char* exception_name(std::uint32_t exception) noexcept {
  switch (exception) {
    case 2U: return "NMI";
    case 3U: return "HardFault";
    case 4U: return "MemManage";
    case 5U: return "BusFault";
    case 6U: return "UsageFault";
    default: return exception >= 16U ? "unexpected interrupt" : "unexpected exception";
  }
}

/// "0x" and 8 hex digits into out[0..11).
void hex(std::uint32_t value, char* out) noexcept {
  out[0] = '0';
  out[1] = 'x';
  for (int i = 0; i < 8; ++i) {
    const auto digit = static_cast<char>((value >> (28 - 4 * i)) & 0xFU);
    out[2 + i] = static_cast<char>(digit < 10 ? '0' + digit : 'a' + (digit - 10));
  }
  out[10] = '\0';
}

void write_hex(const char* label, std::uint32_t value) noexcept {
  char text[11];
  hex(value, text);
  ccmap_board_write(label);
  ccmap_board_write(text);
}

}  // namespace
}  // namespace ccmap::board

using namespace ccmap::board;

// Step 1 in assembly: the compiler may use FPU registers in any compiled function.
extern "C" __attribute__((naked)) void ccmap_board_reset() {
  __asm__ volatile(
      "ldr r0, =0xE000ED88\n"  // CPACR
      "ldr r1, [r0]\n"
      "orr r1, r1, #0x00F00000\n"
      "str r1, [r0]\n"
      "dsb\n"
      "isb\n"
      "b ccmap_board_start\n");
}

extern "C" void ccmap_board_start() {
  const std::size_t data_words = count_between(__data_start, __data_end);
  for (std::size_t i = 0; i < data_words; ++i) {
    __data_start[i] = __data_load[i];
  }
  const std::size_t bss_words = count_between(__bss_start, __bss_end);
  for (std::size_t i = 0; i < bss_words; ++i) {
    __bss_start[i] = 0U;
  }
  // Paint from the stack limit to 64 bytes below this frame.
  std::uint32_t* sp = nullptr;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  const std::size_t below_sp = count_between(__stack_limit, sp);
  const std::size_t paint_words = below_sp > 16U ? below_sp - 16U : 0U;
  for (std::size_t i = 0; i < paint_words; ++i) {
    __stack_limit[i] = kStackPaint;
  }
  reg(kScbShcsr) = reg(kScbShcsr) | kShcsrFaultsEnabled;
  reg(kScbCcr) = reg(kScbCcr) | kCcrDivByZeroTrap;
  reg(kTimer0Ctrl) = 0U;
  reg(kTimer0Reload) = 0xFFFFFFFFU;
  reg(kTimer0Value) = 0xFFFFFFFFU;
  reg(kTimer0Ctrl) = 1U;  // enable, no interrupt
  __asm__ volatile("dsb\nisb" ::: "memory");
  const std::size_t constructors = count_between(__init_array_start, __init_array_end);
  for (std::size_t i = 0; i < constructors; ++i) {
    __init_array_start[i]();
  }
  ccmap_board_exit(ccmap_board_program_main());
}

// Every other exception: the stacked frame (r0 r1 r2 r3 r12 lr pc xpsr) is on the main stack
// (no process stack is used) and IPSR holds the exception number.
extern "C" __attribute__((naked)) void ccmap_board_exception() {
  __asm__ volatile(
      "mrs r0, msp\n"
      "mrs r1, ipsr\n"
      "b ccmap_board_report_fault\n");
}

extern "C" void ccmap_board_report_fault(const std::uint32_t* frame, std::uint32_t exception) {
  ccmap_board_write("\nccmap board: CPU fault: ");
  ccmap_board_write(exception_name(exception & 0x1FFU));
  write_hex(" (exception ", exception & 0x1FFU);
  write_hex(") pc ", frame[6]);
  write_hex(" lr ", frame[5]);
  write_hex(" cfsr ", reg(kScbCfsr));
  write_hex(" hfsr ", reg(kScbHfsr));
  write_hex(" mmfar ", reg(kScbMmfar));
  write_hex(" bfar ", reg(kScbBfar));
  ccmap_board_write("\n");
  ccmap_board_exit(CCMAP_BOARD_EXIT_CPU_FAULT);
}

extern "C" {

void ccmap_board_write(const char* text) {
  if (text != nullptr && text[0] != '\0') {
    (void)semihost(kSysWrite0, text);
  }
}

void ccmap_board_exit(int code) {
  const std::uint32_t block[2] = {kApplicationExit, static_cast<std::uint32_t>(code)};
  for (;;) {
    (void)semihost(kSysExitExtended, block);  // does not return under QEMU
  }
}

std::uint32_t ccmap_board_ticks(void) { return 0xFFFFFFFFU - reg(kTimer0Value); }

std::size_t ccmap_board_arguments(char* buffer, std::size_t capacity) {
  if (buffer == nullptr || capacity == 0U) {
    return CCMAP_BOARD_ARGUMENTS_ERROR;
  }
  static char line[1024];  // static: the stack high-water mark should show the program, not this
  // Parameter block: buffer address, its size; the host writes the length back into word 1.
  std::uint32_t block[2] = {static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(line)), sizeof line};
  buffer[0] = '\0';
  if (semihost(kSysGetCmdline, block) != 0U) {
    return CCMAP_BOARD_ARGUMENTS_ERROR;  // no semihosting, or longer than the buffer
  }
  const std::uint32_t length = block[1];
  // QEMU answers "<image> <args of -append>": skip the image name.
  std::size_t i = 0U;
  while (i < length && line[i] != '\0' && line[i] != ' ') {
    ++i;
  }
  while (i < length && line[i] == ' ') {
    ++i;
  }
  std::size_t n = 0U;
  while (i < length && line[i] != '\0') {
    if (n + 1U >= capacity) {
      buffer[0] = '\0';
      return CCMAP_BOARD_ARGUMENTS_ERROR;
    }
    buffer[n++] = line[i++];
  }
  buffer[n] = '\0';
  return n;
}

std::size_t ccmap_board_stack_used(void) {
  const std::size_t words = count_between(__stack_limit, __stack_top);
  std::size_t painted = 0U;
  while (painted < words && __stack_limit[painted] == kStackPaint) {
    ++painted;
  }
  return (words - painted) * sizeof(std::uint32_t);
}

std::size_t ccmap_board_stack_size(void) { return count_between(__stack_limit, __stack_top) * sizeof(std::uint32_t); }

}  // extern "C"
