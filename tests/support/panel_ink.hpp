// The ink of a text panel in an eye image (rendered, or captured from a
// headset's compositor): the panel is the box of pixels in the panel's
// paper colour, its ink the pixels inside that are nearer the ink's colour
// than the paper's (renderer::palette).
#pragma once

#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/image_io.hpp"

#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace curvlab::test {

struct PanelInk {
  int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // the panel's box, inclusive
  std::vector<std::uint8_t> ink;          // row major over the box
  [[nodiscard]] int width() const { return x1 - x0 + 1; }
  [[nodiscard]] int height() const { return y1 - y0 + 1; }
  [[nodiscard]] bool at(int x, int y) const { return ink[static_cast<std::size_t>(y * width() + x)] != 0; }
};

inline PanelInk find_panel(const renderer::Rgba8Image& img) {
  auto to_display = [](const glm::vec4& c) {
    return glm::dvec3(renderer::linear_to_srgb(c.x), renderer::linear_to_srgb(c.y), renderer::linear_to_srgb(c.z));
  };
  const glm::dvec3 paper = to_display(renderer::palette::text_paper);
  const glm::dvec3 ink = to_display(renderer::palette::text_ink);
  auto channel = [&](int x, int y, int c) {
    return static_cast<double>(img.pixels[static_cast<std::size_t>((y * img.width + x) * 4 + c)]) / 255.0;
  };
  PanelInk p{img.width, img.height, -1, -1, {}};
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      bool is_paper = true;
      for (int c = 0; c < 3; ++c) is_paper = is_paper && std::abs(channel(x, y, c) - paper[c]) < 1.5 / 255.0;
      if (!is_paper) continue;
      p.x0 = std::min(p.x0, x), p.y0 = std::min(p.y0, y), p.x1 = std::max(p.x1, x), p.y1 = std::max(p.y1, y);
    }
  if (p.x1 < p.x0) return p;
  const double mid = 0.5 * (paper.y + ink.y);
  for (int y = p.y0; y <= p.y1; ++y)
    for (int x = p.x0; x <= p.x1; ++x) p.ink.push_back(channel(x, y, 1) > mid ? 1 : 0);
  return p;
}

// The rows of the panel's first line of text: the first run of rows with ink.
inline std::pair<int, int> first_line_rows(const PanelInk& p) {
  int first = -1;
  for (int y = 0; y < p.height(); ++y) {
    bool any = false;
    for (int x = 0; x < p.width(); ++x) any = any || p.at(x, y);
    if (any && first < 0) first = y;
    if (!any && first >= 0) return {first, y - 1};
  }
  return {first, p.height() - 1};
}

// The ink in column x over rows [top, bottom], and the first and last
// columns with ink there.
inline int column_ink(const PanelInk& p, int x, int top, int bottom) {
  int n = 0;
  for (int y = top; y <= bottom; ++y) n += p.at(x, y) ? 1 : 0;
  return n;
}
inline std::pair<int, int> ink_columns(const PanelInk& p, int top, int bottom) {
  int first = -1, last = -1;
  for (int x = 0; x < p.width(); ++x)
    if (column_ink(p, x, top, bottom) > 0) {
      if (first < 0) first = x;
      last = x;
    }
  return {first, last};
}

}  // namespace curvlab::test
