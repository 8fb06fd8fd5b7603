# Software version and git commit, recorded with every session for provenance.
execute_process(
  COMMAND git rev-parse --short=12 HEAD
  WORKING_DIRECTORY "${CMAKE_SOURCE_DIR}"
  OUTPUT_VARIABLE CURVLAB_GIT_COMMIT
  OUTPUT_STRIP_TRAILING_WHITESPACE
  ERROR_QUIET)
if(NOT CURVLAB_GIT_COMMIT)
  set(CURVLAB_GIT_COMMIT "unknown")
endif()
