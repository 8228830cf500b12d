# GoogleTest built from Debian's googletest sources inside this build, so that the same
# sources serve the host and the aarch64 target.
if(NOT EXISTS "${CCMAP_GTEST_SOURCE_DIR}/CMakeLists.txt")
  message(FATAL_ERROR "GoogleTest sources not found in ${CCMAP_GTEST_SOURCE_DIR}: apt-get install googletest")
endif()
set(INSTALL_GTEST OFF CACHE BOOL "" FORCE)
set(BUILD_GMOCK OFF CACHE BOOL "" FORCE)
set(gtest_force_shared_crt ON CACHE BOOL "" FORCE)
add_subdirectory(${CCMAP_GTEST_SOURCE_DIR} ${CMAKE_BINARY_DIR}/_deps/googletest EXCLUDE_FROM_ALL SYSTEM)
include(GoogleTest)

# ccmap_add_gtest(<name> SOURCES <files...> [LIBS <targets...>] [LABELS <labels...>])
# One executable per area; each TEST() becomes a ctest test, run under QEMU when cross-built.
function(ccmap_add_gtest name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ccmap::core ccmap_host_flags ccmap_test_support GTest::gtest_main ${ARG_LIBS})
  set(_labels library ${ARG_LABELS})
  gtest_discover_tests(${name}
    DISCOVERY_MODE PRE_TEST
    DISCOVERY_TIMEOUT 120
    PROPERTIES LABELS "${_labels}" TIMEOUT 600)
endfunction()
