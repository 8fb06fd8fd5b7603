#include "curvlab/renderer/swapchain.hpp"

#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/text.hpp"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace curvlab::renderer {
namespace {

// Far from the offscreen targets' numbering, so identities never collide.
std::atomic<std::uint64_t> next_identity{std::uint64_t{1} << 40};

// The renderer's eye format; the window image is composed in it too, so
// letterbox scaling filters linear values and the banner's bytes are display
// values, as the PNGs hold them.
constexpr vk::Format kEyeFormat = vk::Format::eR8G8B8A8Srgb;
constexpr std::array<std::uint8_t, 3> kBannerInk{235, 235, 235};
constexpr std::array<std::uint8_t, 3> kBannerPaper{24, 24, 28};

RenderError surface_failure(std::string message) { return {RenderError::Kind::surface, std::move(message)}; }

const vk::ImageSubresourceLayers kColorLayer{vk::ImageAspectFlagBits::eColor, 0, 0, 1};
const vk::ImageSubresourceRange kColorRange{vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1};

// Makes every earlier write (the renderer's pass, in an earlier submission on
// the same queue) visible to the transfers that follow.
void writes_before_transfer(const vk::raii::CommandBuffer& cb) {
  const vk::MemoryBarrier barrier{.srcAccessMask = vk::AccessFlagBits::eMemoryWrite,
                                  .dstAccessMask = vk::AccessFlagBits::eTransferRead |
                                                   vk::AccessFlagBits::eTransferWrite};
  cb.pipelineBarrier(vk::PipelineStageFlagBits::eAllCommands, vk::PipelineStageFlagBits::eTransfer,
                     {}, barrier, {}, {});
}

// The blit of all of `src` onto the rectangle from (x0, y0) to (x1, y1).
vk::ImageBlit blit_onto(vk::Extent2D src, std::int32_t x0, std::int32_t y0, std::int32_t x1, std::int32_t y1) {
  return vk::ImageBlit{
      .srcSubresource = kColorLayer,
      .srcOffsets = std::array<vk::Offset3D, 2>{
          vk::Offset3D{0, 0, 0}, vk::Offset3D{static_cast<std::int32_t>(src.width),
                                              static_cast<std::int32_t>(src.height), 1}},
      .dstSubresource = kColorLayer,
      .dstOffsets = std::array<vk::Offset3D, 2>{vk::Offset3D{x0, y0, 0}, vk::Offset3D{x1, y1, 1}}};
}

// The blit that shows `src` as large as fits in the rectangle, centred,
// keeping its aspect ratio.
vk::ImageBlit letterbox(vk::Extent2D src, std::int32_t x0, std::int32_t y0, std::uint32_t w,
                        std::uint32_t h) {
  const double scale = std::min(static_cast<double>(w) / src.width,
                                static_cast<double>(h) / src.height);
  const auto dw = static_cast<std::int32_t>(src.width * scale);
  const auto dh = static_cast<std::int32_t>(src.height * scale);
  const std::int32_t ox = x0 + (static_cast<std::int32_t>(w) - dw) / 2;
  const std::int32_t oy = y0 + (static_cast<std::int32_t>(h) - dh) / 2;
  return blit_onto(src, ox, oy, ox + dw, oy + dh);
}

vk::ImageBlit whole(vk::Extent2D src, vk::Extent2D dst) {
  return blit_onto(src, 0, 0, static_cast<std::int32_t>(dst.width), static_cast<std::int32_t>(dst.height));
}

// The colour the window shows around letterboxed eyes (linear).
vk::ClearColorValue letterbox_colour() {
  const glm::vec4 c = display(0.08f, 0.08f, 0.09f);
  return vk::ClearColorValue{std::array<float, 4>{c.x, c.y, c.z, 1.0f}};
}

bool is_srgb(vk::Format f) {
  return f == vk::Format::eB8G8R8A8Srgb || f == vk::Format::eR8G8B8A8Srgb;
}

// sRGB first: the composed window holds sRGB-encoded values, which a blit
// into an sRGB image keeps byte for byte. A UNORM image in the sRGB colour
// space would receive the decoded (linear) values and look too dark.
vk::SurfaceFormatKHR choose_format(const std::vector<vk::SurfaceFormatKHR>& formats) {
  for (const vk::Format want : {vk::Format::eB8G8R8A8Srgb, vk::Format::eR8G8B8A8Srgb,
                                vk::Format::eB8G8R8A8Unorm, vk::Format::eR8G8B8A8Unorm})
    for (const auto& f : formats)
      if (f.format == want && f.colorSpace == vk::ColorSpaceKHR::eSrgbNonlinear) return f;
  return formats.front();
}

vk::PresentModeKHR choose_mode(const std::vector<vk::PresentModeKHR>& modes, bool vsync) {
  if (!vsync)
    for (const auto want : {vk::PresentModeKHR::eMailbox, vk::PresentModeKHR::eImmediate})
      if (std::find(modes.begin(), modes.end(), want) != modes.end()) return want;
  return vk::PresentModeKHR::eFifo;  // always available
}

// Shows the eye image `src` letterboxed in the window image's columns from
// x0, w wide and area_h high.
void show_eye(const vk::raii::CommandBuffer& cb, const Image& src, vk::Image window, std::int32_t x0,
              std::uint32_t w, std::uint32_t area_h) {
  const vk::ImageBlit blit = letterbox(src.extent, x0, 0, w, area_h);
  const std::int32_t shown_w = blit.dstOffsets[1].x - blit.dstOffsets[0].x;
  const std::int32_t shown_h = blit.dstOffsets[1].y - blit.dstOffsets[0].y;
  if (shown_w == static_cast<std::int32_t>(src.extent.width) &&
      shown_h == static_cast<std::int32_t>(src.extent.height)) {
    // Shown at its rendered size (the window's natural size): a plain
    // copy, several times cheaper than a filtered blit on a CPU device.
    const vk::ImageCopy copy{.srcSubresource = kColorLayer,
                             .dstSubresource = kColorLayer,
                             .dstOffset = blit.dstOffsets[0],
                             .extent = {src.extent.width, src.extent.height, 1}};
    cb.copyImage(*src.image, vk::ImageLayout::eTransferSrcOptimal, window, vk::ImageLayout::eTransferDstOptimal,
                 copy);
  } else {
    cb.blitImage(*src.image, vk::ImageLayout::eTransferSrcOptimal, window, vk::ImageLayout::eTransferDstOptimal,
                 blit, vk::Filter::eLinear);
  }
}

// The eyes the layout shows, side by side or one alone, in the window's
// top `area` (the rest is the banner's).
void show_eyes(const vk::raii::CommandBuffer& cb, WindowLayout layout, const std::array<Image, 2>& eyes,
               vk::Image window, vk::Extent2D area, std::uint32_t gap_px) {
  const auto eye = [&eyes](Eye e) -> const Image& { return eyes[static_cast<std::size_t>(e)]; };
  switch (layout) {
    case WindowLayout::side_by_side: {
      const std::uint32_t gap = std::min(gap_px, area.width / 4);  // a narrow window keeps its eyes
      const std::uint32_t half = (area.width - gap) / 2;
      show_eye(cb, eye(Eye::left), window, 0, half, area.height);
      show_eye(cb, eye(Eye::right), window, static_cast<std::int32_t>(half + gap), area.width - half - gap,
               area.height);
      break;
    }
    case WindowLayout::left_eye: show_eye(cb, eye(Eye::left), window, 0, area.width, area.height); break;
    case WindowLayout::right_eye: show_eye(cb, eye(Eye::right), window, 0, area.width, area.height); break;
  }
}

// The banner strip along the bottom `banner_h` rows of the window image.
void copy_banner(const vk::raii::CommandBuffer& cb, const Buffer& banner, vk::Image window, vk::Extent2D extent,
                 std::uint32_t banner_h) {
  const vk::BufferImageCopy region{.imageSubresource = kColorLayer,
                                   .imageOffset = {0, static_cast<std::int32_t>(extent.height - banner_h), 0},
                                   .imageExtent = {extent.width, banner_h, 1}};
  cb.copyBufferToImage(*banner.buffer, window, vk::ImageLayout::eTransferDstOptimal, region);
}

// The composed window image copied into the swapchain image, left ready
// to present.
void copy_to_swapchain_image(const vk::raii::CommandBuffer& cb, vk::Image window, vk::Image target,
                             vk::Extent2D extent) {
  transition(cb, window, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eTransferDstOptimal,
             vk::ImageLayout::eTransferSrcOptimal);
  transition(cb, target, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eUndefined,
             vk::ImageLayout::eTransferDstOptimal);
  cb.blitImage(window, vk::ImageLayout::eTransferSrcOptimal, target, vk::ImageLayout::eTransferDstOptimal,
               whole(extent, extent), vk::Filter::eNearest);
  transition(cb, target, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eTransferDstOptimal,
             vk::ImageLayout::ePresentSrcKHR);
}

// The composition, once the image is acquired; it signals `presentable`.
void submit_composition(const vk::raii::Queue& queue, const vk::raii::CommandBuffer& cb, vk::Semaphore acquired,
                        vk::Semaphore presentable, vk::Fence done) {
  const vk::PipelineStageFlags wait_stage = vk::PipelineStageFlagBits::eTransfer;
  const vk::CommandBuffer raw = *cb;
  queue.submit(vk::SubmitInfo{.waitSemaphoreCount = 1,
                              .pWaitSemaphores = &acquired,
                              .pWaitDstStageMask = &wait_stage,
                              .commandBufferCount = 1,
                              .pCommandBuffers = &raw,
                              .signalSemaphoreCount = 1,
                              .pSignalSemaphores = &presentable},
               done);
}

// Presents the image once `presentable` is signalled; false when the
// swapchain no longer matches the surface (suboptimal or out of date) and
// must be recreated.
bool present(const vk::raii::Queue& queue, vk::SwapchainKHR chain, vk::Semaphore presentable,
             std::uint32_t image_index) {
  try {
    const vk::Result r = queue.presentKHR({.waitSemaphoreCount = 1,
                                           .pWaitSemaphores = &presentable,
                                           .swapchainCount = 1,
                                           .pSwapchains = &chain,
                                           .pImageIndices = &image_index});
    return r != vk::Result::eSuboptimalKHR;
  } catch (const vk::OutOfDateKHRError&) {
    return false;  // the wait still happens (Vulkan spec, vkQueuePresentKHR)
  }
}

}  // namespace

