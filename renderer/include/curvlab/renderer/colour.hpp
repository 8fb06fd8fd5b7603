// Colour in linear light. The renderer shades in linear RGB and writes sRGB
// targets, whose hardware encoding applies the sRGB transfer function
// (IEC 61966-2-1). Stimulus colours were chosen as display values (what an
// sRGB monitor shows for the byte value / 255); display() turns such a value
// into the linear value the shaders need, so unshaded surfaces keep their look.
#pragma once

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cmath>

namespace curvlab::renderer {

// sRGB decoding of one channel, 0–1 (IEC 61966-2-1).
inline float srgb_to_linear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}
// sRGB encoding of one channel, 0–1.
inline float linear_to_srgb(float v) {
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

// A colour given as display values (sRGB-encoded), as linear RGBA; alpha is
// kept.
inline glm::vec4 display(float r, float g, float b, float a = 1.0f) {
  return {srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b), a};
}

// Relative luminance Y (0–1) of a linear sRGB colour (Rec. 709 primaries, D65;
// IEC 61966-2-1).
inline double relative_luminance(const glm::vec3& linear) {
  return 0.2126 * double(linear.x) + 0.7152 * double(linear.y) + 0.0722 * double(linear.z);
}

// The stimulus palette, linear RGBA (docs/renderer.md lists the relative
// luminance of each). Authored as display values; ball colours are chosen where balls are built.
namespace palette {
inline const glm::vec4 background = display(0.015f, 0.017f, 0.03f);  // the void
inline const glm::vec4 cloth = display(0.10f, 0.42f, 0.20f);
inline const glm::vec4 cushion = display(0.08f, 0.34f, 0.16f);
inline const glm::vec4 rail = display(0.45f, 0.26f, 0.12f);
inline const glm::vec4 skirt = display(0.30f, 0.17f, 0.08f);
inline const glm::vec4 stick_butt = display(0.22f, 0.10f, 0.05f);
inline const glm::vec4 stick_shaft = display(0.85f, 0.66f, 0.40f);
inline const glm::vec4 stick_tip = display(0.9f, 0.9f, 0.88f);
// The marked stick's rings (stimulus.stick_marks = "rings"), blended into the
// wood in linear light along each ring's tent profile.
inline const glm::vec4 stick_ring = display(0.95f, 0.95f, 0.92f);
inline const glm::vec4 text_ink = display(0.96f, 0.96f, 0.92f);
inline const glm::vec4 text_paper = display(0.06f, 0.07f, 0.10f);
}  // namespace palette

}  // namespace curvlab::renderer
