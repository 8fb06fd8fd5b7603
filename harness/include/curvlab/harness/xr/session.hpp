// The headset's OpenXR session (DESIGN.md §1, hello_xr's program): the
// XrInstance and XrSession handles with the Vulkan device the runtime made
// for them, the session-state machine (session_state.hpp) fed with the
// runtime's events, the signals those give the runner (pause, resume, quit,
// recenter), the reports kept as data, the frame calls and action sync every
// part shares, and the conversion of the runtime's XrTime to the session
// clock. The other parts borrow it: the swapchain display
// (swapchain_display.hpp), the tracked poses (tracked_poses.hpp) and the
// controllers (controllers.hpp), composed by the CLI's station
// (harness/src/cli/station.cpp) and destroyed before it.
//
// Lifecycle (OpenXR 1.0 §9–10): instance → system → Vulkan made by the runtime
// (XR_KHR_vulkan_enable2) → xrCreateSession; the display begins the session
// when READY comes and the session ends it at STOPPING.
//
// Owns, in order of destruction: the XrSession, the Vulkan context, the
// XrInstance. Used on the frame thread only; not thread-safe.
#pragma once

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/io/display.hpp"
#include "curvlab/harness/io/phase.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/harness/xr/gaze.hpp"
#include "curvlab/harness/xr/handle.hpp"
#include "curvlab/harness/xr/instance.hpp"
#include "curvlab/harness/xr/session_state.hpp"
#include "curvlab/harness/xr/stereo.hpp"

#include <openxr/openxr.h>

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace curvlab::renderer {
class Context;
}

namespace curvlab::harness::xr {

inline constexpr XrViewConfigurationType kViewConfig = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
inline constexpr XrPosef kIdentityPose{{0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}};

struct SessionOptions {
  std::string application_name = "curvlab";
  const harness::io::Clock* clock = nullptr;  // the session's; required
};

// A part of the headset that hears the runtime's events other than session
// states (the session handles those) and the end of input focus. Joins the
// session for its whole life (Session::join in its factory, leave in its
// destructor).
class SessionPart {
 public:
  // Every event the session does not handle itself, in order.
  virtual void on_event(const XrEventDataBuffer& event) { (void)event; }
  // The session left FOCUSED (the actions are inactive until it returns).
  virtual void on_focus_lost() {}

 protected:
  SessionPart() = default;
  ~SessionPart() = default;
  SessionPart(const SessionPart&) = default;
  SessionPart& operator=(const SessionPart&) = default;
};

class Session {
 public:
  // No runtime or no headset: an Error of kind `device` naming the OpenXR
  // result and what to install; another failing call: `api`.
  static harness::Result<std::unique_ptr<Session>> create(const SessionOptions& options);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  [[nodiscard]] const Instance& instance() const { return instance_; }
  [[nodiscard]] XrSystemId system() const { return system_; }
  [[nodiscard]] XrSession handle() const { return session_.get(); }
  // The Vulkan device the runtime made; it outlives every part.
  [[nodiscard]] const renderer::Context& context() const { return *context_; }
  // Whether XR_FB_display_refresh_rate is enabled.
  [[nodiscard]] bool refresh_rate_extension() const { return refresh_extension_; }
  // The eye-tracking extensions enabled (xr/gaze.hpp).
  [[nodiscard]] GazeExtensions gaze_extensions() const { return gaze_; }

  void join(SessionPart& part);
  void leave(SessionPart& part);

  // --- states and events ---
  // Drains the event queue; false when the session must end.
  bool poll_events();
  [[nodiscard]] RunMode mode() const { return state_.mode(); }
  // Between xrBeginSession and xrEndSession.
  [[nodiscard]] bool running() const { return state_.session_running(); }
  // When the session last became FOCUSED (the runtime's event time).
  [[nodiscard]] XrTime focused_at() const { return focused_at_; }
  // What the session asks of the runner next (Display::poll_signal): polls
  // the events first; quit outranks everything still queued.
  harness::io::Signal next_signal();
  // A part's own signal for the runner (a STAGE move without a pose: recenter).
  void signal(harness::io::Signal s) { signals_.push_back(s); }
  // Kept for the session's data until taken (Display::take_reports).
  void report(const harness::io::DisplayReport& r) { reports_.push_back(r); }
  void take_reports(std::vector<harness::io::DisplayReport>& out);
  // Asks the runtime to end a running session (xrRequestExitSession); the
  // step-down that follows is expected, without the pause and exit messages
  // meant for a runtime-initiated stop. false: the request failed (said).
  bool request_exit();