vk::Extent2D natural_window_extent(const SwapchainOptions& options) {
  const bool both = options.layout == WindowLayout::side_by_side;
  return {options.eye_extent.width * (both ? 2 : 1) + (both ? options.eye_gap_px : 0),
          options.eye_extent.height + options.banner_height_px};
}

Rgba8Image read_image(const Context& ctx, vk::Image image, vk::Extent2D extent) {
  Rgba8Image out;
  out.width = static_cast<int>(extent.width);
  out.height = static_cast<int>(extent.height);
  const vk::DeviceSize bytes = vk::DeviceSize{extent.width} * extent.height * 4;
  const Buffer buffer = Buffer::create(ctx, bytes, vk::BufferUsageFlagBits::eTransferDst);
  ctx.submit_and_wait([&](const vk::raii::CommandBuffer& cb) {
    writes_before_transfer(cb);
    const vk::BufferImageCopy region{.imageSubresource = kColorLayer,
                                     .imageExtent = {extent.width, extent.height, 1}};
    cb.copyImageToBuffer(image, vk::ImageLayout::eTransferSrcOptimal, *buffer.buffer, region);
    const vk::MemoryBarrier to_host{.srcAccessMask = vk::AccessFlagBits::eTransferWrite,
                                    .dstAccessMask = vk::AccessFlagBits::eHostRead};
    cb.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {},
                       to_host, {}, {});
  });
  out.pixels.resize(bytes);
  std::memcpy(out.pixels.data(), buffer.mapped, bytes);
  return out;
}

