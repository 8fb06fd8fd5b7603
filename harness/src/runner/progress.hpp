// How a session reports its progress: by default a bar on stderr, one line
// redrawn in place, only when stderr is a terminal; with --progress json, one
// compact JSON object per trial on stdout, a line each, flushed at once, for
// lab scripts that watch a session (docs/xr.md, "The operator window", lists the members).
// Owned by the session thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

namespace curvlab::harness::runner {

class Progress {
 public:
  Progress(bool bar, bool json) : on_(bar && !json && isatty(STDERR_FILENO) != 0), json_(json) {}
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress() {
    if (drawn_) std::fputc('\n', stderr);
  }

  [[nodiscard]] bool json() const { return json_; }

  void update(std::int64_t done, std::int64_t total, const std::string& block) {
    if (!on_ || total <= 0) return;
    constexpr int width = 30;
    const auto filled = static_cast<std::size_t>(width * done / total);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    std::fprintf(stderr, "\r[%s%s] %lld/%lld trials  %-16.16s %5.0f s", std::string(filled, '#').c_str(),
                 std::string(static_cast<std::size_t>(width) - filled, '.').c_str(), static_cast<long long>(done),
                 static_cast<long long>(total), block.c_str(), s);
    std::fflush(stderr);
    drawn_ = true;
  }

  // One trial's JSON object (already serialised, without newlines).
  void line(const std::string& json_object) const {
    if (!json_) return;
    std::fputs(json_object.c_str(), stdout);
    std::fputc('\n', stdout);
    std::fflush(stdout);
  }

 private:
  bool on_;
  bool json_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace curvlab::harness::runner
