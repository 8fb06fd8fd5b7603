// Finding the stick and its rings in one eye's image (stick.hpp). The stick
// is the widest connected region that differs from the background (the
// colour most common on the image border); each ring is located by the
// brightness it adds to the wood, row by row across the stick, as the
// centroid of that excess: a coverage-weighted centroid of a smooth profile,
// so its precision does not depend on where pixel centres fall.
#include "curvlab/harness/measure/stick.hpp"
#include "curvlab/renderer/colour.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>

namespace curvlab::harness::measure {
namespace {

using renderer::Rgba8Image;

Error bad(std::string m) { return Error{Error::Kind::bad_input, std::move(m)}; }

std::uint32_t pixel(const Rgba8Image& img, int x, int y) {
  const auto* p = &img.pixels[(static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) +
                               static_cast<std::size_t>(x)) * 4];
  return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16;
}

double brightness(const Rgba8Image& img, int x, int y) {
  const auto* p = &img.pixels[(static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) +
                               static_cast<std::size_t>(x)) * 4];
  return double(p[0]) + double(p[1]) + double(p[2]);
}

// The light a pixel carries, in linear light (the images are sRGB): the
// ring's tent profile is a tent here, falling to the wood's level without a
// step. The sRGB values of its feet jump by a third of the peak within a
// pixel, so a centroid of sRGB values moves with where the feet fall between
// pixel centres — by a tenth of a pixel, differently in each eye.
double linear_light(const Rgba8Image& img, int x, int y) {
  const auto* p = &img.pixels[(static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) +
                               static_cast<std::size_t>(x)) * 4];
  double sum = 0.0;
  for (int c = 0; c < 3; ++c) sum += double(renderer::srgb_to_linear(float(p[c]) / 255.0f));
  return sum;
}

std::uint32_t border_colour(const Rgba8Image& img) {
  std::map<std::uint32_t, int> count;
  for (int x = 0; x < img.width; ++x) {
    ++count[pixel(img, x, 0)];
    ++count[pixel(img, x, img.height - 1)];
  }
  for (int y = 0; y < img.height; ++y) {
    ++count[pixel(img, 0, y)];
    ++count[pixel(img, img.width - 1, y)];
  }
  return std::max_element(count.begin(), count.end(),
                          [](const auto& a, const auto& b) { return a.second < b.second; })->first;
}

bool differs(std::uint32_t a, std::uint32_t b) {
  for (int c = 0; c < 3; ++c) {
    const int da = int((a >> (8 * c)) & 0xffu) - int((b >> (8 * c)) & 0xffu);
    if (std::abs(da) > 6) return true;
  }
  return false;
}


constexpr std::array<std::pair<int, int>, 4> kSteps{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};

// 4-connected regions of pixels that differ from the background: a label
// per pixel (0 background) and the label of the widest region (0 if none).
struct Regions {
  std::vector<int> label;
  int widest = 0;
  int widest_extent = 0;
};

Regions label_regions(const Rgba8Image& img, std::uint32_t bg) {
  const auto w = static_cast<std::size_t>(img.width);
  const auto index = [w](int x, int y) { return static_cast<std::size_t>(y) * w + static_cast<std::size_t>(x); };
  Regions r;
  r.label.assign(w * static_cast<std::size_t>(img.height), 0);
  int next = 0;
  std::vector<std::pair<int, int>> stack;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      if (r.label[index(x, y)] || !differs(pixel(img, x, y), bg)) continue;
      r.label[index(x, y)] = ++next;
      int lo = x, hi = x;
      stack.assign(1, {x, y});
      while (!stack.empty()) {
        const auto [cx, cy] = stack.back();
        stack.pop_back();
        lo = std::min(lo, cx);
        hi = std::max(hi, cx);
        for (const auto& [dx, dy] : kSteps) {
          const int nx = cx + dx, ny = cy + dy;
          if (nx < 0 || ny < 0 || nx >= img.width || ny >= img.height) continue;
          if (r.label[index(nx, ny)] || !differs(pixel(img, nx, ny), bg)) continue;
          r.label[index(nx, ny)] = next;
          stack.push_back({nx, ny});
        }
      }
      if (hi - lo > r.widest_extent) {
        r.widest_extent = hi - lo;
        r.widest = next;
      }
    }
  return r;
}

