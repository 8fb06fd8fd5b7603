// Files the data tests make and read: a fresh folder per test, whole files
// as bytes, one value of an SQL query.
#pragma once

#include "curvlab/harness/data/database.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace curvlab::testing {

namespace fs = std::filesystem;

// An empty folder under the temporary folder, named for the test and the process.
inline fs::path fresh_test_dir(const std::string& prefix, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("curvlab_" + prefix + "_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_file(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

// The first column of the first row ("NULL" for none), or the open error.
inline std::string scalar(const fs::path& db, const std::string& sql) {
  auto d = harness::data::Database::open(db.string(), harness::data::OpenMode::read_only);
  if (!d) return d.error().message;
  harness::data::Statement s(d.value().connection(), sql);
  if (!s.step() || s.is_null(0)) return "NULL";
  return s.column_text(0);
}

}  // namespace curvlab::testing
