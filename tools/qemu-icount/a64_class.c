/* A64 instruction classes from the encoding tables of the Arm ARM (DDI 0487), C4.1.
 *
 * Top level (C4.1, op0 = bits 28:25):
 *   x1x0  Loads and Stores                                            -> LDST
 *   x111  Data Processing -- Scalar Floating-Point and Advanced SIMD  -> FP / SIMD_*
 *   other Reserved, SME, SVE, DP immediate, branches/system, DP register -> OTHER
 *
 * Inside x111 (the C4.1 table "Data Processing -- Scalar Floating-Point and Advanced SIMD";
 * its op0 is bits 31:28):
 *   x0x1  the scalar floating-point groups (conversions FP<->fixed, FP<->integer, 1-, 2- and
 *         3-source data processing, compare, conditional compare/select, immediate) -> FP
 *   0xx0  Advanced SIMD vector groups; 01x1 Advanced SIMD scalar groups; 0100/0101 and
 *         1100 cryptographic groups -> SIMD_FP or SIMD_INT by the group's opcode fields
 *
 * The SIMD split follows each group's own format (field names as in the Arm ARM). It is
 * checked against binutils' disassembler over the aarch64 system libraries and a fixed
 * random sample of SIMD&FP words (tests/tools/icount_classify_test.cpp). Unallocated
 * encodings land in some class; they never execute (they fault). */
#include "a64_class.h"

#include "icount_marker_encoding.h"

static uint32_t field(uint32_t insn, unsigned hi, unsigned lo) {
  return (insn >> lo) & ((1U << (hi - lo + 1U)) - 1U);
}

static uint32_t bit(uint32_t insn, unsigned b) { return (insn >> b) & 1U; }

/* "Advanced SIMD (scalar) x indexed element": 0 Q U 01111 size L M Rm opcode H 0 Rn Rd
 * (scalar: 01 U 11111 ...). opcode = bits 15:12. */
static int indexed_element_is_fp(uint32_t u, uint32_t opcode, uint32_t size) {
  if (u == 0U) {
    switch (opcode) {
      case 0x0: /* FMLAL */
      case 0x1: /* FMLA */
      case 0x4: /* FMLSL */
      case 0x5: /* FMLS */
      case 0x9: /* FMUL */
        return 1;
      case 0xF: /* size 01 BFDOT, 11 BFMLAL (FP); 00 SUDOT, 10 USDOT (integer) */
        return (int)(size & 1U);
      default: /* SMLAL, SQDMLAL, SMLSL, SQDMLSL, MUL, SMULL, SQDMULL, SQDMULH, SQRDMULH, SDOT */
        return 0;
    }
  }
  if ((opcode & 0x9U) == 0x1U) {
    return 1; /* FCMLA: opcode = 0 rot 1 */
  }
  /* FMLAL2, FMULX, FMLSL2; the rest (MLA, UMLAL, MLS, UMLSL, UMULL, SQRDMLAH, UDOT,
   * SQRDMLSH) is integer. */
  return opcode == 0x8U || opcode == 0x9U || opcode == 0xCU;
}

/* "Advanced SIMD (scalar) two-register miscellaneous": 0 Q U 01110 size 10000 opcode 10 Rn Rd.
 * opcode = bits 16:12. Integer: REV*, [SU]ADDLP, [SU]QADD, CLS/CLZ, CNT/NOT/RBIT, [SU]ADALP,
 * SQABS/SQNEG, CMxx zero, ABS/NEG (0x00..0x0B), XTN/SQXTUN, SHLL, [SU]QXTN (0x12..0x14),
 * URECPE/URSQRTE (0x1C with size<1> = 1). FP: FCMxx zero, FABS/FNEG (0x0C..0x0F), FCVTN/FCVTXN/
 * BFCVTN, FCVTL (0x16, 0x17), FRINT*, FCVT*, SCVTF/UCVTF, FRECPE/FRSQRTE, FRECPX, FSQRT
 * (0x18..0x1F). */
static int two_reg_misc_is_fp(uint32_t opcode, uint32_t size) {
  if (opcode >= 0x0CU && opcode <= 0x0FU) {
    return 1;
  }
  if (opcode >= 0x16U) {
    return !(opcode == 0x1CU && (size & 2U) != 0U);
  }
  return 0;
}

