// The test runtime and curvlab's XR path checked by Khronos' own tools
// rather than by code written here:
//  - Khronos' sample application hello_xr (Debian libopenxr-utils) runs
//    through the test runtime with -g Vulkan2 until the runtime asks it to
//    exit. It calls OpenXR functions curvlab never does (view configuration
//    and blend mode enumeration, bound sources and their localized names,
//    haptics, pose action states), so a runtime that only fits curvlab's
//    calls fails here.
//  - The Khronos core validation API layer (XR_APILAYER_LUNARG_core_validation,
//    Debian openxr-layer-corevalidation) sits between hello_xr and the
//    runtime and must report nothing; a deliberate misuse shows that its
//    reports reach the file the tests read.
#include "khronos_layer.hpp"
#include "../support/png_files.hpp"

#include "curvlab/renderer/image_io.hpp"

#include <openxr/openxr.h>

#include <gtest/gtest.h>

#include <spawn.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;
using curvlab::testing::CoreValidation;

fs::path fresh_dir(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("curvlab_xr_khronos_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The process environment with `vars` set on top.
std::vector<std::string> environment_with(const std::map<std::string, std::string>& vars) {
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry = *e;
    if (vars.count(entry.substr(0, entry.find('='))) == 0) env.push_back(entry);
  }
  for (const auto& [k, v] : vars) env.push_back(k + "=" + v);
  return env;
}

struct Exit {
  bool exited = false;  // by itself, not killed
  int code = -1;
};

// Runs `argv` with its output to `output` and its standard input a pipe that
// stays open (hello_xr quits when a key arrives or its input ends) until it
// exits; killed after `limit`, which only guards against a hang.
Exit run_program(const std::vector<std::string>& argv, const std::map<std::string, std::string>& vars,
                 const fs::path& output, std::chrono::seconds limit) {
  int in[2];
  if (::pipe(in) != 0) return {};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in[0], STDIN_FILENO);
  posix_spawn_file_actions_addclose(&actions, in[1]);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  auto env = environment_with(vars);
  std::vector<char*> envp;
  for (auto& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);
  pid_t pid = -1;
  const int spawned = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  ::close(in[0]);
  Exit result;
  if (spawned == 0) {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    result.exited = WIFEXITED(status);
    result.code = result.exited ? WEXITSTATUS(status) : -1;
  }
  ::close(in[1]);
  return result;
}

// What the test runtime logged (runtime.cpp documents its lines).
struct RuntimeLog {
  std::vector<std::string> states;
  std::map<std::string, std::int64_t> state_at_ns;  // first time of each state
  int frames_with_layers = 0;
  int haptics = 0;
  std::vector<std::string> problems;  // violation and warning lines
  std::vector<std::string> lines;

  explicit RuntimeLog(const fs::path& path) {
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);) {
      lines.push_back(line);
      std::istringstream s(line);
      std::string kind, word;
      s >> kind;
      if (kind == "state") {
        std::string name;
        long long ns = 0;
        s >> name >> word >> ns;
        states.push_back(name);
        state_at_ns.emplace(name, ns);
      } else if (kind == "end_frame") {
        long long index = 0, layers = 0;
        s >> index >> word >> layers;
        frames_with_layers += layers > 0 ? 1 : 0;
      } else if (kind == "haptic") {
        ++haptics;
      } else if (kind == "violation" || kind == "warning") {
        problems.push_back(line);
      }
    }
  }
  [[nodiscard]] bool has(const std::string& line) const {
    return std::find(lines.begin(), lines.end(), line) != lines.end();
  }
};

// Pixels of hello_xr's cubes (faces in pure red, green or blue) in a left-eye
// image the runtime received, and pixels of its clear colour (the corner's).
struct CubePixels {
  int cube = 0;
  int clear = 0;
};

CubePixels cube_pixels(const curvlab::renderer::Rgba8Image& img) {
  CubePixels n;
  const std::uint8_t* corner = img.pixels.data();
  for (std::size_t i = 0; i + 3 < img.pixels.size(); i += 4) {
    const std::uint8_t* p = &img.pixels[i];
    const int hi = std::max({p[0], p[1], p[2]});
    const int lo = std::min({p[0], p[1], p[2]});
    n.cube += hi > 180 && lo < 60 ? 1 : 0;
    n.clear += std::equal(p, p + 3, corner) ? 1 : 0;
  }
  return n;
}

TEST(KhronosCoreValidation, ReportsAMisuseToItsFile) {
  const auto dir = fresh_dir("misuse");
  const CoreValidation layer(dir / "core_validation.txt");
  setenv("XR_RUNTIME_JSON", CURVLAB_TEST_XR_RUNTIME_JSON, 1);
  for (const auto& [k, v] : layer.environment()) setenv(k.c_str(), v.c_str(), 1);
  XrInstanceCreateInfo info{};
  info.type = XR_TYPE_INSTANCE_CREATE_INFO;
  std::strcpy(info.applicationInfo.applicationName, "misuse");
  info.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
  XrInstance instance = XR_NULL_HANDLE;
  ASSERT_EQ(xrCreateInstance(&info, &instance), XR_SUCCESS);
  // A get-info structure without its type: the layer stops the call.
  XrSystemGetInfo untyped{};
  untyped.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  EXPECT_EQ(xrGetSystem(instance, &untyped, &system), XR_ERROR_VALIDATION_FAILURE);
  xrDestroyInstance(instance);
  for (const auto& [k, v] : layer.environment()) unsetenv(k.c_str());
  unsetenv("XR_RUNTIME_JSON");
  EXPECT_NE(layer.messages().find("VUID-XrSystemGetInfo-type-type"), std::string::npos) << layer.messages();
  fs::remove_all(dir);
}

