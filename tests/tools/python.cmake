# Tests of the Python module (tools/python) and its example, label "python", host only.
# Included from tests/tools/CMakeLists.txt when cmake/CcmapPython.cmake enabled the module.
# Each test file is a unittest program (tests/tools/python/support.py: exit 77 = all skipped).
add_executable(ccmap_py_reference ${CMAKE_CURRENT_LIST_DIR}/python/ccmap_py_reference.cpp)
target_link_libraries(ccmap_py_reference PRIVATE ccmap::core ccmap_host_flags)
target_include_directories(ccmap_py_reference PRIVATE ${PROJECT_SOURCE_DIR}/tests)

set(_ccmap_python_env
    "PYTHONPATH=$<TARGET_FILE_DIR:ccmap_python>" "CCMAP_PY_REFERENCE=$<TARGET_FILE:ccmap_py_reference>"
    "CCMAP_SOURCE_DIR=${PROJECT_SOURCE_DIR}" "MPLBACKEND=Agg")
if(CCMAP_PYTHON_PRELOAD)
  # Sanitizer build: the instrumented module inside Debian's interpreter (whose own allocations
  # are never freed at exit, hence no leak report).
  list(APPEND _ccmap_python_env "LD_PRELOAD=${CCMAP_PYTHON_PRELOAD}" "ASAN_OPTIONS=detect_leaks=0")
endif()

# ccmap_add_python_test(<name> <file> [unittest test names...])
function(ccmap_add_python_test name file)
  add_test(NAME ${name} COMMAND ${Python3_EXECUTABLE} ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/python/${file} ${ARGN}
           WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
  set_tests_properties(${name} PROPERTIES
    LABELS "python;tools" TIMEOUT 300 SKIP_RETURN_CODE 77 ENVIRONMENT "${_ccmap_python_env}")
endfunction()

ccmap_add_python_test(ccmap_python_reference test_reference.py)
ccmap_add_python_test(ccmap_python_module test_module.py)
# The example on the real scan (skipped without ../shared/data), and its message without it.
ccmap_add_python_test(ccmap_python_example test_example.py Example.test_maps_the_crop_and_writes_a_png)
ccmap_add_python_test(ccmap_python_example_without_data test_example.py Example.test_without_data_it_says_why)
ccmap_add_python_test(ccmap_python_flight test_flight.py)
ccmap_add_python_test(ccmap_python_global_map test_global_map.py)
