// The experimenter's side of a headset session, through the real `curvlab`
// and loader on the scripted test runtime: the operator window under Xvfb
// (its screenshots show the participant's eye image and the status text),
// scripted operator actions (note, pause/resume, skip) stored as the data
// says they should be, and late frames the runtime scripts counted in
// frames.late and in the export's frames_late / onset_late.
#include "../cli/run_cli.hpp"
#include "../desktop/xvfb.hpp"
#include "../runner/session_db.hpp"
#include "../support/panel_ink.hpp"
#include "../support/png_files.hpp"
#include "runtime_env.hpp"

#include "curvlab/renderer/image_io.hpp"

#include <X11/Xlib.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

namespace {

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_cli;
using curvlab::testing::RuntimeEnv;
const std::string& kPresses = curvlab::testing::kScriptedPresses;
namespace fs = std::filesystem;

const std::string kProtocol = std::string(CURVLAB_SOURCE_DIR) + "/tests/xr/demo_buttons.toml";
nlohmann::json summary(const std::string& out) { return nlohmann::json::parse(out.substr(out.find('{'))); }

// Pixels of the screenshot's eye area (the top 430 rows) that are not the
// window's background, and distinct grey levels in the panel below it.
struct ShotStats {
  int eye_pixels = 0;
  int cloth_pixels = 0;
  int text_pixels = 0;
  std::set<int> panel_levels;
};

ShotStats inspect(const curvlab::renderer::Rgba8Image& img) {
  ShotStats s;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const auto* p = &img.pixels[static_cast<std::size_t>((y * img.width + x) * 4)];
      if (y < 430) {
        if (p[0] != 24 || p[1] != 24 || p[2] != 24) ++s.eye_pixels;
        // The cloth (0.10, 0.42, 0.20), lit: green well above red and blue.
        if (p[1] > 40 && p[1] > p[0] + 25 && p[1] > p[2] + 15) ++s.cloth_pixels;
      } else if (y >= 440) {
        s.panel_levels.insert(p[0]);
        if (p[0] > 150) ++s.text_pixels;
      }
    }
  return s;
}

}  // namespace