  // --- failures ---
  [[nodiscard]] bool failed() const { return failed_; }
  // Marks the session failed (nothing more is asked of the runtime but its
  // teardown) and throws DeviceFailure naming the call.
  [[noreturn]] void fail(XrResult r, const char* call);
  void mark_failed() { failed_ = true; }

  // --- the frame loop's calls (driven by the swapchain display) ---
  // xrWaitFrame into frame(); xrBeginFrame; xrEndFrame at frame()'s display
  // time with `layers`, back to front (none: nothing shown). The results are
  // the caller's.
  [[nodiscard]] XrResult wait_frame();
  [[nodiscard]] XrResult begin_frame();
  [[nodiscard]] XrResult end_frame(const std::vector<const XrCompositionLayerBaseHeader*>& layers);
  [[nodiscard]] const XrFrameState& frame() const { return frame_state_; }
  // A frame was begun and not yet ended.
  [[nodiscard]] bool frame_begun() const { return frame_begun_; }
  // After xrBeginFrame, at `now_ns` (the session clock when xrWaitFrame
  // returned): anchors the clock map where the runtime converts no times,
  // and syncs the actions while FOCUSED.
  void frame_began(std::int64_t now_ns);

  // --- actions ---
  // xrAttachSessionActionSets, once, with every set; they are synced together.
  harness::Result<harness::Done> attach(const std::vector<XrActionSet>& sets);
  // xrSyncActions for this frame (a failure other than a lost session is
  // said; the states then read inactive).
  void sync_actions();
  // xrSyncActions was called in this frame while FOCUSED.
  [[nodiscard]] bool synced() const { return synced_; }

  // --- time ---
  // The runtime's time on the session clock.
  std::int64_t to_session_ns(XrTime t);
  [[nodiscard]] std::int64_t now_ns() const { return clock_->now_ns(); }

 private:
  Session(Instance instance, const harness::io::Clock& clock);
  struct Extensions;
  harness::Result<harness::Done> open(const Extensions& offered);
  void on_state(SessionState next);
  void on_events_lost(const XrEventDataEventsLost& e);
  std::int64_t monotonic_to_session();

  Instance instance_;
  const harness::io::Clock* clock_;
  XrSystemId system_ = XR_NULL_SYSTEM_ID;
  std::unique_ptr<renderer::Context> context_;
  SessionHandle session_;
  bool refresh_extension_ = false;
  GazeExtensions gaze_;
  std::vector<SessionPart*> parts_;
  std::vector<XrActiveActionSet> active_sets_;  // every attached set, synced together

  SessionStateMachine state_;
  std::deque<harness::io::Signal> signals_;
  std::vector<harness::io::DisplayReport> reports_;
  bool failed_ = false;
  bool leaving_ = false;       // request_exit asked the runtime to end the session
  bool focus_wait_ = false;    // READY came, the first focus not yet: a pause held back
  XrTime focused_at_ = 0;

  XrFrameState frame_state_ = tagged<XrFrameState>(XR_TYPE_FRAME_STATE);
  bool frame_begun_ = false;
  std::int64_t frames_ended_ = 0;  // xrEndFrame calls
  bool synced_ = false;

  // Time conversion: XR_KHR_convert_timespec_time (or on Windows
  // XR_KHR_win32_convert_performance_counter_time) where offered, else the
  // clock map anchored at the first frame (stereo.hpp). Kept as the loader's
  // untyped pointers; session.cpp casts them to their platform types.
  PFN_xrVoidFunction to_timespec_ = nullptr;
#ifdef _WIN32
  PFN_xrVoidFunction to_counter_ = nullptr;
#endif
  XrClockMap clock_map_;
  std::int64_t offset_ns_ = 0;      // monotonic_to_session's estimate
  std::int64_t offset_at_ns_ = -1;  // when it was made (CLOCK_MONOTONIC); -1 none
};

}  // namespace curvlab::harness::xr
