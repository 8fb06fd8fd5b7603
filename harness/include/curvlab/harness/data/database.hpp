// Opening, creating and migrating a curvlab data file (DESIGN.md §7). The
// schema is data_schema/schema.sql, embedded at build time and executed
// verbatim; older files are migrated with data_schema/migrations/, newer ones
// refused.
#pragma once

#include "curvlab/harness/data/error.hpp"
#include "curvlab/harness/data/sqlite.hpp"

#include <cstdint>
#include <string>
#include <string_view>

namespace curvlab::harness::data {

// The schema version this build writes (PRAGMA user_version).
inline constexpr std::int64_t current_schema_version = 9;
// Marks curvlab files (PRAGMA application_id, ASCII "CVLB").
inline constexpr std::int64_t curvlab_application_id = 0x43564C42;
// Free space required before a session may start; below it opening for a
// session fails with disk_full instead of failing mid-session.
inline constexpr std::uint64_t min_free_bytes_to_start = 64ull << 20;

// The free space a create_or_open asks for, and what for (in its message).
struct SpaceNeeded {
  std::uint64_t bytes = min_free_bytes_to_start;
  std::string what = "a session";
};

// The embedded SQL texts (generated from data_schema/ at build time).
std::string_view schema_sql();
// The migration that brings version `to - 1` to `to`; empty when none exists.
std::string_view migration_sql(std::int64_t to);

enum class OpenMode {
  create_or_open,  // for running sessions: create if missing, migrate if older,
                   // check free space and writability
  open_existing,   // for export: the file must exist; migrates if older
  read_only,       // export, replay, merge inputs: never writes, works on read-only
                   // media; an older file is read through a migrated copy in memory
};

// Owns the connection of one thread (the session thread). WAL mode, foreign
// keys on, synchronous=FULL so that a committed trial survives power loss.
// Move-only; not thread-safe (one thread at a time).
class Database {
 public:
  static Expected<Database> open(const std::string& path, OpenMode mode, const SpaceNeeded& needed = {});

  Connection& connection() { return connection_; }
  const std::string& path() const { return connection_.path(); }
  std::int64_t schema_version() { return connection_.query_int("PRAGMA user_version"); }
  // "ok" when PRAGMA integrity_check passes, else its first message.
  std::string integrity_check();

 private:
  explicit Database(Connection connection) : connection_(std::move(connection)) {}
  // The checks after SQLite has opened the file: foreign or newer files,
  // damaged schemas and (for writers) damaged pages; then WAL mode, the
  // schema created or migrated. Read-only opens of an older file migrate a
  // copy in memory.
  static Expected<Database> checked(Connection connection, const std::string& path, OpenMode mode);
  Connection connection_;
};

// Checks an existing file without SQLite, before anything opens or writes it:
// a file that is not SQLite at all, or another program's SQLite database, is
// refused as not_curvlab, one shorter than its own header says (a copy cut
// off, a disk that filled while copying) as corrupt. A missing or empty file passes (it is created). Database::open
// calls it first; commands call it before they start a window or headset, so
// a bad --db is reported at once. The messages say whether the file can be
// read at all and how to recover committed data (docs/data.md, "Damaged or
// foreign files").
Expected<Done> check_data_file(const std::string& path);

// The schema version a file records (PRAGMA user_version, read-only), or -1
// when it cannot be read.
std::int64_t stored_schema_version(const std::string& path);

// The error for another program's SQLite file (application_id ≠ "CVLB").
DataError foreign_file_error(const std::string& path, std::int64_t application_id);

// The error for a damaged curvlab file: `what` says what is wrong; the message
// adds that only part of it can be read and the SQLite shell's .recover.
DataError corrupt_file_error(const std::string& path, const std::string& what);

// The connection settings every curvlab connection uses (WAL, busy timeout…).
void configure_connection(Connection& connection, bool synchronous_full);

// Removes a database file and its companions (-wal, -shm, -journal), if
// there; for temporary files (merge's staging copy, a pooled export).
void remove_database_files(const std::string& path);

}  // namespace curvlab::harness::data
