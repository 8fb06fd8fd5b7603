#include "desktop_backend.hpp"

#include "curvlab/harness/numbered_files.hpp"
#include "curvlab/harness/render_result.hpp"
#include "curvlab/renderer/image_io.hpp"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <numbers>
#include <thread>

namespace curvlab::harness::desktop {

using harness::Error;
using harness::Result;
using harness::io::DeviceFailure;
using harness::io::DisplayInfo;
using harness::io::Signal;
using harness::io::FrameTiming;
using harness::io::InputEvent;
using harness::io::Overlay;

namespace {

constexpr double kHorizontalFovRad = 90.0 * std::numbers::pi / 180.0;

// GLFW reports errors through one process-wide callback; the last one is
// kept to name it in an Error.
std::mutex g_error_mutex;
std::string g_last_error;

std::string error_code_name(int code) {
  switch (code) {
    case GLFW_NOT_INITIALIZED: return "GLFW_NOT_INITIALIZED";
    case GLFW_NO_CURRENT_CONTEXT: return "GLFW_NO_CURRENT_CONTEXT";
    case GLFW_INVALID_ENUM: return "GLFW_INVALID_ENUM";
    case GLFW_INVALID_VALUE: return "GLFW_INVALID_VALUE";
    case GLFW_OUT_OF_MEMORY: return "GLFW_OUT_OF_MEMORY";
    case GLFW_API_UNAVAILABLE: return "GLFW_API_UNAVAILABLE";
    case GLFW_VERSION_UNAVAILABLE: return "GLFW_VERSION_UNAVAILABLE";
    case GLFW_PLATFORM_ERROR: return "GLFW_PLATFORM_ERROR";
    case GLFW_FORMAT_UNAVAILABLE: return "GLFW_FORMAT_UNAVAILABLE";
    case GLFW_NO_WINDOW_CONTEXT: return "GLFW_NO_WINDOW_CONTEXT";
    default: return "GLFW error " + std::to_string(code);
  }
}

void on_glfw_error(int code, const char* description) {
  const std::lock_guard lock(g_error_mutex);
  g_last_error = std::string(description != nullptr ? description : "") + " (" +
                 error_code_name(code) + ")";
}

std::string take_last_error() {
  const std::lock_guard lock(g_error_mutex);
  std::string e = g_last_error.empty() ? "no error reported" : g_last_error;
  g_last_error.clear();
  return e;
}

DesktopBackend* self(GLFWwindow* window) {
  return static_cast<DesktopBackend*>(glfwGetWindowUserPointer(window));
}

vk::Extent2D framebuffer_extent(GLFWwindow* window) {
  int w = 0;
  int h = 0;
  glfwGetFramebufferSize(window, &w, &h);
  return {static_cast<std::uint32_t>(std::max(w, 0)), static_cast<std::uint32_t>(std::max(h, 0))};
}

renderer::WindowLayout layout_of(DesktopPreview preview) {
  switch (preview) {
    case DesktopPreview::left: return renderer::WindowLayout::left_eye;
    case DesktopPreview::right: return renderer::WindowLayout::right_eye;
    case DesktopPreview::side_by_side: break;
  }
  return renderer::WindowLayout::side_by_side;
}

}  // namespace

class GlfwLibrary {
 public:
  // One GLFW per process, shared by every window (glfwInit is reference-free).
  static Result<std::shared_ptr<GlfwLibrary>> acquire() {
    static std::mutex mutex;
    static std::weak_ptr<GlfwLibrary> current;
    const std::lock_guard lock(mutex);
    if (auto live = current.lock()) return live;
    glfwSetErrorCallback(&on_glfw_error);
    if (glfwInit() != GLFW_TRUE)
      return Error{Error::Kind::device,
                   "cannot open a window: glfwInit failed: " + take_last_error() +
                       ". The desktop backend needs a display: run under a desktop "
                       "session or xvfb-run (e.g. `xvfb-run -a curvlab run …`)"};
    std::shared_ptr<GlfwLibrary> made(new GlfwLibrary);
    current = made;
    return std::shared_ptr<GlfwLibrary>(std::move(made));
  }
  ~GlfwLibrary() { glfwTerminate(); }
  GlfwLibrary(const GlfwLibrary&) = delete;
  GlfwLibrary& operator=(const GlfwLibrary&) = delete;

