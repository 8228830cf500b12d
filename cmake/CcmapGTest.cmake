# GoogleTest built from Debian's googletest sources inside this build, so that the same
# sources serve the host and the aarch64 target.
if(NOT EXISTS "${CCMAP_GTEST_SOURCE_DIR}/CMakeLists.txt")
  message(FATAL_ERROR "GoogleTest sources not found in ${CCMAP_GTEST_SOURCE_DIR}: apt-get install googletest")
endif()
set(INSTALL_GTEST OFF CACHE BOOL "" FORCE)
set(BUILD_GMOCK OFF CACHE BOOL "" FORCE)
set(gtest_force_shared_crt ON CACHE BOOL "" FORCE)
add_subdirectory(${CCMAP_GTEST_SOURCE_DIR} ${CMAKE_BINARY_DIR}/_deps/googletest EXCLUDE_FROM_ALL SYSTEM)
# GoogleTest is the harness, not the subject: no sanitizer or coverage instrumentation (what
# CCMAP_SANITIZE and CCMAP_COVERAGE add to every target of the directory) and -O1 whatever the
# build type. Its one translation unit cost every build ~50 s of CPU at -O2 under ASan + UBSan;
# ASan needs no instrumented harness to check the code it calls (instrumented and plain objects link).
foreach(_gtest_target IN ITEMS gtest gtest_main)
  get_target_property(_gtest_options ${_gtest_target} COMPILE_OPTIONS)
  if(_gtest_options)
    list(FILTER _gtest_options EXCLUDE REGEX "^(-fsanitize|-fno-sanitize-recover|--coverage)")
  else()
    set(_gtest_options)
  endif()
  set_target_properties(${_gtest_target} PROPERTIES COMPILE_OPTIONS "${_gtest_options};-O1")
endforeach()
include(GoogleTest)

# ccmap_add_gtest(<name> SOURCES <files...> [LIBS <targets...>] [LABELS <labels...>])
# One executable per area; each TEST() becomes a ctest test, run under QEMU when cross-built,
# labelled `library` and LABELS (`release`: its subject is the optimised build, so tools/test runs
# it in host-release too, not only in host-coverage and asan).
function(ccmap_add_gtest name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS;LABELS" ${ARGN})
  if(CCMAP_LIBRARY_TESTS STREQUAL "RELEASE" AND NOT "release" IN_LIST ARG_LABELS)
    return()  # built and run by the coverage and sanitizer builds (CCMAP_LIBRARY_TESTS)
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ccmap::core ccmap_host_flags ccmap_test_support GTest::gtest_main ${ARG_LIBS})
  gtest_discover_tests(${name}
    DISCOVERY_MODE PRE_TEST
    DISCOVERY_TIMEOUT 120
    TEST_LIST ${name}_TESTS
    PROPERTIES TIMEOUT 600)
  # The labels (`library` and ARG_LABELS) by a file ctest reads after the discovered tests:
  # gtest_discover_tests passes PROPERTIES as a flat list, so a second label would become a
  # property name instead of a label.
  set(_labels library ${ARG_LABELS})
  set(_labels_file "${CMAKE_CURRENT_BINARY_DIR}/${name}_labels.cmake")
  file(WRITE "${_labels_file}"
       "if(DEFINED ${name}_TESTS)\n  set_tests_properties(\${${name}_TESTS} PROPERTIES LABELS \"${_labels}\")\nendif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${_labels_file}")
endfunction()
