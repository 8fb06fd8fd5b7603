// One live writer per session (DESIGN.md §7; docs/data.md, "Sharing the
// file"). The locks belong to the data file itself, not to the path that
// reached it: one-byte record locks (platform/lock_file.hpp: fcntl
// F_OFD_SETLK, LockFileEx) far beyond any byte SQLite uses (its own locks sit
// at 1 GiB; ours at 2^62), taken through an open of DB, so that symbolic
// links, hard links, `..` and bind mounts all meet the same locks:
// - the file byte: shared by every process writing a session into DB,
//   exclusive for a command that replaces the whole file (merge --out);
// - the set-up byte: exclusive while a writer opens the file and adds its
//   session, so that two sessions started at once on a new file create its
//   schema one after the other;
// - one byte per session N: exclusive for the process writing session N.
// The path is checked again once the file byte is held: a file that another
// process replaced meanwhile is left for the path's new file.
//
// Beside the file (its resolved path, so that links and `..` agree) sit two
// companions that name and help the holders, never trusted for the lock:
// - DB.lock, a 128-byte slot per session (and slot 0 for a replacer) naming
//   the holder's process id, host and start time, so that a refused command
//   can say who holds the session; a slot is cleared when its lock is
//   released, and the last holder removes the file (not on Windows);
// - DB.reserve-N, 1 MiB of disk set aside for session N: when the disk fills
//   during the session, freeing it lets the session's last entries and its
//   `interrupted` status reach the file.
// Companions are never opened through a link and must be regular files with
// one name, owned by this user; anything else there is refused, never
// written or removed.
//
// The kernel releases the locks when the holder dies (kill -9, power loss
// releases them with the machine), so a dead writer's session is resumable
// at once. Locks on a network share hold only as far as the share passes
// fcntl locks on to its server (NFS with lockd does; many SMB setups do not).
//
// Ownership: a WriterLock owns its open of DB and its locks; move-only. Not
// thread-safe; one thread at a time.
#pragma once

#include "curvlab/harness/data/error.hpp"
#include "curvlab/harness/platform/lock_file.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <utility>

namespace curvlab::harness::data {

// Who holds a session or the file: from the holder's slot.
struct LockHolder {
  std::int64_t pid = 0;
  std::string host;
  std::string since_utc;
};

class WriterLock {
 public:
  // The shared hold of DB by a session writer, in set-up until it claims a
  // session (DB is made, empty, when missing). Refused (in_use) while a command
  // replaces the file; read_only or io when DB or its companions cannot be
  // made, bad_input when a companion is a link or another's file.
  static Expected<WriterLock> for_sessions(const std::string& db_path);
  // The exclusive hold of DB for replacing it: refused (in_use) while any
  // session is being written, naming the first such session and its holder.
  // A missing DB is made empty (created_file()) so that no session can start
  // there meanwhile, and removed again on release when nothing replaced it.
  static Expected<WriterLock> for_replacing(const std::string& db_path);
  // A shared hold plus session `session_id`: refused (in_use) while a live
  // process writes that session.
  static Expected<WriterLock> for_session(const std::string& db_path, std::int64_t session_id);

  // Adds session `session_id` to a shared hold (a new session, inside the
  // transaction that creates it, so no other process can see it unlocked),
  // and ends the set-up: the next writer may start.
  Expected<Done> claim(std::int64_t session_id);

  // Whether for_replacing made the file.
  [[nodiscard]] bool created_file() const { return created_; }

  // Frees the claimed session's reserve (the disk is full); true when there
  // was one to free.
  bool free_reserve() noexcept;

  // The live writer of a session, if any, without taking a lock.
  static std::optional<LockHolder> session_writer(const std::string& db_path, std::int64_t session_id);
  // The first session a live process writes into DB, or the process that
  // replaces it (session 0), if any, without taking a lock.
  static std::optional<std::pair<std::int64_t, LockHolder>> file_writer(const std::string& db_path);

  WriterLock(WriterLock&& other) noexcept;
  WriterLock& operator=(WriterLock&& other) noexcept;
  WriterLock(const WriterLock&) = delete;
  WriterLock& operator=(const WriterLock&) = delete;
  ~WriterLock();

 private:
  WriterLock(platform::LockFile data, platform::LockFile holders, std::string db_path, std::string beside)
      : data_(std::move(data)), holders_(std::move(holders)), db_path_(std::move(db_path)), beside_(std::move(beside)) {}
  void release() noexcept;
  bool unused_now() const;
  void end_setup() noexcept;

  platform::LockFile data_;     // the open of DB that holds the locks
  platform::LockFile holders_;  // DB.lock
  std::string db_path_;         // as given, for messages
  std::string beside_;          // DB's resolved path, the companions' stem
  std::optional<std::int64_t> session_;  // the claimed session
  bool replacing_ = false;
  bool setting_up_ = false;
  bool reserve_made_ = false;
  bool created_ = false;
};

// "process P on HOST (since T)", or "another process" when the slot is empty.
std::string describe(const LockHolder& holder);

// The message for a session a live process writes.
std::string session_in_use_message(const std::string& db_path, std::int64_t session_id, const LockHolder& holder);

}  // namespace curvlab::harness::data
