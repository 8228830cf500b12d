# The global map of a patch directory (tools/global_map) and its GeoTIFF, read back with GDAL.
if(CCMAP_GDAL_ENABLED)
  add_executable(ccmap_test_tools_global_map ${CMAKE_CURRENT_LIST_DIR}/global_map_test.cpp)
  target_link_libraries(ccmap_test_tools_global_map PRIVATE GTest::gtest_main ccmap_global_map_lib ccmap_test_support GDAL::GDAL
                        ccmap_host_flags)
  target_include_directories(ccmap_test_tools_global_map PRIVATE ${CMAKE_CURRENT_LIST_DIR})
  target_compile_definitions(ccmap_test_tools_global_map PRIVATE CCMAP_GLOBAL_MAP_BINARY="$<TARGET_FILE:ccmap_global_map>")
  add_dependencies(ccmap_test_tools_global_map ccmap_global_map)
  ccmap_tools_gtest(ccmap_test_tools_global_map 300)
endif()
