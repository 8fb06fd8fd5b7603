// How a session reports its progress. On stderr by default: when stderr is a
// terminal, a bar redrawn in place after every trial; otherwise (a log file,
// a pipe, a lab script's capture) one plain line every `line_every` (10 s by
// default), with no carriage returns, so that a log of a long simulated run
// shows it is alive and how long it has left. With --progress json, one
// compact JSON object per trial on stdout instead, a line each, flushed at
// once, for lab scripts that watch a session (docs/xr.md, "The operator
// window", lists the members). Owned by the session thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

#include "curvlab/harness/platform/terminal.hpp"

namespace curvlab::harness::runner {

// Where a session stands, for a progress report.
struct ProgressPoint {
  std::int64_t trial = 0;  // the trial running, or the last one ended, from 1
  std::int64_t total = 0;  // trials planned
  std::int64_t ended = 0;  // trials ended in this run (a resumed run: since it began)
  std::int64_t left = 0;   // trials still to run
  std::string_view block;
};

class Progress {
 public:
  // `on`: report on stderr (not --quiet, not --json); `json`: the JSON
  // stream on stdout instead.
  Progress(bool on, bool json, std::chrono::milliseconds line_every)
      : mode_(json || !on ? Mode::none : platform::stderr_is_terminal() ? Mode::bar : Mode::lines),
        json_(json),
        line_every_(line_every),
        next_line_(start_ + line_every) {}
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress() {
    if (drawn_) std::fputc('\n', stderr);
  }

  [[nodiscard]] bool json() const { return json_; }

  // After every trial: the bar.
  void update(const ProgressPoint& p) {
    if (mode_ != Mode::bar || p.total <= 0) return;
    constexpr int width = 30;
    const auto filled = static_cast<std::size_t>(width * p.trial / p.total);
    const std::string block(p.block);
    std::fprintf(stderr, "\r[%s%s] %lld/%lld trials  %-16.16s %5.0f s", std::string(filled, '#').c_str(),
                 std::string(static_cast<std::size_t>(width) - filled, '.').c_str(),
                 static_cast<long long>(p.trial), static_cast<long long>(p.total), block.c_str(), elapsed_s());
    std::fflush(stderr);
    drawn_ = true;
  }

  // Every frame: a line when one is due. The time left is the wall time per
  // trial ended so far, times the trials left.
  void tick(const ProgressPoint& p) {
    if (mode_ != Mode::lines || p.total <= 0) return;
    const auto now = std::chrono::steady_clock::now();
    if (now < next_line_) return;
    next_line_ = now + line_every_;
    const double elapsed = elapsed_s();
    const std::string block = p.block.empty() ? std::string() : " (" + std::string(p.block) + ")";
    std::fprintf(stderr, "curvlab: trial %lld of %lld%s, %.0f s elapsed, ", static_cast<long long>(p.trial),
                 static_cast<long long>(p.total), block.c_str(), elapsed);
    if (p.ended > 0)
      std::fprintf(stderr, "about %.0f s left\n", elapsed / static_cast<double>(p.ended) * static_cast<double>(p.left));
    else
      std::fputs("time left not known yet\n", stderr);
    std::fflush(stderr);
  }

  // One trial's JSON object (already serialised, without newlines). false:
  // it could not be written — the reader of stdout has gone (a pipe into
  // `head -3` closed, EPIPE; the CLI ignores SIGPIPE) or the disk behind a
  // redirection is full — and the session should end as on a stop signal.
  [[nodiscard]] bool line(const std::string& json_object) const {
    if (!json_) return true;
    const bool written = std::fputs(json_object.c_str(), stdout) >= 0 && std::fputc('\n', stdout) != EOF;
    return std::fflush(stdout) == 0 && written;
  }

 private:
  enum class Mode { none, bar, lines };

  [[nodiscard]] double elapsed_s() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

  Mode mode_;
  bool json_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::duration line_every_;
  std::chrono::steady_clock::time_point next_line_;
};

}  // namespace curvlab::harness::runner
