// The Lab Streaming Layer through the program, on the loopback only
// (LSLAPICFG names a config this test writes: ResolveScope = machine, IPv6
// off, Interfaces = {127.0.0.1}): a test inlet receives a realtime headless
// session's markers and poses as stored, a resumed session's streams come
// back with the same source ids, and a test outlet's markers recorded with
// --lsl-record land in the database and its export. Without liblsl the
// streaming tests skip and --lsl is refused (exit 2).
#include "run_and_kill.hpp"
#include "run_cli.hpp"
#include "session_db.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#ifdef CURVLAB_WITH_LSL
#include <lsl_cpp.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <fcntl.h>
#include <fstream>
#include <map>
#include <spawn.h>
#include <sstream>
#include <sys/wait.h>
#include <thread>

extern char** environ;

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_cli;
using Json = nlohmann::json;

namespace {

const std::string kDemo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

// liblsl reads its configuration once, at its first use in a process: the
// file is written, and LSLAPICFG set, before any test runs (the program
// under test inherits it).
class LoopbackOnly : public ::testing::Environment {
 public:
  void SetUp() override {
    const auto dir = fresh_dir("lsl_config");
    const auto path = (dir / "lsl_api.cfg").string();
    std::ofstream(path) << "[ports]\nIPv6 = disable\n"
                        << "[multicast]\nResolveScope = machine\nInterfaces = {127.0.0.1}\n"
                        << "[lab]\nKnownPeers = {127.0.0.1}\n";
    setenv("LSLAPICFG", path.c_str(), 1);
  }
};
[[maybe_unused]] const auto* const kLoopback = ::testing::AddGlobalTestEnvironment(new LoopbackOnly);

// The program, running: started with its output in `log`.
struct Running {
  pid_t pid = 0;
  std::string log;

