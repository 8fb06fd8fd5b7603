#include "curvlab/harness/render_result.hpp"
#include "curvlab/harness/runner/headless.hpp"

#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/renderer.hpp"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <thread>

namespace curvlab::harness::runner {

using geometry::LabFrame;
using geometry::Vec3;

LabFrame standing_pose(const geometry::PhysicalTableFit& table, double eye_height_m,
                       std::int64_t t_ns) {
  // In front of edge 0 (the table's +z side), 0.35 m from the edge, facing
  // the centre and looking 25° down; a slow sway of about a centimetre (as a
  // standing person makes) so tracking and rendering see real motion.
  const double t = static_cast<double>(t_ns) * 1e-9;
  const double c = std::cos(table.yaw_rad);
  const double s = std::sin(table.yaw_rad);
  auto lab = [&](double x, double y, double z) {  // table frame → lab
    return Vec3(table.centre_m.x + c * x + s * z, y, table.centre_m.y - s * x + c * z);
  };
  const double back = table.edge_m / 2.0 + 0.35;
  const double sway_x = 0.008 * std::sin(2.0 * std::numbers::pi * 0.23 * t);
  const double sway_z = 0.006 * std::sin(2.0 * std::numbers::pi * 0.17 * t + 1.0);
  LabFrame f;
  auto& head = f[geometry::Device::head];
  head.position_m = lab(sway_x, eye_height_m, back + sway_z);
  const geometry::Quat yaw = glm::angleAxis(table.yaw_rad, Vec3(0.0, 1.0, 0.0));
  const geometry::Quat pitch = glm::angleAxis(-25.0 * std::numbers::pi / 180.0, Vec3(1.0, 0.0, 0.0));
  head.orientation = yaw * pitch;
  for (auto [device, side] : {std::pair{geometry::Device::left_hand, -1.0},
                              std::pair{geometry::Device::right_hand, 1.0}}) {
    auto& hand = f[device];
    hand.position_m = lab(side * 0.25, table.height_m + 0.03, table.edge_m / 2.0 + 0.02);
    hand.orientation = yaw;
  }
  return f;
}

struct HeadlessDisplay::Impl {
  HeadlessOptions options;
  SimulatedClock sim_clock;
  io::SteadyClock steady;
  std::int64_t period_ns = 0;
  std::int64_t index = 0;
  std::int64_t first_ns = 0;
  std::optional<renderer::Context> ctx;
  std::optional<renderer::Renderer> renderer;
  std::optional<renderer::OffscreenTarget> target;
  bool drawn = false;

