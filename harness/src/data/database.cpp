#include "curvlab/harness/data/database.hpp"

#include <sqlite3.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <filesystem>
#include <system_error>

namespace curvlab::data {
namespace {

namespace fs = std::filesystem;

std::string utc_now_sql() { return "strftime('%Y-%m-%dT%H:%M:%fZ', 'now')"; }

// Checks made before a session starts, so that a read-only folder or a full
// disk is reported up front rather than as a failure in the middle of trials.
std::optional<DataError> check_writable_location(const std::string& path) {
  const fs::path file(path);
  fs::path dir = file.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    return DataError{DataError::Kind::io,
                     path + ": folder " + dir.string() + " does not exist (create it first)"};
  }
  if (::access(dir.c_str(), W_OK) != 0) {
    return DataError{DataError::Kind::read_only,
                     path + ": folder " + dir.string() +
                         " is not writable (the WAL journal needs a writable folder)"};
  }
  if (fs::exists(file, ec) && ::access(file.c_str(), W_OK) != 0) {
    return DataError{DataError::Kind::read_only, path + ": file is read-only"};
  }
  struct statvfs st {};
  if (::statvfs(dir.c_str(), &st) == 0) {
    const std::uint64_t free_bytes = std::uint64_t{st.f_bavail} * std::uint64_t{st.f_frsize};
    if (free_bytes < min_free_bytes_to_start) {
      return DataError{DataError::Kind::disk_full,
                       path + ": only " + std::to_string(free_bytes >> 20) +
                           " MiB free; a session needs at least " +
                           std::to_string(min_free_bytes_to_start >> 20) + " MiB"};
    }
  }
  return std::nullopt;
}

bool is_empty_database(Connection& c) {
  return c.query_int("SELECT count(*) FROM sqlite_master") == 0;
}

void create_schema(Connection& c) {
  Transaction txn(c);
  c.exec(schema_sql());
  c.exec("PRAGMA application_id = " + std::to_string(curvlab_application_id));
  c.exec("INSERT INTO schema_migrations (version, applied_utc, note) VALUES (" +
         std::to_string(current_schema_version) + ", " + utc_now_sql() +
         ", 'created by curvlab')");
  txn.commit();
}

void migrate(Connection& c, std::int64_t from) {
  // Foreign keys must be off while tables are rebuilt (a pragma that cannot
  // change inside a transaction); they are checked before the commit.
  c.exec("PRAGMA foreign_keys = OFF");
  {
    Transaction txn(c);
    for (std::int64_t v = from + 1; v <= current_schema_version; ++v) {
      const std::string_view sql = migration_sql(v);
      if (sql.empty())
        throw SqliteFailure(SQLITE_ERROR, "no migration to schema version " + std::to_string(v));
      c.exec(sql);
    }
    c.exec("PRAGMA application_id = " + std::to_string(curvlab_application_id));
    if (c.query_int("SELECT count(*) FROM pragma_foreign_key_check") != 0)
      throw SqliteFailure(SQLITE_CONSTRAINT, "migration left dangling foreign keys");
    txn.commit();
  }
  c.exec("PRAGMA foreign_keys = ON");
}

}  // namespace

void configure_connection(Connection& c, bool synchronous_full) {
  sqlite3_busy_timeout(c.get(), 5000);
  c.exec("PRAGMA foreign_keys = ON");
  c.exec(synchronous_full ? "PRAGMA synchronous = FULL" : "PRAGMA synchronous = NORMAL");
}

Expected<Database> Database::open(const std::string& path, OpenMode mode) {
  if (path.empty()) return DataError{DataError::Kind::io, "no database path given"};
  std::error_code ec;
  const bool exists = std::filesystem::exists(path, ec);
  if (mode != OpenMode::create_or_open && !exists)
    return DataError{DataError::Kind::io, path + ": no such file"};
  if (exists && std::filesystem::is_directory(path, ec))
    return DataError{DataError::Kind::io, path + ": is a folder, expected a database file"};
  if (mode == OpenMode::create_or_open) {
    if (auto problem = check_writable_location(path)) return *problem;
  }
  try {
    const OpenFlags flags = mode == OpenMode::create_or_open ? OpenFlags::read_write_create
                            : mode == OpenMode::open_existing ? OpenFlags::read_write
                                                              : OpenFlags::read_only;
    Connection c = Connection::open(path, flags);
    // Reading the header first turns "file is not a database" into a clear error.
    const std::int64_t version = c.query_int("PRAGMA user_version");
    const std::int64_t app_id = c.query_int("PRAGMA application_id");
    const bool empty = is_empty_database(c);
    if (!empty && app_id != curvlab_application_id && !(app_id == 0 && version == 1)) {
      return DataError{DataError::Kind::not_curvlab,
                       path + ": not a curvlab data file (application_id " +
                           std::to_string(app_id) + ")"};
    }
    if (version > current_schema_version) {
      return DataError{DataError::Kind::newer_schema,
                       path + ": written with schema version " + std::to_string(version) +
                           " by a newer curvlab; this build understands up to version " +
                           std::to_string(current_schema_version) +
                           ". Use a newer curvlab; the file was not modified."};
    }
    if (mode == OpenMode::read_only) {
      if (empty || version < current_schema_version)
        return DataError{DataError::Kind::io,
                         path + ": schema version " + std::to_string(version) +
                             " needs migrating to " + std::to_string(current_schema_version) +
                             "; open it once writable (for example with curvlab export)"};
      configure_connection(c, false);
      return Database(std::move(c));
    }
    c.exec("PRAGMA journal_mode = WAL");
    configure_connection(c, true);
    if (empty) {
      create_schema(c);
    } else if (version < current_schema_version) {
      migrate(c, version);
    }
    return Database(std::move(c));
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, path);
  }
}

std::string Database::integrity_check() {
  Statement stmt(connection_, "PRAGMA integrity_check");
  if (!stmt.step()) return "no result";
  return stmt.column_text(0);
}

}  // namespace curvlab::data
