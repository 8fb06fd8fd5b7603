#include "mirror.hpp"


#include <cmath>
#include <cstring>
#include <utility>

namespace curvlab::harness::xr {

namespace {

// The bytes shown for each byte read: sRGB-encoded (IEC 61966-2-1) for a
// linear image, as they are otherwise.
std::array<std::uint8_t, 256> encoding(bool linear) {
  std::array<std::uint8_t, 256> lut{};
  for (int v = 0; v < 256; ++v) {
    const double l = v / 255.0;
    const double e = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
    lut[static_cast<std::size_t>(v)] = static_cast<std::uint8_t>(linear ? std::lround(e * 255.0) : v);
  }
  return lut;
}

}  // namespace

OperatorMirror::OperatorMirror(const renderer::Context& ctx, vk::Extent2D eye, bool bgra, bool linear)
    : ctx_(ctx),
      eye_(eye),
      bgra_(bgra),
      encode_(encoding(linear)),
      pool_(ctx.device(), {.flags = vk::CommandPoolCreateFlagBits::eResetCommandBuffer,
                           .queueFamilyIndex = ctx.queue_family()}),
      fence_(ctx.device(), vk::FenceCreateInfo{}),
      staging_(renderer::Buffer::create(ctx, vk::DeviceSize{2} * eye.width * eye.height * 4,
                                        vk::BufferUsageFlagBits::eTransferDst)) {
  vk::raii::CommandBuffers cbs(ctx.device(), {.commandPool = *pool_,
                                              .level = vk::CommandBufferLevel::ePrimary,
                                              .commandBufferCount = 1});
  cb_ = std::move(cbs.front());
}

OperatorMirror::~OperatorMirror() {
  if (state_.load(std::memory_order_acquire) == kCopying)
    (void)ctx_.device().waitForFences(*fence_, VK_TRUE, 1'000'000'000);
}

void OperatorMirror::request() {
  int idle = kIdle;
  state_.compare_exchange_strong(idle, kRequested, std::memory_order_acq_rel);
}

bool OperatorMirror::take(harness::io::MirrorImage& out) {
  if (state_.load(std::memory_order_acquire) != kCopying) return false;
  if (ctx_.device().waitForFences(*fence_, VK_TRUE, 0) != vk::Result::eSuccess) return false;
  out.width = eye_.width * 2;
  out.height = eye_.height;
  out.rgba.resize(std::size_t{out.width} * out.height * 4);
  const auto* src = static_cast<const std::uint8_t*>(staging_.mapped);
  const std::size_t row = std::size_t{eye_.width} * 4;
  for (std::uint32_t y = 0; y < eye_.height; ++y)
    for (std::size_t e = 0; e < 2; ++e)
      std::memcpy(out.rgba.data() + (std::size_t{y} * out.width * 4) + e * row,
                  src + e * row * eye_.height + y * row, row);
  if (bgra_)
    for (std::size_t i = 0; i < out.rgba.size(); i += 4) std::swap(out.rgba[i], out.rgba[i + 2]);
  for (std::size_t i = 0; i < out.rgba.size(); ++i)
    if (i % 4 != 3) out.rgba[i] = encode_[out.rgba[i]];
  state_.store(kIdle, std::memory_order_release);
  return true;
}

void OperatorMirror::copy(const std::array<vk::Image, 2>& images) {
  if (state_.load(std::memory_order_acquire) != kRequested) return;
  ctx_.device().resetFences(*fence_);
  cb_.reset();
  cb_.begin({.flags = vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
  for (std::size_t e = 0; e < 2; ++e) {
    constexpr auto color = vk::ImageAspectFlagBits::eColor;
    renderer::transition(cb_, images[e], color, vk::ImageLayout::eColorAttachmentOptimal,
                         vk::ImageLayout::eTransferSrcOptimal);
    const vk::BufferImageCopy region{.bufferOffset = vk::DeviceSize{e} * eye_.width * eye_.height * 4,
                                     .imageSubresource = {color, 0, 0, 1},
                                     .imageExtent = {eye_.width, eye_.height, 1}};
    cb_.copyImageToBuffer(images[e], vk::ImageLayout::eTransferSrcOptimal, *staging_.buffer, region);
    renderer::transition(cb_, images[e], color, vk::ImageLayout::eTransferSrcOptimal,
                         vk::ImageLayout::eColorAttachmentOptimal);
  }
  cb_.end();
  ctx_.submit(*cb_, *fence_);
  state_.store(kCopying, std::memory_order_release);
}

}  // namespace curvlab::harness::xr
