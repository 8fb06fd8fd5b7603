#include "curvlab/harness/operator/operator_window.hpp"

#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/text.hpp"

#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <optional>
#include <thread>

namespace curvlab::harness::operator_console {

namespace {

using runner::OperatorAction;
using runner::OperatorActionKind;

constexpr int kWidth = 960;
constexpr int kHeight = 720;
constexpr int kEyeHeight = 430;      // the participant's view, top
constexpr int kPanelTop = 440;       // the status panel below it
constexpr auto kTick = std::chrono::milliseconds(66);  // about 15 Hz
constexpr int kPollEvery = 4;        // frames between glfwPollEvents
constexpr const char* kKeys = "keys: P pause  R resume  C recenter  T repeat  S skip  N note  Q end";

std::string glfw_error() {
  const char* text = nullptr;
  glfwGetError(&text);
  return text == nullptr ? "unknown error" : text;
}

// Nearest-neighbour scaling of `src` (or one half of it) into the canvas
// rectangle, keeping its aspect ratio, centred.
void blit_scaled(const io::MirrorImage& src, EyeView eyes, renderer::Rgba8Image& dst, int top, int height) {
  if (src.width == 0 || src.height == 0) return;
  const int half = static_cast<int>(src.width / 2);
  const int x0 = eyes == EyeView::right ? half : 0;
  const int sw = eyes == EyeView::both ? static_cast<int>(src.width) : half;
  const int sh = static_cast<int>(src.height);
  const double scale = std::min(static_cast<double>(dst.width) / sw, static_cast<double>(height) / sh);
  const int w = static_cast<int>(sw * scale), h = static_cast<int>(sh * scale);
  const int left = (dst.width - w) / 2, up = top + (height - h) / 2;
  for (int y = 0; y < h; ++y) {
    const int sy = std::min(sh - 1, static_cast<int>(y / scale));
    for (int x = 0; x < w; ++x) {
      const int sx = x0 + std::min(sw - 1, static_cast<int>(x / scale));
      const auto* p = &src.rgba[(static_cast<std::size_t>(sy) * src.width + static_cast<std::size_t>(sx)) * 4];
      auto* q = &dst.pixels[(static_cast<std::size_t>(up + y) * static_cast<std::size_t>(dst.width) +
                             static_cast<std::size_t>(left + x)) * 4];
      std::copy(p, p + 3, q);
      q[3] = 255;
    }
  }
}

// The coverage bitmap as light text on the panel's background.
void blit_text(const renderer::CoverageBitmap& text, renderer::Rgba8Image& dst, int left, int top) {
  for (int y = 0; y < text.height && top + y < dst.height; ++y)
    for (int x = 0; x < text.width && left + x < dst.width; ++x) {
      const int c = text.pixels[static_cast<std::size_t>(y * text.width + x)];
      auto* q = &dst.pixels[(static_cast<std::size_t>(top + y) * static_cast<std::size_t>(dst.width) +
                             static_cast<std::size_t>(left + x)) * 4];
      for (int k = 0; k < 3; ++k) q[k] = static_cast<std::uint8_t>((q[k] * (255 - c) + 235 * c) / 255);
    }
}

class OperatorWindow final : public runner::OperatorConsole {
 public:
  OperatorWindow(OperatorWindowOptions options, GLFWwindow* window)
      : options_(std::move(options)), window_(window), script_(std::move(options_.script)) {
    glfwSetWindowUserPointer(window_, this);
    glfwSetKeyCallback(window_, &OperatorWindow::on_key);
    glfwSetCharCallback(window_, &OperatorWindow::on_char);
    glfwSetWindowCloseCallback(window_, &OperatorWindow::on_close);
    glfwMakeContextCurrent(nullptr);
    canvas_.width = kWidth;
    canvas_.height = kHeight;
    canvas_.pixels.assign(static_cast<std::size_t>(kWidth) * kHeight * 4, 0);
    thread_ = std::thread([this] { draw_loop(); });
  }

