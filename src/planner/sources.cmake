target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/detail/region.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/footprint.cpp ${CMAKE_CURRENT_LIST_DIR}/path_query.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/costmap.cpp)
