// A file of one-byte record locks: the primitive under data/writer_lock.cpp
// (DESIGN.md §7, one live writer per session). A lock is held through one
// open of the file (a LockFile) and conflicts with locks held through any
// other open, in this process or another, never with its own; the system
// releases it when the holder closes the file or dies (kill -9 included).
// POSIX: open-file-description locks (fcntl F_OFD_SETLK). Windows: LockFileEx
// on the file's handle; the locked bytes are never read or written (Windows
// locks are mandatory), and an open file cannot be deleted while others
// have it open, so on Windows a companion stays in place (unlink_when_free
// is false).
//
// Two kinds of file are opened:
// - a companion, which curvlab makes beside a user's file (DB.lock): never
//   opened through a symbolic link (O_NOFOLLOW; Windows: a reparse point is
//   refused), and refused unless it is a regular file with one name, owned
//   by this user (POSIX), so that a link or a planted file can never make
//   curvlab write into someone else's data;
// - the data file itself (Mode::database…), reached through whatever path
//   the user gave, links included: a lock on it belongs to the file, so every
//   path to one file meets the same locks. On POSIX, closing any descriptor
//   of a file drops the classic fcntl locks this process holds on it — the
//   ones SQLite's connections hold — so a data file's descriptor is never
//   closed: close() gives back its locks and keeps the descriptor for the
//   next open of the same file, until the process exits.
//
// Ownership: move-only, owns its descriptor. Not thread-safe (the keeping
// of data-file descriptors is).
#pragma once

#include <cstdint>
#include <map>
#include <string>

namespace curvlab::harness::platform {

// Why a companion was refused after it was opened.
enum class Unsafe { none, link, not_regular, several_names, other_owner };
std::string describe(Unsafe why);

class LockFile {
 public:
  // Whether the last holder removes a companion (POSIX) or leaves it
  // (Windows, see above).
  static const bool unlink_when_free;

  enum class Mode {
    create_read_write,   // a companion, made if missing
    read_only,           // a companion, only if it exists
    database,            // the data file, made if missing (links followed)
    database_read_only,  // the data file, only if it exists (links followed)
  };
  // Opens `path`; on failure the result is not open() and either error() is
  // an errno value (EACCES, EROFS or EPERM: read-only; ENOENT: missing) or
  // unsafe() says why a companion was refused.
  static LockFile open(const std::string& path, Mode mode);

  LockFile() = default;
  LockFile(LockFile&& other) noexcept;
  LockFile& operator=(LockFile&& other) noexcept;
  LockFile(const LockFile&) = delete;
  LockFile& operator=(const LockFile&) = delete;
  ~LockFile();

  [[nodiscard]] bool is_open() const { return fd_ >= 0; }
  [[nodiscard]] int error() const { return error_; }
  [[nodiscard]] Unsafe unsafe() const { return unsafe_; }

  // Non-blocking; false when another open holds a conflicting lock.
  bool try_lock(std::int64_t byte, bool exclusive);
  void unlock(std::int64_t byte);
  // Whether another open holds a lock that conflicts with one of this kind.
  // (On Windows, where this open holds the byte shared, another shared
  // holder is not seen.)
  bool held_elsewhere(std::int64_t byte, bool exclusive);

  // Whether `path` (links followed) still names the file this is open on: a
  // lock on a file that another process replaced or unlinked meanwhile is
  // worthless.
  bool still_named(const std::string& path) const;

  std::int64_t size() const;
  void write_at(const std::string& bytes, std::int64_t at);
  std::string read_at(std::size_t n, std::int64_t at) const;

  void close() noexcept;

 private:
  int fd_ = -1;
  int error_ = 0;
  Unsafe unsafe_ = Unsafe::none;
  bool keep_open_ = false;  // a data file's descriptor (see above)
  // The bytes this open holds, and whether exclusively: Windows has no
  // F_GETLK and must tell its own locks from others' (windows.cpp).
  std::map<std::int64_t, bool> own_;
};

// Sets `bytes` of disk aside in a new companion file at `path` (a help, not
// a condition: without space, an empty file). False when `path` exists (a
// link, a folder or anyone's file is never touched) or cannot be made.
bool reserve_file(const std::string& path, std::int64_t bytes);

// Removes `path` only if it is a regular file (never through a link, never a
// folder); true when it was removed.
bool remove_regular_file(const std::string& path);

}  // namespace curvlab::harness::platform
