// The graphics pipelines of the scene and tube shaders (scene.vert/.frag,
// tube.vert/.frag): the formats and uniform blocks the shaders share with the
// renderer, and the fixed-function state, specialisation constants and vertex
// layouts a pipeline is built from. Private to the renderer (renderer.cpp,
// renderer_resources.cpp).
#pragma once

#include "curvlab/renderer/renderer.hpp"
#include "curvlab/renderer/shader.hpp"

#include <glm/glm.hpp>

#include <cstdint>
#include <string_view>
#include <vector>

namespace curvlab::renderer {

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

// Which pipeline a draw needs: every field is a specialisation or a fixed
// state of the pipeline, so equal keys share one.
struct PipelineKey {
  Projection projection = Projection::tourist;
  int k = 0;  // the space's curvature sign
  Hemisphere hemisphere = Hemisphere::front;
  Shading shading = Shading::lit;
  Topology topology = Topology::triangles;
  bool overlay = false;  // a head-locked panel: clip position given, no depth
  auto operator<=>(const PipelineKey&) const = default;
};

// The shader modules the pipelines are built from.
struct PipelineShaders {
  vk::ShaderModule vert, frag;            // scene meshes
  vk::ShaderModule tube_vert, tube_frag;  // tubes
};

// SPIR-V of one of the renderer's own shaders; a shader that fails to
// compile is a bug in the program, so this aborts with the message.
std::vector<std::uint32_t> compile_or_abort(std::string_view name, ShaderStage stage);

inline glm::mat4 to_float(const glm::dmat4& m) { return glm::mat4(m); }

inline vk::SampleCountFlagBits sample_bits(std::uint32_t samples) {
  return static_cast<vk::SampleCountFlagBits>(samples);
}

// A new pipeline for `key`, drawing into sRGB colour (kColorFormat) and
// depth (kDepthFormat) attachments with `msaa` samples.
vk::raii::Pipeline make_pipeline(const vk::raii::Device& dev, const PipelineKey& key, const PipelineShaders& shaders,
                                 vk::PipelineLayout layout, std::uint32_t msaa);

}  // namespace curvlab::renderer