  Running(const std::vector<std::string>& args, std::string log_path)
      : pid(curvlab::testing::spawn_curvlab(args, log_path)), log(std::move(log_path)) {}
  Running(const Running&) = delete;
  Running& operator=(const Running&) = delete;
  ~Running() {
    if (pid != 0) kill9();
  }
  bool exited() {
    int status = 0;
    if (pid == 0) return true;
    if (waitpid(pid, &status, WNOHANG) == 0) return false;
    exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    pid = 0;
    return true;
  }
  int wait() {
    int status = 0;
    if (pid != 0) waitpid(pid, &status, 0);
    if (pid != 0) exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    pid = 0;
    return exit_code;
  }
  void kill9() {
    kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);
    pid = 0;
  }
  std::string output() const {
    std::ifstream in(log);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  int exit_code = -1;
};

#ifdef CURVLAB_WITH_LSL

// The session's UUID once the program has stored it (polled; empty when the
// program ended first or a minute passed).
std::string session_uuid(const std::string& db, Running& run) {
  for (int i = 0; i < 3000; ++i) {
    const auto rows = query(db, "SELECT session_uuid FROM sessions WHERE session_id = 1");
    if (!rows.empty() && rows[0][0] != "NULL") return rows[0][0];
    if (run.exited()) return {};
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return {};
}

// The session clock's nanoseconds on the LSL clock, through the stored
// reading nearest in time (lsl_clock).
struct ClockMap {
  std::vector<std::pair<std::int64_t, double>> readings;  // t_ns, lsl_time_s

  explicit ClockMap(const std::string& db) {
    for (const auto& row : query(db, "SELECT t_ns, lsl_time_s FROM lsl_clock WHERE session_id = 1 ORDER BY t_ns"))
      readings.emplace_back(std::stoll(row[0]), std::stod(row[1]));
  }
  [[nodiscard]] double to_lsl(std::int64_t t_ns) const {
    const auto nearest = std::min_element(readings.begin(), readings.end(), [t_ns](const auto& a, const auto& b) {
      return std::llabs(a.first - t_ns) < std::llabs(b.first - t_ns);
    });
    return nearest->second + static_cast<double>(t_ns - nearest->first) * 1e-9;
  }
};

std::unique_ptr<lsl::stream_inlet> subscribe(const std::string& source_id) {
  const auto found = lsl::resolve_stream("source_id='" + source_id + "'", 1, 60.0);
  if (found.empty()) return nullptr;
  auto inlet = std::make_unique<lsl::stream_inlet>(found.front());
  inlet->open_stream(60.0);
  return inlet;
}

// liblsl 1.16 sends every inlet one more sample as an outlet closes
// (tcp_server::end_serving's wake-up), with whatever its reused sample
// buffer held: a recorder sees it after the session's last marker and last
// frame. It is dropped here, at most one per stream.
struct Received {
  std::vector<std::pair<double, Json>> markers;  // time stamp, marker
  std::vector<std::pair<double, std::vector<float>>> poses;
};

// Pulls both streams until the program has exited and nothing is left.
Received receive_until_exit(lsl::stream_inlet& markers, lsl::stream_inlet& poses, Running& run) {
  std::vector<std::pair<double, std::string>> texts;
  Received got;
  std::vector<std::string> text;
  std::vector<float> pose;
  auto pull = [&](double timeout) {
    bool any = false;
    for (double ts = markers.pull_sample(text, 0.0); ts != 0.0; ts = markers.pull_sample(text, 0.0)) {
      texts.emplace_back(ts, text.at(0));
      any = true;
    }
    for (double ts = poses.pull_sample(pose, timeout); ts != 0.0; ts = poses.pull_sample(pose, 0.0)) {
      got.poses.emplace_back(ts, pose);
      any = true;
    }
    return any;
  };
  while (!run.exited()) pull(0.02);
  // What was still on its way when the program ended.
  while (pull(0.5)) {
  }
  for (const auto& [ts, t] : texts) {
    if (!got.markers.empty() && got.markers.back().second.at("event") == "session_end") {
      EXPECT_EQ(&t, &texts.back().second) << "markers after the session's end";
      break;
    }
    got.markers.emplace_back(ts, Json::parse(t));
  }
  return got;
}

std::map<std::string, int> count_by_kind(const std::vector<std::pair<double, Json>>& markers) {
  std::map<std::string, int> n;
  for (const auto& [ts, m] : markers) ++n[m.at("event").get<std::string>()];
  return n;
}

#endif

}  // namespace

TEST(LslBuild, LslIsRefusedWhereItCannotWork) {
#ifdef CURVLAB_WITH_LSL
  // The LSL clock is the machine's; a fast headless session's is simulated.
  const auto r = run_cli("run " + kDemo + " --participant P01 --db " +
                         (fresh_dir("lsl_fast") / "s.sqlite").string() + " --render none --lsl --quiet");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--pace realtime"), std::string::npos) << r.out;
  EXPECT_NE(run_cli("--version").out.find("with Lab Streaming Layer"), std::string::npos);
#else
  const auto r = run_cli("run " + kDemo + " --participant P01 --db " +
                         (fresh_dir("lsl_absent") / "s.sqlite").string() +
                         " --render none --pace realtime --lsl --quiet");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("built without Lab Streaming Layer"), std::string::npos) << r.out;
  EXPECT_NE(run_cli("--version").out.find("without Lab Streaming Layer"), std::string::npos);
#endif
}

