# Monte-Carlo campaigns (tools/campaign): a tiny Fig. 6/7 campaign through GNU parallel and
# through the Slurm array script equals the one-process run (tests/tools/campaign_test.sh).
# Included from tests/tools/CMakeLists.txt (host builds with the tools).
add_test(NAME ccmap_campaign_fig6_shards_merge_exactly
         COMMAND ${CMAKE_CURRENT_LIST_DIR}/campaign_test.sh $<TARGET_FILE:ccmap_exp_fig6> ${PROJECT_SOURCE_DIR}
                 ${CMAKE_CURRENT_BINARY_DIR}/campaign)
set_tests_properties(ccmap_campaign_fig6_shards_merge_exactly PROPERTIES
  LABELS "tools;campaign" TIMEOUT 600 SKIP_RETURN_CODE 77)
