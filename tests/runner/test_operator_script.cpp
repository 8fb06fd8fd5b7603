// The operator's actions as data: the script format (each bad line named by
// file:line), the order they come due, and what repeat and skip do to an
// attempt in the trial state machine.
#include "curvlab/harness/runner/operator.hpp"
#include "curvlab/harness/runner/trial_state.hpp"

#include <gtest/gtest.h>

namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;

namespace {

constexpr std::int64_t kS = 1'000'000'000;

std::string parse_error(const std::string& text) {
  const auto r = rn::parse_operator_script(text, "ops.txt");
  EXPECT_FALSE(r.has_value()) << text;
  return r ? std::string() : r.error().message;
}

}  // namespace

TEST(OperatorScript, ReadsActionsCommentsAndVerbatimNotes) {
  const auto r = rn::parse_operator_script(
      "# a session with everything\n"
      "\n"
      "4.5 skip   # the participant misunderstood\n"
      "1 pause\n"
      "2.25 resume\n"
      "3 note  Participant said: \"the stick # looks bent\" \n"
      "7 end\n",
      "ops.txt");
  ASSERT_TRUE(r.has_value()) << r.error().message;
  const auto& a = r.value();
  ASSERT_EQ(a.size(), 5u);
  // Sorted by time.
  EXPECT_EQ(a[0].kind, rn::OperatorActionKind::pause);
  EXPECT_EQ(a[0].at_ns, 1 * kS);
  EXPECT_EQ(a[1].kind, rn::OperatorActionKind::resume);
  EXPECT_EQ(a[1].at_ns, 2'250'000'000);
  EXPECT_EQ(a[2].kind, rn::OperatorActionKind::note);
  // Everything after the one blank that follows "note", '#' and spaces included.
  EXPECT_EQ(a[2].text, " Participant said: \"the stick # looks bent\" ");
  EXPECT_EQ(a[2].source, "script ops.txt:6");
  EXPECT_EQ(a[3].kind, rn::OperatorActionKind::skip);
  EXPECT_EQ(a[3].source, "script ops.txt:3");
  EXPECT_EQ(a[4].kind, rn::OperatorActionKind::end);
}

// The source is stored with each operator_action event: the file's name and
// line, not the folder (a home folder names a person). Messages keep the path
// as given, to find the file.
TEST(OperatorScript, TheStoredSourceNamesTheFileNotItsFolder) {
  const auto r = rn::parse_operator_script("1 pause\n2 resume\n", "/home/jane.doe/study/ops.txt");
  ASSERT_TRUE(r.has_value()) << r.error().message;
  EXPECT_EQ(r.value().at(1).source, "script ops.txt:2");
  const auto bad = rn::parse_operator_script("1 jump\n", "/home/jane.doe/study/ops.txt");
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().message.rfind("/home/jane.doe/study/ops.txt:1: ", 0), 0u) << bad.error().message;
}

TEST(OperatorScript, ABadLineIsNamedByFileAndLine) {
  EXPECT_NE(parse_error("1 pause\n2 jump\n").find("ops.txt:2: unknown action 'jump'"), std::string::npos);
  EXPECT_NE(parse_error("# ok\nsoon pause\n").find("ops.txt:2: expected SECONDS ACTION"), std::string::npos);
  EXPECT_NE(parse_error("-1 pause\n").find("ops.txt:1:"), std::string::npos);
  EXPECT_NE(parse_error("1 pause\n\n3 note\n").find("ops.txt:3: a note needs its text"), std::string::npos);
  EXPECT_NE(parse_error("1 skip now\n").find("ops.txt:1: 'skip' takes no text"), std::string::npos);
  EXPECT_NE(parse_error("1\n").find("ops.txt:1: unknown action ''"), std::string::npos);
}

TEST(OperatorScript, AMissingFileIsNotFound) {
  const auto r = rn::read_operator_script("/nonexistent/ops.txt");
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().kind, curvlab::harness::Error::Kind::not_found);
  EXPECT_NE(r.error().message.find("/nonexistent/ops.txt"), std::string::npos);
}

TEST(OperatorScript, ActionsComeDueOnceWhenTheirTimeHasPassed) {
  auto parsed = rn::parse_operator_script("1 pause\n1 note a\n2 resume\n", "ops.txt");
  ASSERT_TRUE(parsed.has_value());
  rn::ScriptedActions script(std::move(parsed).value());
  std::vector<rn::OperatorAction> out;
  script.due(kS - 1, out);
  EXPECT_TRUE(out.empty());
  script.due(kS, out);
  ASSERT_EQ(out.size(), 2u);
  script.due(kS + 1, out);
  EXPECT_EQ(out.size(), 2u);
  script.due(10 * kS, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[2].kind, rn::OperatorActionKind::resume);
  EXPECT_TRUE(script.empty());
}

TEST(OperatorScript, RepeatAndSkipAbortTheAttemptAndDecideItsFate) {
  pr::Timeline t;
  t.fixation_ms = 100;
  for (const auto& [signal, reason] : {std::pair{rn::Signal::repeat, rn::AbortReason::repeat},
                                      std::pair{rn::Signal::skip, rn::AbortReason::skip}}) {
    rn::Attempt a(t, {}, 0);
    EXPECT_FALSE(a.advance({0, 10, true, rn::Signal::none}).abort);
    const auto step = a.advance({11'000'000, 21'000'000, true, signal});
    ASSERT_TRUE(step.abort);
    EXPECT_EQ(*step.abort, reason);
  }
  pr::TrackingLoss capped;
  capped.max_attempts = 2;
  // The operator's repeat runs again even past the protocol's cap; a skip never does.
  EXPECT_EQ(rn::after_abort(rn::AbortReason::repeat, 5, capped), rn::AfterAbort::repeat);
  EXPECT_EQ(rn::after_abort(rn::AbortReason::skip, 1, capped), rn::AfterAbort::give_up);
  EXPECT_EQ(rn::to_string(rn::AbortReason::skip), "operator_skip");
}

TEST(OperatorStatus, LinesShowTrialPhaseTrackingAndTiming) {
  rn::OperatorStatus s;
  s.participant = "P07";
  s.session_id = 3;
  s.protocol = "demo";
  s.block = "main";
  s.trial = 4;
  s.trials = 8;
  s.condition = "space=H3";
  s.phase = rn::Phase::response;
  s.phase_left_ns = 1'500'000'000;
  s.tracked = {true, false, true};
  s.lost_ns = {-1, 2'000'000'000, -1};
  s.last_response = "convex";
  s.last_rt_ms = 812.0;
  s.late_trial = 2;
  s.late_session = 5;
  s.partner = "you host P07, partner join AB: connected  RTT 3 ms  loss 0 %";
  const auto lines = rn::status_lines(s, 12.5);
  std::string all;
  for (const auto& l : lines) all += l + "\n";
  for (const char* want : {"participant P07", "session 3", "protocol demo", "trial 4/8", "space=H3",
                           "phase response  1.5 s left", "left LOST 2.0 s", "right ok", "convex  RT 812 ms",
                           "late frames 2 trial  5 session", "disk free 12.5 GB",
                           "partner join AB: connected"})
    EXPECT_NE(all.find(want), std::string::npos) << want << "\n" << all;
}