TEST(LslSession, AnInletReceivesEveryMarkerAtItsMomentAndOnePoseSamplePerFrame) {
#ifndef CURVLAB_WITH_LSL
  GTEST_SKIP() << "curvlab was built without liblsl (run scripts/lsl.sh and configure with its prefix)";
#else
  const auto dir = fresh_dir("lsl_session");
  const auto db = (dir / "s.sqlite").string();
  Running run({"run", kDemo, "--participant", "P01", "--db", db, "--render", "none", "--pace", "realtime", "--lsl",
               "--lsl-wait-s", "60", "--quiet"},
              (dir / "run.log").string());
  const std::string uuid = session_uuid(db, run);
  ASSERT_FALSE(uuid.empty()) << run.output();
  auto markers = subscribe("curvlab-" + uuid + "-markers");
  auto poses = subscribe("curvlab-" + uuid + "-poses");
  ASSERT_TRUE(markers && poses) << "the session's streams were not found on the loopback\n" << run.output();
  EXPECT_EQ(poses->info().channel_count(), 24);
  EXPECT_EQ(poses->info(5.0).desc().child("channels").child("channel").child_value("label"), std::string("head_x"));
  const Received got = receive_until_exit(*markers, *poses, run);
  ASSERT_EQ(run.exit_code, 0) << run.output();
  ASSERT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");

  // Every event the session stored (but the two written with the session's
  // row, before any stream), every trial's end and answer, every block's
  // end, and the start: once each.
  std::map<std::string, int> stored;
  for (const auto& row : query(db, "SELECT kind, COUNT(*) FROM events WHERE session_id = 1 AND kind NOT IN "
                                   "('session_start', 'observer') GROUP BY kind"))
    stored[row[0]] = std::stoi(row[1]);
  stored["session_start"] = 1;
  stored["trial_end"] = std::stoi(query(db, "SELECT COUNT(*) FROM trials")[0][0]);
  stored["response"] = std::stoi(query(db, "SELECT COUNT(*) FROM trials WHERE response != 'timeout'")[0][0]);
  stored["block_end"] = std::stoi(query(db, "SELECT COUNT(*) FROM blocks")[0][0]);
  EXPECT_GT(stored["onset"], 0);
  EXPECT_EQ(count_by_kind(got.markers), stored);

  // Each onset marker is stamped with its trial's stored onset display time
  // on the LSL clock.
  const ClockMap clock(db);
  ASSERT_FALSE(clock.readings.empty());
  std::map<std::int64_t, std::int64_t> onset_of;
  for (const auto& row : query(db, "SELECT trial_id, onset_ns FROM trials WHERE onset_ns IS NOT NULL"))
    onset_of[std::stoll(row[0])] = std::stoll(row[1]);
  double largest_s = 0.0;
  int onsets = 0;
  for (const auto& [ts, m] : got.markers) {
    if (m.at("event") != "onset") continue;
    const auto trial = m.at("trial_id").get<std::int64_t>();
    ASSERT_TRUE(onset_of.contains(trial));
    largest_s = std::max(largest_s, std::abs(ts - clock.to_lsl(onset_of[trial])));
    ++onsets;
  }
  EXPECT_EQ(onsets, static_cast<int>(onset_of.size()));
  EXPECT_LT(largest_s, 1e-4);
  std::printf("onset markers: %d, largest difference from the stored onset on the LSL clock: %.3f us\n", onsets,
              largest_s * 1e6);

  // One pose sample per frame, at the frame's predicted display time.
  const auto frames = query(db, "SELECT predicted_display_ns FROM frames WHERE session_id = 1 ORDER BY frame_index");
  auto poses_got = got.poses;
  if (poses_got.size() == frames.size() + 1) poses_got.pop_back();  // the closing sample (Received)
  ASSERT_EQ(poses_got.size(), frames.size());
  double largest_pose_s = 0.0;
  for (std::size_t i = 0; i < frames.size(); ++i)
    largest_pose_s = std::max(largest_pose_s, std::abs(poses_got[i].first - clock.to_lsl(std::stoll(frames[i][0]))));
  EXPECT_LT(largest_pose_s, 1e-4);
  std::printf("pose samples: %zu for %zu frames, largest difference from the frame's display time: %.3f us\n",
              poses_got.size(), frames.size(), largest_pose_s * 1e6);
#endif
}

TEST(LslSession, AResumedSessionsStreamsComeBackWithTheSameSourceIds) {
#ifndef CURVLAB_WITH_LSL
  GTEST_SKIP() << "curvlab was built without liblsl (run scripts/lsl.sh and configure with its prefix)";
#else
  const auto dir = fresh_dir("lsl_resume");
  const auto db = (dir / "s.sqlite").string();
  std::string uid_before;
  std::string uuid;
  {
    Running run({"run", kDemo, "--participant", "P01", "--db", db, "--render", "none", "--pace", "realtime",
                 "--lsl", "--lsl-wait-s", "60", "--quiet"},
                (dir / "run.log").string());
    uuid = session_uuid(db, run);
    ASSERT_FALSE(uuid.empty()) << run.output();
    auto markers = subscribe("curvlab-" + uuid + "-markers");
    auto poses = subscribe("curvlab-" + uuid + "-poses");
    ASSERT_TRUE(markers && poses) << run.output();
    uid_before = markers->info(5.0).uid();
    // Killed once the first trial's onset has been streamed.
    std::vector<std::string> text;
    std::vector<float> pose;
    bool onset = false;
    while (!onset && !run.exited()) {
      if (markers->pull_sample(text, 0.05) != 0.0 && !text.at(0).empty())
        onset = Json::parse(text.at(0)).at("event") == "onset";
      while (poses->pull_sample(pose, 0.0) != 0.0) {
      }
    }
    ASSERT_TRUE(onset) << run.output();
    run.kill9();
  }
  ASSERT_EQ(query(db, "SELECT status FROM sessions")[0][0], "running");

  Running resumed({"resume", "--db", db, "--session", "1", "--render", "none", "--pace", "realtime", "--lsl",
                   "--lsl-wait-s", "60", "--quiet"},
                  (dir / "resume.log").string());
  auto markers = subscribe("curvlab-" + uuid + "-markers");
  auto poses = subscribe("curvlab-" + uuid + "-poses");
  ASSERT_TRUE(markers && poses) << "the resumed session's streams were not found by their source ids\n"
                                << resumed.output();
  EXPECT_NE(markers->info(5.0).uid(), uid_before) << "a new outlet, not the killed one";
  const Received got = receive_until_exit(*markers, *poses, resumed);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output();
  ASSERT_FALSE(got.markers.empty());
  EXPECT_EQ(got.markers.front().second.at("event"), "resume");
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");
  // The stored streams are the same two rows, run and resumed.
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM lsl_streams WHERE role = 'outlet'")[0][0], "2");
#endif
}

