// The Windows side of harness/include/curvlab/harness/platform/ (built with
// MinGW-w64, tested under Wine: tests/windows). Paths are UTF-8 in curvlab
// and UTF-16 for the Win32 calls.
#include "curvlab/harness/platform/files.hpp"
#include "curvlab/harness/platform/lock_file.hpp"
#include "curvlab/harness/platform/process.hpp"
#include "curvlab/harness/platform/signals.hpp"
#include "curvlab/harness/platform/terminal.hpp"

#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#ifndef NOMINMAX
#define NOMINMAX
#endif
#include <windows.h>

#include <fcntl.h>
#include <io.h>

#include <array>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <utility>

namespace curvlab::harness::platform {
namespace {

std::wstring wide(const std::string& utf8) { return std::filesystem::u8path(utf8).wstring(); }

int errno_of(DWORD error) {
  switch (error) {
    case ERROR_ACCESS_DENIED:
    case ERROR_SHARING_VIOLATION:
    case ERROR_LOCK_VIOLATION: return EACCES;
    case ERROR_WRITE_PROTECT: return EROFS;
    case ERROR_FILE_NOT_FOUND:
    case ERROR_PATH_NOT_FOUND: return ENOENT;
    case ERROR_DIR_NOT_EMPTY: return ENOTEMPTY;
    case ERROR_ALREADY_EXISTS:
    case ERROR_FILE_EXISTS: return EEXIST;
    case ERROR_DISK_FULL:
    case ERROR_HANDLE_DISK_FULL: return ENOSPC;
    case ERROR_NOT_SUPPORTED:
    case ERROR_CALL_NOT_IMPLEMENTED: return ENOSYS;
    default: return EIO;
  }
}

HANDLE handle_of(int fd) { return reinterpret_cast<HANDLE>(::_get_osfhandle(fd)); }

OVERLAPPED at_offset(std::int64_t at) {
  OVERLAPPED o{};
  o.Offset = static_cast<DWORD>(static_cast<std::uint64_t>(at) & 0xffffffffu);
  o.OffsetHigh = static_cast<DWORD>(static_cast<std::uint64_t>(at) >> 32);
  return o;
}

}  // namespace

// --- process ---------------------------------------------------------------

std::int64_t process_id() { return static_cast<std::int64_t>(::GetCurrentProcessId()); }

bool process_alive(std::int64_t pid) {
  if (pid <= 0 || pid > 0xffffffffLL) return false;
  HANDLE h = ::OpenProcess(PROCESS_QUERY_LIMITED_INFORMATION, FALSE, static_cast<DWORD>(pid));
  if (h == nullptr) return ::GetLastError() == ERROR_ACCESS_DENIED;  // exists, another user's
  DWORD code = 0;
  const bool running = ::GetExitCodeProcess(h, &code) != 0 && code == STILL_ACTIVE;
  ::CloseHandle(h);
  return running;
}

std::string host_name() {
  std::array<char, MAX_COMPUTERNAME_LENGTH + 1> host{};
  DWORD n = static_cast<DWORD>(host.size());
  if (::GetComputerNameA(host.data(), &n) == 0) return {};
  return std::string(host.data(), n);
}

std::string utc_now_iso8601() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  ::gmtime_s(&tm, &t);
  std::array<char, 32> text{};
  std::strftime(text.data(), text.size(), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text.data();
}

void set_env_default(const char* name, const char* value) {
  if (std::getenv(name) == nullptr) ::_putenv_s(name, value);
}

// --- files -----------------------------------------------------------------

bool writable(const std::string& path) {
  const DWORD attributes = ::GetFileAttributesW(wide(path).c_str());
  if (attributes == INVALID_FILE_ATTRIBUTES) return false;
  // The read-only attribute of a folder is advisory on Windows: a folder is
  // writable when a file can be made in it.
  if ((attributes & FILE_ATTRIBUTE_DIRECTORY) == 0) return (attributes & FILE_ATTRIBUTE_READONLY) == 0;
  const std::wstring probe = wide(path) + L"\\.curvlab-write-probe-" + std::to_wstring(::GetCurrentProcessId());
  HANDLE h = ::CreateFileW(probe.c_str(), GENERIC_WRITE, 0, nullptr, CREATE_NEW,
                           FILE_ATTRIBUTE_TEMPORARY | FILE_FLAG_DELETE_ON_CLOSE, nullptr);
  if (h == INVALID_HANDLE_VALUE) return false;
  ::CloseHandle(h);
  return true;
}

std::optional<std::uint64_t> free_bytes(const std::string& dir) {
  ULARGE_INTEGER available{};
  if (::GetDiskFreeSpaceExW(wide(dir).c_str(), &available, nullptr, nullptr) == 0) return std::nullopt;
  return available.QuadPart;
}

int rename_replacing(const std::string& from, const std::string& to) {
  const std::wstring f = wide(from), t = wide(to);
  const DWORD to_attributes = ::GetFileAttributesW(t.c_str());
  if (to_attributes != INVALID_FILE_ATTRIBUTES && (to_attributes & FILE_ATTRIBUTE_DIRECTORY) != 0) {
    // MoveFileEx replaces files only: an empty folder goes first, as
    // rename(2) would replace it.
    if (::RemoveDirectoryW(t.c_str()) == 0) {
      const DWORD e = ::GetLastError();
      return e == ERROR_DIR_NOT_EMPTY ? ENOTEMPTY : errno_of(e);
    }
  }
  if (::MoveFileExW(f.c_str(), t.c_str(), MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH) != 0) return 0;
  return errno_of(::GetLastError());
}

int exchange_paths(const std::string&, const std::string&) { return ENOSYS; }

std::FILE* create_new_file(const std::string& path) {
  HANDLE h = ::CreateFileW(wide(path).c_str(), GENERIC_WRITE, FILE_SHARE_READ, nullptr, CREATE_NEW,
                           FILE_ATTRIBUTE_NORMAL, nullptr);
  if (h == INVALID_HANDLE_VALUE) return nullptr;
  const int fd = ::_open_osfhandle(reinterpret_cast<intptr_t>(h), _O_WRONLY | _O_BINARY);
  if (fd < 0) {
    ::CloseHandle(h);
    return nullptr;
  }
  std::FILE* f = ::_fdopen(fd, "wb");
  if (f == nullptr) ::_close(fd);
  return f;
}

std::string beside_executable(const std::string& relative) {
  std::wstring exe(32768, L'\0');
  exe.resize(::GetModuleFileNameW(nullptr, exe.data(), static_cast<DWORD>(exe.size())));
  const auto path = std::filesystem::path(exe).parent_path() / std::filesystem::u8path(relative);
  const auto utf8 = path.u8string();
  return std::string(utf8.begin(), utf8.end());
}

// --- lock file ---------------------------------------------------------------

const bool LockFile::unlink_when_free = false;

namespace {

// Why a companion opened without following reparse points is not one
// curvlab may write (the owner is not checked on Windows).
Unsafe check_companion(HANDLE h) {
  BY_HANDLE_FILE_INFORMATION info{};
  if (::GetFileInformationByHandle(h, &info) == 0) return Unsafe::not_regular;
  if ((info.dwFileAttributes & FILE_ATTRIBUTE_REPARSE_POINT) != 0) return Unsafe::link;
  if ((info.dwFileAttributes & FILE_ATTRIBUTE_DIRECTORY) != 0) return Unsafe::not_regular;
  if (info.nNumberOfLinks > 1) return Unsafe::several_names;
  return Unsafe::none;
}

}  // namespace

LockFile LockFile::open(const std::string& path, Mode mode) {
  LockFile f;
  const bool database = mode == Mode::database || mode == Mode::database_read_only;
  const bool rw = mode == Mode::create_read_write || mode == Mode::database;
  const DWORD flags = FILE_ATTRIBUTE_NORMAL | (database ? 0 : FILE_FLAG_OPEN_REPARSE_POINT);
  HANDLE h = ::CreateFileW(wide(path).c_str(), rw ? GENERIC_READ | GENERIC_WRITE : GENERIC_READ,
                           FILE_SHARE_READ | FILE_SHARE_WRITE | FILE_SHARE_DELETE, nullptr,
                           rw ? OPEN_ALWAYS : OPEN_EXISTING, flags, nullptr);
  if (h == INVALID_HANDLE_VALUE) {
    f.error_ = errno_of(::GetLastError());
    return f;
  }
  if (!database) {
    f.unsafe_ = check_companion(h);
    if (f.unsafe_ != Unsafe::none) {
      ::CloseHandle(h);
      return f;
    }
  }
  // A C runtime descriptor owns the handle from here on (closed by _close).
  f.fd_ = ::_open_osfhandle(reinterpret_cast<intptr_t>(h), rw ? _O_RDWR : _O_RDONLY);
  if (f.fd_ < 0) {
    ::CloseHandle(h);
    f.error_ = EMFILE;
  }
  return f;
}

void LockFile::close() noexcept {
  if (fd_ >= 0) ::_close(fd_);
  fd_ = -1;
  own_.clear();
}

bool LockFile::try_lock(std::int64_t byte, bool exclusive) {
  // POSIX replaces a lock this open holds by the new kind; Windows would
  // stack a second lock (or refuse an exclusive one), so the old one goes
  // first: a conversion that fails leaves this open holding none.
  if (const auto held = own_.find(byte); held != own_.end()) {
    if (held->second == exclusive) return true;
    unlock(byte);
  }
  OVERLAPPED o = at_offset(byte);
  const DWORD flags = LOCKFILE_FAIL_IMMEDIATELY | (exclusive ? LOCKFILE_EXCLUSIVE_LOCK : 0);
  if (::LockFileEx(handle_of(fd_), flags, 0, 1, 0, &o) == 0) return false;
  own_[byte] = exclusive;
  return true;
}

void LockFile::unlock(std::int64_t byte) {
  if (own_.erase(byte) == 0) return;
  OVERLAPPED o = at_offset(byte);
  (void)::UnlockFileEx(handle_of(fd_), 0, 1, 0, &o);
}

bool LockFile::held_elsewhere(std::int64_t byte, bool exclusive) {
  // Windows has no F_GETLK: probe with a lock of the same kind and give it
  // back at once. A byte this open holds exclusively no other can hold;
  // one it holds shared conflicts only with exclusive probes, which cannot
  // be made through this open.
  if (const auto held = own_.find(byte); held != own_.end()) return false;
  if (!try_lock(byte, exclusive)) return true;
  unlock(byte);
  return false;
}

bool LockFile::still_named(const std::string& path) const {
  HANDLE h = ::CreateFileW(wide(path).c_str(), 0, FILE_SHARE_READ | FILE_SHARE_WRITE | FILE_SHARE_DELETE, nullptr,
                           OPEN_EXISTING, FILE_ATTRIBUTE_NORMAL, nullptr);
  if (h == INVALID_HANDLE_VALUE) return false;
  BY_HANDLE_FILE_INFORMATION by_path{}, by_fd{};
  const bool same = ::GetFileInformationByHandle(h, &by_path) != 0 &&
                    ::GetFileInformationByHandle(handle_of(fd_), &by_fd) != 0 &&
                    by_path.dwVolumeSerialNumber == by_fd.dwVolumeSerialNumber &&
                    by_path.nFileIndexHigh == by_fd.nFileIndexHigh && by_path.nFileIndexLow == by_fd.nFileIndexLow;
  ::CloseHandle(h);
  return same;
}

std::int64_t LockFile::size() const {
  LARGE_INTEGER n{};
  if (::GetFileSizeEx(handle_of(fd_), &n) == 0) return 0;
  return n.QuadPart;
}

void LockFile::write_at(const std::string& bytes, std::int64_t at) {
  OVERLAPPED o = at_offset(at);
  DWORD written = 0;
  (void)::WriteFile(handle_of(fd_), bytes.data(), static_cast<DWORD>(bytes.size()), &written, &o);
}

std::string LockFile::read_at(std::size_t n, std::int64_t at) const {
  std::string text(n, '\0');
  OVERLAPPED o = at_offset(at);
  DWORD got = 0;
  if (::ReadFile(handle_of(fd_), text.data(), static_cast<DWORD>(n), &got, &o) == 0) got = 0;
  text.resize(got);
  return text;
}

bool reserve_file(const std::string& path, std::int64_t bytes) {
  HANDLE h = ::CreateFileW(wide(path).c_str(), GENERIC_WRITE, FILE_SHARE_READ | FILE_SHARE_DELETE, nullptr,
                           CREATE_NEW, FILE_ATTRIBUTE_NORMAL | FILE_FLAG_OPEN_REPARSE_POINT, nullptr);
  if (h == INVALID_HANDLE_VALUE) return false;
  LARGE_INTEGER end{};
  end.QuadPart = bytes;
  // Extending the end allocates the clusters on NTFS; without space the
  // file stays empty.
  if (::SetFilePointerEx(h, end, nullptr, FILE_BEGIN) == 0 || ::SetEndOfFile(h) == 0) {
    LARGE_INTEGER zero{};
    (void)::SetFilePointerEx(h, zero, nullptr, FILE_BEGIN);
    (void)::SetEndOfFile(h);
  }
  ::CloseHandle(h);
  return true;
}

bool remove_regular_file(const std::string& path) {
  const DWORD attributes = ::GetFileAttributesW(wide(path).c_str());
  if (attributes == INVALID_FILE_ATTRIBUTES ||
      (attributes & (FILE_ATTRIBUTE_DIRECTORY | FILE_ATTRIBUTE_REPARSE_POINT)) != 0)
    return false;
  return ::DeleteFileW(wide(path).c_str()) != 0;
}

// --- signals -----------------------------------------------------------------

namespace {
constexpr int console_closed = 1;  // SIGHUP's number on POSIX
std::atomic<int> stop_signal{0};

extern "C" void on_stop_signal(int sig) { stop_signal.store(sig, std::memory_order_relaxed); }

// Runs on a thread of its own that the system starts. Ctrl-C and Ctrl-Break
// go to the C runtime's SIGINT handler; closing the console, logoff and
// shutdown end the process when this returns, so it waits briefly for the
// frame loop to see the stop and commit.
BOOL WINAPI on_console_event(DWORD event) {
  switch (event) {
    case CTRL_CLOSE_EVENT:
    case CTRL_LOGOFF_EVENT:
    case CTRL_SHUTDOWN_EVENT:
      stop_signal.store(console_closed, std::memory_order_relaxed);
      ::Sleep(2000);
      return TRUE;
    default: return FALSE;
  }
}
}  // namespace

const std::atomic<int>& catch_stop_signals() {
  // The C runtime resets a handler to the default before calling it, as
  // SA_RESETHAND does: a second Ctrl-C ends the process.
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  std::signal(SIGBREAK, on_stop_signal);
  ::SetConsoleCtrlHandler(on_console_event, TRUE);
  return stop_signal;
}

int stop_signal_received() { return stop_signal.load(std::memory_order_relaxed); }

std::string signal_name(int sig) {
  switch (sig) {
    case SIGINT: return "Interrupt";
    case SIGTERM: return "Terminated";
    case SIGBREAK: return "Ctrl-Break";
    case console_closed: return "Console closed";
    default: return "signal " + std::to_string(sig);
  }
}

// --- terminal ----------------------------------------------------------------

bool stderr_is_terminal() {
  DWORD mode = 0;
  return ::GetConsoleMode(::GetStdHandle(STD_ERROR_HANDLE), &mode) != 0;
}

}  // namespace curvlab::harness::platform
