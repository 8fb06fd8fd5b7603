# Writes a C++ source holding the data_schema/ SQL texts as raw string
# literals, so the program creates exactly the schema in those files.
# Inputs: SCHEMA_DIR, OUTPUT.
file(READ "${SCHEMA_DIR}/schema.sql" schema)
file(READ "${SCHEMA_DIR}/migrations/0002_from_v1.sql" m2)
file(READ "${SCHEMA_DIR}/migrations/0003_from_v2.sql" m3)
file(READ "${SCHEMA_DIR}/migrations/0004_from_v3.sql" m4)
file(READ "${SCHEMA_DIR}/migrations/0005_from_v4.sql" m5)
file(READ "${SCHEMA_DIR}/migrations/0006_from_v5.sql" m6)
file(READ "${SCHEMA_DIR}/migrations/0007_from_v6.sql" m7)
file(READ "${SCHEMA_DIR}/migrations/0008_from_v7.sql" m8)
file(READ "${SCHEMA_DIR}/migrations/0009_from_v8.sql" m9)
foreach(text IN ITEMS "${schema}" "${m2}" "${m3}" "${m4}" "${m5}" "${m6}" "${m7}" "${m8}" "${m9}")
  string(FIND "${text}" ")curvlab_sql\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "SQL text contains the raw-string delimiter")
  endif()
endforeach()
file(WRITE "${OUTPUT}.tmp" "// Generated from data_schema/ by embed_sql.cmake; do not edit.
#include \"curvlab/harness/data/database.hpp\"

namespace curvlab::harness::data {
namespace {
constexpr std::string_view k_schema = R\"curvlab_sql(${schema})curvlab_sql\";
constexpr std::string_view k_migration_2 = R\"curvlab_sql(${m2})curvlab_sql\";
constexpr std::string_view k_migration_3 = R\"curvlab_sql(${m3})curvlab_sql\";
constexpr std::string_view k_migration_4 = R\"curvlab_sql(${m4})curvlab_sql\";
constexpr std::string_view k_migration_5 = R\"curvlab_sql(${m5})curvlab_sql\";
constexpr std::string_view k_migration_6 = R\"curvlab_sql(${m6})curvlab_sql\";
constexpr std::string_view k_migration_7 = R\"curvlab_sql(${m7})curvlab_sql\";
constexpr std::string_view k_migration_8 = R\"curvlab_sql(${m8})curvlab_sql\";
constexpr std::string_view k_migration_9 = R\"curvlab_sql(${m9})curvlab_sql\";
}  // namespace

std::string_view schema_sql() { return k_schema; }

std::string_view migration_sql(std::int64_t to) {
  if (to == 2) return k_migration_2;
  if (to == 3) return k_migration_3;
  if (to == 4) return k_migration_4;
  if (to == 5) return k_migration_5;
  if (to == 6) return k_migration_6;
  if (to == 7) return k_migration_7;
  if (to == 8) return k_migration_8;
  if (to == 9) return k_migration_9;
  return {};
}

}  // namespace curvlab::harness::data
")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