// --- SwapchainTarget --------------------------------------------------------

SwapchainTarget::SwapchainTarget(const Context& ctx, const SwapchainOptions& options)
    : ctx_(ctx), options_(options), layout_(options.layout), identity_(next_identity++) {}

std::variant<std::unique_ptr<SwapchainTarget>, RenderError> SwapchainTarget::create(
    const Context& ctx, vk::Extent2D framebuffer_px, const SwapchainOptions& options) {
  if (!*ctx.surface())
    return surface_failure("SwapchainTarget needs a Context made with a surface "
                           "(ContextEmbedding::create_surface)");
  if (options.eye_extent.width == 0 || options.eye_extent.height == 0)
    return surface_failure("the eye images must not be empty");
  std::unique_ptr<SwapchainTarget> t(new SwapchainTarget(ctx, options));
  try {
    const auto& dev = ctx.device();
    for (auto& eye : t->eyes_)
      eye = Image::create(ctx, options.eye_extent, kEyeFormat,
                          vk::ImageUsageFlagBits::eColorAttachment |
                              vk::ImageUsageFlagBits::eTransferSrc |
                              vk::ImageUsageFlagBits::eTransferDst,
                          vk::ImageAspectFlagBits::eColor);
    for (auto& f : t->frames_) {
      f.cb = std::move(vk::raii::CommandBuffers(dev, {.commandPool = *ctx.command_pool(),
                                                      .level = vk::CommandBufferLevel::ePrimary,
                                                      .commandBufferCount = 1})
                           .front());
      f.fence = vk::raii::Fence(dev, {.flags = vk::FenceCreateFlagBits::eSignaled});
      f.acquired = vk::raii::Semaphore(dev, vk::SemaphoreCreateInfo{});
    }
    if (auto e = t->recreate(framebuffer_px)) return *e;
  } catch (const vk::SystemError& e) {
    return surface_failure(std::string("creating the window's swapchain failed: ") + e.what());
  }
  return t;
}

