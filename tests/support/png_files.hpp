// PNG files in tests, through the renderer's image I/O: a failure fails the
// test with the renderer's message, which names the file and what went wrong.
//   ASSERT_TRUE(read_png_into(path, image));
//   ASSERT_TRUE(png_written(renderer::write_png(path, image)));
#pragma once

#include "curvlab/renderer/image_io.hpp"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <variant>

namespace curvlab::test {

inline ::testing::AssertionResult read_png_into(const std::string& path, renderer::Rgba8Image& image) {
  auto read = renderer::read_png(path);
  if (auto* e = std::get_if<renderer::RenderError>(&read)) return ::testing::AssertionFailure() << e->message;
  image = std::get<renderer::Rgba8Image>(std::move(read));
  return ::testing::AssertionSuccess();
}

inline ::testing::AssertionResult png_written(const std::variant<renderer::Done, renderer::RenderError>& written) {
  if (auto* e = std::get_if<renderer::RenderError>(&written)) return ::testing::AssertionFailure() << e->message;
  return ::testing::AssertionSuccess();
}

}  // namespace curvlab::test
