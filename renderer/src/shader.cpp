#include "curvlab/renderer/shader.hpp"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>

#include <mutex>
#include <sstream>

namespace curvlab::renderer {
namespace {

const ShaderSource* find_source(std::string_view name) {
  for (const auto& s : embedded_shader_sources())
    if (s.name == name) return &s;
  return nullptr;
}

// Replaces `#include "file"` lines by the embedded file's text (one level is
// all the shaders use; deeper includes are resolved recursively anyway).
std::variant<std::string, RenderError> resolve_includes(std::string_view name, int depth) {
  if (depth > 8) return RenderError{RenderError::Kind::shader, "include depth exceeded in " + std::string(name)};
  const ShaderSource* src = find_source(name);
  if (src == nullptr)
    return RenderError{RenderError::Kind::shader, "no embedded shader named " + std::string(name)};
  std::istringstream in{std::string(src->text)};
  std::ostringstream out;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto first = line.find_first_not_of(" \t");
    if (first != std::string::npos && line.compare(first, 8, "#include") == 0) {
      const auto open = line.find('"');
      const auto close = line.rfind('"');
      if (open == std::string::npos || close <= open)
        return RenderError{RenderError::Kind::shader,
                           std::string(name) + ":" + std::to_string(line_no) + ": expected #include \"file\""};
      auto inner = resolve_includes(line.substr(open + 1, close - open - 1), depth + 1);
      if (auto* e = std::get_if<RenderError>(&inner)) return *e;
      out << std::get<std::string>(inner) << '\n';
    } else {
      out << line << '\n';
    }
  }
  return out.str();
}

EShLanguage to_glslang(ShaderStage stage) {
  switch (stage) {
    case ShaderStage::vertex: return EShLangVertex;
    case ShaderStage::fragment: return EShLangFragment;
    case ShaderStage::compute: return EShLangCompute;
  }
  return EShLangVertex;
}

}  // namespace

std::variant<std::vector<std::uint32_t>, RenderError> compile_shader(std::string_view name,
                                                                     ShaderStage stage) {
  static std::once_flag init;
  std::call_once(init, [] { glslang::InitializeProcess(); });

  auto text = resolve_includes(name, 0);
  if (auto* e = std::get_if<RenderError>(&text)) return *e;
  const std::string& source = std::get<std::string>(text);
  const char* strings[] = {source.c_str()};
  const std::string name_str(name);
  const char* names[] = {name_str.c_str()};

  const EShLanguage lang = to_glslang(stage);
  glslang::TShader shader(lang);
  shader.setStringsWithLengthsAndNames(strings, nullptr, names, 1);
  shader.setEnvInput(glslang::EShSourceGlsl, lang, glslang::EShClientVulkan, 100);
  shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_2);
  shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_5);
  const auto messages = static_cast<EShMessages>(EShMsgSpvRules | EShMsgVulkanRules);
  if (!shader.parse(GetDefaultResources(), 460, false, messages))
    return RenderError{RenderError::Kind::shader,
                       "GLSL compile failed in " + name_str + ":\n" + shader.getInfoLog()};
  glslang::TProgram program;
  program.addShader(&shader);
  if (!program.link(messages))
    return RenderError{RenderError::Kind::shader,
                       "GLSL link failed for " + name_str + ":\n" + program.getInfoLog()};
  std::vector<std::uint32_t> spirv;
  glslang::SpvOptions options;
  options.validate = false;
  glslang::GlslangToSpv(*program.getIntermediate(lang), spirv, &options);
  return spirv;
}

}  // namespace curvlab::renderer
