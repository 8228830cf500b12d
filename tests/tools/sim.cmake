# Tests of the host simulator (tools/sim) and the paper experiments (tools/experiments).
# Included from tests/tools/CMakeLists.txt (host builds only). tests/ is configured before
# tools/, so the tool targets are referenced by name (resolved at generation time).
add_executable(ccmap_test_tools_sim ${CMAKE_CURRENT_LIST_DIR}/sim_test.cpp)
target_link_libraries(ccmap_test_tools_sim PRIVATE GTest::gtest_main ccmap_sim ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_sim 300)

add_executable(ccmap_test_tools_experiments ${CMAKE_CURRENT_LIST_DIR}/experiments_test.cpp)
target_link_libraries(ccmap_test_tools_experiments PRIVATE GTest::gtest_main ccmap_sim ccmap_experiments ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_experiments 300)

add_executable(ccmap_test_tools_traverse ${CMAKE_CURRENT_LIST_DIR}/traverse_test.cpp)
target_link_libraries(ccmap_test_tools_traverse PRIVATE GTest::gtest_main ccmap_traverse_lib ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_traverse 300)

add_executable(ccmap_test_tools_lidar ${CMAKE_CURRENT_LIST_DIR}/lidar_test.cpp)
target_link_libraries(ccmap_test_tools_lidar PRIVATE GTest::gtest_main ccmap_experiments ccmap_sim ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_lidar 300)

add_executable(ccmap_test_tools_detection ${CMAKE_CURRENT_LIST_DIR}/detection_test.cpp)
target_link_libraries(ccmap_test_tools_detection PRIVATE GTest::gtest_main ccmap_sim ccmap_experiments ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_detection 300)

add_executable(ccmap_test_tools_team ${CMAKE_CURRENT_LIST_DIR}/team_test.cpp)
target_link_libraries(ccmap_test_tools_team PRIVATE GTest::gtest_main ccmap_team_lib ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_team 300)

add_executable(ccmap_test_tools_ghosts ${CMAKE_CURRENT_LIST_DIR}/ghosts_test.cpp)
target_link_libraries(ccmap_test_tools_ghosts PRIVATE GTest::gtest_main ccmap_ghosts_lib ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_ghosts 300)

add_executable(ccmap_test_tools_drop_place ${CMAKE_CURRENT_LIST_DIR}/drop_place_test.cpp)
target_link_libraries(ccmap_test_tools_drop_place PRIVATE GTest::gtest_main ccmap_ghosts_lib ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_drop_place 60)

add_executable(ccmap_test_tools_dropoff_truth ${CMAKE_CURRENT_LIST_DIR}/dropoff_truth_test.cpp)
target_link_libraries(ccmap_test_tools_dropoff_truth PRIVATE GTest::gtest_main ccmap_ghosts_lib ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_dropoff_truth 120)
add_executable(ccmap_test_tools_ghost_truth ${CMAKE_CURRENT_LIST_DIR}/ghost_truth_test.cpp)
target_link_libraries(ccmap_test_tools_ghost_truth PRIVATE GTest::gtest_main ccmap_ghosts_lib ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_ghost_truth 120)
