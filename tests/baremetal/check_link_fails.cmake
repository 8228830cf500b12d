# The no-heap promise as a link error: links a probe that calls malloc and operator new with the
# board's linker script and succeeds only if that link fails with the script's heap message.
#
#   cmake -DCXX=<compiler> -DFLAGS=<compile+link flags string> -DLINK_OPTIONS=<list>
#         -DOBJECTS=<list> -DOUTPUT=<elf> -DEXPECT_MESSAGE=<regex> -P check_link_fails.cmake
separate_arguments(_flags UNIX_COMMAND "${FLAGS}")
file(REMOVE ${OUTPUT})
execute_process(COMMAND ${CXX} ${_flags} ${LINK_OPTIONS} ${OBJECTS} -o ${OUTPUT}
                RESULT_VARIABLE _rc OUTPUT_VARIABLE _out ERROR_VARIABLE _err)
if(_rc EQUAL 0)
  message(FATAL_ERROR "the probe linked: the heap is not a link error (${OUTPUT})")
endif()
if(NOT "${_out}${_err}" MATCHES "${EXPECT_MESSAGE}")
  message(FATAL_ERROR "the probe's link failed, but not with '${EXPECT_MESSAGE}':\n${_out}${_err}")
endif()
string(REGEX MATCH "[^\n]*${EXPECT_MESSAGE}[^\n]*" _line "${_out}${_err}")
message(STATUS "the allocating probe does not link, as it must not:\n  ${_line}")
