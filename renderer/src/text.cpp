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
#include <memory>
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

namespace {

// A TrueType font read into memory; `info` points into `data`.
struct Font {
  std::vector<unsigned char> data;
  stbtt_fontinfo info{};
  int ascent = 0, descent = 0, gap = 0;  // font units
};

std::variant<std::unique_ptr<Font>, RenderError> load_font(const std::string& font_path) {
  std::ifstream in(font_path, std::ios::binary);
#ifdef _WIN32
  if (!in && std::filesystem::path(font_path).is_relative()) in.open(beside_executable(font_path), std::ios::binary);
  constexpr const char* kHowToGetFont = " (it ships in the zip's fonts folder, beside curvlab.exe)";
#else
  constexpr const char* kHowToGetFont = " (apt-get install fonts-dejavu-core)";
#endif
  if (!in) return RenderError{RenderError::Kind::font, "cannot open font " + font_path + kHowToGetFont};
  std::vector<unsigned char> data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto font = std::make_unique<Font>();
  font->data = std::move(data);
  if (stbtt_InitFont(&font->info, font->data.data(), stbtt_GetFontOffsetForIndex(font->data.data(), 0)) == 0)
    return RenderError{RenderError::Kind::font, font_path + " is not a TrueType font"};
  stbtt_GetFontVMetrics(&font->info, &font->ascent, &font->descent, &font->gap);
  return font;
}

using Line = std::vector<int>;  // code points

std::vector<Line> split_lines(const std::string& text) {
  std::vector<Line> lines;
  std::istringstream ls(text);
  for (std::string line; std::getline(ls, line);) lines.push_back(decode_utf8(line));
  if (lines.empty()) lines.emplace_back();
  return lines;
}

float line_width(const Font& font, const Line& line, float scale) {
  int advance_sum = 0;
  for (std::size_t i = 0; i < line.size(); ++i) {
    int adv = 0;
    int lsb = 0;
    stbtt_GetCodepointHMetrics(&font.info, line[i], &adv, &lsb);
    advance_sum += adv;
    if (i + 1 < line.size()) advance_sum += stbtt_GetCodepointKernAdvance(&font.info, line[i], line[i + 1]);
  }
  return static_cast<float>(advance_sum) * scale;
}

// The height of a capital (the H's box) as a fraction of the pixel height
// stb_truetype scales to (ascent to descent).
double cap_height_fraction(const Font& font) {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  if (stbtt_GetCodepointBox(&font.info, 'H', &x0, &y0, &x1, &y1) == 0) return 0.7;
  return static_cast<double>(y1) / static_cast<double>(font.ascent - font.descent);
}

// Lines broken at spaces so that none is wider than `width` pixels (a
// single word wider than that stays whole).
std::vector<Line> wrap(const Font& font, const std::vector<Line>& lines, float scale, float width) {
  std::vector<Line> out;
  for (const Line& line : lines) {
    Line current;
    std::size_t i = 0;
    while (i < line.size()) {
      std::size_t gap_end = i;  // the spaces before the word, kept within a line
      while (gap_end < line.size() && line[gap_end] == ' ') ++gap_end;
      std::size_t j = gap_end;
      while (j < line.size() && line[j] != ' ') ++j;
      Line candidate = current;
      candidate.insert(candidate.end(), line.begin() + static_cast<std::ptrdiff_t>(i),
                       line.begin() + static_cast<std::ptrdiff_t>(j));
      if (!current.empty() && line_width(font, candidate, scale) > width) {
        out.push_back(std::move(current));
        current.assign(line.begin() + static_cast<std::ptrdiff_t>(gap_end), line.begin() + static_cast<std::ptrdiff_t>(j));
      } else {
        current = std::move(candidate);
      }
      i = j;
    }
    out.push_back(std::move(current));
  }
  return out;
}

// Draws the lines centred in the bitmap at `scale`, the block centred vertically.
void draw_lines(const Font& font, const std::vector<Line>& lines, float scale, CoverageBitmap& bmp) {
  const float line_h = static_cast<float>(font.ascent - font.descent + font.gap) * scale;
  const float block_h = line_h * static_cast<float>(lines.size());
  float baseline = (static_cast<float>(bmp.height) - block_h) / 2.0f + static_cast<float>(font.ascent) * scale;
  std::vector<std::uint8_t> glyph;
  for (const auto& line : lines) {
    float x = (static_cast<float>(bmp.width) - line_width(font, line, scale)) / 2.0f;
    for (std::size_t i = 0; i < line.size(); ++i) {
      int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
      stbtt_GetCodepointBitmapBox(&font.info, line[i], scale, scale, &x0, &y0, &x1, &y1);
      const int gw = x1 - x0;
      const int gh = y1 - y0;
      if (gw > 0 && gh > 0) {
        glyph.assign(static_cast<std::size_t>(gw * gh), 0);
        stbtt_MakeCodepointBitmap(&font.info, glyph.data(), gw, gh, gw, scale, scale, line[i]);
        const int ox = static_cast<int>(std::lround(x)) + x0;
        const int oy = static_cast<int>(std::lround(baseline)) + y0;
        for (int gy = 0; gy < gh; ++gy)
          for (int gx = 0; gx < gw; ++gx) {
            const int px_x = ox + gx;
            const int px_y = oy + gy;
            if (px_x < 0 || px_y < 0 || px_x >= bmp.width || px_y >= bmp.height) continue;
            auto& dst = bmp.pixels[static_cast<std::size_t>(px_y * bmp.width + px_x)];
            dst = std::max(dst, glyph[static_cast<std::size_t>(gy * gw + gx)]);
          }
      }
      int adv = 0;
      int lsb = 0;
      stbtt_GetCodepointHMetrics(&font.info, line[i], &adv, &lsb);
      x += static_cast<float>(adv) * scale;
      if (i + 1 < line.size())
        x += static_cast<float>(stbtt_GetCodepointKernAdvance(&font.info, line[i], line[i + 1])) * scale;
    }
    baseline += line_h;
  }
}

}  // namespace

