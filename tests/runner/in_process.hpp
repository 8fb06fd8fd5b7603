// Whole sessions in process for the runner's tests: the headless backend
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

// Forwards to a headless backend; the test's hooks may invalidate the head,
// add inputs and raise signals. `phase` is the phase of the last submitted
// frame, as a window would show it.
class ScriptedBackend final : public rn::Backend {
 public:
  explicit ScriptedBackend(rn::HeadlessBackend& inner) : inner_(inner) {}

  std::function<bool(std::int64_t t_ns)> head_valid = [](std::int64_t) { return true; };
  std::function<rn::BackendSignal(const rn::FrameTiming&, const std::string& phase,
                                  std::vector<rn::InputEvent>&)>
      inputs;

  [[nodiscard]] rn::BackendInfo info() const override { return inner_.info(); }
  std::optional<rn::FrameTiming> begin_frame() override {
    auto t = inner_.begin_frame();
    if (t) timing_ = *t;
    return t;
  }
  geometry::LabFrame poses(const rn::FrameTiming& frame) override {
    auto p = inner_.poses(frame);
    p[geometry::Device::head].valid = head_valid(frame.now_ns);
    return p;
  }
  rn::BackendSignal poll_input(std::vector<rn::InputEvent>& out) override {
    const auto signal = inner_.poll_input(out);
    if (inputs) {
      const auto mine = inputs(timing_, phase_, out);
      if (mine != rn::BackendSignal::none) return mine;
    }
    return signal;
  }
  renderer::StereoRig rig(const rn::FrameTiming& frame, double ipd_m) override {
    return inner_.rig(frame, ipd_m);
  }
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const rn::Overlay& overlay, bool draw) override {
    phase_ = std::string(rn::to_string(overlay.phase));
    return inner_.submit(scene, frame, overlay, draw);
  }

 private:
  rn::HeadlessBackend& inner_;
  rn::FrameTiming timing_;
  std::string phase_;
};

struct Outcome {
  std::string db;
  rn::SessionSummary summary;
};

// A protocol of protocols/ (file name without .toml) with `extra` appended,
// run to the end; `observer` answers with the default simulated observer.
inline Outcome run_protocol(const std::string& protocol, const std::string& name, const std::string& extra,
                            bool observer, const std::function<void(ScriptedBackend&)>& script) {
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
  ho.table = rn::nominal_calibration(p.session_settings());
  auto made = rn::HeadlessBackend::create(ho);
  EXPECT_TRUE(made.has_value()) << (made ? "" : made.error().message);
  if (!made) return {};
  auto& headless = *made.value();
  ScriptedBackend backend(headless);
  script(backend);
  rn::RunOptions o;
  o.participant = "T01";
  if (observer) o.observer = rn::ObserverParams{};
  o.drawing = rn::FrameDrawing::none;
  const auto db = (fresh_dir("in_process_" + name) / "s.sqlite").string();
  auto result = rn::run_session(p, text.str(), db, o, backend, headless.clock());
  EXPECT_TRUE(result.has_value()) << (result ? "" : result.error().message);
  if (!result) return {};
  return {db, result.value()};
}

}  // namespace curvlab::testing
