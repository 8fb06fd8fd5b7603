// What showing a frame costs on top of drawing it: the same stereo stimulus
// frame drawn offscreen (headless: submit, wait, read back) and drawn into the
// desktop window (compose the eyes and the information line into the
// swapchain image, present; frames pipelined two deep), per eye size and
// preview layout. Needs a display: run under `xvfb-run -a`.
//
//   xvfb-run -a build/dev/bin/bench_present_cost [frames]
#include "desktop_backend.hpp"
#include "bench_scenes.hpp"

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/scene.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

namespace {

using namespace curvlab;
using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

renderer::FrameDescription describe(const bench::StimulusScene& s, std::uint32_t size,
                                    int frame) {
  renderer::FrameDescription f;
  f.space = s.space;
  f.settings = renderer::ViewSettings::preset(renderer::ViewPreset::native);
  // A slowly turning head, so no frame is a repeat of the last.
  f.head = s.head * geometry::rotation(glm::dvec3(0, 1, 0), 0.002 * frame);
  f.rig = renderer::StereoRig::from_ipd(0.063, renderer::Fov::symmetric(std::numbers::pi / 2, 1.0));
  f.width_px = size;
  f.height_px = size;
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::max(5, std::atoi(argv[1])) : 40;
  const auto s = bench::scene_of(geometry::SpaceKind::H3, bench::SceneKind::billiards);
  harness::io::SteadyClock clock;

  std::printf("H3 billiards, native view, lavapipe, window under Xvfb; %d frames each, "
              "median ms per frame\n\n",
              frames);
  std::printf("%-6s %-13s %12s %12s %8s %8s\n", "eye", "layout", "offscreen_ms", "window_ms",
              "ratio", "window_fps");
  for (const std::uint32_t size : {256u, 512u, 960u}) {
    // Offscreen, as the headless backend draws.
    auto ctx_made = renderer::Context::create({.device = renderer::DeviceChoice::software, .validation = false});
    if (auto* e = std::get_if<renderer::RenderError>(&ctx_made)) {
      std::fprintf(stderr, "%s\n", e->message.c_str());
      return 1;
    }
    const auto& ctx = std::get<renderer::Context>(ctx_made);
    std::vector<double> offscreen_ms;
    {
      renderer::Renderer r(ctx);
      renderer::OffscreenTarget target(ctx, size, size);
      for (int i = 0; i < frames + 3; ++i) {
        const auto t0 = Clock::now();
        r.render(s.scene, describe(s, size, i), target);
        if (i >= 3) offscreen_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      }
    }
    for (const auto preview : {harness::desktop::DesktopPreview::side_by_side, harness::desktop::DesktopPreview::left}) {
      harness::desktop::DesktopOptions o;
      o.eye_width_px = size;
      o.eye_height_px = size;
      o.preview = preview;
      o.software = true;
      o.vsync = false;
      o.clock = &clock;
      auto backend_made = harness::desktop::DesktopBackend::create(o);
      if (!backend_made) {
        std::fprintf(stderr, "%s\n", backend_made.error().message.c_str());
        return 1;
      }
      auto& backend = *backend_made.value();
      std::vector<double> window_ms;
      const harness::io::Overlay overlay{harness::io::Phase::stimulus, "block 1 · trial 3 of 8 · H3 native", false};
      Clock::time_point last{};
      for (int i = 0; i < frames + 3; ++i) {
        auto timing = backend.begin_frame();
        if (!timing) break;
        backend.submit(s.scene, describe(s, size, i), overlay, true);
        const auto now = Clock::now();
        // Frame to frame: presentation is pipelined, so the interval is the cost.
        if (i >= 3) window_ms.push_back(std::chrono::duration<double, std::milli>(now - last).count());
        last = now;
      }
      const double off = median(offscreen_ms);
      const double win = median(window_ms);
      std::printf("%-6u %-13s %12.2f %12.2f %8.2f %8.1f\n", size,
                  preview == harness::desktop::DesktopPreview::side_by_side ? "side-by-side" : "one eye",
                  off, win, win / off, 1000.0 / win);
    }
  }
  return 0;
}
