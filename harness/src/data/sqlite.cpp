#include "curvlab/harness/data/sqlite.hpp"

#include "curvlab/harness/data/database.hpp"

#include <sqlite3.h>

#include "curvlab/harness/platform/files.hpp"

#include <cstring>
#include <filesystem>

namespace curvlab::harness::data {

DataError to_data_error(const SqliteFailure& failure, const std::string& path) {
  const std::string where = path + ": " + failure.what();
  switch (failure.code & 0xff) {
    case SQLITE_FULL:
      return {DataError::Kind::disk_full,
              where + " (the disk is full: free space, then resume; committed trials are kept)"};
    case SQLITE_READONLY:
    case SQLITE_PERM:
      return {DataError::Kind::read_only,
              where + " (the file or its folder is not writable: choose a writable --db path)"};
    case SQLITE_CANTOPEN:
      return {DataError::Kind::io, where + " (check that the folder exists and is writable; on read-only media "
                                           "a file with a write-ahead log needs its -shm file beside it, or a "
                                           "copy of the three files in a writable folder)"};
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      return {DataError::Kind::busy, where + " (another process is writing this file)"};
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
      return corrupt_file_error(path, std::string("SQLite reports \"") + failure.what() + "\"");
    case SQLITE_CONSTRAINT:
    case SQLITE_MISMATCH:
    case SQLITE_RANGE:
      return {DataError::Kind::bad_input, where};
    default:
      return {DataError::Kind::io, where};
  }
}

void SqliteCloser::operator()(sqlite3* db) const noexcept {
  // close_v2 defers the close until the last statement is finalized, so the
  // destruction order of statements and connection cannot leak or crash.
  sqlite3_close_v2(db);
}

void StatementFinalizer::operator()(sqlite3_stmt* stmt) const noexcept { sqlite3_finalize(stmt); }

bool needs_immutable_open(const std::string& path) {
  // On read-only media SQLite cannot create the -shm index a WAL file needs
  // (sqlite.org/wal.html, "Read-Only Databases"); without a log there is
  // nothing it would hold, and the file can be read as immutable.
  std::error_code ec;
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty()) dir = ".";
  if (platform::writable(dir.string()) || std::filesystem::exists(path + "-shm", ec)) return false;
  return !std::filesystem::exists(path + "-wal", ec) || std::filesystem::file_size(path + "-wal", ec) == 0;
}

std::string file_uri(const std::string& path, std::string_view query) {
  const std::string absolute = std::filesystem::absolute(path).lexically_normal().string();
  static constexpr std::string_view plain = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789/._-~";
  static constexpr char digits[] = "0123456789ABCDEF";
  std::string out = "file:";
  for (const char ch : absolute) {
    if (plain.find(ch) != std::string_view::npos) {
      out += ch;
    } else {
      const auto b = static_cast<unsigned char>(ch);
      out += '%';
      out += digits[b >> 4];
      out += digits[b & 0xF];
    }
  }
  return out + "?" + std::string(query);
}

Connection Connection::open(const std::string& path, OpenFlags flags) {
  int sqlite_flags = SQLITE_OPEN_NOMUTEX;  // one thread per connection by contract
  switch (flags) {
    case OpenFlags::read_write_create: sqlite_flags |= SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE; break;
    case OpenFlags::read_write: sqlite_flags |= SQLITE_OPEN_READWRITE; break;
    case OpenFlags::read_only: sqlite_flags |= SQLITE_OPEN_READONLY; break;
  }
  const bool immutable = flags == OpenFlags::read_only && path != ":memory:" && needs_immutable_open(path);
  const std::string name = immutable ? file_uri(path, "mode=ro&immutable=1") : path;
  if (immutable) sqlite_flags |= SQLITE_OPEN_URI;
  sqlite3* raw = nullptr;
  const int rc = sqlite3_open_v2(name.c_str(), &raw, sqlite_flags, nullptr);
  ConnectionHandle handle(raw);
  if (rc != SQLITE_OK) {
    const std::string msg = raw ? sqlite3_errmsg(raw) : sqlite3_errstr(rc);
    throw SqliteFailure(rc, "cannot open database: " + msg);
  }
  sqlite3_extended_result_codes(raw, 1);
  if (flags == OpenFlags::read_only) sqlite3_db_config(raw, SQLITE_DBCONFIG_NO_CKPT_ON_CLOSE, 1, nullptr);
  return Connection(std::move(handle), path);
}

Connection Connection::copy_into_memory(Connection& source) {
  Connection copy = open(":memory:", OpenFlags::read_write_create);
  sqlite3_backup* backup = sqlite3_backup_init(copy.get(), "main", source.get(), "main");
  if (backup == nullptr) copy.fail(sqlite3_errcode(copy.get()), "copy of " + source.path());
  const int rc = sqlite3_backup_step(backup, -1);
  sqlite3_backup_finish(backup);
  if (rc != SQLITE_DONE) source.fail(rc, "copy of " + source.path());
  copy.path_ = source.path_;
  return copy;
}

