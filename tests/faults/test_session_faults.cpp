// A backend that fails part-way through a session, in process: the session
// ends `interrupted`, run_session returns an error naming the API call and
// its result, every trial completed before the fault is kept, and
// resume_session completes the session with each trial exactly once
// (docs/runner.md, "Faults"). Faults come from a wrapper that throws
// BackendFailure at frame N (begin_frame or submit), and from the test
// Vulkan layer inside the real headless backend (vkQueueSubmit returns
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

// Forwards to another backend and throws at frame `fail_at` (counted from
// 0 by begin_frame) in the method the test chose.
class FailingBackend final : public rn::Backend {
 public:
  enum class Where { begin_frame, submit };
  FailingBackend(rn::Backend& inner, std::int64_t fail_at, Where where, rn::BackendFailure failure)
      : inner_(inner), fail_at_(fail_at), where_(where), failure_(std::move(failure)) {}

  [[nodiscard]] rn::BackendInfo info() const override { return inner_.info(); }
  std::optional<rn::FrameTiming> begin_frame() override {
    if (where_ == Where::begin_frame && frames_ == fail_at_) throw failure_;
    ++frames_;
    return inner_.begin_frame();
  }
  geometry::LabFrame poses(const rn::FrameTiming& f) override { return inner_.poses(f); }
  rn::BackendSignal poll_input(std::vector<rn::InputEvent>& out) override { return inner_.poll_input(out); }
  renderer::StereoRig rig(const rn::FrameTiming& f, double ipd_m) override { return inner_.rig(f, ipd_m); }
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const rn::Overlay& overlay, bool draw) override {
    if (where_ == Where::submit && frames_ - 1 == fail_at_) throw failure_;
    return inner_.submit(scene, frame, overlay, draw);
  }

 private:
  rn::Backend& inner_;
  std::int64_t fail_at_;
  Where where_;
  rn::BackendFailure failure_;
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

std::unique_ptr<rn::HeadlessBackend> headless(const pr::Protocol& p, bool gpu) {
  rn::HeadlessOptions o;
  o.no_gpu = !gpu;
  o.software = true;
  o.width_px = 64;
  o.height_px = 64;
  o.refresh_hz = p.refresh_hz;
  o.table = rn::nominal_calibration(p.session_settings());
  auto made = rn::HeadlessBackend::create(o);
  EXPECT_TRUE(made.has_value()) << (made ? "" : made.error().message);
  return made ? std::move(made).value() : nullptr;
}

rn::RunOptions options(rn::FrameDrawing drawing) {
  rn::RunOptions o;
  o.participant = "F01";
  o.observer = rn::ObserverParams{};
  o.drawing = drawing;
  return o;
}

int count(const std::string& db, const std::string& sql) { return std::stoi(query(db, sql)[0][0]); }

// Runs the demo through `backend` (which fails part-way) and checks what the
// fault left: an error naming `api_result`, the session interrupted, the
// trials completed so far kept. Then resumes it with a healthy backend.
void fault_then_resume(const std::string& db, rn::Backend& backend, const devices::Clock& clock,
                       rn::FrameDrawing drawing, const std::string& api_result, bool gpu_resume) {
  const Demo d = demo();
  std::optional<rn::RunResult> result;
  try {
    result.emplace(rn::run_session(d.protocol, d.text, db, options(drawing), backend, clock));
  } catch (const rn::BackendFailure& f) {
    FAIL() << "run_session let the backend's failure escape instead of ending the session: " << f.what();
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
  ASSERT_TRUE(healthy);
  auto resumed = rn::resume_session(db, session, s, *loaded, options(drawing), *healthy, healthy->clock());
  ASSERT_TRUE(resumed.has_value()) << resumed.error().message;
  EXPECT_EQ(resumed->status, curvlab::data::SessionStatus::completed);
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
  ASSERT_TRUE(inner);
  // Frame 300 at 90 Hz: 3.3 s in, after two or three of the ~1.2 s trials.
  FailingBackend backend(*inner, 300, FailingBackend::Where::begin_frame,
                         rn::BackendFailure("xrWaitFrame", "XR_ERROR_SESSION_LOST"));
  const auto db = (fresh_dir("fault_begin") / "s.sqlite").string();
  fault_then_resume(db, backend, inner->clock(), rn::FrameDrawing::none, "xrWaitFrame: XR_ERROR_SESSION_LOST",
                    false);
}

TEST(SessionFaults, LostDeviceInSubmitEndsInterruptedAndResumes) {
  const Demo d = demo();
  auto inner = headless(d.protocol, false);
  ASSERT_TRUE(inner);
  FailingBackend backend(*inner, 300, FailingBackend::Where::submit,
                         rn::BackendFailure("vkQueueSubmit", "VK_ERROR_DEVICE_LOST"));
  const auto db = (fresh_dir("fault_submit") / "s.sqlite").string();
  fault_then_resume(db, backend, inner->clock(), rn::FrameDrawing::none, "vkQueueSubmit: VK_ERROR_DEVICE_LOST",
                    false);
}

TEST(SessionFaults, RealHeadlessDeviceLossEndsInterruptedAndResumes) {
  // The real headless backend drawing every frame on lavapipe; the test
  // layer makes its 400th vkQueueSubmit report a lost device.
  const Demo d = demo();
  const auto db = (fresh_dir("fault_vulkan") / "s.sqlite").string();
  {
    const VulkanFault fault("vkQueueSubmit@400");
    auto backend = headless(d.protocol, true);
    ASSERT_TRUE(backend);
    std::optional<rn::RunResult> result;
    try {
      result.emplace(rn::run_session(d.protocol, d.text, db, options(rn::FrameDrawing::all), *backend, backend->clock()));
    } catch (const rn::BackendFailure& f) {
      FAIL() << "run_session let the backend's failure escape instead of ending the session: " << f.what();
    }
    ASSERT_TRUE(result && !result->has_value());
    EXPECT_NE(result->error().message.find("vkQueueSubmit: VK_ERROR_DEVICE_LOST"), std::string::npos)
        << result->error().message;
  }  // the backend is destroyed on the lost device, then the layer is off
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  const int done = count(db, "SELECT count(*) FROM trials WHERE status = 'completed'");
  EXPECT_GT(done, 0);
  EXPECT_LT(done, 8);
}
