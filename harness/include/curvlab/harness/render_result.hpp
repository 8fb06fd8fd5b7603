// The renderer's failures (renderer::RenderError) become the harness's Error
// in one place, the message prefixed with what was being done. The kind
// follows what a person must fix: a device, driver, surface or shader is
// `device` (install or update something); a font or image file that cannot
// be read or written is `io`; stimulus options that give no scene are
// `bad_input` (fix the protocol or the command).
#pragma once

#include "curvlab/harness/result.hpp"
#include "curvlab/renderer/error.hpp"

#include <string>
#include <string_view>
#include <utility>
#include <variant>

namespace curvlab::harness {

inline Error::Kind from_renderer(renderer::RenderError::Kind kind) {
  switch (kind) {
    case renderer::RenderError::Kind::device:
    case renderer::RenderError::Kind::surface:
    case renderer::RenderError::Kind::shader:
      return Error::Kind::device;
    case renderer::RenderError::Kind::font:
    case renderer::RenderError::Kind::file:
      return Error::Kind::io;
    case renderer::RenderError::Kind::stimulus:
      return Error::Kind::bad_input;
  }
  return Error::Kind::device;
}

inline Error from_renderer(const renderer::RenderError& e, std::string_view doing = {}) {
  return Error{from_renderer(e.kind), std::string(doing) + e.message};
}

template <class T>
Result<T> from_renderer(std::variant<T, renderer::RenderError> made, std::string_view doing = {}) {
  if (auto* e = std::get_if<renderer::RenderError>(&made)) return from_renderer(*e, doing);
  return std::get<T>(std::move(made));
}

}  // namespace curvlab::harness
