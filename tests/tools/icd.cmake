# The interface control document (docs/icd/ccmap_icd.json) against what it describes, host only:
# docs/icd.md is what the ICD generates; include/ccmap/ccmap.h's status values, struct fields and
# constants; the C++ types (a probe generated from the ICD: static_asserts and run-time checks
# through the library's own encoder); the Python module's names (with the module only).
set(_icd ${PROJECT_SOURCE_DIR}/tools/icd/icd.py)
add_test(NAME ICD.Doc COMMAND ${CCMAP_PYTHON3} ${_icd} doc --check)
add_test(NAME ICD.Header COMMAND ${CCMAP_PYTHON3} ${_icd} header)
set(_icd_probe ${CMAKE_CURRENT_BINARY_DIR}/icd_probe.cpp)
add_custom_command(OUTPUT ${_icd_probe}
  COMMAND ${CCMAP_PYTHON3} ${_icd} probe ${_icd_probe}
  DEPENDS ${_icd} ${PROJECT_SOURCE_DIR}/docs/icd/ccmap_icd.json
  COMMENT "C++ probe of the ICD" VERBATIM)
add_executable(ccmap_icd_probe ${_icd_probe})
target_link_libraries(ccmap_icd_probe PRIVATE ccmap::core)
add_test(NAME ICD.CppTypes COMMAND ccmap_icd_probe)
set(_icd_tests ICD.Doc ICD.Header ICD.CppTypes)
if(CCMAP_PYTHON_ENABLED)
  add_test(NAME ICD.Python COMMAND ${Python3_EXECUTABLE} ${_icd} python)
  set(_icd_python_env "PYTHONPATH=$<TARGET_FILE_DIR:ccmap_python>")
  if(CCMAP_PYTHON_PRELOAD)  # sanitizer build: the instrumented module needs its runtimes first (tests/tools/python.cmake)
    list(APPEND _icd_python_env "LD_PRELOAD=${CCMAP_PYTHON_PRELOAD}" "ASAN_OPTIONS=detect_leaks=0")
  endif()
  set_tests_properties(ICD.Python PROPERTIES ENVIRONMENT "${_icd_python_env}")
  list(APPEND _icd_tests ICD.Python)
endif()
set_tests_properties(${_icd_tests} PROPERTIES LABELS "tools;icd" TIMEOUT 120)
