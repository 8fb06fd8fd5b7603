// The experimenter's side of the frame loop (DESIGN.md §6; docs/xr.md, "The
// operator window"): the actions the console hands in, each logged with its
// time stamp and turned into the signal a device would have raised, and the
// status the console shows every frame. Owned by the frame thread; does
// nothing without a console.
#pragma once

#include "curvlab/geometry/tracking.hpp"
#include "curvlab/harness/data/events.hpp"
#include "curvlab/harness/io/frame.hpp"
#include "curvlab/harness/runner/operator.hpp"

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

namespace curvlab::harness::runner {

// What the frame loop knows at a frame's end, for the status.
struct StatusFacts {
  std::int64_t now_ns = 0;
  std::int64_t elapsed_ns = 0;  // since the session started
  std::int64_t trials_ended = 0;  // in this run
  std::int64_t trials_before = 0;  // ended before it (a resumed run)
  const geometry::LabFrame* lab = nullptr;
  double cpu_ms = 0.0;
  double gpu_ms = -1.0;
  std::uint64_t logger_drops = 0;
  double logger_lock_wait_s = 0.0;
};

class OperatorRoom {
 public:
  explicit OperatorRoom(OperatorConsole* console) : console_(console) {}
  [[nodiscard]] bool open() const { return console_ != nullptr; }

  // The actions due `elapsed_ns` after the start (`now_ns` on the session
  // clock), as the events to store; the first signal among them (or one
  // left from an earlier frame) becomes `signal` when the frame has none
  // yet. Call only when open().
  const std::vector<data::events::OperatorActionEvent>& take(std::int64_t elapsed_ns, std::int64_t now_ns,
                                                              io::Signal& signal);
  // Tells the console its actions were carried out (stored and signalled):
  // its screenshots are taken here.
  void acted();
  // Every frame: the status as of its end.
  void show(const StatusFacts& facts, Phase phase);
  // The last status, once the session is over.
  void show_ended();
  // A late frame, counted for the trial and the session.
  void count_late() {
    ++status.late_trial;
    ++status.late_session;
  }

  // What the block kinds tell the operator: block, trial, condition,
  // attempt and the last answer; the time the phase has left (set before
  // each frame's end, -1 open-ended).
  OperatorStatus status;
  std::int64_t phase_left_ns = -1;

 private:
  OperatorConsole* console_;
  std::vector<OperatorAction> actions_;       // this frame's, reused
  std::vector<data::events::OperatorActionEvent> events_;  // their records, reused
  std::deque<io::Signal> signals_;            // not yet handed to the loop
  std::array<std::int64_t, 3> lost_since_{-1, -1, -1};
};

}  // namespace curvlab::harness::runner