  ~OperatorWindow() override {
    if (!options_.screenshot_dir.empty()) {
      // The last one waits (bounded) for the drawing thread: the session is over.
      std::unique_lock lock(mutex_);
      shots_.emplace_back("end");
      wake_.notify_all();
      wake_.wait_for(lock, std::chrono::seconds(5), [this] { return shots_.empty(); });
    }
    {
      const std::lock_guard lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
    glfwDestroyWindow(window_);
    if (options_.terminate_glfw) glfwTerminate();
  }
  OperatorWindow(const OperatorWindow&) = delete;
  OperatorWindow& operator=(const OperatorWindow&) = delete;

  void show(const runner::OperatorStatus& status) override {
    // A flag test per frame; the copy only when the drawing thread asked.
    if (!want_status_.load(std::memory_order_acquire) && !status.ended) return;
    const std::lock_guard lock(mutex_);
    status_ = status;
    want_status_.store(false, std::memory_order_release);
  }

  void take(std::int64_t elapsed_ns, std::vector<OperatorAction>& out) override {
    script_.due(elapsed_ns, out);
    if (++frames_ % kPollEvery == 0) glfwPollEvents();
    for (auto& a : keyed_) {
      a.at_ns = elapsed_ns;
      out.push_back(std::move(a));
    }
    keyed_.clear();
  }

  // The drawing thread saves its next frame; the frame thread does not wait.
  void acted(const OperatorAction& action) override {
    if (options_.screenshot_dir.empty()) return;
    const std::lock_guard lock(mutex_);
    shots_.push_back(std::string("action_")
                         .append(std::to_string(++actions_))
                         .append("_")
                         .append(runner::to_string(action.kind)));
    wake_.notify_all();
  }

 private:
  static void on_key(GLFWwindow* w, int key, int scancode, int action, int mods) {
    (void)scancode;
    (void)mods;
    if (action != GLFW_PRESS) return;
    static_cast<OperatorWindow*>(glfwGetWindowUserPointer(w))->key(key);
  }
  // The window's close button ends the session as Q does (it stays
  // resumable); the window itself stays until the session has ended.
  static void on_close(GLFWwindow* w) {
    glfwSetWindowShouldClose(w, GLFW_FALSE);
    static_cast<OperatorWindow*>(glfwGetWindowUserPointer(w))->close_requested();
  }
  static void on_char(GLFWwindow* w, unsigned int codepoint) {
    static_cast<OperatorWindow*>(glfwGetWindowUserPointer(w))->character(codepoint);
  }

  void add(OperatorActionKind kind, std::string text = {}) {
    keyed_.push_back(OperatorAction{kind, 0, std::move(text), "window"});
  }

  void key(int key) {
    const std::lock_guard lock(mutex_);
    if (note_) {
      if (key == GLFW_KEY_ENTER || key == GLFW_KEY_KP_ENTER) {
        if (!note_->empty()) add(OperatorActionKind::note, *note_);
        note_.reset();
      } else if (key == GLFW_KEY_ESCAPE) {
        note_.reset();
      } else if (key == GLFW_KEY_BACKSPACE && !note_->empty()) {
        note_->pop_back();
      }
      return;
    }
    switch (key) {
      case GLFW_KEY_P: add(OperatorActionKind::pause); break;
      case GLFW_KEY_R: add(OperatorActionKind::resume); break;
      case GLFW_KEY_C: add(OperatorActionKind::recenter); break;
      case GLFW_KEY_T: add(OperatorActionKind::repeat); break;
      case GLFW_KEY_S: add(OperatorActionKind::skip); break;
      case GLFW_KEY_Q: add(OperatorActionKind::end); break;
      case GLFW_KEY_N: note_.emplace(); skip_char_ = true; break;
      default: break;
    }
  }

  void close_requested() {
    const std::lock_guard lock(mutex_);
    note_.reset();
    add(OperatorActionKind::end);
  }

  void character(unsigned int codepoint) {
    const std::lock_guard lock(mutex_);
    if (!note_) return;
    if (skip_char_) {  // the 'n' that opened the note
      skip_char_ = false;
      return;
    }
    if (codepoint < 0x80) note_->push_back(static_cast<char>(codepoint));
  }

  // ---- the drawing thread ----------------------------------------------------

  void draw_loop() {
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(0);
    auto disk_checked = std::chrono::steady_clock::now() - std::chrono::hours(1);
    std::optional<double> free_gb;
    for (;;) {
      std::vector<std::string> stems;
      runner::OperatorStatus status;
      std::string note;
      bool typing = false;
      {
        std::unique_lock lock(mutex_);
        wake_.wait_for(lock, kTick, [this] { return stop_ || !shots_.empty(); });
        if (stop_ && shots_.empty()) break;
        stems = shots_;
        status = status_;
        typing = note_.has_value();
        if (typing) note = *note_;
      }
      want_status_.store(true, std::memory_order_release);
      if (options_.mirror != nullptr && options_.mirror->take(eyes_)) have_eyes_ = true;
      if (options_.mirror != nullptr) options_.mirror->request();
      if (std::chrono::steady_clock::now() - disk_checked > std::chrono::seconds(1)) {
        free_gb = free_disk_gb();
        disk_checked = std::chrono::steady_clock::now();
      }
      compose(status, free_gb, typing ? std::optional<std::string>(note) : std::nullopt);
      present(stems);
      if (!stems.empty()) {
        const std::lock_guard lock(mutex_);
        shots_.erase(shots_.begin(), shots_.begin() + static_cast<std::ptrdiff_t>(stems.size()));
        wake_.notify_all();
      }
    }
    glfwMakeContextCurrent(nullptr);
  }

  std::optional<double> free_disk_gb() const {
    std::error_code ec;
    const auto info = std::filesystem::space(options_.db_dir.empty() ? "." : options_.db_dir, ec);
    if (ec) return std::nullopt;
    return static_cast<double>(info.available) / 1e9;
  }

  void compose(const runner::OperatorStatus& status, std::optional<double> free_gb,
               const std::optional<std::string>& note) {
    for (std::size_t i = 0; i < canvas_.pixels.size(); i += 4) {
      canvas_.pixels[i] = canvas_.pixels[i + 1] = canvas_.pixels[i + 2] = 24;
      canvas_.pixels[i + 3] = 255;
    }
    if (have_eyes_) blit_scaled(eyes_, options_.eyes, canvas_, 0, kEyeHeight);
    auto lines = runner::status_lines(status, free_gb);
    lines.push_back(note ? std::string("note: ").append(*note).append("_   (Enter stores, Esc cancels)") : std::string(kKeys));
    std::string text;
    if (options_.mirror == nullptr) text = "(no copy of the participant's view: see its own window)\n";
    for (const auto& l : lines) text.append(l).append("\n");
    if (!text.empty()) text.pop_back();
    // Rasterised again only when the text changed.
    if (text != panel_text_) {
      auto bitmap = renderer::render_text(text, kWidth - 20, kHeight - kPanelTop - 10, 30.0,
                                          options_.font_path.empty() ? CURVLAB_DEFAULT_FONT : options_.font_path);
      panel_ = std::get_if<renderer::CoverageBitmap>(&bitmap) != nullptr
                   ? std::get<renderer::CoverageBitmap>(std::move(bitmap))
                   : renderer::CoverageBitmap{};
      panel_text_ = text;
    }
    blit_text(panel_, canvas_, 10, kPanelTop);
  }

  void present(const std::vector<std::string>& stems) {
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_, &fw, &fh);
    glViewport(0, 0, fw, fh);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glPixelZoom(1.0f, -1.0f);  // canvas rows run top to bottom
    glRasterPos2f(-1.0f, 1.0f);
    glDrawPixels(kWidth, kHeight, GL_RGBA, GL_UNSIGNED_BYTE, canvas_.pixels.data());
    for (const auto& stem : stems) save(stem, fw, fh);
    glfwSwapBuffers(window_);
  }

