// The POSIX (Linux) side of harness/include/curvlab/harness/platform/: the
// system calls curvlab has used on Linux from the start.
#include "curvlab/harness/platform/files.hpp"
#include "curvlab/harness/platform/lock_file.hpp"
#include "curvlab/harness/platform/process.hpp"
#include "curvlab/harness/platform/signals.hpp"
#include "curvlab/harness/platform/terminal.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <mutex>
#include <vector>
#include <utility>

namespace curvlab::harness::platform {

// --- process ---------------------------------------------------------------

std::int64_t process_id() { return ::getpid(); }

bool process_alive(std::int64_t pid) {
  if (pid <= 0 || pid > std::numeric_limits<pid_t>::max()) return false;
  return !(::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH);
}

std::string host_name() {
  std::array<char, 256> host{};
  if (::gethostname(host.data(), host.size() - 1) != 0) return {};
  return host.data();
}

std::string utc_now_iso8601() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::array<char, 32> text{};
  std::strftime(text.data(), text.size(), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text.data();
}

void set_env_default(const char* name, const char* value) { ::setenv(name, value, 0); }

// --- files -----------------------------------------------------------------

bool writable(const std::string& path) { return ::access(path.c_str(), W_OK) == 0; }

std::optional<std::uint64_t> free_bytes(const std::string& dir) {
  struct statvfs st {};
  if (::statvfs(dir.c_str(), &st) != 0) return std::nullopt;
  return std::uint64_t{st.f_bavail} * std::uint64_t{st.f_frsize};
}

int rename_replacing(const std::string& from, const std::string& to) {
  return ::rename(from.c_str(), to.c_str()) == 0 ? 0 : errno;
}

int exchange_paths(const std::string& a, const std::string& b) {
  return ::renameat2(AT_FDCWD, a.c_str(), AT_FDCWD, b.c_str(), RENAME_EXCHANGE) == 0 ? 0 : errno;
}

std::FILE* create_new_file(const std::string& path) { return std::fopen(path.c_str(), "wx"); }

std::string beside_executable(const std::string& relative) {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? relative : (exe.parent_path() / relative).string();
}

// --- lock file ---------------------------------------------------------------

const bool LockFile::unlink_when_free = true;

namespace {
struct flock range(short type, std::int64_t start) {
  struct flock f {};
  f.l_type = type;
  f.l_whence = SEEK_SET;
  f.l_start = static_cast<off_t>(start);
  f.l_len = 1;
  return f;
}

// Data-file descriptors given back by close(): never closed before the
// process exits (lock_file.hpp), reused by the next open of the same file.
struct KeptDescriptor {
  int fd;
  bool writable;
};
std::mutex kept_mutex;
std::vector<KeptDescriptor> kept;

bool same_file(const struct stat& a, const struct stat& b) { return a.st_dev == b.st_dev && a.st_ino == b.st_ino; }

int take_kept(const std::string& path, bool writable) {
  struct stat by_path {};
  if (::stat(path.c_str(), &by_path) != 0) return -1;
  std::lock_guard lock(kept_mutex);
  for (auto it = kept.begin(); it != kept.end(); ++it) {
    struct stat by_fd {};
    if ((writable && !it->writable) || ::fstat(it->fd, &by_fd) != 0 || !same_file(by_fd, by_path)) continue;
    const int fd = it->fd;
    kept.erase(it);
    return fd;
  }
  return -1;
}

void keep(int fd) {
  const bool writable = (::fcntl(fd, F_GETFL) & O_ACCMODE) == O_RDWR;
  // Gives back every lock of this open, and only its own: an open-file-
  // description unlock never touches SQLite's classic locks.
  struct flock all = range(F_UNLCK, 0);
  all.l_len = 0;
  (void)::fcntl(fd, F_OFD_SETLK, &all);
  std::lock_guard lock(kept_mutex);
  kept.push_back({fd, writable});
}

Unsafe check_companion(const struct stat& st) {
  if (S_ISLNK(st.st_mode)) return Unsafe::link;
  if (!S_ISREG(st.st_mode)) return Unsafe::not_regular;
  if (st.st_nlink != 1) return Unsafe::several_names;
  if (st.st_uid != ::geteuid()) return Unsafe::other_owner;
  return Unsafe::none;
}

int open_database(const std::string& path, bool writable) {
  const int fd = take_kept(path, writable);
  if (fd >= 0) return fd;
  return writable ? ::open(path.c_str(), O_RDWR | O_CREAT | O_NONBLOCK | O_CLOEXEC, 0666)
                  : ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
}

}  // namespace

LockFile LockFile::open(const std::string& path, Mode mode) {
  LockFile f;
  const bool database = mode == Mode::database || mode == Mode::database_read_only;
  const bool writable = mode == Mode::database || mode == Mode::create_read_write;
  if (database) {
    f.fd_ = open_database(path, writable);
  } else {
    // A companion is looked at before it is opened, so that a hard link to
    // another file is never opened at all, and again after (its name may
    // have been replaced in between).
    struct stat before {};
    if (::lstat(path.c_str(), &before) == 0) f.unsafe_ = check_companion(before);
    if (f.unsafe_ != Unsafe::none) return f;
    f.fd_ = writable ? ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0644)
                     : ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
  }
  if (f.fd_ < 0) {
    f.error_ = errno;
    if (!database && f.error_ == ELOOP) f.unsafe_ = Unsafe::link;
    if (!database && f.error_ == EISDIR) f.unsafe_ = Unsafe::not_regular;
    return f;
  }
  struct stat st {};
  (void)::fstat(f.fd_, &st);
  const Unsafe found = database ? (S_ISREG(st.st_mode) ? Unsafe::none : Unsafe::not_regular) : check_companion(st);
  if (found != Unsafe::none) {
    // Kept, not closed: a planted name may reach a file this process has
    // open in SQLite.
    if (S_ISREG(st.st_mode)) keep(f.fd_);
    else ::close(f.fd_);
    f.fd_ = -1;
    f.unsafe_ = found;
    return f;
  }
  f.keep_open_ = database;
  return f;
}

