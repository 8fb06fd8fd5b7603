// Where a session's frames come from and go to (DESIGN.md §6). The session
// runner (session.hpp) drives one Backend frame by frame:
//
//   while (auto frame = backend.begin_frame()) {      // paced by the backend
//     poses  = backend.poses(*frame);                   // lab poses at the predicted time
//     backend.poll_input(events);                       // keys, buttons, controllers
//     ... state machine, tracking, scene ...
//     backend.submit(scene, description, overlay);      // draw (or plan only)
//   }
//
// Three implementations: headless (offscreen renderer, generated or replayed
// poses, simulated observer; headless.hpp), desktop (GLFW window, keyboard
// and mouse move the head; desktop.hpp) and xr (OpenXR; xr/backend.hpp).
// A backend that cannot start (no runtime, no display, no GPU) fails in its
// factory with an Error (result.hpp; kind `device`, or `api` for a call that
// failed) before the runner writes anything. Once running, a failing Vulkan
// or OpenXR call throws BackendFailure (below) from whichever method met it.
//
// This header stays free of Vulkan: it needs the frame's plain structs
// (plan.hpp, frame_stats.hpp), not the renderer.
#pragma once

#include "curvlab/geometry/tracking.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/harness/runner/phase.hpp"
#include "curvlab/renderer/frame_stats.hpp"
#include "curvlab/renderer/plan.hpp"

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace curvlab::harness::runner {

// A Vulkan or OpenXR call that failed while a session runs: a lost device, a
// lost session, a runtime that failed. It is the only exception a backend
// method throws (STYLE.md: exceptions for what the frame loop cannot go on
// from, caught by the session runner). The message names the call and its
// result as the C APIs spell them — "vkQueueSubmit: VK_ERROR_DEVICE_LOST",
// "xrWaitFrame: XR_ERROR_SESSION_LOST" — followed by any detail. The runner
// ends the session `interrupted` (completed trials are already committed),
// and it can be resumed. A backend that threw is not used again, only
// destroyed; destructors never throw.
struct BackendFailure : std::runtime_error {
  BackendFailure(std::string call_name, std::string result_name, const std::string& detail = {})
      : std::runtime_error(call_name + ": " + result_name + (detail.empty() ? "" : " (" + detail + ")")),
        call(std::move(call_name)),
        result(std::move(result_name)) {}

  std::string call;    // "vkQueueSubmit", "xrWaitFrame"
  std::string result;  // "VK_ERROR_DEVICE_LOST", "XR_ERROR_SESSION_LOST"
};

// Provenance the session stores (DESIGN.md §7).
struct BackendInfo {
  std::string name;  // "headless", "desktop" or "xr"
  std::string renderer_device;
  std::string renderer_driver;
  double refresh_hz = 90.0;
  // Each eye's image as the backend draws it (the window's eye viewport, the
  // OpenXR swapchain, the offscreen target); 0: the protocol's resolution.
  std::uint32_t eye_width_px = 0;
  std::uint32_t eye_height_px = 0;
  // Samples per pixel the renderer draws with (after clamping to the
  // device); 0: nothing is drawn (no GPU).
  std::uint32_t msaa = 0;
};

struct FrameTiming {
  std::int64_t index = 0;              // frames since the backend started
  std::int64_t now_ns = 0;             // session clock when the frame began
  std::int64_t predicted_display_ns = 0;  // when this frame's image will be shown
  std::int64_t period_ns = 11'111'111;
  // The runtime's verdict on this frame (OpenXR): its display time skipped
  // `skipped_periods` refreshes after the previous frame's (the loop missed
  // them), or it is not shown at all (shouldRender false). Late frames are
  // counted per trial (docs/xr.md, "Frame timing").
  std::int32_t skipped_periods = 0;
  bool late = false;
};

// One discrete input: a key (GLFW-style lower-case names: "1", "left",
// "space", "escape"), a HID or controller button (names from the mapping
// file or the XR action set), or a simulated observer's key press. The runner
// maps names to responses through the protocol's judgement options.
struct InputEvent {
  std::int64_t t_ns = 0;  // session clock
  std::string name;
  std::string device;  // "keyboard", "hid:<name>", "xr:left", "observer", …
  bool pressed = true;
};

// What the runner shows besides the scene (for desktop windows and logs).
// Instruction pages and breaks advance on the key "space" or "enter", or a
// button named "continue"; responses come from the keys and buttons of the
// judgement's options.
struct Overlay {
  Phase phase = Phase::iti;
  std::string text;   // trial information line (block, trial, condition)
  bool waiting_for_input = false;  // instructions, response window, break
};

// Both eyes of a frame as submitted to the display, side by side (left
// first), RGBA8, rows top to bottom.
struct MirrorImage {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<std::uint8_t> rgba;
};

// Copies of the images a backend submitted, for the operator window. The
// frame thread only records a GPU copy into a staging buffer in the frame it
// submits, at most once per request; the operator's thread waits for that
// copy and reads it, so the participant's frame loop never waits for it.
// request() and take() are called from one other thread; the backend owns
// the mirror, which must not be used after the backend is destroyed.
class FrameMirror {
 public:
  virtual ~FrameMirror() = default;
  FrameMirror() = default;
  FrameMirror(const FrameMirror&) = delete;
  FrameMirror& operator=(const FrameMirror&) = delete;
  // Asks for a copy of the next frame submitted (no-op while one is pending).
  virtual void request() = 0;
  // The requested copy, once the GPU has made it; false: not ready yet.
  virtual bool take(MirrorImage& out) = 0;
};

class Backend {
 public:
  virtual ~Backend() = default;
  Backend() = default;
  Backend(const Backend&) = delete;
  Backend& operator=(const Backend&) = delete;

  [[nodiscard]] virtual BackendInfo info() const = 0;
  // Every method below may throw BackendFailure (and nothing else).
  //
  // Waits until the next frame should be prepared (real time) or returns at
  // once (fast headless); nullopt ends the session (window closed, runtime
  // exiting, replay finished).
  virtual std::optional<FrameTiming> begin_frame() = 0;
  // Lab poses of head and hands for the frame's predicted display time.
  virtual geometry::LabFrame poses(const FrameTiming& frame) = 0;
  // Appends inputs that arrived since the last call; returns a signal.
  virtual BackendSignal poll_input(std::vector<InputEvent>& out) = 0;
  // Eye offsets and fields of view for this frame (OpenXR views; otherwise
  // from the participant's IPD), as the renderer takes them.
  virtual renderer::StereoRig rig(const FrameTiming& frame, double ipd_m) = 0;
  // Draws (or, when nothing will look at it, only plans) the frame.
  // `draw` false: the runner knows no one needs the pixels (fast headless
  // between onsets); the backend may skip the GPU but still returns the plan's counts.
  virtual renderer::FrameStats submit(const renderer::Scene& scene,
                                      const renderer::FrameDescription& frame,
                                      const Overlay& overlay, bool draw) = 0;
  // Writes the last drawn frame as `stem`_left.png / `stem`_right.png (a
  // screenshot, or the stimulus image of a trial's onset); returns the files
  // written. Backends that cannot read their images back return none.
  virtual std::vector<std::string> save_frame(const std::string& stem) {
    (void)stem;
    return {};
  }
  // Copies of the submitted images for the operator window; nullptr when
  // the backend offers none (headless, desktop: the participant's window is
  // on the same desk).
  virtual FrameMirror* mirror() { return nullptr; }
};

}  // namespace curvlab::harness::runner
