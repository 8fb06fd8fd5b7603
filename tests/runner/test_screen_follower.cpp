// A pilot who knows nothing but what the screen says: every example
// protocol, run with a participant who reads the page's continue line and
// the pilot window's key legend and presses only what they name, completes
// with every trial answered. A page that promised a key the runner ignores,
// or a legend naming a key that does not answer, would leave this
// participant waiting for ever (the session would time out trial after
// trial).
#include "in_process.hpp"
#include "session_db.hpp"

#include "curvlab/harness/desktop/desktop.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using namespace curvlab;
namespace io = harness::io;
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

// A participant at a keyboard who presses what the screen names.
class ScreenFollower {
 public:
  // Reads each frame's overlay as the pilot window shows it.
  void read(const io::Overlay& overlay) {
    const std::string legend = harness::desktop::legend_text(overlay);
    const std::string seen = std::string(io::to_string(overlay.phase)) + "\n" + overlay.text + "\n" + legend;
    if (seen == seen_) return;
    seen_ = seen;
    next_ns_ = now_ns_ + 400'000'000;
    presses_ = 0;
    key_ = "";
    if (!overlay.waiting_for_input) return;
    key_ = overlay.answers.empty() ? continue_key(overlay.text) : legend_key(legend);
    if (key_.empty()) unreadable_.push_back(seen);
  }
  // Presses 400 ms after the screen asks, and again each second while it
  // still asks (a break that must last longer ignores the first press).
  io::Signal press(std::int64_t now_ns, std::vector<io::InputEvent>& out) {
    now_ns_ = now_ns;
    // A screen that names no key would hold a page for ever: give up.
    if (!unreadable_.empty()) return io::Signal::quit;
    if (key_.empty() || now_ns < next_ns_) return io::Signal::none;
    out.push_back(harness::desktop::key_input(now_ns, key_, true));
    out.push_back(harness::desktop::key_input(now_ns, key_, false));
    next_ns_ = now_ns + 1'000'000'000;
    return ++presses_ > 600 ? io::Signal::quit : io::Signal::none;  // ten minutes on one screen: not listening
  }

  std::vector<std::string> unreadable_;  // screens that asked without saying how

 private:
  std::string seen_, key_;
  std::int64_t now_ns_ = 0, next_ns_ = 0;
  int presses_ = 0;
};

class ScreenFollowerRun : public ::testing::TestWithParam<const char*> {};

TEST_P(ScreenFollowerRun, CompletesWithEveryTrialAnswered) {
  ScreenFollower person;
  const auto out = curvlab::testing::run_protocol(GetParam(), std::string("screen_") + GetParam(), "", false,
                                                  [&](curvlab::testing::ScriptedDevices& d) {
                                                    d.reach_as = harness::desktop::keyboard_reach();
                                                    d.shown = [&](const io::Overlay& o) { person.read(o); };
                                                    d.inputs = [&](const io::FrameTiming& t, const std::string&,
                                                                   std::vector<io::InputEvent>& in) {
                                                      return person.press(t.now_ns, in);
                                                    };
                                                  });
  ASSERT_FALSE(out.db.empty());
  EXPECT_TRUE(person.unreadable_.empty()) << "a screen asked without saying how:\n" << person.unreadable_.front();
  EXPECT_EQ(out.summary.status, curvlab::harness::data::SessionStatus::completed);
  EXPECT_GT(out.summary.trials_completed, 0);
  EXPECT_EQ(query(out.db, "SELECT count(*) FROM trials WHERE status = 'completed' AND response IS NULL")[0][0], "0")
      << "trials timed out: the legend named keys that do not answer";
}

INSTANTIATE_TEST_SUITE_P(ExampleProtocols, ScreenFollowerRun,
                         ::testing::Values("demo", "one_eye_vs_two", "proposed_study", "body_coherence",
                                           "stick_pse_staircase"));

}  // namespace
