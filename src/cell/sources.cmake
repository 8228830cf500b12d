target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/ccm_cell.cpp ${CMAKE_CURRENT_LIST_DIR}/constant_cell.cpp)
