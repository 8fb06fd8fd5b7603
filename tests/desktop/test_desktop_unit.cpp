// Pure parts of the desktop backend: the key-script format and timing rule,
// the pilot body's start pose and movement, key names.
#include "desktop_backend.hpp"

#include "curvlab/harness/numbered_files.hpp"

#include <GLFW/glfw3.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <cstdlib>
#include <iostream>

namespace {

using namespace curvlab::harness::desktop;

TEST(KeyScript, ParsesKeysDelaysAndComments) {
  auto parsed = parse_key_script("# pilot\nspace\n\n2 150  # straight\nLEFT 0\n", "keys.txt");
  ASSERT_TRUE(parsed) << parsed.error().message;
  const auto& keys = parsed.value();
  ASSERT_EQ(keys.size(), 3u);
  EXPECT_EQ(keys[0].name, "space");
  EXPECT_EQ(keys[0].delay_ns, 300'000'000);
  EXPECT_EQ(keys[0].line, 2);
  EXPECT_EQ(keys[1].name, "2");
  EXPECT_EQ(keys[1].delay_ns, 150'000'000);
  EXPECT_EQ(keys[2].name, "left");
  EXPECT_EQ(keys[2].delay_ns, 0);
}

// A script saved in Latin-1 (Windows Notepad's é is 0xE9) is refused at load
// with its line, byte and column, before a session starts.
TEST(KeyScript, TextThatIsNotUtf8IsRefusedWithItsLineAndByte) {
  auto parsed = parse_key_script("space\n# Ren\xE9's pilot\n2 150\n", "keys.txt");
  ASSERT_FALSE(parsed);
  EXPECT_EQ(parsed.error().message,
            "keys.txt:2: the key script is not UTF-8 (byte 0xE9 at column 6); save the file as UTF-8");
  EXPECT_TRUE(parse_key_script("space\n# Ren\xC3\xA9's pilot\n2 150\n", "keys.txt"));
}

TEST(KeyScript, BadLinesNameFileLineAndWhatWasExpected) {
  for (const char* bad : {"1\n2 soon\n", "1\n2 -5\n", "1\n2 10 3\n", "1\n2 1.5\n"}) {
    auto parsed = parse_key_script(bad, "keys.txt");
    ASSERT_FALSE(parsed) << bad;
    const auto& message = parsed.error().message;
    EXPECT_EQ(message.rfind("keys.txt:2: expected `KEY [PHASE+DELAY_MS | DELAY_MS]`", 0), 0u) << message;
  }
  auto missing = load_key_script("/nonexistent/keys.txt");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("/nonexistent/keys.txt"), std::string::npos);
}

// A hand line puts a hand on a lab position (a table corner) for scripted
// calibrations; a malformed one names the form it expected.
TEST(KeyScript, HandLinesPlaceAHand) {
  auto parsed = parse_key_script("hand right -0.45 0.76 0.45 120\nspace\nhand left 0 1 -0.5\n", "keys.txt");
  ASSERT_TRUE(parsed) << parsed.error().message;
  const auto& keys = parsed.value();
  ASSERT_EQ(keys.size(), 3u);
  ASSERT_TRUE(keys[0].hand_m.has_value());
  EXPECT_FALSE(keys[0].left_hand);
  EXPECT_EQ(*keys[0].hand_m, glm::dvec3(-0.45, 0.76, 0.45));
  EXPECT_EQ(keys[0].delay_ns, 120'000'000);
  EXPECT_FALSE(keys[1].hand_m.has_value());
  EXPECT_TRUE(keys[2].left_hand);
  EXPECT_EQ(keys[2].delay_ns, 300'000'000);
  for (const char* bad : {"space\nhand middle 0 1 0\n", "space\nhand right 0 1\n", "space\nhand right 0 1 x\n",
                          "space\nhand right 0 1 40\n", "space\nhand right 0 1 0 10 3\n"}) {
    auto refused = parse_key_script(bad, "keys.txt");
    ASSERT_FALSE(refused) << bad;
    EXPECT_EQ(refused.error().message.rfind("keys.txt:2: expected `hand left|right X Y Z [PHASE+DELAY_MS | DELAY_MS]`", 0), 0u)
        << refused.error().message;
  }
}

