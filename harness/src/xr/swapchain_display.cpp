// The swapchain display (xr/swapchain_display.hpp). Per frame: xrWaitFrame →
// xrBeginFrame → follow a STAGE move → sync the actions → locate the views
// and the tracked poses at the predicted display time → render into the
// swapchains → xrEndFrame with the projection layer.
#include "curvlab/harness/xr/swapchain_display.hpp"

#include "mirror.hpp"
#include "quad_panels.hpp"
#include "swapchains.hpp"

#include "curvlab/harness/io/frame.hpp"
#include "curvlab/harness/xr/stereo.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/renderer.hpp"
#include "curvlab/renderer/swapchain.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <thread>
#include <utility>

namespace curvlab::harness::xr {

using harness::Done;
using harness::Error;
using harness::Result;
using harness::io::DeviceFailure;
using harness::io::FrameTiming;

SwapchainDisplay::SwapchainDisplay(Session& session, TrackedPoses& poses, const SwapchainDisplayOptions& options)
    : session_(session), poses_(poses), refresh_(options.refresh_hz) {}

Result<std::unique_ptr<SwapchainDisplay>> SwapchainDisplay::create(Session& session, TrackedPoses& poses,
                                                                   const SwapchainDisplayOptions& options) {
  std::unique_ptr<SwapchainDisplay> d(new SwapchainDisplay(session, poses, options));
  d->negotiate_refresh_rate();
  auto swapchains = EyeSwapchains::create(session);
  if (!swapchains) return swapchains.error();
  d->swapchains_ = std::make_unique<EyeSwapchains>(std::move(swapchains).value());
  if (auto r = d->make_renderer(options); !r) return r.error();
  session.join(*d);
  return d;
}

// The renderer, the target that draws into the swapchain images and, when
// asked for, the operator window's mirror.
Result<Done> SwapchainDisplay::make_renderer(const SwapchainDisplayOptions& options) {
  const renderer::Context& c = session_.context();
  try {
    renderer_ = std::make_unique<renderer::Renderer>(c, renderer::RendererOptions{.msaa = options.msaa});
  } catch (const renderer::VulkanFailure& f) {
    return Error{Error::Kind::api, std::string("cannot render for the headset: ") + f.what()};
  } catch (const vk::SystemError& e) {
    return Error{Error::Kind::api, "cannot render for the headset: " + renderer::vk_call_name(e.what()) +
                                       ": " + renderer::vk_result_name(e.code().value())};
  }
  target_ = std::make_unique<renderer::ExternalImagesTarget>(c);
  panels_ = std::make_unique<QuadPanels>(c, swapchains_->format());
  if (options.mirror) {
    const auto format = static_cast<vk::Format>(swapchains_->format());
    const bool bgra = format == vk::Format::eB8G8R8A8Srgb || format == vk::Format::eB8G8R8A8Unorm;
    const bool linear = format == vk::Format::eR8G8B8A8Unorm || format == vk::Format::eB8G8R8A8Unorm;
    mirror_ = std::make_unique<OperatorMirror>(c, vk::Extent2D{swapchains_->width(), swapchains_->height()}, bgra,
                                               linear);
  }
  return Done{};
}

SwapchainDisplay::~SwapchainDisplay() {
  // A frame the runner began but never submitted must still end; after a
  // failure the runtime may answer with errors, which nothing can act on
  // here (the failure was reported where it happened).
  try {
    if (session_.frame_begun()) (void)end_frame(undrawn());
    leave_session();
  } catch (...) {
    // poll_events() throws for a runtime that fails while we leave: leave anyway.
  }
  if (renderer_) renderer_->wait_idle_noexcept();
  session_.leave(*this);
}

// The runner is done with a session the runtime still runs: ask the runtime
// to end it (xrRequestExitSession), keep frames flowing without layers while
// it steps down to STOPPING, and end it there, so the runtime sees an
// orderly exit rather than a running session destroyed. Bounded to 2 s.
void SwapchainDisplay::leave_session() {
  if (session_.failed() || !session_.running()) return;
  if (!session_.request_exit()) return;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (std::chrono::steady_clock::now() < deadline) {
    if (!session_.poll_events() || !session_.running()) break;
    if (XR_FAILED(session_.wait_frame())) break;
    if (XR_FAILED(session_.begin_frame())) break;
    if (XR_FAILED(end_frame(undrawn()))) break;
  }
}

harness::io::DisplayInfo SwapchainDisplay::info() const {
  // Once frames run, the runtime's frame period; before, the display's
  // reported rate (XR_FB_display_refresh_rate) or 90 Hz, the common rate.
  const double period = static_cast<double>(session_.frame().predictedDisplayPeriod);
  const renderer::Context& c = session_.context();
  return {data::Backend::xr, c.device_name(), c.driver_info(), period > 0.0 ? 1e9 / period : refresh_.current_hz(),
          swapchains_->width(), swapchains_->height(), renderer_ ? renderer_->msaa() : 0};
}

harness::io::FrameMirror* SwapchainDisplay::mirror() { return mirror_.get(); }

void SwapchainDisplay::fail(const renderer::VulkanFailure& f) {
  session_.mark_failed();
  throw DeviceFailure(f.call, renderer::vk_result_name(f.result), "rendering for the headset");
}

SwapchainDisplay::FrameLayer SwapchainDisplay::undrawn() const {
  return session_.frame().shouldRender == XR_TRUE ? FrameLayer::held : FrameLayer::none;
}

// A held layer names the same swapchains with the views their images were
// rendered for: the compositor shows each swapchain's last released image
// (OpenXR 1.0 §10.5, "Swapchain Image Management"), reprojected to the head
// of now, so the participant keeps seeing the last frame, world-locked.
XrResult SwapchainDisplay::end_frame(FrameLayer what) {
  if (what == FrameLayer::fresh) shown_views_ = views_;
  if (what == FrameLayer::held && !shown_views_) what = FrameLayer::none;
  const std::array<XrView, 2>& from = what == FrameLayer::fresh || !shown_views_ ? views_ : *shown_views_;
  std::array<XrCompositionLayerProjectionView, 2> views{};
  for (std::size_t i = 0; i < 2; ++i) {
    views[i] = tagged<XrCompositionLayerProjectionView>(XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW);
    views[i].pose = from[i].pose;
    views[i].fov = from[i].fov;
    views[i].subImage = swapchains_->sub_image(i);
  }
  auto layer = tagged<XrCompositionLayerProjection>(XR_TYPE_COMPOSITION_LAYER_PROJECTION);
  layer.space = poses_.stage();
  layer.viewCount = 2;
  layer.views = views.data();
  // The head-locked panels follow as quad layers, over the projection (a
  // held frame keeps the last ones: their swapchains keep their images).
  layers_.clear();  // its capacity kept: no allocation per frame
  if (what != FrameLayer::none) {
    layers_.push_back(reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer));
    if (panels_)
      for (const XrCompositionLayerQuad& quad : panels_->layers())
        layers_.push_back(reinterpret_cast<const XrCompositionLayerBaseHeader*>(&quad));
  }
  return session_.end_frame(layers_);
}

