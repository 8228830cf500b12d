# Every host-tool test runs with TMPDIR set to one directory of this build tree, inside the
# ctest fixture ccmap_tools_tmp: its setup test creates the directory empty, its cleanup test
# (after every test that requires the fixture, also under `ctest -R`) fails if a test left
# anything there. Tests make their temporary directories with tests/tools/temp_dir.hpp, which
# removes them also when the test fails.
set(CCMAP_TOOLS_TEST_TMPDIR ${CMAKE_CURRENT_BINARY_DIR}/tmp)
add_test(NAME ccmap_tools_tmp_setup
         COMMAND ${CMAKE_COMMAND} -DMODE=setup -DDIR=${CCMAP_TOOLS_TEST_TMPDIR} -P ${CMAKE_CURRENT_LIST_DIR}/temp_check.cmake)
add_test(NAME ccmap_tools_tests_leave_no_temporary_files
         COMMAND ${CMAKE_COMMAND} -DMODE=check -DDIR=${CCMAP_TOOLS_TEST_TMPDIR} -P ${CMAKE_CURRENT_LIST_DIR}/temp_check.cmake)
set_tests_properties(ccmap_tools_tmp_setup PROPERTIES FIXTURES_SETUP ccmap_tools_tmp LABELS "tools")
set_tests_properties(ccmap_tools_tests_leave_no_temporary_files PROPERTIES FIXTURES_CLEANUP ccmap_tools_tmp LABELS "tools")

# ccmap_tools_gtest(<target> <timeout s>): every TEST of a host-tool test binary becomes a ctest
# test labelled "tools", run in the ccmap_tools_tmp fixture.
function(ccmap_tools_gtest target timeout)
  gtest_discover_tests(${target} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
                       PROPERTIES LABELS "tools" TIMEOUT ${timeout}
                                  ENVIRONMENT "TMPDIR=${CCMAP_TOOLS_TEST_TMPDIR}"
                                  FIXTURES_REQUIRED ccmap_tools_tmp)
endfunction()
