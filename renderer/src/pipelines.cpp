#include "pipelines.hpp"

#include "curvlab/renderer/colour.hpp"

#include <cstddef>
#include <cstdlib>
#include <iostream>

namespace curvlab::renderer {
namespace {

struct SpecData {
  std::int32_t native_view;
  std::int32_t curvature;
  std::int32_t back;
  std::int32_t shading;
  std::int32_t overlay;
  glm::vec3 ink;    // text panels' glyphs, linear RGB
  glm::vec3 paper;  // text panels' ground, linear RGB
  // Tubes (tube.frag): the stick's colours, linear RGB, and its rings.
  std::array<glm::vec3, 4> wood;  // butt, shaft, tip, ring
  std::array<float, 5> ring_fractions;
  float ring_half_m;
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
SpecData spec_data(const PipelineKey& key) {
  SpecData spec{native_view(key.projection), key.k, key.hemisphere == Hemisphere::back ? 1 : 0,
                static_cast<std::int32_t>(key.shading), key.overlay ? 1 : 0, glm::vec3(palette::text_ink),
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
  entries.push_back({28, offsetof(SpecData, overlay), 4});
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
// Head-locked panels are drawn last, over whatever the scene put there.
const vk::PipelineDepthStencilStateCreateInfo kNoDepth{.depthTestEnable = VK_FALSE, .depthWriteEnable = VK_FALSE};

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

std::vector<std::uint32_t> compile_or_abort(std::string_view name, ShaderStage stage) {
  auto result = compile_shader(name, stage);
  if (auto* e = std::get_if<RenderError>(&result)) {
    // The shaders are part of the program: failing to compile them is a bug.
    std::cerr << "curvlab renderer: " << e->message << '\n';
    std::abort();
  }
  return std::get<std::vector<std::uint32_t>>(std::move(result));
}

vk::raii::Pipeline make_pipeline(const vk::raii::Device& dev, const PipelineKey& key, const PipelineShaders& shaders,
                                 vk::PipelineLayout layout, std::uint32_t msaa) {
  const bool tube = key.shading == Shading::tube;
  const SpecData spec = spec_data(key);
  const auto entries = spec_entries();
  const vk::SpecializationInfo spec_info{.mapEntryCount = static_cast<std::uint32_t>(entries.size()),
                                         .pMapEntries = entries.data(),
                                         .dataSize = sizeof(SpecData),
                                         .pData = &spec};
  const vk::PipelineShaderStageCreateInfo stages[] = {
      {.stage = vk::ShaderStageFlagBits::eVertex, .module = tube ? shaders.tube_vert : shaders.vert, .pName = "main",
       .pSpecializationInfo = &spec_info},
      {.stage = vk::ShaderStageFlagBits::eFragment, .module = tube ? shaders.tube_frag : shaders.frag, .pName = "main",
       .pSpecializationInfo = &spec_info}};
  const vk::VertexInputBindingDescription binding{
      .binding = 0, .stride = static_cast<std::uint32_t>(tube ? sizeof(TubeVertex) : sizeof(Vertex)), .inputRate = vk::VertexInputRate::eVertex};
  const vk::PipelineVertexInputStateCreateInfo vertex_input{
      .vertexBindingDescriptionCount = 1, .pVertexBindingDescriptions = &binding,
      .vertexAttributeDescriptionCount = tube ? 6u : 3u,
      .pVertexAttributeDescriptions = tube ? kTubeVertexAttributes : kVertexAttributes};
  const vk::PipelineInputAssemblyStateCreateInfo assembly{
      .topology = key.topology == Topology::lines ? vk::PrimitiveTopology::eLineList
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
                                            .pDepthStencilState = key.overlay ? &kNoDepth : &kDepthTest,
                                            .pColorBlendState = &blend_state,
                                            .pDynamicState = &dynamic,
                                            .layout = layout};
  return vk::raii::Pipeline(dev, nullptr, info);
}

}  // namespace curvlab::renderer