// A binary file given as --key-script: the message shows the bytes it could
// not read as escapes, so the terminal is not sent control sequences.
TEST(KeyScript, UnprintableBytesInAMessageAreEscaped) {
  // Control bytes are UTF-8: the word is shown escaped. A byte that is not
  // UTF-8 (0xFF) stops the file before, named by its value.
  const char raw[] = "\x7f" "ELF\x02\x01 \x01\x00\x1b[2J\x07 x\n";
  const char not_utf8[] = "\x7f" "ELF\x02\x01 \x01\x00\xff\x1b[2J\x07 x\n";
  for (const auto& [text, expected] : {std::pair{std::string(raw, sizeof raw - 1), "'\\x01\\x00\\x1b[2J\\x07'"},
                                       std::pair{std::string(not_utf8, sizeof not_utf8 - 1), "(byte 0xFF at column 10)"}}) {
    auto parsed = parse_key_script(text, "a.out");
    ASSERT_FALSE(parsed);
    const auto& message = parsed.error().message;
    EXPECT_NE(message.find(expected), std::string::npos) << message;
    for (char c : message) {
      const auto byte = static_cast<unsigned char>(c);
      EXPECT_TRUE(byte >= 0x20 && byte < 0x7f) << "raw byte " << static_cast<int>(byte) << " in: " << message;
    }
  }
}

TEST(KeyScript, EachKeyWaitsForTheNextWaitAndItsDelay) {
  using curvlab::harness::io::Phase;
  KeyScriptPlayer player({{"space", 100, 1, std::nullopt, false, std::nullopt, false, std::nullopt}, {"2", 50, 2, std::nullopt, false, std::nullopt, false, std::nullopt}});
  constexpr std::int64_t ms = 1'000'000;
  EXPECT_FALSE(player.due(0));                       // nothing armed yet
  player.on_frame(Phase::fixation, false, 0);        // fixation: not waiting
  EXPECT_FALSE(player.due(1000 * ms));
  player.on_frame(Phase::instructions, true, 1000 * ms);  // a page waits: armed at 1000 ms
  player.on_frame(Phase::instructions, true, 1050 * ms);  // still the same wait: not re-armed
  EXPECT_FALSE(player.due(1000 * ms + 99));
  auto first = player.due(1000 * ms + 100);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->name, "space");
  // The frame that took the key still shows the page: it arms nothing.
  player.on_frame(Phase::instructions, true, 1100 * ms);
  EXPECT_FALSE(player.due(5000 * ms));
  player.on_frame(Phase::fixation, false, 5000 * ms);
  player.on_frame(Phase::stimulus, true, 6000 * ms);  // the trial waits for an answer
  EXPECT_FALSE(player.due(6000 * ms + 49));
  auto second = player.due(6000 * ms + 50);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->name, "2");
  EXPECT_TRUE(player.finished());
  player.on_frame(Phase::response, true, 7000 * ms);
  EXPECT_FALSE(player.due(9000 * ms));
}

