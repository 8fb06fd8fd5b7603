// Thin RAII layer over the SQLite C API: every sqlite3 and sqlite3_stmt handle
// is owned by exactly one move-only object, and a Transaction rolls back
// unless committed. SQLite failures inside the data layer are thrown as
// SqliteFailure and turned into DataError values at the public API boundary.
//
// Thread-safety: none of these types may be used from two threads at once;
// a Connection (and its statements) belongs to one thread at a time.
#pragma once

#include "curvlab/harness/data/error.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

struct sqlite3;
struct sqlite3_stmt;

namespace curvlab::harness::data {

struct SqliteFailure : std::runtime_error {
  SqliteFailure(int result_code, const std::string& message)
      : std::runtime_error(message), code(result_code) {}
  int code;  // the primary SQLite result code (SQLITE_FULL, SQLITE_READONLY, …)
};

// Maps a failure to the DataError kind a person can act on; `path` names the file.
DataError to_data_error(const SqliteFailure& failure, const std::string& path);

struct SqliteCloser {
  void operator()(sqlite3* db) const noexcept;
};
struct StatementFinalizer {
  void operator()(sqlite3_stmt* stmt) const noexcept;
};
using ConnectionHandle = std::unique_ptr<sqlite3, SqliteCloser>;
using StatementHandle = std::unique_ptr<sqlite3_stmt, StatementFinalizer>;

enum class OpenFlags { read_write_create, read_write, read_only };

// True when `path` lies in a folder that cannot be written (read-only media)
// with no -shm file and no write-ahead log content: SQLite can then read it
// only as immutable. Connection::open does so itself for read_only.
bool needs_immutable_open(const std::string& path);
// A file: URI for `path` with the given query ("mode=ro"), percent-encoded.
std::string file_uri(const std::string& path, std::string_view query);

// Owns one sqlite3 connection. Move-only.
class Connection {
 public:
  // Throws SqliteFailure. Read-only connections never checkpoint, so closing
  // one never deletes a write-ahead log another process is still writing.
  static Connection open(const std::string& path, OpenFlags flags);
  // A writable in-memory copy of `source` (SQLite's backup API), named after
  // it in messages. Throws SqliteFailure.
  static Connection copy_into_memory(Connection& source);

  sqlite3* get() const { return handle_.get(); }
  const std::string& path() const { return path_; }

  // Runs one or more statements without results (DDL, PRAGMA). Throws.
  void exec(std::string_view sql);
  // Runs a single-value query such as "PRAGMA user_version". Throws.
  std::int64_t query_int(std::string_view sql);
  std::int64_t last_insert_rowid() const;
  int changes() const;
  [[noreturn]] void fail(int code, std::string_view context) const;

 private:
  Connection(ConnectionHandle handle, std::string path)
      : handle_(std::move(handle)), path_(std::move(path)) {}
  ConnectionHandle handle_;
  std::string path_;
};

// A prepared statement. Bind indices are 1-based as in SQLite. Move-only; the
// Connection must outlive it.
class Statement {
 public:
  Statement(Connection& db, std::string_view sql);  // throws

  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, int value) { return bind(index, std::int64_t{value}); }
  Statement& bind(int index, double value);
  Statement& bind(int index, std::string_view value);  // copied (SQLITE_TRANSIENT)
  Statement& bind_static(int index, std::string_view value);  // must outlive the step
  Statement& bind_blob(int index, std::span<const std::byte> bytes);
  Statement& bind_null(int index);
  template <class T>
  Statement& bind(int index, const std::optional<T>& value) {
    if (value) return bind(index, *value);
    return bind_null(index);
  }

  // Returns true while a row is available, false when done. Throws on error.
  bool step();
  // Runs to completion and resets (for INSERT / UPDATE).
  void run();
  void reset();

  bool is_null(int column) const;
  std::int64_t column_int(int column) const;
  double column_double(int column) const;
  std::string column_text(int column) const;
  std::optional<std::int64_t> column_opt_int(int column) const;
  std::optional<double> column_opt_double(int column) const;
  std::optional<std::string> column_opt_text(int column) const;
  std::span<const std::byte> column_blob(int column) const;
  int column_count() const;
  std::string column_name(int column) const;

  // The row's columns 0, 1, … read into `out` in order, each by its type:
  // int64, double, bool, string, or an optional of one (NULL: nullopt).
  template <class... T>
  void columns(T&... out) const {
    int column = 0;
    (read_column(column++, out), ...);
  }

 private:
  void read_column(int c, std::int64_t& v) const { v = column_int(c); }
  void read_column(int c, double& v) const { v = column_double(c); }
  void read_column(int c, bool& v) const { v = column_int(c) != 0; }
  void read_column(int c, std::string& v) const { v = column_text(c); }
  void read_column(int c, std::optional<std::int64_t>& v) const { v = column_opt_int(c); }
  void read_column(int c, std::optional<double>& v) const { v = column_opt_double(c); }
  void read_column(int c, std::optional<std::string>& v) const { v = column_opt_text(c); }

  Connection* db_;
  StatementHandle handle_;
};

// BEGIN IMMEDIATE on construction; ROLLBACK in the destructor unless commit()
// succeeded. Never throws from the destructor.
class Transaction {
 public:
  explicit Transaction(Connection& db);  // throws
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  ~Transaction();
  void commit();  // throws; after a failed commit the destructor rolls back

 private:
  Connection* db_;
  bool open_ = true;
};

}  // namespace curvlab::harness::data
