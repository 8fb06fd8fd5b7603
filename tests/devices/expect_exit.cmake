execute_process(COMMAND ${CURVLAB} devices --mapping ${MAPPING}
  RESULT_VARIABLE rc ERROR_VARIABLE err OUTPUT_QUIET)
if(NOT rc EQUAL 2)
  message(FATAL_ERROR "expected exit code 2, got ${rc}: ${err}")
endif()
if(NOT err MATCHES "bad_axis.toml:10:9: device\\[0\\]\\.binding\\[0\\]\\.above: expected an integer in 0 … 255, got 300")
  message(FATAL_ERROR "unexpected message: ${err}")
endif()
