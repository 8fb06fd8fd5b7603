// The real `curvlab` with `--backend xr`, through the real Khronos loader, on
// the scripted test runtime (tests/xr/runtime): a headset that cannot exist
// on this machine. The runtime logs what it handed out (predicted display
// times, head poses, controller presses, session states) and the images it
// received; the tests check the session database against that log.
#include "../cli/run_cli.hpp"
#include "../runner/session_db.hpp"
#include "../support/png_files.hpp"
#include "runtime_env.hpp"

#include "curvlab/renderer/image_io.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <unistd.h>

namespace {

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_cli;
using curvlab::testing::RuntimeEnv;
const std::string& kPresses = curvlab::testing::kScriptedPresses;
namespace fs = std::filesystem;

const std::string kProtocol = std::string(CURVLAB_SOURCE_DIR) + "/tests/xr/demo_buttons.toml";

// Differences between the same instant read on CLOCK_MONOTONIC and on the
// session clock (steady_clock, the same clock read a moment later) stay far
// below one frame period (11.1 ms at 90 Hz): "the same frame" is within 50 µs.
constexpr std::int64_t kSameInstantNs = 50'000;

// The runtime's log (runtime.cpp documents its lines).
struct RuntimeLog {
  struct Frame {
    std::int64_t mono_ns = 0;
    double head[7]{};  // x y z qx qy qz qw
  };
  std::vector<Frame> frames;
  std::vector<std::string> states;
  std::vector<std::pair<std::string, std::int64_t>> presses;  // "button_a /user/hand/right", down time
  std::map<std::int64_t, std::string> captures;               // monotonic display time → PNG
  std::vector<std::string> problems;                          // violation and warning lines
  std::vector<std::string> lines;

  explicit RuntimeLog(const fs::path& path) {
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
      lines.push_back(line);
      std::istringstream s(line);
      std::string kind;
      s >> kind;
      if (kind == "frame") {
        Frame f;
        std::string word;
        long long index = 0, xr = 0, mono = 0;
        s >> index >> word >> xr >> word >> mono >> word;
        f.mono_ns = mono;
        for (double& v : f.head) s >> v;
        frames.push_back(f);
      } else if (kind == "state") {
        std::string name;
        s >> name;
        states.push_back(name);
      } else if (kind == "input") {
        std::string action, hand, word;
        double value = 0.0;
        long long mono = 0;
        s >> action >> hand >> value >> word >> mono;
        if (value > 0.5) presses.emplace_back(action + " " + hand, mono);
      } else if (kind == "capture") {
        std::string file, word;
        long long mono = 0;
        s >> file >> word >> mono;
        captures[mono] = file;
      } else if (kind == "violation" || kind == "warning") {
        problems.push_back(line);
      }
    }
  }

  // The frame whose predicted display time is t (session clock), if any.
  [[nodiscard]] const Frame* frame_at(std::int64_t t_ns) const {
    auto it = std::lower_bound(frames.begin(), frames.end(), t_ns - kSameInstantNs,
                               [](const Frame& f, std::int64_t t) { return f.mono_ns < t; });
    return it != frames.end() && std::llabs(it->mono_ns - t_ns) <= kSameInstantNs ? &*it : nullptr;
  }
  [[nodiscard]] std::string capture_at(std::int64_t t_ns) const {
    auto it = captures.lower_bound(t_ns - kSameInstantNs);
    return it != captures.end() && std::llabs(it->first - t_ns) <= kSameInstantNs ? it->second : "";
  }
};

// The cloth (0.10, 0.42, 0.20), lit: green well above red and blue
// (tests/desktop/test_desktop_window.cpp).
bool cloth(const std::uint8_t* p) { return p[1] > 40 && p[1] > p[0] + 25 && p[1] > p[2] + 15; }

