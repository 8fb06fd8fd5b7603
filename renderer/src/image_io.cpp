#include "curvlab/renderer/image_io.hpp"

#ifdef CURVLAB_PNG_WITH_ZLIB
#include <zlib.h>
#else
#include <png.h>
#endif
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

#ifdef CURVLAB_PNG_WITH_ZLIB
// Windows builds: the same PNG as the libpng branch below (8-bit RGBA, no
// interlace, sRGB + gAMA + cHRM chunks; PNG specification 11.3.3.5), each
// row with filter type 0, the whole deflated by zlib. The pixels equal the
// libpng file's; the compressed bytes may differ.
void put_u32(std::string& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((v >> shift) & 0xffu));
}

void put_chunk(std::string& out, const char* type, const std::string& data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t start = out.size();
  out.append(type, 4);
  out += data;
  const auto crc = crc32(0, reinterpret_cast<const Bytef*>(out.data() + start), static_cast<uInt>(out.size() - start));
  put_u32(out, static_cast<std::uint32_t>(crc));
}

bool encode(std::FILE* file, const Rgba8Image& image) {
  const auto w = static_cast<std::size_t>(image.width), h = static_cast<std::size_t>(image.height);
  std::string raw;
  raw.reserve(h * (1 + w * 4));
  for (std::size_t y = 0; y < h; ++y) {
    raw.push_back('\0');
    raw.append(reinterpret_cast<const char*>(image.pixels.data() + y * w * 4), w * 4);
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string packed(packed_size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size, reinterpret_cast<const Bytef*>(raw.data()),
                static_cast<uLong>(raw.size()), Z_DEFAULT_COMPRESSION) != Z_OK)
    return false;
  packed.resize(packed_size);

  std::string png("\x89PNG\r\n\x1a\n", 8);
  std::string ihdr;
  put_u32(ihdr, static_cast<std::uint32_t>(w));
  put_u32(ihdr, static_cast<std::uint32_t>(h));
  ihdr += std::string("\x08\x06\x00\x00\x00", 5);  // 8 bits, RGBA, deflate, adaptive filters, no interlace
  put_chunk(png, "IHDR", ihdr);
  put_chunk(png, "sRGB", std::string(1, '\0'));  // perceptual intent
  std::string gama;
  put_u32(gama, 45455);
  put_chunk(png, "gAMA", gama);
  std::string chrm;
  for (const std::uint32_t v : {31270u, 32900u, 64000u, 33000u, 30000u, 60000u, 15000u, 6000u}) put_u32(chrm, v);
  put_chunk(png, "cHRM", chrm);
  put_chunk(png, "IDAT", packed);
  put_chunk(png, "IEND", "");
  return std::fwrite(png.data(), 1, png.size(), file) == png.size();
}
#else
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
#endif

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