// The operator takes notes, pauses and resumes the participant, and skips a
// trial; the window's screenshots show the headset's image and the status.
TEST(XrOperator, ScriptedActionsAndTheWindowsScreenshots) {
  curvlab::test::XServer x;
  if (!x.available()) GTEST_SKIP() << x.reason();
  const auto dir = fresh_dir("xr_operator");
  const auto db = (dir / "xr.db").string();
  const auto shots = dir / "shots";
  const auto ops = dir / "ops.txt";
  const std::string note = "P said: the stick # looks \"bent\"";
  // The first trial's stimulus is up from about 0.1 s after focus; answers
  // come from 1.0 s. The pause falls in a trial, the skip in a later one.
  std::ofstream(ops) << "# operator script\n"
                     << "0.9 note " << note << "\n"
                     << "1.45 pause\n"
                     << "1.85 resume\n"
                     << "4.4 skip   # misunderstood\n";
  // With the Vulkan validation layer on (it prints its errors to stdout):
  // the copies for the window share the device, queue and images.
  RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses}, {"VK_INSTANCE_LAYERS", "VK_LAYER_KHRONOS_validation"}});
  const auto r = run_cli("run " + kProtocol + " --participant X01 --backend xr --db " + db +
                         " --operator-script " + ops.string() + " --operator-screenshot " + shots.string() +
                         " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(r.out.find("Validation"), std::string::npos) << r.out;
  const auto doc = summary(r.out);
  EXPECT_EQ(doc["status"], "completed");
  EXPECT_EQ(doc["trials_skipped"], 1);
  EXPECT_EQ(doc["trials_completed"], 7);

  // Exactly one skipped trial, by the operator; it never ran to completion.
  const auto skipped = query(db, "SELECT trial_id, end_reason FROM trials WHERE status = 'skipped'");
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_EQ(skipped[0][1], "operator");
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM trials WHERE status = 'completed'")[0][0], "7");
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM events WHERE kind = 'trial_skipped' AND trial_id = " + skipped[0][0])[0][0],
            "1");
  // The note, verbatim, with its time stamp on the session clock.
  const auto notes = query(db, "SELECT json_extract(detail, '$.text'), t_ns, json_extract(detail, '$.t_ns') "
                               "FROM events WHERE kind = 'operator_note'");
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0][0], note);
  EXPECT_GT(std::stoll(notes[0][1]), 0);
  // The pause aborted the attempt it fell in, which ran again after the resume.
  const auto repeated = query(db, "SELECT trial_id FROM events WHERE kind = 'trial_repeated' AND "
                                  "json_extract(detail, '$.reason') = 'pause'");
  ASSERT_EQ(repeated.size(), 1u);
  EXPECT_EQ(query(db, "SELECT attempt FROM trials WHERE trial_id = " + repeated[0][0])[0][0], "2");
  // Every action is an event with its time stamp.
  const auto actions = query(db, "SELECT json_extract(detail, '$.action'), t_ns FROM events "
                                 "WHERE kind IN ('operator_action', 'operator_note') ORDER BY t_ns");
  ASSERT_EQ(actions.size(), 4u);
  EXPECT_EQ(actions[0][0], "note");
  EXPECT_EQ(actions[1][0], "pause");
  EXPECT_EQ(actions[2][0], "resume");
  EXPECT_EQ(actions[3][0], "skip");

  // A screenshot per action and one at the end. Those taken while a
  // stimulus was up (the note's, in the first trial's response window, and
  // the skip's) show the participant's image with the table's cloth in it;
  // every one shows the status panel's text.
  ShotStats best;
  for (const char* name : {"action_1_note.png", "action_2_pause.png", "action_3_resume.png", "action_4_skip.png",
                           "end.png"}) {
    curvlab::renderer::Rgba8Image img;
    ASSERT_TRUE(curvlab::test::read_png_into((shots / name).string(), img));
    ASSERT_EQ(img.width, 960) << name;
    ASSERT_EQ(img.height, 720) << name;
    const auto s = inspect(img);
    EXPECT_GT(s.text_pixels, 3000) << name << ": no status text";
    EXPECT_GT(s.panel_levels.size(), 20u) << name << ": the panel is uniform";
    if (s.cloth_pixels > best.cloth_pixels) best = s;
  }
  EXPECT_GT(best.eye_pixels, 960 * 430 / 2) << "the eye area is blank";
  EXPECT_GT(best.cloth_pixels, 5000) << "no table in the participant's image";

  // The note's screenshot falls in the response window: the participant's
  // image shows the response panel, which reaches the headset as a quad
  // layer (not in the eye images) and is laid over the window's copy.
  curvlab::renderer::Rgba8Image note_shot;
  ASSERT_TRUE(curvlab::test::read_png_into((shots / "action_1_note.png").string(), note_shot));
  note_shot.height = 430;
  note_shot.pixels.resize(static_cast<std::size_t>(note_shot.width) * 430 * 4);
  const auto panel = curvlab::test::find_panel(note_shot);
  EXPECT_GT(panel.width(), 20) << "no response panel in the participant's image";
  EXPECT_GT(std::count(panel.ink.begin(), panel.ink.end(), 1), 20) << "no text on the response panel";
}

