target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/capi.cpp)
