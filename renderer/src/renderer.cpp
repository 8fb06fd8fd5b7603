#include "curvlab/renderer/renderer.hpp"

#include "curvlab/renderer/shader.hpp"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <iostream>

namespace curvlab::renderer {
namespace {

constexpr vk::Format kDepthFormat = vk::Format::eD32Sfloat;
// The eye images every target hands the renderer: shaded in linear light,
// stored sRGB-encoded by the hardware (colour.hpp).
constexpr vk::Format kColorFormat = vk::Format::eR8G8B8A8Srgb;
constexpr vk::DeviceSize kViewStride = 256;  // ≥ minUniformBufferOffsetAlignment everywhere

// std140 layout of the View block in scene.vert.
struct ViewBlock {
  glm::mat4 proj_front;
  glm::mat4 proj_back;
  glm::mat4 eye_from_nose;
  glm::vec4 params;
};
static_assert(sizeof(ViewBlock) <= kViewStride);

struct DrawBlock {
  glm::mat4 model_view;
  glm::vec4 tint;
};

struct SpecData {
  std::int32_t native_view;
  std::int32_t curvature;
  std::int32_t back;
  std::int32_t shading;
  glm::vec3 ink;    // text panels' glyphs, linear RGB
  glm::vec3 paper;  // text panels' ground, linear RGB
  // Tubes (tube.frag): the stick's colours, linear RGB, and its rings.
  std::array<glm::vec3, 4> wood;  // butt, shaft, tip, ring
  std::array<float, 5> ring_fractions;
  float ring_half_m;
};

struct GpuMesh {
  Buffer vertices;
  Buffer indices;
  std::uint32_t index_count = 0;
  std::uint64_t primitives = 0;
  Topology topology = Topology::triangles;
  Shading shading = Shading::lit;
  std::uint64_t mesh_revision = 0;
};

struct Texture {
  Image image;
  vk::raii::DescriptorSet set{nullptr};
  std::uint64_t mesh_revision = 0;
};

// Objects the GPU may still be reading; destroyed when their slot is reused.
struct Garbage {
  std::vector<GpuMesh> meshes;
  std::vector<Texture> textures;
  std::vector<Image> images;
  void clear() {
    meshes.clear();
    textures.clear();
    images.clear();
  }
};

struct FrameSlot {
  vk::raii::CommandBuffer cb{nullptr};
  vk::raii::Fence fence{nullptr};
  Buffer ubo;
  vk::raii::DescriptorSet view_set{nullptr};
  vk::raii::QueryPool queries{nullptr};
  bool pending = false;  // submitted and not yet waited for
  Garbage garbage;
};

std::vector<std::uint32_t> compile_or_abort(std::string_view name, ShaderStage stage) {
  auto result = compile_shader(name, stage);
  if (auto* e = std::get_if<RenderError>(&result)) {
    // The shaders are part of the program: failing to compile them is a bug.
    std::cerr << "curvlab renderer: " << e->message << '\n';
    std::abort();
  }
  return std::get<std::vector<std::uint32_t>>(std::move(result));
}

glm::mat4 to_float(const glm::dmat4& m) { return glm::mat4(m); }

vk::SampleCountFlagBits sample_bits(std::uint32_t samples) {
  return static_cast<vk::SampleCountFlagBits>(samples);
}

// What one eye is drawn into: the target's image itself (one sample), or a
// multisampled colour image resolved into it at the end of the pass.
struct EyeAttachments {
  Image color;  // multisampled; empty when drawing with one sample
  Image depth;
};

// What the steps of recording one frame share.
struct FrameRecording {
  const Scene& scene;
  const FrameDescription& frame;
  RenderTarget& target;
  FrameSlot& slot;
  std::array<float, 4> background;
  int k;  // the space's curvature sign, a pipeline specialisation
  FrameStats& stats;
};

// The GPU meshes and text textures of one eye's draws, in the plan's order.
struct EyeDraws {
  std::vector<GpuMesh*> meshes;
  std::vector<const Texture*> textures;  // null: no text
};

// The shaders' native_view constant (shaders/curved.glsl, curv_clip).
std::int32_t native_view(Projection proj) {
  switch (proj) {
    case Projection::tourist: return 0;
    case Projection::native: return 1;
  }
  std::abort();  // not a Projection: a broken contract
}

// The specialisation constants of a pipeline's shaders.
SpecData spec_data(Projection proj, int k, Hemisphere hemi, Shading shading) {
  SpecData spec{native_view(proj), k, hemi == Hemisphere::back ? 1 : 0,
                static_cast<std::int32_t>(shading), glm::vec3(palette::text_ink),
                glm::vec3(palette::text_paper),
                {glm::vec3(palette::stick_butt), glm::vec3(palette::stick_shaft),
                 glm::vec3(palette::stick_tip), glm::vec3(palette::stick_ring)},
                {}, static_cast<float>(kStickRingHalfWidthM)};
  for (std::size_t i = 0; i < spec.ring_fractions.size(); ++i)
    spec.ring_fractions[i] = static_cast<float>(kStickRingFractions[i]);
  return spec;
}

// Where each constant_id of the shaders lies in SpecData.
std::vector<vk::SpecializationMapEntry> spec_entries() {
  std::vector<vk::SpecializationMapEntry> entries{{0, offsetof(SpecData, native_view), 4},
                                                  {1, offsetof(SpecData, curvature), 4},
                                                  {2, offsetof(SpecData, back), 4},
                                                  {3, offsetof(SpecData, shading), 4}};
  for (std::uint32_t c = 0; c < 3; ++c) {
    entries.push_back({4 + c, static_cast<std::uint32_t>(offsetof(SpecData, ink) + 4 * c), 4});
    entries.push_back({7 + c, static_cast<std::uint32_t>(offsetof(SpecData, paper) + 4 * c), 4});
  }
  for (std::uint32_t w = 0; w < 4; ++w)
    for (std::uint32_t c = 0; c < 3; ++c)
      entries.push_back({10 + 3 * w + c,
                         static_cast<std::uint32_t>(offsetof(SpecData, wood) + sizeof(glm::vec3) * w + 4 * c), 4});
  for (std::uint32_t i = 0; i < 5; ++i)
    entries.push_back({22 + i, static_cast<std::uint32_t>(offsetof(SpecData, ring_fractions) + 4 * i), 4});
  entries.push_back({27, offsetof(SpecData, ring_half_m), 4});
  return entries;
}

// The vertex layouts of scene meshes (scene.vert) and tubes (tube.vert).
const vk::VertexInputAttributeDescription kVertexAttributes[] = {
    {0, 0, vk::Format::eR32G32B32A32Sfloat, offsetof(Vertex, position)},
    {1, 0, vk::Format::eR32G32B32A32Sfloat, offsetof(Vertex, normal)},
    {2, 0, vk::Format::eR32G32B32A32Sfloat, offsetof(Vertex, color)}};
const vk::VertexInputAttributeDescription kTubeVertexAttributes[] = {
    {0, 0, vk::Format::eR32G32B32A32Sfloat, offsetof(TubeVertex, axis)},
    {1, 0, vk::Format::eR32G32B32A32Sfloat, offsetof(TubeVertex, tangent)},
    {2, 0, vk::Format::eR32G32B32A32Sfloat, offsetof(TubeVertex, up)},
    {3, 0, vk::Format::eR32G32B32A32Sfloat, offsetof(TubeVertex, side)},
    {4, 0, vk::Format::eR32G32B32A32Sfloat, offsetof(TubeVertex, design)},
    {5, 0, vk::Format::eR32G32B32A32Sfloat, offsetof(TubeVertex, place)}};

// No face culling: the S3 twin and the native map may flip orientation.
const vk::PipelineRasterizationStateCreateInfo kRasterization{.polygonMode = vk::PolygonMode::eFill,
                                                              .cullMode = vk::CullModeFlagBits::eNone,
                                                              .frontFace = vk::FrontFace::eCounterClockwise,
                                                              .lineWidth = 1.0f};
const vk::PipelineDepthStencilStateCreateInfo kDepthTest{
    .depthTestEnable = VK_TRUE, .depthWriteEnable = VK_TRUE, .depthCompareOp = vk::CompareOp::eLess};

// Tubes carry their coverage in alpha and are blended over what is behind
// them (they are drawn after everything else); the rest is opaque.
vk::PipelineColorBlendAttachmentState blending(bool tube) {
  return {.blendEnable = tube ? VK_TRUE : VK_FALSE,
          .srcColorBlendFactor = vk::BlendFactor::eSrcAlpha,
          .dstColorBlendFactor = vk::BlendFactor::eOneMinusSrcAlpha,
          .colorBlendOp = vk::BlendOp::eAdd,
          .srcAlphaBlendFactor = vk::BlendFactor::eOne,
          .dstAlphaBlendFactor = vk::BlendFactor::eOneMinusSrcAlpha,
          .alphaBlendOp = vk::BlendOp::eAdd,
          .colorWriteMask = vk::ColorComponentFlagBits::eR | vk::ColorComponentFlagBits::eG |
                            vk::ColorComponentFlagBits::eB | vk::ColorComponentFlagBits::eA};
}

}  // namespace

struct Renderer::Impl {
  const Context& ctx;
  RendererOptions options;
  vk::raii::DescriptorSetLayout view_layout{nullptr};
  vk::raii::DescriptorSetLayout texture_layout{nullptr};
  vk::raii::PipelineLayout pipeline_layout{nullptr};
  vk::raii::DescriptorPool pool{nullptr};
  vk::raii::Sampler sampler{nullptr};
  vk::raii::ShaderModule vert{nullptr};
  vk::raii::ShaderModule frag{nullptr};
  vk::raii::ShaderModule tube_vert{nullptr};
  vk::raii::ShaderModule tube_frag{nullptr};
  std::uint32_t msaa = 1;
  std::map<std::tuple<int, int, int, int, int>, vk::raii::Pipeline> pipelines;
  std::map<std::pair<std::size_t, int>, GpuMesh> meshes;
  std::map<std::size_t, Texture> textures;
  std::array<EyeAttachments, 2> attachments;
  std::vector<FrameSlot> slots;
  std::size_t next_slot = 0;
  bool timestamps = false;
  RenderPlan last_plan;
  std::vector<double> last_signature;
  // Eyes of a content-preserving target known to hold only the background:
  // not cleared or read back again while they stay unshown.
  std::uint64_t blank_target = 0;
  std::array<bool, 2> blank_eye{false, false};
  // Bound to set 1 for draws without text, so every pipeline's sets are bound.
  Texture blank;

