#include "mirror.hpp"

#include "quad_panels.hpp"

#include "curvlab/renderer/scene.hpp"

#include <algorithm>

#include <cmath>
#include <cstring>
#include <utility>

namespace curvlab::harness::xr {

namespace {

// The bytes shown for each byte read: sRGB-encoded (IEC 61966-2-1) for a
// linear image, as they are otherwise.
std::array<std::uint8_t, 256> encoding(bool linear) {
  std::array<std::uint8_t, 256> lut{};
  for (int v = 0; v < 256; ++v) {
    const double l = v / 255.0;
    const double e = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
    lut[static_cast<std::size_t>(v)] = static_cast<std::uint8_t>(linear ? std::lround(e * 255.0) : v);
  }
  return lut;
}

}  // namespace

void lay_panel(std::vector<std::uint8_t>& rgba, std::uint32_t stride_px, std::uint32_t eye_x0,
               vk::Extent2D eye_px, const MirrorEye& eye, const MirrorPanel& panel) {
  static const auto texels = panel_texels(static_cast<std::int64_t>(vk::Format::eR8G8B8A8Srgb));
  if (panel.text.width <= 0 || panel.text.height <= 0) return;
  // The eye in the card's frame.
  glm::dmat4 head_from_eye = glm::mat4_cast(eye.in_head.orientation);
  head_from_eye[3] = glm::dvec4(eye.in_head.position_m, 1.0);
  const glm::dmat4 card_from_eye = glm::inverse(panel.in_head) * head_from_eye;
  const glm::dmat4 eye_from_card = glm::inverse(card_from_eye);
  const FrustumTangents& t = eye.view;
  const double w = eye_px.width, h = eye_px.height;
  // The card's corners in the image: its box, where all lie ahead of the eye.
  double x_min = w, x_max = 0.0, y_min = h, y_max = 0.0;
  for (const double sx : {-0.5, 0.5})
    for (const double sy : {-0.5, 0.5}) {
      const glm::dvec4 c = eye_from_card * glm::dvec4(sx * panel.size_m.x, sy * panel.size_m.y, 0.0, 1.0);
      if (c.z >= -1e-6) {
        x_min = 0.0, x_max = w, y_min = 0.0, y_max = h;  // a corner behind the eye: every pixel
        continue;
      }
      const double px = (-c.x / c.z - t.left) / (t.right - t.left) * w;
      const double py = (t.up - -c.y / c.z) / (t.up - t.down) * h;
      x_min = std::min(x_min, px), x_max = std::max(x_max, px);
      y_min = std::min(y_min, py), y_max = std::max(y_max, py);
    }
  const auto first_x = static_cast<std::uint32_t>(std::clamp(std::floor(x_min), 0.0, w));
  const auto last_x = static_cast<std::uint32_t>(std::clamp(std::ceil(x_max), 0.0, w));
  const auto first_y = static_cast<std::uint32_t>(std::clamp(std::floor(y_min), 0.0, h));
  const auto last_y = static_cast<std::uint32_t>(std::clamp(std::ceil(y_max), 0.0, h));
  const glm::dvec3 origin(card_from_eye[3]);
  const glm::dmat3 turn(card_from_eye);
  for (std::uint32_t y = first_y; y < last_y; ++y)
    for (std::uint32_t x = first_x; x < last_x; ++x) {
      const glm::dvec3 d = turn * glm::dvec3(t.left + (x + 0.5) / w * (t.right - t.left),
                                             t.up - (y + 0.5) / h * (t.up - t.down), -1.0);
      if (std::abs(d.z) < 1e-12) continue;
      const double along = -origin.z / d.z;
      if (along <= 0.0) continue;
      const double u = (origin.x + along * d.x) / panel.size_m.x + 0.5;
      const double v = 0.5 - (origin.y + along * d.y) / panel.size_m.y;
      if (u < 0.0 || u >= 1.0 || v < 0.0 || v >= 1.0) continue;
      const auto tx = static_cast<std::size_t>(u * panel.text.width);
      const auto ty = static_cast<std::size_t>(v * panel.text.height);
      const std::uint8_t coverage = panel.text.pixels[ty * static_cast<std::size_t>(panel.text.width) + tx];
      std::copy_n(texels[coverage].data(), 4, rgba.data() + (std::size_t{y} * stride_px + eye_x0 + x) * 4);
    }
}

OperatorMirror::OperatorMirror(const renderer::Context& ctx, vk::Extent2D eye, bool bgra, bool linear)
    : ctx_(ctx),
      eye_(eye),
      bgra_(bgra),
      encode_(encoding(linear)),
      pool_(ctx.device(), {.flags = vk::CommandPoolCreateFlagBits::eResetCommandBuffer,
                           .queueFamilyIndex = ctx.queue_family()}),
      fence_(ctx.device(), vk::FenceCreateInfo{}),
      staging_(renderer::Buffer::create(ctx, vk::DeviceSize{2} * eye.width * eye.height * 4,
                                        vk::BufferUsageFlagBits::eTransferDst)) {
  vk::raii::CommandBuffers cbs(ctx.device(), {.commandPool = *pool_,
                                              .level = vk::CommandBufferLevel::ePrimary,
                                              .commandBufferCount = 1});
  cb_ = std::move(cbs.front());
}

OperatorMirror::~OperatorMirror() {
  if (state_.load(std::memory_order_acquire) == kCopying)
    (void)ctx_.device().waitForFences(*fence_, VK_TRUE, 1'000'000'000);
}

void OperatorMirror::request() {
  int idle = kIdle;
  state_.compare_exchange_strong(idle, kRequested, std::memory_order_acq_rel);
}

bool OperatorMirror::take(harness::io::MirrorImage& out) {
  if (state_.load(std::memory_order_acquire) != kCopying) return false;
  if (ctx_.device().waitForFences(*fence_, VK_TRUE, 0) != vk::Result::eSuccess) return false;
  out.width = eye_.width * 2;
  out.height = eye_.height;
  out.rgba.resize(std::size_t{out.width} * out.height * 4);
  const auto* src = static_cast<const std::uint8_t*>(staging_.mapped);
  const std::size_t row = std::size_t{eye_.width} * 4;
  for (std::uint32_t y = 0; y < eye_.height; ++y)
    for (std::size_t e = 0; e < 2; ++e)
      std::memcpy(out.rgba.data() + (std::size_t{y} * out.width * 4) + e * row,
                  src + e * row * eye_.height + y * row, row);
  if (bgra_)
    for (std::size_t i = 0; i < out.rgba.size(); i += 4) std::swap(out.rgba[i], out.rgba[i + 2]);
  for (std::size_t i = 0; i < out.rgba.size(); ++i)
    if (i % 4 != 3) out.rgba[i] = encode_[out.rgba[i]];
  for (std::uint32_t e = 0; e < 2; ++e)
    for (const MirrorPanel& panel : panels_) lay_panel(out.rgba, out.width, e * eye_.width, eye_, eyes_[e], panel);
  state_.store(kIdle, std::memory_order_release);
  return true;
}

void OperatorMirror::copy(const std::array<vk::Image, 2>& images, const renderer::Scene& scene,
                          bool panels_as_layers, const std::array<MirrorEye, 2>& eyes) {
  if (state_.load(std::memory_order_acquire) != kRequested) return;
  panels_.clear();
  eyes_ = eyes;
  if (panels_as_layers)
    for (const renderer::SceneObject& o : scene.objects())
      if (o.head_locked && o.visible && o.text) panels_.push_back({*o.text, o.pose.m, o.panel_size_m});
  ctx_.device().resetFences(*fence_);
  cb_.reset();
  cb_.begin({.flags = vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
  for (std::size_t e = 0; e < 2; ++e) {
    constexpr auto color = vk::ImageAspectFlagBits::eColor;
    renderer::transition(cb_, images[e], color, vk::ImageLayout::eColorAttachmentOptimal,
                         vk::ImageLayout::eTransferSrcOptimal);
    const vk::BufferImageCopy region{.bufferOffset = vk::DeviceSize{e} * eye_.width * eye_.height * 4,
                                     .imageSubresource = {color, 0, 0, 1},
                                     .imageExtent = {eye_.width, eye_.height, 1}};
    cb_.copyImageToBuffer(images[e], vk::ImageLayout::eTransferSrcOptimal, *staging_.buffer, region);
    renderer::transition(cb_, images[e], color, vk::ImageLayout::eTransferSrcOptimal,
                         vk::ImageLayout::eColorAttachmentOptimal);
  }
  cb_.end();
  ctx_.submit(*cb_, *fence_);
  state_.store(kCopying, std::memory_order_release);
}

}  // namespace curvlab::harness::xr