std::optional<StickMask> stick_mask(const Rgba8Image& img) {
  const std::uint32_t bg = border_colour(img);
  const Regions regions = label_regions(img, bg);
  if (regions.widest == 0 || regions.widest_extent < 20) return std::nullopt;
  StickMask m;
  m.width = img.width;
  m.background = bg;
  m.inside.assign(regions.label.size(), 0);
  m.x0 = img.width;
  for (std::size_t i = 0; i < regions.label.size(); ++i)
    if (regions.label[i] == regions.widest) {
      m.inside[i] = 1;
      const int x = static_cast<int>(i % static_cast<std::size_t>(img.width));
      m.x0 = std::min(m.x0, x);
      m.x1 = std::max(m.x1, x);
    }
  const auto n = static_cast<std::size_t>(m.x1 - m.x0 + 1);
  m.top.assign(n, -1);
  m.bottom.assign(n, -1);
  for (int y = 0; y < img.height; ++y)
    for (int x = m.x0; x <= m.x1; ++x)
      if (m.at(x, y)) {
        auto& t = m.top[static_cast<std::size_t>(x - m.x0)];
        if (t < 0) t = y;
        m.bottom[static_cast<std::size_t>(x - m.x0)] = y;
      }
  return m;
}

// Light above the background, in linear light (the images are sRGB).
double excess_over(const Rgba8Image& img, int x, int y, std::uint32_t bg) {
  const std::uint32_t p = pixel(img, x, y);
  double sum = 0.0;
  for (int c = 0; c < 3; ++c)
    sum += double(renderer::srgb_to_linear(float((p >> (8 * c)) & 0xffu) / 255.0f)) -
           double(renderer::srgb_to_linear(float((bg >> (8 * c)) & 0xffu) / 255.0f));
  return sum;
}

// An anti-aliased outline has partly covered pixels on both sides: a column's
// first and last rows count only when at least half covered (their light
// above the background at least half their inner neighbour's), the rule a
// single-sample rasterizer applies at the pixel centre, so that the outline's
// thickness and midline do not depend on the sample count.
void drop_partial_outline(const Rgba8Image& img, StickMask& m) {
  const std::uint32_t bg = m.background;
  for (int x = m.x0; x <= m.x1; ++x) {
    const auto i = static_cast<std::size_t>(x - m.x0);
    int& top = m.top[i];
    int& bottom = m.bottom[i];
    if (top < 0 || bottom - top < 4) continue;
    if (excess_over(img, x, top, bg) < 0.5 * excess_over(img, x, top + 1, bg)) ++top;
    if (excess_over(img, x, bottom, bg) < 0.5 * excess_over(img, x, bottom - 1, bg)) --bottom;
  }
}

// Least-squares polynomials (degree 3) of the stick's midline row and half
// thickness against the column: the outline is quantized per column, the
// fit over hundreds of columns is not.
enum class Outline { midline, half_thickness };
struct Cubic {
  double centre = 0.0, scale = 1.0;
  std::array<double, 4> c{};
  [[nodiscard]] double at(double x) const {
    const double t = (x - centre) / scale;
    return c[0] + t * (c[1] + t * (c[2] + t * c[3]));
  }
};

Cubic fit_outline(const StickMask& m, Outline what) {
  Cubic f;
  f.centre = 0.5 * (m.x0 + m.x1 + 1);
  f.scale = std::max(1.0, 0.5 * (m.x1 - m.x0 + 1));
  std::array<std::array<double, 5>, 4> a{};  // normal equations, augmented
  for (int x = m.x0; x <= m.x1; ++x) {
    const auto i = static_cast<std::size_t>(x - m.x0);
    if (m.top[i] < 0 || m.bottom[i] - m.top[i] < 2) continue;
    const double t = (x + 0.5 - f.centre) / f.scale;
    const double v = what == Outline::midline ? 0.5 * (m.top[i] + m.bottom[i] + 1)
                                              : 0.5 * (m.bottom[i] - m.top[i] + 1);
    const std::array<double, 4> p{1.0, t, t * t, t * t * t};
    for (std::size_t r = 0; r < 4; ++r) {
      for (std::size_t c = 0; c < 4; ++c) a[r][c] += p[r] * p[c];
      a[r][4] += p[r] * v;
    }
  }
  for (std::size_t k = 0; k < 4; ++k) {  // Gauss–Jordan; the matrix is positive definite
    if (std::abs(a[k][k]) < 1e-12) return f;
    for (std::size_t r = 0; r < 4; ++r) {
      if (r == k) continue;
      const double q = a[r][k] / a[k][k];
      for (std::size_t c = k; c < 5; ++c) a[r][c] -= q * a[k][c];
    }
  }
  for (std::size_t k = 0; k < 4; ++k) f.c[k] = a[k][4] / a[k][k];
  return f;
}

