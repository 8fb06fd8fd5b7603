// Text for instruction and prompt panels: participants in a headset cannot see
// a monitor. Lines are rasterised with stb_truetype into a coverage bitmap
// that a panel samples.
#pragma once

#include "curvlab/renderer/error.hpp"

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace curvlab::renderer {

struct CoverageBitmap {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // row major, 0 = background, 255 = ink
};

// Lays out `text` ('\n' separates lines), centred, in a bitmap of the given
// size with a margin, at the largest pixel height ≤ max_line_px that fits.
// font_path: a TrueType file (default: DejaVu Sans from fonts-dejavu-core).
std::variant<CoverageBitmap, RenderError> render_text(const std::string& text, int width, int height,
                                                      double max_line_px, const std::string& font_path);

// Text at a fixed size for a panel that is sized to it (head-locked panels,
// scene.hpp): line_px is a line's pixel height (ascent to descent), lines
// longer than max_width_px are broken at spaces, every line is centred, and
// the bitmap is as wide as the widest line (at least a third of
// max_width_px) and as tall as the lines, each plus a margin of 0.6 lines.
struct TextBlock {
  CoverageBitmap bitmap;
  int lines = 0;
  double cap_height_px = 0.0;  // a capital letter's height at this size
};
std::variant<TextBlock, RenderError> render_text_block(const std::string& text, double line_px, int max_width_px,
                                                      const std::string& font_path);

}  // namespace curvlab::renderer
