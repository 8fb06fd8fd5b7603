// What the sharing tests and the reader-plus-kill benchmark need: a curvlab
// process in the background, the readers a lab opens the file with, a
// read-only file system.
#pragma once

#include "data_files.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace curvlab::testing::sharing {

namespace fs = std::filesystem;

inline std::int64_t count_lines(const fs::path& p, const std::string& needle) {
  std::istringstream in(read_file(p));
  std::int64_t n = 0;
  for (std::string line; std::getline(in, line);)
    if (line.find(needle) != std::string::npos) ++n;
  return n;
}

// A child process with stdout and stderr in files; killed with SIGKILL if
// still running when destroyed.
struct Child {
  pid_t pid = -1;
  fs::path out, err;
  bool reaped = false;
  int status = 0;  // the wait status, once reaped

  int wait() {
    if (!reaped) ::waitpid(pid, &status, 0);
    reaped = true;
    return status;
  }
  void kill9() {
    ::kill(pid, SIGKILL);
    wait();
  }
  int signal_and_wait(int sig) {
    ::kill(pid, sig);
    return wait();
  }
  bool running() {
    if (reaped) return false;
    if (::waitpid(pid, &status, WNOHANG) == pid) reaped = true;
    return !reaped;
  }
  Child() = default;
  Child(Child&& o) noexcept : pid(o.pid), out(o.out), err(o.err), reaped(o.reaped), status(o.status) {
    o.reaped = true;
  }
  Child& operator=(Child&&) = delete;
  ~Child() {
    if (!reaped && pid > 0) kill9();
  }
};

inline Child spawn(const std::string& program, const std::vector<std::string>& args, const fs::path& out,
                   const fs::path& err) {
  Child c;
  c.out = out;
  c.err = err;
  c.pid = ::fork();
  if (c.pid == 0) {
    const int o = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int e = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(o, STDOUT_FILENO);
    ::dup2(e, STDERR_FILENO);
    std::vector<char*> argv{const_cast<char*>(program.c_str())};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(program.c_str(), argv.data());
    ::_exit(127);
  }
  return c;
}

// A realtime session of `protocol` in the background, its output in
// DIR/PARTICIPANT.out and .err (one JSON line per trial on stdout).
inline Child start_realtime_session(const std::string& curvlab, const std::string& protocol, const fs::path& dir,
                                    const std::string& db, const std::string& participant) {
  return spawn(curvlab,
               {"run", protocol, "--participant", participant, "--db", db, "--render", "none", "--pace", "realtime",
                "--progress", "json"},
               dir / (participant + ".out"), dir / (participant + ".err"));
}

// Waits until `file` has `count` lines containing `needle`.
inline bool wait_for_lines(const fs::path& file, const std::string& needle, std::int64_t count,
                           std::chrono::seconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < until) {
    if (count_lines(file, needle) >= count) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

// Opens and closes `db` once as a lab's reader would, taking turns:
// curvlab export, the sqlite3 shell, Python's sqlite3 module.
inline void read_once(const std::string& curvlab, const std::string& db, const fs::path& scratch, int turn) {
  std::string cmd;
  switch (turn % 3) {
    case 0:
      cmd = curvlab + " export --db " + db + " --out " + (scratch / "reader_export").string() +
            " --format csv";
      break;
    case 1: cmd = "sqlite3 " + db + " 'SELECT count(*) FROM trials' "; break;
    default:
      cmd = "/usr/bin/python3 -c \"import sqlite3; c = sqlite3.connect('" + db +
            "'); c.execute('SELECT count(*) FROM trials').fetchone(); c.close()\"";
  }
  (void)!std::system((cmd + " >/dev/null 2>&1").c_str());
  fs::remove_all(scratch / "reader_export");
}

// Writes `file` until the file system is full (ENOSPC).
inline void fill_disk(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const std::string block(1 << 16, 'x');
  while (::write(fd, block.data(), block.size()) > 0) {
  }
  const std::string small(512, 'x');
  while (::write(fd, small.data(), small.size()) > 0) {
  }
  ::close(fd);
}

// A small tmpfs mounted at `path`, remounted read-only on request, unmounted
// on destruction. Needs root (CAP_SYS_ADMIN); ok() says whether it worked.
class ReadOnlyMount {
 public:
  explicit ReadOnlyMount(fs::path path, std::string options = "size=160m")
      : path_(std::move(path)), options_(std::move(options)) {
    fs::create_directories(path_);
    if (::mount("tmpfs", path_.c_str(), "tmpfs", 0, options_.c_str()) != 0) {
      why_ = std::strerror(errno);
      return;
    }
    mounted_ = true;
  }
  ~ReadOnlyMount() {
    if (mounted_) ::umount2(path_.c_str(), MNT_DETACH);
  }
  ReadOnlyMount(const ReadOnlyMount&) = delete;
  ReadOnlyMount& operator=(const ReadOnlyMount&) = delete;
  bool ok() const { return mounted_; }
  const std::string& why() const { return why_; }
  const fs::path& path() const { return path_; }
  bool make_read_only() {
    if (::mount("tmpfs", path_.c_str(), "tmpfs", MS_REMOUNT | MS_RDONLY, options_.c_str()) == 0) return true;
    why_ = std::strerror(errno);
    return false;
  }

 private:
  fs::path path_;
  std::string options_;
  bool mounted_ = false;
  std::string why_;
};

}  // namespace curvlab::testing::sharing
