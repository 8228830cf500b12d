target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/calibration.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/stack_support.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/front.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/motion.cpp)
# The front's loops are vectorised only if gcc may evaluate their float operations
# unconditionally (if-conversion): -fno-trapping-math (no float exception is observed by the
# core; values are unchanged: IEEE rounding, no reassociation, no contraction).
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/front.cpp PROPERTIES COMPILE_OPTIONS "-fno-trapping-math")
