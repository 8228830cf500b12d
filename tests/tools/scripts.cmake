# Tests of the repository's scripts (host only).
#
# tools/check-paths (part of tools/lint) on a small fixture tree: it must name exactly the stale
# paths and the conditional CMake pickups planted there, and pass the same tree once they are
# fixed. Python 3 is in the host package tier.
find_program(CCMAP_PYTHON3 python3 REQUIRED)
add_test(NAME ccmap_tools_check_paths_finds_stale_paths
         COMMAND ${CMAKE_COMMAND} -DPYTHON=${CCMAP_PYTHON3} -DCHECKER=${PROJECT_SOURCE_DIR}/tools/check-paths
                 -DDIR=${CMAKE_CURRENT_BINARY_DIR}/check_paths_fixture -P ${CMAKE_CURRENT_LIST_DIR}/check_paths_check.cmake)
# tools/check-figures (part of tools/lint) on a small fixture tree: it must name exactly the
# figures stated against the fixture's docs/figures.md, the sections that do not exist and the
# figure key that is not there, and pass the same tree once they are fixed.
add_test(NAME ccmap_tools_check_figures_finds_stale_figures
         COMMAND ${CMAKE_COMMAND} -DPYTHON=${CCMAP_PYTHON3} -DCHECKER=${PROJECT_SOURCE_DIR}/tools/check-figures
                 -DDIR=${CMAKE_CURRENT_BINARY_DIR}/check_figures_fixture -P ${CMAKE_CURRENT_LIST_DIR}/check_figures_check.cmake)
# tools/install-deps tiers (--list only: nothing is installed): the host tier carries no cross,
# lint, fuzz or bare-metal package; `all` is the union of the tiers; an unknown tier is an error.
add_test(NAME ccmap_tools_install_deps_tiers
         COMMAND ${CMAKE_COMMAND} -DSCRIPT=${PROJECT_SOURCE_DIR}/tools/install-deps
                 -P ${CMAKE_CURRENT_LIST_DIR}/install_deps_check.cmake)
set_tests_properties(ccmap_tools_check_paths_finds_stale_paths ccmap_tools_check_figures_finds_stale_figures
                     ccmap_tools_install_deps_tiers
                     PROPERTIES LABELS "tools" TIMEOUT 60)