void Connection::fail(int code, std::string_view context) const {
  throw SqliteFailure(code, std::string(context) + ": " + sqlite3_errmsg(handle_.get()));
}

void Connection::exec(std::string_view sql) {
  const std::string text(sql);
  char* err = nullptr;
  const int rc = sqlite3_exec(handle_.get(), text.c_str(), nullptr, nullptr, &err);
  if (rc != SQLITE_OK) {
    std::string msg = err ? err : sqlite3_errstr(rc);
    sqlite3_free(err);
    throw SqliteFailure(rc, msg);
  }
}

std::int64_t Connection::query_int(std::string_view sql) {
  Statement stmt(*this, sql);
  if (!stmt.step()) return 0;
  return stmt.column_int(0);
}

std::int64_t Connection::last_insert_rowid() const { return sqlite3_last_insert_rowid(handle_.get()); }
int Connection::changes() const { return sqlite3_changes(handle_.get()); }

Statement::Statement(Connection& db, std::string_view sql) : db_(&db) {
  sqlite3_stmt* raw = nullptr;
  const int rc = sqlite3_prepare_v3(db.get(), sql.data(), static_cast<int>(sql.size()),
                                    SQLITE_PREPARE_PERSISTENT, &raw, nullptr);
  handle_.reset(raw);
  if (rc != SQLITE_OK) db.fail(rc, "cannot prepare \"" + std::string(sql.substr(0, 60)) + "\"");
}

namespace {
void check_bind(Connection& db, int rc) {
  if (rc != SQLITE_OK) db.fail(rc, "bind");
}
}  // namespace

Statement& Statement::bind(int index, std::int64_t value) {
  check_bind(*db_, sqlite3_bind_int64(handle_.get(), index, value));
  return *this;
}
Statement& Statement::bind(int index, double value) {
  check_bind(*db_, sqlite3_bind_double(handle_.get(), index, value));
  return *this;
}
Statement& Statement::bind(int index, std::string_view value) {
  check_bind(*db_, sqlite3_bind_text64(handle_.get(), index, value.data(), value.size(),
                                       SQLITE_TRANSIENT, SQLITE_UTF8));
  return *this;
}
Statement& Statement::bind_static(int index, std::string_view value) {
  check_bind(*db_, sqlite3_bind_text64(handle_.get(), index, value.data(), value.size(),
                                       SQLITE_STATIC, SQLITE_UTF8));
  return *this;
}
Statement& Statement::bind_blob(int index, std::span<const std::byte> bytes) {
  check_bind(*db_, sqlite3_bind_blob64(handle_.get(), index, bytes.data(), bytes.size(),
                                       SQLITE_TRANSIENT));
  return *this;
}
Statement& Statement::bind_null(int index) {
  check_bind(*db_, sqlite3_bind_null(handle_.get(), index));
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(handle_.get());
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  sqlite3_reset(handle_.get());
  db_->fail(rc, "step");
}

void Statement::run() {
  while (step()) {
  }
  reset();
}

void Statement::reset() {
  sqlite3_reset(handle_.get());
  sqlite3_clear_bindings(handle_.get());
}

bool Statement::is_null(int column) const {
  return sqlite3_column_type(handle_.get(), column) == SQLITE_NULL;
}
std::int64_t Statement::column_int(int column) const { return sqlite3_column_int64(handle_.get(), column); }
double Statement::column_double(int column) const { return sqlite3_column_double(handle_.get(), column); }
std::string Statement::column_text(int column) const {
  const auto* text = sqlite3_column_text(handle_.get(), column);
  const int n = sqlite3_column_bytes(handle_.get(), column);
  if (!text) return {};
  return std::string(reinterpret_cast<const char*>(text), static_cast<std::size_t>(n));
}
std::optional<std::int64_t> Statement::column_opt_int(int column) const {
  if (is_null(column)) return std::nullopt;
  return column_int(column);
}
std::optional<double> Statement::column_opt_double(int column) const {
  if (is_null(column)) return std::nullopt;
  return column_double(column);
}
std::optional<std::string> Statement::column_opt_text(int column) const {
  if (is_null(column)) return std::nullopt;
  return column_text(column);
}
std::span<const std::byte> Statement::column_blob(int column) const {
  const void* data = sqlite3_column_blob(handle_.get(), column);
  const int n = sqlite3_column_bytes(handle_.get(), column);
  return {static_cast<const std::byte*>(data), static_cast<std::size_t>(n)};
}
int Statement::column_count() const { return sqlite3_column_count(handle_.get()); }
std::string Statement::column_name(int column) const {
  return sqlite3_column_name(handle_.get(), column);
}

Transaction::Transaction(Connection& db) : db_(&db) { db.exec("BEGIN IMMEDIATE"); }

Transaction::~Transaction() {
  if (open_) sqlite3_exec(db_->get(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::commit() {
  db_->exec("COMMIT");
  open_ = false;
}

}  // namespace curvlab::harness::data