std::array<double, 3> rotate(const double q[4], const std::array<double, 3>& v) {
  // v + 2 q⃗ × (q⃗ × v + w v), q = (x, y, z, w)
  const std::array<double, 3> u{q[0], q[1], q[2]};
  auto cross = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return std::array<double, 3>{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  const auto c1 = cross(u, v);
  const std::array<double, 3> t{c1[0] + q[3] * v[0], c1[1] + q[3] * v[1], c1[2] + q[3] * v[2]};
  const auto c2 = cross(u, t);
  return {v[0] + 2 * c2[0], v[1] + 2 * c2[1], v[2] + 2 * c2[2]};
}

// Where the table-top centre (0, 0.76, 0) appears in the left eye, as a
// fraction of the image width and height: a pinhole with the runtime's
// left-eye field of view (angles −0.87, 0.72, 0.80, −0.88 rad) at the eye
// 32 mm left of the logged head pose.
std::pair<double, double> table_centre_in_left_eye(const RuntimeLog::Frame& f) {
  const double* q = f.head + 3;
  const auto off = rotate(q, {-0.032, 0.0, 0.0});
  const std::array<double, 3> eye{f.head[0] + off[0], f.head[1] + off[1], f.head[2] + off[2]};
  const double qi[4] = {-q[0], -q[1], -q[2], q[3]};
  const auto v = rotate(qi, {0.0 - eye[0], 0.76 - eye[1], 0.0 - eye[2]});
  const double tx = v[0] / -v[2], ty = v[1] / -v[2];
  const double l = std::tan(-0.87), r = std::tan(0.72), u = std::tan(0.80), d = std::tan(-0.88);
  return {(tx - l) / (r - l), (u - ty) / (u - d)};
}

TEST(XrSession, CheckNamesTheTestRuntime) {
  RuntimeEnv env({});
  const auto text = run_cli("xr-check");
  EXPECT_EQ(text.exit_code, 0) << text.out;
  EXPECT_NE(text.out.find("curvlab test runtime 0.1.0"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("curvlab scripted headset"), std::string::npos) << text.out;
  const auto json = run_cli("xr-check --json");
  ASSERT_EQ(json.exit_code, 0) << json.out;
  const auto doc = nlohmann::json::parse(json.out.substr(json.out.find('{')));
  EXPECT_EQ(doc["ok"], true);
  EXPECT_EQ(doc["runtime"], "curvlab test runtime 0.1.0");
  EXPECT_EQ(doc["system"], "curvlab scripted headset");
  EXPECT_EQ(doc["position_tracking"], true);
  // XR_KHR_vulkan_enable2 and XR_KHR_convert_timespec_time from the runtime
  // (and whatever the loader adds), by name in both forms.
  const auto& extensions = doc["extensions"];
  ASSERT_TRUE(extensions.is_array());
  for (const char* name : {"XR_KHR_vulkan_enable2", "XR_KHR_convert_timespec_time"}) {
    EXPECT_NE(std::find(extensions.begin(), extensions.end(), name), extensions.end()) << name;
    EXPECT_NE(text.out.find(name), std::string::npos) << text.out;
  }
}

TEST(XrSession, DemoRunsThroughTheRuntimeWithControllersAndAFocusLoss) {
  const auto dir = fresh_dir("demo");
  const auto captures = dir / "captures";
  fs::create_directories(captures);
  const auto db = dir / "xr.db";
  const auto log_path = dir / "runtime.log";
  // Focus goes 3.15 s after it first came: 0.35 s after the fourth press,
  // i.e. in the middle of the fifth trial's stimulus; it returns 0.4 s later.
  // With the Vulkan validation layer on (it prints its errors to stdout):
  // the runtime and curvlab share the device, the queue and the images.
  RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                  {"CURVLAB_TEST_XR_UNFOCUS", "3.15+0.4"},
                  {"VK_INSTANCE_LAYERS", "VK_LAYER_KHRONOS_validation"},
                  {"CURVLAB_TEST_XR_CAPTURE_DIR", captures.string()},
                  {"CURVLAB_TEST_XR_LOG", log_path.string()}});
  const auto r = run_cli("run " + kProtocol + " --participant X01 --backend xr --db " + db.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(curvlab::testing::without_layer_banner(r.out).find("Validation"), std::string::npos) << r.out;
  const auto doc = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(doc["status"], "completed");
  EXPECT_EQ(doc["trials_completed"], 8);
  EXPECT_EQ(doc["attempts_repeated"], 1);

  const RuntimeLog log(log_path);
  EXPECT_TRUE(log.problems.empty()) << "the runtime saw broken rules:\n" << log.problems.front();
  // The lifecycle: READY → xrBeginSession → SYNCHRONIZED … FOCUSED, the focus
  // spell, and at the end curvlab's own exit request stepping down to
  // STOPPING → xrEndSession → IDLE → EXITING; nothing else.
  const std::vector<std::string> states = {
      "XR_SESSION_STATE_IDLE",         "XR_SESSION_STATE_READY",    "XR_SESSION_STATE_SYNCHRONIZED",
      "XR_SESSION_STATE_VISIBLE",      "XR_SESSION_STATE_FOCUSED",  "XR_SESSION_STATE_VISIBLE",
      "XR_SESSION_STATE_FOCUSED",      "XR_SESSION_STATE_VISIBLE",  "XR_SESSION_STATE_SYNCHRONIZED",
      "XR_SESSION_STATE_STOPPING",     "XR_SESSION_STATE_IDLE",     "XR_SESSION_STATE_EXITING"};
  EXPECT_EQ(log.states, states);
  // An orderly exit: the session was ended before it was destroyed.
  EXPECT_EQ(std::find(log.lines.begin(), log.lines.end(), "note xrDestroySession while the session is running"),
            log.lines.end());
  // A completed run tells the experimenter nothing about pauses or exits.
  EXPECT_EQ(r.out.find("asked curvlab to exit"), std::string::npos) << r.out;
  ASSERT_GT(log.frames.size(), 100u);

  const auto session = query(db, "SELECT backend, display_refresh_hz, status FROM sessions");
  ASSERT_EQ(session.size(), 1u);
  EXPECT_EQ(session[0][0], "xr");
  EXPECT_EQ(std::stod(session[0][1]), 90.0);
  EXPECT_EQ(session[0][2], "completed");

  // Every onset is the predicted display time of a frame the runtime handed
  // out, and that frame's left-eye image, as the runtime received it, shows
  // the table where a pinhole with the runtime's field of view puts it.
  const auto trials = query(db,
                            "SELECT trial_index, status, attempt, onset_ns, response, response_device, response_ns "
                            "FROM trials ORDER BY trial_index");
  ASSERT_EQ(trials.size(), 8u);
  std::map<std::string, int> answers;
  for (const auto& t : trials) {
    SCOPED_TRACE("trial " + t[0]);
    EXPECT_EQ(t[1], "completed");
    const std::int64_t onset = std::stoll(t[3]);
    const RuntimeLog::Frame* frame = log.frame_at(onset);
    ASSERT_NE(frame, nullptr) << "onset " << onset << " is no predicted display time the runtime gave";
    const std::string png = log.capture_at(onset);
    ASSERT_FALSE(png.empty()) << "no capture of the onset frame";
    curvlab::renderer::Rgba8Image img;
    ASSERT_TRUE(curvlab::test::read_png_into(png, img));
    ASSERT_EQ(img.width, 320);
    const auto w = static_cast<std::size_t>(img.width), h = static_cast<std::size_t>(img.height);
    const auto at = [&img](double fx, double fy) {
      const auto x = static_cast<std::size_t>(fx * img.width), y = static_cast<std::size_t>(fy * img.height);
      return &img.pixels[4 * (y * static_cast<std::size_t>(img.width) + x)];
    };
    int in_box = 0, box = 0, top = 0;
    double sum_x = 0.0;
    int total = 0;
    for (std::size_t y = 0; y < h; ++y)
      for (std::size_t x = 0; x < w; ++x) {
        const double fx = (static_cast<double>(x) + 0.5) / static_cast<double>(w);
        const double fy = (static_cast<double>(y) + 0.5) / static_cast<double>(h);
        const bool c = cloth(&img.pixels[4 * (y * w + x)]);
        if (fx > 0.4 && fx < 0.8 && fy > 0.6 && fy < 0.8) {
          ++box;
          in_box += c ? 1 : 0;
        }
        if (fy < 0.35) top += c ? 1 : 0;
        if (c) {
          sum_x += fx;
          ++total;
        }
      }
    EXPECT_GT(in_box, 0.8 * box) << "cloth below and right of the centre: " << png;
    EXPECT_EQ(top, 0) << "cloth in the upper third: " << png;
    const auto [cx, cy] = table_centre_in_left_eye(*frame);
    EXPECT_TRUE(cloth(at(cx, cy))) << "the table-top centre (" << cx << ", " << cy << ") is not cloth: " << png;
    // The left eye's wider outer half puts the table right of the image
    // centre; a symmetric field of view would put it near 0.52.
    ASSERT_GT(total, 0);
    EXPECT_NEAR(sum_x / total, cx, 0.03) << png;

    // Answers: A is "straight", X "convex", the right trigger "concave"
    // (demo_buttons.toml); the response time is the runtime's press time.
    static const std::map<std::string, std::pair<std::string, std::string>> by_answer = {
        {"straight", {"xr:right", "button_a /user/hand/right"}},
        {"convex", {"xr:left", "button_x /user/hand/left"}},
        {"concave", {"xr:right", "trigger /user/hand/right"}}};
    ASSERT_EQ(by_answer.count(t[4]), 1u) << "answer " << t[4];
    const auto& [device, input] = by_answer.at(t[4]);
    EXPECT_EQ(t[5], device);
    ++answers[t[4]];
    const std::int64_t response = std::stoll(t[6]);
    const bool pressed = std::any_of(log.presses.begin(), log.presses.end(), [&](const auto& p) {
      return std::llabs(p.second - response) <= kSameInstantNs && p.first == input;
    });
    EXPECT_TRUE(pressed) << "response at " << response << " is no press of " << input;
  }
  // All three inputs answered (boolean actions of both hands and the float
  // trigger through its press threshold).
  EXPECT_EQ(answers.size(), 3u);

  // The focus loss aborted a trial (reason pause) and it was run again.
  const auto aborted = query(db, "SELECT trial_id, json_extract(detail, '$.reason') FROM events "
                                 "WHERE kind = 'trial_aborted'");
  ASSERT_EQ(aborted.size(), 1u);
  EXPECT_EQ(aborted[0][1], "pause");
  EXPECT_EQ(query(db, "SELECT attempt FROM trials WHERE trial_id = " + aborted[0][0])[0][0], "2");
  EXPECT_EQ(query(db, "SELECT count(*) FROM events WHERE kind = 'trial_repeated' AND "
                      "json_extract(detail, '$.reason') = 'pause'")[0][0],
            "1");
  // Without focus the runtime reports the hands untracked.
  EXPECT_GT(std::stoi(query(db, "SELECT count(*) FROM tracking_samples WHERE device = 'right_hand' "
                                "AND position_valid = 0")[0][0]),
            10);

  // Every head sample is the runtime's scripted pose at that frame's
  // predicted display time; the head sways.
  const auto heads = query(db, "SELECT t_ns, lab_px_m, lab_py_m, lab_pz_m, lab_qx, lab_qy, lab_qz, lab_qw, "
                               "position_valid FROM tracking_samples WHERE device = 'head' ORDER BY t_ns");
  ASSERT_GT(heads.size(), 100u);
  double min_x = 1.0, max_x = -1.0;
  int mismatched = 0;
  for (const auto& h : heads) {
    const RuntimeLog::Frame* f = log.frame_at(std::stoll(h[0]));
    if (f == nullptr || h[8] != "1") {
      ++mismatched;
      continue;
    }
    double dq = 0.0, dq_flip = 0.0, dp = 0.0;
    for (int k = 0; k < 3; ++k) dp = std::max(dp, std::abs(std::stod(h[1 + k]) - f->head[k]));
    for (int k = 0; k < 4; ++k) {
      dq = std::max(dq, std::abs(std::stod(h[4 + k]) - f->head[3 + k]));
      dq_flip = std::max(dq_flip, std::abs(std::stod(h[4 + k]) + f->head[3 + k]));
    }
    if (dp > 1e-5 || std::min(dq, dq_flip) > 1e-5) ++mismatched;
    min_x = std::min(min_x, f->head[0]);
    max_x = std::max(max_x, f->head[0]);
  }
  EXPECT_EQ(mismatched, 0) << "of " << heads.size() << " head samples";
  EXPECT_GT(max_x - min_x, 0.005) << "the sway";
  fs::remove_all(dir);
}

// Replay redraws an OpenXR session's onset frames from the recorded views —
// the runtime's asymmetric fields of view and eye poses, its swapchain size —
// pixel for pixel as the runtime received the left eye's image.
TEST(XrSession, ReplayReproducesTheOnsetFrameTheRuntimeReceived) {
  const auto dir = fresh_dir("replay");
  const auto captures = dir / "captures";
  fs::create_directories(captures);
  const auto db = dir / "xr.db";
  const auto log_path = dir / "runtime.log";
  {
    // A swapchain that is neither square nor the protocol's resolution.
    RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                    {"CURVLAB_TEST_XR_SIZE", "288x256"},
                    {"CURVLAB_TEST_XR_CAPTURE_DIR", captures.string()},
                    {"CURVLAB_TEST_XR_LOG", log_path.string()}});
    const auto r = run_cli("run " + kProtocol + " --participant X03 --backend xr --db " + db.string() + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.out;
  }
  const RuntimeLog log(log_path);
  const auto trials = query(db, "SELECT trial_index, onset_ns FROM trials WHERE trial_index IN (1, 6) "
                                "ORDER BY trial_index");
  ASSERT_EQ(trials.size(), 2u);
  for (const auto& t : trials) {
    SCOPED_TRACE("trial " + t[0]);
    const std::string png = log.capture_at(std::stoll(t[1]));
    ASSERT_FALSE(png.empty()) << "no capture of the onset frame";
    const auto out = dir / ("replay" + t[0]);
    const auto rp = run_cli("replay --db " + db.string() + " --session 1 --trial " + t[0] + " --out " +
                            out.string() + " --software");
    ASSERT_EQ(rp.exit_code, 0) << rp.out;
    std::ifstream json(out / "replay.json");
    EXPECT_EQ(nlohmann::json::parse(json)["eye_geometry"], "recorded");
    curvlab::renderer::Rgba8Image received, replayed;
    ASSERT_TRUE(curvlab::test::read_png_into(png, received));
    ASSERT_TRUE(curvlab::test::read_png_into((out / "left.png").string(), replayed));
    EXPECT_EQ(replayed.width, 288);
    EXPECT_EQ(replayed.height, 256);
    const auto diff = curvlab::renderer::diff_images(received, replayed, 0);
    EXPECT_EQ(diff.differing_pixels, 0) << png << ": largest channel difference " << diff.max_channel_diff;
  }
  fs::remove_all(dir);
}

