// Targets that put frames in front of a person: a window's swapchain
// (SwapchainTarget, for the desktop pilot backend) and images owned by
// someone else, handed in per frame (ExternalImagesTarget, for OpenXR
// swapchain images). Both let the renderer draw into sRGB RGBA8 images of
// their own — the format its pipelines are built for — and copy the result
// into the presented images, so the presented format is negotiated freely.
//
// The renderer knows nothing of windows: the surface comes from the Context
// (ContextEmbedding::create_surface), made by whoever owns the window.
#pragma once

#include "curvlab/renderer/gpu.hpp"
#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/target.hpp"

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <variant>

namespace curvlab::renderer {

enum class WindowLayout { side_by_side, left_eye, right_eye };

struct SwapchainOptions {
  vk::Extent2D eye_extent{960, 960};  // the size each eye is rendered at
  WindowLayout layout = WindowLayout::side_by_side;
  bool vsync = true;  // FIFO; otherwise MAILBOX or IMMEDIATE when offered
  std::uint32_t banner_height_px = 28;  // the text line along the bottom
  // Side by side: the dark strip between the eyes, so that the two images
  // never read as one wide picture (two abutting sticks as one long stick).
  std::uint32_t eye_gap_px = 32;
  std::string font_path = CURVLAB_DEFAULT_FONT;
};

// The window size that shows the eyes at their rendered size with the banner
// below them.
vk::Extent2D natural_window_extent(const SwapchainOptions& options);

// Presents to the Context's surface. Each frame: begin_frame() acquires a
// swapchain image; Renderer::render() draws both eyes into the target's own
// images; frame_finished() (called by the renderer after its submit) records
// and submits the composition — eyes letterboxed side by side or one of them,
// the banner text below — into the swapchain image and presents it. The
// composition waits on the acquire semaphore and signals a per-image
// semaphore the present waits on; two frames may be in flight.
//
// Holds a reference to the Context (which must outlive it) and owns the
// swapchain, its semaphores, fences and command buffers and the eye, window
// and banner images; the destructor waits for the device to go idle. Not
// thread-safe: one thread drives the frame loop.
class SwapchainTarget final : public RenderTarget {
 public:
  // framebuffer_px: the window's size in pixels now.
  static std::variant<std::unique_ptr<SwapchainTarget>, RenderError> create(
      const Context& ctx, vk::Extent2D framebuffer_px, const SwapchainOptions& options);
  ~SwapchainTarget() override;

  // Acquires the image for the coming frame, first recreating the swapchain
  // when the window's size changed or the old one went out of date. false:
  // there is nothing to draw into now (a minimised window); skip the frame.
  std::variant<bool, RenderError> begin_frame(vk::Extent2D framebuffer_px);
  // The text line drawn along the bottom of the window (trial information).
  void set_banner(const std::string& text);
  void set_layout(WindowLayout layout) { layout_ = layout; }

  EyeImage eye_image(Eye eye) override;
  void record_after(const vk::raii::CommandBuffer& cb, Eye eye) override;
  void frame_finished() override;
  [[nodiscard]] bool preserves_contents() const override { return false; }
  [[nodiscard]] std::uint64_t identity() const override { return identity_; }

  // A failure during composition or presentation (device or surface lost);
  // the frame loop should stop. The failing call also throws VulkanFailure
  // (from begin_frame, or from frame_finished inside Renderer::render).
  [[nodiscard]] const std::optional<RenderError>& failure() const { return failure_; }

  // The last presented frame: one eye as rendered, or the whole window as
  // composed (banner included). Waits for the GPU. nullopt before the first
  // frame.
  [[nodiscard]] std::optional<Rgba8Image> read_eye(Eye eye) const;
  [[nodiscard]] std::optional<Rgba8Image> read_window() const;

  [[nodiscard]] vk::Extent2D window_extent() const { return extent_; }
  [[nodiscard]] vk::Format format() const { return format_; }
  [[nodiscard]] vk::PresentModeKHR present_mode() const { return mode_; }
  [[nodiscard]] std::uint64_t presented_frames() const { return presented_; }
  [[nodiscard]] std::uint32_t recreations() const { return recreations_; }

