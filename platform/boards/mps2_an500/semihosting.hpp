// Arm semihosting calls (AArch32, M profile: BKPT 0xAB), as QEMU implements them with
// -semihosting. Internal to the board layer.
#pragma once

#include <cstdint>

namespace ccmap::board {

// Operation numbers (Arm "Semihosting for AArch32 and AArch64", version 2.0).
inline constexpr std::uint32_t kSysWrite0 = 0x04U;
inline constexpr std::uint32_t kSysGetCmdline = 0x15U;
inline constexpr std::uint32_t kSysExitExtended = 0x20U;
/// ADP_Stopped_ApplicationExit: with SYS_EXIT_EXTENDED the second word is the exit code.
inline constexpr std::uint32_t kApplicationExit = 0x20026U;

/// One semihosting call: r0 = operation, r1 = argument (a pointer to a parameter block or a
/// string, depending on the operation). Returns the host's r0.
inline std::uint32_t semihost(std::uint32_t operation, const void* argument) noexcept {
  register std::uint32_t r0 __asm__("r0") = operation;
  register const void* r1 __asm__("r1") = argument;
  __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

}  // namespace ccmap::board
