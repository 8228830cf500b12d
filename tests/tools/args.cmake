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

ccmap_args_test(sim_demo_help ccmap_sim_demo 0 "^$" "--stride K=1" --help)
ccmap_args_test(sim_demo_stride_zero ccmap_sim_demo 2 "^ccmap_sim_demo: error: --stride: 0 is out of range" "^$" --stride 0)
# CLI::Range lets NaN through: the demo reads numbers with tools/args/number_options.hpp.
ccmap_args_test(sim_demo_res_nan ccmap_sim_demo 2 "^ccmap_sim_demo: error: --res: nan is out of range" "^$" --res nan)
ccmap_args_test(sim_demo_unknown ccmap_sim_demo 2 "^ccmap_sim_demo: error: .*not expected: --bogus" "^$" --bogus)
ccmap_args_test(sim_demo_streaks_not_a_number ccmap_sim_demo 2 "--streaks" "^$" --streaks x)
if(CCMAP_BUILD_BENCH)  # the benchmark may be switched off on its own
  ccmap_args_test(bench_selftimed_help ccmap_bench_selftimed 0 "^$" "reps" --help)
  ccmap_args_test(bench_selftimed_zero_reps ccmap_bench_selftimed 2 "^ccmap_bench_selftimed: error: reps: Value 0 not in range" "^$" 0)
  ccmap_args_test(bench_selftimed_two_counts ccmap_bench_selftimed 2 "not expected: 4" "^$" 3 4)
endif()

# The number options those parsers share (tools/args/number_options.hpp).
add_executable(ccmap_test_tools_number_options ${CMAKE_CURRENT_LIST_DIR}/number_options_test.cpp)
target_link_libraries(ccmap_test_tools_number_options PRIVATE GTest::gtest_main ccmap_cli11 ccmap_host_flags)
ccmap_tools_gtest(ccmap_test_tools_number_options 60)

# The experiments (tools/experiments: the options of every experiment come from common.cpp)
# and the traverse programs (tools/traverse).
foreach(fig fig4 fig5 lidar lateral fig6 fig10 outliers)
  ccmap_args_test(exp_${fig}_help ccmap_exp_${fig} 0 "^$" "Usage: ccmap_exp_${fig}.*--seed N=1.*--out DIR=out/experiments.*--quick.*--paper-cell.*--data DIR.*--gate K.*--change-points M.*--change-share S" --help)
  ccmap_args_test(exp_${fig}_seed_not_whole ccmap_exp_${fig} 2 "^ccmap_exp_${fig}: error: --seed: '1.5' is not a whole number" "^$" --seed 1.5)
  ccmap_args_test(exp_${fig}_unknown ccmap_exp_${fig} 2 "^ccmap_exp_${fig}: error: .*not expected: --bogus" "^$" --bogus)
endforeach()
ccmap_args_test(exp_fig4_stray_argument ccmap_exp_fig4 2 "^ccmap_exp_fig4: error: .*not expected: stray" "^$" --quick stray)
ccmap_args_test(exp_fig5_seed_negative ccmap_exp_fig5 2 "^ccmap_exp_fig5: error: --seed: -1 is out of range" "^$" --seed -1)
ccmap_args_test(exp_lidar_seed_missing ccmap_exp_lidar 2 "^ccmap_exp_lidar: error: --seed: 1 required N missing" "^$" --seed)
ccmap_args_test(exp_fig6_gate_negative ccmap_exp_fig6 2 "^ccmap_exp_fig6: error: --gate: -1 is out of range" "^$" --gate -1)
ccmap_args_test(exp_outliers_change_share_nan ccmap_exp_outliers 2 "^ccmap_exp_outliers: error: --change-share: nan is out of range" "^$" --change-share nan)
ccmap_args_test(exp_lidar_change_points_not_a_number ccmap_exp_lidar 2 "^ccmap_exp_lidar: error: --change-points: '3p' is not a number" "^$" --change-points 3p)
# Gate values the library refuses are refused before the run (before: ccmap_exp_lidar --gate 0.5
# printed empty stack tables and exited 0; ccmap_traverse said "stack init failed", exit 1).
ccmap_args_test(exp_lidar_gate_below_one ccmap_exp_lidar 2 "^ccmap_exp_lidar: error: --gate: 0.5 is refused by the library's validate_stack_params" "^$" --gate 0.5)
ccmap_args_test(exp_outliers_change_share_above_half ccmap_exp_outliers 2 "^ccmap_exp_outliers: error: --change-share: 0.6 is refused by the library" "^$" --change-share 0.6)
ccmap_args_test(exp_fig6_help_own ccmap_exp_fig6 0 "^$" "--seeds A:B.*--merge SHARD.csv \\.\\.\\..*fig6_shard_<A>_<B>.csv" --help)
ccmap_args_test(exp_fig6_seeds_reversed ccmap_exp_fig6 2 "^ccmap_exp_fig6: error: --seeds: '5:3' is not A:B with B > A" "^$" --seeds 5:3)
ccmap_args_test(exp_fig6_seeds_no_colon ccmap_exp_fig6 2 "^ccmap_exp_fig6: error: --seeds: '3' is not A:B" "^$" --seeds 3)
ccmap_args_test(exp_fig6_merge_nothing ccmap_exp_fig6 2 "^ccmap_exp_fig6: error: --merge: 1 required SHARD.csv missing" "^$" --merge)
ccmap_args_test(exp_fig6_merge_then_option ccmap_exp_fig6 2 "^ccmap_exp_fig6: error: --merge: '--out' is not a shard file" "^$" --merge --out x)
# --seeds is read in base 10: 010:011 is seed 10 (CLI11's own integers would make it 8:9).
ccmap_args_test(exp_fig6_seeds_base_ten ccmap_exp_fig6 0 "^fig6: trial 1/1 \\(seed 10\\) done" "wrote shard .*/fig6_shard_10_11\\.csv"
                --quick --seeds 010:011 --out ${CMAKE_CURRENT_BINARY_DIR}/args_out/fig6_base_ten)
