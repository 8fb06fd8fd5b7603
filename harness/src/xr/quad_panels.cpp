#include "quad_panels.hpp"

#include "swapchains.hpp"

#include "curvlab/harness/xr/views.hpp"
#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>

namespace curvlab::harness::xr {

namespace {

// Swapchain sizes grow in steps of this many texels, so a panel whose text
// changes by a few texels keeps its swapchain.
constexpr std::uint32_t kGrain = 64;

std::uint32_t rounded_up(std::uint32_t n) { return (n + kGrain - 1) / kGrain * kGrain; }

}  // namespace

// sRGB-encoded for an sRGB format (IEC 61966-2-1), linear for a UNORM one.
std::array<std::array<std::uint8_t, 4>, 256> panel_texels(std::int64_t format) {
  const auto f = static_cast<vk::Format>(format);
  const bool bgra = f == vk::Format::eB8G8R8A8Srgb || f == vk::Format::eB8G8R8A8Unorm;
  const bool srgb = f == vk::Format::eR8G8B8A8Srgb || f == vk::Format::eB8G8R8A8Srgb;
  const glm::vec3 ink(renderer::palette::text_ink);
  const glm::vec3 paper(renderer::palette::text_paper);
  std::array<std::array<std::uint8_t, 4>, 256> lut{};
  for (std::size_t c = 0; c < 256; ++c) {
    const glm::vec3 mixed = paper + (ink - paper) * (static_cast<float>(c) / 255.0f);
    std::array<std::uint8_t, 4> px{0, 0, 0, 255};
    for (int k = 0; k < 3; ++k) {
      const float v = srgb ? renderer::linear_to_srgb(mixed[k]) : mixed[k];
      px[static_cast<std::size_t>(bgra ? 2 - k : k)] = static_cast<std::uint8_t>(std::lround(v * 255.0f));
    }
    lut[c] = px;
  }
  return lut;
}

QuadPanels::QuadPanels(const renderer::Context& ctx, std::int64_t format)
    : ctx_(ctx), format_(format), texels_(panel_texels(format)) {}

bool QuadPanels::update(Session& session, XrSpace view, const renderer::Scene& scene) {
  layers_.clear();
  const auto& objects = scene.objects();
  std::size_t k = 0;
  for (std::size_t i = 0; i < objects.size(); ++i) {
    const renderer::SceneObject& o = objects[i];
    if (!o.head_locked || !o.visible || !o.text || o.text->width <= 0 || o.text->height <= 0) continue;
    if (k == slots_.size()) slots_.emplace_back();
    Slot& slot = slots_[k++];
    const auto w = static_cast<std::uint32_t>(o.text->width);
    const auto h = static_cast<std::uint32_t>(o.text->height);
    if (!fit(session, slot, w, h)) return false;
    if (slot.revision != scene.mesh_revision(i)) {
      write(session, slot, o.text->pixels, w, h);
      slot.revision = scene.mesh_revision(i);
    }
    auto quad = tagged<XrCompositionLayerQuad>(XR_TYPE_COMPOSITION_LAYER_QUAD);
    quad.space = view;
    quad.eyeVisibility = XR_EYE_VISIBILITY_BOTH;
    quad.subImage.swapchain = slot.handle.get();
    quad.subImage.imageRect = {{0, 0}, {static_cast<std::int32_t>(w), static_cast<std::int32_t>(h)}};
    quad.subImage.imageArrayIndex = 0;
    StagePose pose;
    pose.position_m = glm::dvec3(o.pose.m[3]);
    pose.orientation = glm::normalize(glm::quat_cast(glm::dmat3(o.pose.m)));
    quad.pose = to_xr_pose(pose);
    quad.size = {static_cast<float>(o.panel_size_m.x), static_cast<float>(o.panel_size_m.y)};
    layers_.push_back(quad);
  }
  return true;
}

bool QuadPanels::fit(Session& session, Slot& slot, std::uint32_t width, std::uint32_t height) {
  if (slot.handle.get() != XR_NULL_HANDLE && width <= slot.width && height <= slot.height) return true;
  const std::uint32_t w = rounded_up(std::max(width, slot.width));
  const std::uint32_t h = rounded_up(std::max(height, slot.height));
  auto made = make_swapchain(session, format_, w, h,
                             XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT);
  if (!made) {
    std::cerr << "curvlab: xr: " << made.error().message
              << "; the panels are drawn into the eye images instead of as quad layers\n";
    return false;
  }
  slot.handle = std::move(made.value().handle);
  slot.images = std::move(made.value().images);
  slot.width = w;
  slot.height = h;
  slot.staging = renderer::Buffer::create(ctx_, vk::DeviceSize{w} * h * 4, vk::BufferUsageFlagBits::eTransferSrc);
  slot.revision = 0;
  return true;
}

void QuadPanels::write(Session& session, Slot& slot, const std::vector<std::uint8_t>& coverage,
                       std::uint32_t width, std::uint32_t height) {
  auto* out = static_cast<std::uint8_t*>(slot.staging.mapped);
  for (std::size_t i = 0; i < std::size_t{width} * height; ++i)
    std::copy_n(texels_[coverage[i]].data(), 4, out + 4 * i);

  std::uint32_t index = 0;
  auto acquire = tagged<XrSwapchainImageAcquireInfo>(XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO);
  if (const XrResult r = xrAcquireSwapchainImage(slot.handle.get(), &acquire, &index); XR_FAILED(r))
    session.fail(r, "xrAcquireSwapchainImage");
  wait_swapchain_image(session, slot.handle.get(), wait_said_);
  const vk::Image image = slot.images[index].image;
  ctx_.submit_and_wait([&](const vk::raii::CommandBuffer& cb) {
    constexpr auto color = vk::ImageAspectFlagBits::eColor;
    // An acquired image is in COLOR_ATTACHMENT_OPTIMAL and is released in
    // it (XR_KHR_vulkan_enable2).
    renderer::transition(cb, image, color, vk::ImageLayout::eColorAttachmentOptimal,
                         vk::ImageLayout::eTransferDstOptimal);
    const vk::BufferImageCopy region{.bufferOffset = 0,
                                     .bufferRowLength = width,
                                     .bufferImageHeight = height,
                                     .imageSubresource = {color, 0, 0, 1},
                                     .imageExtent = {width, height, 1}};
    cb.copyBufferToImage(*slot.staging.buffer, image, vk::ImageLayout::eTransferDstOptimal, region);
    renderer::transition(cb, image, color, vk::ImageLayout::eTransferDstOptimal,
                         vk::ImageLayout::eColorAttachmentOptimal);
  });
  auto release = tagged<XrSwapchainImageReleaseInfo>(XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO);
  if (const XrResult r = xrReleaseSwapchainImage(slot.handle.get(), &release); XR_FAILED(r))
    session.fail(r, "xrReleaseSwapchainImage");
}

}  // namespace curvlab::harness::xr