// `2 response+150` after the last instruction page: the answer waits for the
// response window itself, however long fixation and stimulus last, and
// never lands in the fixation that follows the page.
TEST(KeyScript, APhaseKeyCountsFromThatPhasesStart) {
  using curvlab::harness::io::Phase;
  auto parsed = parse_key_script("space instructions+300\n2 response+150\n2 response+150\n", "keys.txt");
  ASSERT_TRUE(parsed) << parsed.error().message;
  ASSERT_EQ(parsed.value().size(), 3u);
  EXPECT_EQ(parsed.value()[1].phase, Phase::response);
  EXPECT_EQ(parsed.value()[1].delay_ns, 150'000'000);
  KeyScriptPlayer player(parsed.value());
  constexpr std::int64_t ms = 1'000'000;
  player.on_frame(Phase::instructions, true, 0);
  ASSERT_TRUE(player.due(300 * ms));
  player.on_frame(Phase::instructions, true, 300 * ms);  // the frame that took it
  for (std::int64_t t = 311; t < 811; t += 11) {         // 500 ms of fixation
    player.on_frame(Phase::fixation, false, t * ms);
    EXPECT_FALSE(player.due(t * ms)) << "pressed during fixation at " << t << " ms";
  }
  for (std::int64_t t = 811; t < 3811; t += 11) {        // 3 s of stimulus, which also takes answers
    player.on_frame(Phase::stimulus, true, t * ms);
    EXPECT_FALSE(player.due(t * ms)) << "pressed during the stimulus at " << t << " ms";
  }
  player.on_frame(Phase::response, true, 3811 * ms);
  EXPECT_FALSE(player.due(3960 * ms));
  auto answer = player.due(3961 * ms);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->name, "2");
  EXPECT_EQ(answer->line, 2);
  player.on_frame(Phase::response, true, 3972 * ms);  // took the answer
  player.on_frame(Phase::iti, false, 3983 * ms);
  EXPECT_FALSE(player.due(9000 * ms));  // the next answer waits for the next response window
  player.on_frame(Phase::response, true, 9000 * ms);
  EXPECT_TRUE(player.due(9150 * ms));
  EXPECT_TRUE(player.finished());
  EXPECT_EQ(player.last_line(), 3);
}

// A break page that must stay up 10 s: the page key's time counts from when
// the page accepts a key, not from when it appeared.
TEST(KeyScript, APageKeyCountsFromWhenThePageAcceptsKeys) {
  using curvlab::harness::io::Phase;
  KeyScriptPlayer player(parse_key_script("space break+300\n", "keys.txt").value());
  constexpr std::int64_t ms = 1'000'000;
  player.on_frame(Phase::break_page, false, 0);
  player.on_frame(Phase::break_page, false, 9990 * ms);
  EXPECT_FALSE(player.due(9990 * ms));
  player.on_frame(Phase::break_page, true, 10000 * ms);
  EXPECT_FALSE(player.due(10299 * ms));
  EXPECT_TRUE(player.due(10300 * ms));
}

// Standing rules: every instruction page and every response window gets its
// key, however many there are, and a line in order still comes first.
TEST(KeyScript, ARepeatLinePressesAtEveryStartOfItsPhase) {
  using curvlab::harness::io::Phase;
  auto parsed = parse_key_script("space instructions+300 repeat\n2 response+150 repeat\n", "keys.txt");
  ASSERT_TRUE(parsed) << parsed.error().message;
  KeyScriptPlayer player(parsed.value());
  constexpr std::int64_t ms = 1'000'000;
  std::int64_t t = 0;
  int spaces = 0;
  int answers = 0;
  // Two pages, then three trials; each frame 10 ms.
  const auto run = [&](Phase phase, bool waiting, int frames) {
    for (int i = 0; i < frames; ++i, t += 10 * ms) {
      if (auto k = player.due(t)) (k->name == "space" ? spaces : answers) += 1;
      player.on_frame(phase, waiting, t);
    }
  };
  // A page turns on the frame that takes its key (the 31st), as an answer
  // ends the response window on the frame that takes it (the 16th).
  run(Phase::instructions, true, 31);
  EXPECT_EQ(spaces, 1);
  run(Phase::instructions, true, 31);
  EXPECT_EQ(spaces, 2);
  for (int trial = 0; trial < 3; ++trial) {
    run(Phase::fixation, false, 50);
    run(Phase::stimulus, true, 100);
    run(Phase::response, true, 16);
    run(Phase::iti, false, 50);
  }
  EXPECT_EQ(spaces, 2);
  EXPECT_EQ(answers, 3);
  EXPECT_TRUE(player.finished());
  EXPECT_FALSE(parse_key_script("2 150 repeat\n", "keys.txt"));
  EXPECT_FALSE(parse_key_script("2 response+150 again\n", "keys.txt"));
}

