/* Classification of one A64 instruction word by its encoding group (Arm Architecture
 * Reference Manual for A-profile, DDI 0487, section C4.1 "A64 instruction set encoding" and
 * its subsections). Pure functions: used by the QEMU plugin at translation time and by the
 * host test that checks them against binutils' disassembler. */
#ifndef CCMAP_A64_CLASS_H
#define CCMAP_A64_CLASS_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

enum a64_class {
  /* Everything else: integer data processing, branches, system, SVE/SME, unallocated. */
  A64_CLASS_OTHER = 0,
  /* Loads and stores (op0 = x1x0), general-purpose and SIMD&FP registers alike, including
   * prefetch, exclusive and atomic memory instructions. */
  A64_CLASS_LDST,
  /* Scalar floating-point data processing (SIMD&FP group, op0 = x0x1): FADD/FMUL/FDIV/
   * FSQRT/FMADD/FCMP/FCSEL/FMOV/FCVT, conversions to and from general registers. */
  A64_CLASS_FP,
  /* Advanced SIMD (SIMD&FP group, op0 = 0xx0 vector, 01x1 scalar, 1100 crypto) whose
   * operation is not floating point: integer arithmetic, compares, bitwise, shifts, moves,
   * DUP/INS/UMOV, permutes, table lookup, crypto. */
  A64_CLASS_SIMD_INT,
  /* Advanced SIMD floating-point operations, vector and scalar forms (FADD v.4s, FMLA by
   * element, FCMGT s0,s1,#0, FADDP s0,v1.2s, SCVTF s0,s1, FCVTN, FMOV v.4s,#imm, BF16). */
  A64_CLASS_SIMD_FP,
  A64_CLASS_COUNT
};

enum a64_class a64_classify(uint32_t insn);

/* Marker decoding (icount_marker_encoding.h). Returns 1 for a begin marker, 2 for an end
 * marker, 0 otherwise; *region_id receives the id of a marker. */
int a64_marker(uint32_t insn, uint32_t *region_id);

#ifdef __cplusplus
}
#endif

#endif /* CCMAP_A64_CLASS_H */
