#include "curvlab/harness/data/writer_lock.hpp"

#include "curvlab/harness/data/staging.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <sstream>
#include <utility>

namespace curvlab::data {
namespace {

constexpr off_t file_byte = 0;
constexpr off_t slots_at = 1 << 16;  // holder slots from here on (the lock bytes below never hold data)
constexpr std::size_t slot_bytes = 128;

off_t session_byte(std::int64_t session_id) { return 1 + static_cast<off_t>(session_id); }
off_t slot_of(std::int64_t session_id) { return slots_at + static_cast<off_t>(session_id) * slot_bytes; }

std::string lock_path(const std::string& db_path) { return db_path + ".lock"; }
std::string reserve_path(const std::string& db_path, std::int64_t session_id) {
  return db_path + ".reserve-" + std::to_string(session_id);
}
constexpr off_t reserve_bytes = 1 << 20;

// Sets disk space aside for the end of a session; without space to spare
// the session still runs (the reserve is a help, not a condition).
void make_reserve(const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) return;
  if (::posix_fallocate(fd, 0, reserve_bytes) != 0) (void)::ftruncate(fd, 0);
  ::close(fd);
}

struct flock range(short type, off_t start) {
  struct flock f {};
  f.l_type = type;
  f.l_whence = SEEK_SET;
  f.l_start = start;
  f.l_len = 1;
  return f;
}

// Non-blocking; false when another open file description holds a
// conflicting lock.
bool try_lock(int fd, short type, off_t start) {
  struct flock f = range(type, start);
  return ::fcntl(fd, F_OFD_SETLK, &f) == 0;
}

void unlock(int fd, off_t start) {
  struct flock f = range(F_UNLCK, start);
  (void)::fcntl(fd, F_OFD_SETLK, &f);
}

bool held_by_other(int fd, short type, off_t start) {
  struct flock f = range(type, start);
  if (::fcntl(fd, F_OFD_GETLK, &f) != 0) return false;
  return f.l_type != F_UNLCK;
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::array<char, 32> text{};
  std::strftime(text.data(), text.size(), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text.data();
}

void write_slot(int fd, std::int64_t session_id) {
  std::array<char, 64> host{};
  if (::gethostname(host.data(), host.size() - 1) != 0) host[0] = '\0';
  std::string text = std::to_string(::getpid()) + ' ' + host.data() + ' ' + utc_now();
  text.resize(slot_bytes, '\0');
  (void)!::pwrite(fd, text.data(), text.size(), slot_of(session_id));
}

void clear_slot(int fd, std::int64_t session_id) {
  const std::string zeros(slot_bytes, '\0');
  (void)!::pwrite(fd, zeros.data(), zeros.size(), slot_of(session_id));
}

LockHolder read_slot(int fd, std::int64_t session_id) {
  std::string text(slot_bytes, '\0');
  const ssize_t got = ::pread(fd, text.data(), text.size(), slot_of(session_id));
  text.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
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

// Opens DB.lock and takes `type` on the file byte. A lock taken on a lock
// file that a releasing process unlinked meanwhile is worthless, so the
// descriptor must still name the path's file once the lock is held.
Expected<int> open_locked(const std::string& db_path, short type, std::string& refused) {
  const std::string path = lock_path(db_path);
  for (int attempt = 0; attempt < 16; ++attempt) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (fd < 0) {
      const int err = errno;
      const auto kind = err == EACCES || err == EROFS || err == EPERM ? DataError::Kind::read_only
                                                                      : DataError::Kind::io;
      return DataError{kind, db_path + ": cannot create its lock file " + path + ": " + std::strerror(err) +
                                 (kind == DataError::Kind::read_only
                                      ? " (the folder is not writable; a session needs a writable folder)"
                                      : "")};
    }
    if (!try_lock(fd, type, file_byte)) {
      refused = path;
      return fd;  // the caller names the holder, then closes
    }
    struct stat by_fd {}, by_path {};
    if (::fstat(fd, &by_fd) == 0 && ::stat(path.c_str(), &by_path) == 0 && by_fd.st_ino == by_path.st_ino &&
        by_fd.st_dev == by_path.st_dev)
      return fd;
    ::close(fd);
  }
  return DataError{DataError::Kind::busy, db_path + ": its lock file " + path + " keeps being replaced"};
}

// The first session whose writer is alive, from the slots in use.
std::optional<std::pair<std::int64_t, LockHolder>> live_session(int fd) {
  struct stat st {};
  if (::fstat(fd, &st) != 0 || st.st_size <= slots_at) return std::nullopt;
  const auto slots = static_cast<std::int64_t>((st.st_size - slots_at) / static_cast<off_t>(slot_bytes));
  for (std::int64_t id = 1; id < slots; ++id)
    if (held_by_other(fd, F_WRLCK, session_byte(id))) return std::pair{id, read_slot(fd, id)};
  return std::nullopt;
}

// Reserves left by writers that died (kill -9) for sessions no one holds.
void remove_stale_reserves(int fd, const std::string& db_path) {
  const std::filesystem::path db(db_path);
  remove_numbered(db.parent_path().string(), db.filename().string() + ".reserve-", [fd](std::int64_t session_id) {
    return session_id > 0 && !held_by_other(fd, F_WRLCK, session_byte(session_id));
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
  auto fd = open_locked(db_path, F_RDLCK, refused);
  if (!fd) return fd.error();
  if (!refused.empty()) {
    const LockHolder h = read_slot(*fd, 0);
    ::close(*fd);
    return DataError{DataError::Kind::in_use, db_path + ": the whole file is being replaced by " + describe(h) +
                                                  " (curvlab merge --out); nothing was changed. Try again when it "
                                                  "has finished"};
  }
  remove_stale_reserves(*fd, db_path);
  return WriterLock(*fd, db_path);
}

Expected<WriterLock> WriterLock::for_replacing(const std::string& db_path) {
  std::string refused;
  auto fd = open_locked(db_path, F_WRLCK, refused);
  if (!fd) return fd.error();
  if (!refused.empty()) {
    const auto live = live_session(*fd);
    const LockHolder other = live ? live->second : read_slot(*fd, 0);
    ::close(*fd);
    if (live) return DataError{DataError::Kind::in_use, session_in_use_message(db_path, live->first, live->second)};
    return DataError{DataError::Kind::in_use, db_path + ": the file is in use by " + describe(other) +
                                                  "; nothing was changed. Try again when it has finished"};
  }
  write_slot(*fd, 0);
  WriterLock lock(*fd, db_path);
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
  if (!try_lock(fd_, F_WRLCK, session_byte(session_id)))
    return DataError{DataError::Kind::in_use, session_in_use_message(db_path_, session_id, read_slot(fd_, session_id))};
  write_slot(fd_, session_id);
  session_ = session_id;
  make_reserve(reserve_path(db_path_, session_id));
  return Done{};
}

bool WriterLock::free_reserve() noexcept {
  if (fd_ < 0 || !session_) return false;
  return ::unlink(reserve_path(db_path_, *session_).c_str()) == 0;
}

std::optional<LockHolder> WriterLock::session_writer(const std::string& db_path, std::int64_t session_id) {
  // O_RDONLY and no O_CREAT: probing never creates a file; closing this
  // descriptor releases no lock, since OFD locks belong to their own
  // open file description.
  const int fd = ::open(lock_path(db_path).c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  std::optional<LockHolder> out;
  if (held_by_other(fd, F_WRLCK, session_byte(session_id))) out = read_slot(fd, session_id);
  ::close(fd);
  return out;
}

WriterLock::WriterLock(WriterLock&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      db_path_(std::move(other.db_path_)),
      session_(std::exchange(other.session_, std::nullopt)),
      replacing_(std::exchange(other.replacing_, false)) {}

WriterLock& WriterLock::operator=(WriterLock&& other) noexcept {
  if (this != &other) {
    release();
    fd_ = std::exchange(other.fd_, -1);
    db_path_ = std::move(other.db_path_);
    session_ = std::exchange(other.session_, std::nullopt);
    replacing_ = std::exchange(other.replacing_, false);
  }
  return *this;
}

WriterLock::~WriterLock() { release(); }

void WriterLock::release() noexcept {
  if (fd_ < 0) return;
  if (session_) {
    ::unlink(reserve_path(db_path_, *session_).c_str());
    clear_slot(fd_, *session_);
    unlock(fd_, session_byte(*session_));
  }
  if (replacing_) clear_slot(fd_, 0);
  // The last holder removes the lock file; later lockers find the path's
  // new file (open_locked checks the inode after locking).
  if (try_lock(fd_, F_WRLCK, file_byte)) ::unlink(lock_path(db_path_).c_str());
  ::close(fd_);
  fd_ = -1;
}

}  // namespace curvlab::data
