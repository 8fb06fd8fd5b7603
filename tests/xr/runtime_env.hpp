// What the XR tests share about the scripted runtime (tests/xr/runtime/):
// the environment for one run of curvlab against it, and the participant's
// scripted answers.
#pragma once

#include "khronos_layer.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <unistd.h>

namespace curvlab::testing {

// The participant presses A (right hand, "straight") one second after focus,
// X (left hand, "convex") 0.6 s later, the right trigger ("concave") 0.6 s
// after that, and so on round: a press every 0.6 s. Each answer ends a
// trial; the next one's stimulus (after 100 ms ITI and 100 ms fixation) is up
// 0.2 s later, so presses and trials stay in step and every later press
// lands in a stimulus (tests/xr/demo_buttons.toml).
inline const std::string kScriptedPresses = "right:a@1.0/1.8,left:x@1.6/1.8,right:trigger@2.2/1.8";

// Sets the runtime's environment for one run of the program and clears it
// after. With CURVLAB_TEST_CORE_VALIDATION set (the ctest entry
// xr_session_core_validation), the Khronos core validation layer sits
// between curvlab and the runtime, and any report from it fails the test.
class RuntimeEnv {
 public:
  explicit RuntimeEnv(const std::map<std::string, std::string>& vars) {
    setenv("XR_RUNTIME_JSON", CURVLAB_TEST_XR_RUNTIME_JSON, 1);
    for (const char* v : kAll) unsetenv(v);
    for (const auto& [k, v] : vars) setenv(k.c_str(), v.c_str(), 1);
    if (std::getenv("CURVLAB_TEST_CORE_VALIDATION") != nullptr) {
      layer_.emplace(std::filesystem::temp_directory_path() /
                     ("curvlab_xr_core_validation_" + std::to_string(::getpid())));
      for (const auto& [k, v] : layer_->environment()) setenv(k.c_str(), v.c_str(), 1);
    }
  }
  ~RuntimeEnv() {
    unsetenv("XR_RUNTIME_JSON");
    for (const char* v : kAll) unsetenv(v);
    if (!layer_) return;
    for (const auto& [k, v] : layer_->environment()) unsetenv(k.c_str());
    if (const std::string m = layer_->messages(); !m.empty())
      ADD_FAILURE() << "the core validation layer reported:\n" << m;
  }
  RuntimeEnv(const RuntimeEnv&) = delete;
  RuntimeEnv& operator=(const RuntimeEnv&) = delete;

 private:
  std::optional<CoreValidation> layer_;
  static constexpr const char* kAll[] = {"CURVLAB_TEST_XR_PRESS",         "CURVLAB_TEST_XR_UNFOCUS",
                                         "CURVLAB_TEST_XR_HAND",          "CURVLAB_TEST_XR_LOSS",
                                         "CURVLAB_TEST_XR_EXIT",          "CURVLAB_TEST_XR_LATE",
                                         "CURVLAB_TEST_XR_CAPTURE_DIR",   "CURVLAB_TEST_XR_CAPTURE_EVERY",
                                         "CURVLAB_TEST_XR_LOG",           "CURVLAB_TEST_XR_SIZE",
                                         "CURVLAB_TEST_XR_HEAD",          "CURVLAB_TEST_XR_RESTART",
                                         "CURVLAB_TEST_XR_TIMING",        "CURVLAB_TEST_XR_SWAPCHAIN_WAIT",
                                         "CURVLAB_TEST_XR_STATES",        "CURVLAB_TEST_XR_STAGE_MOVE",
                                         "CURVLAB_TEST_XR_EVENTS_LOST",   "CURVLAB_TEST_XR_FORMATS",
                                         "CURVLAB_TEST_XR_VIEWS",         "CURVLAB_TEST_XR_TRACKING",
                                         "CURVLAB_TEST_XR_REFRESH",       "CURVLAB_TEST_XR_REFRESH_CHANGE",
                                         "CURVLAB_TEST_XR_GAZE",
                                         "VK_INSTANCE_LAYERS"};
};

}  // namespace curvlab::testing