  explicit Impl(const HeadlessOptions& o) : options(o), sim_clock(o.start_ns) {}
  const io::Clock& clock() const {
    if (options.pace == Pace::fast) return sim_clock;
    return steady;
  }
};

Result<std::unique_ptr<HeadlessDisplay>> HeadlessDisplay::create(const HeadlessOptions& options) {
  if (!(options.refresh_hz >= 1.0 && options.refresh_hz <= 1000.0))
    return Error{Error::Kind::usage, "headless: refresh rate must lie in [1, 1000] Hz"};
  auto impl = std::make_unique<Impl>(options);
  impl->period_ns = static_cast<std::int64_t>(std::llround(1e9 / options.refresh_hz));
  if (!options.no_gpu) {
    auto created = renderer::Context::create(
        {.device = options.software ? renderer::DeviceChoice::software : renderer::DeviceChoice::automatic,
         .validation = false});
    auto made = from_renderer(std::move(created), "headless: cannot start Vulkan: ");
    if (!made) return made.error();
    impl->ctx.emplace(std::move(made).value());
    try {
      impl->renderer.emplace(*impl->ctx, renderer::RendererOptions{.msaa = options.msaa});
      impl->target.emplace(*impl->ctx, options.width_px, options.height_px);
    } catch (const renderer::VulkanFailure& f) {
      return Error{Error::Kind::api, std::string("headless: cannot start the renderer: ") + f.what()};
    } catch (const vk::SystemError& e) {
      return Error{Error::Kind::api, "headless: cannot start the renderer: " +
                                         renderer::vk_call_name(e.what()) + ": " +
                                         renderer::vk_result_name(e.code().value())};
    }
  }
  impl->first_ns = options.pace == Pace::fast ? options.start_ns : impl->steady.now_ns();
  return std::unique_ptr<HeadlessDisplay>(new HeadlessDisplay(std::move(impl)));
}

HeadlessDisplay::HeadlessDisplay(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
HeadlessDisplay::~HeadlessDisplay() {
  // The members' destructors wait for their own GPU work without throwing;
  // this waits for everything first (a lost device: nothing to wait for).
  if (impl_ && impl_->ctx) impl_->ctx->wait_idle_noexcept();
}

const io::Clock& HeadlessDisplay::clock() const { return impl_->clock(); }

io::DisplayInfo HeadlessDisplay::info() const {
  io::DisplayInfo i;
  i.backend = data::Backend::headless;
  i.refresh_hz = impl_->options.refresh_hz;
  i.eye_width_px = impl_->options.width_px;
  i.eye_height_px = impl_->options.height_px;
  if (impl_->ctx) {
    i.renderer_device = impl_->ctx->device_name();
    i.renderer_driver = impl_->ctx->driver_info();
    if (impl_->renderer) i.msaa = impl_->renderer->msaa();
  } else {
    i.renderer_device = "none";
    i.renderer_driver = "none";
  }
  return i;
}

std::int64_t HeadlessDisplay::first_ns() const { return impl_->first_ns; }
std::int64_t HeadlessDisplay::period_ns() const { return impl_->period_ns; }

std::optional<io::FrameTiming> HeadlessDisplay::begin_frame() {
  auto& m = *impl_;
  io::FrameTiming f;
  f.index = m.index++;
  f.period_ns = m.period_ns;
  const std::int64_t due = m.first_ns + f.index * m.period_ns;
  if (m.options.pace == Pace::fast) {
    m.sim_clock.set(due);
    f.now_ns = due;
  } else {
    const std::int64_t now = m.steady.now_ns();
    if (now < due) std::this_thread::sleep_for(std::chrono::nanoseconds(due - now));
    f.now_ns = m.steady.now_ns();
  }
  // Shown one period after the frame starts (a display's latency).
  f.predicted_display_ns = due + m.period_ns;
  return f;
}

Result<HeadlessDevices> HeadlessDevices::create(const HeadlessOptions& display, TrajectoryOptions trajectory) {
  auto made = HeadlessDisplay::create(display);
  if (!made) return made.error();
  HeadlessDevices out;
  out.display = std::move(made).value();
  trajectory.start_ns = out.display->first_ns();
  trajectory.period_ns = out.display->period_ns();
  out.poses = std::make_unique<TrajectoryPoses>(std::move(trajectory));
  return out;
}

LabFrame TrajectoryPoses::poses(const io::FrameTiming& frame) {
  const auto& o = options_;
  const std::int64_t t = frame.predicted_display_ns - o.start_ns;
  if (o.trajectory.empty()) return standing_pose(o.table, o.eye_height_m, t);
  // Recorded or generated trajectory, looped; the sample at or before t.
  const std::int64_t t0 = o.trajectory.front().t_ns;
  const std::int64_t span = o.trajectory.back().t_ns - t0 + o.period_ns;
  const std::int64_t local = t0 + (span > 0 ? t % span : 0);
  auto it = std::upper_bound(o.trajectory.begin(), o.trajectory.end(), local,
                             [](std::int64_t v, const geometry::TrajectorySample& s) { return v < s.t_ns; });
  if (it != o.trajectory.begin()) --it;
  return it->frame;
}

renderer::StereoRig HeadlessDisplay::rig(const io::FrameTiming&, double ipd_m) {
  const auto& o = impl_->options;
  return renderer::StereoRig::from_ipd(
      ipd_m, renderer::Fov::symmetric(std::numbers::pi / 2.0,
                                      static_cast<double>(o.width_px) / static_cast<double>(o.height_px)));
}

renderer::FrameStats HeadlessDisplay::submit(const renderer::Scene& scene,
                                             const renderer::FrameDescription& frame,
                                             const io::Overlay&, bool draw) {
  auto& m = *impl_;
  if (!m.renderer) return {};
  if (draw) {
    try {
      renderer::FrameStats stats = m.renderer->render(scene, frame, *m.target);
      m.drawn = true;
      return stats;
    } catch (const renderer::VulkanFailure& f) {
      throw io::DeviceFailure(f.call, renderer::vk_result_name(f.result), "headless rendering");
    }
  }
  // Planned, not drawn: the counts the frame would have had, its CPU cost.
  const auto start = std::chrono::steady_clock::now();
  const renderer::RenderPlan plan = renderer::plan_frame(scene, frame);
  renderer::FrameStats stats;
  stats.views = plan.rendered_views();
  stats.draws = static_cast<int>(plan.draw_count());
  stats.back_hemisphere = plan.back_hemisphere;
  stats.max_level = plan.max_level;
  stats.reused = true;
  stats.cpu_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

std::vector<std::string> HeadlessDisplay::save_frame(const std::string& stem) {
  auto& m = *impl_;
  std::vector<std::string> written;
  if (!m.target || !m.drawn) return written;
  for (auto [eye, suffix] : {std::pair{renderer::Eye::left, "_left.png"},
                             std::pair{renderer::Eye::right, "_right.png"}}) {
    const std::string path = stem + suffix;
    // A frame that cannot be written is left out of the files returned (the
    // onset's record names only images that exist) and told on stderr, as the
    // other backends do; the session goes on.
    const auto saved = renderer::write_png(path, m.target->image(eye));
    if (const auto* err = std::get_if<renderer::RenderError>(&saved))
      std::fprintf(stderr, "curvlab: headless: frame not saved: %s\n", err->message.c_str());
    else
      written.push_back(path);
  }
  return written;
}

}  // namespace curvlab::harness::runner
