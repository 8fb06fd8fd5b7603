// One live writer per session (DESIGN.md §7; docs/data.md, "Sharing the
// file"). A data file DB has a companion lock file DB.lock holding one-byte
// record locks (platform/lock_file.hpp: fcntl F_OFD_SETLK, LockFileEx):
// - byte 0: shared by every process writing a session into DB, exclusive
//   for a command that replaces the whole file (merge --out);
// - byte 1 + N: exclusive for the process writing session N;
// - a 128-byte slot per session (and slot 0 for a replacer) naming the
//   holder's process id, host and start time, so that a refused command can
//   say who holds the session. A slot is cleared when its lock is released.
// A claimed session also keeps DB.reserve-N, 1 MiB of disk set aside: when
// the disk fills during the session, freeing it lets the session's last
// entries and its `interrupted` status reach the file.
// The kernel releases the locks when the holder dies (kill -9, power loss
// releases them with the machine), so a dead writer's session is resumable
// at once. The lock file is separate from DB: SQLite's own locks on DB are
// never touched. Locks on a network share hold only as far as the share
// passes fcntl locks on (NFS with lockd does; many SMB setups do not).
//
// On Windows DB.lock stays when the last holder releases it (an open file
// cannot be unlinked there).
//
// Ownership: a WriterLock owns its lock file and locks; move-only. Not
// thread-safe; one thread at a time.
#pragma once

#include "curvlab/harness/data/error.hpp"
#include "curvlab/harness/platform/lock_file.hpp"

#include <cstdint>
#include <optional>
#include <string>

namespace curvlab::data {

// Who holds a session or the file: from the holder's slot.
struct LockHolder {
  std::int64_t pid = 0;
  std::string host;
  std::string since_utc;
};

class WriterLock {
 public:
  // The shared hold of DB by a session writer. Refused (in_use) while a
  // command replaces the file; read_only or io when DB.lock cannot be made.
  static Expected<WriterLock> for_sessions(const std::string& db_path);
  // The exclusive hold of DB for replacing it: refused (in_use) while any
  // session is being written, naming the first such session and its holder.
  static Expected<WriterLock> for_replacing(const std::string& db_path);
  // A shared hold plus session `session_id`: refused (in_use) while a live
  // process writes that session.
  static Expected<WriterLock> for_session(const std::string& db_path, std::int64_t session_id);

  // Adds session `session_id` to a shared hold (a new session, inside the
  // transaction that creates it, so no other process can see it unlocked).
  Expected<Done> claim(std::int64_t session_id);

  // Frees the claimed session's reserve (the disk is full); true when there
  // was one to free.
  bool free_reserve() noexcept;

  // The live writer of a session, if any, without taking a lock.
  static std::optional<LockHolder> session_writer(const std::string& db_path, std::int64_t session_id);

  WriterLock(WriterLock&& other) noexcept;
  WriterLock& operator=(WriterLock&& other) noexcept;
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;
  ~WriterLock();

 private:
  WriterLock(platform::LockFile file, std::string db_path) : file_(std::move(file)), db_path_(std::move(db_path)) {}
  void release() noexcept;

  platform::LockFile file_;
  std::string db_path_;
  std::optional<std::int64_t> session_;  // the claimed session
  bool replacing_ = false;
};

// The message for a session a live process writes.
std::string session_in_use_message(const std::string& db_path, std::int64_t session_id, const LockHolder& holder);

}  // namespace curvlab::data
