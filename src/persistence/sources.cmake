target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/snapshot.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/exchange.cpp)