// hello_xr -g Vulkan2 on the test runtime (Vulkan on lavapipe, no display)
// with the core validation layer between them: the runtime asks it to exit
// 5.5 s after the session became focused, a scripted squeeze makes it
// vibrate the controller, and it must leave through STOPPING → xrEndSession
// → EXITING with exit code 0, having rendered frames, with no broken rule
// seen by the runtime and no message from the layer.
TEST(KhronosHelloXr, RunsThroughTheTestRuntimeAndExitsWhenAsked) {
  ASSERT_TRUE(fs::exists(CURVLAB_HELLO_XR)) << "hello_xr not found: install libopenxr-utils (scripts/deps.sh)";
  const auto dir = fresh_dir("hello_xr");
  const auto log_path = dir / "runtime.log";
  const auto output = dir / "hello_xr.txt";
  const auto captures = dir / "captures";
  fs::create_directories(captures);
  const CoreValidation layer(dir / "core_validation.txt");
  auto vars = layer.environment();
  vars["XR_RUNTIME_JSON"] = CURVLAB_TEST_XR_RUNTIME_JSON;
  vars["CURVLAB_TEST_XR_LOG"] = log_path.string();
  vars["CURVLAB_TEST_XR_EXIT"] = "5.5";
  vars["CURVLAB_TEST_XR_PRESS"] = "left:squeeze@1.0~0.3";
  vars["CURVLAB_TEST_XR_CAPTURE_DIR"] = captures.string();
  vars["CURVLAB_TEST_XR_CAPTURE_EVERY"] = "60";
  if (fs::exists(CURVLAB_LAVAPIPE_ICD)) vars["VK_ICD_FILENAMES"] = CURVLAB_LAVAPIPE_ICD;
  const Exit exit = run_program({CURVLAB_HELLO_XR, "-g", "Vulkan2"}, vars, output, std::chrono::seconds(90));
  const std::string out = read_text(output);
  ASSERT_TRUE(exit.exited) << "hello_xr crashed or hung:\n" << out;
  EXPECT_EQ(exit.code, 0) << out;

  const RuntimeLog log(log_path);
  EXPECT_TRUE(log.problems.empty()) << "the runtime saw broken rules:\n" << log.problems.front();
  const std::vector<std::string> states = {
      "XR_SESSION_STATE_IDLE",         "XR_SESSION_STATE_READY",    "XR_SESSION_STATE_SYNCHRONIZED",
      "XR_SESSION_STATE_VISIBLE",      "XR_SESSION_STATE_FOCUSED",  "XR_SESSION_STATE_VISIBLE",
      "XR_SESSION_STATE_SYNCHRONIZED", "XR_SESSION_STATE_STOPPING", "XR_SESSION_STATE_IDLE",
      "XR_SESSION_STATE_EXITING"};
  EXPECT_EQ(log.states, states) << out;
  ASSERT_EQ(log.state_at_ns.count("XR_SESSION_STATE_STOPPING"), 1u);
  const auto focused_ns = log.state_at_ns.at("XR_SESSION_STATE_FOCUSED");
  const auto stopping_ns = log.state_at_ns.at("XR_SESSION_STATE_STOPPING");
  EXPECT_GE(stopping_ns - focused_ns, 5'000'000'000) << "it ran at least 5 s";
  // It ended the session itself before destroying it, and rendered frames:
  // projection layers, each made of images it rendered and released.
  EXPECT_FALSE(log.has("note xrDestroySession while the session is running"));
  EXPECT_TRUE(log.has("instance destroyed"));
  EXPECT_GE(log.frames_with_layers, 10) << out;
  // What it rendered reached the runtime: its cubes on its clear colour.
  std::vector<fs::path> pngs;
  for (const auto& e : fs::directory_iterator(captures)) pngs.push_back(e.path());
  ASSERT_FALSE(pngs.empty());
  std::sort(pngs.begin(), pngs.end());  // any one of them; sorted for a repeatable choice
  curvlab::renderer::Rgba8Image img;
  ASSERT_TRUE(curvlab::test::read_png_into(pngs.back().string(), img));
  const CubePixels px = cube_pixels(img);
  EXPECT_GT(px.cube, 100) << pngs.back();
  EXPECT_GT(px.clear, img.width * img.height / 2) << pngs.back();
  // Its grab action read the scripted squeeze and it answered with haptics;
  // it named the bound sources through xrGetInputSourceLocalizedName.
  EXPECT_GE(log.haptics, 1);
  EXPECT_NE(out.find("Left Hand Oculus Touch Controller Squeeze Value"), std::string::npos) << out;
  EXPECT_EQ(layer.messages(), "") << "the core validation layer reported";
  std::cout << "hello_xr: " << log.frames_with_layers << " frames with layers (" << px.cube << " cube pixels, "
            << px.clear << " clear ones in " << pngs.back().filename().string() << "), "
            << static_cast<double>(stopping_ns - focused_ns) * 1e-9 << " s focused, exit code " << exit.code
            << "\n";
  fs::remove_all(dir);
}

}  // namespace
