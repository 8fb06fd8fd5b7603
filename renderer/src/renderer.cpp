#include "renderer_impl.hpp"

#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <iostream>

namespace curvlab::renderer {

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
  // Three passes over the draws: the opaque scene, then tubes (they blend
  // over what is behind them), then head-locked panels over everything.
  enum class Pass { scene, tubes, overlays };
  auto pass_of = [&](std::size_t i) {
    if (vp.draws[i].overlay) return Pass::overlays;
    return draws.meshes[i]->shading == Shading::tube ? Pass::tubes : Pass::scene;
  };
  for (const Pass pass : {Pass::scene, Pass::tubes, Pass::overlays}) {
    for (std::size_t i = 0; i < vp.draws.size(); ++i) {
      if (pass_of(i) != pass) continue;
      const PlannedDraw& d = vp.draws[i];
      GpuMesh& m = *draws.meshes[i];
      if (m.index_count == 0) continue;
      const PipelineKey key = d.overlay ? PipelineKey{.shading = m.shading, .topology = m.topology, .overlay = true}
                                        : PipelineKey{rec.frame.settings.projection, rec.k, d.hemisphere, m.shading,
                                                      m.topology};
      const auto& pipe = pipeline(key);
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
