// Where a session's frames go (DESIGN.md §6): the display paces the frame
// loop, says where the eyes are and what they see, draws the scene, and
// keeps what it drew for screenshots and the operator window. Three exist:
// the offscreen display (runner/headless.hpp), the desktop window
// (desktop/desktop.hpp) and the headset (xr/backend.hpp). The session asks
// for poses and responses separately (pose_source.hpp, response_source.hpp);
// the CLI composes the three (station.hpp).
//
// A display that cannot start (no runtime, no window system, no GPU) fails in
// its factory with an Error (result.hpp; kind `device`, or `api` for a call
// that failed) before the runner writes anything. Once running, a failing
// Vulkan or OpenXR call throws DeviceFailure (frame.hpp).
#pragma once

#include "curvlab/harness/data/records.hpp"
#include "curvlab/harness/io/frame.hpp"
#include "curvlab/renderer/frame_stats.hpp"
#include "curvlab/renderer/plan.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::io {

// Provenance the session stores (DESIGN.md §7).
struct DisplayInfo {
  data::Backend backend = data::Backend::headless;  // which of the three displays
  std::string renderer_device;
  std::string renderer_driver;
  double refresh_hz = 90.0;
  // Each eye's image as the display draws it (the window's eye viewport, the
  // OpenXR swapchain, the offscreen target); 0: the protocol's resolution.
  std::uint32_t eye_width_px = 0;
  std::uint32_t eye_height_px = 0;
  // Samples per pixel the renderer draws with (after clamping to the
  // device); 0: nothing is drawn (no GPU).
  std::uint32_t msaa = 0;
};

// What a headset's runtime reported that the session keeps as data: its
// event queue overflowed, its STAGE origin moved, its refresh rate changed.
// Stored as the events of the same names (data_schema/codebook.md).
struct DisplayReport {
  enum class Kind { events_lost, stage_moved, refresh_rate };
  Kind kind = Kind::events_lost;
  std::uint32_t lost_events = 0;  // events_lost: how many the runtime dropped
  // stage_moved: from when (session clock, ns), and the new STAGE origin in
  // the previous one, x y z (m) and quaternion x y z w, where the runtime
  // knew it (pose_valid); kept_lab_frame: the lab frame (and with it the
  // table's calibration) stayed where it was.
  std::int64_t change_ns = 0;
  bool pose_valid = false;
  std::array<double, 7> origin{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0};
  bool kept_lab_frame = false;
  // refresh_rate: the display's rate before and after (Hz); requested: the
  // change was curvlab's (the protocol's [backend] refresh_hz), else the runtime's.
  double from_hz = 0.0;
  double to_hz = 0.0;
  bool requested = false;
};

// Both eyes of a frame as submitted, side by side (left first), RGBA8, rows
// top to bottom.
struct MirrorImage {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::vector<std::uint8_t> rgba;
};

// Copies of the images a display submitted, for the operator window. The
// frame thread only records a GPU copy into a staging buffer in the frame it
// submits, at most once per request; the operator's thread waits for that
// copy and reads it, so the participant's frame loop never waits for it.
// request() and take() are called from one other thread; the display owns
// the mirror, which must not be used after the display is destroyed.
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

class Display {
 public:
  virtual ~Display() = default;
  Display() = default;
  Display(const Display&) = delete;
  Display& operator=(const Display&) = delete;

  [[nodiscard]] virtual DisplayInfo info() const = 0;
  // Every method below may throw DeviceFailure (and nothing else).
  //
  // Waits until the next frame should be prepared (real time) or returns at
  // once (simulated time); nullopt ends the session (window closed, runtime
  // exiting).
  virtual std::optional<FrameTiming> begin_frame() = 0;
  // What the display itself asks of the session this frame (the window was
  // closed, the headset's session lost focus or is exiting).
  virtual Signal poll_signal() { return Signal::none; }
  // Eye offsets and fields of view for this frame (OpenXR views; otherwise
  // from the participant's IPD), as the renderer takes them.
  virtual renderer::StereoRig rig(const FrameTiming& frame, double ipd_m) = 0;
  // Draws (or, when nothing will look at it, only plans) the frame.
  // `draw` false: the runner knows no one needs the pixels (fast headless
  // between onsets); the display may skip the GPU but still returns the
  // plan's counts.
  virtual renderer::FrameStats submit(const renderer::Scene& scene,
                                      const renderer::FrameDescription& frame,
                                      const Overlay& overlay, bool draw) = 0;
  // Writes the last drawn frame as `stem`_left.png / `stem`_right.png (a
  // screenshot, or the stimulus image of a trial's onset); returns the files
  // written. Displays that cannot read their images back return none.
  virtual std::vector<std::string> save_frame(const std::string& stem) {
    (void)stem;
    return {};
  }
  // Copies of the submitted images for the operator window; nullptr when
  // the display offers none (headless; desktop, whose window is on the
  // experimenter's desk).
  virtual FrameMirror* mirror() { return nullptr; }
  // Moves the reports gathered since the last call into `out` (none from
  // displays without a runtime).
  virtual void take_reports(std::vector<DisplayReport>& out) { (void)out; }
};

}  // namespace curvlab::harness::io