static int simd_is_fp(uint32_t insn) {
  const uint32_t scalar = bit(insn, 28); /* 01x1: scalar groups; 0xx0: vector groups */
  const uint32_t u = bit(insn, 29);
  const uint32_t size = field(insn, 23, 22);
  if (bit(insn, 24) != 0U) {
    if (bit(insn, 10) == 0U) {
      return indexed_element_is_fp(u, field(insn, 15, 12), size);
    }
    if (bit(insn, 23) != 0U) {
      return 0; /* unallocated */
    }
    if (scalar == 0U && field(insn, 22, 19) == 0U) {
      /* "Advanced SIMD modified immediate" (immh = 0): cmode = 1111 is FMOV (vector,
       * immediate); MOVI/MVNI/ORR/BIC otherwise. */
      return field(insn, 15, 12) == 0xFU;
    }
    /* "Advanced SIMD (scalar) shift by immediate": opcode = bits 15:11; 11100 SCVTF/UCVTF and
     * 11111 FCVTZS/FCVTZU (fixed-point) are FP, every shift/narrow/insert is integer. */
    return field(insn, 15, 11) == 0x1CU || field(insn, 15, 11) == 0x1FU;
  }
  if (bit(insn, 21) != 0U) {
    if (bit(insn, 10) != 0U) {
      /* "Advanced SIMD (scalar) three same": opcode = bits 15:11; 11xxx are the FP
       * operations (FMAXNM, FMLA, FADD, FMULX, FCMEQ, FMLAL, FMAX, FRECPS, FMINNM, FMLS,
       * FSUB, FMIN, FRSQRTS, FMUL, FDIV, FABD, FACGE, ...). */
      return field(insn, 15, 14) == 0x3U;
    }
    if (bit(insn, 11) == 0U) {
      return 0; /* "three different" (bits 11:10 = 00): long/wide/narrow integer, PMULL */
    }
    if (field(insn, 22, 17) == 0x3CU) {
      return 1; /* "two-register miscellaneous (FP16)": a 1 1 1 1 0 0 opcode 1 0 */
    }
    switch (field(insn, 20, 17)) {
      case 0x0U: /* "two-register miscellaneous": size 1 0000 opcode 1 0 */
        return two_reg_misc_is_fp(field(insn, 16, 12), size);
      case 0x8U: /* "across lanes" / scalar "pairwise": size 1 1000 opcode 1 0; FMAXNMV/
                  * FMAXNMP, FADDP, FMAXV/FMAXP (and their MIN forms) are FP; [SU]ADDLV,
                  * [SU]MAXV, [SU]MINV, ADDV, ADDP integer. */
        return field(insn, 16, 12) == 0x0CU || field(insn, 16, 12) == 0x0DU || field(insn, 16, 12) == 0x0FU;
      default: /* cryptographic AES and two-register SHA (bits 21:17 = 10100), unallocated */
        return 0;
    }
  }
  if (bit(insn, 10) != 0U) {
    if (bit(insn, 15) != 0U) {
      /* "three-register extension" (bit 21 = 0, bit 15 = 1): opcode = bits 14:11; 1xxx are
       * FCMLA, FCADD, BFMMLA, BFDOT, BFMLAL; 0xxx SQRDMLAH, SQRDMLSH, [SU]DOT, USDOT, *MMLA. */
      return (int)bit(insn, 14);
    }
    /* bit 22 = 1: "three same (FP16)" (a 1 0 Rm 0 0 opcode 1); bits 23:21 = 000: "copy"
     * (DUP, INS, UMOV, SMOV). */
    return (int)bit(insn, 22);
  }
  return 0; /* table lookup, permute, extract, cryptographic three-register SHA */
}

enum a64_class a64_classify(uint32_t insn) {
  if ((insn & 0x0A000000U) == 0x08000000U) {
    return A64_CLASS_LDST; /* op0 = x1x0 */
  }
  if ((insn & 0x0E000000U) != 0x0E000000U) {
    return A64_CLASS_OTHER; /* not op0 = x111 */
  }
  if (bit(insn, 28) != 0U && bit(insn, 30) == 0U) {
    return A64_CLASS_FP; /* x0x1 */
  }
  if (bit(insn, 31) != 0U) {
    /* 1100: SHA512, SM3, SM4, EOR3, BCAX, XAR, RAX1; 11x1 unallocated */
    return A64_CLASS_SIMD_INT;
  }
  return simd_is_fp(insn) ? A64_CLASS_SIMD_FP : A64_CLASS_SIMD_INT;
}

int a64_marker(uint32_t insn, uint32_t *region_id) {
  const uint32_t kind_bits = insn & ~CCMAP_ICOUNT_MARKER_ID_MASK;
  int kind = 0;
  if (kind_bits == CCMAP_ICOUNT_MARKER_BEGIN) {
    kind = 1;
  } else if (kind_bits == CCMAP_ICOUNT_MARKER_END) {
    kind = 2;
  }
  if (kind != 0) {
    *region_id = (insn & CCMAP_ICOUNT_MARKER_ID_MASK) >> CCMAP_ICOUNT_MARKER_ID_SHIFT;
  }
  return kind;
}
