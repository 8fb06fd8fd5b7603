# docs/data.md names the current schema version where it describes the file
# (`schema.sql` (version N), the study database merge writes, the version
# analysis/R/io.R accepts); each must be the `PRAGMA user_version` that
# data_schema/schema.sql sets.
file(READ "${SOURCE_DIR}/data_schema/schema.sql" schema)
if(NOT schema MATCHES "PRAGMA user_version = ([0-9]+);")
  message(FATAL_ERROR "data_schema/schema.sql sets no PRAGMA user_version")
endif()
set(version "${CMAKE_MATCH_1}")
file(READ "${SOURCE_DIR}/docs/data.md" doc)
foreach(claim
    "`data_schema/schema.sql` \\(version ([0-9]+)"
    "database of the current schema \\(version ([0-9]+)\\)"
    "`analysis/R/io.R` accepts exactly version ([0-9]+)")
  if(NOT doc MATCHES "${claim}")
    message(FATAL_ERROR "docs/data.md no longer says '${claim}'; keep it stating the schema version")
  endif()
  if(NOT CMAKE_MATCH_1 STREQUAL version)
    message(FATAL_ERROR "docs/data.md says '${CMAKE_MATCH_0}', but data_schema/schema.sql is version ${version}")
  endif()
endforeach()
