// Reading a session's results back for the runner's tests (plain SQLite
// through the data layer's RAII wrappers).
#pragma once

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/sqlite.hpp"

#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

namespace curvlab::testing {

// One folder per test and process: suites of two checkouts may run at once.
inline std::filesystem::path test_dir(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("curvlab_runner_" + name + "_" + std::to_string(::getpid()));
}

// test_dir(name), emptied.
inline std::filesystem::path fresh_dir(const std::string& name) {
  const auto dir = test_dir(name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Rows of a query, each column as text ("NULL" for null).
inline std::vector<std::vector<std::string>> query(const std::string& db_path, const std::string& sql) {
  auto db = harness::data::Database::open(db_path, harness::data::OpenMode::read_only);
  std::vector<std::vector<std::string>> rows;
  if (!db) return rows;
  harness::data::Statement s(db.value().connection(), sql);
  while (s.step()) {
    std::vector<std::string> row;
    for (int c = 0; c < s.column_count(); ++c) row.push_back(s.is_null(c) ? "NULL" : s.column_text(c));
    rows.push_back(std::move(row));
  }
  return rows;
}

inline std::string integrity(const std::string& db_path) {
  auto db = harness::data::Database::open(db_path, harness::data::OpenMode::read_only);
  if (!db) return db.error().message;
  return db.value().integrity_check();
}

}  // namespace curvlab::testing