  Impl(const Context& c, RendererOptions o)
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

  // The GPU may still read what the members own: wait before they go. A
  // destructor cannot report a lost device, and after one there is nothing
  // to wait for, so the results are ignored (the failure surfaced as a
  // VulkanFailure from the call that met it).
  ~Impl() {
    for (auto& s : slots)
      if (s.pending) {
        const VkFence fence = *s.fence;
        (void)ctx.device().getDispatcher()->vkWaitForFences(static_cast<VkDevice>(*ctx.device()), 1,
                                                            &fence, VK_TRUE, UINT64_MAX);
        s.pending = false;
      }
  }

  void wait_all() {
    for (auto& s : slots)
      if (s.pending) {
        ctx.wait_for(*s.fence);
        s.pending = false;
      }
  }

  const vk::raii::Pipeline& pipeline(Projection proj, int k, Hemisphere hemi, Shading shading,
                                     Topology topology) {
    const auto key = std::make_tuple(static_cast<int>(proj), k, static_cast<int>(hemi),
                                     static_cast<int>(shading), static_cast<int>(topology));
    if (auto it = pipelines.find(key); it != pipelines.end()) return it->second;
    const bool tube = shading == Shading::tube;
    const SpecData spec = spec_data(proj, k, hemi, shading);
    const auto entries = spec_entries();
    const vk::SpecializationInfo spec_info{.mapEntryCount = static_cast<std::uint32_t>(entries.size()),
                                           .pMapEntries = entries.data(),
                                           .dataSize = sizeof(SpecData),
                                           .pData = &spec};
    const vk::PipelineShaderStageCreateInfo stages[] = {
        {.stage = vk::ShaderStageFlagBits::eVertex, .module = tube ? *tube_vert : *vert, .pName = "main",
         .pSpecializationInfo = &spec_info},
        {.stage = vk::ShaderStageFlagBits::eFragment, .module = tube ? *tube_frag : *frag, .pName = "main",
         .pSpecializationInfo = &spec_info}};
    const vk::VertexInputBindingDescription binding{
        .binding = 0, .stride = static_cast<std::uint32_t>(tube ? sizeof(TubeVertex) : sizeof(Vertex)), .inputRate = vk::VertexInputRate::eVertex};
    const vk::PipelineVertexInputStateCreateInfo vertex_input{
        .vertexBindingDescriptionCount = 1, .pVertexBindingDescriptions = &binding,
        .vertexAttributeDescriptionCount = tube ? 6u : 3u,
        .pVertexAttributeDescriptions = tube ? kTubeVertexAttributes : kVertexAttributes};
    const vk::PipelineInputAssemblyStateCreateInfo assembly{
        .topology = topology == Topology::lines ? vk::PrimitiveTopology::eLineList
                                                : vk::PrimitiveTopology::eTriangleList};
    const vk::PipelineViewportStateCreateInfo viewport{.viewportCount = 1, .scissorCount = 1};
    // Multisampling anti-aliases edges only: the fragment shader runs once
    // per pixel, so text sampled from its atlas stays as sharp as without.
    const vk::PipelineMultisampleStateCreateInfo multisample{
        .rasterizationSamples = sample_bits(msaa)};
    const vk::PipelineColorBlendAttachmentState blend = blending(tube);
    const vk::PipelineColorBlendStateCreateInfo blend_state{.attachmentCount = 1, .pAttachments = &blend};
    const vk::DynamicState dyn[] = {vk::DynamicState::eViewport, vk::DynamicState::eScissor};
    const vk::PipelineDynamicStateCreateInfo dynamic{.dynamicStateCount = 2, .pDynamicStates = dyn};
    const vk::Format color_format = kColorFormat;
    const vk::PipelineRenderingCreateInfo rendering{.colorAttachmentCount = 1,
                                                    .pColorAttachmentFormats = &color_format,
                                                    .depthAttachmentFormat = kDepthFormat};
    const vk::GraphicsPipelineCreateInfo info{.pNext = &rendering,
                                              .stageCount = 2,
                                              .pStages = stages,
                                              .pVertexInputState = &vertex_input,
                                              .pInputAssemblyState = &assembly,
                                              .pViewportState = &viewport,
                                              .pRasterizationState = &kRasterization,
                                              .pMultisampleState = &multisample,
                                              .pDepthStencilState = &kDepthTest,
                                              .pColorBlendState = &blend_state,
                                              .pDynamicState = &dynamic,
                                              .layout = *pipeline_layout};
    auto [it, inserted] = pipelines.emplace(key, vk::raii::Pipeline(ctx.device(), nullptr, info));
    (void)inserted;
    return it->second;
  }

