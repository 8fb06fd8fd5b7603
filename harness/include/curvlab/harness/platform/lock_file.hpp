// A file of one-byte record locks: the primitive under data/writer_lock.cpp
// (DESIGN.md §7, one live writer per session). A lock is held through one
// open of the file (a LockFile) and conflicts with locks held through any
// other open, in this process or another, never with its own; the system
// releases it when the holder closes the file or dies (kill -9 included).
// POSIX: open-file-description locks (fcntl F_OFD_SETLK). Windows: LockFileEx
// on the file's handle; the locked bytes are never read or written (Windows
// locks are mandatory), and an open lock file cannot be deleted while others
// have it open, so on Windows it stays in place (unlink_when_free is false).
//
// Ownership: move-only, owns its descriptor. Not thread-safe.
#pragma once

#include <cstdint>
#include <map>
#include <string>

namespace curvlab::platform {

class LockFile {
 public:
  // Whether the last holder removes the lock file (POSIX) or leaves it
  // (Windows, see above).
  static const bool unlink_when_free;

  enum class Mode { create_read_write, read_only };
  // Opens `path`; on failure the result is not open() and error() is an
  // errno value (EACCES, EROFS or EPERM: the folder or file is read-only).
  static LockFile open(const std::string& path, Mode mode);

  LockFile() = default;
  LockFile(LockFile&& other) noexcept;
  LockFile& operator=(LockFile&& other) noexcept;
  LockFile(const LockFile&) = delete;
  LockFile& operator=(const LockFile&) = delete;
  ~LockFile();

  [[nodiscard]] bool is_open() const { return fd_ >= 0; }
  [[nodiscard]] int error() const { return error_; }

  // Non-blocking; false when another open holds a conflicting lock.
  bool try_lock(std::int64_t byte, bool exclusive);
  void unlock(std::int64_t byte);
  // Whether another open holds a lock that conflicts with one of this kind.
  // (On Windows, where this open holds the byte shared, another shared
  // holder is not seen.)
  bool held_elsewhere(std::int64_t byte, bool exclusive);

  // Whether `path` still names the file this is open on (a lock on a file
  // another process unlinked meanwhile is worthless).
  bool still_named(const std::string& path) const;

  std::int64_t size() const;
  void write_at(const std::string& bytes, std::int64_t at);
  std::string read_at(std::size_t n, std::int64_t at) const;

  void close() noexcept;

 private:
  int fd_ = -1;
  int error_ = 0;
  // The bytes this open holds, and whether exclusively: Windows has no
  // F_GETLK and must tell its own locks from others' (windows.cpp).
  std::map<std::int64_t, bool> own_;
};

// Sets `bytes` of disk aside in a file at `path` (a help, not a condition:
// without space, an empty file or none).
void reserve_file(const std::string& path, std::int64_t bytes);

}  // namespace curvlab::platform
