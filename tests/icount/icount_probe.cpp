// A program with an analytically known instruction count between markers, to prove the QEMU
// instruction-count plugin (tools/qemu-icount) exact. aarch64 only; run by the ctests of
// tests/icount/CMakeLists.txt, which state the expected counts.
//
//   icount_probe <m> [errors]
//
// The kernel (assembly below) runs m >= 1 iterations. One call, counting the `bl` that calls
// it, executes exactly
//   K(m) = 1 (bl) + 4 (set-up) + 10 m (loop) + 1 (ret) = 6 + 10 m instructions:
//   fp = 2 m (FADD s, FMUL d), simd_fp = 2 m (FADD v.4s, FCMGT s,s,#0), simd_int = 2 m
//   (ADD v.4s, UMOV), ldst = 2 m + 1 (LDR, STR per iteration; the LDR of m).
// Regions (no instruction of main lies between a marker and the call it brackets: the call has
// no arguments and no result):
//   1      one call                                    K
//   2      three intervals of one call each            3 K, min = max = K
//   3      begin directly followed by end              0
//   4, 5   overlapping: b4 call b5 call e4 call e5     2 K each
//   65535  one call (the largest id)                   K
// The kernel is also called once before and once after all regions: counted in the total
// only (10 calls in all, 11 with `errors`). With `errors`, three marker errors follow: an end
// of region 7 that was never begun, a second begin of the open region 9 (its interval, one
// call, still counts), a begin of region 8 never ended.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "support/icount_marker.hpp"

#if !defined(__aarch64__)
#error "icount_probe is aarch64 code (built in the aarch64 build only)"
#endif

extern "C" {
// Read by the kernel (adrp + ldr): iterations per call; the buffer it loads from and stores to.
[[gnu::used]] std::uint64_t ccmap_icount_probe_iterations = 1;
[[gnu::used]] std::uint32_t ccmap_icount_probe_buffer[2] = {0, 0};
void ccmap_icount_probe_kernel();
}

// Only caller-saved registers (x0, x9..x12, v0..v7, v16, v17: AAPCS64), so it is an ordinary
// function for the compiler. Classes per the Arm ARM encoding groups (a64_class.h).
asm(R"(
  .text
  .balign 16
  .global ccmap_icount_probe_kernel
  .type ccmap_icount_probe_kernel, %function
ccmap_icount_probe_kernel:
  adrp x9, ccmap_icount_probe_iterations
  ldr  x0, [x9, :lo12:ccmap_icount_probe_iterations]    // ldst
  adrp x10, ccmap_icount_probe_buffer
  add  x10, x10, :lo12:ccmap_icount_probe_buffer
1:
  fadd s0, s0, s1                                       // fp
  fmul d2, d2, d3                                       // fp
  fadd v4.4s, v4.4s, v5.4s                              // simd_fp
  fcmgt s6, s7, #0.0                                    // simd_fp (scalar Advanced SIMD)
  add  v16.4s, v16.4s, v17.4s                           // simd_int
  umov w11, v16.s[1]                                    // simd_int
  ldr  w12, [x10]                                       // ldst
  str  w12, [x10, #4]                                   // ldst
  subs x0, x0, #1
  b.ne 1b
  ret
  .size ccmap_icount_probe_kernel, . - ccmap_icount_probe_kernel
)");

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: icount_probe <iterations >= 1> [errors]\n");
    return 2;
  }
  char* end = nullptr;
  const unsigned long long m = std::strtoull(argv[1], &end, 10);
  if (end == argv[1] || *end != '\0' || m < 1ULL || m > 100000000ULL) {
    std::fprintf(stderr, "icount_probe: iterations must be 1 .. 1e8, got '%s'\n", argv[1]);
    return 2;
  }
  ccmap_icount_probe_iterations = m;

  using ccmap::test::icount_begin;
  using ccmap::test::icount_end;
  ccmap_icount_probe_kernel();  // outside every region

  icount_begin<1>();
  ccmap_icount_probe_kernel();
  icount_end<1>();

  for (int i = 0; i < 3; ++i) {
    icount_begin<2>();
    ccmap_icount_probe_kernel();
    icount_end<2>();
  }

  icount_begin<3>();
  icount_end<3>();

  icount_begin<4>();
  ccmap_icount_probe_kernel();
  icount_begin<5>();
  ccmap_icount_probe_kernel();
  icount_end<4>();
  ccmap_icount_probe_kernel();
  icount_end<5>();

  icount_begin<65535>();
  ccmap_icount_probe_kernel();
  icount_end<65535>();

  ccmap_icount_probe_kernel();  // outside every region

  if (argc == 3) {
    if (std::strcmp(argv[2], "errors") != 0) {
      std::fprintf(stderr, "icount_probe: unknown mode '%s'\n", argv[2]);
      return 2;
    }
    icount_end<7>();
    icount_begin<9>();
    icount_begin<9>();
    ccmap_icount_probe_kernel();
    icount_end<9>();
    icount_begin<8>();
  }
  std::printf("icount_probe: %llu iterations per call, kernel value %u\n", m, ccmap_icount_probe_buffer[1]);
  return 0;
}
