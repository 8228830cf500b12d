# The command lines of the host programs parsed with CLI11 (tools/args/parse_args.hpp): --help
# prints the generated options and exits 0; a bad value or an unknown option is one line on
# stderr naming it, and exit 2. (The ccmap CLI has its own tests in cli_test.cpp.)
# ccmap_args_test(<name> <target> <exit code> <stderr regex> <stdout regex> [args...])
function(ccmap_args_test name target rc err_regex out_regex)
  list(JOIN ARGN "|" joined)
  add_test(NAME ccmap_args_${name}
           COMMAND ${CMAKE_COMMAND} -DEXE=$<TARGET_FILE:${target}> "-DARGS=${joined}" -DRC=${rc}
                   "-DSTDERR=${err_regex}" "-DSTDOUT=${out_regex}" -P ${CMAKE_CURRENT_LIST_DIR}/args_check.cmake)
  set_tests_properties(ccmap_args_${name} PROPERTIES LABELS "tools" TIMEOUT 60)
endfunction()

ccmap_args_test(sim_demo_help ccmap_sim_demo 0 "^$" "--stride INT" --help)
ccmap_args_test(sim_demo_stride_zero ccmap_sim_demo 2 "^ccmap_sim_demo: error: --stride: Value 0 not in range" "^$" --stride 0)
ccmap_args_test(sim_demo_unknown ccmap_sim_demo 2 "^ccmap_sim_demo: error: .*not expected: --bogus" "^$" --bogus)
ccmap_args_test(sim_demo_streaks_not_a_number ccmap_sim_demo 2 "--streaks" "^$" --streaks x)
if(CCMAP_BUILD_BENCH)  # the benchmark may be switched off on its own
  ccmap_args_test(bench_selftimed_help ccmap_bench_selftimed 0 "^$" "reps" --help)
  ccmap_args_test(bench_selftimed_zero_reps ccmap_bench_selftimed 2 "^ccmap_bench_selftimed: error: reps: Value 0 not in range" "^$" 0)
  ccmap_args_test(bench_selftimed_two_counts ccmap_bench_selftimed 2 "not expected: 4" "^$" 3 4)
endif()
