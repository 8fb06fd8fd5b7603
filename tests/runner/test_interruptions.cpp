// Whole sessions in process, with the headless backend (no GPU) wrapped so
// that a test decides when the head is lost, when a recenter comes and which
// keys are pressed when: what the runner does with anticipations, tracking
// loss under each `tracking.on_loss` policy, and `tracking.max_attempts`.
#include "in_process.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/data/export.hpp"

namespace {

using namespace curvlab;
using curvlab::testing::fresh_dir;
using curvlab::testing::Outcome;
using curvlab::testing::query;
using curvlab::testing::run_protocol;
using curvlab::testing::ScriptedDevices;
namespace rn = harness::runner;
namespace pr = harness::protocol;

using Rows = std::vector<std::vector<std::string>>;

// The demo protocol (8 trials: 100 ms fixation, 300 ms stimulus, 2.5 s
// response window) with `extra` appended, run to the end.
Outcome run_demo(const std::string& name, const std::string& extra, bool observer,
                 const std::function<void(ScriptedDevices&)>& script) {
  return run_protocol("demo", name, extra, observer, script);
}

// The head untracked in [from, to) of session time, in milliseconds.
std::function<bool(std::int64_t)> lost_between(std::vector<std::pair<int, int>> spans_ms) {
  return [spans_ms](std::int64_t t_ns) {
    for (auto [from, to] : spans_ms)
      if (t_ns >= from * 1'000'000LL && t_ns < to * 1'000'000LL) return false;
    return true;
  };
}

}  // namespace

// A key pressed before the stimulus is on the display — during the fixation,
// or in the onset frame itself but time-stamped before that frame's display
// time — is logged as an anticipation and does not answer the trial; the
// key pressed after it does.
TEST(Interruptions, PressesBeforeTheDisplayedOnsetAreAnticipationsNotAnswers) {
  bool answered = false;
  const auto out = run_demo("early", "", false, [&](ScriptedDevices& b) {
    b.inputs = [&](const harness::io::FrameTiming& t, const std::string& phase, std::vector<harness::io::InputEvent>& in) {
      if (phase == "fixation") {
        // Includes the frame in which the runner decides onset: stamped at
        // the frame's start, before its predicted display time.
        in.push_back(curvlab::harness::desktop::key_input(t.now_ns, "1", true));
        answered = false;
      } else if ((phase == "stimulus" || phase == "response") && !answered) {
        in.push_back(curvlab::harness::desktop::key_input(t.predicted_display_ns, "2", true));
        answered = true;
      }
      return rn::Signal::none;
    };
  });
  ASSERT_FALSE(out.db.empty());
  EXPECT_EQ(out.summary.trials_completed, 8);
  // Every trial was answered by the later key ("straight"), none by "1".
  EXPECT_EQ(query(out.db, "SELECT DISTINCT response FROM trials"), (Rows{{"straight"}}));
  // The press in the onset frame was logged, stamped before the onset.
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM trials t WHERE EXISTS (SELECT 1 FROM events e "
                          "WHERE e.trial_id = t.trial_id AND e.kind = 'early_input' AND "
                          "json_extract(e.detail, '$.name') = '1' AND "
                          "json_extract(e.detail, '$.t_ns') < t.onset_ns AND "
                          "json_extract(e.detail, '$.t_ns') > t.onset_ns - 30000000)")[0][0],
            "8");
  // And so were the presses during the fixation (100 ms at 90 Hz: ≥ 8 each).
  EXPECT_GE(std::stoi(query(out.db, "SELECT MIN(n) FROM (SELECT COUNT(*) AS n FROM events "
                                    "WHERE kind = 'early_input' GROUP BY trial_id)")[0][0]),
            9);
}

