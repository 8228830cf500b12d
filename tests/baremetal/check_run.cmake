# Runs a board image and checks its exit code and output (for images that must fail in a
# particular way, which a plain ctest exit-code test cannot tell apart from another failure).
#
#   cmake -DEMULATOR=<command;...> -DIMAGE=<elf> -DEXPECT_CODE=<n> -DEXPECT_OUTPUT=<regex>
#         -P check_run.cmake
execute_process(COMMAND ${EMULATOR} ${IMAGE} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                TIMEOUT 50)
if(NOT rc STREQUAL "${EXPECT_CODE}")
  message(FATAL_ERROR "${IMAGE} exited with '${rc}', expected ${EXPECT_CODE}:\n${out}${err}")
endif()
if(NOT "${out}" MATCHES "${EXPECT_OUTPUT}")
  message(FATAL_ERROR "${IMAGE} did not print '${EXPECT_OUTPUT}':\n${out}${err}")
endif()
message(STATUS "exit code ${rc} and the expected report:\n${out}")
