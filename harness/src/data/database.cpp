#include "curvlab/harness/data/database.hpp"

#include "curvlab/harness/platform/files.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <optional>
#include <set>
#include <vector>
#include <system_error>

namespace curvlab::harness::data {
namespace {

namespace fs = std::filesystem;

std::string utc_now_sql() { return "strftime('%Y-%m-%dT%H:%M:%fZ', 'now')"; }

// Checks made before a session starts, so that a read-only folder or a full
// disk is reported up front rather than as a failure in the middle of trials.
std::optional<DataError> check_writable_location(const std::string& path, const SpaceNeeded& needed) {
  const fs::path file(path);
  fs::path dir = file.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    return DataError{DataError::Kind::io,
                     path + ": folder " + dir.string() + " does not exist (create it first)"};
  }
  if (!platform::writable(dir.string())) {
    return DataError{DataError::Kind::read_only,
                     path + ": folder " + dir.string() +
                         " is not writable (the WAL journal needs a writable folder)"};
  }
  if (fs::exists(file, ec) && !platform::writable(file.string())) {
    return DataError{DataError::Kind::read_only, path + ": file is read-only"};
  }
  if (const auto free_bytes = platform::free_bytes(dir.string())) {
    if (*free_bytes < needed.bytes) {
      return DataError{DataError::Kind::disk_full,
                       path + ": only " + std::to_string(*free_bytes >> 20) + " MiB free; " + needed.what +
                           " needs at least " + std::to_string((needed.bytes + (1u << 20) - 1) >> 20) + " MiB"};
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
constexpr std::size_t wal_header_bytes = 32;
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

namespace {

// The first bytes of a file, read through SQLite's default VFS. On POSIX,
// closing any descriptor of a file drops every fcntl lock the process holds
// on it, so an ifstream opened and closed beside a live connection silently
// releases that connection's locks and lets another process checkpoint and
// delete the write-ahead log under it (sqlite.org/howtocorrupt.html, 2.2).
// SQLite's unix VFS keeps such a descriptor open until the process's own
// locks on the file are released, so this read is safe at any time.
struct FilePrefix {
  std::string bytes;        // up to the requested count
  std::uintmax_t size = 0;  // the whole file's size
};

std::optional<FilePrefix> read_prefix(const std::string& path, std::size_t count, int open_kind) {
  sqlite3_vfs* vfs = sqlite3_vfs_find(nullptr);
  if (vfs == nullptr) return std::nullopt;
  std::vector<std::byte> storage(static_cast<std::size_t>(vfs->szOsFile));
  auto* file = reinterpret_cast<sqlite3_file*>(storage.data());
  int out_flags = 0;
  if (vfs->xOpen(vfs, path.c_str(), file, SQLITE_OPEN_READONLY | open_kind, &out_flags) != SQLITE_OK) {
    if (file->pMethods != nullptr) file->pMethods->xClose(file);
    return std::nullopt;
  }
  FilePrefix out;
  sqlite3_int64 size = 0;
  if (file->pMethods->xFileSize(file, &size) == SQLITE_OK && size > 0) {
    out.size = static_cast<std::uintmax_t>(size);
    out.bytes.resize(std::min<std::size_t>(count, static_cast<std::size_t>(size)));
    if (file->pMethods->xRead(file, out.bytes.data(), static_cast<int>(out.bytes.size()), 0) != SQLITE_OK)
      out.bytes.clear();
  }
  file->pMethods->xClose(file);
  return out;
}

std::uint32_t word(const std::string& b, std::size_t at, bool big) {
  const auto* p = reinterpret_cast<const unsigned char*>(b.data() + at);
  return big ? big_endian(p, 4)
             : std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
                   std::uint32_t{p[3]} << 24;
}

// The write-ahead log's header (sqlite.org/fileformat.html, "WAL File
// Format"): magic, version 3007000, page size and a checksum of its first 24
// bytes. SQLite treats a log with a bad header as empty, so the transactions
// it holds would vanish on the next open and be deleted by the next
// checkpoint; a log with frames behind a bad header is therefore refused.
Expected<Done> check_wal(const std::string& path) {
  const std::string wal = path + "-wal";
  std::error_code ec;
  if (!fs::is_regular_file(wal, ec)) return Done{};
  const auto prefix = read_prefix(wal, wal_header_bytes, SQLITE_OPEN_WAL);
  if (!prefix || prefix->size == 0) return Done{};
  const std::string& h = prefix->bytes;
  std::string problem;
  if (h.size() < wal_header_bytes) {
    problem = "is cut off inside its 32-byte header";
  } else {
    const std::uint32_t magic = word(h, 0, true);
    const bool big = (magic & 1u) != 0;
    if ((magic & ~1u) != 0x377f0682u) problem = "does not begin with the WAL magic number";
    else if (word(h, 4, true) != 3007000u) problem = "records an unknown format version";
    else {
      std::uint32_t s0 = 0, s1 = 0;
      for (std::size_t i = 0; i < 24; i += 8) {
        s0 += word(h, i, big) + s1;
        s1 += word(h, i + 4, big) + s0;
      }
      if (s0 != word(h, 24, true) || s1 != word(h, 28, true)) problem = "has a header whose checksum does not match";
    }
  }
  if (problem.empty() || prefix->size <= wal_header_bytes) return Done{};  // no frames: nothing to lose
  return DataError{DataError::Kind::corrupt,
                   path + ": damaged curvlab data file: its write-ahead log " + wal + " (" +
                       std::to_string(prefix->size) + " bytes of transactions not yet copied into the file) " +
                       problem + ", so SQLite would discard those transactions on the next open. Nothing was "
                       "changed. Before any program opens the file, copy " + shell_quoted(path) + " and " +
                       shell_quoted(wal) + " aside together; docs/data.md (\"A damaged write-ahead log\") shows "
                       "how to repair the header and recover the committed rows"};
}

}  // namespace

Expected<Done> check_data_file(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return Done{};  // missing or a folder: Database::open says so
  const auto prefix = read_prefix(path, header_bytes, SQLITE_OPEN_MAIN_DB);
  if (!prefix) return Done{};  // unreadable: SQLite's own error names the cause
  const std::uintmax_t size = prefix->size;
  if (size == 0) return check_wal(path);  // empty: becomes a new curvlab file, unless a log holds its data
  std::array<unsigned char, header_bytes> h{};
  std::memcpy(h.data(), prefix->bytes.data(), prefix->bytes.size());
  const std::size_t got = prefix->bytes.size();
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
  if (auto wal = check_wal(path); !wal) return wal.error();
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

namespace {

// "table.column" for every column of every table the schema defines.
std::set<std::string> columns_of(Connection& c) {
  std::set<std::string> out;
  Statement s(c, "SELECT m.name || '.' || p.name FROM sqlite_master AS m, pragma_table_info(m.name) AS p "
                 "WHERE m.type = 'table' AND m.name NOT LIKE 'sqlite_%'");
  while (s.step()) out.insert(s.column_text(0));
  return out;
}

const std::set<std::string>& expected_columns() {
  static const std::set<std::string> columns = [] {
    Connection c = Connection::open(":memory:", OpenFlags::read_write_create);
    c.exec(schema_sql());
    return columns_of(c);
  }();
  return columns;
}

DataError damaged_schema(const std::string& path, const std::string& what) {
  return corrupt_file_error(path, "its schema is damaged (" + what + "); nothing was changed");
}

// A current-version file must hold every table and column the schema
// defines; anything missing is damage (a dropped table, a tool that rewrote
// it), reported before a command reads or writes a row.
Expected<Done> check_schema(Connection& c, const std::string& path) {
  const std::set<std::string> have = columns_of(c);
  std::vector<std::string> missing;
  for (const auto& column : expected_columns())
    if (!have.contains(column)) missing.push_back(column);
  if (missing.empty()) return Done{};
  std::string list;
  for (std::size_t i = 0; i < missing.size() && i < 4; ++i) list += (i ? ", " : "") + missing[i];
  if (missing.size() > 4) list += " and " + std::to_string(missing.size() - 4) + " more";
  return damaged_schema(path, "schema version " + std::to_string(current_schema_version) + " lacks " + list);
}

// Brings an older file to the current schema; a migration that does not fit
// the file (its recorded version is wrong) is damage, rolled back.
Expected<Done> migrate_checked(Connection& c, std::int64_t version, const std::string& path) {
  try {
    migrate(c, version);
  } catch (const SqliteFailure& failure) {
    c.exec("PRAGMA foreign_keys = ON");
    return damaged_schema(path, "it records schema version " + std::to_string(version) +
                                    " but its tables do not match that version: " + failure.what());
  }
  return check_schema(c, path);
}

// Writers check the pages before adding a row: a session started in a file
// damaged inside would otherwise be stored half-written.
Expected<Done> check_pages(Connection& c, const std::string& path) {
  try {
    const std::string result = [&] {
      Statement s(c, "PRAGMA quick_check(1)");
      return s.step() ? s.column_text(0) : std::string("no result");
    }();
    if (result == "ok") return Done{};
    return corrupt_file_error(path, "SQLite's quick_check reports \"" + result + "\"");
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, path);
  }
}

}  // namespace

Expected<Database> Database::checked(Connection c, const std::string& path, OpenMode mode) {
  // Reading the header first turns "file is not a database" into a clear error.
  const std::int64_t version = c.query_int("PRAGMA user_version");
  const std::int64_t app_id = c.query_int("PRAGMA application_id");
  const bool empty = is_empty_database(c);
  if (!empty && app_id != curvlab_application_id && !(app_id == 0 && version == 1))
    return foreign_file_error(path, app_id);
  if (version > current_schema_version) {
    return DataError{DataError::Kind::newer_schema,
                     path + ": written with schema version " + std::to_string(version) +
                         " by a newer curvlab; this build understands up to version " +
                         std::to_string(current_schema_version) + ". Use a newer curvlab; the file was not modified."};
  }
  if (!empty && version < 1)
    return damaged_schema(path, "it records schema version " + std::to_string(version) +
                                    ", which no curvlab writes");
  if (mode == OpenMode::read_only) {
    if (empty)
      return damaged_schema(path, "it holds no tables, so it was never a finished curvlab file");
    configure_connection(c, false);
    if (version == current_schema_version) {
      if (auto ok = check_schema(c, path); !ok) return ok.error();
      return Database(std::move(c));
    }
    // Older files are read through a migrated copy in memory: the file
    // itself stays as it is, even on read-only media.
    Connection copy = Connection::copy_into_memory(c);
    if (auto ok = migrate_checked(copy, version, path); !ok) return ok.error();
    return Database(std::move(copy));
  }
  // Once, when a session starts or resumes: the session's writer thread and
  // upgrade open the file again (open_existing) and need not read it all.
  if (!empty && mode == OpenMode::create_or_open)
    if (auto ok = check_pages(c, path); !ok) return ok.error();
  configure_connection(c, true);  // first: switching to WAL waits out other openers
  c.exec("PRAGMA journal_mode = WAL");
  if (empty) {
    create_schema(c);
    return Database(std::move(c));
  }
  if (version < current_schema_version) {
    if (auto ok = migrate_checked(c, version, path); !ok) return ok.error();
  } else if (auto ok = check_schema(c, path); !ok) {
    return ok.error();
  }
  return Database(std::move(c));
}

Expected<Database> Database::open(const std::string& path, OpenMode mode, const SpaceNeeded& needed) {
  if (path.empty()) return DataError{DataError::Kind::io, "no database path given"};
  std::error_code ec;
  const bool exists = std::filesystem::exists(path, ec);
  if (mode != OpenMode::create_or_open && !exists)
    return DataError{DataError::Kind::not_found, path + ": no such file"};
  if (exists && std::filesystem::is_directory(path, ec))
    return DataError{DataError::Kind::io, path + ": is a folder, expected a database file"};
  if (auto checked = check_data_file(path); !checked) return checked.error();
  if (mode == OpenMode::create_or_open) {
    if (auto problem = check_writable_location(path, needed)) return *problem;
  }
  try {
    const OpenFlags flags = mode == OpenMode::create_or_open ? OpenFlags::read_write_create
                            : mode == OpenMode::open_existing ? OpenFlags::read_write
                                                              : OpenFlags::read_only;
    return checked(Connection::open(path, flags), path, mode);
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, path);
  }
}

std::int64_t stored_schema_version(const std::string& path) {
  try {
    Connection c = Connection::open(path, OpenFlags::read_only);
    return c.query_int("PRAGMA user_version");
  } catch (const SqliteFailure&) {
    return -1;
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

}  // namespace curvlab::harness::data
