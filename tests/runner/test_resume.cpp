// kill -9 at random instants of headless sessions, then resume: every trial
// is completed exactly once, in the stored order, and the file stays sound.
#include "run_and_kill.hpp"
#include "run_cli.hpp"
#include "session_db.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <fstream>
#include <fcntl.h>
#include <functional>
#include <random>
#include <spawn.h>
#include <sys/wait.h>
#include <thread>

extern char** environ;

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_and_kill;
using curvlab::testing::run_cli;

namespace {

const std::string kProtocols = std::string(CURVLAB_SOURCE_DIR) + "/protocols/";


}  // namespace

TEST(Resume, KillNineAtRandomPointsThenResumeCompletesEveryTrialOnce) {
  const auto dir = fresh_dir("kill");
  const auto db = (dir / "study.sqlite").string();
  std::mt19937 rng(20260731);
  std::uniform_int_distribution<int> delay_ms(250, 1400);
  int kills = 0;
  int interrupted_mid_session = 0;
  for (int round = 0; round < 6; ++round) {
    const auto sessions = query(db, "SELECT session_id, status FROM sessions");
    if (!sessions.empty() && sessions[0][1] == "completed") break;
    std::vector<std::string> args;
    if (sessions.empty())
      args = {"run", kProtocols + "proposed_study.toml", "--participant", "P03", "--db", db, "--render", "none",
              "--quiet"};
    else
      args = {"resume", "--db", db, "--session", sessions[0][0], "--render", "none", "--quiet"};
    auto stored = [&] { return !query(db, "SELECT 1 FROM sessions").empty(); };
    if (run_and_kill(args, std::chrono::milliseconds(delay_ms(rng)), stored)) {
      ++kills;
      const auto done = query(db, "SELECT COUNT(*) FROM trials WHERE status = 'completed'");
      if (!done.empty() && std::stoi(done[0][0]) > 0) ++interrupted_mid_session;
    }
  }
  // Finish whatever is left.
  auto sessions = query(db, "SELECT session_id, status FROM sessions");
  ASSERT_EQ(sessions.size(), 1u) << "the first run was killed before it stored its session";
  if (sessions[0][1] != "completed") {
    const auto r = run_cli("resume --db " + db + " --session " + sessions[0][0] + " --render none --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.out;
  }
  EXPECT_GE(kills, 1);
  EXPECT_GE(interrupted_mid_session, 1);

  // Every trial completed exactly once, with one response.
  const auto counts = query(db, "SELECT COUNT(*), SUM(status = 'completed'), SUM(response IS NOT NULL), "
                                "MIN(attempt), MAX(attempt) FROM trials");
  EXPECT_EQ(counts[0][0], counts[0][1]);
  EXPECT_EQ(counts[0][0], counts[0][2]);
  EXPECT_EQ(counts[0][3], "1");
  // In the stored order: the trials' onsets, in the order they happened,
  // never go back (an interrupted trial is run again, then the next).
  const auto onsets = query(db, "SELECT t.trial_index FROM events e JOIN trials t ON t.trial_id = e.trial_id "
                                "WHERE e.kind = 'onset' ORDER BY e.event_id");
  ASSERT_FALSE(onsets.empty());
  int previous = -1;
  for (const auto& row : onsets) {
    const int index = std::stoi(row[0]);
    EXPECT_GE(index, previous);
    previous = index;
  }
  // Each completed trial's response came after its last onset, and the
  // resumed runs logged their frames after the killed ones (one clock).
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM trials WHERE response_ns < onset_ns")[0][0], "0");
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");
  EXPECT_EQ(curvlab::testing::integrity(db), "ok");

  // A completed session cannot be resumed again.
  const auto again = run_cli("resume --db " + db + " --session " + sessions[0][0]);
  EXPECT_EQ(again.exit_code, 2);
  EXPECT_NE(again.out.find("already completed"), std::string::npos) << again.out;
}

// Random streams derive from (session seed, trial index, attempt), never from
// what came before: a simulated session killed at random instants and
// resumed answers exactly as the uninterrupted session of the same
// participant — the same trials in the same order, the same responses and
// the same response times.
TEST(Resume, KilledAndResumedSessionAnswersAsTheUninterruptedOne) {
  const auto dir = fresh_dir("reproducible");
  const auto whole = (dir / "whole.sqlite").string();
  const auto pieces = (dir / "pieces.sqlite").string();
  const std::string protocol = kProtocols + "proposed_study.toml";
  auto r = run_cli("run " + protocol + " --participant P05 --render none --quiet --db " + whole);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::mt19937 rng(20261124);
  std::uniform_int_distribution<int> delay_ms(200, 1200);
  int kills = 0;
  for (int round = 0; round < 5; ++round) {
    const auto sessions = query(pieces, "SELECT session_id, status FROM sessions");
    if (!sessions.empty() && sessions[0][1] == "completed") break;
    std::vector<std::string> args =
        sessions.empty()
            ? std::vector<std::string>{"run", protocol, "--participant", "P05", "--db", pieces, "--render", "none",
                                       "--quiet"}
            : std::vector<std::string>{"resume", "--db", pieces, "--session", sessions[0][0], "--render", "none",
                                       "--quiet"};
    // Killed at a random instant once the session is stored (a machine
    // under load may take longer than the delay to get there).
    auto stored = [&] { return !query(pieces, "SELECT 1 FROM sessions").empty(); };
    if (run_and_kill(args, std::chrono::milliseconds(delay_ms(rng)), stored)) ++kills;
  }
  const auto sessions = query(pieces, "SELECT session_id, status FROM sessions");
  ASSERT_EQ(sessions.size(), 1u);
  if (sessions[0][1] != "completed") {
    r = run_cli("resume --db " + pieces + " --session " + sessions[0][0] + " --render none --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.out;
  }
  ASSERT_GE(kills, 1);
  const std::string trials =
      "SELECT trial_index, conditions, response, response_ns - onset_ns FROM trials ORDER BY trial_index";
  const auto a = query(whole, trials);
  const auto b = query(pieces, trials);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_FALSE(a.empty());
  int differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i], b[i]) << "trial " << i;
    differ += a[i] != b[i] ? 1 : 0;
  }
  EXPECT_EQ(differ, 0) << "of " << a.size() << " trials, after " << kills << " kills";
  // The order the trials ran in is the stored order in both.
  const std::string order = "SELECT t.trial_index FROM events e JOIN trials t ON t.trial_id = e.trial_id "
                            "WHERE e.kind = 'onset' ORDER BY e.event_id";
  const auto oa = query(whole, order);
  auto ob = query(pieces, order);
  ob.erase(std::unique(ob.begin(), ob.end()), ob.end());  // a killed trial's onset, run again
  EXPECT_EQ(oa, ob);
}