void LockFile::close() noexcept {
  if (fd_ >= 0) {
    if (keep_open_) keep(fd_);
    else ::close(fd_);
  }
  fd_ = -1;
  keep_open_ = false;
  own_.clear();
}

bool LockFile::try_lock(std::int64_t byte, bool exclusive) {
  struct flock f = range(exclusive ? F_WRLCK : F_RDLCK, byte);
  if (::fcntl(fd_, F_OFD_SETLK, &f) != 0) return false;
  own_[byte] = exclusive;
  return true;
}

void LockFile::unlock(std::int64_t byte) {
  struct flock f = range(F_UNLCK, byte);
  (void)::fcntl(fd_, F_OFD_SETLK, &f);
  own_.erase(byte);
}

bool LockFile::held_elsewhere(std::int64_t byte, bool exclusive) {
  struct flock f = range(exclusive ? F_WRLCK : F_RDLCK, byte);
  if (::fcntl(fd_, F_OFD_GETLK, &f) != 0) return false;
  return f.l_type != F_UNLCK;
}

bool LockFile::still_named(const std::string& path) const {
  struct stat by_fd {}, by_path {};
  return ::fstat(fd_, &by_fd) == 0 && ::stat(path.c_str(), &by_path) == 0 && by_fd.st_ino == by_path.st_ino &&
         by_fd.st_dev == by_path.st_dev;
}

std::int64_t LockFile::size() const {
  struct stat st {};
  if (::fstat(fd_, &st) != 0) return 0;
  return st.st_size;
}

void LockFile::write_at(const std::string& bytes, std::int64_t at) {
  (void)!::pwrite(fd_, bytes.data(), bytes.size(), static_cast<off_t>(at));
}

std::string LockFile::read_at(std::size_t n, std::int64_t at) const {
  std::string text(n, '\0');
  const ssize_t got = ::pread(fd_, text.data(), text.size(), static_cast<off_t>(at));
  text.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
  return text;
}

bool reserve_file(const std::string& path, std::int64_t bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) return false;
  if (::posix_fallocate(fd, 0, static_cast<off_t>(bytes)) != 0) (void)::ftruncate(fd, 0);
  ::close(fd);
  return true;
}

bool remove_regular_file(const std::string& path) {
  struct stat st {};
  return ::lstat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::unlink(path.c_str()) == 0;
}

// --- signals -----------------------------------------------------------------

namespace {
// A handler may only set a lock-free atomic.
std::atomic<int> stop_signal{0};
extern "C" void on_stop_signal(int sig) { stop_signal.store(sig, std::memory_order_relaxed); }
}  // namespace

const std::atomic<int>& catch_stop_signals() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND | SA_RESTART;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &sa, nullptr);
  return stop_signal;
}

int stop_signal_received() { return stop_signal.load(std::memory_order_relaxed); }

std::string signal_name(int sig) { return ::strsignal(sig); }

// --- terminal ----------------------------------------------------------------

bool stderr_is_terminal() { return ::isatty(STDERR_FILENO) != 0; }

}  // namespace curvlab::harness::platform
