// The desktop window (on Xvfb when there is no display):
// the runner's frame loop driven by hand, a scripted key arriving as an
// InputEvent, a stimulus drawn into the swapchain and saved as a screenshot
// that shows it. Vulkan on lavapipe with the validation layer on.
#include "desktop_backend.hpp"
#include "xvfb.hpp"
#include "../renderer/stimulus_fixtures.hpp"
#include "../support/png_files.hpp"

#include "../faults/fault_env.hpp"

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/scene.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

namespace {

using namespace curvlab;
using harness::io::Signal;
using harness::desktop::DesktopOptions;
using harness::io::InputEvent;
using harness::io::Overlay;

test::XServer* g_xserver = nullptr;

class XEnvironment : public ::testing::Environment {
 public:
  void SetUp() override { g_xserver = new test::XServer; }
  void TearDown() override {
    delete g_xserver;
    g_xserver = nullptr;
  }
};
const auto* const g_env = ::testing::AddGlobalTestEnvironment(new XEnvironment);

std::filesystem::path fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("curvlab_desktop_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

bool validation_layer_installed() {
  return std::filesystem::exists("/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json");
}

// Pixels of a kind inside a rectangle (fractions of the image).
template <class Pred>
int count_pixels(const renderer::Rgba8Image& img, double x0, double y0, double x1, double y1,
                 Pred pred) {
  int n = 0;
  for (int y = static_cast<int>(y0 * img.height); y < static_cast<int>(y1 * img.height); ++y)
    for (int x = static_cast<int>(x0 * img.width); x < static_cast<int>(x1 * img.width); ++x) {
      const std::uint8_t* p = &img.pixels[4 * (static_cast<std::size_t>(y) * img.width + x)];
      if (pred(p[0], p[1], p[2])) ++n;
    }
  return n;
}

// The cloth (0.10, 0.42, 0.20), lit: green well above red and blue.
bool cloth(int r, int g, int b) { return g > 40 && g > r + 25 && g > b + 15; }
// The cue's shaft (0.85, 0.66, 0.40) and butt (0.22, 0.10, 0.05), lit: red
// above green above blue — wood, which nothing else in the scene is.
bool wood(int r, int g, int b) { return r > 40 && r > g + 10 && g > b + 5 && r < 250; }

// One frame of a stimulus scene, as the runner submits it; false: the
// window gave no frame.
bool show_stimulus_frame(harness::desktop::DesktopBackend& backend, const renderer::fixtures::StimulusScene& s) {
  auto timing = backend.begin_frame();
  if (!timing) return false;
  renderer::FrameDescription f;
  f.space = s.space;
  f.head = s.head;
  f.rig = backend.rig(*timing, 0.063);
  backend.submit(s.scene, f, Overlay{harness::io::Phase::stimulus, "", false}, true);
  return true;
}

class DesktopWindow : public ::testing::Test {
 protected:
  void SetUp() override {
    if (g_xserver == nullptr || !g_xserver->available())
      GTEST_SKIP() << "no X display: " << (g_xserver ? g_xserver->reason() : "not started");
  }
  // Window options every test starts from: lavapipe, the test's clock.
  DesktopOptions window(std::uint32_t eye_width_px, std::uint32_t eye_height_px) {
    DesktopOptions o;
    o.eye_width_px = eye_width_px;
    o.eye_height_px = eye_height_px;
    o.software = true;
    o.clock = &clock_;
    return o;
  }
  // The backend, or null with the factory's error reported as a failure.
  static std::unique_ptr<harness::desktop::DesktopBackend> open(const DesktopOptions& options) {
    auto made = harness::desktop::DesktopBackend::create(options);
    if (!made) {
      ADD_FAILURE() << made.error().message;
      return nullptr;
    }
    return std::move(made).value();
  }
  harness::io::SteadyClock clock_;
};

TEST_F(DesktopWindow, ScriptedKeyArrivesAndStimulusScreenshotShowsTheTable) {
  const auto dir = fresh_dir("stimulus");
  const auto script = dir / "keys.txt";
  std::ofstream(script) << "# answer the first trial with key 2 after 40 ms\n2 40\n";

  DesktopOptions options = window(320, 320);
  options.screenshot_dir = (dir / "shots").string();
  options.key_script = script.string();
  options.validation = validation_layer_installed();
  const auto opened = open(options);
  ASSERT_NE(opened, nullptr);
  auto& backend = *opened;
  EXPECT_EQ(backend.info().backend, curvlab::harness::data::Backend::desktop);
  EXPECT_NE(backend.info().renderer_device.find("llvmpipe"), std::string::npos);

  const auto s = renderer::fixtures::make(geometry::SpaceKind::E3, renderer::fixtures::SceneKind::billiards);

  // fixation → stimulus (onset screenshot) → response until the scripted key.
  std::vector<InputEvent> events;
  std::optional<InputEvent> answer;
  int frames = 0;
  for (; frames < 400 && !answer; ++frames) {
    auto timing = backend.begin_frame();
    ASSERT_TRUE(timing.has_value());
    EXPECT_EQ(timing->index, frames);
    EXPECT_GT(timing->predicted_display_ns, timing->now_ns);
    const auto lab = backend.poses(*timing);
    EXPECT_TRUE(lab[geometry::Device::head].valid);
    events.clear();
    EXPECT_EQ(backend.poll(events), Signal::none);
    for (const auto& e : events)
      if (to_string(e.source) == "script") answer = e;
    renderer::FrameDescription f;
    f.space = s.space;
    f.settings = renderer::ViewSettings::preset(renderer::ViewPreset::tourist);
    f.head = s.head;
    f.rig = backend.rig(*timing, 0.063);
    Overlay overlay;
    overlay.phase = frames < 2 ? harness::io::Phase::fixation : frames < 4 ? harness::io::Phase::stimulus : harness::io::Phase::response;
    overlay.text = "block 1 · trial 1 of 8 · E3 tourist";
    overlay.waiting_for_input = overlay.phase == harness::io::Phase::response;
    const auto stats = backend.submit(s.scene, f, overlay, true);
    EXPECT_EQ(stats.views, 2);
  }
  ASSERT_TRUE(answer.has_value()) << "the scripted key never arrived";
  EXPECT_EQ(answer->control.name, "2");
  EXPECT_TRUE(answer->pressed);
  EXPECT_GE(frames, 5);  // armed only once the response phase waited for input
  EXPECT_EQ(backend.scripted_keys_pressed(), 1u);
  EXPECT_GE(backend.target().presented_frames(), static_cast<std::uint64_t>(frames));
  EXPECT_NE(backend.banner().find("trial 1 of 8"), std::string::npos);

  // The onset screenshot: both eyes and the window.
  const auto shots = dir / "shots";
  for (const char* name : {"stimulus_001_left.png", "stimulus_001_right.png", "stimulus_001_window.png"})
    EXPECT_TRUE(std::filesystem::exists(shots / name)) << name;
  renderer::Rgba8Image left;
  ASSERT_TRUE(test::read_png_into((shots / "stimulus_001_left.png").string(), left));
  ASSERT_EQ(left.width, 320);
  ASSERT_EQ(left.height, 320);
  // The head looks at the table centre: cloth fills the middle of the image,
  // the cue lies across the table toward the participant, below the centre.
  const int centre_cloth = count_pixels(left, 0.35, 0.35, 0.65, 0.65, cloth);
  EXPECT_GT(centre_cloth, 0.6 * (0.3 * 320) * (0.3 * 320)) << "cloth pixels in the centre";
  EXPECT_GT(count_pixels(left, 0.3, 0.5, 0.7, 1.0, wood), 100) << "cue pixels below the centre";
  EXPECT_LT(count_pixels(left, 0.0, 0.0, 1.0, 0.15, cloth), count_pixels(left, 0.0, 0.4, 1.0, 0.55, cloth));

  // The window holds both eyes side by side, a strip between them, and the
  // banner below them.
  renderer::Rgba8Image window;
  ASSERT_TRUE(test::read_png_into((shots / "stimulus_001_window.png").string(), window));
  EXPECT_EQ(window.width, 640 + static_cast<int>(renderer::SwapchainOptions{}.eye_gap_px));
  EXPECT_EQ(window.height, 320 + 28);
  EXPECT_GT(count_pixels(window, 0.1, 0.3, 0.4, 0.7, cloth), 1000) << "left eye in the left half";
  EXPECT_GT(count_pixels(window, 0.6, 0.3, 0.9, 0.7, cloth), 1000) << "right eye in the right half";
  const double banner_top = 320.0 / window.height;
  EXPECT_GT(count_pixels(window, 0.0, banner_top, 1.0, 1.0,
                         [](int r, int g, int b) { return r > 150 && g > 150 && b > 150; }),
            50)
      << "banner text";

  // F12-style screenshot on request: save_frame writes the same three files.
  const auto files = backend.save_frame((dir / "again").string());
  EXPECT_EQ(files.size(), 3u);
  EXPECT_EQ(backend.context().validation_log().count(), 0u);
  // CURVLAB_KEEP_TEST_OUTPUT=1 keeps the screenshots for a person to look at.
  if (std::getenv("CURVLAB_KEEP_TEST_OUTPUT") == nullptr) std::filesystem::remove_all(dir);
  else std::cout << "screenshots kept in " << shots << '\n';
}

TEST_F(DesktopWindow, SideBySideEyesAreSeparatedByAGap) {
  // Two abutting stick images read as one long stick; a dark strip keeps the
  // eyes apart at the window's natural size.
  DesktopOptions options = window(200, 150);
  options.vsync = false;
  const auto opened = open(options);
  ASSERT_NE(opened, nullptr);
  auto& backend = *opened;
  const auto s = renderer::fixtures::make(geometry::SpaceKind::E3, renderer::fixtures::SceneKind::stick);
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(show_stimulus_frame(backend, s));
  }
  const auto w = backend.target().read_window();
  ASSERT_TRUE(w.has_value());
  const int gap = w->width - 2 * 200;
  EXPECT_GE(gap, 16) << "the eyes abut";
  // Every pixel of the strip is the window's background; the eyes' edge
  // columns beside it are the scene's (not the background).
  auto px = [&](int x, int y) {
    const auto* p = &w->pixels[4 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(w->width) + x)];
    return std::array<int, 3>{p[0], p[1], p[2]};
  };
  const auto strip = px(200, 10);
  for (int y = 0; y < 150; y += 7)
    for (int x = 200; x < 200 + gap; ++x) ASSERT_EQ(px(x, y), strip) << x << "," << y;
  int differing = 0;
  for (int y = 0; y < 150; ++y) differing += px(199, y) != strip;
  EXPECT_GT(differing, 100) << "the left eye's last column looks like the gap";
}