TEST(XrSession, RuntimeExitRequestLeavesTheSessionResumable) {
  const auto dir = fresh_dir("exit");
  const auto db = dir / "xr.db";
  const auto log_path = dir / "runtime.log";
  {
    RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                    {"CURVLAB_TEST_XR_EXIT", "2.5"},
                    {"CURVLAB_TEST_XR_LOG", log_path.string()}});
    const auto r = run_cli("run " + kProtocol + " --participant X02 --backend xr --db " + db.string() + " --quiet");
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find("the OpenXR runtime is stopping the session"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("curvlab resume --db " + db.string() + " --session 1"), std::string::npos) << r.out;
  }
  {
    const RuntimeLog log(log_path);
    EXPECT_TRUE(log.problems.empty()) << log.problems.front();
    // STOPPING came down through VISIBLE and SYNCHRONIZED; curvlab ended the
    // session (xrEndSession is refused in any other state) and left on EXITING.
    const std::vector<std::string> tail = {"XR_SESSION_STATE_VISIBLE", "XR_SESSION_STATE_SYNCHRONIZED",
                                           "XR_SESSION_STATE_STOPPING", "XR_SESSION_STATE_IDLE",
                                           "XR_SESSION_STATE_EXITING"};
    ASSERT_GE(log.states.size(), tail.size());
    EXPECT_TRUE(std::equal(tail.begin(), tail.end(), log.states.end() - static_cast<std::ptrdiff_t>(tail.size())));
    EXPECT_NE(std::find(log.lines.begin(), log.lines.end(), "instance destroyed"), log.lines.end());
  }
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  const int done = std::stoi(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0]);
  EXPECT_GT(done, 0);
  EXPECT_LT(done, 8);

  // Resumed with the headset back, it finishes: every trial exactly once.
  RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses}, {"CURVLAB_TEST_XR_LOG", log_path.string() + "2"}});
  const auto r = run_cli("resume --db " + db.string() + " --session 1 --backend xr --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(query(db, "SELECT status, backend FROM sessions")[0], (std::vector<std::string>{"completed", "xr"}));
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0], "8");
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE response_device NOT IN ('xr:left', 'xr:right')")[0][0],
            "0");
  EXPECT_TRUE(RuntimeLog(log_path.string() + "2").problems.empty());
  fs::remove_all(dir);
}

