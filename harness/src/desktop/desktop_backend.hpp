// The desktop pilot window (desktop/desktop.hpp) as a class, so tests can see
// what the window did (frames presented, validation messages, scripted keys
// left). The runner only sees it through make_desktop_backend().
#pragma once

#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/renderer.hpp"
#include "curvlab/renderer/swapchain.hpp"

#include "key_script.hpp"
#include "pilot_body.hpp"

#include <deque>
#include <memory>
#include <optional>

struct GLFWwindow;

namespace curvlab::harness::desktop {

// GLFW's process-wide state: glfwInit on creation, glfwTerminate when the
// last owner goes. Every window is destroyed before it.
class GlfwLibrary;

struct WindowDeleter {
  void operator()(GLFWwindow* window) const noexcept;
};

// Owns, in order of destruction: the renderer, the swapchain target, the
// Vulkan context (with the window's surface), the window, GLFW. Runs on the
// thread that created it (GLFW's event processing must be on the main
// thread); not thread-safe. A failing Vulkan call in submit() or
// save_frame() throws DeviceFailure naming it.
class DesktopBackend final : public harness::io::InteractiveDisplay {
 public:
  // No display, no Vulkan: an Error of kind `device`; a bad option or key
  // script: `usage` / `bad_input`.
  static harness::Result<std::unique_ptr<DesktopBackend>> create(
      const DesktopOptions& options);
  // Never throws, a lost device included.
  ~DesktopBackend() override;

  [[nodiscard]] harness::io::DisplayInfo info() const override;
  std::optional<harness::io::FrameTiming> begin_frame() override;
  geometry::LabFrame poses(const harness::io::FrameTiming& frame) override;
  // Keys (scripted ones too) and the signals they carry; quit once the
  // window is closed.
  harness::io::Signal poll(std::vector<harness::io::InputEvent>& out) override;
  // Every key; pages continue on space.
  [[nodiscard]] harness::io::Reach reach() const override { return keyboard_reach(); }
  renderer::StereoRig rig(const harness::io::FrameTiming& frame, double ipd_m) override;
  renderer::FrameStats submit(const renderer::Scene& scene,
                              const renderer::FrameDescription& frame,
                              const harness::io::Overlay& overlay, bool draw) override;
  std::vector<std::string> save_frame(const std::string& stem) override;

  // For tests and logs.
  [[nodiscard]] const renderer::Context& context() const { return *context_; }
  [[nodiscard]] const renderer::SwapchainTarget& target() const { return *target_; }
  [[nodiscard]] std::size_t scripted_keys_pressed() const;
  [[nodiscard]] const std::vector<std::string>& screenshots() const { return screenshots_; }
  [[nodiscard]] const PilotBody& body() const { return body_; }
  [[nodiscard]] const std::string& banner() const { return banner_; }

 private:
  explicit DesktopBackend(const DesktopOptions& options);
  void on_key(int key, int action, int mods);
  void on_cursor(double x, double y);
  void on_scroll(double dy);
  void screenshot_f12();
  // The trial-information line: the window's title and the text drawn below the eyes.
  [[nodiscard]] std::string banner_text(const harness::io::Overlay& overlay) const;

  DesktopOptions options_;
  std::shared_ptr<GlfwLibrary> glfw_;
  std::unique_ptr<GLFWwindow, WindowDeleter> window_;
  std::unique_ptr<renderer::Context> context_;
  std::unique_ptr<renderer::SwapchainTarget> target_;
  std::unique_ptr<renderer::Renderer> renderer_;
  PilotBody body_;
  std::optional<KeyScriptPlayer> script_;
  std::deque<harness::io::InputEvent> pending_;
  harness::io::Signal signal_ = harness::io::Signal::none;
  std::int64_t frame_index_ = 0;
  std::int64_t last_frame_ns_ = 0;
  std::int64_t period_ns_ = 16'666'667;
  double refresh_hz_ = 60.0;
  std::optional<glm::dvec2> cursor_px_;
  bool f12_ = false;
  harness::io::Phase last_phase_ = harness::io::Phase::iti;
  std::string banner_;
  int stimulus_onsets_ = 0;
  int f12_count_ = 0;
  std::vector<std::string> screenshots_;
  bool failed_ = false;
  bool quit_delivered_ = false;  // poll has returned quit
};

// The GLFW-style lower-case name of a key ("a", "1", "space", "left",
// "f12", "kp_1"); empty for keys curvlab does not name.
std::string key_name(int glfw_key);

}  // namespace curvlab::harness::desktop
