// The renderer's failures (renderer::RenderError: no usable Vulkan device or
// driver, a surface that cannot be drawn to) become the harness's Error in
// one place: kind `device`, the message prefixed with what was being started.
#pragma once

#include "curvlab/harness/result.hpp"
#include "curvlab/renderer/context.hpp"

#include <string_view>
#include <utility>
#include <variant>

namespace curvlab::harness {

template <class T>
Result<T> from_renderer(std::variant<T, renderer::RenderError> made, std::string_view doing = {}) {
  if (auto* e = std::get_if<renderer::RenderError>(&made))
    return Error{Error::Kind::device, std::string(doing) + e->message};
  return std::get<T>(std::move(made));
}

}  // namespace curvlab::harness