TEST(XrSession, ALostSessionIsLeftWithoutEndingItAndResumes) {
  // LOSS_PENDING (headset unplugged, runtime going away): curvlab must not
  // call xrEndSession, which the runtime refuses outside STOPPING; frame
  // calls then fail XR_ERROR_SESSION_LOST. The session stays resumable.
  const auto dir = fresh_dir("loss");
  const auto db = dir / "xr.db";
  const auto log_path = dir / "runtime.log";
  {
    RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                    {"CURVLAB_TEST_XR_LOSS", "2.5"},
                    {"CURVLAB_TEST_XR_LOG", log_path.string()}});
    const auto r = run_cli("run " + kProtocol + " --participant X03 --backend xr --db " + db.string() + " --quiet");
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find("curvlab resume --db " + db.string() + " --session 1"), std::string::npos) << r.out;
  }
  {
    const RuntimeLog log(log_path);
    EXPECT_TRUE(log.problems.empty()) << log.problems.front();
    ASSERT_FALSE(log.states.empty());
    EXPECT_EQ(log.states.back(), "XR_SESSION_STATE_LOSS_PENDING");
    EXPECT_EQ(std::count_if(log.lines.begin(), log.lines.end(),
                            [](const std::string& l) { return l.rfind("end_session", 0) == 0; }),
              0)
        << "xrEndSession was called on a session being lost";
  }
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses}, {"CURVLAB_TEST_XR_LOG", log_path.string() + "2"}});
  const auto r = run_cli("resume --db " + db.string() + " --session 1 --backend xr --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0], "8");
  fs::remove_all(dir);
}

