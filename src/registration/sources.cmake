# Registration (include/ccmap/registration/): the 4 x 4 algebra uses Eigen's fixed-size float
# types (ccmap_eigen, linked PRIVATE in src/CMakeLists.txt; no Eigen type in a public header).
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/types.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/detail/normal_equations.cpp)
