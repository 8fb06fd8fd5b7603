// A pilot who knows nothing but what the screen says: every example
// protocol, run with a participant who reads the page's continue line and
// the pilot window's key legend and presses only what they name, completes
// with every trial answered. A page that promised a key the runner ignores,
// or a legend naming a key that does not answer, would leave this
// participant waiting for ever (the session would time out trial after
// trial).
#include "session_db.hpp"

#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using namespace curvlab;
namespace io = harness::io;
namespace rn = harness::runner;
namespace pr = harness::protocol;
using curvlab::testing::fresh_dir;
using curvlab::testing::query;

// The key a page's last line names: "To continue: press space, or …" → "space".
std::string continue_key(const std::string& text) {
  const std::string cue = "To continue: press ";
  const auto at = text.rfind(cue);
  if (at == std::string::npos) return "";
  const auto from = at + cue.size();
  return text.substr(from, text.find_first_of(",. ", from) - from);
}

// The key the legend gives the answer the participant picks: the confirm of
// an adjustment, otherwise the first answer that has a key. "1/left convex"
// → "1".
std::string legend_key(const std::string& legend) {
  std::vector<std::string> entries;
  std::size_t from = legend.find("  ");  // after the question
  from = from == std::string::npos ? 0 : from + 2;
  const std::string separator = " · ";
  while (from < legend.size()) {
    const auto end = legend.find(separator, from);
    entries.push_back(legend.substr(from, end == std::string::npos ? std::string::npos : end - from));
    if (end == std::string::npos) break;
    from = end + separator.size();
  }
  std::string pick;
  for (const auto& e : entries) {
    if (e.find(": no key") != std::string::npos) continue;
    const std::string key = e.substr(0, e.find_first_of(" /"));
    if (e.find(" confirm") != std::string::npos) return key;
    if (pick.empty()) pick = key;
  }
  return pick;
}

// The headless display, seen by a participant at a keyboard who presses what
// the screen names.
class ScreenFollower final : public io::Display, public io::ResponseSource {
 public:
  ScreenFollower(rn::HeadlessDisplay& display, const devices::Clock& clock) : display_(display), clock_(clock) {}

  [[nodiscard]] io::DisplayInfo info() const override { return display_.info(); }
  std::optional<io::FrameTiming> begin_frame() override { return display_.begin_frame(); }
  renderer::StereoRig rig(const io::FrameTiming& f, double ipd_m) override { return display_.rig(f, ipd_m); }
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const io::Overlay& overlay, bool draw) override {
    const std::string seen = std::string(io::to_string(overlay.phase)) + "\n" + overlay.text + "\n" +
                             desktop::legend_text(overlay);
    if (seen != seen_) {
      seen_ = seen;
      next_ns_ = clock_.now_ns() + 400'000'000;
      presses_ = 0;
      key_ = "";
      if (overlay.waiting_for_input)
        key_ = overlay.answers.empty() ? continue_key(overlay.text) : legend_key(desktop::legend_text(overlay));
      if (overlay.waiting_for_input && key_.empty()) unreadable_.push_back(seen);
    }
    return display_.submit(scene, frame, overlay, draw);
  }
  io::Signal poll(std::vector<io::InputEvent>& out) override {
    // A screen that names no key would hold a page for ever: give up.
    if (!unreadable_.empty()) return io::Signal::quit;
    // 400 ms after the screen asks, and again each second while it still
    // asks (a break that must last longer ignores the first press).
    if (!key_.empty() && clock_.now_ns() >= next_ns_) {
      out.push_back({clock_.now_ns(), key_, "keyboard", true});
      out.push_back({clock_.now_ns(), key_, "keyboard", false});
      next_ns_ = clock_.now_ns() + 1'000'000'000;
      if (++presses_ > 600) return io::Signal::quit;  // ten minutes on one screen: it does not listen
    }
    return io::Signal::none;
  }
  [[nodiscard]] io::Reach reach() const override { return desktop::keyboard_reach(); }

  std::vector<std::string> unreadable_;  // screens that asked without saying how

 private:
  rn::HeadlessDisplay& display_;
  const devices::Clock& clock_;
  std::string seen_, key_;
  std::int64_t next_ns_ = 0;
  int presses_ = 0;
};

class ScreenFollowerRun : public ::testing::TestWithParam<const char*> {};

TEST_P(ScreenFollowerRun, CompletesWithEveryTrialAnswered) {
  const std::string path = std::string(CURVLAB_SOURCE_DIR) + "/protocols/" + GetParam() + ".toml";
  auto loaded = pr::load_protocol_file(path);
  ASSERT_TRUE(loaded.has_value()) << loaded.error().message;
  const auto& p = *loaded;
  rn::HeadlessOptions ho;
  ho.no_gpu = true;
  ho.refresh_hz = p.refresh_hz;
  auto made = rn::HeadlessDevices::create(ho, rn::standing_at(rn::nominal_calibration(p.session_settings())));
  ASSERT_TRUE(made.has_value()) << made.error().message;
  auto& headless = made.value();
  ScreenFollower person(*headless.display, headless.clock());
  rn::RunOptions o;
  o.participant = "S01";
  o.drawing = rn::FrameDrawing::none;
  const auto db = (fresh_dir(std::string("screen_") + GetParam()) / "s.sqlite").string();
  auto result = rn::run_session(p, p.text, db, o, {&person, headless.poses.get(), {&person}}, headless.clock());
  ASSERT_TRUE(result.has_value()) << result.error().message;
  EXPECT_TRUE(person.unreadable_.empty()) << "a screen asked without saying how:\n" << person.unreadable_.front();
  EXPECT_EQ(result->status, curvlab::data::SessionStatus::completed);
  EXPECT_GT(result->trials_completed, 0);
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed' AND response IS NULL")[0][0], "0")
      << "trials timed out: the legend named keys that do not answer";
}

INSTANTIATE_TEST_SUITE_P(ExampleProtocols, ScreenFollowerRun,
                         ::testing::Values("demo", "one_eye_vs_two", "proposed_study", "body_coherence",
                                           "stick_pse_staircase"));

}  // namespace
