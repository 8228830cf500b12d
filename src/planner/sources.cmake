target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/detail/region.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/planner_support.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/costmap.cpp)
