target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/calibration.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/classify.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/config.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/stack.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/types.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/update/front.cpp)
target_sources(ccmap_core PRIVATE ${CMAKE_CURRENT_LIST_DIR}/detail/motion.cpp)
# The front's loops are vectorised only if gcc may evaluate their float operations
# unconditionally (if-conversion): -fno-trapping-math (no float exception is observed by the
# core; values are unchanged: IEEE rounding, no reassociation, no contraction).
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/update/front.cpp PROPERTIES COMPILE_OPTIONS "-fno-trapping-math")
# A coverage build (CCMAP_COVERAGE) compiles one copy of the front's loops instead of a clone per
# ISA level inlined into each entry point (update/front.cpp, CCMAP_FRONT_CLONES): gcov counts the
# branches of every inlined copy apart, and a machine runs only one clone, so the clones would
# show half the front's branches as never taken.
if(CCMAP_COVERAGE)
  set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/update/front.cpp PROPERTIES COMPILE_DEFINITIONS "CCMAP_FRONT_NO_CLONES")
endif()
