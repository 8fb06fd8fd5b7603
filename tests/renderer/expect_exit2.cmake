# Runs EXE render ARGS and requires exit code 2 with a message on stderr.
execute_process(COMMAND ${EXE} render ${ARGS} RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 2)
  message(FATAL_ERROR "expected exit code 2, got ${rc}: ${err}")
endif()
if(err STREQUAL "")
  message(FATAL_ERROR "expected a message on stderr")
endif()
message(STATUS "${err}")
