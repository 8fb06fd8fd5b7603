#include "curvlab/harness/xr/actions.hpp"
#include "curvlab/harness/xr/instance.hpp"
#include "curvlab/harness/xr/session_state.hpp"
#include "curvlab/harness/xr/views.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <set>

namespace {

using namespace curvlab::harness::xr;

TEST(XrResultName, NamesWithoutAnInstance) {
  EXPECT_EQ(result_name(XR_ERROR_RUNTIME_UNAVAILABLE), "XR_ERROR_RUNTIME_UNAVAILABLE");
  EXPECT_EQ(static_cast<int>(XR_ERROR_RUNTIME_UNAVAILABLE), -51);
  EXPECT_EQ(result_name(XR_ERROR_FORM_FACTOR_UNAVAILABLE), "XR_ERROR_FORM_FACTOR_UNAVAILABLE");
  EXPECT_EQ(result_name(XR_SESSION_LOSS_PENDING), "XR_SESSION_LOSS_PENDING");
  EXPECT_EQ(result_name(static_cast<XrResult>(-987654)), "XR_RESULT_-987654");
}

// This machine has no OpenXR runtime (DESIGN.md §9). Where one is installed
// the probe may succeed, and this test has nothing to check.
TEST(XrProbe, WithoutARuntimeFailsCleanlyAndWritesNothing) {
  const auto dir = std::filesystem::temp_directory_path() / "curvlab_xr_probe_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto old = std::filesystem::current_path();
  std::filesystem::current_path(dir);
  const auto result = probe("curvlab test");
  std::filesystem::current_path(old);
  const bool empty = std::filesystem::is_empty(dir);
  std::filesystem::remove_all(dir);
  if (result) GTEST_SKIP() << "an OpenXR runtime is present";
  const auto& e = result.error();
  EXPECT_EQ(e.kind, curvlab::harness::Error::Kind::device);
  const auto f = failed_call(e);
  ASSERT_TRUE(f) << e.message;
  EXPECT_EQ(f->result, XR_ERROR_RUNTIME_UNAVAILABLE);
  EXPECT_NE(e.message.find("XR_ERROR_RUNTIME_UNAVAILABLE (-51)"), std::string::npos) << e.message;
  EXPECT_NE(e.message.find("monado-service"), std::string::npos);
  EXPECT_NE(e.message.find("SteamVR"), std::string::npos);
  EXPECT_NE(e.message.find("XR_RUNTIME_JSON"), std::string::npos);
  EXPECT_TRUE(empty) << "the probe wrote files into the working directory";
  // Creating the instance directly fails the same way.
  auto instance = Instance::create("curvlab test");
  ASSERT_FALSE(instance.has_value());
  const auto call = failed_call(instance.error());
  ASSERT_TRUE(call) << instance.error().message;
  EXPECT_EQ(call->call, "xrCreateInstance");
  EXPECT_EQ(call->result, XR_ERROR_RUNTIME_UNAVAILABLE);
}

TEST(SessionState, NumberingMatchesOpenXR) {
  EXPECT_EQ(static_cast<int>(SessionState::Idle), XR_SESSION_STATE_IDLE);
  EXPECT_EQ(static_cast<int>(SessionState::Ready), XR_SESSION_STATE_READY);
  EXPECT_EQ(static_cast<int>(SessionState::Synchronized), XR_SESSION_STATE_SYNCHRONIZED);
  EXPECT_EQ(static_cast<int>(SessionState::Visible), XR_SESSION_STATE_VISIBLE);
  EXPECT_EQ(static_cast<int>(SessionState::Focused), XR_SESSION_STATE_FOCUSED);
  EXPECT_EQ(static_cast<int>(SessionState::Stopping), XR_SESSION_STATE_STOPPING);
  EXPECT_EQ(static_cast<int>(SessionState::LossPending), XR_SESSION_STATE_LOSS_PENDING);
  EXPECT_EQ(static_cast<int>(SessionState::Exiting), XR_SESSION_STATE_EXITING);
}

TEST(SessionState, FullLifecycleWithFocusLossAndResume) {
  SessionStateMachine m;
  auto u = m.on_state_changed(SessionState::Idle);
  EXPECT_EQ(u.mode, RunMode::WaitForRuntime);
  u = m.on_state_changed(SessionState::Ready);
  EXPECT_TRUE(u.begin_session);
  EXPECT_EQ(u.mode, RunMode::FramesOnly);
  EXPECT_TRUE(m.session_running());
  u = m.on_state_changed(SessionState::Synchronized);
  EXPECT_EQ(u.mode, RunMode::FramesOnly);
  u = m.on_state_changed(SessionState::Visible);
  EXPECT_EQ(u.mode, RunMode::FramesOnly);  // not yet focused: nothing to pause
  EXPECT_TRUE(u.message.empty());
  u = m.on_state_changed(SessionState::Focused);
  EXPECT_EQ(u.mode, RunMode::Running);
  // The participant opens the system menu: pause with a message.
  u = m.on_state_changed(SessionState::Visible);
  EXPECT_EQ(u.mode, RunMode::Paused);
  EXPECT_NE(u.message.find("lost input focus"), std::string::npos);
  u = m.on_state_changed(SessionState::Focused);
  EXPECT_EQ(u.mode, RunMode::Running);
  EXPECT_NE(u.message.find("resuming"), std::string::npos);
  // Headset off: FOCUSED → VISIBLE → SYNCHRONIZED stays paused.
  m.on_state_changed(SessionState::Visible);
  u = m.on_state_changed(SessionState::Synchronized);
  EXPECT_EQ(u.mode, RunMode::Paused);
  u = m.on_state_changed(SessionState::Stopping);
  EXPECT_TRUE(u.end_session);
  EXPECT_EQ(u.mode, RunMode::Stopped);
  EXPECT_FALSE(m.session_running());
  u = m.on_state_changed(SessionState::Idle);
  EXPECT_EQ(u.mode, RunMode::Stopped);
  u = m.on_state_changed(SessionState::Exiting);
  EXPECT_EQ(u.mode, RunMode::Exit);
  EXPECT_FALSE(u.end_session);
  EXPECT_FALSE(u.unexpected);
}

TEST(SessionState, TheFirstTrialWaitsForTheFirstFocus) {
  // A runtime that brings the session up over many frames: READY pauses the
  // runner (nothing is shown before VISIBLE, nothing answered before
  // FOCUSED), the first FOCUSED resumes it; later READYs give no pause of
  // their own.
  SessionStateMachine m;
  m.on_state_changed(SessionState::Idle);
  auto u = m.on_state_changed(SessionState::Ready);
  EXPECT_TRUE(u.begin_session);
  EXPECT_TRUE(u.pause);
  EXPECT_TRUE(u.message.empty());
  EXPECT_FALSE(m.on_state_changed(SessionState::Synchronized).resume);
  EXPECT_FALSE(m.on_state_changed(SessionState::Visible).resume);
  u = m.on_state_changed(SessionState::Focused);
  EXPECT_TRUE(u.resume);
  EXPECT_FALSE(u.pause);
  EXPECT_EQ(u.mode, RunMode::Running);
}

TEST(SessionState, StoppingAndReadyAgainPauseAndResumeTheTrial) {
  SessionStateMachine m;
  for (auto s : {SessionState::Idle, SessionState::Ready, SessionState::Synchronized,
                 SessionState::Visible, SessionState::Focused})
    m.on_state_changed(s);
  // The runtime stops the session from FOCUSED (its transitions skipped).
  auto u = m.on_state_changed(SessionState::Stopping);
  EXPECT_TRUE(u.unexpected);
  EXPECT_TRUE(u.pause);
  EXPECT_TRUE(u.end_session);
  EXPECT_NE(u.message.find("paused"), std::string::npos);
  EXPECT_FALSE(m.on_state_changed(SessionState::Idle).pause);
  u = m.on_state_changed(SessionState::Ready);
  EXPECT_TRUE(u.begin_session);
  EXPECT_FALSE(u.resume);
  m.on_state_changed(SessionState::Synchronized);
  u = m.on_state_changed(SessionState::Visible);
  EXPECT_FALSE(u.pause) << "paused already";
  u = m.on_state_changed(SessionState::Focused);
  EXPECT_TRUE(u.resume);
  EXPECT_EQ(u.mode, RunMode::Running);
  // Down through VISIBLE: one pause, not a second at STOPPING.
  EXPECT_TRUE(m.on_state_changed(SessionState::Visible).pause);
  EXPECT_FALSE(m.on_state_changed(SessionState::Synchronized).pause);
  EXPECT_FALSE(m.on_state_changed(SessionState::Stopping).pause);
  m.on_state_changed(SessionState::Idle);
  u = m.on_state_changed(SessionState::Exiting);
  EXPECT_FALSE(u.pause);
  EXPECT_FALSE(u.resume);
  EXPECT_EQ(u.mode, RunMode::Exit);
}

TEST(SessionState, LossPendingLeavesARunningSessionWithoutEndingIt) {
  SessionStateMachine m;
  for (auto s : {SessionState::Idle, SessionState::Ready, SessionState::Synchronized,
                 SessionState::Visible, SessionState::Focused})
    m.on_state_changed(s);
  const auto u = m.on_state_changed(SessionState::LossPending);
  EXPECT_TRUE(u.lost);
  EXPECT_FALSE(u.end_session) << "xrEndSession is valid only in STOPPING";
  EXPECT_FALSE(m.session_running());
  EXPECT_EQ(u.mode, RunMode::Exit);
  EXPECT_FALSE(u.unexpected);
  EXPECT_NE(u.message.find("can be resumed"), std::string::npos);
}

TEST(SessionState, UnexpectedTransitionIsFlaggedButFollowed) {
  SessionStateMachine m;
  m.on_state_changed(SessionState::Idle);
  const auto u = m.on_state_changed(SessionState::Focused);  // skipped READY…VISIBLE
  EXPECT_TRUE(u.unexpected);
  EXPECT_NE(u.message.find("IDLE → FOCUSED"), std::string::npos);
  EXPECT_EQ(u.mode, RunMode::Running);
  // READY twice does not begin twice.
  SessionStateMachine n;
  n.on_state_changed(SessionState::Idle);
  EXPECT_TRUE(n.on_state_changed(SessionState::Ready).begin_session);
  EXPECT_FALSE(n.on_state_changed(SessionState::Ready).begin_session);
}

bool valid_name(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.';
  });
}