// A script that stopped answering: a page that waits with the script used
// up ends the pilot after a stated wait, unless someone types.
TEST(KeyScript, AUsedUpScriptRunsOutAtAWaitingPage) {
  using curvlab::harness::io::Phase;
  KeyScriptPlayer player(parse_key_script("space\n", "keys.txt").value());
  constexpr std::int64_t ms = 1'000'000;
  player.on_frame(Phase::instructions, true, 0);
  ASSERT_TRUE(player.due(300 * ms));
  player.on_frame(Phase::instructions, true, 310 * ms);
  player.on_frame(Phase::break_page, true, 320 * ms);
  EXPECT_FALSE(player.ran_out(320 * ms + KeyScriptPlayer::kRunOutNs - 1));
  player.typed();
  player.on_frame(Phase::break_page, true, 400 * ms);
  EXPECT_FALSE(player.ran_out(320 * ms + KeyScriptPlayer::kRunOutNs));
  EXPECT_TRUE(player.ran_out(400 * ms + KeyScriptPlayer::kRunOutNs));
  EXPECT_EQ(player.ran_out_message("keys.txt", Phase::break_page),
            "the key script keys.txt ran out (its last key, line 1, was pressed) and the break page waited 5 s for a "
            "key; the session ends here, resumable");
}

TEST(KeyScript, ALineThatWouldLandInTheWrongPhaseIsRefusedWithItsLine) {
  KeyScriptLimits limits;
  limits.protocol = "study.toml";
  limits.fixation_ms = 500;
  limits.stimulus_ms = 3000;
  limits.response_ms = 4000;
  limits.iti_ms = 500;
  limits.answer_keys = {"1", "2", "3"};
  const auto check = [&limits](const std::string& text) {
    auto keys = parse_key_script(text, "keys.txt");
    EXPECT_TRUE(keys) << text;
    return check_key_script(keys.value(), "keys.txt", limits);
  };
  EXPECT_FALSE(check("space instructions+300\n2 response+150\n3 stimulus+2999\nspace break+100\n2 150\n"));
  const auto late = check("space\n2 response+150\n2 response+4000\n");
  ASSERT_TRUE(late);
  EXPECT_EQ(late->message,
            "keys.txt:3: '2 response+4000' would land in the iti, not the response (it lasts 4000 ms in study.toml); "
            "expected a delay below 4000 ms");
  const auto early = check("2 fixation+100\n");
  ASSERT_TRUE(early);
  EXPECT_EQ(early->message.rfind("keys.txt:1: '2' answers in study.toml, and an answer during fixation is an early "
                                 "input the trial drops",
                                 0),
            0u)
      << early->message;
  const auto bare = check("space\n\n1 7000\n");
  ASSERT_TRUE(bare);
  EXPECT_EQ(bare->message.rfind("keys.txt:3: '1 7000 ms' would answer after the response window closes", 0), 0u)
      << bare->message;
  auto unknown = parse_key_script("2 respons+150\n", "keys.txt");
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().message.rfind("keys.txt:1: expected `KEY [PHASE+DELAY_MS | DELAY_MS]` with WHEN a phase", 0), 0u)
      << unknown.error().message;
}

TEST(PilotBody, StartsAtTheTableLookingAtItsCentre) {
  PilotBody body;
  const auto frame = body.frame();
  const auto& head = frame[curvlab::geometry::Device::head];
  EXPECT_NEAR(head.position_m.y, 1.55, 1e-12);
  EXPECT_NEAR(head.position_m.z, 0.9, 1e-12);
  // The view direction (−z of the head) points at the table-top centre.
  const glm::dvec3 forward = head.orientation * glm::dvec3(0.0, 0.0, -1.0);
  const glm::dvec3 to_centre = glm::normalize(glm::dvec3(0.0, 0.76, 0.0) - head.position_m);
  EXPECT_NEAR(glm::dot(forward, to_centre), 1.0, 1e-12);
  // Hands below the eyes, in front, right hand to the right.
  const auto& left = frame[curvlab::geometry::Device::left_hand];
  const auto& right = frame[curvlab::geometry::Device::right_hand];
  EXPECT_LT(right.position_m.y, head.position_m.y);
  EXPECT_LT(right.position_m.z, head.position_m.z);
  EXPECT_GT(right.position_m.x, left.position_m.x);
}

