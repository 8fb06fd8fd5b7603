#include "curvlab/harness/data/database.hpp"

#include <sqlite3.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
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

// A path as a shell needs it in a command the message suggests.
std::string shell_quoted(const std::string& path) {
  static constexpr std::string_view plain =
      "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789/._-+,:@%=";
  if (!path.empty() && path.find_first_not_of(plain) == std::string::npos) return path;
  std::string out = "'";
  for (const char c : path) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string recover_command(const std::string& path) {
  return "sqlite3 " + shell_quoted(path) + " .recover | sqlite3 recovered.sqlite";
}

std::uint32_t big_endian(const unsigned char* p, int bytes) {
  std::uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

// The database header (sqlite.org/fileformat.html, "The Database Header").
constexpr std::size_t header_bytes = 100;
constexpr std::string_view sqlite_magic("SQLite format 3\0", 16);

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

DataError foreign_file_error(const std::string& path, std::int64_t application_id) {
  return DataError{DataError::Kind::not_curvlab,
                   path + ": not a curvlab data file: a readable SQLite database written by another "
                          "program (application_id " + std::to_string(application_id) + "; curvlab writes " +
                       std::to_string(curvlab_application_id) +
                       ", \"CVLB\"). It was not modified and there is nothing to recover; give the "
                       "file curvlab run wrote (by default results/<protocol name>.sqlite)"};
}

DataError corrupt_file_error(const std::string& path, const std::string& what) {
  return DataError{DataError::Kind::corrupt,
                   path + ": damaged curvlab data file: " + what +
                       ", so only part of it can be read. Recover the committed data into a new file "
                       "with the SQLite shell: " + recover_command(path) +
                       "; then use recovered.sqlite (" + path +
                       " is left as it is; docs/data.md shows how without .recover)"};
}

Expected<Done> check_data_file(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return Done{};  // missing or a folder: Database::open says so
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec || size == 0) return Done{};  // empty: becomes a new curvlab file
  std::ifstream in(path, std::ios::binary);
  if (!in) return Done{};  // unreadable: SQLite's own error names the cause
  std::array<unsigned char, header_bytes> h{};
  in.read(reinterpret_cast<char*>(h.data()), h.size());
  const auto got = static_cast<std::size_t>(in.gcount());
  if (std::memcmp(h.data(), sqlite_magic.data(), std::min(got, sqlite_magic.size())) != 0) {
    return DataError{DataError::Kind::not_curvlab,
                     path + ": not an SQLite database (it does not begin with \"SQLite format 3\"), so it "
                            "cannot be read at all and is not a curvlab data file. If it should hold curvlab "
                            "data it was overwritten: use a backup, or save whatever SQLite pages remain with "
                            "the SQLite shell: " + recover_command(path)};
  }
  if (got < header_bytes) {
    return corrupt_file_error(path, "truncated to " + std::to_string(size) +
                                        " bytes, shorter than the 100-byte SQLite header");
  }
  std::uint32_t page_size = big_endian(&h[16], 2);
  if (page_size == 1) page_size = 65536;
  if (page_size < 512 || page_size > 65536 || (page_size & (page_size - 1)) != 0)
    return corrupt_file_error(path, "its header is damaged (page size " + std::to_string(page_size) + ")");
  // While a write-ahead log is pending, SQLite finishes an interrupted
  // checkpoint on open, and the file may legitimately be shorter until then.
  const fs::path wal(path + "-wal");
  if (fs::exists(wal, ec) && fs::file_size(wal, ec) > 0 && !ec) return Done{};
  // The page count in the header is valid when its "version-valid-for" number
  // equals the change counter (always, for files written since SQLite 3.7.0).
  const std::uint32_t pages = big_endian(&h[28], 4);
  if (pages != 0 && big_endian(&h[24], 4) == big_endian(&h[92], 4)) {
    const std::uintmax_t expected = std::uintmax_t{pages} * page_size;
    if (size < expected)
      return corrupt_file_error(path, "truncated to " + std::to_string(size) + " bytes where its header records " +
                                          std::to_string(expected) + " (" + std::to_string(pages) +
                                          " pages of " + std::to_string(page_size) + " bytes)");
  }
  // Another program's database, with the exceptions Database::open makes: a
  // schema-version-1 file (before application_id was set) and an empty
  // database of one page, which becomes a curvlab file.
  const std::uint32_t app_id = big_endian(&h[68], 4);
  const std::uint32_t user_version = big_endian(&h[60], 4);
  if (app_id != curvlab_application_id && !(app_id == 0 && user_version == 1) && pages > 1)
    return foreign_file_error(path, app_id);
  return Done{};
}

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
    return DataError{DataError::Kind::not_found, path + ": no such file"};
  if (exists && std::filesystem::is_directory(path, ec))
    return DataError{DataError::Kind::io, path + ": is a folder, expected a database file"};
  if (auto checked = check_data_file(path); !checked) return checked.error();
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
      return foreign_file_error(path, app_id);
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

void remove_database_files(const std::string& path) {
  std::error_code ec;
  for (const char* suffix : {"", "-wal", "-shm", "-journal"}) fs::remove(path + suffix, ec);
}

}  // namespace curvlab::data