 private:
  GlfwLibrary() = default;
};

void WindowDeleter::operator()(GLFWwindow* window) const noexcept { glfwDestroyWindow(window); }

std::string key_name(int key) {
  if (key >= GLFW_KEY_A && key <= GLFW_KEY_Z) return std::string(1, static_cast<char>('a' + (key - GLFW_KEY_A)));
  if (key >= GLFW_KEY_0 && key <= GLFW_KEY_9) return std::string(1, static_cast<char>('0' + (key - GLFW_KEY_0)));
  if (key >= GLFW_KEY_KP_0 && key <= GLFW_KEY_KP_9) {
    std::string name = "kp_";
    name += static_cast<char>('0' + (key - GLFW_KEY_KP_0));
    return name;
  }
  if (key >= GLFW_KEY_F1 && key <= GLFW_KEY_F25) {
    std::string name = "f";
    name.append(std::to_string(key - GLFW_KEY_F1 + 1));
    return name;
  }
  switch (key) {
    case GLFW_KEY_SPACE: return "space";
    case GLFW_KEY_ENTER: return "enter";
    case GLFW_KEY_KP_ENTER: return "kp_enter";
    case GLFW_KEY_ESCAPE: return "escape";
    case GLFW_KEY_TAB: return "tab";
    case GLFW_KEY_BACKSPACE: return "backspace";
    case GLFW_KEY_INSERT: return "insert";
    case GLFW_KEY_DELETE: return "delete";
    case GLFW_KEY_LEFT: return "left";
    case GLFW_KEY_RIGHT: return "right";
    case GLFW_KEY_UP: return "up";
    case GLFW_KEY_DOWN: return "down";
    case GLFW_KEY_PAGE_UP: return "page_up";
    case GLFW_KEY_PAGE_DOWN: return "page_down";
    case GLFW_KEY_HOME: return "home";
    case GLFW_KEY_END: return "end";
    case GLFW_KEY_COMMA: return "comma";
    case GLFW_KEY_PERIOD: return "period";
    case GLFW_KEY_SLASH: return "slash";
    case GLFW_KEY_MINUS: return "minus";
    case GLFW_KEY_EQUAL: return "equal";
    case GLFW_KEY_SEMICOLON: return "semicolon";
    case GLFW_KEY_LEFT_SHIFT: return "left_shift";
    case GLFW_KEY_RIGHT_SHIFT: return "right_shift";
    case GLFW_KEY_LEFT_CONTROL: return "left_control";
    case GLFW_KEY_RIGHT_CONTROL: return "right_control";
    default: return "";
  }
}

namespace {

PilotBodyOptions body_options(const DesktopOptions& o) {
  PilotBodyOptions b;
  if (o.stand_across) b.start_head_m.z = -b.start_head_m.z;
  return b;
}

}  // namespace

DesktopBackend::DesktopBackend(const DesktopOptions& options) : options_(options), body_(body_options(options)) {}

DesktopBackend::~DesktopBackend() {
  // Members go in reverse order: renderer (waits for its frames), target
  // (waits for the device), context (surface, device, instance), window, GLFW.
  // None of them throws, a lost device included.
  if (renderer_) renderer_->wait_idle_noexcept();
}

Result<std::unique_ptr<DesktopBackend>> DesktopBackend::create(const DesktopOptions& options) {
  if (options.clock == nullptr)
    return Error{Error::Kind::usage, "the desktop backend needs the session clock (DesktopOptions::clock)"};
  if (options.eye_width_px < 16 || options.eye_height_px < 16 || options.eye_width_px > 8192 ||
      options.eye_height_px > 8192)
    return Error{Error::Kind::usage, "the desktop window's eye size must lie between 16 and 8192 pixels, got " +
                                         std::to_string(options.eye_width_px) + "x" +
                                         std::to_string(options.eye_height_px)};
  std::unique_ptr<DesktopBackend> b(new DesktopBackend(options));
  // Screenshots of an earlier run (a resumed session) keep their numbers.
  if (!options.screenshot_dir.empty()) {
    b->stimulus_onsets_ = harness::highest_number(options.screenshot_dir, "stimulus_");
    b->f12_count_ = harness::highest_number(options.screenshot_dir, "screenshot_");
  }
  if (!options.key_script.empty()) {
    auto loaded = load_key_script(options.key_script);
    if (!loaded) return loaded.error();
    if (options.key_script_limits)
      if (auto wrong = check_key_script(loaded.value(), options.key_script, *options.key_script_limits))
        return *wrong;
    b->script_.emplace(std::move(loaded).value());
  }

  auto lib = GlfwLibrary::acquire();
  if (!lib) return lib.error();
  b->glfw_ = std::move(lib).value();
  if (glfwVulkanSupported() != GLFW_TRUE)
    return Error{Error::Kind::device, "cannot open a Vulkan window: GLFW finds no Vulkan loader (" +
                                          take_last_error() + "); install libvulkan1 and mesa-vulkan-drivers"};

  renderer::SwapchainOptions sc;
  sc.eye_extent = vk::Extent2D{options.eye_width_px, options.eye_height_px};
  sc.layout = layout_of(options.preview);
  sc.vsync = options.vsync;
  const vk::Extent2D size = renderer::natural_window_extent(sc);
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
  b->window_.reset(glfwCreateWindow(static_cast<int>(size.width), static_cast<int>(size.height),
                                    "curvlab", nullptr, nullptr));
  if (!b->window_)
    return Error{Error::Kind::device, "cannot open a window: glfwCreateWindow failed: " + take_last_error() +
                                          ". Run under a desktop session or xvfb-run"};
  GLFWwindow* window = b->window_.get();
  glfwSetWindowUserPointer(window, b.get());
  glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int mods) {
    self(w)->on_key(key, action, mods);
  });
  glfwSetCursorPosCallback(window, [](GLFWwindow* w, double x, double y) { self(w)->on_cursor(x, y); });
  glfwSetScrollCallback(window, [](GLFWwindow* w, double, double dy) { self(w)->on_scroll(dy); });
  if (const GLFWvidmode* mode = glfwGetVideoMode(glfwGetPrimaryMonitor());
      mode != nullptr && mode->refreshRate > 0) {
    b->refresh_hz_ = mode->refreshRate;
    b->period_ns_ = static_cast<std::int64_t>(1e9 / b->refresh_hz_);
  }

  renderer::ContextOptions co;
  co.device = options.software ? renderer::DeviceChoice::software : renderer::DeviceChoice::automatic;
  co.validation = options.validation;
  renderer::ContextEmbedding window_embedding;
  std::uint32_t count = 0;
  const char** required = glfwGetRequiredInstanceExtensions(&count);
  for (std::uint32_t i = 0; i < count; ++i) window_embedding.instance_extensions.emplace_back(required[i]);
  window_embedding.create_surface = [window](VkInstance instance)
      -> std::variant<VkSurfaceKHR, renderer::RenderError> {
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    if (const VkResult r = glfwCreateWindowSurface(instance, window, nullptr, &surface);
        r != VK_SUCCESS)
      return renderer::RenderError{renderer::RenderError::Kind::surface,
                                   "glfwCreateWindowSurface failed (" +
                                       vk::to_string(static_cast<vk::Result>(r)) + "): " + take_last_error()};
    return surface;
  };
  constexpr std::string_view doing = "cannot render to the desktop window: ";
  auto ctx = harness::from_renderer(renderer::Context::create(co, window_embedding), doing);
  if (!ctx) return ctx.error();
  b->context_ = std::make_unique<renderer::Context>(std::move(ctx).value());

  auto target = harness::from_renderer(renderer::SwapchainTarget::create(*b->context_, framebuffer_extent(window), sc), doing);
  if (!target) return target.error();
  b->target_ = std::move(target).value();
  try {
    b->renderer_ = std::make_unique<renderer::Renderer>(*b->context_,
                                                        renderer::RendererOptions{.msaa = options.msaa});
  } catch (const renderer::VulkanFailure& f) {
    return Error{Error::Kind::api, std::string("cannot render to the desktop window: ") + f.what()};
  } catch (const vk::SystemError& e) {
    return Error{Error::Kind::api, "cannot render to the desktop window: " +
                                       renderer::vk_call_name(e.what()) + ": " +
                                       renderer::vk_result_name(e.code().value())};
  }
  b->last_frame_ns_ = options.clock->now_ns();
  return b;
}

