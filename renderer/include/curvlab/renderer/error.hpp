// The renderer's one failure value (STYLE.md, "Three kinds of failure"): no
// usable device or driver, a surface that cannot be drawn to, a shader that
// does not compile, a font or image file that cannot be read or written,
// stimulus options that give no scene. Functions that can fail return
// std::variant<T, RenderError> (std::variant<Done, RenderError> when there is
// nothing to return); the harness turns it into its Error in one place
// (harness/render_result.hpp), where the kind picks the harness's kind. A
// Vulkan call that fails while drawing is thrown as VulkanFailure
// (vulkan_failure.hpp) and caught by the backend that called the renderer.
#pragma once

#include <string>

namespace curvlab::renderer {

struct RenderError {
  enum class Kind {
    device,    // no Vulkan loader, device, driver or layer that will do; a call failing at start-up
    surface,   // a window surface or swapchain that cannot be made or drawn to
    shader,    // an embedded shader that does not resolve, compile or link
    font,      // a font file that cannot be opened or is not TrueType
    file,      // an image file that cannot be written or read
    stimulus,  // stimulus options that give no scene (a table no space can hold)
  };
  Kind kind = Kind::device;
  std::string message;  // names the device, file, shader or option and what failed
};

// The value of a function that can fail but returns nothing.
struct Done {};

}  // namespace curvlab::renderer
