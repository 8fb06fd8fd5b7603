#include "curvlab/renderer/offscreen.hpp"

#include <atomic>
#include <cstring>

namespace curvlab::renderer {
namespace {
std::atomic<std::uint64_t> next_identity{1};
}

OffscreenTarget::OffscreenTarget(const Context& ctx, std::uint32_t width_px,
                                 std::uint32_t height_px)
    : identity_(next_identity++) {
  const vk::DeviceSize bytes = static_cast<vk::DeviceSize>(width_px) * height_px * 4;
  for (int e = 0; e < 2; ++e) {
    images_[e] = Image::create(ctx, {width_px, height_px}, vk::Format::eR8G8B8A8Srgb,
                               vk::ImageUsageFlagBits::eColorAttachment |
                                   vk::ImageUsageFlagBits::eTransferSrc |
                                   vk::ImageUsageFlagBits::eTransferDst,
                               vk::ImageAspectFlagBits::eColor);
    readback_[e] = Buffer::create(ctx, bytes, vk::BufferUsageFlagBits::eTransferDst);
    cpu_[e].width = static_cast<int>(width_px);
    cpu_[e].height = static_cast<int>(height_px);
    cpu_[e].pixels.assign(bytes, 0);
  }
}

EyeImage OffscreenTarget::eye_image(Eye eye) {
  const auto& img = images_[static_cast<int>(eye)];
  return {*img.image, *img.view, img.extent, img.format, vk::ImageLayout::eTransferSrcOptimal};
}

void OffscreenTarget::record_after(const vk::raii::CommandBuffer& cb, Eye eye) {
  const int e = static_cast<int>(eye);
  const vk::BufferImageCopy region{
      .bufferOffset = 0,
      .bufferRowLength = 0,
      .bufferImageHeight = 0,
      .imageSubresource = {vk::ImageAspectFlagBits::eColor, 0, 0, 1},
      .imageOffset = {0, 0, 0},
      .imageExtent = {images_[e].extent.width, images_[e].extent.height, 1}};
  cb.copyImageToBuffer(*images_[e].image, vk::ImageLayout::eTransferSrcOptimal,
                       *readback_[e].buffer, region);
  // Make the copy visible to the host once the frame's fence signals.
  const vk::MemoryBarrier to_host{.srcAccessMask = vk::AccessFlagBits::eTransferWrite,
                                  .dstAccessMask = vk::AccessFlagBits::eHostRead};
  cb.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost, {},
                     to_host, {}, {});
  copied_[e] = true;
}

void OffscreenTarget::frame_finished() {
  for (int e = 0; e < 2; ++e) {
    if (!copied_[e]) continue;
    std::memcpy(cpu_[e].pixels.data(), readback_[e].mapped, cpu_[e].pixels.size());
    copied_[e] = false;
  }
}

}  // namespace curvlab::renderer