TEST(LslRecord, ATestOutletsMarkersLandInTheDatabaseAndTheExport) {
#ifndef CURVLAB_WITH_LSL
  GTEST_SKIP() << "curvlab was built without liblsl (run scripts/lsl.sh and configure with its prefix)";
#else
  const auto dir = fresh_dir("lsl_record");
  const auto db = (dir / "s.sqlite").string();
  const std::string name = "photodiode_" + std::to_string(getpid());
  lsl::stream_outlet outlet(lsl::stream_info(name, "Markers", 1, lsl::IRREGULAR_RATE, lsl::cf_string, name));
  Running run({"run", kDemo, "--participant", "P01", "--db", db, "--render", "none", "--pace", "realtime",
               "--lsl-record", name, "--export", (dir / "export").string(), "--quiet"},
              (dir / "run.log").string());
  ASSERT_TRUE(outlet.wait_for_consumers(60.0)) << run.output();
  std::vector<double> sent;
  for (int k = 0; k < 20; ++k) {
    const std::string text = "flash " + std::to_string(k);
    sent.push_back(lsl::local_clock());
    outlet.push_sample(&text, sent.back());
  }
  ASSERT_EQ(run.wait(), 0) << run.output();

  const auto rows = query(db, "SELECT s.value, s.lsl_time_s, s.lsl_offset_s, s.t_ns FROM lsl_samples s JOIN "
                              "lsl_streams r USING (lsl_stream_id) WHERE r.name = '" + name +
                                  "' AND r.role = 'recorded' ORDER BY s.lsl_sample_id");
  ASSERT_EQ(rows.size(), sent.size());
  const auto reading = query(db, "SELECT t_ns, lsl_time_s FROM lsl_clock ORDER BY t_ns LIMIT 1");
  ASSERT_FALSE(reading.empty());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(Json::parse(rows[k][0]), Json::array({"flash " + std::to_string(k)}));
    EXPECT_NEAR(std::stod(rows[k][1]), sent[k], 1e-7);
    // On the session clock through the stored mapping and offset.
    const double lsl_s = std::stod(rows[k][1]) + std::stod(rows[k][2]);
    const double expected_ns =
        static_cast<double>(std::stoll(reading[0][0])) + (lsl_s - std::stod(reading[0][1])) * 1e9;
    EXPECT_NEAR(static_cast<double>(std::stoll(rows[k][3])), expected_ns, 1e5);
  }
  // The streams' stored descriptions name no machine (DESIGN.md §7).
  for (const auto& row : query(db, "SELECT info_xml FROM lsl_streams")) {
    EXPECT_EQ(row[0].find("hostname"), std::string::npos) << row[0];
    EXPECT_EQ(row[0].find("address"), std::string::npos) << row[0];
    EXPECT_NE(row[0].find("<source_id>" + name + "</source_id>"), std::string::npos) << row[0];
  }
  // The export's extra table has them too.
  std::ifstream csv(dir / "export" / "csv" / "lsl_samples.csv");
  ASSERT_TRUE(csv) << "no lsl_samples.csv in the export";
  std::stringstream text;
  text << csv.rdbuf();
  EXPECT_NE(text.str().find("flash 19"), std::string::npos) << text.str().substr(0, 2000);
#endif
}