// Mean brightness of the stick's inner rows in each column (the silhouette
// rows, partly covered, left out).
std::vector<double> column_profile(const Rgba8Image& img, const StickMask& m) {
  std::vector<double> p(m.top.size(), 0.0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    double sum = 0.0;
    int n = 0;
    const int x = m.x0 + static_cast<int>(i);
    for (int y = m.top[i] + 1; m.top[i] >= 0 && y < m.bottom[i]; ++y)
      if (m.at(x, y)) {
        sum += brightness(img, x, y);
        ++n;
      }
    p[i] = n > 0 ? sum / n : 0.0;
  }
  return p;
}

// The rings' half-width in pixels at each column: the stick's half
// thickness there, scaled by the ring's half-width over the stick's radius
// (both lie across the line of sight at the same depth).
std::vector<double> ring_half_widths(const StickMask& m, double rings_per_radius) {
  std::vector<double> h(m.top.size(), 0.0);
  for (std::size_t i = 0; i < h.size(); ++i)
    if (m.top[i] >= 0) h[i] = 0.5 * (m.bottom[i] - m.top[i] + 1) * rings_per_radius;
  return h;
}

// The rings' columns, left to right: the `count` strongest local maxima of
// the profile's excess over the mean two half-widths to either side (zero on
// a linear ramp, so the butt-to-shaft transition does not count as a ring),
// more than four half-widths from the stick's ends in the image (the white
// tip and the end caps are not rings; no ring lies that close to an end).
std::vector<int> ring_columns(const std::vector<double>& p, const std::vector<double>& half_px, std::size_t count) {
  const int n = static_cast<int>(p.size());
  std::vector<double> excess(p.size(), 0.0);
  for (int i = 0; i < n; ++i) {
    const int reach = static_cast<int>(std::ceil(2.0 * half_px[static_cast<std::size_t>(i)]));
    if (reach < 1 || i - 2 * reach < 0 || i + 2 * reach >= n) continue;
    const auto at = [&](int k) { return p[static_cast<std::size_t>(k)]; };
    excess[static_cast<std::size_t>(i)] = at(i) - 0.5 * (at(i - reach) + at(i + reach));
  }
  std::vector<std::pair<double, int>> peaks;
  for (int i = 0; i < n; ++i) {
    const double e = excess[static_cast<std::size_t>(i)];
    const int reach = static_cast<int>(std::ceil(2.0 * half_px[static_cast<std::size_t>(i)]));
    bool top = e >= 12.0;  // under ~4 levels per channel: no ring
    for (int k = std::max(0, i - reach); top && k <= std::min(n - 1, i + reach); ++k)
      top = excess[static_cast<std::size_t>(k)] < e || (excess[static_cast<std::size_t>(k)] == e && k >= i);
    if (top) peaks.push_back({e, i});
  }
  std::sort(peaks.begin(), peaks.end(), std::greater<>());
  std::vector<int> out;
  for (std::size_t k = 0; k < std::min(count, peaks.size()); ++k) out.push_back(peaks[k].second);
  std::sort(out.begin(), out.end());
  return out;
}