TEST(XrSession, ButtonsAreReadFromAFreshSyncWhenFocusReturns) {
  // The demo's presses with a focus loss in the fifth trial's stimulus
  // (3.15 s to 3.55 s after focus), X pressed and released while unfocused
  // (the demo's own, at 3.4 s), and the right trigger pulled at 3.5 s and held
  // across the return until 3.8 s: neither may answer or count as an input.
  const auto dir = fresh_dir("refocus");
  const auto db = dir / "xr.db";
  const auto log_path = dir / "runtime.log";
  {
    RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses + ",right:trigger@3.5~0.3"},
                    {"CURVLAB_TEST_XR_UNFOCUS", "3.15+0.4"},
                    {"CURVLAB_TEST_XR_LOG", log_path.string()}});
    const auto r = run_cli("run " + kProtocol + " --participant X06 --backend xr --db " + db.string() + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
  }
  const RuntimeLog log(log_path);
  EXPECT_TRUE(log.problems.empty()) << log.problems.front();
  // Every action-state read while FOCUSED follows an xrSyncActions made
  // while FOCUSED in the same frame (OpenXR 1.0 §11.5: states are those of
  // the last sync, which before the focus loss are stale).
  std::int64_t frame = -1, synced = -2, reads = 0;
  std::vector<std::string> stale;
  for (const auto& line : log.lines) {
    std::istringstream in(line);
    std::string kind, word;
    in >> kind;
    if (kind == "frame") {
      in >> frame;
    } else if (kind == "sync_actions") {
      std::int64_t n = 0;
      int focused = 0;
      in >> word >> n >> word >> focused;
      synced = focused == 1 ? n : -2;
    } else if (kind == "action_state") {
      std::string call, action;
      std::int64_t n = 0;
      int focused = 0;
      in >> call >> action >> word >> n >> word >> focused;
      ++reads;
      if (focused == 1 && (n != frame || synced != frame)) stale.push_back(line);
    }
  }
  EXPECT_GT(reads, 100);
  EXPECT_TRUE(stale.empty()) << stale.size() << " reads without a sync in their frame, the first: " << stale.front();

  // The focus loss repeated the fifth trial, and every trial was answered.
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0], "8");
  EXPECT_EQ(query(db, "SELECT count(*) FROM events WHERE kind = 'trial_aborted'")[0][0], "1");
  // Every input the session stored (answers and anticipations) is a press
  // the runtime delivered while focused, at its time: none is a state from
  // before the focus loss, a press made without focus, or the trigger held
  // across the return.
  auto is_press = [&log](std::int64_t t_ns) {
    return std::any_of(log.presses.begin(), log.presses.end(),
                       [&](const auto& p) { return std::llabs(p.second - t_ns) <= kSameInstantNs; });
  };
  for (const auto& row : query(db, "SELECT response_ns FROM trials"))
    EXPECT_TRUE(is_press(std::stoll(row[0]))) << "answer at " << row[0] << " is no press";
  for (const auto& row : query(db, "SELECT json_extract(detail, '$.t_ns'), json_extract(detail, '$.name') "
                                   "FROM events WHERE kind = 'early_input'"))
    EXPECT_TRUE(is_press(std::stoll(row[0]))) << "early input " << row[1] << " at " << row[0] << " is no press";
  fs::remove_all(dir);
}

