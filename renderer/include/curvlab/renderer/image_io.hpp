// RGBA8 images on the CPU and PNG files (libpng with an sRGB chunk /
// stb_image).
#pragma once

#include "curvlab/renderer/error.hpp"

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace curvlab::renderer {

struct Rgba8Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // row major, 4 bytes per pixel
};

// Writes sRGB-encoded pixels as a PNG with an sRGB chunk. A file that
// cannot be created, encoded or flushed is a RenderError of kind `file`
// naming the path and the step that failed.
std::variant<Done, RenderError> write_png(const std::string& path, const Rgba8Image& image);
// Reads a PNG (any colour type) as RGBA8; a RenderError of kind `file`
// naming the path and the decoder's reason when it cannot.
std::variant<Rgba8Image, RenderError> read_png(const std::string& path);

struct ImageDiff {
  int differing_pixels = 0;  // channels differing by more than the tolerance
  int max_channel_diff = 0;
  Rgba8Image visual;         // |a − b| amplified, for people to look at
};
// Compares equally sized images; a pixel differs when any channel differs by
// more than channel_tolerance.
ImageDiff diff_images(const Rgba8Image& a, const Rgba8Image& b, int channel_tolerance);

}  // namespace curvlab::renderer
