# Runs `curvlab ARGS…` (arguments separated by '|') and checks its exit code
# and that its stdout+stderr match EXPECT (a regular expression).
string(REPLACE "|" ";" args "${ARGS}")
execute_process(COMMAND ${CURVLAB} ${args}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL ${RC})
  message(FATAL_ERROR "curvlab ${ARGS}: expected exit code ${RC}, got ${rc}\n${out}${err}")
endif()
if(NOT "${out}${err}" MATCHES "${EXPECT}")
  message(FATAL_ERROR "curvlab ${ARGS}: output does not match '${EXPECT}':\n${out}${err}")
endif()
