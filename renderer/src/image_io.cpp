#include "curvlab/renderer/image_io.hpp"

#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cstdlib>

namespace curvlab::renderer {

std::string write_png(const std::string& path, const Rgba8Image& image) {
  if (stbi_write_png(path.c_str(), image.width, image.height, 4, image.pixels.data(),
                     image.width * 4) == 0)
    return "cannot write PNG " + path;
  return {};
}

bool read_png(const std::string& path, Rgba8Image& image, std::string& error) {
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 4);
  if (data == nullptr) {
    error = "cannot read PNG " + path + ": " + stbi_failure_reason();
    return false;
  }
  image.width = w;
  image.height = h;
  image.pixels.assign(data, data + static_cast<std::size_t>(w * h * 4));
  stbi_image_free(data);
  return true;
}

ImageDiff diff_images(const Rgba8Image& a, const Rgba8Image& b, int channel_tolerance) {
  ImageDiff d;
  d.visual = a;
  if (a.width != b.width || a.height != b.height) {
    d.differing_pixels = std::max(a.width * a.height, b.width * b.height);
    d.max_channel_diff = 255;
    return d;
  }
  for (std::size_t i = 0; i < a.pixels.size(); i += 4) {
    int worst = 0;
    for (std::size_t c = 0; c < 3; ++c)
      worst = std::max(worst, std::abs(int(a.pixels[i + c]) - int(b.pixels[i + c])));
    d.max_channel_diff = std::max(d.max_channel_diff, worst);
    if (worst > channel_tolerance) ++d.differing_pixels;
    const auto v = static_cast<std::uint8_t>(std::min(255, worst * 8));
    d.visual.pixels[i] = v;
    d.visual.pixels[i + 1] = worst > channel_tolerance ? 0 : v;
    d.visual.pixels[i + 2] = worst > channel_tolerance ? 0 : v;
    d.visual.pixels[i + 3] = 255;
  }
  return d;
}

}  // namespace curvlab::renderer
