// RGBA8 images on the CPU and PNG files (libpng with an sRGB chunk /
// stb_image).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace curvlab::renderer {

struct Rgba8Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // row major, 4 bytes per pixel
};

// Writes sRGB-encoded pixels as a PNG with an sRGB chunk. Returns an empty
// string on success, else a message naming the file.
std::string write_png(const std::string& path, const Rgba8Image& image);
// Reads a PNG as RGBA8; false with a message on failure.
bool read_png(const std::string& path, Rgba8Image& image, std::string& error);

struct ImageDiff {
  int differing_pixels = 0;  // channels differing by more than the tolerance
  int max_channel_diff = 0;
  Rgba8Image visual;         // |a − b| amplified, for people to look at
};
// Compares equally sized images; a pixel differs when any channel differs by
// more than channel_tolerance.
ImageDiff diff_images(const Rgba8Image& a, const Rgba8Image& b, int channel_tolerance);

}  // namespace curvlab::renderer
