// The renderer's state behind Renderer (renderer.hpp): the GPU objects it
// keeps between frames, the per-frame slots, and the steps of recording a
// frame. Private to the renderer: renderer_resources.cpp makes and caches the
// GPU objects, renderer.cpp records and submits frames.
//
// Owned by one Renderer; used by one thread at a time, as Renderer is.
#pragma once

#include "pipelines.hpp"

#include "curvlab/renderer/renderer.hpp"

#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace curvlab::renderer {

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
  std::map<PipelineKey, vk::raii::Pipeline> pipelines;
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

  Impl(const Context& c, RendererOptions o);
  // The GPU may still read what the members own: wait before they go. A
  // destructor cannot report a lost device, and after one there is nothing
  // to wait for, so the results are ignored (the failure surfaced as a
  // VulkanFailure from the call that met it).
  ~Impl();
  void wait_all();

  // The GPU objects a frame draws with, made on first use and kept while
  // what they were made from is unchanged (renderer_resources.cpp); what
  // they replace goes to the slot's garbage.
  const vk::raii::Pipeline& pipeline(const PipelineKey& key);
  GpuMesh& mesh(const Scene& scene, std::size_t object, int level, Garbage& garbage);
  Texture upload_texture(const CoverageBitmap& bmp);
  const Texture& texture(const Scene& scene, std::size_t object, Garbage& garbage);
  const EyeAttachments& eye_attachments(int eye, vk::Extent2D extent, Garbage& garbage);

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
};

}  // namespace curvlab::renderer