// The ring's column position: in every row that crosses the whole window
// inside the stick, the centroid of the light (linear) above the line
// through the window's two ends. A row crosses the stick's visible half at
// sin α = (row − axis) / radius, on the ring's point at depth cos α (radii)
// in front of the centre line; seen obliquely, nearer points of the ring lie
// further out along the stick's image, and seen from above or below, the
// ring's image leans (its upper and lower points lie at different depths).
// The column is fitted over the rows as a + k cos α + l sin α (least
// squares) and reported at the rows' mean cos α and at the midline (sin α =
// 0), with k, so that the two eyes can be compared at the same depth on the
// ring: a plain mean over rows moves with which rows each eye happens to
// hold (one row more in one eye shifts the disparity of an outer ring by up
// to 0.2 px, 5 mm of depth at a metre).
std::optional<RingSighting> refine_ring(const Rgba8Image& img, const StickMask& m, const Cubic& mid,
                                        const Cubic& thickness, double centre_x, double half_px) {
  const int a = static_cast<int>(std::floor(centre_x - 1.7 * half_px));
  const int b = static_cast<int>(std::ceil(centre_x + 1.7 * half_px));
  const int foot = std::max(1, static_cast<int>(0.3 * half_px));
  if (a < m.x0 || b > m.x1) return std::nullopt;
  int y0 = 0, y1 = img.height;
  for (int x = a; x <= b; ++x) {
    const auto i = static_cast<std::size_t>(x - m.x0);
    if (m.top[i] < 0) return std::nullopt;
    y0 = std::max(y0, m.top[i] + 1);
    y1 = std::min(y1, m.bottom[i]);
  }
  const double half_height = thickness.at(centre_x);
  const double centre_y = mid.at(centre_x);
  // Normal equations of the fit in (1, cos α, sin α), augmented.
  std::array<std::array<double, 4>, 3> n{};
  double depth = 0.0;
  int rows = 0;
  for (int y = y0; y < y1; ++y) {
    double left = 0.0, right = 0.0;
    for (int k = 0; k < foot; ++k) {
      left += linear_light(img, a + k, y);
      right += linear_light(img, b - k, y);
    }
    left /= foot;
    right /= foot;
    const double xl = a + 0.5 * foot, xr = b + 1.0 - 0.5 * foot;
    double w_sum = 0.0, wx_sum = 0.0;
    for (int x = a; x <= b; ++x) {
      const double xc = x + 0.5;
      const double base = left + (right - left) * (xc - xl) / (xr - xl);
      const double w = std::max(0.0, linear_light(img, x, y) - base);
      w_sum += w;
      wx_sum += w * xc;
    }
    if (w_sum <= 0.0) continue;
    const double sine = std::clamp((y + 0.5 - centre_y) / half_height, -1.0, 1.0);
    const double cosine = std::sqrt(1.0 - sine * sine);
    const std::array<double, 3> basis{1.0, cosine, sine};
    for (std::size_t r = 0; r < 3; ++r) {
      for (std::size_t c = 0; c < 3; ++c) n[r][c] += basis[r] * basis[c];
      n[r][3] += basis[r] * (wx_sum / w_sum);
    }
    depth += cosine;
    ++rows;
  }
  if (rows < 2) return std::nullopt;
  depth /= rows;
  const double mean_x = n[0][3] / rows;
  RingSighting ring{{mean_x, mid.at(mean_x)}, rows, depth, half_height};
  // Too few rows, or rows all at one depth, to separate the three terms:
  // the plain mean, as it is.
  if (rows < 4) return ring;
  auto q = n;
  for (std::size_t k = 0; k < 3; ++k) {  // Gauss–Jordan; the matrix is positive semi-definite
    if (std::abs(q[k][k]) < 1e-9 * rows) return ring;
    for (std::size_t r = 0; r < 3; ++r) {
      if (r == k) continue;
      const double f = q[r][k] / q[k][k];
      for (std::size_t c = k; c < 4; ++c) q[r][c] -= f * q[k][c];
    }
  }
  const double a0 = q[0][3] / q[0][0], k_px = q[1][3] / q[1][1];
  const double x = a0 + k_px * depth;
  ring.px = {x, mid.at(x)};
  ring.px_per_depth_radius = k_px;
  return ring;
}

}  // namespace

std::optional<StickMask> find_stick(const renderer::Rgba8Image& image) {
  if (image.width < 8 || image.height < 8) return std::nullopt;
  auto mask = stick_mask(image);
  if (mask) drop_partial_outline(image, *mask);
  return mask;
}

Result<std::vector<RingSighting>> find_rings(const renderer::Rgba8Image& image, const StickMask& stick,
                                             double stick_radius_m) {
  const auto half_px = ring_half_widths(stick, renderer::kStickRingHalfWidthM / stick_radius_m);
  const auto profile = column_profile(image, stick);
  const Cubic mid = fit_outline(stick, Outline::midline);
  const Cubic thickness = fit_outline(stick, Outline::half_thickness);
  const std::size_t count = renderer::kStickRingFractions.size();
  const auto columns = ring_columns(profile, half_px, count);
  if (columns.size() < count)
    return bad("found " + std::to_string(columns.size()) + " of the stick's " + std::to_string(count) +
               " rings (is the stick marked, and are all its rings in view?)");
  std::vector<RingSighting> out;
  for (std::size_t k = 0; k < count; ++k) {
    const auto c = static_cast<std::size_t>(columns[k]);
    if (half_px[c] < 1.5)
      return bad("a ring is " + std::to_string(2.0 * half_px[c]) +
                 " px wide; at least 3 px are needed (a larger image or a narrower field of view)");
    const auto ring = refine_ring(image, stick, mid, thickness, stick.x0 + columns[k] + 0.5, half_px[c]);
    if (!ring) return bad("ring " + std::to_string(k + 1) + " is cut by the stick's outline or the image border");
    out.push_back(*ring);
  }
  return out;
}

}  // namespace curvlab::harness::measure