// The runtime misses refreshes and hides frames; curvlab counts them late,
// per frame and per trial, and flags the onsets they hit.
TEST(XrOperator, LateFramesAreCountedPerFrameAndPerTrial) {
  const auto dir = fresh_dir("xr_late");
  const auto db = (dir / "xr.db").string();
  // Three missed refreshes, and 80 frames (0.9 s, longer than a trial's
  // 0.6 s cycle) the runtime says not to render: some trial's onset is
  // among them. All within the first 300 frames: the session lasts a fixed
  // time, so on a loaded machine, where lavapipe misses real refreshes too,
  // it has fewer frames (about 450 when idle, 355 seen under load).
  std::set<std::int64_t> late = {120, 160, 300};
  std::string spec = "120,160,300";
  for (int k = 200; k < 280; ++k) {
    late.insert(k);
    spec.append(",").append(std::to_string(k)).append("!");
  }
  RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses}, {"CURVLAB_TEST_XR_LATE", spec}});
  const auto r = run_cli("run " + kProtocol + " --participant X01 --backend xr --operator-window off --db " + db +
                         " --export " + (dir / "export").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(summary(r.out)["status"], "completed");

  // Frame k of the runtime is frame_index k of the session (nothing aborted):
  // every scripted frame is late. Lavapipe on a busy machine misses real
  // refreshes too, and the first frames come before the session is visible
  // (shouldRender false): those are late as well, with the refreshes they
  // skipped counted, or with nothing drawn.
  std::set<std::int64_t> marked;
  for (const auto& row : query(db, "SELECT frame_index, dropped_frames, views FROM frames WHERE late = 1")) {
    marked.insert(std::stoll(row[0]));
    if (late.count(std::stoll(row[0])) == 0) {
      EXPECT_TRUE(std::stoi(row[1]) >= 1 || row[2] == "0") << "frame " << row[0];
    }
  }
  for (int k = 200; k < 280; ++k) {
    const auto views = query(db, "SELECT views FROM frames WHERE frame_index = " + std::to_string(k));
    ASSERT_EQ(views.size(), 1u);
    EXPECT_EQ(views[0][0], "0") << "frame " << k << " was drawn although the runtime said not to";
  }
  for (const auto k : late) EXPECT_EQ(marked.count(k), 1u) << "frame " << k << " is not marked late";
  // A missed refresh shows as a display time (skipped + 1) periods after the last.
  for (const int k : {120, 160, 300}) {
    const auto skip = query(db, "SELECT f.predicted_display_ns - p.predicted_display_ns, f.display_period_ns, "
                                "f.dropped_frames FROM frames f JOIN frames p ON p.frame_index = f.frame_index - 1 "
                                "WHERE f.frame_index = " + std::to_string(k));
    ASSERT_EQ(skip.size(), 1u);
    EXPECT_GE(std::stoi(skip[0][2]), 1) << "frame " << k;
    EXPECT_NEAR(std::stod(skip[0][0]) / std::stod(skip[0][1]), std::stod(skip[0][2]) + 1.0, 0.01) << "frame " << k;
  }

  // The export: frames_late adds up to the late frames inside trials, and
  // onset_late is 1 exactly where the onset frame was late.
  std::ifstream csv(dir / "export" / "csv" / "trials.csv");
  ASSERT_TRUE(csv.good());
  std::string header_line, line;
  std::getline(csv, header_line);
  std::vector<std::string> header;
  for (std::stringstream h(header_line); std::getline(h, line, ',');) header.push_back(line);
  const auto col = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  ASSERT_LT(col("frames_late"), header.size());
  ASSERT_LT(col("onset_late"), header.size());
  long sum = 0;
  int onsets_late = 0;
  while (std::getline(csv, line)) {
    std::vector<std::string> cells;
    for (std::stringstream c(line); std::getline(c, header_line, ',');) cells.push_back(header_line);
    sum += std::stol(cells[col("frames_late")]);
    onsets_late += cells[col("onset_late")] == "1";
  }
  EXPECT_EQ(std::to_string(sum), query(db, "SELECT COUNT(*) FROM frames WHERE late = 1 AND trial_id IS NOT NULL")[0][0]);
  EXPECT_GE(sum, 40);
  const auto expected_onsets = query(db, "SELECT COUNT(*) FROM trials t JOIN frames f ON f.trial_id = t.trial_id "
                                         "AND f.predicted_display_ns = t.onset_ns WHERE f.late = 1");
  EXPECT_EQ(std::to_string(onsets_late), expected_onsets[0][0]);
  EXPECT_GE(onsets_late, 1);
}