TEST(Resume, UnknownSessionOrDatabaseIsAUsageError) {
  const auto dir = fresh_dir("unknown");
  auto r = run_cli("resume --db " + (dir / "missing.sqlite").string() + " --session 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("no such database"), std::string::npos) << r.out;
  const auto db = (dir / "d.sqlite").string();
  ASSERT_EQ(run_cli("run " + kProtocols + "demo.toml --participant P01 --render none --quiet --db " + db).exit_code, 0);
  r = run_cli("resume --db " + db + " --session 9");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("no session with id 9"), std::string::npos) << r.out;
}

// Tracking lost during a trial (the head's samples flagged invalid for half a
// second of a recorded trajectory): the attempt is aborted and the trial runs
// again once tracking is back; the rest of the session is unaffected.
TEST(Resume, LostTrackingRepeatsTheTrial) {
  const auto dir = fresh_dir("lost");
  const auto walk = (dir / "walk.csv").string();
  auto r = run_cli("trajectory walk-around --laps 3 --out " + walk);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::ifstream in(walk);
  const auto lost = (dir / "lost.csv").string();
  std::ofstream out(lost);
  std::string line;
  int flagged = 0;
  while (std::getline(in, line)) {
    if (!line.empty() && std::isdigit(static_cast<unsigned char>(line[0]))) {
      const auto comma = line.find(',');
      const long long t = std::stoll(line.substr(0, comma));
      if (t >= 250'000'000 && t < 750'000'000) {
        line[comma + 1] = '0';  // head_valid
        ++flagged;
      }
    }
    out << line << '\n';
  }
  out.close();
  ASSERT_GT(flagged, 40);
  const auto db = (dir / "lost.sqlite").string();
  r = run_cli("run " + kProtocols + "demo.toml --participant P01 --render none --quiet --trajectory " + lost +
              " --db " + db);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(query(db, "SELECT attempt, status FROM trials WHERE trial_index = 0")[0],
            (std::vector<std::string>{"2", "completed"}));
  EXPECT_EQ(query(db, "SELECT MAX(attempt) FROM trials WHERE trial_index > 0")[0][0], "1");
  EXPECT_EQ(query(db, "SELECT json_extract(detail, '$.reason') FROM events WHERE kind = 'trial_aborted'"),
            (std::vector<std::vector<std::string>>{{"tracking_lost"}}));
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM events WHERE kind = 'trial_repeated'")[0][0], "1");
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM trials WHERE status != 'completed'")[0][0], "0");
  // The lost samples are logged as such.
  EXPECT_GT(std::stoi(query(db, "SELECT COUNT(*) FROM tracking_samples WHERE device = 'head' "
                                "AND position_valid = 0")[0][0]),
            20);
}

