// What the runner does when the OpenXR session changes state: a pure state
// machine, so the lifecycle rules are tested without a runtime.
//
// OpenXR's lifecycle: IDLE → READY (call xrBeginSession, start the frame loop)
// → SYNCHRONIZED → VISIBLE → FOCUSED, and back down; STOPPING (call
// xrEndSession) → IDLE; EXITING (leave); LOSS_PENDING (the runtime lost the
// session, e.g. the headset was unplugged: end it and leave). A trial runs
// only while FOCUSED: in VISIBLE the runtime shows its own overlay and takes
// the controllers, so losing focus pauses the session with a message, and
// regaining it resumes. A STOPPING that is not an exit (the runtime stops
// the session and later makes it READY again: STOPPING → IDLE → READY) pauses
// the same way until FOCUSED comes back.
#pragma once

#include <string>

namespace curvlab::harness::xr {

// The same numbering as XrSessionState, so conversion is a cast checked by a
// test; this header needs no OpenXR include.
enum class SessionState {
  Unknown = 0,
  Idle = 1,
  Ready = 2,
  Synchronized = 3,
  Visible = 4,
  Focused = 5,
  Stopping = 6,
  LossPending = 7,
  Exiting = 8,
};

std::string to_string(SessionState state);

// What the session loop is allowed to do now.
enum class RunMode {
  WaitForRuntime,  // no frame loop yet (IDLE before READY)
  FramesOnly,      // frame loop running, nothing the participant can answer
  Paused,          // frames running, trial paused: the participant lost focus
  Running,         // FOCUSED: trials run, input counts
  Stopped,         // frame loop ended; waiting for IDLE/EXITING
  Exit,            // leave the session loop
};

std::string to_string(RunMode mode);

struct SessionUpdate {
  bool begin_session = false;  // call xrBeginSession now
  bool end_session = false;    // call xrEndSession now
  RunMode mode = RunMode::WaitForRuntime;
  // The trial pauses (READY before the first focus, focus lost, display
  // hidden, the runtime stopping the session) or resumes (FOCUSED after any
  // of them): each pause is followed by at most one resume, and a resume
  // only follows a pause.
  bool pause = false;
  bool resume = false;
  bool lost = false;           // LOSS_PENDING: the session must be recreated
  bool unexpected = false;     // a transition OpenXR's lifecycle does not allow
  std::string message;         // for the experimenter (pause and exit reasons)
};

// Not thread-safe: the session loop owns it and feeds it every
// XrEventDataSessionStateChanged in order.
class SessionStateMachine {
 public:
  SessionUpdate on_state_changed(SessionState next);
  [[nodiscard]] SessionState state() const { return state_; }
  [[nodiscard]] RunMode mode() const { return mode_; }
  // True between xrBeginSession and xrEndSession.
  [[nodiscard]] bool session_running() const { return running_; }

 private:
  SessionState state_ = SessionState::Unknown;
  RunMode mode_ = RunMode::WaitForRuntime;
  bool running_ = false;
  bool was_focused_ = false;
  bool paused_ = false;  // a pause was given and not yet its resume
};

}  // namespace curvlab::harness::xr
