// Runs the curvlab executable as a user would and captures its output and
// exit code.
#pragma once

#include <array>
#include <cstdio>
#include <string>
#include <sys/wait.h>

namespace curvlab::testing {

struct CliResult {
  int exit_code = -1;
  std::string out;  // stdout and stderr together
};

// Runs a shell command line; its stdout and exit code.
inline CliResult run_shell(const std::string& cmd) {
  CliResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buf{};
  std::size_t n = 0;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// A run that hangs is stopped after 10 minutes (exit 124, its output kept),
// so a broken session fails its test instead of holding up the suite.
inline CliResult run_cli(const std::string& args) {
  return run_shell("timeout --foreground -k 10 600 " + std::string(CURVLAB_BIN) + " " + args + " 2>&1");
}

}  // namespace curvlab::testing
