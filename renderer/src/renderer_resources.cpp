#include "renderer_impl.hpp"

#include <algorithm>

namespace curvlab::renderer {

Renderer::Impl::Impl(const Context& c, RendererOptions o)
    : ctx(c), options(o), msaa(o.msaa ? supported_msaa(c, *o.msaa) : automatic_msaa(c)) {
  const auto& dev = ctx.device();
  const vk::DescriptorSetLayoutBinding view_binding{
      .binding = 0,
      .descriptorType = vk::DescriptorType::eUniformBufferDynamic,
      .descriptorCount = 1,
      .stageFlags = vk::ShaderStageFlagBits::eVertex};
  view_layout = vk::raii::DescriptorSetLayout(dev, {.bindingCount = 1, .pBindings = &view_binding});
  const vk::DescriptorSetLayoutBinding tex_binding{
      .binding = 0,
      .descriptorType = vk::DescriptorType::eCombinedImageSampler,
      .descriptorCount = 1,
      .stageFlags = vk::ShaderStageFlagBits::eFragment};
  texture_layout = vk::raii::DescriptorSetLayout(dev, {.bindingCount = 1, .pBindings = &tex_binding});
  const vk::PushConstantRange push{.stageFlags = vk::ShaderStageFlagBits::eVertex,
                                   .offset = 0,
                                   .size = sizeof(DrawBlock)};
  const vk::DescriptorSetLayout set_layouts[] = {*view_layout, *texture_layout};
  pipeline_layout = vk::raii::PipelineLayout(dev, {.setLayoutCount = 2,
                                                   .pSetLayouts = set_layouts,
                                                   .pushConstantRangeCount = 1,
                                                   .pPushConstantRanges = &push});
  const vk::DescriptorPoolSize sizes[] = {
      {vk::DescriptorType::eUniformBufferDynamic, 16},
      {vk::DescriptorType::eCombinedImageSampler, 64}};
  pool = vk::raii::DescriptorPool(
      dev, {.flags = vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet,
            .maxSets = 80,
            .poolSizeCount = 2,
            .pPoolSizes = sizes});
  sampler = vk::raii::Sampler(dev, {.magFilter = vk::Filter::eLinear,
                                    .minFilter = vk::Filter::eLinear,
                                    .mipmapMode = vk::SamplerMipmapMode::eNearest,
                                    .addressModeU = vk::SamplerAddressMode::eClampToEdge,
                                    .addressModeV = vk::SamplerAddressMode::eClampToEdge,
                                    .addressModeW = vk::SamplerAddressMode::eClampToEdge,
                                    .maxLod = 0.0f});
  const auto vs = compile_or_abort("scene.vert", ShaderStage::vertex);
  const auto fs = compile_or_abort("scene.frag", ShaderStage::fragment);
  vert = vk::raii::ShaderModule(dev, {.codeSize = vs.size() * 4, .pCode = vs.data()});
  frag = vk::raii::ShaderModule(dev, {.codeSize = fs.size() * 4, .pCode = fs.data()});
  const auto tvs = compile_or_abort("tube.vert", ShaderStage::vertex);
  const auto tfs = compile_or_abort("tube.frag", ShaderStage::fragment);
  tube_vert = vk::raii::ShaderModule(dev, {.codeSize = tvs.size() * 4, .pCode = tvs.data()});
  tube_frag = vk::raii::ShaderModule(dev, {.codeSize = tfs.size() * 4, .pCode = tfs.data()});

  const auto families = ctx.physical().getQueueFamilyProperties();
  timestamps = families[ctx.queue_family()].timestampValidBits > 0;
  for (std::size_t i = 0; i < std::max<std::size_t>(1, options.frames_in_flight); ++i) {
    FrameSlot s;
    s.cb = std::move(vk::raii::CommandBuffers(dev, {.commandPool = *ctx.command_pool(),
                                                    .level = vk::CommandBufferLevel::ePrimary,
                                                    .commandBufferCount = 1})
                         .front());
    s.fence = vk::raii::Fence(dev, vk::FenceCreateInfo{});
    s.ubo = Buffer::create(ctx, 2 * kViewStride, vk::BufferUsageFlagBits::eUniformBuffer);
    const vk::DescriptorSetLayout l = *view_layout;
    s.view_set = std::move(vk::raii::DescriptorSets(
                               dev, {.descriptorPool = *pool, .descriptorSetCount = 1, .pSetLayouts = &l})
                               .front());
    const vk::DescriptorBufferInfo info{.buffer = *s.ubo.buffer, .offset = 0, .range = sizeof(ViewBlock)};
    dev.updateDescriptorSets(vk::WriteDescriptorSet{.dstSet = *s.view_set,
                                                    .dstBinding = 0,
                                                    .descriptorCount = 1,
                                                    .descriptorType = vk::DescriptorType::eUniformBufferDynamic,
                                                    .pBufferInfo = &info},
                             {});
    if (timestamps)
      s.queries = vk::raii::QueryPool(dev, {.queryType = vk::QueryType::eTimestamp, .queryCount = 2});
    slots.push_back(std::move(s));
  }
  blank = upload_texture(CoverageBitmap{1, 1, {0}});
}

Renderer::Impl::~Impl() {
  for (auto& s : slots)
    if (s.pending) {
      const VkFence fence = *s.fence;
      (void)ctx.device().getDispatcher()->vkWaitForFences(static_cast<VkDevice>(*ctx.device()), 1,
                                                          &fence, VK_TRUE, UINT64_MAX);
      s.pending = false;
    }
}

void Renderer::Impl::wait_all() {
  for (auto& s : slots)
    if (s.pending) {
      ctx.wait_for(*s.fence);
      s.pending = false;
    }
}

const vk::raii::Pipeline& Renderer::Impl::pipeline(const PipelineKey& key) {
  if (auto it = pipelines.find(key); it != pipelines.end()) return it->second;
  const PipelineShaders shaders{*vert, *frag, *tube_vert, *tube_frag};
  return pipelines.emplace(key, make_pipeline(ctx.device(), key, shaders, *pipeline_layout, msaa)).first->second;
}

GpuMesh& Renderer::Impl::mesh(const Scene& scene, std::size_t object, int level, Garbage& garbage) {
  const std::uint64_t rev = scene.mesh_revision(object);
  const auto key = std::make_pair(object, level);
  if (auto it = meshes.find(key); it != meshes.end()) {
    if (it->second.mesh_revision == rev) return it->second;
    garbage.meshes.push_back(std::move(it->second));
    meshes.erase(it);
  }
  const MeshData data = scene.objects()[object].build(level);
  GpuMesh m;
  const bool tube = data.shading == Shading::tube;
  const std::size_t vbytes =
      tube ? data.tube_vertices.size() * sizeof(TubeVertex) : data.vertices.size() * sizeof(Vertex);
  const std::size_t ibytes = data.indices.size() * sizeof(std::uint32_t);
  m.vertices = Buffer::create(ctx, std::max<std::size_t>(vbytes, 16), vk::BufferUsageFlagBits::eVertexBuffer);
  m.indices = Buffer::create(ctx, std::max<std::size_t>(ibytes, 16), vk::BufferUsageFlagBits::eIndexBuffer);
  m.vertices.write(tube ? static_cast<const void*>(data.tube_vertices.data()) : data.vertices.data(), vbytes);
  m.indices.write(data.indices.data(), ibytes);
  m.index_count = static_cast<std::uint32_t>(data.indices.size());
  m.primitives = data.primitive_count();
  m.topology = data.topology;
  m.shading = data.shading;
  m.mesh_revision = rev;
  return meshes.emplace(key, std::move(m)).first->second;
}

Texture Renderer::Impl::upload_texture(const CoverageBitmap& bmp) {
  Texture t;
  const vk::Extent2D extent{static_cast<std::uint32_t>(bmp.width), static_cast<std::uint32_t>(bmp.height)};
  t.image = Image::create(ctx, extent, vk::Format::eR8Unorm,
                          vk::ImageUsageFlagBits::eSampled | vk::ImageUsageFlagBits::eTransferDst,
                          vk::ImageAspectFlagBits::eColor);
  // Uploaded once, synchronously, when the panel is first drawn.
  const Buffer staging = Buffer::create(ctx, bmp.pixels.size(), vk::BufferUsageFlagBits::eTransferSrc);
  staging.write(bmp.pixels.data(), bmp.pixels.size());
  ctx.submit_and_wait([&](const vk::raii::CommandBuffer& cb) {
    transition(cb, *t.image.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eUndefined,
               vk::ImageLayout::eTransferDstOptimal);
    const vk::BufferImageCopy region{.imageSubresource = {vk::ImageAspectFlagBits::eColor, 0, 0, 1},
                                     .imageExtent = {extent.width, extent.height, 1}};
    cb.copyBufferToImage(*staging.buffer, *t.image.image, vk::ImageLayout::eTransferDstOptimal, region);
    transition(cb, *t.image.image, vk::ImageAspectFlagBits::eColor,
               vk::ImageLayout::eTransferDstOptimal, vk::ImageLayout::eShaderReadOnlyOptimal);
  });
  const vk::DescriptorSetLayout l = *texture_layout;
  t.set = std::move(vk::raii::DescriptorSets(ctx.device(), {.descriptorPool = *pool,
                                                           .descriptorSetCount = 1,
                                                           .pSetLayouts = &l})
                        .front());
  const vk::DescriptorImageInfo info{.sampler = *sampler, .imageView = *t.image.view,
                                     .imageLayout = vk::ImageLayout::eShaderReadOnlyOptimal};
  ctx.device().updateDescriptorSets(
      vk::WriteDescriptorSet{.dstSet = *t.set, .dstBinding = 0, .descriptorCount = 1,
                             .descriptorType = vk::DescriptorType::eCombinedImageSampler,
                             .pImageInfo = &info},
      {});
  return t;
}

const Texture& Renderer::Impl::texture(const Scene& scene, std::size_t object, Garbage& garbage) {
  const std::uint64_t rev = scene.mesh_revision(object);
  if (auto it = textures.find(object); it != textures.end()) {
    if (it->second.mesh_revision == rev) return it->second;
    garbage.textures.push_back(std::move(it->second));
    textures.erase(it);
  }
  Texture t = upload_texture(*scene.objects()[object].text);
  t.mesh_revision = rev;
  return textures.emplace(object, std::move(t)).first->second;
}

const EyeAttachments& Renderer::Impl::eye_attachments(int eye, vk::Extent2D extent, Garbage& garbage) {
  EyeAttachments& a = attachments[eye];
  if (*a.depth.image && a.depth.extent == extent) return a;
  if (*a.depth.image) garbage.images.push_back(std::move(a.depth));
  if (*a.color.image) garbage.images.push_back(std::move(a.color));
  a.depth = Image::create(ctx, extent, kDepthFormat, vk::ImageUsageFlagBits::eDepthStencilAttachment,
                          vk::ImageAspectFlagBits::eDepth, sample_bits(msaa));
  if (msaa > 1)
    a.color = Image::create(ctx, extent, kColorFormat,
                            vk::ImageUsageFlagBits::eColorAttachment |
                                vk::ImageUsageFlagBits::eTransientAttachment,
                            vk::ImageAspectFlagBits::eColor, sample_bits(msaa));
  return a;
}

}  // namespace curvlab::renderer
