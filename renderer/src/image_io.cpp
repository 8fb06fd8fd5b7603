#include "curvlab/renderer/image_io.hpp"

#include <png.h>
#include <stb_image.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <utility>

namespace curvlab::renderer {
namespace {

RenderError file_failure(std::string message) { return {RenderError::Kind::file, std::move(message)}; }

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

// libpng reports errors by longjmp to the setjmp in encode(); no C++ object
// with a destructor may live between the two.
bool encode(std::FILE* file, const Rgba8Image& image) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height),
               8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  // The pixels are sRGB-encoded (the renderer's targets are sRGB): say so
  // with an sRGB chunk and the gAMA/cHRM values the PNG specification
  // (11.3.3.5) pairs with it, for readers that know only those.
  png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y)
    png_write_row(png, image.pixels.data() + static_cast<std::size_t>(y) * image.width * 4);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

std::variant<Done, RenderError> write_png(const std::string& path, const Rgba8Image& image) {
  const std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "wb"));
  if (!file) return file_failure("cannot create PNG " + path + ": " + std::strerror(errno));
  // libpng writes through fwrite and fflush writes what stdio buffered: a
  // full disk or a lost mount shows in errno; without one, libpng refused.
  errno = 0;
  if (!encode(file.get(), image) || std::fflush(file.get()) != 0)
    return file_failure("cannot write PNG " + path + ": " +
                        (errno != 0 ? std::strerror(errno) : "libpng could not encode the image"));
  return Done{};
}

std::variant<Rgba8Image, RenderError> read_png(const std::string& path) {
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 4);
  if (data == nullptr) return file_failure("cannot read PNG " + path + ": " + stbi_failure_reason());
  Rgba8Image image;
  image.width = w;
  image.height = h;
  image.pixels.assign(data, data + static_cast<std::size_t>(w * h * 4));
  stbi_image_free(data);
  return image;
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
