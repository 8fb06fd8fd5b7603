// Offscreen target: two sRGB RGBA8 images and their read-back buffers; the
// bytes read back are sRGB-encoded, as PNG viewers expect.
#pragma once

#include "curvlab/renderer/gpu.hpp"
#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/target.hpp"

#include <array>

namespace curvlab::renderer {

// Owns per-eye colour images and host-visible read-back buffers. The CPU
// copies (left(), right()) are valid after render() returns, since the
// renderer waits for headless frames. Move-only; not thread-safe.
class OffscreenTarget final : public RenderTarget {
 public:
  OffscreenTarget(const Context& ctx, std::uint32_t width_px, std::uint32_t height_px);

  EyeImage eye_image(Eye eye) override;
  void record_after(const vk::raii::CommandBuffer& cb, Eye eye) override;
  void frame_finished() override;
  [[nodiscard]] bool preserves_contents() const override { return true; }
  [[nodiscard]] std::uint64_t identity() const override { return identity_; }

  [[nodiscard]] const Rgba8Image& image(Eye eye) const { return cpu_[static_cast<int>(eye)]; }

 private:
  std::array<Image, 2> images_;
  std::array<Buffer, 2> readback_;
  std::array<Rgba8Image, 2> cpu_;
  std::array<bool, 2> copied_{false, false};
  std::uint64_t identity_;
};

}  // namespace curvlab::renderer
