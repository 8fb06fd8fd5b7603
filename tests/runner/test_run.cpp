// Whole headless sessions through the program, answered by the simulated
// observer: the paper's study, reproducibility, replay, bad input.
#include "run_cli.hpp"
#include "../data/data_files.hpp"
#include "session_db.hpp"
#include "../support/edited_file.hpp"
#include "../support/png_files.hpp"

#include "curvlab/renderer/image_io.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>
#include <map>
#include <sstream>

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_cli;

namespace {

const std::string kProtocols = std::string(CURVLAB_SOURCE_DIR) + "/protocols/";

}  // namespace

// The proposed study with two simulated participants answering with human
// limits (the default observer): on the straight stick both binocular
// views of H3 are mostly judged convex (bowed toward the viewer) and both
// of S3 concave, E3's and every one-eye view straight (docs/runner.md, "The
// human observer"; paper, "Mental models of space"). Each cell has 6
// trials; a straight stick seen with one eye, or in E3 at the specific
// distance, is answered "straight" with P ≥ 0.92 (criterion 6 mm, metric
// noise 3.3 mm, lapse 0.02), so the bound for those cells is half of them
// (P(X ≤ 2 of 6) < 0.001); the curved views answer with P > 0.99.
TEST(RunHeadless, TheProposedStudyFollowsTheHumanModel) {
  const auto dir = fresh_dir("study");
  const auto db = (dir / "study.sqlite").string();
  for (const char* who : {"P01", "P02"}) {
    const auto r = run_cli("run " + kProtocols + "proposed_study.toml --participant " + who + " --db " + db +
                           " --render none --quiet --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
  }
  const auto rows = query(db,
                          "SELECT json_extract(conditions, '$.space'), json_extract(conditions, '$.view'), "
                          "response FROM trials t JOIN blocks b ON b.block_id = t.block_id WHERE b.is_practice = 0 "
                          "AND json_extract(conditions, '$.judged') = 'stick' "
                          "AND json_extract(conditions, '$.stick_bend') = '0' AND t.status = 'completed'");
  std::map<std::string, std::map<std::string, int>> counts;  // "H3 native" → response → n
  for (const auto& row : rows) ++counts[row[0] + " " + row[1]][row[2]];
  ASSERT_EQ(counts.size(), 9u);
  auto share = [&](const std::string& cond, const std::string& response) {
    int n = 0;
    for (const auto& [resp, k] : counts[cond]) n += k;
    return n == 0 ? 0.0 : counts[cond][response] / double(n);
  };
  for (const char* view : {"native", "tourist"}) {
    EXPECT_GE(share(std::string("H3 ") + view, "convex"), 0.8) << view;
    EXPECT_GE(share(std::string("S3 ") + view, "concave"), 0.8) << view;
    EXPECT_GE(share(std::string("E3 ") + view, "straight"), 0.5) << view;
  }
  for (const char* space : {"S3", "E3", "H3"})
    EXPECT_GE(share(std::string(space) + " monocular", "straight"), 0.5) << space;
  // Each binocular onset records the observer's account: fused, a finite
  // perceived distance, the threshold; one-eye onsets record none.
  const auto accounts = query(db,
                              "SELECT json_extract(t.conditions, '$.view'), json_extract(e.detail, '$.percept.fused'), "
                              "json_extract(e.detail, '$.percept.perceived_distance_m'), "
                              "json_extract(e.detail, '$.percept.threshold_arcsec') FROM events e "
                              "JOIN trials t ON t.trial_id = e.trial_id WHERE e.kind = 'onset'");
  ASSERT_FALSE(accounts.empty());
  for (const auto& a : accounts) {
    if (a[0] == "monocular") {
      EXPECT_EQ(a[1], "NULL");
      continue;
    }
    EXPECT_EQ(a[1], "1") << a[0];
    EXPECT_GT(std::stod(a[2]), 0.5);
    EXPECT_LT(std::stod(a[2]), 3.0);
    EXPECT_EQ(std::stod(a[3]), 30.0);
  }
  // Complete: every planned trial answered, samples and frames logged, the
  // observer's parameters and the provenance stored.
  const auto incomplete = query(db, "SELECT COUNT(*) FROM trials WHERE status != 'completed'");
  EXPECT_EQ(incomplete[0][0], "0");
  const auto sessions = query(db, "SELECT status, backend, renderer_device, seed, table_calibration FROM sessions");
  ASSERT_EQ(sessions.size(), 2u);
  for (const auto& s : sessions) {
    EXPECT_EQ(s[0], "completed");
    EXPECT_EQ(s[1], "headless");
    EXPECT_NE(s[4], "NULL");
  }
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM events WHERE kind = 'observer'")[0][0], "2");
  const auto samples = query(db, "SELECT COUNT(*), SUM(virtual_pose IS NOT NULL) FROM tracking_samples");
  EXPECT_GT(std::stol(samples[0][0]), 100000);
  EXPECT_EQ(samples[0][0], samples[0][1]);
  EXPECT_EQ(curvlab::testing::integrity(db), "ok");
}

TEST(RunHeadless, TheSameSeedReproducesTheSessionExactly) {
  const auto dir = fresh_dir("repro");
  std::vector<std::vector<std::vector<std::string>>> results;
  for (const char* name : {"a.sqlite", "b.sqlite"}) {
    const auto db = (dir / name).string();
    const auto r = run_cli("run " + kProtocols + "demo.toml --participant P07 --db " + db + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    auto rows = query(db, "SELECT trial_index, conditions, stimulus, response, onset_ns, response_ns, attempt "
                          "FROM trials ORDER BY trial_index");
    const auto samples = query(db, "SELECT COUNT(*), SUM(t_ns), SUM(lab_px_m), SUM(coherence_error_m) "
                                   "FROM tracking_samples");
    rows.push_back(samples[0]);
    const auto seed = query(db, "SELECT seed FROM sessions");
    rows.push_back(seed[0]);
    results.push_back(rows);
  }
  ASSERT_EQ(results[0].size(), 10u);  // 8 trials, samples, seed
  EXPECT_EQ(results[0], results[1]);
  // A different participant number draws a different order.
  const auto other = (dir / "c.sqlite").string();
  ASSERT_EQ(run_cli("run " + kProtocols + "demo.toml --participant P08 --db " + other + " --quiet").exit_code, 0);
  const auto c = query(other, "SELECT trial_index, conditions FROM trials ORDER BY trial_index");
  std::vector<std::vector<std::string>> a_order;
  for (std::size_t i = 0; i < 8; ++i) a_order.push_back({results[0][i][0], results[0][i][1]});
  EXPECT_NE(c, a_order);
}

// Replay re-renders the onset frame from the logged poses: pixel for pixel
// the stimulus image the session saved.
TEST(RunHeadless, ReplayReproducesTheStimulusImage) {
  const auto dir = fresh_dir("replay");
  const auto db = (dir / "demo.sqlite").string();
  const auto images = (dir / "images").string();
  auto r = run_cli("run " + kProtocols + "demo.toml --participant P01 --db " + db + " --images " + images +
                   " --render onset --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  // The onset events name the images by file name; the folder (here under
  // the temporary folder, often a home folder) is not stored.
  const auto named = query(db, "SELECT json_extract(detail, '$.images[0]') FROM events WHERE kind = 'onset' "
                               "ORDER BY event_id LIMIT 1");
  ASSERT_EQ(named.size(), 1u);
  EXPECT_EQ(named[0][0], "trial_0000_left.png");
  for (int trial : {2, 5}) {
    const auto out = (dir / ("replay" + std::to_string(trial))).string();
    r = run_cli("replay --db " + db + " --session 1 --trial " + std::to_string(trial) + " --out " + out + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    for (const char* eye : {"left", "right"}) {
      curvlab::renderer::Rgba8Image saved, replayed;
      char stem[32];
      std::snprintf(stem, sizeof stem, "trial_%04d_%s.png", trial, eye);
      ASSERT_TRUE(curvlab::test::read_png_into(images + "/" + stem, saved));
      ASSERT_TRUE(curvlab::test::read_png_into(out + "/" + eye + ".png", replayed));
      const auto diff = curvlab::renderer::diff_images(saved, replayed, 0);
      EXPECT_EQ(diff.differing_pixels, 0) << "trial " << trial << " " << eye;
    }
  }
  // Frames stored without eye geometry (schema version 2) are replayed with
  // the headless backend's: the same image here, marked "assumed".
  {
    auto c = curvlab::harness::data::Connection::open(db, curvlab::harness::data::OpenFlags::read_write);
    c.exec("UPDATE frames SET eye_width_px = NULL, eye_height_px = NULL, eye_views = NULL");
  }
  const auto assumed = (dir / "assumed").string();
  r = run_cli("replay --db " + db + " --session 1 --trial 5 --out " + assumed);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  {
    std::ifstream json(assumed + "/replay.json");
    EXPECT_EQ(nlohmann::json::parse(json)["eye_geometry"], "assumed");
    curvlab::renderer::Rgba8Image saved, replayed;
    ASSERT_TRUE(curvlab::test::read_png_into(images + "/trial_0005_left.png", saved));
    ASSERT_TRUE(curvlab::test::read_png_into(assumed + "/left.png", replayed));
    EXPECT_EQ(curvlab::renderer::diff_images(saved, replayed, 0).differing_pixels, 0);
  }
  // A frame outside the trial is refused with the trial's frame range.
  r = run_cli("replay --db " + db + " --session 1 --trial 2 --frame 0 --out " + (dir / "x").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("its frames:"), std::string::npos) << r.out;
}

// Method of adjustment: replay shows the value in force at the replayed
// frame (the attempt's last logged change at or before it), not the start.
TEST(RunHeadless, ReplayShowsTheAdjustmentInForceAtTheFrame) {
  const auto dir = fresh_dir("replay_adjustment");
  const auto db = (dir / "bc.sqlite").string();
  auto r = run_cli("run " + kProtocols + "body_coherence.toml --participant P01 --db " + db +
                   " --render none --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto trial = query(db, "SELECT trial_id, response, stimulus FROM trials WHERE trial_index = 0");
  ASSERT_EQ(trial.size(), 1u);
  const auto changes = query(db, "SELECT json_extract(detail, '$.frame_index'), json_extract(detail, '$.value') "
                                 "FROM events WHERE kind = 'adjustment' AND trial_id = " + trial[0][0] +
                                 " ORDER BY event_id");
  ASSERT_GE(changes.size(), 3u) << "the observer adjusts in steps";
  auto replay = [&](const std::string& frame, const std::string& out_name) {
    const auto out = dir / out_name;
    const auto rr = run_cli("replay --db " + db + " --session 1 --trial 0 --frame " + frame + " --out " + out.string());
    EXPECT_EQ(rr.exit_code, 0) << rr.out;
    std::ifstream json(out / "replay.json");
    return nlohmann::json::parse(json);
  };
  // Before the first change: the start value; at a change: that value; at
  // the last change (then confirmed): the answer.
  const auto start = nlohmann::json::parse(trial[0][2]).at("adjustment_start").get<double>();
  EXPECT_DOUBLE_EQ(replay(std::to_string(std::stoll(changes[0][0]) - 1), "before")["adjustment_value"].get<double>(),
                   start);
  // (The query's text form of a real keeps 15 digits.)
  EXPECT_NEAR(replay(changes[2][0], "third")["adjustment_value"].get<double>(), std::stod(changes[2][1]), 1e-12);
  EXPECT_NEAR(replay(changes.back()[0], "last")["adjustment_value"].get<double>(), std::stod(trial[0][1]), 1e-8);

  // The change shows: without the logged changes the same frame looks different.
  {
    auto c = curvlab::harness::data::Connection::open(db, curvlab::harness::data::OpenFlags::read_write);
    c.exec("DELETE FROM events WHERE kind = 'adjustment'");
  }
  EXPECT_DOUBLE_EQ(replay(changes.back()[0], "unadjusted")["adjustment_value"].get<double>(), start);
  curvlab::renderer::Rgba8Image adjusted, unadjusted;
  ASSERT_TRUE(curvlab::test::read_png_into((dir / "last" / "left.png").string(), adjusted));
  ASSERT_TRUE(curvlab::test::read_png_into((dir / "unadjusted" / "left.png").string(), unadjusted));
  EXPECT_GT(curvlab::renderer::diff_images(adjusted, unadjusted, 0).differing_pixels, 100);
}

TEST(RunHeadless, BadInputIsRefusedAndWritesNothing) {
  const auto dir = fresh_dir("bad");
  const auto db = (dir / "never.sqlite").string();
  auto r = run_cli("run " + kProtocols + "demo.toml --participant 'Jane Doe' --db " + db);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("pseudonym"), std::string::npos) << r.out;
  r = run_cli("run " + std::string(CURVLAB_SOURCE_DIR) +
              "/tests/protocol/malformed/unknown_key.toml --participant P01 --db " + db);
  EXPECT_EQ(r.exit_code, 2);
  r = run_cli("run " + kProtocols + "demo.toml --participant P01 --observer-lapse 2 --db " + db);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("lapse"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

TEST(RunHeadless, AnAbsentResponseDeviceStopsTheRunBeforeAnythingIsWritten) {
  // The docs' example mapping names a gamepad that no test machine has.
  const auto dir = fresh_dir("absent_hid");
  const auto db = (dir / "never.sqlite").string();
  const std::string mapping = std::string(CURVLAB_SOURCE_DIR) + "/tests/devices/data/docs_example.toml";
  auto r = run_cli("run " + kProtocols + "demo.toml --participant P01 --pace realtime --responses hid:" + mapping +
                   " --db " + db);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("'gamepad'"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("docs_example.toml"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(db));
  // Simulated time cannot take a person's presses; a spec that is not hid: is refused.
  r = run_cli("run " + kProtocols + "demo.toml --participant P01 --responses hid:" + mapping + " --db " + db);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--pace realtime"), std::string::npos) << r.out;
  r = run_cli("run " + kProtocols + "demo.toml --participant P01 --pace realtime --responses " + mapping +
              " --db " + db);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("hid:MAPPING.toml"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

TEST(RunHeadless, AKeysOnlyProtocolIsRefusedInTheHeadsetBeforeAnythingStarts) {
  // No runtime is needed to learn it: the check comes before the headset starts.
  const auto dir = fresh_dir("keys_only_xr");
  const auto db = (dir / "never.sqlite").string();
  auto r = run_cli("run " + kProtocols + "demo.toml --participant P01 --backend xr --db " + db);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("'convex' (keys 1)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--backend xr"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

TEST(RunHeadless, ASecondRunIntoTheSameImagesFolderReplacesNothing) {
  const auto dir = fresh_dir("images_twice");
  const auto db = (dir / "s.sqlite").string();
  const auto images = (dir / "images").string();
  auto r = run_cli("run " + kProtocols + "demo.toml --participant P01 --db " + db + " --images " + images +
                   " --render onset --quiet --msaa 1");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto first = curvlab::testing::read_file(images + "/trial_0000_left.png");
  ASSERT_FALSE(first.empty());
  r = run_cli("run " + kProtocols + "demo.toml --participant P02 --db " + db + " --images " + images +
              " --render onset --quiet --msaa 1");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(curvlab::testing::read_file(images + "/trial_0000_left.png"), first);
  EXPECT_FALSE(curvlab::testing::read_file(images + "/trial_0000_2_left.png").empty());
  // Each session's onset events name its own files.
  const auto named = query(db, "SELECT json_extract(detail, '$.images[0]') FROM events e JOIN sessions s "
                               "USING (session_id) WHERE e.kind = 'onset' AND s.session_id = 2 ORDER BY e.event_id "
                               "LIMIT 1");
  ASSERT_EQ(named.size(), 1u);
  EXPECT_EQ(named[0][0].rfind("_2_left.png"), named[0][0].size() - 11) << named[0][0];
}

TEST(Predict, PrintsProportionsAndPower) {
  const auto r = run_cli("predict " + kProtocols + "proposed_study.toml --participants 10 --simulations 50 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc.at("participants"), 10);
  EXPECT_FALSE(doc.at("conditions").empty());
  for (const auto& c : doc.at("conditions")) {
    double sum = 0.0;
    for (const auto& [k, v] : c.at("proportions").items()) sum += v.get<double>();
    EXPECT_NEAR(sum, 1.0, 1e-9);
  }
  EXPECT_FALSE(doc.at("power").empty());
  const auto bad = run_cli("predict " + kProtocols + "proposed_study.toml --effect view:native,nowhere");
  EXPECT_EQ(bad.exit_code, 2);
}

// --msaa overrides the protocol's [viewing] msaa, is clamped to the device
// with a warning, and the count drawn with is the session's provenance.
TEST(RunHeadless, MsaaIsClampedWarnedAndStoredWithTheSession) {
  const auto dir = fresh_dir("msaa");
  const auto db = (dir / "demo.sqlite").string();
  const auto images = (dir / "images").string();
  auto r = run_cli("run " + kProtocols + "demo.toml --participant P01 --db " + db + " --images " + images +
                   " --render onset --quiet --software --msaa 8");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("warning: msaa 8 is more than the Vulkan device supports; drawing with 4"),
            std::string::npos)
      << r.out;
  const auto start = query(db, "SELECT detail FROM events WHERE kind = 'session_start'");
  ASSERT_EQ(start.size(), 1u);
  EXPECT_EQ(nlohmann::json::parse(start[0][0]).at("msaa"), 4);
  std::ifstream png(images + "/trial_0000_left.png", std::ios::binary);
  std::string head(64, '\0');
  png.read(head.data(), 64);
  EXPECT_NE(head.find("sRGB"), std::string::npos) << "the saved stimulus carries an sRGB chunk";
  r = run_cli("run " + kProtocols + "demo.toml --participant P02 --db " + db + " --render none --msaa 3");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--msaa must be 1, 2, 4 or 8, got 3"), std::string::npos) << r.out;
}

// msaa "auto", the default, draws with one sample on a CPU device (4 on a
// GPU); a number in the protocol or on the command line wins, and
// `--msaa auto` gives the choice back to the device. The count drawn with is
// in the summary and in the session's provenance.
TEST(RunHeadless, MsaaAutoDrawsWithOneSampleOnACpuDeviceAndANumberWins) {
  const auto dir = fresh_dir("msaa_auto");
  const auto db = (dir / "demo.sqlite").string();
  std::ifstream in(kProtocols + "demo.toml");
  std::stringstream text;
  text << in.rdbuf();
  const auto four = (dir / "demo_msaa4.toml").string();
  std::ofstream(four) << text.str() << "\n[viewing]\nmsaa = 4\n";
  struct Case {
    std::string protocol, extra;
    int samples;
  };
  const std::vector<Case> cases = {{kProtocols + "demo.toml", "", 1},
                                   {four, "", 4},
                                   {four, " --msaa auto", 1},
                                   {kProtocols + "demo.toml", " --msaa 4", 4}};
  int participant = 0;
  for (const auto& c : cases) {
    SCOPED_TRACE(c.protocol + c.extra);
    const auto r = run_cli("run " + c.protocol + " --participant P0" + std::to_string(++participant) + " --db " +
                           db + " --render onset --software --quiet --json" + c.extra);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    EXPECT_NE(r.out.find("\"msaa\": " + std::to_string(c.samples) + ","), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("warning"), std::string::npos) << r.out;
    const auto start = query(db, "SELECT detail FROM events WHERE kind = 'session_start' ORDER BY event_id DESC "
                                 "LIMIT 1");
    ASSERT_EQ(start.size(), 1u);
    EXPECT_EQ(nlohmann::json::parse(start[0][0]).at("msaa"), c.samples);
  }
  const auto bad = run_cli("run " + kProtocols + "demo.toml --participant P09 --db " + db + " --msaa four");
  EXPECT_EQ(bad.exit_code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--msaa must be auto, 1, 2, 4 or 8, got 'four'"), std::string::npos) << bad.out;
}

// judgement.feedback: after every answer the participant is shown the answer
// given, by its label, and the session stores what was shown with the trial;
// without it nothing is shown.
TEST(RunHeadless, FeedbackShowsTheAnswerGivenByItsLabel) {
  const auto dir = fresh_dir("feedback");
  std::ofstream(dir / "feedback.toml") << curvlab::test::edited_file(
      kProtocols + "demo.toml",
      {{"prompt = \"Convex, straight or concave?\"", "prompt = \"Convex, straight or concave?\"\nfeedback = true"},
       {"{ value = \"convex\",", "{ value = \"convex\", label = \"bowed toward me\","},
       {"{ value = \"straight\",", "{ value = \"straight\", label = \"straight\","},
       {"{ value = \"concave\",", "{ value = \"concave\", label = \"bowed away\","}});
  const auto db = (dir / "feedback.sqlite").string();
  auto r = run_cli("run " + (dir / "feedback.toml").string() + " --participant P01 --db " + db +
                   " --render none --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto rows = query(db,
                          "SELECT t.response, json_extract(e.detail, '$.text') FROM trials t "
                          "LEFT JOIN events e ON e.trial_id = t.trial_id AND e.kind = 'feedback' "
                          "ORDER BY t.trial_id");
  ASSERT_EQ(rows.size(), 8u);
  const std::map<std::string, std::string> labels{
      {"convex", "bowed toward me"}, {"straight", "straight"}, {"concave", "bowed away"}, {"timeout", ""}};
  for (const auto& row : rows)
    EXPECT_EQ(row[1], row[0] == "timeout" ? "No answer" : "Your answer: " + labels.at(row[0]));

  const auto plain = (dir / "plain.sqlite").string();
  r = run_cli("run " + kProtocols + "demo.toml --participant P01 --db " + plain + " --render none --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(query(plain, "SELECT count(*) FROM events WHERE kind = 'feedback'").at(0).at(0), "0");
}