DisplayInfo DesktopBackend::info() const {
  return {data::Backend::desktop, context_->device_name(), context_->driver_info(), refresh_hz_, options_.eye_width_px,
          options_.eye_height_px, renderer_ ? renderer_->msaa() : 0};
}

std::size_t DesktopBackend::scripted_keys_pressed() const {
  return script_ ? script_->pressed() : 0;
}

std::optional<FrameTiming> DesktopBackend::begin_frame() {
  if (failed_ && quit_delivered_) return std::nullopt;
  // Pace to the display's refresh: FIFO presentation blocks on a real
  // display, but not under Xvfb, where key-script delays and frame times
  // should still mean what they say.
  if (options_.vsync) {
    const std::int64_t wait_ns = last_frame_ns_ + period_ns_ - options_.clock->now_ns();
    if (wait_ns > 0 && wait_ns <= period_ns_)
      std::this_thread::sleep_for(std::chrono::nanoseconds(wait_ns));
  }
  glfwPollEvents();
  // Escape or the window's close button: one more frame, so poll can
  // hand the runner the keys and the quit signal; the session ends after it.
  if (glfwWindowShouldClose(window_.get()) == GLFW_TRUE && quit_delivered_) return std::nullopt;

  const std::int64_t now = options_.clock->now_ns();
  const double dt_s = std::clamp(static_cast<double>(now - last_frame_ns_) * 1e-9, 0.0, 0.1);
  last_frame_ns_ = now;
  GLFWwindow* w = window_.get();
  auto down = [w](int key) { return glfwGetKey(w, key) == GLFW_PRESS ? 1.0 : 0.0; };
  body_.walk(down(GLFW_KEY_W) - down(GLFW_KEY_S), down(GLFW_KEY_D) - down(GLFW_KEY_A),
             down(GLFW_KEY_E) - down(GLFW_KEY_Q), dt_s);

  FrameTiming t;
  t.index = frame_index_++;
  t.now_ns = now;
  t.period_ns = period_ns_;
  // The image is shown at the next vertical blank after presentation; one
  // period ahead is the estimate a window system without timing feedback
  // allows (docs/lab.md).
  t.predicted_display_ns = now + period_ns_;
  return t;
}

