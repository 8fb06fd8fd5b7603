#include "curvlab/renderer/gpu.hpp"

#include <cstring>

namespace curvlab::renderer {

Buffer Buffer::create(const Context& ctx, vk::DeviceSize size, vk::BufferUsageFlags usage) {
  Buffer b;
  b.size = size;
  b.buffer = vk::raii::Buffer(ctx.device(), {.size = size, .usage = usage,
                                             .sharingMode = vk::SharingMode::eExclusive});
  const auto req = b.buffer.getMemoryRequirements();
  b.memory = vk::raii::DeviceMemory(
      ctx.device(),
      {.allocationSize = req.size,
       .memoryTypeIndex = ctx.memory_type(req.memoryTypeBits,
                                          vk::MemoryPropertyFlagBits::eHostVisible |
                                              vk::MemoryPropertyFlagBits::eHostCoherent)});
  b.buffer.bindMemory(*b.memory, 0);
  b.mapped = b.memory.mapMemory(0, VK_WHOLE_SIZE);
  return b;
}

void Buffer::write(const void* data, std::size_t bytes, std::size_t offset) const {
  std::memcpy(static_cast<char*>(mapped) + offset, data, bytes);
}

Image Image::create(const Context& ctx, vk::Extent2D extent, vk::Format format,
                    vk::ImageUsageFlags usage, vk::ImageAspectFlags aspect,
                    vk::SampleCountFlagBits samples) {
  Image img;
  img.format = format;
  img.samples = samples;
  img.extent = extent;
  img.image = vk::raii::Image(ctx.device(), {.imageType = vk::ImageType::e2D,
                                             .format = format,
                                             .extent = {extent.width, extent.height, 1},
                                             .mipLevels = 1,
                                             .arrayLayers = 1,
                                             .samples = samples,
                                             .tiling = vk::ImageTiling::eOptimal,
                                             .usage = usage,
                                             .sharingMode = vk::SharingMode::eExclusive,
                                             .initialLayout = vk::ImageLayout::eUndefined});
  const auto req = img.image.getMemoryRequirements();
  img.memory = vk::raii::DeviceMemory(
      ctx.device(),
      {.allocationSize = req.size,
       .memoryTypeIndex =
           ctx.memory_type(req.memoryTypeBits, vk::MemoryPropertyFlagBits::eDeviceLocal)});
  img.image.bindMemory(*img.memory, 0);
  img.view = vk::raii::ImageView(
      ctx.device(), {.image = *img.image,
                     .viewType = vk::ImageViewType::e2D,
                     .format = format,
                     .subresourceRange = {aspect, 0, 1, 0, 1}});
  return img;
}

void transition(const vk::raii::CommandBuffer& cb, vk::Image image, vk::ImageAspectFlags aspect,
                vk::ImageLayout from, vk::ImageLayout to) {
  const vk::ImageMemoryBarrier barrier{
      .srcAccessMask = vk::AccessFlagBits::eMemoryWrite,
      .dstAccessMask = vk::AccessFlagBits::eMemoryRead | vk::AccessFlagBits::eMemoryWrite,
      .oldLayout = from,
      .newLayout = to,
      .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
      .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
      .image = image,
      .subresourceRange = {aspect, 0, 1, 0, 1}};
  cb.pipelineBarrier(vk::PipelineStageFlagBits::eAllCommands,
                     vk::PipelineStageFlagBits::eAllCommands, {}, {}, {}, barrier);
}

}  // namespace curvlab::renderer