TEST(PilotBody, KeysWalkInTheHeadingAndMouseTurnsIt) {
  PilotBody body;
  body.walk(1.0, 0.0, 0.0, 0.5);  // W for half a second toward the table
  EXPECT_NEAR(body.head_m().z, 0.9 - 0.4, 1e-12);
  EXPECT_NEAR(body.head_m().y, 1.55, 1e-12);  // walking keeps the height
  body.walk(0.0, 0.0, 1.0, 0.5);  // E: up
  EXPECT_NEAR(body.head_m().y, 1.75, 1e-12);
  // Mouse right by 100 px turns right (yaw decreases) by 0.3 rad; D then
  // strafes along the new right.
  const double yaw = body.yaw_rad();
  body.look(100.0, 0.0);
  EXPECT_NEAR(body.yaw_rad(), yaw - 0.3, 1e-12);
  const glm::dvec3 before = body.head_m();
  body.walk(0.0, 1.0, 0.0, 1.0);
  const glm::dvec3 step = body.head_m() - before;
  EXPECT_NEAR(step.x, 0.8 * std::cos(0.3), 1e-12);
  EXPECT_NEAR(step.z, 0.8 * std::sin(0.3), 1e-12);  // facing right of −z, right leans to +z
  // Pitch stops short of straight down.
  body.look(0.0, 1e6);
  EXPECT_GT(body.pitch_rad(), -1.5);
  body.reset();
  EXPECT_NEAR(body.head_m().z, 0.9, 1e-12);
}

TEST(PilotBody, HandsMoveWithinReach) {
  PilotBody body;
  const auto before = body.frame()[curvlab::geometry::Device::right_hand].position_m;
  body.move_hand(Hand::right, 50.0, -25.0, 0.0);  // right and up
  const auto after = body.frame()[curvlab::geometry::Device::right_hand].position_m;
  EXPECT_NEAR(after.x - before.x, 0.1, 1e-12);
  EXPECT_NEAR(after.y - before.y, 0.05, 1e-12);
  body.move_hand(Hand::left, 0.0, 0.0, 1000.0);  // scrolled far forward
  const auto moved = body.frame();
  EXPECT_LE(glm::length(moved[curvlab::geometry::Device::left_hand].position_m -
                        moved[curvlab::geometry::Device::head].position_m),
            0.9 + 1e-9);
}

// A placed hand is where it was put, and then moves with the head.
TEST(PilotBody, APlacedHandIsWhereItWasPutAndFollowsTheHead) {
  PilotBody body;
  body.look(80.0, 0.0);  // turned away from the start heading
  const glm::dvec3 corner(-0.45, 0.76, 0.45);
  body.place_hand(Hand::right, corner);
  EXPECT_LT(glm::length(body.frame()[curvlab::geometry::Device::right_hand].position_m - corner), 1e-12);
  body.walk(1.0, 0.0, 0.0, 0.25);  // 0.2 m forward
  const auto moved = body.frame()[curvlab::geometry::Device::right_hand].position_m;
  EXPECT_NEAR(glm::length(moved - corner), 0.2, 1e-12);
}

TEST(KeyNames, GlfwStyleLowerCase) {
  EXPECT_EQ(key_name(GLFW_KEY_1), "1");
  EXPECT_EQ(key_name(GLFW_KEY_A), "a");
  EXPECT_EQ(key_name(GLFW_KEY_LEFT), "left");
  EXPECT_EQ(key_name(GLFW_KEY_SPACE), "space");
  EXPECT_EQ(key_name(GLFW_KEY_ENTER), "enter");
  EXPECT_EQ(key_name(GLFW_KEY_ESCAPE), "escape");
  EXPECT_EQ(key_name(GLFW_KEY_F12), "f12");
  EXPECT_EQ(key_name(GLFW_KEY_KP_3), "kp_3");
  EXPECT_EQ(key_name(GLFW_KEY_UNKNOWN), "");
}