TEST(XrSession, PausesKeepAnImageInTheHeadset) {
  // A focus loss (3.15 s to 3.55 s after focus) and the operator's pause and
  // resume: every frame the runtime shows (VISIBLE or FOCUSED, shouldRender)
  // ends with a layer, so the participant never sees a black refresh.
  const auto dir = fresh_dir("pause_layers");
  const auto db = dir / "xr.db";
  const auto log_path = dir / "runtime.log";
  const auto script = dir / "ops.txt";
  std::ofstream(script) << "4.7 pause\n5.3 resume\n";
  RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                  {"CURVLAB_TEST_XR_UNFOCUS", "3.15+0.4"},
                  {"CURVLAB_TEST_XR_LOG", log_path.string()}});
  const auto r = run_cli("run " + kProtocol + " --participant X07 --backend xr --db " + db.string() +
                         " --operator-window off --operator-script " + script.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0], "8");
  EXPECT_EQ(query(db, "SELECT count(*) FROM events WHERE kind = 'operator_action' AND "
                      "json_extract(detail, '$.action') = 'pause'")[0][0],
            "1");
  // Both pauses interrupted the session (a trial's attempt, a page or the interval).
  const int paused = std::stoi(query(db, "SELECT count(*) FROM events WHERE kind IN ('trial_aborted', 'paused')")[0][0]);
  EXPECT_GE(paused, 2);

  const RuntimeLog log(log_path);
  EXPECT_TRUE(log.problems.empty()) << log.problems.front();
  int shown = 0;
  std::vector<std::string> black;
  for (const auto& line : log.lines) {
    std::istringstream in(line);
    std::string kind, word, state;
    long long index = 0, layers = 0;
    int render = 0;
    in >> kind;
    if (kind != "end_frame") continue;
    in >> index >> word >> layers >> word >> state >> word >> render;
    const bool visible = state == "XR_SESSION_STATE_VISIBLE" || state == "XR_SESSION_STATE_FOCUSED";
    if (!visible || render != 1) continue;
    ++shown;
    if (layers == 0) black.push_back(line);
  }
  EXPECT_GT(shown, 300);
  EXPECT_TRUE(black.empty()) << black.size() << " frames shown without a layer, the first: " << black.front();
  fs::remove_all(dir);
}