std::variant<CoverageBitmap, RenderError> render_text(const std::string& text, int width,
                                                    int height, double max_line_px,
                                                    const std::string& font_path) {
  auto loaded = load_font(font_path);
  if (auto* e = std::get_if<RenderError>(&loaded)) return *e;
  const Font& font = *std::get<std::unique_ptr<Font>>(loaded);
  const std::vector<Line> lines = split_lines(text);
  const int margin = std::max(2, height / 12);
  // Largest pixel height that fits every line in width and all lines in height.
  double px = std::min(max_line_px, (height - 2.0 * margin) / (1.25 * static_cast<double>(lines.size())));
  for (; px > 4.0; px *= 0.95) {
    const float scale = stbtt_ScaleForPixelHeight(&font.info, static_cast<float>(px));
    bool fits = true;
    for (const auto& l : lines) fits = fits && line_width(font, l, scale) <= static_cast<float>(width - 2 * margin);
    if (fits) break;
  }
  CoverageBitmap bmp{width, height, std::vector<std::uint8_t>(static_cast<std::size_t>(width * height), 0)};
  draw_lines(font, lines, stbtt_ScaleForPixelHeight(&font.info, static_cast<float>(px)), bmp);
  return bmp;
}

std::variant<TextBlock, RenderError> render_text_block(const std::string& text, double line_px, int max_width_px,
                                                      const std::string& font_path) {
  auto loaded = load_font(font_path);
  if (auto* e = std::get_if<RenderError>(&loaded)) return *e;
  const Font& font = *std::get<std::unique_ptr<Font>>(loaded);
  const float scale = stbtt_ScaleForPixelHeight(&font.info, static_cast<float>(line_px));
  const int margin = std::max(2, static_cast<int>(std::lround(0.6 * line_px)));
  const std::vector<Line> lines =
      wrap(font, split_lines(text), scale, static_cast<float>(max_width_px - 2 * margin));
  float widest = 0.0f;
  for (const auto& l : lines) widest = std::max(widest, line_width(font, l, scale));
  const float line_h = static_cast<float>(font.ascent - font.descent + font.gap) * scale;
  TextBlock block;
  block.lines = static_cast<int>(lines.size());
  block.cap_height_px = line_px * cap_height_fraction(font);
  CoverageBitmap& bmp = block.bitmap;
  bmp.width = std::max(max_width_px / 3, static_cast<int>(std::ceil(widest)) + 2 * margin);
  bmp.height = static_cast<int>(std::ceil(line_h * static_cast<float>(lines.size()))) + 2 * margin;
  bmp.pixels.assign(static_cast<std::size_t>(bmp.width * bmp.height), 0);
  draw_lines(font, lines, scale, bmp);
  return block;
}

}  // namespace curvlab::renderer