SwapchainTarget::~SwapchainTarget() { wait_idle(); }

void SwapchainTarget::wait_idle() const noexcept {
  // The C entry point: it reports instead of throwing, as a destructor needs.
  (void)ctx_.device().getDispatcher()->vkDeviceWaitIdle(static_cast<VkDevice>(*ctx_.device()));
}

std::optional<RenderError> SwapchainTarget::recreate(vk::Extent2D framebuffer_px) {
  wait_idle();  // nothing may still use the old images and semaphores
  requested_ = framebuffer_px;
  const auto& pd = ctx_.physical();
  const auto surface = *ctx_.surface();
  const auto caps = pd.getSurfaceCapabilitiesKHR(surface);
  vk::Extent2D extent = caps.currentExtent;
  if (extent.width == 0xFFFFFFFFu) {  // the window takes the swapchain's size
    extent.width = std::clamp(framebuffer_px.width, caps.minImageExtent.width,
                              caps.maxImageExtent.width);
    extent.height = std::clamp(framebuffer_px.height, caps.minImageExtent.height,
                               caps.maxImageExtent.height);
  }
  if (extent.width == 0 || extent.height == 0) {
    out_of_date_ = true;  // minimised: try again on a later frame
    extent_ = extent;
    return std::nullopt;
  }
  if (!(caps.supportedUsageFlags & vk::ImageUsageFlagBits::eTransferDst))
    return surface_failure("the window's swapchain images cannot be written by transfers "
                           "(VK_IMAGE_USAGE_TRANSFER_DST_BIT unsupported)");
  const auto chosen = choose_format(pd.getSurfaceFormatsKHR(surface));
  if (!(pd.getFormatProperties(chosen.format).optimalTilingFeatures &
        vk::FormatFeatureFlagBits::eBlitDst))
    return surface_failure("the window's swapchain format " + vk::to_string(chosen.format) +
                           " cannot be a blit destination");
  if (!is_srgb(chosen.format) && format_ != chosen.format)
    std::fprintf(stderr, "curvlab: warning: the window offers no sRGB swapchain format; it shows %s, "
                         "darker than the stimulus PNGs\n", vk::to_string(chosen.format).c_str());
  format_ = chosen.format;
  mode_ = choose_mode(pd.getSurfacePresentModesKHR(surface), options_.vsync);
  std::uint32_t count = caps.minImageCount + 1;
  if (caps.maxImageCount > 0) count = std::min(count, caps.maxImageCount);
  const auto alpha = (caps.supportedCompositeAlpha & vk::CompositeAlphaFlagBitsKHR::eOpaque)
                         ? vk::CompositeAlphaFlagBitsKHR::eOpaque
                         : vk::CompositeAlphaFlagBitsKHR::eInherit;
  vk::raii::SwapchainKHR next(
      ctx_.device(),
      vk::SwapchainCreateInfoKHR{.surface = surface,
                                 .minImageCount = count,
                                 .imageFormat = chosen.format,
                                 .imageColorSpace = chosen.colorSpace,
                                 .imageExtent = extent,
                                 .imageArrayLayers = 1,
                                 .imageUsage = vk::ImageUsageFlagBits::eTransferDst,
                                 .imageSharingMode = vk::SharingMode::eExclusive,
                                 .preTransform = caps.currentTransform,
                                 .compositeAlpha = alpha,
                                 .presentMode = mode_,
                                 .clipped = VK_TRUE,
                                 .oldSwapchain = *swapchain_});
  swapchain_ = std::move(next);
  images_ = swapchain_.getImages();
  presentable_.clear();
  for (std::size_t i = 0; i < images_.size(); ++i)
    presentable_.emplace_back(ctx_.device(), vk::SemaphoreCreateInfo{});
  extent_ = extent;
  // Only transfers touch it; the colour-attachment usage is there because
  // Image::create makes a view, which needs a usage that views allow.
  window_ = Image::create(ctx_, extent, kEyeFormat,
                          vk::ImageUsageFlagBits::eTransferSrc | vk::ImageUsageFlagBits::eTransferDst |
                              vk::ImageUsageFlagBits::eColorAttachment,
                          vk::ImageAspectFlagBits::eColor);
  const vk::DeviceSize banner_bytes = vk::DeviceSize{extent.width} * options_.banner_height_px * 4;
  for (auto& f : frames_)
    f.banner = Buffer::create(ctx_, std::max<vk::DeviceSize>(banner_bytes, 16),
                              vk::BufferUsageFlagBits::eTransferSrc);
  render_banner();
  out_of_date_ = false;
  ++recreations_;
  return std::nullopt;
}

