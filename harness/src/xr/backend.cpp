// The headset's parts as one InteractiveDisplay (xr/backend.hpp), for
// programs that drive it without a station.
#include "curvlab/harness/xr/backend.hpp"

#include "curvlab/harness/xr/controllers.hpp"
#include "curvlab/harness/xr/session.hpp"
#include "curvlab/harness/xr/swapchain_display.hpp"
#include "curvlab/harness/xr/tracked_poses.hpp"

#include <utility>

namespace curvlab::harness::xr {

using harness::Error;
using harness::Result;
using harness::io::InteractiveDisplay;

namespace {

// Forwards each seam to its part. Owns the parts; they are destroyed in the
// reverse order of their creation (the display first, the session last).
class Headset final : public InteractiveDisplay {
 public:
  Headset(std::unique_ptr<Session> session, std::unique_ptr<Controllers> controllers,
          std::unique_ptr<TrackedPoses> poses, std::unique_ptr<SwapchainDisplay> display)
      : session_(std::move(session)),
        controllers_(std::move(controllers)),
        poses_(std::move(poses)),
        display_(std::move(display)) {}

  [[nodiscard]] harness::io::DisplayInfo info() const override { return display_->info(); }
  std::optional<harness::io::FrameTiming> begin_frame() override { return display_->begin_frame(); }
  harness::io::Signal poll_signal() override { return display_->poll_signal(); }
  renderer::StereoRig rig(const harness::io::FrameTiming& frame, double ipd_m) override {
    return display_->rig(frame, ipd_m);
  }
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const harness::io::Overlay& overlay, bool draw) override {
    return display_->submit(scene, frame, overlay, draw);
  }
  std::vector<std::string> save_frame(const std::string& stem) override { return display_->save_frame(stem); }
  harness::io::FrameMirror* mirror() override { return display_->mirror(); }
  void take_reports(std::vector<harness::io::DisplayReport>& out) override { display_->take_reports(out); }

  geometry::LabFrame poses(const harness::io::FrameTiming& frame) override { return poses_->poses(frame); }
  [[nodiscard]] harness::io::HeadTracking head_tracking() const override { return poses_->head_tracking(); }
  [[nodiscard]] std::string describe_head_tracking() const override { return poses_->describe_head_tracking(); }
  [[nodiscard]] std::optional<harness::io::Gaze> gaze() const override { return poses_->gaze(); }

  harness::io::Signal poll(std::vector<harness::io::InputEvent>& out) override { return controllers_->poll(out); }
  [[nodiscard]] harness::io::Reach reach() const override { return controllers_->reach(); }

 private:
  std::unique_ptr<Session> session_;
  std::unique_ptr<Controllers> controllers_;
  std::unique_ptr<TrackedPoses> poses_;
  std::unique_ptr<SwapchainDisplay> display_;
};

}  // namespace

Result<std::unique_ptr<InteractiveDisplay>> make_xr_backend(const XrBackendOptions& options) {
  if (options.clock == nullptr)
    return Error{Error::Kind::usage, "the OpenXR backend needs the session clock (XrBackendOptions::clock)"};
  auto session = Session::create({.application_name = options.application_name, .clock = options.clock});
  if (!session) return session.error();
  auto controllers = Controllers::create(*session.value());
  if (!controllers) return controllers.error();
  auto poses = TrackedPoses::create(*session.value(), *controllers.value());
  if (!poses) return poses.error();
  auto display = SwapchainDisplay::create(
      *session.value(), *poses.value(),
      {.mirror = options.mirror, .msaa = options.msaa, .refresh_hz = options.refresh_hz});
  if (!display) return display.error();
  return std::unique_ptr<InteractiveDisplay>(std::make_unique<Headset>(
      std::move(session).value(), std::move(controllers).value(), std::move(poses).value(),
      std::move(display).value()));
}

}  // namespace curvlab::harness::xr
