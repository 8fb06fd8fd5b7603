#include "curvlab/renderer/text.hpp"

#include <stb_truetype.h>

#ifdef _WIN32
#ifndef NOMINMAX
#define NOMINMAX
#endif
#include <windows.h>
#include <filesystem>
#endif

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

namespace curvlab::renderer {
namespace {

// Decodes UTF-8 into code points; malformed bytes become U+FFFD.
std::vector<int> decode_utf8(const std::string& s) {
  std::vector<int> out;
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    int cp = 0xFFFD;
    int len = 1;
    if (c < 0x80) {
      cp = c;
    } else if ((c >> 5) == 0x6 && i + 1 < s.size()) {
      cp = ((c & 0x1F) << 6) | (s[i + 1] & 0x3F);
      len = 2;
    } else if ((c >> 4) == 0xE && i + 2 < s.size()) {
      cp = ((c & 0x0F) << 12) | ((s[i + 1] & 0x3F) << 6) | (s[i + 2] & 0x3F);
      len = 3;
    }
    out.push_back(cp);
    i += static_cast<std::size_t>(len);
  }
  return out;
}

#ifdef _WIN32
// A relative font path that is not found from the working folder is looked
// up beside the executable, where the Windows zip keeps fonts/.
std::filesystem::path beside_executable(const std::string& relative) {
  std::wstring exe(32768, L'\0');
  exe.resize(GetModuleFileNameW(nullptr, exe.data(), static_cast<DWORD>(exe.size())));
  return std::filesystem::path(exe).parent_path() / std::filesystem::u8path(relative);
}
#endif

}  // namespace

std::variant<CoverageBitmap, RenderError> render_text(const std::string& text, int width,
                                                    int height, double max_line_px,
                                                    const std::string& font_path) {
  std::ifstream in(font_path, std::ios::binary);
#ifdef _WIN32
  if (!in && std::filesystem::path(font_path).is_relative()) in.open(beside_executable(font_path), std::ios::binary);
#endif
#ifdef _WIN32
  constexpr const char* kHowToGetFont = " (it ships in the zip's fonts folder, beside curvlab.exe)";
#else
  constexpr const char* kHowToGetFont = " (apt-get install fonts-dejavu-core)";
#endif
  if (!in) return RenderError{RenderError::Kind::font, "cannot open font " + font_path + kHowToGetFont};
  const std::vector<unsigned char> font_data((std::istreambuf_iterator<char>(in)),
                                             std::istreambuf_iterator<char>());
  stbtt_fontinfo font;
  if (stbtt_InitFont(&font, font_data.data(), stbtt_GetFontOffsetForIndex(font_data.data(), 0)) ==
      0)
    return RenderError{RenderError::Kind::font, font_path + " is not a TrueType font"};

  std::vector<std::vector<int>> lines;
  std::istringstream ls(text);
  for (std::string line; std::getline(ls, line);) lines.push_back(decode_utf8(line));
  if (lines.empty()) lines.emplace_back();

  const int margin = std::max(2, height / 12);
  auto line_width = [&](const std::vector<int>& line, float scale) {
    int advance_sum = 0;
    for (std::size_t i = 0; i < line.size(); ++i) {
      int adv = 0;
      int lsb = 0;
      stbtt_GetCodepointHMetrics(&font, line[i], &adv, &lsb);
      advance_sum += adv;
      if (i + 1 < line.size()) advance_sum += stbtt_GetCodepointKernAdvance(&font, line[i], line[i + 1]);
    }
    return static_cast<float>(advance_sum) * scale;
  };
  // Largest pixel height that fits every line in width and all lines in height.
  double px = std::min(max_line_px, (height - 2.0 * margin) / (1.25 * static_cast<double>(lines.size())));
  for (; px > 4.0; px *= 0.95) {
    const float scale = stbtt_ScaleForPixelHeight(&font, static_cast<float>(px));
    bool fits = true;
    for (const auto& l : lines) fits = fits && line_width(l, scale) <= static_cast<float>(width - 2 * margin);
    if (fits) break;
  }
  const float scale = stbtt_ScaleForPixelHeight(&font, static_cast<float>(px));
  int ascent = 0;
  int descent = 0;
  int gap = 0;
  stbtt_GetFontVMetrics(&font, &ascent, &descent, &gap);
  const float line_h = static_cast<float>(ascent - descent + gap) * scale;

  CoverageBitmap bmp{width, height, std::vector<std::uint8_t>(static_cast<std::size_t>(width * height), 0)};
  const float block_h = line_h * static_cast<float>(lines.size());
  float baseline = (static_cast<float>(height) - block_h) / 2.0f + static_cast<float>(ascent) * scale;
  std::vector<std::uint8_t> glyph;
  for (const auto& line : lines) {
    float x = (static_cast<float>(width) - line_width(line, scale)) / 2.0f;
    for (std::size_t i = 0; i < line.size(); ++i) {
      int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
      stbtt_GetCodepointBitmapBox(&font, line[i], scale, scale, &x0, &y0, &x1, &y1);
      const int gw = x1 - x0;
      const int gh = y1 - y0;
      if (gw > 0 && gh > 0) {
        glyph.assign(static_cast<std::size_t>(gw * gh), 0);
        stbtt_MakeCodepointBitmap(&font, glyph.data(), gw, gh, gw, scale, scale, line[i]);
        const int ox = static_cast<int>(std::lround(x)) + x0;
        const int oy = static_cast<int>(std::lround(baseline)) + y0;
        for (int gy = 0; gy < gh; ++gy)
          for (int gx = 0; gx < gw; ++gx) {
            const int px_x = ox + gx;
            const int px_y = oy + gy;
            if (px_x < 0 || px_y < 0 || px_x >= width || px_y >= height) continue;
            auto& dst = bmp.pixels[static_cast<std::size_t>(px_y * width + px_x)];
            dst = std::max(dst, glyph[static_cast<std::size_t>(gy * gw + gx)]);
          }
      }
      int adv = 0;
      int lsb = 0;
      stbtt_GetCodepointHMetrics(&font, line[i], &adv, &lsb);
      x += static_cast<float>(adv) * scale;
      if (i + 1 < line.size())
        x += static_cast<float>(stbtt_GetCodepointKernAdvance(&font, line[i], line[i + 1])) * scale;
    }
    baseline += line_h;
  }
  return bmp;
}

}  // namespace curvlab::renderer
