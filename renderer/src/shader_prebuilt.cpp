// compile_shader() where no GLSL compiler runs at load time (Windows): the
// SPIR-V of every stage was compiled on the build host by glslangValidator
// with the settings src/shader.cpp uses (cmake/compile_shaders.cmake).
#include "curvlab/renderer/shader.hpp"

namespace curvlab::renderer {

struct PrebuiltSpirv {
  std::string_view name;
  std::vector<std::uint32_t> words;
};
const std::vector<PrebuiltSpirv>& prebuilt_spirv();  // generated

namespace {
std::string_view extension_of(ShaderStage stage) {
  switch (stage) {
    case ShaderStage::vertex: return ".vert";
    case ShaderStage::fragment: return ".frag";
    case ShaderStage::compute: return ".comp";
  }
  return "";
}
}  // namespace

std::variant<std::vector<std::uint32_t>, RenderError> compile_shader(std::string_view name, ShaderStage stage) {
  if (!name.ends_with(extension_of(stage)))
    return RenderError{RenderError::Kind::shader,
                       std::string(name) + " is not a " + std::string(extension_of(stage).substr(1)) + " shader"};
  for (const auto& s : prebuilt_spirv())
    if (s.name == name) return s.words;
  return RenderError{RenderError::Kind::shader, "no embedded shader named " + std::string(name)};
}

}  // namespace curvlab::renderer
