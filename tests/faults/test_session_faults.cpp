// A display that fails part-way through a session, in process: the session
// ends `interrupted`, run_session returns an error naming the API call and
// its result, every trial completed before the fault is kept, and
// resume_session completes the session with each trial exactly once
// (docs/runner.md, "Faults"). Faults come from a wrapper that throws
// DeviceFailure at frame N (begin_frame or submit), and from the test
// Vulkan layer inside the real headless display (vkQueueSubmit returns
// VK_ERROR_DEVICE_LOST).
#include "fault_env.hpp"

#include "../runner/session_db.hpp"

#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <gtest/gtest.h>

#include <optional>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <sstream>

namespace {

using namespace curvlab;
namespace rn = harness::runner;
namespace pr = harness::protocol;
using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::VulkanFault;

// Forwards to another display and throws at frame `fail_at` (counted from
// 0 by begin_frame) in the method the test chose.
class FailingDisplay final : public harness::io::Display {
 public:
  enum class Where { begin_frame, submit };
  FailingDisplay(harness::io::Display& inner, std::int64_t fail_at, Where where, harness::io::DeviceFailure failure)
      : inner_(inner), fail_at_(fail_at), where_(where), failure_(std::move(failure)) {}

  [[nodiscard]] harness::io::DisplayInfo info() const override { return inner_.info(); }
  std::optional<harness::io::FrameTiming> begin_frame() override {
    if (where_ == Where::begin_frame && frames_ == fail_at_) throw failure_;
    ++frames_;
    return inner_.begin_frame();
  }
  renderer::StereoRig rig(const harness::io::FrameTiming& f, double ipd_m) override { return inner_.rig(f, ipd_m); }
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const harness::io::Overlay& overlay, bool draw) override {
    if (where_ == Where::submit && frames_ - 1 == fail_at_) throw failure_;
    return inner_.submit(scene, frame, overlay, draw);
  }

 private:
  harness::io::Display& inner_;
  std::int64_t fail_at_;
  Where where_;
  harness::io::DeviceFailure failure_;
  std::int64_t frames_ = 0;
};

struct Demo {
  std::string text;
  pr::Protocol protocol;
};

Demo demo() {
  const std::string path = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  auto loaded = pr::load_protocol_text(text.str(), path);
  EXPECT_TRUE(loaded.has_value());
  return {text.str(), *loaded};
}

rn::HeadlessDevices headless(const pr::Protocol& p, bool gpu) {
  rn::HeadlessOptions o;
  o.no_gpu = !gpu;
  o.software = true;
  o.width_px = 64;
  o.height_px = 64;
  o.refresh_hz = p.refresh_hz;
  auto made = rn::HeadlessDevices::create(o, rn::standing_at(rn::nominal_calibration(p.session_settings())));
  EXPECT_TRUE(made.has_value()) << (made ? "" : made.error().message);
  return made ? std::move(made).value() : rn::HeadlessDevices{};
}

rn::RunOptions options(rn::FrameDrawing drawing) {
  rn::RunOptions o;
  o.participant = "F01";
  o.observer = rn::ObserverParams{};
  o.drawing = drawing;
  return o;
}

int count(const std::string& db, const std::string& sql) { return std::stoi(query(db, sql)[0][0]); }

