target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/assert.cpp ${CMAKE_CURRENT_LIST_DIR}/status.cpp
                   ${CMAKE_CURRENT_LIST_DIR}/sin_cos.cpp)
