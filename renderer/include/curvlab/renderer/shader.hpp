// GLSL → SPIR-V with glslang, at load time. The GLSL text is embedded into the
// build tree from renderer/shaders/ (see cmake/embed_shaders.cmake).
#pragma once

#include "curvlab/renderer/error.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace curvlab::renderer {

struct ShaderSource {
  std::string_view name;  // file name under renderer/shaders/
  std::string_view text;
};

// Every file of renderer/shaders/, embedded at build time.
const std::vector<ShaderSource>& embedded_shader_sources();

enum class ShaderStage { vertex, fragment, compute };

// Compiles the embedded shader `name` (resolving `#include "file"` lines from
// the other embedded files) to SPIR-V for Vulkan 1.2. Thread-safe: glslang's
// process-wide state is initialised once.
std::variant<std::vector<std::uint32_t>, RenderError> compile_shader(std::string_view name, ShaderStage stage);

}  // namespace curvlab::renderer
