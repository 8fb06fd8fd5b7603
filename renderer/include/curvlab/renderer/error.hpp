// The renderer's one failure value (STYLE.md, "Three kinds of failure"): no
// usable device or driver, a surface that cannot be drawn to, a shader that
// does not compile, a font that cannot be read. Functions that can fail
// return std::variant<T, RenderError>; the harness turns it into its Error
// in one place (harness/render_result.hpp). A Vulkan call that fails while
// drawing is thrown as VulkanFailure (vulkan_failure.hpp) and caught by the
// backend that called the renderer.
#pragma once

#include <string>

namespace curvlab::renderer {

struct RenderError {
  std::string message;
};

}  // namespace curvlab::renderer
