# Shared by the fixture tests of the repository's checkers (check_paths_check.cmake,
# check_figures_check.cmake), run with cmake -DPYTHON=... -DCHECKER=... -DDIR=... -P.
#
# ccmap_check_fixture(<exit code> <findings> [<text>...]): runs CHECKER on the fixture tree DIR
# and fails unless it exits with <exit code>, prints <findings> lines besides its summary lines
# ("ccmap lint: ..." and "tools/check-<name>: ..."), and each <text> appears in its output.
function(ccmap_check_fixture expected_rc expected_findings)
  execute_process(COMMAND "${PYTHON}" "${CHECKER}" --root "${DIR}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}${err}")
  get_filename_component(checker "${CHECKER}" NAME)
  if(NOT rc EQUAL expected_rc)
    message(FATAL_ERROR "${checker} on the fixture exited with '${rc}' (expected ${expected_rc}):\n${out}${err}")
  endif()
  # Lines counted as characters (a CMake list would join lines that hold brackets).
  string(REGEX REPLACE "[^\n]" "" newlines "${out}")
  string(LENGTH "${newlines}" found)
  string(REGEX MATCHALL "(^|\n)(ccmap lint|tools/check-[a-z]+): " summaries "${out}")
  list(LENGTH summaries summary_count)
  math(EXPR found "${found} - ${summary_count}")
  if(NOT found EQUAL expected_findings)
    message(FATAL_ERROR "${checker} reported ${found} findings, expected ${expected_findings}")
  endif()
  foreach(e IN LISTS ARGN)
    string(FIND "${out}" "${e}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "${checker} did not report: ${e}")
    endif()
  endforeach()
endfunction()
