target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/product_buffers.cpp)
