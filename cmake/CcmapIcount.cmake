# Deterministic instruction counts of aarch64 code under QEMU user mode (tools/qemu-icount,
# docs/performance.md "Counting instructions under QEMU").
#
# In every build where an aarch64 cross toolchain exists (the aarch64 build; a host build that
# finds aarch64-linux-gnu-gcc), the QEMU plugin libccmap_icount.so is built with the host C
# compiler as an external project (no cross or sanitizer flags reach it):
#   CCMAP_ICOUNT_PLUGIN   its path; empty when it is not built
#
# ccmap_add_icount_test(NAME <test> TARGET <aarch64 executable target>
#                       [ARGS <program arguments>...]
#                       [CHECKS <region>:<field>:<op>:<integer>...]
#                       [PER <region>:<units per interval>:<unit name>...]
#                       [RATIOS <region>:<field>:LE:<percent>:<region>...]
#                       [RUNS <n>] [EXPECT_MARKER_ERRORS <n>] [LABELS <labels>...])
# In the aarch64 build only: a ctest that runs TARGET under
#   <CMAKE_CROSSCOMPILING_EMULATOR> -plugin libccmap_icount.so,out=<file> TARGET ARGS
# RUNS times (default 1; with 2 or more, every count file must equal the first, byte for
# byte), prints the counts and checks them (cmake/ccmap_icount_run.cmake):
#   <region>   a region id or `total`
#   <field>    intervals insns fp simd_int simd_fp ldst min_interval_insns max_interval_insns
#              unmatched (regions); insns fp simd_int simd_fp ldst marker_errors vcpus (total)
#   <op>       EQ NE LT LE GT GE
# e.g. 1:max_interval_insns:LE:86000000 (every interval of region 1 within 86 M instructions).
# It also requires total marker_errors = EXPECT_MARKER_ERRORS (default 0) and vcpus = 1, and
# each CHECKS region to be present. PER prints instructions, float instructions (fp +
# simd_fp) and loads/stores per unit, e.g. 1:4000:point. RATIOS compare two regions' fields:
# 2:insns:LE:125:3 requires 100 * insns(2) <= 125 * insns(3). Label `icount` unless LABELS is given.
include_guard(GLOBAL)
include(ExternalProject)

set(CCMAP_ICOUNT_PLUGIN "")
if(CMAKE_CROSSCOMPILING)
  set(_ccmap_icount_cross OFF)
  if("${CMAKE_SYSTEM_PROCESSOR}" STREQUAL "aarch64")
    set(_ccmap_icount_cross ON)
  endif()
else()
  find_program(CCMAP_AARCH64_GCC aarch64-linux-gnu-gcc)
  set(_ccmap_icount_cross OFF)
  if(CCMAP_AARCH64_GCC)
    set(_ccmap_icount_cross ON)
  endif()
endif()

if(_ccmap_icount_cross)
  find_program(CCMAP_HOST_C_COMPILER NAMES cc gcc clang DOC "Host C compiler for the QEMU plugin")
  if(NOT CCMAP_HOST_C_COMPILER)
    message(STATUS "ccmap: no host C compiler found: no QEMU instruction-count plugin")
  else()
    set(_ccmap_icount_dir ${CMAKE_BINARY_DIR}/tools/qemu-icount)
    set(CCMAP_ICOUNT_PLUGIN ${_ccmap_icount_dir}/libccmap_icount.so)
    ExternalProject_Add(ccmap_icount_plugin
      SOURCE_DIR ${PROJECT_SOURCE_DIR}/tools/qemu-icount
      BINARY_DIR ${_ccmap_icount_dir}
      CMAKE_ARGS -DCMAKE_C_COMPILER=${CCMAP_HOST_C_COMPILER} -DCMAKE_BUILD_TYPE=Release
      INSTALL_COMMAND ""
      BUILD_ALWAYS ON                      # rebuild when the plugin's sources change
      BUILD_BYPRODUCTS ${CCMAP_ICOUNT_PLUGIN})
  endif()
endif()

function(ccmap_add_icount_test)
  cmake_parse_arguments(ARG "" "NAME;TARGET;RUNS;EXPECT_MARKER_ERRORS" "ARGS;CHECKS;PER;RATIOS;LABELS" ${ARGN})
  if(NOT ARG_NAME OR NOT ARG_TARGET)
    message(FATAL_ERROR "ccmap_add_icount_test: NAME and TARGET are required")
  endif()
  if(NOT CMAKE_CROSSCOMPILING OR NOT "${CMAKE_SYSTEM_PROCESSOR}" STREQUAL "aarch64" OR NOT CCMAP_ICOUNT_PLUGIN)
    return()  # counts are of aarch64 code under qemu-aarch64: the aarch64 build only
  endif()
  if(NOT ARG_RUNS)
    set(ARG_RUNS 1)
  endif()
  if(NOT DEFINED ARG_EXPECT_MARKER_ERRORS)
    set(ARG_EXPECT_MARKER_ERRORS 0)
  endif()
  if(NOT ARG_LABELS)
    set(ARG_LABELS icount)
  endif()
  # Lists travel to the script joined with '|': add_test would split them at ';'.
  string(REPLACE ";" "|" _emulator "${CMAKE_CROSSCOMPILING_EMULATOR}")
  string(REPLACE ";" "|" _args "${ARG_ARGS}")
  string(REPLACE ";" "|" _checks "${ARG_CHECKS}")
  string(REPLACE ";" "|" _per "${ARG_PER}")
  string(REPLACE ";" "|" _ratios "${ARG_RATIOS}")
  add_test(NAME ${ARG_NAME}
           COMMAND ${CMAKE_COMMAND}
                   "-DEMULATOR=${_emulator}" "-DPLUGIN=${CCMAP_ICOUNT_PLUGIN}"
                   "-DEXE=$<TARGET_FILE:${ARG_TARGET}>" "-DARGS=${_args}"
                   "-DOUT=${CMAKE_CURRENT_BINARY_DIR}/${ARG_NAME}.icount" "-DRUNS=${ARG_RUNS}"
                   "-DCHECKS=${_checks}" "-DPER=${_per}" "-DRATIOS=${_ratios}" "-DEXPECT_MARKER_ERRORS=${ARG_EXPECT_MARKER_ERRORS}"
                   -P ${PROJECT_SOURCE_DIR}/cmake/ccmap_icount_run.cmake)
  set_tests_properties(${ARG_NAME} PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT 900)
  add_dependencies(${ARG_TARGET} ccmap_icount_plugin)
endfunction()