// on_loss = "flag": the trial goes on through a 500 ms loss, is completed in
// its first attempt and carries the loss, in its event and in the export.
TEST(Interruptions, FlaggedTrackingLossKeepsTheTrialAndRecordsHowLong) {
  const auto out = run_demo("flag", "[tracking]\non_loss = \"flag\"\n", true,
                            [](ScriptedDevices& b) { b.head_valid = lost_between({{50, 550}}); });
  ASSERT_FALSE(out.db.empty());
  EXPECT_EQ(out.summary.trials_completed, 8);
  EXPECT_EQ(out.summary.trials_flagged, 1);
  EXPECT_EQ(out.summary.attempts_repeated, 0);
  EXPECT_EQ(query(out.db, "SELECT attempt, status FROM trials WHERE trial_index = 0"), (Rows{{"1", "completed"}}));
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM events WHERE kind = 'trial_aborted'")[0][0], "0");
  const auto flagged = query(out.db, "SELECT t.trial_index, json_extract(e.detail, '$.lost_ms'), "
                                     "json_extract(e.detail, '$.spells') FROM events e "
                                     "JOIN trials t ON t.trial_id = e.trial_id WHERE e.kind = 'tracking_flagged'");
  ASSERT_EQ(flagged.size(), 1u);
  EXPECT_EQ(flagged[0][0], "0");
  EXPECT_NEAR(std::stod(flagged[0][1]), 500.0, 12.0);  // one 90 Hz frame either side
  EXPECT_EQ(flagged[0][2], "1");

  auto db = harness::data::Database::open(out.db, harness::data::OpenMode::read_only);
  ASSERT_TRUE(db);
  harness::data::ExportOptions eo;
  eo.out_dir = fresh_dir("interrupt_flag_export").string();
  ASSERT_TRUE(harness::data::export_trials_csv(db.value(), eo));
  std::ifstream csv(std::filesystem::path(eo.out_dir) / "trials.csv");
  std::string header, first, second;
  std::getline(csv, header);
  std::getline(csv, first);
  std::getline(csv, second);
  const auto split = [](const std::string& text) {
    std::vector<std::string> cells;
    std::stringstream ss(text);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (!text.empty() && text.back() == ',') cells.emplace_back();
    return cells;
  };
  const auto column = [&](const std::string& line) {
    const auto h = split(header);
    const auto v = split(line);
    for (std::size_t k = 0; k < h.size() && k < v.size(); ++k)
      if (h[k] == "tracking_lost_ms") return v[k];
    return std::string("missing");
  };
  EXPECT_NEAR(std::stod(column(first)), 500.0, 12.0) << header << '\n' << first;
  EXPECT_EQ(column(second), "NA") << second;
}