// Until the runtime makes the session READY there is no frame loop; wait
// for its events (the runner shows nothing meanwhile).
SwapchainDisplay::Await SwapchainDisplay::await_running_session() {
  for (;;) {
    if (!session_.poll_events()) return Await::end;
    if (session_.running()) return Await::running;
    if (session_.mode() == RunMode::Stopped) return Await::stopped;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

std::optional<FrameTiming> SwapchainDisplay::begin_frame() {
  // Once the runtime has stopped a session that ran (STOPPING, then IDLE
  // until it is READY again), the runner keeps its own loop, paused, on
  // frames without OpenXR.
  switch (await_running_session()) {
    case Await::end: return std::nullopt;
    case Await::stopped: return stopped_frame();
    case Await::running: break;
  }
  // A frame the runner began but did not draw (it paused, aborted or quit
  // there) ends with the last image held.
  if (session_.frame_begun())
    if (const XrResult r = end_frame(undrawn()); XR_FAILED(r)) session_.fail(r, "xrEndFrame");
  if (const XrResult r = session_.wait_frame(); XR_FAILED(r)) session_.fail(r, "xrWaitFrame");
  const std::int64_t now = session_.now_ns();
  if (const XrResult r = session_.begin_frame(); XR_FAILED(r)) session_.fail(r, "xrBeginFrame");
  const XrTime t = session_.frame().predictedDisplayTime;
  poses_.follow_stage_change(t);
  session_.frame_began(now);
  // Views and devices where they will be when this frame is seen.
  locate_views(t);
  poses_.locate(t);

  FrameTiming timing;
  timing.index = frame_index_++;
  timing.now_ns = now;
  timing.predicted_display_ns = session_.to_session_ns(t);
  timing.period_ns = session_.frame().predictedDisplayPeriod;
  mark_late(timing);
  return timing;
}

void SwapchainDisplay::locate_views(XrTime t) {
  auto locate_info = tagged<XrViewLocateInfo>(XR_TYPE_VIEW_LOCATE_INFO);
  locate_info.viewConfigurationType = kViewConfig;
  locate_info.displayTime = t;
  locate_info.space = poses_.stage();
  auto view_state = tagged<XrViewState>(XR_TYPE_VIEW_STATE);
  std::uint32_t n = 0;
  views_ = {tagged<XrView>(XR_TYPE_VIEW), tagged<XrView>(XR_TYPE_VIEW)};
  const XrResult located = xrLocateViews(session_.handle(), &locate_info, &view_state, 2, &n, views_.data());
  if (fatal(located)) session_.fail(located, "xrLocateViews");
  views_valid_ = XR_SUCCEEDED(located) && n == 2 &&
                 (view_state.viewStateFlags & XR_VIEW_STATE_POSITION_VALID_BIT) != 0 &&
                 (view_state.viewStateFlags & XR_VIEW_STATE_ORIENTATION_VALID_BIT) != 0;
}

// A frame of the runner's loop while the runtime has the session stopped:
// paced at the display's period, nothing located (the head and hands are
// untracked, the eyes from the IPD), nothing submitted (submit() finds no
// begun frame), and late, since nothing is shown. The pause it carries
// (SessionUpdate::pause) stops the trial's clock at the STOPPING, not when
// the runtime makes the session READY again; the runner stays free to quit.
FrameTiming SwapchainDisplay::stopped_frame() {
  const XrDuration display_period = session_.frame().predictedDisplayPeriod;
  const std::int64_t period =
      display_period > 0 ? display_period : static_cast<std::int64_t>(1e9 / refresh_.current_hz());
  std::this_thread::sleep_for(std::chrono::nanoseconds(period));
  views_valid_ = false;
  poses_.lose_tracking();
  last_display_ = 0;  // the display times after the restart start afresh
  FrameTiming timing;
  timing.index = frame_index_++;
  timing.now_ns = session_.now_ns();
  timing.predicted_display_ns = timing.now_ns + period;
  timing.period_ns = period;
  timing.late = true;
  return timing;
}

// A frame is late when its display time skipped refreshes after the
// previous frame's (the loop missed them: the previous image stayed up
// longer) or the runtime said not to render it (it is not shown).
void SwapchainDisplay::mark_late(FrameTiming& timing) {
  const XrTime t = session_.frame().predictedDisplayTime;
  const XrDuration period = session_.frame().predictedDisplayPeriod;
  if (last_display_ != 0 && period > 0 && t > last_display_) {
    const double periods = static_cast<double>(t - last_display_) / static_cast<double>(period);
    timing.skipped_periods = static_cast<std::int32_t>(std::max<std::int64_t>(0, std::llround(periods) - 1));
  }
  last_display_ = t;
  timing.late = timing.skipped_periods > 0 || session_.frame().shouldRender != XR_TRUE;
}

renderer::StereoRig SwapchainDisplay::rig(const FrameTiming& frame, double ipd_m) {
  (void)frame;
  if (!views_valid_) return renderer::StereoRig::from_ipd(ipd_m, renderer::Fov{});
  return rig_from_views(poses_.head(), {to_stage_pose(views_[0].pose), to_stage_pose(views_[1].pose)},
                        {to_fov(views_[0].fov), to_fov(views_[1].fov)});
}

// Each eye of this frame in the head's frame (VIEW), with its field of view.
std::array<MirrorEye, 2> SwapchainDisplay::mirror_eyes() const {
  const StagePose& head = poses_.head();
  const glm::dquat from_stage = glm::conjugate(head.orientation);
  std::array<MirrorEye, 2> eyes{};
  for (std::size_t i = 0; i < 2; ++i) {
    const StagePose eye = to_stage_pose(views_[i].pose);
    eyes[i].in_head = {from_stage * (eye.position_m - head.position_m), from_stage * eye.orientation};
    eyes[i].view = tangents(to_fov(views_[i].fov));
  }
  return eyes;
}

renderer::FrameStats SwapchainDisplay::submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                                              const harness::io::Overlay& overlay, bool draw) {
  // The headset shows every frame: `draw` cannot skip one.
  (void)overlay;
  (void)draw;
  renderer::FrameStats stats;
  if (!session_.frame_begun()) return stats;
  const bool render = session_.frame().shouldRender == XR_TRUE && views_valid_;
  if (!render) {
    if (const XrResult r = end_frame(undrawn()); XR_FAILED(r)) session_.fail(r, "xrEndFrame");
    return stats;
  }
  const std::array<vk::Image, 2> images = swapchains_->acquire(session_);
  for (std::size_t i = 0; i < 2; ++i)
    target_->set_image(i == 0 ? renderer::Eye::left : renderer::Eye::right,
                       {images[i], static_cast<vk::Format>(swapchains_->format()),
                        vk::Extent2D{swapchains_->width(i), swapchains_->height(i)},
                        vk::ImageLayout::eColorAttachmentOptimal});
  renderer::FrameDescription f = frame;
  f.width_px = swapchains_->width();
  f.height_px = swapchains_->height();
  try {
    // The panels as quad layers; where the runtime refuses their
    // swapchains, drawn into the eye images from then on.
    if (panels_ && !panels_->update(session_, poses_.view(), scene)) panels_.reset();
    f.draw_head_locked = panels_ == nullptr;
    // render() submits before returning, as xrReleaseSwapchainImage requires.
    stats = renderer_->render(scene, f, *target_);
    // The operator window's copy, while the images are still acquired.
    if (mirror_ && mirror_->wanted()) mirror_->copy(images, scene, !f.draw_head_locked, mirror_eyes());
  } catch (const renderer::VulkanFailure& e) {
    swapchains_->release();
    fail(e);
  } catch (const vk::SystemError& e) {
    swapchains_->release();
    fail(renderer::VulkanFailure(renderer::vk_call_name(e.what()), e.code().value()));
  }
  swapchains_->release();
  if (const XrResult r = end_frame(FrameLayer::fresh); XR_FAILED(r)) session_.fail(r, "xrEndFrame");
  return stats;
}

std::vector<std::string> SwapchainDisplay::save_frame(const std::string& stem) {
  std::vector<std::string> written;
  try {
    for (const auto eye : {renderer::Eye::left, renderer::Eye::right}) {
      const auto image = target_->read_eye(eye);
      if (!image) continue;
      const std::string path = stem + (eye == renderer::Eye::left ? "_left.png" : "_right.png");
      const auto saved = renderer::write_png(path, *image);
      if (const auto* err = std::get_if<renderer::RenderError>(&saved)) {
        std::cerr << "curvlab: xr: frame not saved: " << err->message << '\n';
        continue;
      }
      written.push_back(path);
    }
  } catch (const renderer::VulkanFailure& e) {
    fail(e);
  } catch (const vk::SystemError& e) {
    fail(renderer::VulkanFailure(renderer::vk_call_name(e.what()), e.code().value()));
  }
  return written;
}

// A lab fixes the display rate for its timing (refresh_rate.hpp): where the
// runtime offers XR_FB_display_refresh_rate, the display's rate before the
// first frame (the session's provenance), and the protocol's asked for.
void SwapchainDisplay::negotiate_refresh_rate() {
  const XrInstance xr = session_.instance().handle();
  if (!session_.refresh_rate_extension() || XR_FAILED(load(xr, "xrGetDisplayRefreshRateFB", get_refresh_)) ||
      XR_FAILED(load(xr, "xrEnumerateDisplayRefreshRatesFB", enumerate_refresh_)) ||
      XR_FAILED(load(xr, "xrRequestDisplayRefreshRateFB", request_refresh_))) {
    get_refresh_ = nullptr;
    request_refresh_ = nullptr;
    return;
  }
  float hz = 0.0f;
  if (XR_SUCCEEDED(get_refresh_(session_.handle(), &hz)) && hz > 0.0f)
    refresh_.display_runs_at(static_cast<double>(hz));
  request_refresh_rate();
}

void SwapchainDisplay::request_refresh_rate() {
  if (request_refresh_ == nullptr || !refresh_.should_request()) return;
  const XrSession session = session_.handle();
  std::uint32_t n = 0;
  std::vector<float> rates;
  if (XR_SUCCEEDED(enumerate_refresh_(session, 0, &n, nullptr))) {
    rates.resize(n);
    if (XR_FAILED(enumerate_refresh_(session, n, &n, rates.data()))) rates.clear();
  }
  const auto offered = refresh_.choose(rates);
  if (!offered) {
    std::cerr << "curvlab: xr: " << refresh_.not_offered_message(rates) << '\n';
    return;
  }
  if (const XrResult r = request_refresh_(session, *offered); XR_FAILED(r)) {
    std::cerr << "curvlab: xr: " << failure_of(r, "xrRequestDisplayRefreshRateFB").message << '\n';
    return;
  }
  float now = 0.0f;
  if (XR_FAILED(get_refresh_(session, &now)) || now <= 0.0f) now = *offered;
  harness::io::DisplayReport report;
  report.kind = harness::io::DisplayReport::Kind::refresh_rate;
  report.from_hz = refresh_.current_hz();
  report.to_hz = now;
  report.requested = true;
  session_.report(report);
  refresh_.requested(*offered, now);
}

void SwapchainDisplay::on_event(const XrEventDataBuffer& event) {
  if (event.type == XR_TYPE_EVENT_DATA_DISPLAY_REFRESH_RATE_CHANGED_FB)
    on_refresh_rate_changed(*reinterpret_cast<const XrEventDataDisplayRefreshRateChangedFB*>(&event));
}

// The display's rate changed. Frames follow the runtime's period at once
// (each frame's is stored); a change the lab did not ask for is said,
// recorded, and the protocol's rate asked for again.
void SwapchainDisplay::on_refresh_rate_changed(const XrEventDataDisplayRefreshRateChangedFB& e) {
  if (refresh_.on_change(e.toDisplayRefreshRate)) return;  // the change curvlab asked for, already recorded
  std::cerr << "curvlab: xr: the headset changed its refresh rate from " << e.fromDisplayRefreshRate << " to "
            << e.toDisplayRefreshRate << " Hz\n";
  harness::io::DisplayReport report;
  report.kind = harness::io::DisplayReport::Kind::refresh_rate;
  report.from_hz = e.fromDisplayRefreshRate;
  report.to_hz = static_cast<double>(e.toDisplayRefreshRate);
  session_.report(report);
  request_refresh_rate();
}

}  // namespace curvlab::harness::xr
