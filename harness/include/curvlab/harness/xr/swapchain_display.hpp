// The headset as a display (io/display.hpp): the frame loop (xrWaitFrame →
// xrBeginFrame → locate at the predicted display time → render → xrEndFrame)
// into one swapchain per eye, the views it draws with (xrLocateViews, eye
// poses and fields of view that may change from frame to frame), the refresh
// rate it asks the runtime for (refresh_rate.hpp), and the operator window's
// copies of what it submitted.
//
// The scene's head-locked panels go over it as quad layers in VIEW space
// (quad_panels.hpp), drawn by the runtime's compositor.
//
// Every frame the runtime shows ends with a projection layer: a frame the
// runner begins but does not draw submits the last drawn frame's layer again
// (docs/xr.md, "No black refresh"). While the runtime has the session stopped
// it hands the runner frames of its own, paced at the display's period, with
// nothing tracked or submitted.
//
// Owns the swapchains, the renderer and its target and the operator mirror;
// borrows the session and the tracked poses (whose STAGE space its views and
// layers are in), which must outlive it. Its destructor ends a begun frame
// and, where the runtime still runs the session, the session itself. Used on
// the frame thread only (the mirror's request/take excepted); not thread-safe.
#pragma once

#include "curvlab/harness/io/display.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/harness/xr/refresh_rate.hpp"
#include "curvlab/harness/xr/session.hpp"
#include "curvlab/harness/xr/tracked_poses.hpp"

#include <openxr/openxr.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::renderer {
class Renderer;
class ExternalImagesTarget;
struct VulkanFailure;
}  // namespace curvlab::renderer

namespace curvlab::harness::xr {

class EyeSwapchains;
class OperatorMirror;
class QuadPanels;
struct MirrorEye;

struct SwapchainDisplayOptions {
  // Offer copies of the submitted images for the operator window (mirror()).
  bool mirror = false;
  std::optional<std::uint32_t> msaa;  // samples per pixel requested (clamped); nullopt: the device's automatic count
  // The refresh rate to ask the headset for (the protocol's [backend]
  // refresh_hz), where the runtime offers XR_FB_display_refresh_rate and that
  // rate; nullopt: the runtime's rate.
  std::optional<double> refresh_hz;
};

class SwapchainDisplay final : public harness::io::Display, private SessionPart {
 public:
  static harness::Result<std::unique_ptr<SwapchainDisplay>> create(Session& session, TrackedPoses& poses,
                                                                   const SwapchainDisplayOptions& options);
  // Ends a begun frame and the session as far as the runtime still answers;
  // never throws (a lost session or device included).
  ~SwapchainDisplay() override;

  [[nodiscard]] harness::io::DisplayInfo info() const override;
  std::optional<harness::io::FrameTiming> begin_frame() override;
  // Session-state events: pause, resume, quit (and recenter, from a STAGE move).
  harness::io::Signal poll_signal() override { return session_.next_signal(); }
  renderer::StereoRig rig(const harness::io::FrameTiming& frame, double ipd_m) override;
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const harness::io::Overlay& overlay, bool draw) override;
  std::vector<std::string> save_frame(const std::string& stem) override;
  harness::io::FrameMirror* mirror() override;
  void take_reports(std::vector<harness::io::DisplayReport>& out) override { session_.take_reports(out); }

 private:
  SwapchainDisplay(Session& session, TrackedPoses& poses, const SwapchainDisplayOptions& options);
  harness::Result<harness::Done> make_renderer(const SwapchainDisplayOptions& options);
  // What a frame ends with: the projection layer just rendered into the
  // swapchains, the last one again (a frame the runner began but did not
  // draw: the image before it stays up instead of a black refresh), or none.
  enum class FrameLayer { fresh, held, none };
  // xrEndFrame; its result is left to the caller (the frame loop fails on
  // it, teardown ignores it).
  [[nodiscard]] XrResult end_frame(FrameLayer layer);
  // For a frame ended without drawing: the last layer where the runtime
  // shows this frame (shouldRender), none where it does not.
  [[nodiscard]] FrameLayer undrawn() const;
  // Waits for the runtime to run the session: it runs, the runtime has
  // stopped it (the runner's own frames), or the session ends.
  enum class Await { running, stopped, end };
  Await await_running_session();
  void locate_views(XrTime t);
  harness::io::FrameTiming stopped_frame();
  void mark_late(harness::io::FrameTiming& timing);
  void render(const renderer::Scene& scene, const renderer::FrameDescription& frame);
  // This frame's eyes in the head's frame, for the operator's copy.
  [[nodiscard]] std::array<MirrorEye, 2> mirror_eyes() const;
  void leave_session();
  [[noreturn]] void fail(const renderer::VulkanFailure& f);
  // --- refresh-rate negotiation (XR_FB_display_refresh_rate) ---
  void negotiate_refresh_rate();
  // Asks the display for the protocol's refresh rate where it offers it;
  // the rate it then runs at.
  void request_refresh_rate();
  void on_event(const XrEventDataBuffer& event) override;
  void on_refresh_rate_changed(const XrEventDataDisplayRefreshRateChangedFB& e);

  Session& session_;
  TrackedPoses& poses_;
  RefreshRatePolicy refresh_;
  PFN_xrGetDisplayRefreshRateFB get_refresh_ = nullptr;
  PFN_xrEnumerateDisplayRefreshRatesFB enumerate_refresh_ = nullptr;
  PFN_xrRequestDisplayRefreshRateFB request_refresh_ = nullptr;

  std::unique_ptr<EyeSwapchains> swapchains_;
  std::unique_ptr<renderer::Renderer> renderer_;
  std::unique_ptr<renderer::ExternalImagesTarget> target_;
  std::unique_ptr<OperatorMirror> mirror_;
  std::unique_ptr<QuadPanels> panels_;  // null: the panels are drawn into the eye images
  std::vector<const XrCompositionLayerBaseHeader*> layers_;  // the frame's, reused by end_frame

  std::int64_t frame_index_ = 0;
  XrTime last_display_ = 0;  // the previous frame's predicted display time
  std::array<XrView, 2> views_{tagged<XrView>(XR_TYPE_VIEW), tagged<XrView>(XR_TYPE_VIEW)};
  bool views_valid_ = false;
  // The views of the last layer submitted with a fresh image (the pose and
  // field of view its images were rendered for); nullopt before the first.
  std::optional<std::array<XrView, 2>> shown_views_;
};

}  // namespace curvlab::harness::xr
