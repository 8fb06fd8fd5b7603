// Two curvlab processes on the loopback play one shared game
// (docs/shared_play.md): each with its own database, simulated players
// taking turns, in S3, E3 and H3, and through the seeded relay with 5% loss
// and 50 ms delay each way. Both files must hold the same shots — inputs,
// events and rest states — and the same game. Stations that differ are
// refused before either writes anything. Sessions run in real time (the
// link needs a real clock): these tests run alone.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <sstream>
#include <unistd.h>

#include "../desktop/xvfb.hpp"
#include "../support/edited_file.hpp"
#include "../support/png_files.hpp"
#include "run_and_kill.hpp"
#include "run_cli.hpp"
#include "session_db.hpp"
#include "udp_relay.hpp"

using curvlab::testing::CliResult;
using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_cli;
using Json = nlohmann::ordered_json;

namespace {

// A play-only protocol: four turns at a rack of three (played out even when
// the rack is cleared sooner).
std::string protocol(const std::string& space, const std::string& extra = "") {
  std::ifstream in(std::string(CURVLAB_SOURCE_DIR) + "/protocols/adaptation_play.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string t = ss.str();
  t = t.substr(0, t.find("[[blocks]]"));
  const std::string from = "levels = [\"E3\", \"H3\"]";
  t.replace(t.find(from), from.size(), "levels = [\"S3\", \"E3\", \"H3\"]");
  t += "[[blocks]]\nname = \"play\"\nkind = \"play\"\nlevels = { space = \"" + space +
       "\" }\nduration_s = 120\nshots = 4\nuntil = \"time\"\nrack = 3\n" + extra;
  return t;
}

std::string write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

// A port for this process's host: test suites of two checkouts may run at once.
std::uint16_t port_for(int k) { return static_cast<std::uint16_t>(20000 + (::getpid() % 4000) * 8 + k); }

std::string station(const std::string& protocol_file, const std::string& participant, const std::string& db,
                    const std::string& shared) {
  return "run " + protocol_file + " --participant " + participant + " --db " + db +
         " --render none --pace realtime --partner-wait-s 30 --json " + shared;
}

struct Pair {
  CliResult host, join;
};

Pair play(const std::string& host_protocol, const std::string& join_protocol, const std::filesystem::path& dir,
          std::uint16_t host_port, std::uint16_t join_to) {
  auto host = std::async(std::launch::async, [&] {
    return run_cli(station(host_protocol, "HOST01", (dir / "host.sqlite").string(),
                           "--shared host --bind 127.0.0.1 --listen " + std::to_string(host_port)));
  });
  auto join = std::async(std::launch::async, [&] {
    return run_cli(station(join_protocol, "JOIN01", (dir / "join.sqlite").string(),
                           "--shared join --partner 127.0.0.1:" + std::to_string(join_to)));
  });
  return {host.get(), join.get()};
}

void expect_same_game(const std::filesystem::path& dir, std::size_t shots = 4) {
  const std::string a = (dir / "host.sqlite").string(), b = (dir / "join.sqlite").string();
  const std::string shots_sql =
      "SELECT shot_index, player, ball, shot, before_state, events, rest_state, pocketed FROM shots ORDER BY shot_index";
  const auto shots_a = query(a, shots_sql);
  const auto shots_b = query(b, shots_sql);
  EXPECT_EQ(shots_a.size(), shots);
  EXPECT_EQ(shots_a, shots_b);
  const std::string game_sql = "SELECT json_extract(detail, '$.game_uuid') FROM events WHERE kind = 'shared_game'";
  const auto game_a = query(a, game_sql);
  const auto game_b = query(b, game_sql);
  ASSERT_EQ(game_a.size(), 1u);
  ASSERT_FALSE(game_b.empty());
  for (const auto& g : game_b) EXPECT_EQ(g, game_a[0]);  // a rejoined station: one row per (re)join
  for (const auto& db : {a, b}) {
    // Each station shot the turns of its role and agreed with the other's.
    const auto turns = query(db, "SELECT json_extract(detail, '$.shot_index'), json_extract(detail, '$.shooter'), "
                                 "json_extract(detail, '$.same_events'), json_extract(detail, '$.rest_difference_m') "
                                 "FROM events WHERE kind = 'shared_shot' ORDER BY event_id");
    ASSERT_EQ(turns.size(), shots) << db;
    for (const auto& t : turns) {
      EXPECT_EQ(t[1], std::stoi(t[0]) % 2 == 0 ? "host" : "join") << db;
      EXPECT_EQ(t[2], "1") << db;
      EXPECT_EQ(std::stod(t[3]), 0.0) << db;
    }
    EXPECT_FALSE(query(db, "SELECT 1 FROM events WHERE kind = 'partner_clock'").empty()) << db;
    // The partner as drawn: head, hands and cue at each frame, the head
    // rows with the two heads' distance in the virtual space.
    const auto devices = query(db, "SELECT device, count(*) FROM partner_samples GROUP BY device ORDER BY device");
    ASSERT_EQ(devices.size(), 4u) << db;
    EXPECT_GT(std::stoi(devices[0][1]), 20) << db;
    const auto far = query(db, "SELECT count(distance_m), min(distance_m), max(distance_m) FROM partner_samples "
                               "WHERE device = 'head'");
    EXPECT_GT(std::stoi(far[0][0]), 20) << db;
    EXPECT_GT(std::stod(far[0][1]), 0.1) << "two players at one point: " << db;
    EXPECT_LT(std::stod(far[0][2]), 10.0) << db;
    const auto net = query(db, "SELECT json_extract(detail, '$.poses_received') FROM events WHERE kind = 'shared_network'");
    ASSERT_FALSE(net.empty()) << db;
    EXPECT_GT(std::stoi(net.back()[0]), 0) << db;
  }
}

// `curvlab merge` pools the two files; the game links the two sessions.
void expect_merged_game(const std::filesystem::path& dir) {
  const std::string study = (dir / "study.sqlite").string();
  const auto r = run_cli("merge --out " + study + " " + (dir / "host.sqlite").string() + " " +
                         (dir / "join.sqlite").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto players = query(study, "SELECT json_extract(detail, '$.game_uuid'), json_extract(detail, '$.role'), "
                                    "session_id FROM events WHERE kind = 'shared_game' ORDER BY 2");
  ASSERT_EQ(players.size(), 2u);
  EXPECT_EQ(players[0][0], players[1][0]);
  EXPECT_EQ(players[0][1], "host");
  EXPECT_EQ(players[1][1], "join");
  EXPECT_NE(players[0][2], players[1][2]);
  // Each session keeps its copy of the game's shots and of its partner as drawn.
  EXPECT_EQ(query(study, "SELECT 1 FROM shots").size(), 8u);
  const auto drawn = [](const std::string& db) {
    return std::stoll(query(db, "SELECT count(*) FROM partner_samples")[0][0]);
  };
  EXPECT_EQ(drawn(study), drawn((dir / "host.sqlite").string()) + drawn((dir / "join.sqlite").string()));
  // The distance between the two heads is one quantity seen from both
  // stations: their means agree to within the partner stream's latency.
  const auto means = query(study, "SELECT avg(distance_m) FROM partner_samples WHERE device = 'head' "
                                  "GROUP BY session_id ORDER BY session_id");
  ASSERT_EQ(means.size(), 2u);
  EXPECT_NEAR(std::stod(means[0][0]), std::stod(means[1][0]), 0.25);
  std::printf("heads apart in the virtual space: %.3f m (host's view), %.3f m (joiner's view)\n",
              std::stod(means[0][0]), std::stod(means[1][0]));
}

// The report on the merged study shows the game from both stations, each
// copy with the same shots struck and balls pocketed by host and joiner.
void expect_report_shows_both_sides(const std::filesystem::path& dir) {
  if (::access("/usr/bin/Rscript", X_OK) != 0) {
    std::printf("Rscript not found: the report's part of this test did not run\n");
    return;
  }
  const auto out = dir / "report";
  const auto r = curvlab::testing::run_shell("/usr/bin/Rscript " + std::string(CURVLAB_SOURCE_DIR) +
                                             "/analysis/report.R --db " + (dir / "study.sqlite").string() +
                                             " --out " + out.string() + " --quiet 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string html = curvlab::test::read_text((out / "report.html").string());
  const auto at = html.find("<h3>Shared games</h3>");
  ASSERT_NE(at, std::string::npos);
  const std::string section = html.substr(at, html.find("</table>", at) - at);
  EXPECT_NE(section.find("<td>host</td>"), std::string::npos) << section;
  EXPECT_NE(section.find("<td>join</td>"), std::string::npos) << section;
  std::size_t agree = 0;
  for (auto p = section.find("<td>yes</td>"); p != std::string::npos; p = section.find("<td>yes</td>", p + 1)) ++agree;
  EXPECT_EQ(agree, 2u) << section;
  EXPECT_NE(section.find("partner_<wbr>distance_<wbr>m"), std::string::npos) << section;
}

}  // namespace

TEST(SharedPlay, TwoStationsPlayTheSameGameInEverySpace) {
  int k = 0;
  for (const std::string space : {"S3", "E3", "H3"}) {
    SCOPED_TRACE(space);
    const auto dir = fresh_dir("shared_" + space);
    const std::string p = write(dir / "p.toml", protocol(space));
    const std::uint16_t port = port_for(k++);
    const Pair r = play(p, p, dir, port, port);
    ASSERT_EQ(r.host.exit_code, 0) << r.host.out;
    ASSERT_EQ(r.join.exit_code, 0) << r.join.out;
    expect_same_game(dir);
    expect_merged_game(dir);
    if (space == "H3") expect_report_shows_both_sides(dir);
  }
}

TEST(SharedPlay, ThroughALossyDelayingRelayTheGameIsStillTheSame) {
  const auto dir = fresh_dir("shared_relay");
  const std::string p = write(dir / "p.toml", protocol("H3"));
  const std::uint16_t port = port_for(4);
  std::string error;
  auto relay = curvlab::test::UdpRelay::start(
      {.target_port = port, .loss = 0.05, .delay_ns = 50'000'000, .jitter_ns = 5'000'000, .reorder = 0.01, .seed = 5},
      &error);
  ASSERT_TRUE(relay) << error;
  const Pair r = play(p, p, dir, port, relay->port());
  ASSERT_EQ(r.host.exit_code, 0) << r.host.out;
  ASSERT_EQ(r.join.exit_code, 0) << r.join.out;
  expect_same_game(dir);
  EXPECT_GT(relay->counters().dropped, 0u);
  // The round trip the stations measured holds the relay's 2 × 50 ms.
  const auto rtt = query((dir / "host.sqlite").string(),
                         "SELECT json_extract(detail, '$.round_trip_ns') FROM events WHERE kind = 'partner_clock' "
                         "ORDER BY event_id DESC LIMIT 1");
  ASSERT_EQ(rtt.size(), 1u);
  EXPECT_GE(std::stoll(rtt[0][0]), 100'000'000LL);
}

// The joiner killed after its first stored shot and resumed: the host pauses
// and goes on, the joiner gets the shots it missed, the files agree.
TEST(SharedPlay, AKilledJoinerResumesAndRejoinsTheSameGame) {
  const auto dir = fresh_dir("shared_rejoin");
  const std::string p = write(dir / "p.toml", protocol("E3"));
  const std::uint16_t port = port_for(6);
  const std::string host_db = (dir / "host.sqlite").string(), join_db = (dir / "join.sqlite").string();
  auto host = std::async(std::launch::async, [&] {
    return run_cli(station(p, "HOST01", host_db, "--shared host --bind 127.0.0.1 --listen " + std::to_string(port)));
  });
  const bool killed = curvlab::testing::run_and_kill(
      {"run", p, "--participant", "JOIN01", "--db", join_db, "--render", "none", "--pace", "realtime",
       "--partner-wait-s", "30", "--shared", "join", "--partner", "127.0.0.1:" + std::to_string(port)},
      std::chrono::milliseconds(300), [&] {
        return std::filesystem::exists(join_db) &&
               !query(join_db, "SELECT 1 FROM shots").empty();
      });
  ASSERT_TRUE(killed);
  // Longer than the link's 3 s timeout: the host notices on its own.
  std::this_thread::sleep_for(std::chrono::seconds(5));
  const auto resumed = run_cli("resume --db " + join_db + " --session 1 --json --shared join --partner 127.0.0.1:" +
                               std::to_string(port));
  const auto h = host.get();
  ASSERT_EQ(h.exit_code, 0) << h.out;
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out;
  expect_same_game(dir);
  const auto pause = query(host_db, "SELECT kind FROM events WHERE kind IN ('partner_left', 'partner_back') ORDER BY event_id");
  ASSERT_EQ(pause.size(), 2u);
  EXPECT_EQ(pause[0][0], "partner_left");
  EXPECT_EQ(pause[1][0], "partner_back");
  EXPECT_EQ(query(join_db, "SELECT 1 FROM events WHERE kind = 'shared_game'").size(), 2u);
}

// The host killed after its first stored shot and resumed: the joiner
// pauses, names the game, and the host rejoins it.
TEST(SharedPlay, AKilledHostResumesAndRejoinsTheSameGame) {
  const auto dir = fresh_dir("shared_host_rejoin");
  const std::string p = write(dir / "p.toml", protocol("S3"));
  const std::uint16_t port = port_for(7);
  const std::string host_db = (dir / "host.sqlite").string(), join_db = (dir / "join.sqlite").string();
  auto join = std::async(std::launch::async, [&] {
    return run_cli(station(p, "JOIN01", join_db, "--shared join --partner 127.0.0.1:" + std::to_string(port)));
  });
  const bool killed = curvlab::testing::run_and_kill(
      {"run", p, "--participant", "HOST01", "--db", host_db, "--render", "none", "--pace", "realtime",
       "--partner-wait-s", "30", "--shared", "host", "--bind", "127.0.0.1", "--listen", std::to_string(port)},
      std::chrono::milliseconds(300), [&] {
        return std::filesystem::exists(host_db) && !query(host_db, "SELECT 1 FROM shots").empty();
      });
  ASSERT_TRUE(killed);
  std::this_thread::sleep_for(std::chrono::seconds(5));
  const auto resumed = run_cli("resume --db " + host_db + " --session 1 --json --shared host --bind 127.0.0.1 --listen " +
                               std::to_string(port));
  const auto j = join.get();
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out;
  ASSERT_EQ(j.exit_code, 0) << j.out;
  const std::string game_sql = "SELECT json_extract(detail, '$.game_uuid') FROM events WHERE kind = 'shared_game'";
  const auto host_games = query(host_db, game_sql);
  const auto join_games = query(join_db, game_sql);
  ASSERT_EQ(host_games.size(), 2u);
  ASSERT_EQ(join_games.size(), 1u);
  EXPECT_EQ(host_games[0], join_games[0]);
  EXPECT_EQ(host_games[1], join_games[0]);
  const std::string shots_sql = "SELECT shot_index, shot, before_state, events, rest_state FROM shots ORDER BY shot_index";
  const auto a = query(host_db, shots_sql);
  EXPECT_EQ(a.size(), 4u);
  EXPECT_EQ(a, query(join_db, shots_sql));
  const auto pause = query(join_db, "SELECT kind FROM events WHERE kind IN ('partner_left', 'partner_back') ORDER BY event_id");
  ASSERT_EQ(pause.size(), 2u);
  EXPECT_EQ(pause[0][0], "partner_left");
  EXPECT_EQ(pause[1][0], "partner_back");
}

TEST(SharedPlay, StationsWithDifferentProtocolsAreRefusedBeforeAnythingIsWritten) {
  const auto dir = fresh_dir("shared_refused");
  const std::string a = write(dir / "a.toml", protocol("E3"));
  const std::string b = write(dir / "b.toml", protocol("E3", "\n[blocks.physics]\nmu_roll = 0.02\n"));
  const std::uint16_t port = port_for(5);
  const Pair r = play(a, b, dir, port, port);
  EXPECT_EQ(r.host.exit_code, 2) << r.host.out;
  EXPECT_EQ(r.join.exit_code, 2) << r.join.out;
  for (const auto* out : {&r.host.out, &r.join.out}) {
    EXPECT_NE(out->find("The protocols differ"), std::string::npos) << *out;
    EXPECT_NE(out->find("play.0.physics.mu_roll"), std::string::npos) << *out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "host.sqlite"));
  EXPECT_FALSE(std::filesystem::exists(dir / "join.sqlite"));
}

TEST(SharedPlay, ASharedRunNeedsRealTimeAndAPort) {
  const auto dir = fresh_dir("shared_usage");
  const std::string p = write(dir / "p.toml", protocol("E3"));
  auto r = run_cli("run " + p + " --participant A --db " + (dir / "x.sqlite").string() + " --shared host --listen 7000");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--pace realtime"), std::string::npos) << r.out;
  r = run_cli("run " + p + " --participant A --db " + (dir / "x.sqlite").string() + " --pace realtime --shared join");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("--partner HOST:PORT"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.sqlite"));
}

namespace {

// Pixels of the upper half of an eye's image that `is` picks.
int count_upper(const curvlab::renderer::Rgba8Image& image, const std::function<bool(int, int, int)>& is) {
  int n = 0;
  for (int y = 0; y < image.height / 2; ++y)
    for (int x = 0; x < image.width; ++x) {
      const auto* p = &image.pixels[4 * (static_cast<std::size_t>(y) * image.width + x)];
      n += is(p[0], p[1], p[2]) ? 1 : 0;
    }
  return n;
}

}  // namespace

// Two desktop pilots on one X display, each in its own window, the joiner
// standing across the E3 table from the host: the host sends a photo
// (--avatar), the joiner only its initials. In each station's F12
// screenshot the partner's head stands across the table, and the joiner sees
// the host's photo on its face, where the host sees initials.
TEST(SharedPlay, TwoDesktopWindowsShowEachPlayerThePartnersAvatar) {
  curvlab::test::XServer xserver;
  if (!xserver.available()) GTEST_SKIP() << "no X display: " << xserver.reason();
  const auto dir = fresh_dir("shared_avatar");
  std::string text = protocol("E3");
  text.replace(text.find("duration_s = 120"), 16, "duration_s = 6");
  const std::string p = write(dir / "p.toml", text);
  const std::string keys = write(dir / "keys.txt", "f12 stimulus+2500\nspace done+300\n");
  // A mid-grey face with a dark frame, 60 × 75 pixels.
  curvlab::renderer::Rgba8Image photo{60, 75, {}};
  for (int y = 0; y < photo.height; ++y)
    for (int x = 0; x < photo.width; ++x) {
      const std::uint8_t g = (x < 4 || y < 4 || x >= photo.width - 4 || y >= photo.height - 4) ? 20 : 170;
      photo.pixels.insert(photo.pixels.end(), {g, g, g, 255});
    }
  ASSERT_TRUE(curvlab::test::png_written(curvlab::renderer::write_png((dir / "face.png").string(), photo)));
  const std::uint16_t port = port_for(6);
  auto desktop = [&](const std::string& who, const std::string& shared) {
    std::filesystem::create_directories(dir / who);
    return run_cli("run " + p + " --participant " + who + " --db " + (dir / (who + ".sqlite")).string() +
                   " --backend desktop --software --window-size 320x320 --key-script " + keys + " --screenshot " +
                   (dir / who).string() + " --partner-wait-s 30 " + shared);
  };
  auto host = std::async(std::launch::async, [&] {
    return desktop("HOST01", "--shared host --bind 127.0.0.1 --listen " + std::to_string(port) + " --avatar " +
                                 (dir / "face.png").string());
  });
  auto join = std::async(std::launch::async, [&] {
    return desktop("JOIN01", "--shared join --initials JB --partner 127.0.0.1:" + std::to_string(port));
  });
  const CliResult h = host.get(), j = join.get();
  ASSERT_EQ(h.exit_code, 0) << h.out;
  ASSERT_EQ(j.exit_code, 0) << j.out;
  const auto blue = [](int r, int g, int b) { return b > 150 && b > r + 60 && b > g + 20; };
  const auto light_grey = [](int r, int g, int b) {
    return std::abs(r - g) < 12 && std::abs(g - b) < 12 && r > 90 && r < 235;
  };
  curvlab::renderer::Rgba8Image seen_by_host, seen_by_join;
  ASSERT_TRUE(curvlab::test::read_png_into((dir / "HOST01" / "screenshot_001_left.png").string(), seen_by_host));
  ASSERT_TRUE(curvlab::test::read_png_into((dir / "JOIN01" / "screenshot_001_left.png").string(), seen_by_join));
  EXPECT_GT(count_upper(seen_by_host, blue), 30) << "the host does not see the joiner's head";
  EXPECT_GT(count_upper(seen_by_join, blue), 30) << "the joiner does not see the host's head";
  const int photo_at_join = count_upper(seen_by_join, light_grey);
  const int photo_at_host = count_upper(seen_by_host, light_grey);
  EXPECT_GT(photo_at_join, 40) << "the host's photo is not on its avatar's face";
  EXPECT_GT(photo_at_join, 3 * photo_at_host) << "the joiner's initials card looks like a photo";
}