// Runs the demo on `station` (whose display fails part-way) and checks what
// the fault left: an error naming `api_result`, the session interrupted, the
// trials completed so far kept. Then resumes it with healthy devices.
void fault_then_resume(const std::string& db, const harness::io::Station& station, const harness::io::Clock& clock,
                       rn::FrameDrawing drawing, const std::string& api_result, bool gpu_resume) {
  const Demo d = demo();
  std::optional<rn::RunResult> result;
  try {
    result.emplace(rn::run_session(d.protocol, d.text, db, options(drawing), station, clock));
  } catch (const harness::io::DeviceFailure& f) {
    FAIL() << "run_session let the display's failure escape instead of ending the session: " << f.what();
  }
  ASSERT_TRUE(result && !result->has_value()) << "the session ran to the end despite the fault";
  const auto& error = result->error();
  EXPECT_EQ(curvlab::harness::exit_code(error), 1);  // a run-time failure, not bad input
  EXPECT_NE(error.message.find(api_result), std::string::npos) << error.message;

  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  const int done = count(db, "SELECT count(*) FROM trials WHERE status = 'completed'");
  EXPECT_GT(done, 0) << "the fault came before the first trial ended";
  EXPECT_LT(done, 8);
  std::cout << "fault: " << error.message << "; kept " << done << " of 8 trials\n";
  EXPECT_EQ(count(db, "SELECT count(*) FROM trials WHERE status = 'completed' AND response IS NULL"), 0);
  const std::string kept_sql =
      "SELECT trial_index, response, rt_ns, completed_utc FROM trials WHERE status = 'completed' ORDER BY trial_index";
  const auto kept = query(db, kept_sql);

  const std::int64_t session = std::stoll(query(db, "SELECT session_id FROM sessions")[0][0]);
  auto stored = rn::read_stored_session(db, session);
  ASSERT_TRUE(stored.has_value()) << stored.error().message;
  const auto& s = stored.value();
  auto loaded = pr::load_protocol_text(s.protocol_text, s.protocol_source);
  ASSERT_TRUE(loaded.has_value());
  auto healthy = headless(*loaded, gpu_resume);
  ASSERT_TRUE(healthy.display);
  auto resumed = rn::resume_session(db, session, s, *loaded, options(drawing), healthy.station(), healthy.clock());
  ASSERT_TRUE(resumed.has_value()) << resumed.error().message;
  EXPECT_EQ(resumed->status, curvlab::harness::data::SessionStatus::completed);
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");
  // Every trial completed; the ones done before the fault kept as they were.
  EXPECT_EQ(count(db, "SELECT count(*) FROM trials WHERE status = 'completed'"), 8);
  const auto after = query(db, kept_sql);
  for (const auto& row : kept)
    EXPECT_NE(std::find(after.begin(), after.end(), row), after.end()) << "trial " << row[0] << " changed";
  EXPECT_EQ(curvlab::testing::integrity(db), "ok");
}

}  // namespace

TEST(SessionFaults, LostSessionInBeginFrameEndsInterruptedAndResumes) {
  const Demo d = demo();
  auto inner = headless(d.protocol, false);
  ASSERT_TRUE(inner.display);
  // Frame 300 at 90 Hz: 3.3 s in, after two or three of the ~1.2 s trials.
  FailingDisplay display(*inner.display, 300, FailingDisplay::Where::begin_frame,
                         harness::io::DeviceFailure("xrWaitFrame", "XR_ERROR_SESSION_LOST"));
  const auto db = (fresh_dir("fault_begin") / "s.sqlite").string();
  fault_then_resume(db, {&display, inner.poses.get(), {}}, inner.clock(), rn::FrameDrawing::none, "xrWaitFrame: XR_ERROR_SESSION_LOST",
                    false);
}

TEST(SessionFaults, LostDeviceInSubmitEndsInterruptedAndResumes) {
  const Demo d = demo();
  auto inner = headless(d.protocol, false);
  ASSERT_TRUE(inner.display);
  FailingDisplay display(*inner.display, 300, FailingDisplay::Where::submit,
                         harness::io::DeviceFailure("vkQueueSubmit", "VK_ERROR_DEVICE_LOST"));
  const auto db = (fresh_dir("fault_submit") / "s.sqlite").string();
  fault_then_resume(db, {&display, inner.poses.get(), {}}, inner.clock(), rn::FrameDrawing::none, "vkQueueSubmit: VK_ERROR_DEVICE_LOST",
                    false);
}

TEST(SessionFaults, RealHeadlessDeviceLossEndsInterruptedAndResumes) {
  // The real headless display drawing every frame on lavapipe; the test
  // layer makes its 400th vkQueueSubmit report a lost device.
  const Demo d = demo();
  const auto db = (fresh_dir("fault_vulkan") / "s.sqlite").string();
  {
    const VulkanFault fault("vkQueueSubmit@400");
    auto devices = headless(d.protocol, true);
    ASSERT_TRUE(devices.display);
    std::optional<rn::RunResult> result;
    try {
      result.emplace(rn::run_session(d.protocol, d.text, db, options(rn::FrameDrawing::all), devices.station(), devices.clock()));
    } catch (const harness::io::DeviceFailure& f) {
      FAIL() << "run_session let the display's failure escape instead of ending the session: " << f.what();
    }
    ASSERT_TRUE(result && !result->has_value());
    EXPECT_NE(result->error().message.find("vkQueueSubmit: VK_ERROR_DEVICE_LOST"), std::string::npos)
        << result->error().message;
  }  // the display is destroyed on the lost device, then the layer is off
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  const int done = count(db, "SELECT count(*) FROM trials WHERE status = 'completed'");
  EXPECT_GT(done, 0);
  EXPECT_LT(done, 8);
}
