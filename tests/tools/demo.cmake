# The README's main job as a test: tools/demo --quick against this build tree (the quick
# traverse and every other step of the script: host packages, build, traverse, single-cell
# demo). demo_check.cmake asserts exit 0, the progress lines and the files the demo promises.
# Host only (tests/tools is built with the tools); TIMEOUT covers the ASan build's slower traverse.
add_test(NAME ccmap_tools_demo_quick
         COMMAND ${CMAKE_COMMAND} -DDEMO=${PROJECT_SOURCE_DIR}/tools/demo -DBUILD_DIR=${CMAKE_BINARY_DIR}
                 -DOUT_DIR=${CMAKE_CURRENT_BINARY_DIR}/demo_out -P ${CMAKE_CURRENT_LIST_DIR}/demo_check.cmake)
set_tests_properties(ccmap_tools_demo_quick PROPERTIES LABELS "tools" TIMEOUT 600)