// A copy of the demo protocol with `extra` appended (a [tracking] section).
fs::path protocol_with(const fs::path& dir, const std::string& extra) {
  const auto path = dir / "protocol.toml";
  std::ifstream in(kProtocol);
  std::ostringstream text;
  text << in.rdbuf() << "\n" << extra << "\n";
  std::ofstream(path) << text.str();
  return path;
}

// The program under a time limit: a session that waits forever for the head
// is killed (exit 124) instead of hanging the test.
curvlab::testing::CliResult run_cli_within(int seconds, const std::string& args) {
  return curvlab::testing::run_shell("timeout -k 5 " + std::to_string(seconds) + " " + std::string(CURVLAB_BIN) + " " +
                                     args + " 2>&1");
}

TEST(XrSession, AHeadWithoutPositionTrackingStopsTheSessionResumably) {
  // Monado's simulated headset: orientation tracked, position valid but not
  // tracked. The demo protocol asks for a position-tracked head (the
  // default): the first trial is lost, the session waits its 10 s for the
  // head, then stops interrupted with the runtime's flags, and resumes.
  const auto dir = fresh_dir("orientation_only");
  const auto db = dir / "xr.db";
  const auto log_path = dir / "runtime.log";
  {
    RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                    {"CURVLAB_TEST_XR_HEAD", "orientation_only"},
                    {"CURVLAB_TEST_XR_LOG", log_path.string()}});
    const auto r =
        run_cli_within(60, "run " + kProtocol + " --participant X04 --backend xr --db " + db.string() + " --quiet");
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find("head_requires = \"position\""), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("ORIENTATION_TRACKED | POSITION_VALID | no POSITION_TRACKED"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("curvlab resume --db " + db.string() + " --session 1"), std::string::npos) << r.out;
    EXPECT_TRUE(RuntimeLog(log_path).problems.empty());
  }
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0], "0");
  const auto aborted = query(db, "SELECT json_extract(detail, '$.reason') FROM events WHERE kind = 'trial_aborted'");
  ASSERT_EQ(aborted.size(), 1u);
  EXPECT_EQ(aborted[0][0], "tracking_lost");
  // The head's samples are stored with their (inferred) positions.
  EXPECT_EQ(query(db, "SELECT count(*) FROM tracking_samples WHERE device = 'head' AND position_valid = 0")[0][0],
            "0");

  RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses}, {"CURVLAB_TEST_XR_LOG", log_path.string() + "2"}});
  const auto r = run_cli_within(60, "resume --db " + db.string() + " --session 1 --backend xr --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0], "8");
  fs::remove_all(dir);
}

TEST(XrSession, AHeadWithoutPositionTrackingRunsWhereTheProtocolAsksLess) {
  for (const std::string need : {"orientation", "none"}) {
    SCOPED_TRACE(need);
    const auto dir = fresh_dir("head_requires_" + need);
    const auto db = dir / "xr.db";
    const auto log_path = dir / "runtime.log";
    const auto protocol = protocol_with(dir, "[tracking]\nhead_requires = \"" + need + "\"");
    RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                    {"CURVLAB_TEST_XR_HEAD", "orientation_only"},
                    {"CURVLAB_TEST_XR_LOG", log_path.string()}});
    const auto r = run_cli_within(60, "run " + protocol.string() + " --participant X05 --backend xr --db " +
                                          db.string() + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");
    EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0], "8");
    EXPECT_EQ(query(db, "SELECT count(*) FROM events WHERE kind = 'trial_aborted'")[0][0], "0");
    EXPECT_TRUE(RuntimeLog(log_path).problems.empty());
    fs::remove_all(dir);
  }
}

