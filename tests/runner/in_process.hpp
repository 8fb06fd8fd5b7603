// Whole sessions in process for the runner's tests: the headless devices
// without a GPU, wrapped so that a test decides when the head is lost, when
// signals come and which keys are pressed when.
#pragma once

#include "session_db.hpp"

#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

namespace curvlab::testing {

namespace rn = harness::runner;
namespace pr = harness::protocol;

// A session's devices as a test scripts them: the headless display and
// trajectory, with the test's hooks deciding when the head is lost, and a
// response source adding inputs and signals. `phase` is the phase of the last
// submitted frame, as a window would show it.
class ScriptedDevices final : public harness::io::Display,
                              public harness::io::PoseSource,
                              public harness::io::ResponseSource {
 public:
  ScriptedDevices(rn::HeadlessDisplay& display, rn::TrajectoryPoses& poses) : display_(display), poses_(poses) {}

  std::function<bool(std::int64_t t_ns)> head_valid = [](std::int64_t) { return true; };
  // Changes the poses as a faulty runtime would (NaN, 1e308 m); none by default.
  std::function<void(std::int64_t t_ns, geometry::LabFrame&)> alter_poses;
  std::function<harness::io::Signal(const harness::io::FrameTiming&, const std::string& phase,
                                    std::vector<harness::io::InputEvent>&)>
      inputs;
  // Sees what each frame shows besides the scene (a participant reading the screen).
  std::function<void(const harness::io::Overlay&)> shown;
  // What the scripted inputs can press (the page's continue line is made from it).
  harness::io::Reach reach_as;

  [[nodiscard]] harness::io::Station station() { return {this, this, {this}}; }

  [[nodiscard]] harness::io::DisplayInfo info() const override { return display_.info(); }
  std::optional<harness::io::FrameTiming> begin_frame() override {
    auto t = display_.begin_frame();
    if (t) timing_ = *t;
    return t;
  }
  geometry::LabFrame poses(const harness::io::FrameTiming& frame) override {
    auto p = poses_.poses(frame);
    p[geometry::Device::head].valid = head_valid(frame.now_ns);
    if (alter_poses) alter_poses(frame.now_ns, p);
    return p;
  }
  [[nodiscard]] harness::io::Reach reach() const override { return reach_as; }
  harness::io::Signal poll(std::vector<harness::io::InputEvent>& out) override {
    return inputs ? inputs(timing_, phase_, out) : harness::io::Signal::none;
  }
  renderer::StereoRig rig(const harness::io::FrameTiming& frame, double ipd_m) override {
    return display_.rig(frame, ipd_m);
  }
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const harness::io::Overlay& overlay, bool draw) override {
    phase_ = std::string(harness::io::to_string(overlay.phase));
    if (shown) shown(overlay);
    return display_.submit(scene, frame, overlay, draw);
  }

 private:
  rn::HeadlessDisplay& display_;
  rn::TrajectoryPoses& poses_;
  harness::io::FrameTiming timing_;
  std::string phase_;
};

struct Outcome {
  std::string db;
  rn::SessionSummary summary;
};

// A protocol of protocols/ (file name without .toml) with `extra` appended,
// run to the end; `observer` answers with the default simulated observer.
inline Outcome run_protocol(const std::string& protocol, const std::string& name, const std::string& extra,
                            bool observer, const std::function<void(ScriptedDevices&)>& script) {
  const std::string path = std::string(CURVLAB_SOURCE_DIR) + "/protocols/" + protocol + ".toml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf() << '\n' << extra;
  auto loaded = pr::load_protocol_text(text.str(), path);
  EXPECT_TRUE(loaded.has_value()) << (loaded ? "" : pr::format_diagnostic(loaded.error().diagnostics[0]));
  if (!loaded) return {};
  const auto& p = *loaded;
  rn::HeadlessOptions ho;
  ho.no_gpu = true;
  ho.refresh_hz = p.refresh_hz;
  auto made = rn::HeadlessDevices::create(ho, rn::standing_at(rn::nominal_calibration(p.session_settings())));
  EXPECT_TRUE(made.has_value()) << (made ? "" : made.error().message);
  if (!made) return {};
  auto& headless = made.value();
  ScriptedDevices devices(*headless.display, *headless.poses);
  script(devices);
  rn::RunOptions o;
  o.participant = "T01";
  if (observer) o.observer = rn::ObserverParams{};
  o.drawing = rn::FrameDrawing::none;
  const auto db = (fresh_dir("in_process_" + name) / "s.sqlite").string();
  auto result = rn::run_session(p, text.str(), db, o, devices.station(), headless.clock());
  EXPECT_TRUE(result.has_value()) << (result ? "" : result.error().message);
  if (!result) return {};
  return {db, result.value()};
}

}  // namespace curvlab::testing