  // Renderer::render and its steps, defined after the helpers they use.
  FrameStats render(const Scene& scene, const FrameDescription& frame, RenderTarget& target);
  FrameSlot& take_slot();
  void begin_commands(const FrameSlot& slot) const;
  void clear_eye(FrameRecording& rec, int e, const ViewPlan& vp, const EyeImage& img);
  void draw_eye(FrameRecording& rec, int e, const ViewPlan& vp, const EyeImage& img);
  void write_view(FrameRecording& rec, int e, const ViewPlan& vp, const EyeImage& img) const;
  EyeDraws upload_draws(FrameRecording& rec, const ViewPlan& vp);
  void begin_pass(FrameRecording& rec, int e, const EyeImage& img);
  void record_draws(FrameRecording& rec, const ViewPlan& vp, const EyeDraws& draws);
  void submit(FrameRecording& rec);

  GpuMesh& mesh(const Scene& scene, std::size_t object, int level, Garbage& garbage) {
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

  Texture upload_texture(const CoverageBitmap& bmp) {
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

  const Texture& texture(const Scene& scene, std::size_t object, Garbage& garbage) {
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

  const EyeAttachments& eye_attachments(int eye, vk::Extent2D extent, Garbage& garbage) {
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
};

Renderer::Renderer(const Context& ctx, RendererOptions options)
    : impl_(std::make_unique<Impl>(ctx, options)) {}
Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;

const RenderPlan& Renderer::last_plan() const { return impl_->last_plan; }
std::uint32_t Renderer::msaa() const { return impl_->msaa; }

std::uint32_t supported_msaa(const Context& ctx, std::uint32_t requested) {
  const auto& limits = ctx.physical().getProperties().limits;
  const vk::SampleCountFlags both =
      limits.framebufferColorSampleCounts & limits.framebufferDepthSampleCounts;
  for (std::uint32_t n = 8; n > 1; n /= 2)
    if (n <= requested && (both & sample_bits(n))) return n;
  return 1;
}

std::uint32_t automatic_msaa(const Context& ctx) { return ctx.is_software() ? 1 : supported_msaa(ctx, 4); }

void Renderer::wait_idle() {
  try {
    impl_->wait_all();
  } catch (const vk::SystemError& e) {
    Context::throw_vulkan_failure(e);
  }
}
void Renderer::wait_idle_noexcept() noexcept {
  if (impl_) impl_->ctx.wait_idle_noexcept();
}

namespace {

// The eye's colour attachment: the target's image, or the multisampled image
// averaged into it when the pass ends (the resolve; for sRGB images the
// average is taken of linear values).
vk::RenderingAttachmentInfo color_attachment(std::uint32_t msaa, const EyeAttachments& att,
                                             const EyeImage& img, const std::array<float, 4>& bg) {
  vk::RenderingAttachmentInfo info{.imageView = img.view,
                                   .imageLayout = vk::ImageLayout::eColorAttachmentOptimal,
                                   .loadOp = vk::AttachmentLoadOp::eClear,
                                   .storeOp = vk::AttachmentStoreOp::eStore,
                                   .clearValue = vk::ClearColorValue{bg}};
  if (msaa == 1) return info;
  info.imageView = *att.color.view;
  info.storeOp = vk::AttachmentStoreOp::eDontCare;
  info.resolveMode = vk::ResolveModeFlagBits::eAverage;
  info.resolveImageView = img.view;
  info.resolveImageLayout = vk::ImageLayout::eColorAttachmentOptimal;
  return info;
}

// Every target hands the renderer sRGB RGBA8 images (its pipelines' format);
// another format is a broken contract.
void check_eye_format(const EyeImage& img) {
  if (img.format == kColorFormat) return;
  std::cerr << "curvlab renderer: an eye image is " << vk::to_string(img.format) << ", not "
            << vk::to_string(kColorFormat) << '\n';
  std::abort();
}

// Everything a frame's pixels depend on besides the scene content.
std::vector<double> frame_signature(const Scene& scene, const FrameDescription& f,
                                    const RenderTarget& target) {
  std::vector<double> s{static_cast<double>(scene.revision()),
                        static_cast<double>(target.identity()),
                        static_cast<double>(f.space.kind), f.space.radius_m,
                        static_cast<double>(f.settings.projection),
                        static_cast<double>(f.settings.eyes),
                        static_cast<double>(f.settings.dominant_eye),
                        f.settings.back_hemisphere ? 1.0 : 0.0, f.settings.near_m,
                        f.settings.error_budget_px,
                        static_cast<double>(f.settings.forced_level.value_or(-1)),
                        static_cast<double>(f.width_px),
                        static_cast<double>(f.height_px)};
  const double* h = glm::value_ptr(f.head.m);
  s.insert(s.end(), h, h + 16);
  for (const auto& e : f.rig.eyes) {
    s.insert(s.end(), {e.position_m.x, e.position_m.y, e.position_m.z, e.fov.angle_left_rad,
                       e.fov.angle_right_rad, e.fov.angle_up_rad, e.fov.angle_down_rad});
    const double* r = glm::value_ptr(e.rotation);
    s.insert(s.end(), r, r + 9);
  }
  return s;
}

}  // namespace

FrameStats Renderer::render(const Scene& scene, const FrameDescription& frame,
                            RenderTarget& target) {
  try {
    return impl_->render(scene, frame, target);
  } catch (const vk::SystemError& e) {
    Context::throw_vulkan_failure(e);
  }
}

FrameStats Renderer::Impl::render(const Scene& scene, const FrameDescription& frame, RenderTarget& target) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  FrameStats stats;
  auto signature = frame_signature(scene, frame, target);
  if (target.preserves_contents() && signature == last_signature) {
    stats.reused = true;
    stats.back_hemisphere = last_plan.back_hemisphere;
    stats.frame_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    return stats;
  }

  FrameSlot& slot = take_slot();
  RenderPlan plan = plan_frame(scene, frame);
  begin_commands(slot);
  FrameRecording rec{scene,
                     frame,
                     target,
                     slot,
                     {options.background.x, options.background.y, options.background.z, options.background.w},
                     static_cast<int>(frame.space.k()),
                     stats};
  for (int e = 0; e < 2; ++e) {
    const ViewPlan& vp = plan.views[e];
    const EyeImage img = target.eye_image(vp.eye);
    if (vp.rendered)
      draw_eye(rec, e, vp, img);
    else
      clear_eye(rec, e, vp, img);
  }
  if (timestamps) slot.cb.writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *slot.queries, 1);
  slot.cb.end();
  const auto t_recorded = Clock::now();
  submit(rec);
  target.frame_finished();
  stats.back_hemisphere = plan.back_hemisphere;
  stats.max_level = plan.max_level;
  stats.cpu_ms = std::chrono::duration<double, std::milli>(t_recorded - t0).count();
  stats.frame_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  last_plan = std::move(plan);
  last_signature = std::move(signature);
  return stats;
}

// The next slot in turn, once the GPU has finished its previous frame.
FrameSlot& Renderer::Impl::take_slot() {
  FrameSlot& slot = slots[next_slot];
  next_slot = (next_slot + 1) % slots.size();
  if (slot.pending) {
    ctx.wait_for(*slot.fence);
    slot.pending = false;
  }
  slot.garbage.clear();  // everything in it was last used by this slot's finished frame
  ctx.device().resetFences({*slot.fence});
  return slot;
}

void Renderer::Impl::begin_commands(const FrameSlot& slot) const {
  const vk::raii::CommandBuffer& cb = slot.cb;
  cb.reset();
  cb.begin({.flags = vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
  if (timestamps) {
    cb.resetQueryPool(*slot.queries, 0, 2);
    cb.writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *slot.queries, 0);
  }
}

// Only the background: a clear, no pass — and nothing at all when a
// headless target's image already holds just the background.
void Renderer::Impl::clear_eye(FrameRecording& rec, int e, const ViewPlan& vp, const EyeImage& img) {
  RenderTarget& target = rec.target;
  if (target.preserves_contents() && blank_target == target.identity() && blank_eye[e]) return;
  const vk::raii::CommandBuffer& cb = rec.slot.cb;
  const vk::ImageSubresourceRange color_range{vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1};
  transition(cb, img.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eUndefined,
             vk::ImageLayout::eTransferDstOptimal);
  cb.clearColorImage(img.image, vk::ImageLayout::eTransferDstOptimal, vk::ClearColorValue{rec.background},
                     color_range);
  transition(cb, img.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eTransferDstOptimal,
             img.final_layout);
  target.record_after(cb, vp.eye);
  if (target.preserves_contents()) {
    if (blank_target != target.identity()) blank_eye = {false, false};
    blank_target = target.identity();
    blank_eye[e] = true;
  }
}

void Renderer::Impl::draw_eye(FrameRecording& rec, int e, const ViewPlan& vp, const EyeImage& img) {
  if (blank_target == rec.target.identity()) blank_eye[e] = false;
  write_view(rec, e, vp, img);
  // Meshes and textures first: building one may submit an upload.
  const EyeDraws draws = upload_draws(rec, vp);
  check_eye_format(img);
  begin_pass(rec, e, img);
  record_draws(rec, vp, draws);
  const vk::raii::CommandBuffer& cb = rec.slot.cb;
  cb.endRendering();
  transition(cb, img.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eColorAttachmentOptimal,
             img.final_layout);
  rec.target.record_after(cb, vp.eye);
  rec.stats.culled += vp.culled;
  rec.stats.error_px = std::max(rec.stats.error_px, vp.estimated_error_px);
}

// The eye's View block, at its offset in the slot's uniform buffer.
void Renderer::Impl::write_view(FrameRecording& rec, int e, const ViewPlan& vp, const EyeImage& img) const {
  const ViewBlock block{to_float(vp.constants.proj_front), to_float(vp.constants.proj_back),
                        to_float(vp.constants.eye_from_nose),
                        glm::vec4(static_cast<float>(rec.frame.space.radius_m), static_cast<float>(img.extent.width),
                                  static_cast<float>(img.extent.height), 0.0f)};
  rec.slot.ubo.write(&block, sizeof(block), static_cast<std::size_t>(e) * kViewStride);
}

EyeDraws Renderer::Impl::upload_draws(FrameRecording& rec, const ViewPlan& vp) {
  EyeDraws draws;
  for (const auto& d : vp.draws) {
    draws.meshes.push_back(&mesh(rec.scene, d.object, d.level, rec.slot.garbage));
    draws.textures.push_back(rec.scene.objects()[d.object].text ? &texture(rec.scene, d.object, rec.slot.garbage)
                                                                : nullptr);
  }
  return draws;
}

// The eye's attachments in their drawing layouts, the pass begun, and the
// state every draw shares bound.
void Renderer::Impl::begin_pass(FrameRecording& rec, int e, const EyeImage& img) {
  const vk::raii::CommandBuffer& cb = rec.slot.cb;
  const EyeAttachments& att = eye_attachments(e, img.extent, rec.slot.garbage);
  const Image& depth = att.depth;
  transition(cb, img.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eUndefined,
             vk::ImageLayout::eColorAttachmentOptimal);
  if (msaa > 1)
    transition(cb, *att.color.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eUndefined,
               vk::ImageLayout::eColorAttachmentOptimal);
  transition(cb, *depth.image, vk::ImageAspectFlagBits::eDepth, vk::ImageLayout::eUndefined,
             vk::ImageLayout::eDepthAttachmentOptimal);
  const vk::RenderingAttachmentInfo color_att = color_attachment(msaa, att, img, rec.background);
  const vk::ClearValue depth_clear{.depthStencil = {.depth = 1.0f, .stencil = 0}};
  const vk::RenderingAttachmentInfo depth_att{.imageView = *depth.view,
                                              .imageLayout = vk::ImageLayout::eDepthAttachmentOptimal,
                                              .loadOp = vk::AttachmentLoadOp::eClear,
                                              .storeOp = vk::AttachmentStoreOp::eDontCare,
                                              .clearValue = depth_clear};
  cb.beginRendering({.renderArea = {{0, 0}, img.extent},
                     .layerCount = 1,
                     .colorAttachmentCount = 1,
                     .pColorAttachments = &color_att,
                     .pDepthAttachment = &depth_att});
  ++rec.stats.passes;
  ++rec.stats.views;
  cb.setViewport(0, vk::Viewport{0.0f, 0.0f, static_cast<float>(img.extent.width),
                                 static_cast<float>(img.extent.height), 0.0f, 1.0f});
  cb.setScissor(0, vk::Rect2D{{0, 0}, img.extent});
  cb.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, *pipeline_layout, 0, *rec.slot.view_set,
                        static_cast<std::uint32_t>(e * kViewStride));
  cb.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, *pipeline_layout, 1, *blank.set, {});
}

void Renderer::Impl::record_draws(FrameRecording& rec, const ViewPlan& vp, const EyeDraws& draws) {
  const vk::raii::CommandBuffer& cb = rec.slot.cb;
  FrameStats& stats = rec.stats;
  vk::Pipeline bound{};
  // Two passes over the draws: tubes last, as they blend over what is
  // behind them.
  for (const bool tubes : {false, true}) {
    for (std::size_t i = 0; i < vp.draws.size(); ++i) {
      if ((draws.meshes[i]->shading == Shading::tube) != tubes) continue;
      const PlannedDraw& d = vp.draws[i];
      GpuMesh& m = *draws.meshes[i];
      if (m.index_count == 0) continue;
      const auto& pipe = pipeline(rec.frame.settings.projection, rec.k, d.hemisphere, m.shading, m.topology);
      if (*pipe != bound) {
        cb.bindPipeline(vk::PipelineBindPoint::eGraphics, *pipe);
        bound = *pipe;
      }
      if (draws.textures[i] != nullptr)
        cb.bindDescriptorSets(vk::PipelineBindPoint::eGraphics, *pipeline_layout, 1, *draws.textures[i]->set, {});
      const DrawBlock db{to_float(d.model_view), rec.scene.objects()[d.object].tint};
      cb.pushConstants<DrawBlock>(*pipeline_layout, vk::ShaderStageFlagBits::eVertex, 0, db);
      cb.bindVertexBuffers(0, *m.vertices.buffer, vk::DeviceSize{0});
      cb.bindIndexBuffer(*m.indices.buffer, 0, vk::IndexType::eUint32);
      cb.drawIndexed(m.index_count, 1, 0, 0, 0);
      ++stats.draws;
      (m.topology == Topology::triangles ? stats.triangles : stats.lines) += m.primitives;
    }
  }
}

// Submit and wait name their calls in a VulkanFailure (a lost device shows
// here first); a frame that failed stays pending for the destructor. A
// target that keeps its contents is read back, so its frame is waited for.
void Renderer::Impl::submit(FrameRecording& rec) {
  FrameSlot& slot = rec.slot;
  ctx.submit(*slot.cb, *slot.fence);
  slot.pending = true;
  if (!rec.target.preserves_contents()) return;
  ctx.wait_for(*slot.fence);
  slot.pending = false;
  if (!timestamps) return;
  std::array<std::uint64_t, 2> ts{};
  // Through the device's dispatcher, as every other call: Windows builds
  // have no Vulkan import library (vulkan-1.dll is loaded at run time).
  const vk::Result res = (*ctx.device()).getQueryPoolResults(
      *slot.queries, 0, 2, sizeof(ts), ts.data(), sizeof(std::uint64_t),
      vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait, *ctx.device().getDispatcher());
  if (res == vk::Result::eSuccess)
    rec.stats.gpu_ms = static_cast<double>(ts[1] - ts[0]) * ctx.timestamp_period_ns() * 1e-6;
}

}  // namespace curvlab::renderer