TEST(XrSession, TheRuntimeStoppingAndStartingTheSessionAgainPausesTheTrial) {
  // 3.15 s after focus, in the fifth trial's stimulus, the runtime stops the
  // session (STOPPING → xrEndSession → IDLE) and makes it READY again 0.6 s
  // later: the trial in flight is paused and run again, as for a focus loss,
  // and the session completes.
  const auto dir = fresh_dir("restart");
  const auto db = dir / "xr.db";
  const auto log_path = dir / "runtime.log";
  RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                  {"CURVLAB_TEST_XR_RESTART", "3.15+0.6"},
                  {"CURVLAB_TEST_XR_LOG", log_path.string()}});
  const auto r = run_cli_within(60, "run " + kProtocol + " --participant X08 --backend xr --db " + db.string() +
                                        " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const RuntimeLog log(log_path);
  EXPECT_TRUE(log.problems.empty()) << log.problems.front();
  const std::vector<std::string> restart = {"XR_SESSION_STATE_VISIBLE", "XR_SESSION_STATE_SYNCHRONIZED",
                                            "XR_SESSION_STATE_STOPPING", "XR_SESSION_STATE_IDLE",
                                            "XR_SESSION_STATE_READY",   "XR_SESSION_STATE_SYNCHRONIZED",
                                            "XR_SESSION_STATE_VISIBLE", "XR_SESSION_STATE_FOCUSED"};
  EXPECT_NE(std::search(log.states.begin(), log.states.end(), restart.begin(), restart.end()), log.states.end());
  EXPECT_EQ(std::count_if(log.lines.begin(), log.lines.end(),
                          [](const std::string& l) { return l.rfind("begin_session", 0) == 0; }),
            2);

  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0], "8");
  const auto aborted = query(db, "SELECT trial_id, json_extract(detail, '$.reason') FROM events "
                                 "WHERE kind = 'trial_aborted'");
  ASSERT_EQ(aborted.size(), 1u);
  EXPECT_EQ(aborted[0][1], "pause");
  EXPECT_EQ(query(db, "SELECT attempt FROM trials WHERE trial_id = " + aborted[0][0])[0][0], "2");
  // The trial's answer came after the session ran again: the repeated
  // attempt's onset is after the runtime made it READY.
  std::int64_t restarted = 0;  // the last READY (monotonic ns), the restart's
  for (const auto& line : log.lines)
    if (line.rfind("state XR_SESSION_STATE_READY", 0) == 0) restarted = std::stoll(line.substr(line.rfind(' ') + 1));
  ASSERT_GT(restarted, 0);
  EXPECT_GT(std::stoll(query(db, "SELECT onset_ns FROM trials WHERE trial_id = " + aborted[0][0])[0][0]), restarted);
  fs::remove_all(dir);
}

TEST(XrSession, TheOperatorCanEndASessionTheRuntimeHasStopped) {
  // The runtime stops the session 3.15 s after focus and keeps it IDLE for a
  // minute (a headset put away in standby): the trial in flight is paused at
  // once, and the operator's end (about 5 s into the session) ends the session,
  // interrupted and resumable, without waiting for the runtime.
  const auto dir = fresh_dir("stopped_end");
  const auto db = dir / "xr.db";
  const auto log_path = dir / "runtime.log";
  const auto script = dir / "ops.txt";
  std::ofstream(script) << "5 end\n";
  {
    RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses},
                    {"CURVLAB_TEST_XR_RESTART", "3.15+60"},
                    {"CURVLAB_TEST_XR_LOG", log_path.string()}});
    const auto r = run_cli_within(30, "run " + kProtocol + " --participant X09 --backend xr --db " + db.string() +
                                          " --operator-window off --operator-script " + script.string() + " --quiet");
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find("curvlab resume --db " + db.string() + " --session 1"), std::string::npos) << r.out;
    EXPECT_TRUE(RuntimeLog(log_path).problems.empty());
  }
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  const auto aborted = query(db, "SELECT json_extract(detail, '$.reason') FROM events WHERE kind = 'trial_aborted'");
  ASSERT_GE(aborted.size(), 1u);
  EXPECT_EQ(aborted[0][0], "pause");
  fs::remove_all(dir);
}

}  // namespace
