// Starts `curvlab` (CURVLAB_BIN) with its output discarded, waits until
// `ready()` (polled every 20 ms, at most 120 s), then `delay`, and kills it
// with SIGKILL — a crash at an instant the test chooses. Returns true when the
// kill landed (the program was still running), false when it had exited.
#pragma once

#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <functional>
#include <spawn.h>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <vector>

extern char** environ;

namespace curvlab::testing {

// Starts CURVLAB_BIN with `args`, its stdout and stderr written to `out`
// (truncated; /dev/null discards them): its pid, or 0 when it did not start.
inline pid_t spawn_curvlab(const std::vector<std::string>& args, const std::string& out = "/dev/null") {
  std::vector<char*> argv;
  std::string bin = CURVLAB_BIN;
  argv.push_back(bin.data());
  std::vector<std::string> copy = args;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  if (posix_spawn(&pid, bin.c_str(), &actions, nullptr, argv.data(), environ) != 0) pid = 0;
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

inline bool run_and_kill(const std::vector<std::string>& args, std::chrono::milliseconds delay,
                         const std::function<bool()>& ready = [] { return true; }) {
  const pid_t pid = spawn_curvlab(args);
  if (pid == 0) return false;
  int status = 0;
  for (int i = 0; i < 6000 && !ready(); ++i) {
    if (waitpid(pid, &status, WNOHANG) != 0) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(delay);
  const bool running = waitpid(pid, &status, WNOHANG) == 0;
  if (running) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  return running;
}

}  // namespace curvlab::testing
