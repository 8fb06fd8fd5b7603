#include "curvlab/harness/data/writer_lock.hpp"

#include "curvlab/harness/data/staging.hpp"

#include "curvlab/harness/platform/lock_file.hpp"
#include "curvlab/harness/platform/process.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <thread>
#include <utility>

namespace curvlab::harness::data {
namespace {

namespace fs = std::filesystem;
using platform::LockFile;

// Bytes of DB itself, far beyond any page (and beyond SQLite's own locks at
// 1 GiB), so that no reader or writer of the data ever meets them.
constexpr std::int64_t lock_base = std::int64_t{1} << 62;
constexpr std::int64_t file_byte = lock_base;
constexpr std::int64_t setup_byte = lock_base + 1;
std::int64_t session_byte(std::int64_t session_id) { return lock_base + 2 + session_id; }

// How long a writer waits for another to finish setting up (creating the
// schema of a new file takes milliseconds; a migration of a large file
// seconds).
constexpr auto setup_patience = std::chrono::seconds(60);

constexpr std::int64_t slots_at = 1 << 16;  // holder slots from here on (older files kept lock bytes below)
constexpr std::int64_t slot_bytes = 128;
std::int64_t slot_of(std::int64_t session_id) { return slots_at + session_id * slot_bytes; }

// The companions' stem: DB's resolved path where it can be resolved, so
// that every symbolic link and `..` path to DB names the same companions.
std::string beside_of(const std::string& db_path) {
  std::error_code ec;
  const fs::path resolved = fs::weakly_canonical(fs::path(db_path), ec);
  return ec || resolved.empty() ? db_path : resolved.string();
}
std::string holders_path(const std::string& beside) { return beside + ".lock"; }
std::string reserve_path(const std::string& beside, std::int64_t session_id) {
  return beside + ".reserve-" + std::to_string(session_id);
}
constexpr std::int64_t reserve_bytes = 1 << 20;

void write_slot(LockFile& holders, std::int64_t session_id) {
  std::string text = std::to_string(platform::process_id()) + ' ' + platform::host_name() + ' ' +
                     platform::utc_now_iso8601();
  text.resize(slot_bytes, '\0');
  holders.write_at(text, slot_of(session_id));
}

void clear_slot(LockFile& holders, std::int64_t session_id) {
  holders.write_at(std::string(slot_bytes, '\0'), slot_of(session_id));
}

LockHolder read_slot(const LockFile& holders, std::int64_t session_id) {
  LockHolder h;
  if (!holders.is_open()) return h;
  std::string text = holders.read_at(slot_bytes, slot_of(session_id));
  text = text.substr(0, text.find('\0'));
  std::istringstream in(text);
  in >> h.pid >> h.host >> h.since_utc;
  return h;
}

LockHolder read_slot(const std::string& beside, std::int64_t session_id) {
  return read_slot(LockFile::open(holders_path(beside), LockFile::Mode::read_only), session_id);
}

DataError open_failure(const std::string& db_path, const std::string& what, int err) {
  const auto kind =
      err == EACCES || err == EROFS || err == EPERM ? DataError::Kind::read_only : DataError::Kind::io;
  return DataError{kind, db_path + ": cannot open " + what + ": " + std::strerror(err) +
                             (kind == DataError::Kind::read_only
                                  ? " (the file or its folder is not writable; a session needs both writable)"
                                  : "")};
}

DataError unsafe_companion(const std::string& db_path, const std::string& path, platform::Unsafe why) {
  return DataError{DataError::Kind::bad_input,
                   db_path + ": " + path + " " + platform::describe(why) +
                       "; curvlab keeps its lock there and never writes into a file it did not make. Nothing was "
                       "changed. Remove it (rm " + path + ") if no curvlab is running on this file, and try again"};
}

// A writer ending holds the file byte exclusively for a moment (release(),
// to see whether it is the last); a merge holds it for seconds.
bool retry_briefly(LockFile& data, bool exclusive) {
  for (int i = 0; i < 10; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (data.try_lock(file_byte, exclusive)) return true;
  }
  return false;
}

// Opens DB and takes the file byte (shared or exclusive); `refused` is set
// when another holds it. A lock taken on a file that another process
// replaced meanwhile is worthless, so DB must still be the path's once the
// lock is held.
Expected<LockFile> open_locked(const std::string& db_path, bool exclusive, bool& refused) {
  for (int attempt = 0; attempt < 16; ++attempt) {
    LockFile data = LockFile::open(db_path, LockFile::Mode::database);
    if (!data.is_open()) {
      if (data.unsafe() != platform::Unsafe::none)
        return DataError{DataError::Kind::io, db_path + ": " + platform::describe(data.unsafe()) +
                                                  "; a data file must be a regular file"};
      return open_failure(db_path, "it", data.error());
    }
    if (!data.try_lock(file_byte, exclusive) && !retry_briefly(data, exclusive)) {
      refused = true;
      return data;  // the caller names the holder, then closes
    }
    if (data.still_named(db_path)) return data;
  }
  return DataError{DataError::Kind::busy, db_path + ": the file keeps being replaced by another process"};
}

Expected<LockFile> open_holders(const std::string& db_path, const std::string& beside) {
  const std::string path = holders_path(beside);
  LockFile holders = LockFile::open(path, LockFile::Mode::create_read_write);
  if (holders.unsafe() != platform::Unsafe::none) return unsafe_companion(db_path, path, holders.unsafe());
  if (!holders.is_open()) return open_failure(db_path, "its lock file " + path, holders.error());
  return holders;
}

// Waits until no other writer is setting up (making the schema of a new
// file, adding its session).
Expected<Done> wait_for_setup(LockFile& data, const std::string& db_path) {
  const auto give_up = std::chrono::steady_clock::now() + setup_patience;
  while (!data.try_lock(setup_byte, true)) {
    if (std::chrono::steady_clock::now() > give_up)
      return DataError{DataError::Kind::busy, db_path + ": another process has been starting a session here for " +
                                                  std::to_string(setup_patience.count()) + " s; nothing was changed"};
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return Done{};
}

// The first session whose writer is alive: the sessions with slots, and at
// least the first 4096 (DB.lock beside another name of the file, a hard
// link, has no slots for them).
std::optional<std::pair<std::int64_t, LockHolder>> live_session(LockFile& data, const LockFile& holders) {
  const std::int64_t size = holders.is_open() ? holders.size() : 0;
  const std::int64_t slots = std::max<std::int64_t>(size > slots_at ? (size - slots_at) / slot_bytes : 0, 4096);
  for (std::int64_t id = 1; id < slots; ++id)
    if (data.held_elsewhere(session_byte(id), true)) return std::pair{id, read_slot(holders, id)};
  return std::nullopt;
}

// Reserves left by writers that died (kill -9) for sessions no one holds;
// only regular files named exactly DB.reserve-N.
void remove_stale_reserves(LockFile& data, const std::string& beside) {
  const fs::path db(beside);
  remove_numbered(db.parent_path().string(), db.filename().string() + ".reserve-", StagingKind::file,
                  [&data](std::int64_t session_id) {
                    return session_id > 0 && !data.held_elsewhere(session_byte(session_id), true);
                  });
}

// Refuses a companion already there that curvlab may not write (a link,
// another's file), before DB itself is made or opened.
Expected<Done> check_companions(const std::string& db_path) {
  const std::string path = holders_path(beside_of(db_path));
  const LockFile existing = LockFile::open(path, LockFile::Mode::read_only);
  if (existing.unsafe() != platform::Unsafe::none) return unsafe_companion(db_path, path, existing.unsafe());
  return Done{};
}

}  // namespace

std::string describe(const LockHolder& h) {
  if (h.pid <= 0) return "another process";
  std::string out = "process " + std::to_string(h.pid);
  if (!h.host.empty()) out += " on " + h.host;
  if (!h.since_utc.empty()) out += " (since " + h.since_utc + ")";
  return out;
}

std::string session_in_use_message(const std::string& db_path, std::int64_t session_id, const LockHolder& holder) {
  return db_path + ": session " + std::to_string(session_id) + " is being written by " + describe(holder) +
         "; nothing was changed. Wait until it ends, or end it there (Q, Ctrl-C or the operator's end); a session "
         "whose process has died can be resumed at once";
}

Expected<WriterLock> WriterLock::for_sessions(const std::string& db_path) {
  if (auto ok = check_companions(db_path); !ok) return ok.error();
  bool refused = false;
  auto data = open_locked(db_path, false, refused);
  if (!data) return data.error();
  const std::string beside = beside_of(db_path);
  if (refused) {
    return DataError{DataError::Kind::in_use, db_path + ": the whole file is being replaced by " +
                                                  describe(read_slot(beside, 0)) +
                                                  " (curvlab merge --out); nothing was changed. Try again when it "
                                                  "has finished"};
  }
  if (auto ok = wait_for_setup(*data, db_path); !ok) return ok.error();
  auto holders = open_holders(db_path, beside);
  if (!holders) return holders.error();
  remove_stale_reserves(*data, beside);
  WriterLock lock(std::move(data).value(), std::move(holders).value(), db_path, beside);
  lock.setting_up_ = true;
  return lock;
}

Expected<WriterLock> WriterLock::for_replacing(const std::string& db_path) {
  if (auto ok = check_companions(db_path); !ok) return ok.error();
  std::error_code ec;
  const bool existed = fs::exists(db_path, ec);
  bool refused = false;
  auto data = open_locked(db_path, true, refused);
  if (!data) return data.error();
  const std::string beside = beside_of(db_path);
  if (refused) {
    const LockFile holders = LockFile::open(holders_path(beside), LockFile::Mode::read_only);
    if (const auto live = live_session(*data, holders))
      return DataError{DataError::Kind::in_use, session_in_use_message(db_path, live->first, live->second)};
    return DataError{DataError::Kind::in_use, db_path + ": the file is in use by " + describe(read_slot(holders, 0)) +
                                                  "; nothing was changed. Try again when it has finished"};
  }
  auto holders = open_holders(db_path, beside);
  if (!holders) return holders.error();
  write_slot(*holders, 0);
  WriterLock lock(std::move(data).value(), std::move(holders).value(), db_path, beside);
  lock.replacing_ = true;
  lock.created_ = !existed;
  return lock;
}

Expected<WriterLock> WriterLock::for_session(const std::string& db_path, std::int64_t session_id) {
  auto lock = for_sessions(db_path);
  if (!lock) return lock.error();
  if (auto ok = lock->claim(session_id); !ok) return ok.error();
  return lock;
}

Expected<Done> WriterLock::claim(std::int64_t session_id) {
  if (!data_.try_lock(session_byte(session_id), true))
    return DataError{DataError::Kind::in_use,
                     session_in_use_message(db_path_, session_id, read_slot(holders_, session_id))};
  write_slot(holders_, session_id);
  session_ = session_id;
  end_setup();
  // Sets disk space aside for the end of a session; without space to spare
  // the session still runs (the reserve is a help, not a condition).
  reserve_made_ = platform::reserve_file(reserve_path(beside_, session_id), reserve_bytes);
  return Done{};
}

void WriterLock::end_setup() noexcept {
  if (!setting_up_) return;
  data_.unlock(setup_byte);
  setting_up_ = false;
}

bool WriterLock::free_reserve() noexcept {
  if (!data_.is_open() || !session_ || !reserve_made_) return false;
  reserve_made_ = false;
  return platform::remove_regular_file(reserve_path(beside_, *session_));
}

std::optional<LockHolder> WriterLock::session_writer(const std::string& db_path, std::int64_t session_id) {
  // Read-only: probing never creates a file, and the open of DB is kept
  // (never closed) so that SQLite's locks in this process stay whole.
  LockFile data = LockFile::open(db_path, LockFile::Mode::database_read_only);
  if (!data.is_open() || !data.held_elsewhere(session_byte(session_id), true)) return std::nullopt;
  return read_slot(beside_of(db_path), session_id);
}

std::optional<std::pair<std::int64_t, LockHolder>> WriterLock::file_writer(const std::string& db_path) {
  LockFile data = LockFile::open(db_path, LockFile::Mode::database_read_only);
  if (!data.is_open() || !data.held_elsewhere(file_byte, true)) return std::nullopt;
  const LockFile holders = LockFile::open(holders_path(beside_of(db_path)), LockFile::Mode::read_only);
  if (auto live = live_session(data, holders)) return live;
  return std::pair{std::int64_t{0}, read_slot(holders, 0)};
}

WriterLock::WriterLock(WriterLock&& other) noexcept
    : data_(std::move(other.data_)),
      holders_(std::move(other.holders_)),
      db_path_(std::move(other.db_path_)),
      beside_(std::move(other.beside_)),
      session_(std::exchange(other.session_, std::nullopt)),
      replacing_(std::exchange(other.replacing_, false)),
      setting_up_(std::exchange(other.setting_up_, false)),
      reserve_made_(std::exchange(other.reserve_made_, false)),
      created_(std::exchange(other.created_, false)) {}

WriterLock& WriterLock::operator=(WriterLock&& other) noexcept {
  if (this != &other) {
    release();
    data_ = std::move(other.data_);
    holders_ = std::move(other.holders_);
    db_path_ = std::move(other.db_path_);
    beside_ = std::move(other.beside_);
    session_ = std::exchange(other.session_, std::nullopt);
    replacing_ = std::exchange(other.replacing_, false);
    setting_up_ = std::exchange(other.setting_up_, false);
    reserve_made_ = std::exchange(other.reserve_made_, false);
    created_ = std::exchange(other.created_, false);
  }
  return *this;
}

WriterLock::~WriterLock() { release(); }

bool WriterLock::unused_now() const {
  // After a replacer's rename: the path's new file, if no writer has it yet.
  LockFile now = LockFile::open(db_path_, LockFile::Mode::database_read_only);
  return now.is_open() && !now.held_elsewhere(file_byte, true) && now.still_named(db_path_);
}

void WriterLock::release() noexcept {
  if (!data_.is_open()) return;
  end_setup();
  if (session_) {
    if (reserve_made_) platform::remove_regular_file(reserve_path(beside_, *session_));
    if (holders_.is_open()) clear_slot(holders_, *session_);
    data_.unlock(session_byte(*session_));
  }
  if (replacing_ && holders_.is_open()) clear_slot(holders_, 0);
  const bool ours = data_.still_named(db_path_);
  // An empty file made only to hold the path while nothing replaced it.
  if (created_ && ours && data_.size() == 0) platform::remove_regular_file(db_path_);
  // The last holder of the file at the path removes DB.lock; later holders
  // make it anew. Not on Windows (platform/lock_file.hpp).
  if (LockFile::unlink_when_free && holders_.is_open() && (ours ? data_.try_lock(file_byte, true) : unused_now()))
    platform::remove_regular_file(holders_path(beside_));
  holders_.close();
  data_.close();
}

}  // namespace curvlab::harness::data