  // The window's back buffer as drawn, as a PNG.
  void save(const std::string& stem, int fw, int fh) {
    renderer::Rgba8Image shot;
    shot.width = fw;
    shot.height = fh;
    shot.pixels.resize(static_cast<std::size_t>(fw) * static_cast<std::size_t>(fh) * 4);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, fw, fh, GL_RGBA, GL_UNSIGNED_BYTE, shot.pixels.data());
    const std::size_t row = static_cast<std::size_t>(fw) * 4;
    for (int y = 0; y < fh / 2; ++y)
      std::swap_ranges(shot.pixels.begin() + static_cast<std::ptrdiff_t>(y * row),
                       shot.pixels.begin() + static_cast<std::ptrdiff_t>((y + 1) * row),
                       shot.pixels.begin() + static_cast<std::ptrdiff_t>((fh - 1 - y) * row));
    const auto path = (std::filesystem::path(options_.screenshot_dir) / (stem + ".png")).string();
    // A screenshot is the operator's convenience, not session data: a failed
    // write is told on stderr and the session goes on.
    const auto saved = renderer::write_png(path, shot);
    if (const auto* err = std::get_if<renderer::RenderError>(&saved))
      std::cerr << "curvlab: operator window: screenshot not saved: " << err->message << '\n';
  }

  OperatorWindowOptions options_;
  GLFWwindow* window_;
  runner::ScriptedActions script_;
  std::vector<OperatorAction> keyed_;  // main thread only
  std::int64_t frames_ = 0;
  int actions_ = 0;

  std::mutex mutex_;  // guards what both threads touch below
  std::condition_variable wake_;
  runner::OperatorStatus status_;
  std::optional<std::string> note_;  // being typed
  bool skip_char_ = false;
  std::vector<std::string> shots_;  // screenshots wanted, by file stem
  bool stop_ = false;
  std::atomic<bool> want_status_{true};

  // drawing thread only
  io::MirrorImage eyes_;
  bool have_eyes_ = false;
  renderer::Rgba8Image canvas_;
  std::string panel_text_;
  renderer::CoverageBitmap panel_;
  std::thread thread_;
};

}  // namespace

Result<std::unique_ptr<runner::OperatorConsole>> open_operator_window(OperatorWindowOptions options) {
  if (glfwInit() != GLFW_TRUE)
    return Error{Error::Kind::device, "cannot open the operator window: " + glfw_error() +
                                          ". It needs a display (a desktop session, or xvfb-run -a); "
                                          "--operator-window off runs without it"};
  glfwDefaultWindowHints();
  glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  GLFWwindow* window = glfwCreateWindow(kWidth, kHeight, "curvlab operator", nullptr, nullptr);
  if (window == nullptr) {
    const std::string why = glfw_error();
    if (options.terminate_glfw) glfwTerminate();
    return Error{Error::Kind::device, "cannot open the operator window: " + why};
  }
  if (!options.screenshot_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.screenshot_dir, ec);
    if (ec) {
      glfwDestroyWindow(window);
      if (options.terminate_glfw) glfwTerminate();
      return Error{Error::Kind::io, "cannot create --operator-screenshot folder " + options.screenshot_dir + ": " +
                                        ec.message()};
    }
  }
  return std::unique_ptr<runner::OperatorConsole>(new OperatorWindow(std::move(options), window));
}

}  // namespace curvlab::harness::operator_console