// A headset session (the scripted OpenXR runtime of tests/xr/runtime, with
// per-eye gaze) streams the gaze it tracks: each sample at its frame's
// display time, with the stored gaze's values.
TEST(LslXr, AHeadsetSessionStreamsTheGazeItTracks) {
#ifndef CURVLAB_WITH_LSL
  GTEST_SKIP() << "curvlab was built without liblsl (run scripts/lsl.sh and configure with its prefix)";
#else
  const auto dir = fresh_dir("lsl_xr");
  const auto db = (dir / "xr.sqlite").string();
  // The runtime and what it scripts, for the program only.
  setenv("XR_RUNTIME_JSON", CURVLAB_TEST_XR_RUNTIME_JSON, 1);
  setenv("CURVLAB_TEST_XR_GAZE", "both:vergence=1.5:0.9,0.7", 1);
  setenv("CURVLAB_TEST_XR_PRESS", "right:a@1.0/1.8,left:x@1.6/1.8,right:trigger@2.2/1.8", 1);
  Running run({"run", std::string(CURVLAB_SOURCE_DIR) + "/tests/xr/demo_buttons.toml", "--participant", "G01",
               "--backend", "xr", "--db", db, "--lsl", "--lsl-wait-s", "60", "--quiet"},
              (dir / "run.log").string());
  for (const char* v : {"XR_RUNTIME_JSON", "CURVLAB_TEST_XR_GAZE", "CURVLAB_TEST_XR_PRESS"}) unsetenv(v);
  const std::string uuid = session_uuid(db, run);
  ASSERT_FALSE(uuid.empty()) << run.output();
  auto markers = subscribe("curvlab-" + uuid + "-markers");
  auto poses = subscribe("curvlab-" + uuid + "-poses");
  ASSERT_TRUE(markers && poses) << run.output();
  // The gaze stream appears with the first frame that has gaze.
  auto gaze = subscribe("curvlab-" + uuid + "-gaze");
  ASSERT_TRUE(gaze) << run.output();
  EXPECT_EQ(gaze->info(5.0).desc().child("channels").child("channel").next_sibling().child_value("label"),
            std::string("combined_origin_x"));
  std::vector<std::pair<double, std::vector<float>>> got;
  std::vector<float> sample;
  std::vector<std::string> text;
  std::vector<float> pose;
  auto pull = [&](double timeout) {
    bool any = false;
    for (double ts = gaze->pull_sample(sample, timeout); ts != 0.0; ts = gaze->pull_sample(sample, 0.0)) {
      got.emplace_back(ts, sample);
      any = true;
    }
    while (markers->pull_sample(text, 0.0) != 0.0 || poses->pull_sample(pose, 0.0) != 0.0) {
    }
    return any;
  };
  while (!run.exited()) pull(0.02);
  while (pull(0.5)) {
  }
  ASSERT_EQ(run.exit_code, 0) << run.output();

  // Each sample is a stored gaze row's: the one of the frame at its time
  // (the last sample may be the one liblsl sends as the outlet closes).
  const ClockMap clock(db);
  const auto rows = query(db, "SELECT t_ns, left_valid, right_valid, left_confidence, vergence_rad, "
                              "coalesce(combined_valid, 0) "
                              "FROM gaze_samples WHERE session_id = 1 ORDER BY frame_index");
  ASSERT_GT(got.size(), 10u);
  ASSERT_FALSE(rows.empty());
  std::size_t matched = 0;
  for (const auto& [ts, v] : got) {
    const auto row = std::find_if(rows.begin(), rows.end(), [&](const auto& r) {
      return std::abs(clock.to_lsl(std::stoll(r[0])) - ts) < 1e-4;
    });
    if (row == rows.end()) continue;
    ++matched;
    EXPECT_EQ(v[0], std::stof((*row)[5]));
    EXPECT_EQ(v[7], std::stof((*row)[1]));
    EXPECT_EQ(v[15], std::stof((*row)[2]));
    EXPECT_NEAR(v[8], std::stod((*row)[3]), 1e-6);
    if ((*row)[4] != "NULL") {
      EXPECT_NEAR(v[23], std::stod((*row)[4]), 1e-6);
    }
  }
  EXPECT_GE(matched + 1, got.size());
  std::printf("gaze samples: %zu received, %zu matched to stored gaze rows (%zu stored)\n", got.size(), matched,
              rows.size());
#endif
}