void SwapchainTarget::set_banner(const std::string& text) {
  if (text == banner_text_) return;
  banner_text_ = text;
  render_banner();
}

void SwapchainTarget::render_banner() {
  banner_rgba_.clear();
  const auto width = static_cast<int>(extent_.width);
  const auto height = static_cast<int>(options_.banner_height_px);
  if (banner_text_.empty() || width == 0 || height == 0) return;
  auto made = render_text(banner_text_, width, height, 0.7 * height, options_.font_path);
  // Without the font the window title still carries the text.
  if (std::holds_alternative<RenderError>(made)) return;
  const auto& bmp = std::get<CoverageBitmap>(made);
  banner_rgba_.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4);
  for (std::size_t i = 0; i < bmp.pixels.size(); ++i) {
    const unsigned a = bmp.pixels[i];
    for (std::size_t c = 0; c < 3; ++c)
      banner_rgba_[4 * i + c] =
          static_cast<std::uint8_t>((kBannerInk[c] * a + kBannerPaper[c] * (255 - a)) / 255);
    banner_rgba_[4 * i + 3] = 255;
  }
}

std::variant<bool, RenderError> SwapchainTarget::begin_frame(vk::Extent2D framebuffer_px) {
  if (failure_) return *failure_;
  try {
    FrameSync& f = frames_[frame_];
    // The slot's last composition waited on its acquire semaphore: once its
    // fence signals, the semaphore can be used again.
    (void)ctx_.device().waitForFences({*f.fence}, VK_TRUE, UINT64_MAX);
    for (int attempt = 0; attempt < 2; ++attempt) {
      if (out_of_date_ || framebuffer_px != requested_) {
        if (framebuffer_px.width == 0 || framebuffer_px.height == 0) return false;
        if (auto e = recreate(framebuffer_px)) return *e;
        if (out_of_date_) return false;
      }
      try {
        const auto [result, index] = swapchain_.acquireNextImage(UINT64_MAX, *f.acquired, nullptr);
        if (result == vk::Result::eSuccess || result == vk::Result::eSuboptimalKHR) {
          // Suboptimal still presents; recreate after this frame.
          out_of_date_ = result == vk::Result::eSuboptimalKHR;
          image_index_ = index;
          acquired_ = true;
          return true;
        }
        return false;  // timeout or not ready: skip this frame
      } catch (const vk::OutOfDateKHRError&) {
        out_of_date_ = true;
      }
    }
    return false;
  } catch (const vk::SystemError& e) {
    const VulkanFailure f(vk_call_name(e.what()), e.code().value());
    failure_ = surface_failure(std::string(f.what()) + " (presenting to the window)");
    throw f;
  }
}

