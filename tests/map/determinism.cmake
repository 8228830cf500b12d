# Determinism host == aarch64 (== Cortex-M7 for the board scenario). ccmap_determinism_dump maps
# fixed, in-process scenarios and prints a hash of the whole map for each; the host and the
# aarch64/QEMU build compare them with the golden hashes committed from the host build, which
# proves host == golden == aarch64 (the bare-metal build checks board_scenario against the same
# file: tests/baremetal). Regenerate tests/golden/determinism.txt as described in
# determinism_dump.cpp. Label `release`: the golden hashes and the archive's symbols are the
# optimised build's (tools/test runs these in host-release too).
add_executable(ccmap_determinism_dump ${CMAKE_CURRENT_LIST_DIR}/determinism_dump.cpp)
target_link_libraries(ccmap_determinism_dump PRIVATE ccmap::core ccmap_host_flags)
target_include_directories(ccmap_determinism_dump PRIVATE ${PROJECT_SOURCE_DIR}/tests)
add_test(NAME ccmap_determinism_golden_hash
         COMMAND ccmap_determinism_dump --check ${PROJECT_SOURCE_DIR}/tests/golden/determinism.txt cadre_traverse)
# The same traverse with the paper's 9-float CCM cell (Stack<PaperCell<CadreConfig>>).
add_test(NAME ccmap_determinism_golden_hash_paper_cell
         COMMAND ccmap_determinism_dump --check ${PROJECT_SOURCE_DIR}/tests/golden/determinism.txt
                 cadre_traverse_paper_cell)
add_test(NAME ccmap_board_scenario_golden_hash
         COMMAND ccmap_determinism_dump --check ${PROJECT_SOURCE_DIR}/tests/golden/determinism.txt board_scenario)
# No libm transcendental on the update path: the dump program (generation + init + update +
# move + query + export) and the core archive reference none (nm, no emulator needed).
add_test(NAME ccmap_update_path_has_no_transcendentals
         COMMAND ${CMAKE_COMMAND} -DNM=${CMAKE_NM}
                 "-DFILES=$<TARGET_FILE:ccmap_determinism_dump>;$<TARGET_FILE:ccmap_core>"
                 -P ${CMAKE_CURRENT_LIST_DIR}/check_no_transcendentals.cmake)
set_tests_properties(ccmap_determinism_golden_hash ccmap_determinism_golden_hash_paper_cell
                     ccmap_board_scenario_golden_hash
                     ccmap_update_path_has_no_transcendentals
                     PROPERTIES LABELS "library;release" TIMEOUT 300)
