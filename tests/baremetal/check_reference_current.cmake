# cmake -DGENERATOR=<exe> -DCOMMITTED=<file> -DOUTPUT=<file> -P check_reference_current.cmake
# Fails if the committed reference data differs from what the generator writes now.
execute_process(COMMAND ${GENERATOR} OUTPUT_FILE ${OUTPUT} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${GENERATOR} failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUTPUT} ${COMMITTED} RESULT_VARIABLE differ)
if(differ)
  message(FATAL_ERROR "${COMMITTED} is not the output of ${GENERATOR}: regenerate it "
                      "(${GENERATOR} > ${COMMITTED}) and review the change")
endif()
message(STATUS "${COMMITTED} is current")
