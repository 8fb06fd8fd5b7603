// What the operator window costs the participant's frame loop: the same
// OpenXR frames (the scripted test runtime at 90 Hz, lavapipe, an H3
// billiards stimulus) driven with the operator window off and on. With it on,
// the frame thread also records the GPU copy of both submitted eyes when the
// window asks (about 15 Hz), hands the status over when asked and polls the
// window's events every 4th frame; the window draws on its own thread.
// The participant frame's CPU time is measured from the moment xrWaitFrame
// has let the frame start (begin_frame returned) to the return of submit
// (xrEndFrame): the runner's work, the render and the copy. Rounds alternate
// off and on so drift hits both. Needs a display: run under `xvfb-run -a`.
//
//   xvfb-run -a build/ci/bin/bench_operator_cost [frames_per_round] [rounds]
#include "bench_scenes.hpp"
#include "curvlab/harness/operator/operator_window.hpp"

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/xr/backend.hpp"
#include "curvlab/renderer/scene.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

using namespace curvlab;
namespace rn = harness::runner;
using Clock = std::chrono::steady_clock;

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

// One round: a fresh backend (and window), `frames` frames after 30 to settle.
bool round(bool window, int frames, const bench::StimulusScene& s, std::vector<double>& cpu_ms) {
  harness::io::SteadyClock clock;
  harness::xr::XrBackendOptions o;
  o.clock = &clock;
  o.mirror = window;
  auto made = harness::xr::make_xr_backend(o);
  if (!made) {
    std::fprintf(stderr, "%s\n", made.error().message.c_str());
    return false;
  }
  auto& backend = *made.value();
  std::unique_ptr<rn::OperatorConsole> console;
  if (window) {
    harness::operator_console::OperatorWindowOptions w;
    w.mirror = backend.mirror();
    auto opened = harness::operator_console::open_operator_window(std::move(w));
    if (!opened) {
      std::fprintf(stderr, "%s\n", opened.error().message.c_str());
      return false;
    }
    console = std::move(opened).value();
  }
  rn::OperatorStatus status;
  status.participant = "P01";
  status.protocol = "bench";
  status.trials = 100;
  std::vector<harness::io::InputEvent> inputs;
  std::vector<rn::OperatorAction> actions;
  const harness::io::Overlay overlay{rn::Phase::stimulus, "bench", false};
  for (int i = 0; i < frames + 30; ++i) {
    auto timing = backend.begin_frame();
    if (!timing) return false;
    const auto t0 = Clock::now();
    (void)backend.poses(*timing);
    inputs.clear();
    (void)backend.poll_signal();
    (void)backend.poll(inputs);
    if (console) console->take(timing->now_ns, actions);
    renderer::FrameDescription f;
    f.space = s.space;
    f.settings = renderer::ViewSettings::preset(renderer::ViewPreset::native);
    f.head = s.head;
    f.rig = backend.rig(*timing, 0.063);
    backend.submit(s.scene, f, overlay, true);
    if (console) {
      status.trial = i / 60 + 1;
      status.elapsed_ns = timing->now_ns;
      console->show(status);
    }
    if (i >= 30) cpu_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::max(30, std::atoi(argv[1])) : 450;
  const int rounds = argc > 2 ? std::max(1, std::atoi(argv[2])) : 2;
  if (std::getenv("XR_RUNTIME_JSON") == nullptr) setenv("XR_RUNTIME_JSON", CURVLAB_TEST_XR_RUNTIME_JSON, 1);
  const auto s = bench::scene_of(geometry::SpaceKind::H3, bench::SceneKind::billiards);
  std::vector<double> off, on;
  for (int r = 0; r < rounds; ++r)
    if (!round(false, frames, s, off) || !round(true, frames, s, on)) return 1;
  std::printf("participant frame CPU time (begin_frame returned → submit returned), OpenXR test runtime "
              "90 Hz, 320x320 per eye, lavapipe; %d rounds of %d frames each\n\n", rounds, frames);
  std::printf("%-22s %8s %12s %10s\n", "operator window", "frames", "median_ms", "p95_ms");
  std::printf("%-22s %8zu %12.3f %10.3f\n", "off", off.size(), quantile(off, 0.5), quantile(off, 0.95));
  std::printf("%-22s %8zu %12.3f %10.3f\n", "on (mirror, ~15 Hz)", on.size(), quantile(on, 0.5), quantile(on, 0.95));
  std::printf("%-22s %8s %12.3f %10.3f\n", "increase", "", quantile(on, 0.5) - quantile(off, 0.5),
              quantile(on, 0.95) - quantile(off, 0.95));
  return 0;
}