namespace {

// Starts `run …` with its progress read as JSON lines by `head -N`: when
// head exits after N trials, the session ends interrupted, resumable.
void run_interrupted_after(const std::string& args, int trials) {
  curvlab::testing::run_shell(std::string(CURVLAB_BIN) + " run " + args + " --progress json 2>/dev/null | head -" +
                              std::to_string(trials) + " >/dev/null");
}

nlohmann::json summary_of(const std::string& out) {
  const auto start = out.find('{');
  return start == std::string::npos ? nlohmann::json() : nlohmann::json::parse(out.substr(start), nullptr, false);
}

}  // namespace

// `resume` continues as the session ran: an interrupted --render none
// session resumes without drawing (no Vulkan device; nothing drawn).
TEST(Resume, AnInterruptedRenderNoneSessionResumesWithoutRendering) {
  const auto dir = fresh_dir("resume_render_none");
  const std::string db = (dir / "s.sqlite").string();
  run_interrupted_after(kProtocols + "demo.toml --participant P01 --render none --db " + db, 2);
  ASSERT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  const auto r = run_cli("resume --db " + db + " --session 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto doc = summary_of(r.out);
  EXPECT_EQ(doc["status"], "completed") << r.out;
  EXPECT_EQ(doc["msaa"], 0) << "the resumed session drew frames: " << r.out;
  EXPECT_EQ(query(db, "SELECT json_extract(detail, '$.run_options.render') FROM events WHERE kind = 'resume'")[0][0],
            "none");
  std::filesystem::remove_all(dir);
}

// Every stored run option is the default of `resume` (render, pace, images,
// export, observer), and one given on its command line wins and is recorded.
TEST(Resume, EveryStoredRunOptionIsResumesDefaultAndTheCommandLineOverrides) {
  const auto dir = fresh_dir("resume_options");
  const std::string db = (dir / "s.sqlite").string();
  const std::string images = (dir / "onsets").string();
  const std::string exported = (dir / "export").string();
  run_interrupted_after(kProtocols + "demo.toml --participant P01 --render onset --pace fast --observer random --images " +
                            images + " --export " + exported + " --db " + db,
                        2);
  ASSERT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  const auto stored = query(db, "SELECT json_extract(detail, '$.run_options.render'), "
                                "json_extract(detail, '$.run_options.pace'), json_extract(detail, '$.run_options.images'), "
                                "json_extract(detail, '$.run_options.export'), "
                                "json_extract(detail, '$.run_options.observer') FROM events WHERE kind = 'session_start'");
  ASSERT_EQ(stored.size(), 1u);
  EXPECT_EQ(stored[0], (std::vector<std::string>{"onset", "fast", images, exported, "random"}));
  const auto done_before = std::stoi(query(db, "SELECT count(*) FROM trials WHERE status = 'completed'")[0][0]);
  ASSERT_GE(done_before, 1);
  ASSERT_LT(done_before, 8);

  const auto r = run_cli("resume --db " + db + " --session 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto doc = summary_of(r.out);
  EXPECT_EQ(doc["status"], "completed");
  // render onset and images: every trial's onset is in the folder, the
  // resumed ones included; export: the files are written where the run said.
  EXPECT_EQ(doc["images_dir"], images) << r.out;
  EXPECT_GT(doc["msaa"].get<int>(), 0) << r.out;
  int onsets = 0;
  for (const auto& f : std::filesystem::directory_iterator(images))
    if (f.path().filename().string().find("_left.png") != std::string::npos) ++onsets;
  EXPECT_EQ(onsets, 8);
  EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(exported) / "csv")) << r.out;
  EXPECT_FALSE(doc["exports"].empty()) << r.out;
  // The observer kept answering: the random observer's answers, all trials.
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status = 'completed' AND response_device = 'observer'")[0][0],
            "8");
  const auto resumed = query(db, "SELECT json_extract(detail, '$.run_options.render'), "
                                 "json_extract(detail, '$.run_options.pace'), json_extract(detail, '$.run_options.images'), "
                                 "json_extract(detail, '$.run_options.export'), "
                                 "json_extract(detail, '$.run_options.observer') FROM events WHERE kind = 'resume'");
  ASSERT_EQ(resumed.size(), 1u);
  EXPECT_EQ(resumed[0], stored[0]);

  // An option on resume's command line overrides the stored one and is
  // recorded with that resume.
  const std::string db2 = (dir / "s2.sqlite").string();
  run_interrupted_after(kProtocols + "demo.toml --participant P02 --render onset --db " + db2, 2);
  ASSERT_EQ(query(db2, "SELECT status FROM sessions")[0][0], "interrupted");
  const auto r2 = run_cli("resume --db " + db2 + " --session 1 --render none --json");
  ASSERT_EQ(r2.exit_code, 0) << r2.out;
  EXPECT_EQ(summary_of(r2.out)["msaa"], 0) << r2.out;
  EXPECT_EQ(query(db2, "SELECT json_extract(detail, '$.run_options.render') FROM events WHERE kind = 'resume'")[0][0],
            "none");
  std::filesystem::remove_all(dir);
}
