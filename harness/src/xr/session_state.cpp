#include "curvlab/harness/xr/session_state.hpp"

namespace curvlab::harness::xr {
namespace {

// Transitions OpenXR's session lifecycle allows (specification, "Session
// Lifecycle"). LOSS_PENDING may follow any state.
bool allowed(SessionState from, SessionState to) {
  using S = SessionState;
  if (to == S::LossPending) return true;
  switch (from) {
    case S::Unknown: return to == S::Idle;
    case S::Idle: return to == S::Ready || to == S::Exiting;
    case S::Ready: return to == S::Synchronized || to == S::Stopping;
    case S::Synchronized: return to == S::Visible || to == S::Stopping;
    case S::Visible: return to == S::Focused || to == S::Synchronized;
    case S::Focused: return to == S::Visible;
    case S::Stopping: return to == S::Idle;
    case S::LossPending: return to == S::Exiting;
    case S::Exiting: return false;
  }
  return false;
}

}  // namespace

std::string to_string(SessionState state) {
  switch (state) {
    case SessionState::Unknown: return "UNKNOWN";
    case SessionState::Idle: return "IDLE";
    case SessionState::Ready: return "READY";
    case SessionState::Synchronized: return "SYNCHRONIZED";
    case SessionState::Visible: return "VISIBLE";
    case SessionState::Focused: return "FOCUSED";
    case SessionState::Stopping: return "STOPPING";
    case SessionState::LossPending: return "LOSS_PENDING";
    case SessionState::Exiting: return "EXITING";
  }
  return "SessionState(" + std::to_string(static_cast<int>(state)) + ")";
}

std::string to_string(RunMode mode) {
  switch (mode) {
    case RunMode::WaitForRuntime: return "wait-for-runtime";
    case RunMode::FramesOnly: return "frames-only";
    case RunMode::Paused: return "paused";
    case RunMode::Running: return "running";
    case RunMode::Stopped: return "stopped";
    case RunMode::Exit: return "exit";
  }
  return "RunMode(" + std::to_string(static_cast<int>(mode)) + ")";
}

SessionUpdate SessionStateMachine::on_state_changed(SessionState next) {
  SessionUpdate u;
  if (!allowed(state_, next)) {
    // A runtime bug or a missed event; follow the runtime (it owns the
    // session) but let the runner log it.
    u.unexpected = true;
    u.message = "unexpected OpenXR session transition " + to_string(state_) + " → " +
                to_string(next) + "; ";
  }
  const RunMode previous = mode_;
  switch (next) {
    case SessionState::Unknown:
    case SessionState::Idle:
      mode_ = running_ ? mode_ : (state_ == SessionState::Stopping ? RunMode::Stopped
                                                                    : RunMode::WaitForRuntime);
      break;
    case SessionState::Ready:
      u.begin_session = !running_;
      running_ = true;
      mode_ = RunMode::FramesOnly;
      // The first trial waits for input focus: until then the participant
      // may see nothing (SYNCHRONIZED) and cannot answer (VISIBLE).
      if (!was_focused_ && !paused_) {
        u.pause = true;
        paused_ = true;
      }
      break;
    case SessionState::Synchronized:
    case SessionState::Visible:
      if (was_focused_) {
        mode_ = RunMode::Paused;
        if (previous == RunMode::Running)
          u.message += next == SessionState::Visible
                           ? "the headset lost input focus (system menu or another app in "
                             "front); the trial is paused until focus returns"
                           : "the headset display is not visible (headset taken off?); the "
                             "trial is paused until it is back";
      } else {
        mode_ = RunMode::FramesOnly;
      }
      break;
    case SessionState::Focused:
      mode_ = RunMode::Running;
      if (previous == RunMode::Paused) u.message += "focus returned; resuming the trial";
      was_focused_ = true;
      break;
    case SessionState::Stopping:
      u.end_session = running_;
      running_ = false;
      mode_ = RunMode::Stopped;
      u.message += "the OpenXR runtime is stopping the session";
      if (previous == RunMode::Running) u.message += "; the trial is paused until it runs again";
      break;
    case SessionState::LossPending:
      // xrEndSession is valid only in STOPPING (OpenXR 1.0, 10.3.4): a
      // session being lost is left and destroyed, never ended.
      u.end_session = false;
      running_ = false;
      u.lost = true;
      mode_ = RunMode::Exit;
      u.message += "the OpenXR runtime lost the session (headset unplugged or runtime "
                   "stopped); the session is saved and can be resumed";
      break;
    case SessionState::Exiting:
      u.end_session = running_;
      running_ = false;
      mode_ = RunMode::Exit;
      u.message += "the OpenXR runtime asked curvlab to exit; the session is saved and can "
                   "be resumed";
      break;
  }
  // A trial runs only in Running: leaving it for anything but the exit
  // pauses the trial (the frame loop may stop altogether while the runtime
  // has the session stopped), and coming back resumes it.
  if (previous == RunMode::Running && mode_ != RunMode::Running && mode_ != RunMode::Exit) {
    u.pause = true;
    paused_ = true;
  }
  if (mode_ == RunMode::Running && paused_) {
    u.resume = true;
    paused_ = false;
  }
  if (mode_ == RunMode::Exit) paused_ = false;
  state_ = next;
  u.mode = mode_;
  return u;
}

}  // namespace curvlab::harness::xr
