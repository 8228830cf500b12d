# Tests of the host tools' I/O (readers, CSV, pictures) and of the ccmap command-line tool.
# Included from tests/tools/CMakeLists.txt (host builds only). tests/ is configured before
# tools/, so the tool targets are referenced by name (resolved at generation time).
add_executable(ccmap_test_tools_io ${CMAKE_CURRENT_LIST_DIR}/io_test.cpp)
target_link_libraries(ccmap_test_tools_io PRIVATE GTest::gtest_main ccmap_tools_io ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_io 300)

add_executable(ccmap_test_tools_cli ${CMAKE_CURRENT_LIST_DIR}/cli_test.cpp)
target_link_libraries(ccmap_test_tools_cli PRIVATE GTest::gtest_main ccmap_cli_lib ccmap_tools_io ccmap_host_flags)
# Real data for the end-to-end test (overridable at run time with CCMAP_DATA_DIR).
target_compile_definitions(ccmap_test_tools_cli PRIVATE
  CCMAP_DEFAULT_DATA_DIR="${PROJECT_SOURCE_DIR}/../shared/data"
  CCMAP_CLI_BINARY="$<TARGET_FILE:ccmap>")
add_dependencies(ccmap_test_tools_cli ccmap)
ccmap_tools_gtest(ccmap_test_tools_cli 600)

# `ccmap map --register` and `ccmap merge --align` (registration, issue 22).
add_executable(ccmap_test_tools_cli_registration ${CMAKE_CURRENT_LIST_DIR}/cli_registration_test.cpp)
target_link_libraries(ccmap_test_tools_cli_registration PRIVATE GTest::gtest_main ccmap_cli_lib ccmap_tools_io ccmap_host_flags)
target_include_directories(ccmap_test_tools_cli_registration PRIVATE ${PROJECT_SOURCE_DIR}/tests)
ccmap_tools_gtest(ccmap_test_tools_cli_registration 600)

# Whole clouds mapped in tiles (tools/cli/tiling.hpp) against brute-force and one-window references.
add_executable(ccmap_test_tools_tiling ${CMAKE_CURRENT_LIST_DIR}/tiling_test.cpp)
target_link_libraries(ccmap_test_tools_tiling PRIVATE GTest::gtest_main ccmap_cli_lib ccmap_tools_io ccmap_host_flags)
target_include_directories(ccmap_test_tools_tiling PRIVATE ${PROJECT_SOURCE_DIR}/tests)
ccmap_tools_gtest(ccmap_test_tools_tiling 600)

# The CLI without GDAL (always: its refusals of --geotiff / --dem, ccmap_cli_lib_nogdal).
add_executable(ccmap_test_tools_cli_nogdal ${CMAKE_CURRENT_LIST_DIR}/cli_nogdal_test.cpp)
target_link_libraries(ccmap_test_tools_cli_nogdal PRIVATE GTest::gtest_main ccmap_cli_lib_nogdal ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_cli_nogdal 120)

# --geotiff and --dem with GDAL: the files read back and the DEMs written with GDAL in the test;
# the real DTM of ../shared/data when present (overridable with CCMAP_DATA_DIR), else skipped.
if(CCMAP_GDAL_ENABLED)
  add_executable(ccmap_test_tools_raster ${CMAKE_CURRENT_LIST_DIR}/raster_test.cpp)
  target_link_libraries(ccmap_test_tools_raster PRIVATE GTest::gtest_main ccmap_cli_lib GDAL::GDAL ccmap_host_flags)
  target_compile_definitions(ccmap_test_tools_raster PRIVATE CCMAP_DEFAULT_DATA_DIR="${PROJECT_SOURCE_DIR}/../shared/data")
  ccmap_tools_gtest(ccmap_test_tools_raster 300)
endif()
