// Small owners for device memory: a buffer or an image with its memory, each
// move-only (vk::raii members). Destroying one frees the Vulkan objects at
// once, so callers keep them alive until the GPU no longer uses them (the
// renderer retires them through its frame slots).
#pragma once

#include "curvlab/renderer/context.hpp"

namespace curvlab::renderer {

// A buffer in host-visible, coherent memory, persistently mapped. On
// lavapipe all memory is host memory; on a GPU static meshes would do better
// in device-local memory (a later optimisation, measured by bench/).
struct Buffer {
  vk::raii::Buffer buffer{nullptr};
  vk::raii::DeviceMemory memory{nullptr};
  void* mapped = nullptr;
  vk::DeviceSize size = 0;

  static Buffer create(const Context& ctx, vk::DeviceSize size, vk::BufferUsageFlags usage);
  void write(const void* data, std::size_t bytes, std::size_t offset = 0) const;
};

// A 2D image with one mip level, its memory and a view; `samples` > 1 for
// a multisampled attachment.
struct Image {
  vk::raii::Image image{nullptr};
  vk::raii::DeviceMemory memory{nullptr};
  vk::raii::ImageView view{nullptr};
  vk::Format format = vk::Format::eUndefined;
  vk::Extent2D extent{};
  vk::SampleCountFlagBits samples = vk::SampleCountFlagBits::e1;

  static Image create(const Context& ctx, vk::Extent2D extent, vk::Format format,
                      vk::ImageUsageFlags usage, vk::ImageAspectFlags aspect,
                      vk::SampleCountFlagBits samples = vk::SampleCountFlagBits::e1);
};

// Records a whole-image layout transition with conservative stage masks.
void transition(const vk::raii::CommandBuffer& cb, vk::Image image, vk::ImageAspectFlags aspect,
                vk::ImageLayout from, vk::ImageLayout to);

}  // namespace curvlab::renderer