TEST(DesktopBackend, WithoutADisplayNamesTheGlfwErrorAndTheFix) {
  // This process never opens a window, so GLFW initialises here, without X.
  unsetenv("DISPLAY");
  unsetenv("WAYLAND_DISPLAY");
  curvlab::harness::io::SteadyClock clock;
  curvlab::harness::desktop::DesktopOptions options;
  options.clock = &clock;
  auto made = curvlab::harness::desktop::make_desktop_backend(options);
  ASSERT_FALSE(made.has_value());
  EXPECT_EQ(made.error().kind, curvlab::harness::Error::Kind::device);
  const auto& message = made.error().message;
  EXPECT_NE(message.find("glfwInit failed"), std::string::npos) << message;
  EXPECT_NE(message.find("GLFW_PLATFORM_ERROR"), std::string::npos) << message;
  EXPECT_NE(message.find("DISPLAY"), std::string::npos) << message;
  EXPECT_NE(message.find("xvfb-run"), std::string::npos) << message;
  std::cout << message << '\n';
}

TEST(DesktopBackend, BadOptionsAreRefusedBeforeAnyWindow) {
  curvlab::harness::io::SteadyClock clock;
  curvlab::harness::desktop::DesktopOptions options;
  auto no_clock = curvlab::harness::desktop::make_desktop_backend(options);
  ASSERT_FALSE(no_clock.has_value());
  options.clock = &clock;
  options.key_script = "/nonexistent/keys.txt";
  auto no_script = curvlab::harness::desktop::make_desktop_backend(options);
  ASSERT_FALSE(no_script.has_value());
  EXPECT_NE(no_script.error().message.find("keys.txt"), std::string::npos);
}

}  // namespace

TEST(PilotLegend, SaysWhichKeysAnswerAndHowPagesContinue) {
  using curvlab::harness::io::Overlay;
  using curvlab::harness::io::Phase;
  Overlay page(Phase::break_page, "Take a short break.", true);
  EXPECT_EQ(legend_text(page), "space: continue");
  Overlay response(Phase::response, "block main · trial 3 of 8", true);
  response.prompt = "Convex, straight or concave?";
  response.answers = {{"convex", {"1", "left"}, {"left_trigger"}}, {"straight", {"2"}, {}},
                      {"concave", {}, {"right_trigger"}}};
  response.value = "stimulus.stick_sagitta_m = 0.0125";
  EXPECT_EQ(legend_text(response),
            "Convex, straight or concave?  1/left convex · 2 straight · concave: no key  "
            "(stimulus.stick_sagitta_m = 0.0125)");
  EXPECT_EQ(legend_text(Overlay(Phase::fixation, "", false)), "");
}

TEST(NumberedFiles, ANewImageNeverTakesAnOlderOnesName) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "curvlab_numbered_files";
  fs::remove_all(dir);
  fs::create_directories(dir);
  EXPECT_EQ(curvlab::harness::unused_stem(dir, "trial_0004"), "trial_0004");
  EXPECT_EQ(curvlab::harness::highest_number(dir, "stimulus_"), 0);
  for (const char* name : {"trial_0004_left.png", "trial_0004.json", "trial_0004_2_left.png", "trial_00045_left.png",
                           "stimulus_007_left.png", "stimulus_012_window.png", "stimulus_x.png"})
    std::ofstream(dir / name) << "x";
  EXPECT_EQ(curvlab::harness::unused_stem(dir, "trial_0004"), "trial_0004_3");
  EXPECT_EQ(curvlab::harness::unused_stem(dir, "trial_0005"), "trial_0005");
  EXPECT_EQ(curvlab::harness::highest_number(dir, "stimulus_"), 12);
  EXPECT_EQ(curvlab::harness::highest_number(dir / "missing", "stimulus_"), 0);
  fs::remove_all(dir);
}
