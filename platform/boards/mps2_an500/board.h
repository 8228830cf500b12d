/* Board layer for QEMU's mps2-an500 (Arm Cortex-M7, FPv5 single-precision FPU): start-up,
 * the ccmap bare-metal hooks (clock, log, fault) and the few services a test or demo image
 * needs, all through Arm semihosting (QEMU -semihosting) and the board's CMSDK timer.
 *
 * Not part of the ccmap core, and not what flight software links: a flight integration has its
 * own start-up and implements the three ccmap_bm_* hooks of platform/baremetal over its time
 * service, telemetry and FDIR (docs/integration.md, "Bare metal"). This board is the reference
 * integration the bare-metal tests run on.
 *
 * Run an image (the semihosting text then goes to stdout; with plain -semihosting QEMU 7.2
 * writes it to stderr):
 *   qemu-system-arm -M mps2-an500 -cpu cortex-m7 -nographic -monitor none -serial none
 *     -chardev stdio,id=semihost -semihosting-config enable=on,target=native,chardev=semihost
 *     -icount shift=0 -kernel image.elf [-append "args"]
 * With -icount shift=0 every guest instruction advances virtual time by exactly 1 ns, so the
 * 25 MHz timer below counts one tick per 40 instructions, identically on every run.
 */
#ifndef CCMAP_BOARD_MPS2_AN500_BOARD_H
#define CCMAP_BOARD_MPS2_AN500_BOARD_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Frequency of the board's CMSDK APB timer 0 (QEMU's mps2 SYSCLK). */
#define CCMAP_BOARD_TIMER_HZ 25000000u
/* Guest instructions per timer tick under -icount shift=0 (1 ns per instruction). */
#define CCMAP_BOARD_INSTRUCTIONS_PER_TICK 40u

/* Exit codes of ccmap_board_exit besides the program's own (main's return value). */
#define CCMAP_BOARD_EXIT_CPU_FAULT 70 /* HardFault, MemManage, BusFault, UsageFault, NMI */

/* Writes a NUL-terminated text to the host's stdout (semihosting SYS_WRITE0). NULL: ignored. */
void ccmap_board_write(const char* text);

/* Ends the emulation; QEMU exits with `code` (semihosting SYS_EXIT_EXTENDED). */
__attribute__((noreturn)) void ccmap_board_exit(int code);

/* Timer 0 ticks since start-up (25 MHz, counting up, wraps after 2^32 ticks = 171.8 s). */
uint32_t ccmap_board_ticks(void);

/* The arguments after the image name of QEMU's -append "..." (semihosting SYS_GET_CMDLINE),
 * NUL-terminated in buffer[0..capacity). Returns their length (0: none), or
 * CCMAP_BOARD_ARGUMENTS_ERROR (buffer empty) if they cannot be read or do not fit: a program
 * must not mistake a lost argument for no argument. */
#define CCMAP_BOARD_ARGUMENTS_ERROR SIZE_MAX
size_t ccmap_board_arguments(char* buffer, size_t capacity);

/* Deepest main-stack use since start-up (bytes): start-up paints the stack, this counts the
 * bytes no longer holding the paint. */
size_t ccmap_board_stack_used(void);
/* Size of the main stack (bytes; the linker script's __ccmap_stack_size). */
size_t ccmap_board_stack_size(void);

/* Counts of ccmap_bm_fault and ccmap_bm_log_write calls since start-up (tests read them). */
uint32_t ccmap_board_fault_count(void);
uint32_t ccmap_board_log_count(void);

#ifdef __cplusplus
}
#endif

#endif /* CCMAP_BOARD_MPS2_AN500_BOARD_H */