 private:
  struct FrameSync {
    vk::raii::CommandBuffer cb{nullptr};
    vk::raii::Fence fence{nullptr};  // signalled when the slot's composition finished
    vk::raii::Semaphore acquired{nullptr};
    Buffer banner;  // host-visible RGBA strip, written while the slot is idle
  };

  SwapchainTarget(const Context& ctx, const SwapchainOptions& options);
  std::optional<RenderError> recreate(vk::Extent2D framebuffer_px);
  void render_banner();
  void wait_idle() const noexcept;

  const Context& ctx_;
  SwapchainOptions options_;
  WindowLayout layout_;
  std::uint64_t identity_;
  vk::raii::SwapchainKHR swapchain_{nullptr};
  std::vector<vk::Image> images_;                // owned by the swapchain
  std::vector<vk::raii::Semaphore> presentable_;  // one per swapchain image
  vk::Format format_ = vk::Format::eUndefined;
  vk::Extent2D extent_{};
  vk::Extent2D requested_{};  // the window size the swapchain was made for
  vk::PresentModeKHR mode_ = vk::PresentModeKHR::eFifo;
  std::array<Image, 2> eyes_;
  Image window_;
  std::array<FrameSync, 2> frames_;
  std::size_t frame_ = 0;
  std::uint32_t image_index_ = 0;
  bool acquired_ = false;
  bool out_of_date_ = false;
  bool drawn_ = false;
  std::string banner_text_;
  std::vector<std::uint8_t> banner_rgba_;  // extent_.width × banner height, RGBA
  std::optional<RenderError> failure_;
  std::uint64_t presented_ = 0;
  std::uint32_t recreations_ = 0;
};

// An image someone else owns (an OpenXR swapchain image), for one eye and one
// frame.
struct ExternalImage {
  vk::Image image;
  vk::Format format = vk::Format::eR8G8B8A8Srgb;
  vk::Extent2D extent;
  // The layout the owner expects when the frame's commands are done (OpenXR:
  // COLOR_ATTACHMENT_OPTIMAL).
  vk::ImageLayout final_layout = vk::ImageLayout::eColorAttachmentOptimal;
};

// Renders each eye into an sRGB RGBA8 image of its own and, in the frame's
// command buffer, copies it into the external image set for the frame: a raw
// copy for R8G8B8A8_SRGB (the bytes shown are the bytes of the PNGs), a blit
// for other formats, which converts through linear values — so a UNORM
// swapchain, which OpenXR runtimes take as linear, receives linear values. Both images must be
// set before each Renderer::render(); frame_finished() forgets them.
// Holds a reference to the Context; owns its eye images. Not thread-safe.
class ExternalImagesTarget final : public RenderTarget {
 public:
  explicit ExternalImagesTarget(const Context& ctx);
  ~ExternalImagesTarget() override;

  void set_image(Eye eye, const ExternalImage& image);

  EyeImage eye_image(Eye eye) override;
  void record_after(const vk::raii::CommandBuffer& cb, Eye eye) override;
  void frame_finished() override;
  [[nodiscard]] bool preserves_contents() const override { return false; }
  [[nodiscard]] std::uint64_t identity() const override { return identity_; }

  // The last frame's eye as rendered; waits for the GPU. nullopt before the
  // first frame.
  [[nodiscard]] std::optional<Rgba8Image> read_eye(Eye eye) const;

 private:
  const Context& ctx_;
  std::uint64_t identity_;
  std::array<Image, 2> own_;
  std::array<std::optional<ExternalImage>, 2> external_;
  std::array<bool, 2> drawn_{false, false};
};

// Copies a colour image in TRANSFER_SRC_OPTIMAL layout to the CPU (RGBA8
// formats), after every command submitted so far. Waits for the GPU.
Rgba8Image read_image(const Context& ctx, vk::Image image, vk::Extent2D extent);

}  // namespace curvlab::renderer
