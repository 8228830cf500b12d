/* The marker instructions that bracket a counted region (shared by the plugin, which
 * recognises them, and tests/support/icount_marker.hpp, which emits them).
 *
 * A marker is MOVZ XZR, #region_id, LSL #(16 * hw) (Arm ARM, "Move wide (immediate)":
 * sf=1 opc=10 100101 hw imm16 Rd; Rd = 31 names XZR for MOVZ, so the result is discarded and
 * the instruction is an architectural no-op with no flags or memory effect):
 *   begin of region id: hw = 0   0xD280001F | id << 5
 *   end   of region id: hw = 1   0xD2A0001F | id << 5
 * id is 0 .. 65535. Compilers never write a constant to the zero register: none of the
 * aarch64 libc, libm, libstdc++, libgcc_s (tests/tools/icount_classify_test.cpp) or ccmap core
 * and platform libraries (ctest ccmap_icount_no_stray_markers) contains either encoding. */
#ifndef CCMAP_ICOUNT_MARKER_ENCODING_H
#define CCMAP_ICOUNT_MARKER_ENCODING_H

#define CCMAP_ICOUNT_MARKER_BEGIN 0xD280001FU
#define CCMAP_ICOUNT_MARKER_END 0xD2A0001FU
/* Bits that vary between markers of one kind: imm16, bits 20:5. */
#define CCMAP_ICOUNT_MARKER_ID_MASK 0x001FFFE0U
#define CCMAP_ICOUNT_MARKER_ID_SHIFT 5U
#define CCMAP_ICOUNT_MAX_REGION_ID 65535U

#endif /* CCMAP_ICOUNT_MARKER_ENCODING_H */
