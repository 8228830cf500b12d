# Stack usage of the public calls (stack painting, host and QEMU) over the Stack<CadreConfig>
# instance compiled with the core's flags (tests/map/stack_instances.cpp).
add_library(ccmap_stack_instances OBJECT ${CMAKE_CURRENT_LIST_DIR}/stack_instances.cpp)
target_link_libraries(ccmap_stack_instances PRIVATE ccmap::core ccmap_core_flags)
ccmap_add_gtest(ccmap_test_stack_usage SOURCES ${CMAKE_CURRENT_LIST_DIR}/stack_usage_test.cpp
                $<TARGET_OBJECTS:ccmap_stack_instances> LABELS release)
