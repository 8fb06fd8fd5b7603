#include "curvlab/harness/data/writer_lock.hpp"

#include "curvlab/harness/data/staging.hpp"

#include "curvlab/harness/platform/lock_file.hpp"
#include "curvlab/harness/platform/process.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <utility>

namespace curvlab::data {
namespace {

using platform::LockFile;

constexpr std::int64_t file_byte = 0;
constexpr std::int64_t slots_at = 1 << 16;  // holder slots from here on (the lock bytes below never hold data)
constexpr std::int64_t slot_bytes = 128;

std::int64_t session_byte(std::int64_t session_id) { return 1 + session_id; }
std::int64_t slot_of(std::int64_t session_id) { return slots_at + session_id * slot_bytes; }

std::string lock_path(const std::string& db_path) { return db_path + ".lock"; }
std::string reserve_path(const std::string& db_path, std::int64_t session_id) {
  return db_path + ".reserve-" + std::to_string(session_id);
}
constexpr std::int64_t reserve_bytes = 1 << 20;

void write_slot(LockFile& file, std::int64_t session_id) {
  std::string text = std::to_string(platform::process_id()) + ' ' + platform::host_name() + ' ' +
                     platform::utc_now_iso8601();
  text.resize(slot_bytes, '\0');
  file.write_at(text, slot_of(session_id));
}

void clear_slot(LockFile& file, std::int64_t session_id) {
  file.write_at(std::string(slot_bytes, '\0'), slot_of(session_id));
}

LockHolder read_slot(const LockFile& file, std::int64_t session_id) {
  std::string text = file.read_at(slot_bytes, slot_of(session_id));
  text = text.substr(0, text.find('\0'));
  LockHolder h;
  std::istringstream in(text);
  in >> h.pid >> h.host >> h.since_utc;
  return h;
}

std::string describe(const LockHolder& h) {
  if (h.pid <= 0) return "another process";
  std::string out = "process " + std::to_string(h.pid);
  if (!h.host.empty()) out += " on " + h.host;
  if (!h.since_utc.empty()) out += " (since " + h.since_utc + ")";
  return out;
}

// Opens DB.lock and takes the file byte (shared or exclusive). A lock
// taken on a lock file that a releasing process unlinked meanwhile is
// worthless, so the file must still be the path's once the lock is held.
Expected<LockFile> open_locked(const std::string& db_path, bool exclusive, std::string& refused) {
  const std::string path = lock_path(db_path);
  for (int attempt = 0; attempt < 16; ++attempt) {
    LockFile file = LockFile::open(path, LockFile::Mode::create_read_write);
    if (!file.is_open()) {
      const int err = file.error();
      const auto kind = err == EACCES || err == EROFS || err == EPERM ? DataError::Kind::read_only
                                                                      : DataError::Kind::io;
      return DataError{kind, db_path + ": cannot create its lock file " + path + ": " + std::strerror(err) +
                                 (kind == DataError::Kind::read_only
                                      ? " (the folder is not writable; a session needs a writable folder)"
                                      : "")};
    }
    if (!file.try_lock(file_byte, exclusive)) {
      refused = path;
      return file;  // the caller names the holder, then closes
    }
    if (file.still_named(path)) return file;
  }
  return DataError{DataError::Kind::busy, db_path + ": its lock file " + path + " keeps being replaced"};
}

// The first session whose writer is alive, from the slots in use.
std::optional<std::pair<std::int64_t, LockHolder>> live_session(LockFile& file) {
  const std::int64_t size = file.size();
  if (size <= slots_at) return std::nullopt;
  const std::int64_t slots = (size - slots_at) / slot_bytes;
  for (std::int64_t id = 1; id < slots; ++id)
    if (file.held_elsewhere(session_byte(id), true)) return std::pair{id, read_slot(file, id)};
  return std::nullopt;
}

// Reserves left by writers that died (kill -9) for sessions no one holds.
void remove_stale_reserves(LockFile& file, const std::string& db_path) {
  const std::filesystem::path db(db_path);
  remove_numbered(db.parent_path().string(), db.filename().string() + ".reserve-", [&file](std::int64_t session_id) {
    return session_id > 0 && !file.held_elsewhere(session_byte(session_id), true);
  });
}

}  // namespace

std::string session_in_use_message(const std::string& db_path, std::int64_t session_id, const LockHolder& holder) {
  return db_path + ": session " + std::to_string(session_id) + " is being written by " + describe(holder) +
         "; nothing was changed. Wait until it ends, or end it there (Q, Ctrl-C or the operator's end); a session "
         "whose process has died can be resumed at once";
}

Expected<WriterLock> WriterLock::for_sessions(const std::string& db_path) {
  std::string refused;
  auto file = open_locked(db_path, false, refused);
  if (!file) return file.error();
  if (!refused.empty()) {
    const LockHolder h = read_slot(*file, 0);
    return DataError{DataError::Kind::in_use, db_path + ": the whole file is being replaced by " + describe(h) +
                                                  " (curvlab merge --out); nothing was changed. Try again when it "
                                                  "has finished"};
  }
  remove_stale_reserves(*file, db_path);
  return WriterLock(std::move(file).value(), db_path);
}

Expected<WriterLock> WriterLock::for_replacing(const std::string& db_path) {
  std::string refused;
  auto file = open_locked(db_path, true, refused);
  if (!file) return file.error();
  if (!refused.empty()) {
    const auto live = live_session(*file);
    const LockHolder other = live ? live->second : read_slot(*file, 0);
    if (live) return DataError{DataError::Kind::in_use, session_in_use_message(db_path, live->first, live->second)};
    return DataError{DataError::Kind::in_use, db_path + ": the file is in use by " + describe(other) +
                                                  "; nothing was changed. Try again when it has finished"};
  }
  write_slot(*file, 0);
  WriterLock lock(std::move(file).value(), db_path);
  lock.replacing_ = true;
  return lock;
}

Expected<WriterLock> WriterLock::for_session(const std::string& db_path, std::int64_t session_id) {
  auto lock = for_sessions(db_path);
  if (!lock) return lock.error();
  if (auto ok = lock->claim(session_id); !ok) return ok.error();
  return lock;
}

Expected<Done> WriterLock::claim(std::int64_t session_id) {
  if (!file_.try_lock(session_byte(session_id), true))
    return DataError{DataError::Kind::in_use, session_in_use_message(db_path_, session_id, read_slot(file_, session_id))};
  write_slot(file_, session_id);
  session_ = session_id;
  // Sets disk space aside for the end of a session; without space to spare
  // the session still runs (the reserve is a help, not a condition).
  platform::reserve_file(reserve_path(db_path_, session_id), reserve_bytes);
  return Done{};
}

bool WriterLock::free_reserve() noexcept {
  if (!file_.is_open() || !session_) return false;
  std::error_code ec;
  return std::filesystem::remove(reserve_path(db_path_, *session_), ec);
}

std::optional<LockHolder> WriterLock::session_writer(const std::string& db_path, std::int64_t session_id) {
  // Read-only: probing never creates a file; closing it releases no lock
  // but its own, since locks belong to the open that took them.
  LockFile file = LockFile::open(lock_path(db_path), LockFile::Mode::read_only);
  if (!file.is_open()) return std::nullopt;
  std::optional<LockHolder> out;
  if (file.held_elsewhere(session_byte(session_id), true)) out = read_slot(file, session_id);
  return out;
}

WriterLock::WriterLock(WriterLock&& other) noexcept
    : file_(std::move(other.file_)),
      db_path_(std::move(other.db_path_)),
      session_(std::exchange(other.session_, std::nullopt)),
      replacing_(std::exchange(other.replacing_, false)) {}

WriterLock& WriterLock::operator=(WriterLock&& other) noexcept {
  if (this != &other) {
    release();
    file_ = std::move(other.file_);
    db_path_ = std::move(other.db_path_);
    session_ = std::exchange(other.session_, std::nullopt);
    replacing_ = std::exchange(other.replacing_, false);
  }
  return *this;
}

WriterLock::~WriterLock() { release(); }

void WriterLock::release() noexcept {
  if (!file_.is_open()) return;
  std::error_code ec;
  if (session_) {
    std::filesystem::remove(reserve_path(db_path_, *session_), ec);
    clear_slot(file_, *session_);
    file_.unlock(session_byte(*session_));
  }
  if (replacing_) clear_slot(file_, 0);
  // The last holder removes the lock file; later lockers find the path's
  // new file (open_locked checks it after locking). Not on Windows, where
  // an open file cannot be unlinked (platform/lock_file.hpp).
  if (LockFile::unlink_when_free && file_.try_lock(file_byte, true))
    std::filesystem::remove(lock_path(db_path_), ec);
  file_.close();
}

}  // namespace curvlab::data
