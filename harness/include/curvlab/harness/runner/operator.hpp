// The experimenter's side of a session (DESIGN.md §6): actions the operator
// takes while a participant runs (by key in the operator window, or from an
// --operator-script file for tests and demonstrations), and the status the
// session shows the operator each frame.
//
// The session loop (session_loop.cpp) asks its OperatorConsole for the
// actions due at each frame and turns them into the same signals a backend
// gives (phase.hpp): pause and resume hold the session and repeat the trial
// as a participant's pause does; recenter aborts and repeats the attempt;
// repeat runs the trial again; skip stores it `skipped` (end_reason
// "operator") and never runs it again; end stops the session resumable; a
// note is stored verbatim as an `operator_note` event. Every action is an
// event with its time stamp.
#pragma once

#include "curvlab/harness/result.hpp"
#include "curvlab/harness/runner/phase.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::runner {

enum class OperatorActionKind { pause, resume, recenter, repeat, skip, note, end };

std::string_view to_string(OperatorActionKind kind);
std::optional<OperatorActionKind> parse_operator_action(std::string_view name);

struct OperatorAction {
  OperatorActionKind kind = OperatorActionKind::note;
  std::int64_t at_ns = 0;  // script: time since the session started; window: when the key was pressed
  std::string text;        // note: the free text, verbatim
  std::string source;      // "script NAME:LINE" (the file's name, no folder) or "window"
};

// One action a line: `SECONDS ACTION [TEXT]`, seconds since the session
// started (a number ≥ 0), ACTION one of pause resume recenter repeat skip
// note end; TEXT only (and required) for note, kept verbatim after one
// space. `#` starts a comment (outside a note's text); blank lines are
// skipped. A bad line is an Error (kind bad_input) naming `name:line` and
// what was expected. Actions come back sorted by time, stable for equal times.
Result<std::vector<OperatorAction>> parse_operator_script(std::string_view text, const std::string& name);
// Reads and parses the file (an unreadable file is kind not_found).
Result<std::vector<OperatorAction>> read_operator_script(const std::string& path);

// A script's actions, handed out as the session clock passes them. Pure;
// not thread-safe.
class ScriptedActions {
 public:
  ScriptedActions() = default;
  explicit ScriptedActions(std::vector<OperatorAction> actions) : actions_(std::move(actions)) {}
  // Appends the actions due at `elapsed_ns` after the session started.
  void due(std::int64_t elapsed_ns, std::vector<OperatorAction>& out);
  [[nodiscard]] bool empty() const { return next_ >= actions_.size(); }

 private:
  std::vector<OperatorAction> actions_;
  std::size_t next_ = 0;
};

// What the operator sees about the session, rebuilt by the session loop each
// frame from numbers it has anyway (nothing here costs a system call).
struct OperatorStatus {
  std::string participant;
  std::int64_t session_id = 0;
  std::string protocol;
  std::string block;
  std::int64_t trial = 0;  // 1-based position in the design; 0 outside trials
  std::int64_t trials = 0;
  std::string condition;  // factor=level pairs
  std::int64_t attempt = 0;
  Phase phase = Phase::instructions;
  std::int64_t phase_left_ns = -1;  // -1: open-ended (pages, pauses)
  std::int64_t elapsed_ns = 0;
  std::int64_t remaining_ns = -1;  // estimate; -1 before the first trial ends
  // head, left hand, right hand: tracked now, and since when lost (-1 tracked)
  std::array<bool, 3> tracked{false, false, false};
  std::array<std::int64_t, 3> lost_ns{-1, -1, -1};
  std::string last_response;
  double last_rt_ms = -1.0;
  std::int64_t late_trial = 0;
  std::int64_t late_session = 0;
  double cpu_ms = 0.0;
  double gpu_ms = -1.0;  // -1: not measured
  std::uint64_t logger_drops = 0;
  double logger_lock_wait_s = 0.0;  // how long another program has held the file's lock (0: not waiting)
  bool paused = false;
  bool ended = false;  // the session is over; last status
  // A shared game: both players and the link ("you host P01, partner join
  // AB: connected  RTT 3 ms  clock offset +0.2 ms  loss 0 %  heads 1.8 m
  // apart"); empty outside shared games.
  std::string partner;
};

// The operator's console: the status shown and the actions taken. The
// session loop calls it from its frame thread; implementations that draw on
// another thread copy what they need. show() must be cheap (the frame loop
// calls it every frame).
class OperatorConsole {
 public:
  virtual ~OperatorConsole() = default;
  OperatorConsole() = default;
  OperatorConsole(const OperatorConsole&) = delete;
  OperatorConsole& operator=(const OperatorConsole&) = delete;

  virtual void show(const OperatorStatus& status) = 0;
  // Appends the actions due now (`elapsed_ns` since the session started).
  virtual void take(std::int64_t elapsed_ns, std::vector<OperatorAction>& out) = 0;
  // After the loop carried out `action` (screenshots are taken here).
  virtual void acted(const OperatorAction& action) { (void)action; }
};

// A console without a window: the script's actions only (headless runs,
// --operator-window off).
class ScriptConsole final : public OperatorConsole {
 public:
  explicit ScriptConsole(std::vector<OperatorAction> actions) : script_(std::move(actions)) {}
  void show(const OperatorStatus& status) override { (void)status; }
  void take(std::int64_t elapsed_ns, std::vector<OperatorAction>& out) override { script_.due(elapsed_ns, out); }

 private:
  ScriptedActions script_;
};

// The status as text lines for the operator's panel (and logs).
std::vector<std::string> status_lines(const OperatorStatus& status, std::optional<double> free_disk_gb);

}  // namespace curvlab::harness::runner