EyeImage SwapchainTarget::eye_image(Eye eye) {
  const Image& img = eyes_[static_cast<std::size_t>(eye)];
  return {*img.image, *img.view, img.extent, img.format, vk::ImageLayout::eTransferSrcOptimal};
}

void SwapchainTarget::record_after(const vk::raii::CommandBuffer& cb, Eye eye) {
  // Composition happens in frame_finished(), in a submission that waits on
  // the acquire semaphore; the renderer's own submission waits on nothing.
  (void)cb;
  (void)eye;
}

void SwapchainTarget::frame_finished() {
  if (!acquired_) return;
  acquired_ = false;
  try {
    FrameSync& f = frames_[frame_];
    frame_ = (frame_ + 1) % frames_.size();
    ctx_.device().resetFences({*f.fence});
    const vk::Image target_image = images_[image_index_];
    const std::uint32_t banner_h = std::min(options_.banner_height_px, extent_.height);
    const bool banner = !banner_rgba_.empty();
    if (banner) f.banner.write(banner_rgba_.data(), banner_rgba_.size());

    const vk::raii::CommandBuffer& cb = f.cb;
    cb.reset();
    cb.begin({.flags = vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
    writes_before_transfer(cb);
    transition(cb, *window_.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eUndefined,
               vk::ImageLayout::eTransferDstOptimal);
    cb.clearColorImage(*window_.image, vk::ImageLayout::eTransferDstOptimal, letterbox_colour(),
                       kColorRange);
    const std::uint32_t area_h = extent_.height - banner_h;
    if (area_h > 0) show_eyes(cb, layout_, eyes_, *window_.image, {extent_.width, area_h}, options_.eye_gap_px);
    if (banner && banner_h == options_.banner_height_px) copy_banner(cb, f.banner, *window_.image, extent_, banner_h);
    copy_to_swapchain_image(cb, *window_.image, target_image, extent_);
    cb.end();

    const vk::Semaphore presentable = *presentable_[image_index_];
    submit_composition(ctx_.queue(), cb, *f.acquired, presentable, *f.fence);
    drawn_ = true;
    if (!present(ctx_.queue(), *swapchain_, presentable, image_index_)) out_of_date_ = true;
    ++presented_;
  } catch (const vk::SystemError& e) {
    const VulkanFailure f(vk_call_name(e.what()), e.code().value());
    failure_ = surface_failure(std::string(f.what()) + " (presenting to the window)");
    throw f;
  }
}

std::optional<Rgba8Image> SwapchainTarget::read_eye(Eye eye) const {
  if (!drawn_) return std::nullopt;
  const Image& img = eyes_[static_cast<std::size_t>(eye)];
  return read_image(ctx_, *img.image, img.extent);
}

std::optional<Rgba8Image> SwapchainTarget::read_window() const {
  if (!drawn_ || !*window_.image) return std::nullopt;
  return read_image(ctx_, *window_.image, window_.extent);
}

// --- ExternalImagesTarget ---------------------------------------------------

ExternalImagesTarget::ExternalImagesTarget(const Context& ctx)
    : ctx_(ctx), identity_(next_identity++) {}

ExternalImagesTarget::~ExternalImagesTarget() {
  (void)ctx_.device().getDispatcher()->vkDeviceWaitIdle(static_cast<VkDevice>(*ctx_.device()));
}

void ExternalImagesTarget::set_image(Eye eye, const ExternalImage& image) {
  const auto e = static_cast<std::size_t>(eye);
  external_[e] = image;
  if (!*own_[e].image || own_[e].extent != image.extent) {
    // A new size (rare: the runtime's recommendation changed): the old image
    // may still be read by a frame in flight.
    (void)ctx_.device().getDispatcher()->vkDeviceWaitIdle(static_cast<VkDevice>(*ctx_.device()));
    own_[e] = Image::create(ctx_, image.extent, kEyeFormat,
                            vk::ImageUsageFlagBits::eColorAttachment |
                                vk::ImageUsageFlagBits::eTransferSrc |
                                vk::ImageUsageFlagBits::eTransferDst,
                            vk::ImageAspectFlagBits::eColor);
    drawn_[e] = false;
  }
}

EyeImage ExternalImagesTarget::eye_image(Eye eye) {
  const auto e = static_cast<std::size_t>(eye);
  if (!external_[e]) {
    // A broken contract: the embedder must hand in both images every frame.
    std::fprintf(stderr, "curvlab renderer: ExternalImagesTarget drawn without an image\n");
    std::abort();
  }
  const Image& img = own_[e];
  return {*img.image, *img.view, img.extent, img.format, vk::ImageLayout::eTransferSrcOptimal};
}

void ExternalImagesTarget::record_after(const vk::raii::CommandBuffer& cb, Eye eye) {
  const auto e = static_cast<std::size_t>(eye);
  const ExternalImage& dst = *external_[e];
  const Image& src = own_[e];
  writes_before_transfer(cb);
  transition(cb, dst.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eUndefined,
             vk::ImageLayout::eTransferDstOptimal);
  if (dst.format == kEyeFormat) {
    const vk::ImageCopy region{.srcSubresource = kColorLayer,
                               .dstSubresource = kColorLayer,
                               .extent = {src.extent.width, src.extent.height, 1}};
    cb.copyImage(*src.image, vk::ImageLayout::eTransferSrcOptimal, dst.image,
                 vk::ImageLayout::eTransferDstOptimal, region);
  } else {
    cb.blitImage(*src.image, vk::ImageLayout::eTransferSrcOptimal, dst.image,
                 vk::ImageLayout::eTransferDstOptimal, whole(src.extent, dst.extent),
                 vk::Filter::eNearest);
  }
  transition(cb, dst.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eTransferDstOptimal,
             dst.final_layout);
  drawn_[e] = true;
}

void ExternalImagesTarget::frame_finished() { external_ = {}; }

std::optional<Rgba8Image> ExternalImagesTarget::read_eye(Eye eye) const {
  const auto e = static_cast<std::size_t>(eye);
  if (!drawn_[e]) return std::nullopt;
  return read_image(ctx_, *own_[e].image, own_[e].extent);
}

}  // namespace curvlab::renderer