TEST_F(DesktopWindow, OneEyePreviewAndResizeKeepPresenting) {
  DesktopOptions options = window(200, 150);
  options.preview = harness::desktop::DesktopPreview::right;
  options.vsync = false;
  options.validation = validation_layer_installed();
  const auto opened = open(options);
  ASSERT_NE(opened, nullptr);
  auto& backend = *opened;
  const auto s = renderer::fixtures::make(geometry::SpaceKind::H3, renderer::fixtures::SceneKind::stick);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(show_stimulus_frame(backend, s));
  }
  // One eye: the window is that eye plus the banner.
  const auto window = backend.target().read_window();
  ASSERT_TRUE(window.has_value());
  EXPECT_EQ(window->width, 200);
  EXPECT_EQ(window->height, 150 + 28);
  EXPECT_EQ(backend.target().recreations(), 1u);
  EXPECT_EQ(backend.context().validation_log().count(), 0u);

  // Resized by the window system: the swapchain is made again at the new
  // size and the eye is scaled to fit (a filtered blit, letterboxed).
  if (std::system("command -v xdotool > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "xdotool is not installed: resizing not tested";
  ASSERT_EQ(std::system("timeout 10 xdotool search --name '^curvlab' windowsize --sync 420 300"), 0);
  for (int i = 0; i < 50 && backend.target().window_extent().width != 420; ++i) {
    ASSERT_TRUE(show_stimulus_frame(backend, s));
  }
  EXPECT_EQ(backend.target().recreations(), 2u);
  const auto resized = backend.target().read_window();
  ASSERT_TRUE(resized.has_value());
  EXPECT_EQ(resized->width, 420);
  EXPECT_EQ(resized->height, 300);
  if (std::getenv("CURVLAB_KEEP_TEST_OUTPUT") != nullptr) {
    const auto path = std::filesystem::temp_directory_path() / "curvlab_desktop_resized_window.png";
    EXPECT_TRUE(test::png_written(renderer::write_png(path.string(), *resized)));
    std::cout << "resized window kept in " << path << '\n';
  }
  EXPECT_EQ(backend.context().validation_log().count(), 0u);
}

// Real key presses, typed into the window through the X server's XTEST
// extension by xdotool: they arrive as "keyboard" events with GLFW-style
// names, and Escape ends the session.
TEST_F(DesktopWindow, RealKeysArriveAndEscapeQuits) {
  if (std::system("command -v xdotool > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "xdotool is not installed (apt-get install xdotool)";
  DesktopOptions options = window(64, 64);
  options.vsync = false;
  const auto opened = open(options);
  ASSERT_NE(opened, nullptr);
  auto& backend = *opened;
  renderer::Scene empty;
  auto frame = [&](std::vector<InputEvent>& events) {
    auto timing = backend.begin_frame();
    if (!timing) return std::optional<Signal>();
    const Signal signal = backend.poll(events);
    renderer::FrameDescription f;
    f.rig = backend.rig(*timing, 0.063);
    backend.submit(empty, f, Overlay{harness::io::Phase::response, "", true}, true);
    return std::optional<Signal>(signal);
  };
  std::vector<InputEvent> events;
  ASSERT_TRUE(frame(events));  // the window is mapped and drawn once
  ASSERT_EQ(std::system("timeout 10 xdotool search --sync --name '^curvlab' windowfocus --sync "
                        "key 1 Left space"),
            0);
  for (int i = 0; i < 50 && events.size() < 6; ++i) ASSERT_TRUE(frame(events));
  std::vector<std::string> pressed;
  for (const auto& e : events) {
    EXPECT_EQ(to_string(e.source), "keyboard");
    if (e.pressed) pressed.push_back(e.control.name);
  }
  EXPECT_EQ(pressed, (std::vector<std::string>{"1", "left", "space"}));
  EXPECT_EQ(events.size(), 6u);  // and their releases

  ASSERT_EQ(std::system("timeout 10 xdotool search --name '^curvlab' windowfocus --sync key Escape"), 0);
  std::optional<Signal> signal;
  for (int i = 0; i < 50; ++i) {
    events.clear();
    signal = frame(events);
    if (!signal || *signal == Signal::quit) break;
  }
  ASSERT_TRUE(signal.has_value());
  EXPECT_EQ(*signal, Signal::quit);
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front().control.name, "escape");
  EXPECT_FALSE(backend.begin_frame().has_value()) << "the session ends after Escape";
}


// A GPU lost while the window presents (the test Vulkan layer fails the 6th
// vkQueueSubmit: the renderer's or the composition's): submit() throws
// DeviceFailure naming the call and result, and the window, swapchain and
// device are torn down without throwing or terminating.
TEST_F(DesktopWindow, DeviceLossWhilePresentingThrowsDeviceFailureAndTeardownEnds) {
  const curvlab::testing::VulkanFault fault("vkQueueSubmit@6");
  DesktopOptions options = window(160, 160);
  options.vsync = false;
  auto backend = open(options);
  ASSERT_NE(backend, nullptr);
  const auto s = renderer::fixtures::make(geometry::SpaceKind::E3, renderer::fixtures::SceneKind::stick);
  std::optional<harness::io::DeviceFailure> failure;
  int frames = 0;
  for (; frames < 20 && !failure; ++frames) {
    auto timing = backend->begin_frame();
    ASSERT_TRUE(timing.has_value());
    renderer::FrameDescription f;
    f.space = s.space;
    f.head = s.head;
    f.rig = backend->rig(*timing, 0.063);
    try {
      (void)backend->submit(s.scene, f, Overlay{curvlab::harness::io::Phase::stimulus, "", false}, true);
    } catch (const harness::io::DeviceFailure& e) {
      failure = e;
    }
  }
  ASSERT_TRUE(failure.has_value()) << "no failure in 20 frames";
  EXPECT_GT(frames, 1);
  EXPECT_EQ(failure->call, "vkQueueSubmit");
  EXPECT_EQ(failure->result, "VK_ERROR_DEVICE_LOST");
  EXPECT_EQ(std::string(failure->what()).rfind("vkQueueSubmit: VK_ERROR_DEVICE_LOST", 0), 0u) << failure->what();
  backend.reset();  // never throws, a lost device included
}

}  // namespace