TEST(Actions, BindingsExistInTheirProfilesAndCoverTheActions) {
  const ActionSetDef set = curvlab_action_set();
  EXPECT_TRUE(valid_name(set.name));
  std::set<std::string> names;
  for (const auto& a : set.actions) {
    EXPECT_TRUE(valid_name(a.name)) << a.name;
    names.insert(a.name);
  }
  ASSERT_EQ(set.profiles.size(), 4u);
  for (const auto& p : set.profiles) {
    const auto offered = profile_input_paths(p.profile);
    ASSERT_FALSE(offered.empty()) << p.profile;
    for (const auto& b : p.bindings) {
      EXPECT_TRUE(names.count(b.action)) << b.action;
      EXPECT_NE(std::find(offered.begin(), offered.end(), b.path), offered.end())
          << p.profile << " has no " << b.path;
      // A binding's hand must be one of its action's subaction paths.
      const auto& action = *std::find_if(set.actions.begin(), set.actions.end(),
                                         [&](const ActionDef& a) { return a.name == b.action; });
      EXPECT_TRUE(std::any_of(action.subaction_paths.begin(), action.subaction_paths.end(),
                              [&](const std::string& hand) { return b.path.rfind(hand, 0) == 0; }))
          << b.path;
    }
  }
  // The Touch, Index and Vive profiles bind every action, both poses for
  // both hands.
  EXPECT_EQ(set.profiles[1].profile, "/interaction_profiles/oculus/touch_controller");
  EXPECT_EQ(set.profiles[2].profile, "/interaction_profiles/valve/index_controller");
  EXPECT_EQ(set.profiles[3].profile, "/interaction_profiles/htc/vive_controller");
  for (std::size_t i = 1; i < set.profiles.size(); ++i) {
    std::set<std::string> bound;
    for (const auto& b : set.profiles[i].bindings) bound.insert(b.action);
    EXPECT_EQ(bound, names) << set.profiles[i].profile;
  }
}

