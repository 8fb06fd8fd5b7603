// A private X server for window tests: uses $DISPLAY when one is set (a
// desktop session or xvfb-run), else starts Xvfb on a free display number
// (-displayfd) and stops it, by its process id, at the end. When neither is
// possible the tests skip with the reason.
#pragma once

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

namespace curvlab::test {

// Owns the Xvfb child process it started (if any). Move-less; one per test suite.
class XServer {
 public:
  XServer() {
    if (const char* d = std::getenv("DISPLAY"); d != nullptr && *d != '\0') {
      display_ = d;
      return;
    }
    const char* exe = "/usr/bin/Xvfb";
    if (!std::filesystem::exists(exe)) {
      reason_ = "no display and no Xvfb (apt-get install xvfb)";
      return;
    }
    int fds[2];
    if (pipe(fds) != 0) {
      reason_ = "pipe() failed";
      return;
    }
    pid_ = fork();
    if (pid_ == 0) {
      close(fds[0]);
      const std::string fd = std::to_string(fds[1]);
      // Silence the server's chatter about fonts and keymaps.
      const int null = open("/dev/null", O_WRONLY);
      if (null >= 0) {
        dup2(null, 1);
        dup2(null, 2);
      }
      // -noreset: by default the server resets when its last client leaves
      // and refuses connections meanwhile, which fails the next window.
      execl(exe, exe, "-displayfd", fd.c_str(), "-screen", "0", "1280x1024x24", "-nolisten",
            "tcp", "-noreset", static_cast<char*>(nullptr));
      _exit(127);
    }
    close(fds[1]);
    std::string number;
    char c = 0;
    while (read(fds[0], &c, 1) == 1 && c != '\n') number += c;
    close(fds[0]);
    if (pid_ < 0 || number.empty()) {
      reason_ = "Xvfb did not start";
      stop();
      return;
    }
    display_ = ":" + number;
    setenv("DISPLAY", display_.c_str(), 1);
  }
  ~XServer() {
    stop();
  }
  XServer(const XServer&) = delete;
  XServer& operator=(const XServer&) = delete;

  [[nodiscard]] bool available() const { return !display_.empty(); }
  [[nodiscard]] const std::string& reason() const { return reason_; }
  [[nodiscard]] const std::string& display() const { return display_; }

 private:
  void stop() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      waitpid(pid_, nullptr, 0);
      pid_ = -1;
      unsetenv("DISPLAY");
    }
  }
  pid_t pid_ = -1;
  std::string display_;
  std::string reason_;
};

}  // namespace curvlab::test