namespace {

// What a window manager sends when its close button is pressed: the
// WM_DELETE_WINDOW client message, to the top-level window titled `title`
// once it appears and has been up for `after`. False when no such window
// showed within `wait`.
bool press_close_button(const std::string& display, const std::string& title, std::chrono::milliseconds after,
                        std::chrono::seconds wait) {
  Display* dpy = XOpenDisplay(display.c_str());
  if (dpy == nullptr) return false;
  const auto give_up = std::chrono::steady_clock::now() + wait;
  Window found = 0;
  while (found == 0 && std::chrono::steady_clock::now() < give_up) {
    Window root_return = 0, parent = 0, *children = nullptr;
    unsigned int n = 0;
    if (XQueryTree(dpy, DefaultRootWindow(dpy), &root_return, &parent, &children, &n) != 0) {
      for (unsigned int i = 0; i < n && found == 0; ++i) {
        char* name = nullptr;
        if (XFetchName(dpy, children[i], &name) != 0 && name != nullptr) {
          if (title == name) found = children[i];
          XFree(name);
        }
      }
      if (children != nullptr) XFree(children);
    }
    if (found == 0) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (found != 0) {
    std::this_thread::sleep_for(after);
    XEvent ev{};
    ev.xclient.type = ClientMessage;
    ev.xclient.window = found;
    ev.xclient.message_type = XInternAtom(dpy, "WM_PROTOCOLS", False);
    ev.xclient.format = 32;
    ev.xclient.data.l[0] = static_cast<long>(XInternAtom(dpy, "WM_DELETE_WINDOW", False));
    ev.xclient.data.l[1] = CurrentTime;
    XSendEvent(dpy, found, False, NoEventMask, &ev);
    XFlush(dpy);
  }
  XCloseDisplay(dpy);
  return found != 0;
}

}  // namespace

// The window's close button ends the session as Q does: interrupted,
// resumable, and a resume completes it.
TEST(XrOperator, TheWindowsCloseButtonEndsTheSessionResumably) {
  curvlab::test::XServer x;
  if (!x.available()) GTEST_SKIP() << x.reason();
  const auto dir = fresh_dir("xr_operator_close");
  const auto db = (dir / "xr.db").string();
  RuntimeEnv env({{"CURVLAB_TEST_XR_PRESS", kPresses}});
  std::atomic<bool> pressed{false};
  std::thread closer([&] {
    pressed = press_close_button(x.display(), "curvlab operator", std::chrono::milliseconds(1500),
                                 std::chrono::seconds(60));
  });
  const auto r = run_cli("run " + kProtocol + " --participant X01 --backend xr --db " + db + " --json");
  closer.join();
  ASSERT_TRUE(pressed) << "no operator window appeared\n" << r.out;
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("curvlab resume"), std::string::npos) << r.out;
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM events WHERE kind = 'operator_action' AND "
                      "json_extract(detail, '$.action') = 'end'")[0][0],
            "1");
  EXPECT_LT(std::stoi(query(db, "SELECT COUNT(*) FROM trials WHERE status = 'completed'")[0][0]), 8);
}

// The scripted operator in a headless run reports file:line for a bad line
// before anything runs (exit 2), and --operator-window on without a display
// is an error, not a silent run without the window.
TEST(XrOperator, BadScriptsAndAMissingDisplayStopBeforeAnythingRuns) {
  const auto dir = fresh_dir("xr_operator_bad");
  const auto db = dir / "x.db";
  const auto ops = dir / "ops.txt";
  std::ofstream(ops) << "1 pause\n# fine\n2 resmue\n";
  RuntimeEnv env({});
  const auto r = run_cli("run " + kProtocol + " --participant X01 --backend xr --operator-window off --db " +
                         db.string() + " --operator-script " + ops.string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(ops.string() + ":3: unknown action 'resmue'"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(db));

  const char* display = std::getenv("DISPLAY");
  const std::string saved = display != nullptr ? display : "";
  unsetenv("DISPLAY");
  const auto w = run_cli("run " + kProtocol + " --participant X01 --backend xr --operator-window on --db " +
                         db.string());
  if (!saved.empty()) setenv("DISPLAY", saved.c_str(), 1);
  EXPECT_EQ(w.exit_code, 1) << w.out;
  EXPECT_NE(w.out.find("operator window"), std::string::npos) << w.out;
}
