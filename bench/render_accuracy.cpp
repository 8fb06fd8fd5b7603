// Accuracy against speed for the renderer (DESIGN.md §8): prints tables.
//  1. Native view: screen-space error of drawn geodesic edges (the table's
//     edges) against the analytic curve, at a headset's 20 px/deg, for each
//     subdivision level, with frame time.
//  2. Ratios measured in the same run: native/tourist and one-eye/two-eye
//     frame time (billiards, 1024² per eye).
//  3. The billiards frame beside a plain Vulkan loop drawing the same meshes
//     with the same pixel coverage into the same two 1024² images.
//  4. Edge-position precision from the pixels per MSAA sample count
//     (render_precision.cpp).
// Usage: bench_render_accuracy [frames-per-measurement] [precision]
// ("precision": section 4 only)
#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/renderer.hpp"
#include "curvlab/renderer/shader.hpp"

#include "bench_scenes.hpp"
#include "render_precision.hpp"

#include "curvlab/geometry/maps.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

using namespace curvlab;
using namespace curvlab::renderer;
using geometry::SpaceKind;

namespace {

constexpr double kFovRad = std::numbers::pi / 2.0;
constexpr std::uint32_t kHeadsetPx = 1800;  // 90° at 20 px/deg

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

using bench::SceneKind;
using bench::StimulusScene;

StimulusScene make(SpaceKind kind, SceneKind scene) { return bench::scene_of(kind, scene); }

FrameDescription frame_for(const StimulusScene& s, ViewSettings settings, std::uint32_t px) {
  FrameDescription f;
  f.space = s.space;
  f.settings = settings;
  f.head = s.head;
  f.rig = StereoRig::from_ipd(0.063, Fov::symmetric(kFovRad, 1.0));
  f.width_px = px;
  f.height_px = px;
  return f;
}

struct Timing {
  double frame_ms = 0.0;
  double gpu_ms = 0.0;
  double cpu_ms = 0.0;
  FrameStats last;
};

// Median over `frames` frames; the head turns by a microradian each frame so
// no frame is an unchanged (skipped) one.
Timing time_frames(Renderer& r, const StimulusScene& s, FrameDescription f, RenderTarget& target,
                   int frames) {
  std::vector<double> wall, gpu, cpu;
  Timing t;
  for (int i = 0; i < frames + 1; ++i) {
    f.head = s.head * geometry::rotation(geometry::Vec3(0, 1, 0), 1e-6 * i);
    t.last = r.render(s.scene, f, target);
    if (i == 0) continue;  // first frame builds meshes and pipelines
    wall.push_back(t.last.frame_ms);
    gpu.push_back(t.last.gpu_ms);
    cpu.push_back(t.last.cpu_ms);
  }
  t.cpu_ms = median(cpu);
  t.frame_ms = median(wall);
  t.gpu_ms = median(gpu);
  return t;
}

// The plain loop draws exactly what curvlab drew in `plan`: the same meshes
// at the same subdivision levels, each vertex at the clip position curvlab's
// vertex shader gives it (clip_position, its C++ twin), so every pixel is
// covered as in curvlab's frame; with the same sample count, depth test, sRGB
// targets and read-back. What it leaves out — planning, per-draw state, the
// curved-space vertex work, shading — is curvlab's overhead.
struct PlainGeometry {
  struct V {
    float x, y, z, w, r, g, b, a;
  };
  std::array<std::vector<V>, 2> verts;  // per eye, the meshes' vertices
  std::array<std::vector<std::uint32_t>, 2> indices;  // per eye, triangle list
};

PlainGeometry plain_geometry(const StimulusScene& s, const RenderPlan& plan, double px) {
  PlainGeometry g;
  for (int e = 0; e < 2; ++e) {
    const ViewPlan& vp = plan.views[e];
    for (const PlannedDraw& d : vp.draws) {
      const MeshData mesh = s.scene.objects()[d.object].build(d.level);
      if (mesh.topology != Topology::triangles) continue;
      const auto first = static_cast<std::uint32_t>(g.verts[e].size());
      for (const Vertex& v : mesh.vertices) {
        const glm::dvec4 clip = clip_position(vp.constants, d.hemisphere, d.model_view * glm::dvec4(v.position));
        g.verts[e].push_back({float(clip.x), float(clip.y), float(clip.z), float(clip.w), v.color.x, v.color.y,
                              v.color.z, 1.0f});
      }
      // The stick's ribbon at the positions tube.vert gives it (its twin).
      for (const TubeVertex& v : mesh.tube_vertices) {
        const glm::dvec4 clip = tube_clip_position(vp.constants, d.hemisphere, d.model_view, v, px, px);
        g.verts[e].push_back({float(clip.x), float(clip.y), float(clip.z), float(clip.w), palette::stick_shaft.x,
                              palette::stick_shaft.y, palette::stick_shaft.z, 1.0f});
      }
      for (const std::uint32_t i : mesh.indices) g.indices[e].push_back(first + i);
    }
  }
  return g;
}

// `before_each` runs before every plain frame (curvlab's frame, so that load
// from other processes affects both alike).
double plain_loop_ms(const Context& ctx, const PlainGeometry& g, std::uint32_t px, std::uint32_t msaa, int frames,
                     const std::function<void(int)>& before_each) {
  using V = PlainGeometry::V;
  const auto& dev = ctx.device();
  std::array<Buffer, 2> vbs, ibs;
  for (int e = 0; e < 2; ++e) {
    vbs[e] = Buffer::create(ctx, std::max<std::size_t>(16, g.verts[e].size() * sizeof(V)),
                            vk::BufferUsageFlagBits::eVertexBuffer);
    vbs[e].write(g.verts[e].data(), g.verts[e].size() * sizeof(V));
    ibs[e] = Buffer::create(ctx, std::max<std::size_t>(16, g.indices[e].size() * 4),
                            vk::BufferUsageFlagBits::eIndexBuffer);
    ibs[e].write(g.indices[e].data(), g.indices[e].size() * 4);
  }
  auto vs = std::get<std::vector<std::uint32_t>>(compile_shader("plain.vert", ShaderStage::vertex));
  auto fs = std::get<std::vector<std::uint32_t>>(compile_shader("plain.frag", ShaderStage::fragment));
  vk::raii::ShaderModule vm(dev, {.codeSize = vs.size() * 4, .pCode = vs.data()});
  vk::raii::ShaderModule fm(dev, {.codeSize = fs.size() * 4, .pCode = fs.data()});
  vk::raii::PipelineLayout layout(dev, vk::PipelineLayoutCreateInfo{});
  const vk::PipelineShaderStageCreateInfo stages[] = {
      {.stage = vk::ShaderStageFlagBits::eVertex, .module = *vm, .pName = "main"},
      {.stage = vk::ShaderStageFlagBits::eFragment, .module = *fm, .pName = "main"}};
  const vk::VertexInputBindingDescription binding{0, sizeof(V), vk::VertexInputRate::eVertex};
  const vk::VertexInputAttributeDescription attrs[] = {{0, 0, vk::Format::eR32G32B32A32Sfloat, 0},
                                                       {1, 0, vk::Format::eR32G32B32A32Sfloat, 16}};
  const vk::PipelineVertexInputStateCreateInfo vi{.vertexBindingDescriptionCount = 1, .pVertexBindingDescriptions = &binding,
                                                  .vertexAttributeDescriptionCount = 2, .pVertexAttributeDescriptions = attrs};
  const vk::PipelineInputAssemblyStateCreateInfo ia{.topology = vk::PrimitiveTopology::eTriangleList};
  const vk::Viewport viewport{0, 0, float(px), float(px), 0, 1};
  const vk::Rect2D scissor{{0, 0}, {px, px}};
  const vk::PipelineViewportStateCreateInfo vp{.viewportCount = 1, .pViewports = &viewport, .scissorCount = 1, .pScissors = &scissor};
  const vk::PipelineRasterizationStateCreateInfo rs{.cullMode = vk::CullModeFlagBits::eNone, .lineWidth = 1.0f};
  const auto samples = static_cast<vk::SampleCountFlagBits>(msaa);
  const vk::PipelineMultisampleStateCreateInfo ms{.rasterizationSamples = samples};
  const vk::PipelineDepthStencilStateCreateInfo ds{.depthTestEnable = VK_TRUE, .depthWriteEnable = VK_TRUE, .depthCompareOp = vk::CompareOp::eLess};
  const vk::PipelineColorBlendAttachmentState ba{.colorWriteMask = vk::ColorComponentFlagBits::eR | vk::ColorComponentFlagBits::eG |
                                                                   vk::ColorComponentFlagBits::eB | vk::ColorComponentFlagBits::eA};
  const vk::PipelineColorBlendStateCreateInfo bs{.attachmentCount = 1, .pAttachments = &ba};
  const vk::Format cf = vk::Format::eR8G8B8A8Srgb;
  const vk::PipelineRenderingCreateInfo ri{.colorAttachmentCount = 1, .pColorAttachmentFormats = &cf,
                                           .depthAttachmentFormat = vk::Format::eD32Sfloat};
  vk::raii::Pipeline pipeline(dev, nullptr,
                              vk::GraphicsPipelineCreateInfo{.pNext = &ri, .stageCount = 2, .pStages = stages,
                                                             .pVertexInputState = &vi, .pInputAssemblyState = &ia,
                                                             .pViewportState = &vp, .pRasterizationState = &rs,
                                                             .pMultisampleState = &ms, .pDepthStencilState = &ds,
                                                             .pColorBlendState = &bs, .layout = *layout});
  OffscreenTarget target(ctx, px, px);
  std::array<Image, 2> depth, color;
  for (int e = 0; e < 2; ++e) {
    depth[e] = Image::create(ctx, {px, px}, vk::Format::eD32Sfloat, vk::ImageUsageFlagBits::eDepthStencilAttachment,
                             vk::ImageAspectFlagBits::eDepth, samples);
    if (msaa > 1)
      color[e] = Image::create(ctx, {px, px}, cf,
                               vk::ImageUsageFlagBits::eColorAttachment | vk::ImageUsageFlagBits::eTransientAttachment,
                               vk::ImageAspectFlagBits::eColor, samples);
  }
  std::vector<double> times;
  for (int f = 0; f < frames + 1; ++f) {
    before_each(f);
    const auto t0 = std::chrono::steady_clock::now();
    ctx.submit_and_wait([&](const vk::raii::CommandBuffer& cb) {
      for (int e = 0; e < 2; ++e) {
        const EyeImage img = target.eye_image(static_cast<Eye>(e));
        transition(cb, img.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eUndefined, vk::ImageLayout::eColorAttachmentOptimal);
        transition(cb, *depth[e].image, vk::ImageAspectFlagBits::eDepth, vk::ImageLayout::eUndefined, vk::ImageLayout::eDepthAttachmentOptimal);
        vk::RenderingAttachmentInfo ca{.imageView = img.view, .imageLayout = vk::ImageLayout::eColorAttachmentOptimal,
                                       .loadOp = vk::AttachmentLoadOp::eClear, .storeOp = vk::AttachmentStoreOp::eStore,
                                       .clearValue = vk::ClearColorValue{std::array<float, 4>{0, 0, 0, 1}}};
        if (msaa > 1) {
          transition(cb, *color[e].image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eUndefined,
                     vk::ImageLayout::eColorAttachmentOptimal);
          ca.imageView = *color[e].view;
          ca.storeOp = vk::AttachmentStoreOp::eDontCare;
          ca.resolveMode = vk::ResolveModeFlagBits::eAverage;
          ca.resolveImageView = img.view;
          ca.resolveImageLayout = vk::ImageLayout::eColorAttachmentOptimal;
        }
        const vk::RenderingAttachmentInfo da{.imageView = *depth[e].view, .imageLayout = vk::ImageLayout::eDepthAttachmentOptimal,
                                             .loadOp = vk::AttachmentLoadOp::eClear, .storeOp = vk::AttachmentStoreOp::eDontCare,
                                             .clearValue = vk::ClearValue{.depthStencil = {.depth = 1.0f, .stencil = 0}}};
        cb.beginRendering({.renderArea = scissor, .layerCount = 1, .colorAttachmentCount = 1, .pColorAttachments = &ca, .pDepthAttachment = &da});
        cb.bindPipeline(vk::PipelineBindPoint::eGraphics, *pipeline);
        cb.bindVertexBuffers(0, *vbs[e].buffer, vk::DeviceSize{0});
        cb.bindIndexBuffer(*ibs[e].buffer, 0, vk::IndexType::eUint32);
        cb.drawIndexed(static_cast<std::uint32_t>(g.indices[e].size()), 1, 0, 0, 0);
        cb.endRendering();
        transition(cb, img.image, vk::ImageAspectFlagBits::eColor, vk::ImageLayout::eColorAttachmentOptimal, img.final_layout);
        target.record_after(cb, static_cast<Eye>(e));
      }
    });
    target.frame_finished();
    const double elapsed_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (f > 0) times.push_back(elapsed_ms);
  }
  return median(times);
}

// The plain loop's frame time for the billiards frame (E3, native, 1024²)
// at a sample count: the same meshes and coverage as curvlab's frame, or
// nothing drawn at all (`empty`: clearing, resolving and reading back).
double plain_billiards_ms(const Context& ctx, std::uint32_t msaa, bool empty, int frames) {
  if (empty) return plain_loop_ms(ctx, PlainGeometry{}, 1024, msaa, frames, [](int) {});
  const StimulusScene s = make(SpaceKind::E3, SceneKind::billiards);
  Renderer r(ctx, RendererOptions{.msaa = msaa});
  OffscreenTarget t(ctx, 1024, 1024);
  r.render(s.scene, frame_for(s, ViewSettings::preset(ViewPreset::native), 1024), t);
  return plain_loop_ms(ctx, plain_geometry(s, r.last_plan(), 1024.0), 1024, msaa, frames, [](int) {});
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::max(1, std::atoi(argv[1])) : 9;
  auto created = Context::create({.device = DeviceChoice::automatic, .validation = false});
  if (auto* e = std::get_if<RenderError>(&created)) {
    std::fprintf(stderr, "%s\n", e->message.c_str());
    return 1;
  }
  const Context& ctx = std::get<Context>(created);
  std::printf("device: %s (%s); median of %d frames\n\n", ctx.device_name().c_str(), ctx.driver_info().c_str(), frames);
  if (argc > 2 && std::string(argv[2]) == "precision") {
    bench::print_precision_table(
        ctx, frames, [&](std::uint32_t n, bool empty) { return plain_billiards_ms(ctx, n, empty, frames); });
    return 0;
  }

  // ---- 1. native subdivision: error vs level ------------------------------
  std::printf("1. Native view, table edges (geodesics) drawn as straight pieces vs the analytic curve\n");
  std::printf("   %u x %u per eye, 90 deg FOV = 20 px/deg, one sample per pixel; error over both eyes and all edges\n\n",
              kHeadsetPx, kHeadsetPx);
  std::printf("| space | level | pieces/edge | max err px | mean err px | triangles | frame ms | GPU ms |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::H3}) {
    const StimulusScene s = make(kind, SceneKind::billiards);
    // One sample per pixel: the error is geometric, and 1800² with 4× MSAA
    // would double the benchmark's run time on a CPU device.
    Renderer renderer(ctx, RendererOptions{.msaa = 1});
    OffscreenTarget target(ctx, kHeadsetPx, kHeadsetPx);
    const auto& table = s.scene.objects()[0];
    auto errors_at = [&](int level) {
      double max_px = 0.0, sum = 0.0;
      int n = 0;
      const FrameDescription f = frame_for(s, ViewSettings::preset(ViewPreset::native), kHeadsetPx);
      for (int e = 0; e < 2; ++e) {
        const ViewConstants v = make_view_constants(s.space, f.settings, s.head, f.rig.eyes[e]);
        const glm::dmat4 mv = v.viewer_from_world.m * table.pose.m;
        for (const auto& edge : table.info.long_edges) {
          const EdgeError err = edge_screen_error(v, Hemisphere::front, mv, edge, table.info.base_segments << level,
                                                  kHeadsetPx, kHeadsetPx, 32);
          max_px = std::max(max_px, err.max_px);
          sum += err.mean_px * err.samples;
          n += err.samples;
        }
      }
      return std::make_pair(max_px, n > 0 ? sum / n : 0.0);
    };
    for (int level = 0; level <= 5; ++level) {
      ViewSettings settings = ViewSettings::preset(ViewPreset::native);
      settings.forced_level = level;
      const Timing t = time_frames(renderer, s, frame_for(s, settings, kHeadsetPx), target, std::max(3, frames / 3));
      const auto [max_px, mean_px] = errors_at(level);
      std::printf("| %s | %d | %d | %.4f | %.4f | %llu | %.1f | %.1f |\n", std::string(geometry::to_string(kind)).c_str(),
                  level, table.info.base_segments << level, max_px, mean_px,
                  static_cast<unsigned long long>(t.last.triangles), t.frame_ms, t.gpu_ms);
    }
    const Timing d = time_frames(renderer, s, frame_for(s, ViewSettings::preset(ViewPreset::native), kHeadsetPx), target,
                                 std::max(3, frames / 3));
    const auto [dmax, dmean] = errors_at(d.last.max_level);
    std::printf("| %s | default %d (budget 0.1 px) | %d | %.4f | %.4f | %llu | %.1f | %.1f |\n",
                std::string(geometry::to_string(kind)).c_str(), d.last.max_level,
                table.info.base_segments << d.last.max_level, dmax, dmean,
                static_cast<unsigned long long>(d.last.triangles), d.frame_ms, d.gpu_ms);
  }

  // ---- 2. ratios ------------------------------------------------------------
  std::printf("\n2. Ratios, billiards scene, 1024 x 1024 per eye, default settings\n\n");
  std::printf("| space | tourist ms (cpu/gpu) | native ms (cpu/gpu) | native/tourist | one-eye ms | one-eye/two-eye | native triangles | level |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  std::uint64_t billiards_triangles = 0;
  std::optional<PlainGeometry> billiards_geometry;
  std::uint32_t billiards_msaa = 1;
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const StimulusScene s = make(kind, SceneKind::billiards);
    // Three renderers and targets, frames interleaved, so load from other
    // processes on the machine affects all three alike.
    Renderer r_tourist(ctx), r_native(ctx), r_mono(ctx);
    OffscreenTarget t_tourist(ctx, 1024, 1024), t_native(ctx, 1024, 1024), t_mono(ctx, 1024, 1024);
    Timing tourist, native, mono;
    std::vector<double> wt, wn, wm, ct, cn, gt, gn;
    for (int i = 0; i < frames + 1; ++i) {
      const auto head = s.head * geometry::rotation(geometry::Vec3(0, 1, 0), 1e-6 * i);
      auto f = [&](ViewPreset p) {
        FrameDescription fd = frame_for(s, ViewSettings::preset(p), 1024);
        fd.head = head;
        return fd;
      };
      tourist.last = r_tourist.render(s.scene, f(ViewPreset::tourist), t_tourist);
      native.last = r_native.render(s.scene, f(ViewPreset::native), t_native);
      mono.last = r_mono.render(s.scene, f(ViewPreset::monocular), t_mono);
      if (i == 0) continue;
      wt.push_back(tourist.last.frame_ms);
      wn.push_back(native.last.frame_ms);
      wm.push_back(mono.last.frame_ms);
      ct.push_back(tourist.last.cpu_ms);
      cn.push_back(native.last.cpu_ms);
      gt.push_back(tourist.last.gpu_ms);
      gn.push_back(native.last.gpu_ms);
    }
    tourist.frame_ms = median(wt);
    native.frame_ms = median(wn);
    mono.frame_ms = median(wm);
    tourist.cpu_ms = median(ct);
    native.cpu_ms = median(cn);
    tourist.gpu_ms = median(gt);
    native.gpu_ms = median(gn);
    std::printf("| %s | %.1f (%.1f/%.1f) | %.1f (%.1f/%.1f) | %.3f | %.1f | %.3f | %llu | %d |\n",
                std::string(geometry::to_string(kind)).c_str(), tourist.frame_ms, tourist.cpu_ms, tourist.gpu_ms,
                native.frame_ms, native.cpu_ms, native.gpu_ms, native.frame_ms / tourist.frame_ms, mono.frame_ms,
                mono.frame_ms / native.frame_ms, static_cast<unsigned long long>(native.last.triangles), native.last.max_level);
    std::printf("|   | tourist triangles %llu, draws %d |  |  |  |  |  |  |\n",
                static_cast<unsigned long long>(tourist.last.triangles), tourist.last.draws);
    if (kind == SpaceKind::E3) {
      billiards_triangles = native.last.triangles;
      billiards_geometry = plain_geometry(s, r_native.last_plan(), 1024.0);
      billiards_msaa = r_native.msaa();
    }
  }

  // ---- 3. beside a plain loop -----------------------------------------------
  // curvlab's frames interleaved with the plain loop's.
  const StimulusScene e3 = make(SpaceKind::E3, SceneKind::billiards);
  Renderer r_e3(ctx);
  OffscreenTarget t_e3(ctx, 1024, 1024);
  std::vector<double> curvlab_ms;
  const double plain = plain_loop_ms(ctx, *billiards_geometry, 1024, billiards_msaa, frames, [&](int i) {
    FrameDescription fd = frame_for(e3, ViewSettings::preset(ViewPreset::native), 1024);
    fd.head = e3.head * geometry::rotation(geometry::Vec3(0, 1, 0), 1e-6 * i);
    const FrameStats st = r_e3.render(e3.scene, fd, t_e3);
    if (i > 0) curvlab_ms.push_back(st.frame_ms);
  });
  const double billiards_ms = median(curvlab_ms);
  const std::size_t plain_triangles =
      (billiards_geometry->indices[0].size() + billiards_geometry->indices[1].size()) / 3;
  std::printf("\n3. Billiards (E3, native, both eyes, 1024 x 1024 per eye, msaa %u) beside a plain Vulkan loop\n",
              billiards_msaa);
  std::printf("   drawing the same meshes at the same clip positions (same pixel coverage) through a minimal\n");
  std::printf("   pipeline, same sample count, sRGB targets and read-back\n\n");
  std::printf("| what | triangles | frame ms |\n|---|---|---|\n");
  std::printf("| curvlab billiards frame | %llu | %.1f |\n", static_cast<unsigned long long>(billiards_triangles), billiards_ms);
  std::printf("| plain loop, same meshes and coverage, 2 passes + read-back | %zu | %.1f |\n", plain_triangles, plain);
  std::printf("| ratio curvlab/plain | | %.3f |\n", billiards_ms / plain);

  bench::print_precision_table(
        ctx, frames, [&](std::uint32_t n, bool empty) { return plain_billiards_ms(ctx, n, empty, frames); });
  return 0;
}
