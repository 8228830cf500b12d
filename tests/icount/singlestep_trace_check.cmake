# The plugin's whole-program count against QEMU's own trace (tests/icount/CMakeLists.txt):
# with -singlestep every translation block is one instruction, and -d exec,nochain logs one
# "Trace" line before each executed block, i.e. per executed instruction.
#   cmake -DEMULATOR=qemu-aarch64|-L|dir -DPLUGIN=libccmap_icount.so -DEXE=prog -DARGS=a|b
#         -DWORK=dir -P singlestep_trace_check.cmake
cmake_minimum_required(VERSION 3.25)
string(REPLACE "|" ";" EMULATOR "${EMULATOR}")
string(REPLACE "|" ";" ARGS "${ARGS}")
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")

function(run_counted label out_var)
  execute_process(COMMAND ${EMULATOR} ${ARGN} -plugin "${PLUGIN},out=${WORK}/${label}.icount" "${EXE}" ${ARGS}
                  RESULT_VARIABLE rc OUTPUT_QUIET)
  if(NOT rc EQUAL 0 OR NOT EXISTS "${WORK}/${label}.icount")
    message(FATAL_ERROR "singlestep_trace_check: ${label} run failed (exit ${rc})")
  endif()
  file(READ "${WORK}/${label}.icount" counts)
  set(${out_var} "${counts}" PARENT_SCOPE)
endfunction()

run_counted(normal normal)
run_counted(singlestep singlestep -singlestep -d exec,nochain -D "${WORK}/trace.log")
file(STRINGS "${WORK}/trace.log" trace REGEX "^Trace ")
list(LENGTH trace traced)
if(NOT singlestep MATCHES "total insns=([0-9]+) ")
  message(FATAL_ERROR "singlestep_trace_check: no total in\n${singlestep}")
endif()
set(counted ${CMAKE_MATCH_1})
message("singlestep_trace_check: QEMU traced ${traced} executed instructions, the plugin counted ${counted}")
# Regions first (the clearer message), then the whole files: the same program in the same
# environment must count the same with one instruction per block as with normal blocks.
string(REGEX MATCHALL "region=[^\n]*" normal_regions "${normal}")
string(REGEX MATCHALL "region=[^\n]*" singlestep_regions "${singlestep}")
if(NOT traced EQUAL counted)
  message(FATAL_ERROR "singlestep_trace_check: plugin total ${counted} != ${traced} traced instructions")
endif()
if(normal_regions STREQUAL "" OR NOT normal_regions STREQUAL singlestep_regions)
  message(FATAL_ERROR "singlestep_trace_check: region counts differ between the normal and the single-step run:\n"
                      "${normal}\n--- single-step\n${singlestep}")
endif()
if(NOT normal STREQUAL singlestep)
  message(FATAL_ERROR "singlestep_trace_check: totals differ between the normal and the single-step run:\n"
                      "${normal}\n--- single-step\n${singlestep}")
endif()
message("singlestep_trace_check: region counts identical with one instruction per block")