// on_loss = "abort": the trial is marked aborted after its one attempt and
// the session goes on — but only once the head is tracked again, so the
// trials after it are not lost with it.
TEST(Interruptions, AbortPolicyGivesUpTheTrialAndWaitsForTrackingBeforeTheNext) {
  const auto out = run_demo("abort", "[tracking]\non_loss = \"abort\"\n", true,
                            [](ScriptedDevices& b) { b.head_valid = lost_between({{50, 2000}}); });
  ASSERT_FALSE(out.db.empty());
  EXPECT_EQ(out.summary.status, curvlab::harness::data::SessionStatus::completed);
  EXPECT_EQ(out.summary.trials_aborted, 1);
  EXPECT_EQ(out.summary.trials_completed, 7);
  EXPECT_EQ(query(out.db, "SELECT trial_index, attempt, status FROM trials WHERE status != 'completed'"),
            (Rows{{"0", "1", "aborted"}}));
  EXPECT_EQ(query(out.db, "SELECT MAX(attempt) FROM trials")[0][0], "1");
  EXPECT_EQ(query(out.db, "SELECT json_extract(detail, '$.reason'), json_extract(detail, '$.attempts') "
                          "FROM events WHERE kind = 'trial_abandoned'"),
            (Rows{{"tracking_lost", "1"}}));
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM events WHERE kind = 'trial_repeated'")[0][0], "0");
  // The next trial started after tracking came back at 2 s.
  EXPECT_GT(std::stoll(query(out.db, "SELECT onset_ns FROM trials WHERE trial_index = 1")[0][0]),
            2'000'000'000LL);
  // Nothing is left to resume.
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM trials WHERE status IN ('pending', 'running')")[0][0], "0");
}

// max_attempts = 2 with the default on_loss = "repeat": the first loss
// repeats the trial, the second (in attempt 2) gives it up.
TEST(Interruptions, MaxAttemptsEndsRepeatedLosses) {
  // Attempt 1 starts at 0 and is lost at 300 ms (loss from 50 ms); attempt 2
  // starts when the head is back at 600 ms and is lost again at 1.1 s,
  // before the simulated observer's earliest answer (onset + 450 ms).
  const auto out = run_demo("max", "[tracking]\nmax_attempts = 2\n", true, [](ScriptedDevices& b) {
    b.head_valid = lost_between({{50, 600}, {850, 1400}});
  });
  ASSERT_FALSE(out.db.empty());
  EXPECT_EQ(query(out.db, "SELECT trial_index, attempt, status FROM trials WHERE status != 'completed'"),
            (Rows{{"0", "2", "aborted"}}));
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM events WHERE kind = 'trial_aborted'")[0][0], "2");
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM events WHERE kind = 'trial_repeated'")[0][0], "1");
  EXPECT_EQ(query(out.db, "SELECT json_extract(detail, '$.attempts') FROM events WHERE kind = 'trial_abandoned'"),
            (Rows{{"2"}}));
  EXPECT_EQ(out.summary.trials_completed, 7);
}

// A recenter always drops the attempt, whatever on_loss says, and counts
// toward max_attempts.
TEST(Interruptions, RecenterRepeatsTheTrialEvenWhenLossesAreOnlyFlagged) {
  // A recenter in the third fixation frame of the first two attempts.
  int recenters = 0;
  int fixation_frames = 0;
  const auto out = run_demo("recenter", "[tracking]\non_loss = \"flag\"\nmax_attempts = 3\n", true,
                            [&](ScriptedDevices& b) {
                              b.inputs = [&](const harness::io::FrameTiming&, const std::string& phase,
                                             std::vector<harness::io::InputEvent>&) {
                                fixation_frames = phase == "fixation" ? fixation_frames + 1 : 0;
                                if (fixation_frames == 3 && recenters < 2) {
                                  ++recenters;
                                  return rn::Signal::recenter;
                                }
                                return rn::Signal::none;
                              };
                            });
  ASSERT_FALSE(out.db.empty());
  EXPECT_EQ(query(out.db, "SELECT attempt, status FROM trials WHERE trial_index = 0"), (Rows{{"3", "completed"}}));
  EXPECT_EQ(query(out.db, "SELECT json_extract(detail, '$.reason') FROM events WHERE kind = 'trial_aborted'"),
            (Rows{{"recenter"}, {"recenter"}}));
  EXPECT_EQ(out.summary.trials_completed, 8);
}

// Validation of the new settings: a clear error with the allowed values.
TEST(Interruptions, UnknownLossPolicyIsRejectedWithTheAllowedValues) {
  const auto loaded = pr::load_protocol_text(
      "[protocol]\nname = \"x\"\nversion = \"1\"\n[randomization]\nseed = 1\n[tracking]\non_loss = \"retry\"\n"
      "[judgement]\ntype = \"choice\"\noptions = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n",
      "bad.toml");
  ASSERT_FALSE(loaded.has_value());
  const auto message = pr::format_diagnostic(loaded.error().diagnostics.at(0));
  EXPECT_NE(message.find("bad.toml:7"), std::string::npos) << message;
  EXPECT_NE(message.find("on_loss"), std::string::npos) << message;
  EXPECT_NE(message.find("\"repeat\", \"flag\", \"abort\""), std::string::npos) << message;
}

// A pause in the inter-trial interval (the headset's focus lost between
// trials) holds the session until it ends: the next trial starts only after
// the resume, nothing is repeated, and the pause is logged with its length.
TEST(Interruptions, APauseBetweenTrialsHoldsTheSessionUntilResumed) {
  std::int64_t paused_at = -1;
  std::int64_t resumed_at = -1;
  const auto out = run_demo("iti_pause", "", true, [&](ScriptedDevices& b) {
    b.inputs = [&](const harness::io::FrameTiming& t, const std::string& phase, std::vector<harness::io::InputEvent>&) {
      if (paused_at < 0 && phase == "iti") {
        paused_at = t.now_ns;
        return rn::Signal::pause;
      }
      if (paused_at >= 0 && resumed_at < 0 && t.now_ns >= paused_at + 700'000'000) {
        resumed_at = t.now_ns;
        return rn::Signal::resume;
      }
      return rn::Signal::none;
    };
  });
  ASSERT_FALSE(out.db.empty());
  ASSERT_GT(resumed_at, paused_at);
  EXPECT_EQ(out.summary.trials_completed, 8);
  EXPECT_EQ(out.summary.attempts_repeated, 0);
  EXPECT_EQ(query(out.db, "SELECT COUNT(*) FROM events WHERE kind = 'trial_aborted'")[0][0], "0");
  const auto pauses = query(out.db, "SELECT json_extract(detail, '$.phase') FROM events WHERE kind = 'paused'");
  EXPECT_EQ(pauses, (Rows{{"iti"}}));
  const auto held = query(out.db, "SELECT json_extract(detail, '$.paused_ms') FROM events WHERE kind = 'unpaused'");
  ASSERT_EQ(held.size(), 1u);
  EXPECT_NEAR(std::stod(held[0][0]), 700.0, 15.0);
  // Trial 1 began after the resume, and no frame of the session was shown
  // as a trial phase while paused.
  EXPECT_GT(std::stoll(query(out.db, "SELECT onset_ns FROM trials WHERE trial_index = 1")[0][0]), resumed_at);
  EXPECT_EQ(query(out.db, "SELECT status FROM sessions")[0][0], "completed");
}