// Controller events carry the button names protocols bind (docs/protocols.md,
// "Key and button names"): a protocol with buttons = ["a"] must be answerable.
TEST(Actions, EventsUseTheProtocolsButtonNames) {
  const std::set<std::string> protocol_buttons = {"a", "b", "x", "y", "left_trigger", "right_trigger"};
  std::set<std::string> produced;
  for (const auto& a : curvlab_action_set().actions) {
    if (a.type == ActionType::Pose) continue;
    for (const auto& hand : a.subaction_paths) produced.insert(protocol_button(a.name, hand == kLeftHand));
  }
  EXPECT_EQ(produced, protocol_buttons);
  EXPECT_EQ(protocol_button("button_x", true), "x");
  EXPECT_EQ(protocol_button("trigger", false), "right_trigger");
}

TEST(Views, QuaternionOrderAndFov) {
  // 90° about +y: the OpenXR forward −z turns to −x.
  const float h = static_cast<float>(std::sqrt(0.5));
  XrPosef pose{};
  pose.orientation = {0.0f, h, 0.0f, h};  // x, y, z, w
  pose.position = {0.1f, 1.6f, -0.2f};
  const StagePose lab = to_stage_pose(pose);
  const glm::dvec3 forward = lab.orientation * glm::dvec3(0.0, 0.0, -1.0);
  EXPECT_NEAR(forward.x, -1.0, 1e-6);
  EXPECT_NEAR(forward.z, 0.0, 1e-6);
  EXPECT_NEAR(lab.position_m.y, 1.6, 1e-6);
  EXPECT_NEAR(lab.position_m.z, -0.2, 1e-6);
  XrFovf fov{-0.9f, 0.8f, 0.85f, -0.95f};  // left, right, up, down
  const AsymmetricFov f = to_fov(fov);
  EXPECT_NEAR(f.left_rad, -0.9, 1e-6);
  EXPECT_NEAR(f.down_rad, -0.95, 1e-6);
  const FrustumTangents t = tangents(f);
  EXPECT_NEAR(t.left, std::tan(-0.9), 1e-6);
  EXPECT_NEAR(t.up, std::tan(0.85), 1e-6);
}

}  // namespace