geometry::LabFrame DesktopBackend::poses(const FrameTiming& frame) {
  (void)frame;  // the keyboard and mouse have no prediction: the pose of now
  return body_.frame();
}

void DesktopBackend::on_key(int key, int action, int mods) {
  if (action == GLFW_REPEAT) return;
  const bool pressed = action == GLFW_PRESS;
  const std::string name = key_name(key);
  if (!name.empty())
    pending_.push_back(key_input(options_.clock->now_ns(), name, pressed));
  if (!pressed) return;
  if (script_) script_->typed();  // someone is at the keyboard
  if (key == GLFW_KEY_ESCAPE) {
    glfwSetWindowShouldClose(window_.get(), GLFW_TRUE);
    signal_ = Signal::quit;
  } else if (key == GLFW_KEY_HOME) {
    body_.reset();
    if (signal_ == Signal::none) signal_ = Signal::recenter;
  } else if (key == GLFW_KEY_F12) {
    f12_ = true;
  }
  (void)mods;
}

void DesktopBackend::on_cursor(double x, double y) {
  const glm::dvec2 now(x, y);
  if (cursor_px_) {
    const glm::dvec2 d = now - *cursor_px_;
    GLFWwindow* w = window_.get();
    if (glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS) {
      body_.look(d.x, d.y);
    } else if (glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS) {
      const bool left = glfwGetKey(w, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                        glfwGetKey(w, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS;
      body_.move_hand(left ? Hand::left : Hand::right, d.x, d.y, 0.0);
    }
  }
  cursor_px_ = now;
}

void DesktopBackend::on_scroll(double dy) {
  GLFWwindow* w = window_.get();
  const bool left = glfwGetKey(w, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS ||
                    glfwGetKey(w, GLFW_KEY_RIGHT_CONTROL) == GLFW_PRESS;
  body_.move_hand(left ? Hand::left : Hand::right, 0.0, 0.0, dy);
}

Signal DesktopBackend::poll(std::vector<InputEvent>& out) {
  if (script_) {
    if (auto key = script_->due(options_.clock->now_ns())) {
      if (key->hand_m) body_.place_hand(key->left_hand ? Hand::left : Hand::right, *key->hand_m);
      else if (key->look_deg) body_.turn(glm::radians(key->look_deg->x), glm::radians(key->look_deg->y));
      else out.push_back(key_input(options_.clock->now_ns(), key->name, true, harness::io::SourceKind::script));
      // A scripted Escape ends the session as the key does; F12 saves a screenshot.
      if (key->name == "escape") glfwSetWindowShouldClose(window_.get(), GLFW_TRUE);
      if (key->name == "f12") f12_ = true;
    }
    if (script_->ran_out(options_.clock->now_ns()) && !quit_delivered_) {
      std::cerr << "curvlab: " << script_->ran_out_message(options_.key_script, last_phase_) << '\n';
      glfwSetWindowShouldClose(window_.get(), GLFW_TRUE);
    }
  }
  while (!pending_.empty()) {
    out.push_back(std::move(pending_.front()));
    pending_.pop_front();
  }
  if (failed_ || glfwWindowShouldClose(window_.get()) == GLFW_TRUE) {
    quit_delivered_ = true;
    return Signal::quit;
  }
  const Signal s = signal_;
  signal_ = Signal::none;
  return s;
}

renderer::StereoRig DesktopBackend::rig(const FrameTiming& frame, double ipd_m) {
  (void)frame;
  const double aspect = static_cast<double>(options_.eye_width_px) / options_.eye_height_px;
  return renderer::StereoRig::from_ipd(ipd_m, renderer::Fov::symmetric(kHorizontalFovRad, aspect));
}

std::string legend_text(const Overlay& overlay) {
  using harness::io::Phase;
  if (overlay.phase == Phase::instructions || overlay.phase == Phase::break_page || overlay.phase == Phase::done)
    return overlay.waiting_for_input ? "space: continue" : "";
  if (!overlay.waiting_for_input || overlay.answers.empty()) return "";
  std::string text = overlay.prompt.empty() ? "" : overlay.prompt + "  ";
  for (std::size_t i = 0; i < overlay.answers.size(); ++i) {
    const auto& a = overlay.answers[i];
    std::string keys;
    for (const auto& k : a.keys) keys += (keys.empty() ? "" : "/") + k;
    text += (i ? " · " : "") + (keys.empty() ? a.answer + ": no key" : keys + " " + a.answer);
  }
  if (!overlay.value.empty()) text += "  (" + overlay.value + ")";
  return text;
}

std::string DesktopBackend::banner_text(const Overlay& overlay) const {
  std::string text;
  auto add = [&text](const std::string& part) {
    if (part.empty()) return;
    if (!text.empty()) text += " — ";
    text += part;
  };
  add(std::string(harness::io::to_string(overlay.phase)));
  add(overlay.text);
  add(legend_text(overlay));
  return text;
}

renderer::FrameStats DesktopBackend::submit(const renderer::Scene& scene,
                                            const renderer::FrameDescription& frame,
                                            const Overlay& overlay, bool draw) {
  // Someone is looking at the window: every frame is drawn, whatever `draw` says.
  (void)draw;
  renderer::FrameStats stats;
  const std::int64_t now = options_.clock->now_ns();
  if (script_) script_->on_frame(overlay.phase, overlay.waiting_for_input, now);
  if (std::string banner = banner_text(overlay); banner != banner_) {
    banner_ = std::move(banner);
    const std::string title = banner_.empty() ? "curvlab" : "curvlab — " + banner_;
    glfwSetWindowTitle(window_.get(), title.c_str());
    target_->set_banner(banner_);
  }
  if (failed_) return stats;

  // A failing Vulkan call ends the session through the runner (DeviceFailure).
  auto fail = [this](const renderer::VulkanFailure& f) {
    failed_ = true;
    return DeviceFailure(f.call, renderer::vk_result_name(f.result), "desktop window");
  };
  std::variant<bool, renderer::RenderError> ready = false;
  try {
    ready = target_->begin_frame(framebuffer_extent(window_.get()));
  } catch (const renderer::VulkanFailure& f) {
    throw fail(f);
  }
  if (auto* e = std::get_if<renderer::RenderError>(&ready)) {
    // The window's swapchain could not be made again (a resize to a surface
    // the device cannot draw to).
    failed_ = true;
    throw DeviceFailure("vkCreateSwapchainKHR", "unusable surface", e->message);
  }
  const bool onset = overlay.phase == harness::io::Phase::stimulus && last_phase_ != harness::io::Phase::stimulus;
  // The response panel as the participant first read it, numbered as its stimulus.
  const bool answering = overlay.phase == harness::io::Phase::response && last_phase_ != harness::io::Phase::response;
  last_phase_ = overlay.phase;
  if (!std::get<bool>(ready)) return stats;  // minimised: nothing to draw into

  renderer::FrameDescription f = frame;
  f.width_px = options_.eye_width_px;
  f.height_px = options_.eye_height_px;
  try {
    stats = renderer_->render(scene, f, *target_);
  } catch (const renderer::VulkanFailure& e) {
    throw fail(e);
  }
  if (onset && !options_.screenshot_dir.empty()) {
    char name[32];
    std::snprintf(name, sizeof name, "stimulus_%03d", ++stimulus_onsets_);
    save_frame((std::filesystem::path(options_.screenshot_dir) / name).string());
  }
  if (answering && !options_.screenshot_dir.empty()) {
    char name[32];
    std::snprintf(name, sizeof name, "response_%03d", stimulus_onsets_);
    save_frame((std::filesystem::path(options_.screenshot_dir) / name).string());
  }
  if (f12_) {
    f12_ = false;
    screenshot_f12();
  }
  return stats;
}

void DesktopBackend::screenshot_f12() {
  char name[32];
  std::snprintf(name, sizeof name, "screenshot_%03d", ++f12_count_);
  const std::filesystem::path dir =
      options_.screenshot_dir.empty() ? std::filesystem::current_path()
                                      : std::filesystem::path(options_.screenshot_dir);
  for (const auto& file : save_frame((dir / name).string()))
    std::cerr << "curvlab: screenshot " << file << '\n';
}

std::vector<std::string> DesktopBackend::save_frame(const std::string& stem) {
  std::vector<std::string> written;
  std::error_code ec;
  const auto parent = std::filesystem::path(stem).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  auto write = [&](const std::optional<renderer::Rgba8Image>& image, const std::string& suffix) {
    if (!image) return;
    const std::string path = stem + suffix;
    const auto saved = renderer::write_png(path, *image);
    if (const auto* err = std::get_if<renderer::RenderError>(&saved)) {
      std::cerr << "curvlab: screenshot not saved: " << err->message << '\n';
      return;
    }
    written.push_back(path);
  };
  try {
    write(target_->read_eye(renderer::Eye::left), "_left.png");
    write(target_->read_eye(renderer::Eye::right), "_right.png");
    write(target_->read_window(), "_window.png");
  } catch (const renderer::VulkanFailure& f) {
    failed_ = true;
    throw DeviceFailure(f.call, renderer::vk_result_name(f.result), "reading the window back");
  } catch (const vk::SystemError& e) {
    failed_ = true;
    throw DeviceFailure(renderer::vk_call_name(e.what()), renderer::vk_result_name(e.code().value()),
                         "reading the window back");
  }
  screenshots_.insert(screenshots_.end(), written.begin(), written.end());
  return written;
}

harness::io::Reach keyboard_reach() {
  harness::io::Reach r;
  r.kind = harness::io::SourceKind::keyboard;
  for (const char* key : {"space", "enter", "f", "r"}) r.intents |= key_intents(key);
  r.every_key = true;
  r.continue_phrase = "press space";
  return r;
}

harness::io::Intents key_intents(const std::string& key) {
  using harness::io::Intent;
  if (key == "space") return {Intent::continue_page, Intent::calibration_touch, Intent::cue_strike};
  if (key == "enter") return {Intent::continue_page, Intent::calibration_accept};
  if (key == "return") return {Intent::continue_page};
  if (key == "f") return {Intent::calibration_fit_three};
  if (key == "r") return {Intent::calibration_redo};
  return {};
}

InputEvent key_input(std::int64_t t_ns, std::string key, bool pressed, harness::io::SourceKind source) {
  InputEvent in;
  in.t_ns = t_ns;
  in.source = {source, ""};
  in.intents = key_intents(key);
  in.control = {harness::io::ControlKind::key, std::move(key)};
  in.pressed = pressed;
  return in;
}

Result<std::unique_ptr<harness::io::InteractiveDisplay>> make_desktop_backend(const DesktopOptions& options) {
  auto made = DesktopBackend::create(options);
  if (!made) return made.error();
  return std::unique_ptr<harness::io::InteractiveDisplay>(std::move(made).value());
}

}  // namespace curvlab::harness::desktop