ccmap_args_test(exp_fig10_help_own ccmap_exp_fig10 0 "^$" "--odometry-sigma F +sigma of the uncertain moves" --help)
ccmap_args_test(exp_fig10_sigma_above_one ccmap_exp_fig10 2 "^ccmap_exp_fig10: error: --odometry-sigma: 2 is out of range \\(expected a number in \\[0, 1\\]\\)" "^$" --odometry-sigma 2)
ccmap_args_test(exp_fig10_sigma_nan ccmap_exp_fig10 2 "^ccmap_exp_fig10: error: --odometry-sigma: nan is out of range" "^$" --odometry-sigma nan)
ccmap_args_test(exp_fig10_sigma_not_a_number ccmap_exp_fig10 2 "^ccmap_exp_fig10: error: --odometry-sigma: '5%' is not a number" "^$" --odometry-sigma 5%)

ccmap_args_test(traverse_help ccmap_traverse 0 "^$" "Usage: ccmap_traverse.*--seed N=1.*--out DIR=out/traverse.*--stride K.*--frames N.*--quick.*--paper-cell.*--mismatch P=0.*--gate K.*--change-points M.*--change-share S" --help)
# Before CLI11 "--mismatch 0.1x" was read as 0.1 (strtod without an end check).
ccmap_args_test(traverse_mismatch_not_a_number ccmap_traverse 2 "^ccmap_traverse: error: --mismatch: '0.1x' is not a number" "^$" --mismatch 0.1x)
ccmap_args_test(traverse_mismatch_above_one ccmap_traverse 2 "^ccmap_traverse: error: --mismatch: 2 is out of range \\(expected a number in \\[0, 1\\]\\)" "^$" --mismatch 2)
ccmap_args_test(traverse_change_points_below_one ccmap_traverse 2 "^ccmap_traverse: error: --change-points: 0.5 is refused by the library" "^$" --change-points 0.5)
ccmap_args_test(traverse_gate_negative ccmap_traverse 2 "^ccmap_traverse: error: --gate: -3 is out of range" "^$" --gate -3)
ccmap_args_test(traverse_stride_zero ccmap_traverse 2 "^ccmap_traverse: error: --stride: 0 is out of range" "^$" --stride 0)
ccmap_args_test(traverse_frames_not_whole ccmap_traverse 2 "^ccmap_traverse: error: --frames: '2x' is not a whole number" "^$" --frames 2x)
# Before CLI11 a seed that is not a number silently became seed 0.
ccmap_args_test(traverse_seed_not_whole ccmap_traverse 2 "^ccmap_traverse: error: --seed: 'abc' is not a whole number" "^$" --seed abc)
ccmap_args_test(traverse_unknown ccmap_traverse 2 "^ccmap_traverse: error: .*not expected: --bogus" "^$" --bogus)

ccmap_args_test(team_help ccmap_team 0 "^$" "Usage: ccmap_team.*--rovers N=3.*--seed N=1.*--stride K=2.*--spacing M=0.3.*--every N=5.*--floor W=0.*--finest L=0.*--packet B.*--out DIR=out/team.*--quick" --help)
ccmap_args_test(team_rovers_zero ccmap_team 2 "^ccmap_team: error: --rovers: 0 is out of range" "^$" --rovers 0)
ccmap_args_test(team_seed_zero ccmap_team 2 "^ccmap_team: error: --seed: 0 is out of range \\(expected a whole number 1 \\.\\. 1000000000\\)" "^$" --seed 0)
ccmap_args_test(team_spacing_zero ccmap_team 2 "^ccmap_team: error: --spacing: 0 is out of range \\(expected a number in \\(0, 1e\\+09\\]\\)" "^$" --spacing 0)
ccmap_args_test(team_floor_negative ccmap_team 2 "^ccmap_team: error: --floor: -1 is out of range" "^$" --floor -1)
ccmap_args_test(team_finest_five ccmap_team 2 "^ccmap_team: error: --finest: 5 is out of range \\(expected a whole number 0 \\.\\. 4\\)" "^$" --finest 5)
ccmap_args_test(team_packet_not_whole ccmap_team 2 "^ccmap_team: error: --packet: '1.5' is not a whole number" "^$" --packet 1.5)
ccmap_args_test(team_unknown ccmap_team 2 "^ccmap_team: error: .*not expected: --bogus" "^$" --bogus)
