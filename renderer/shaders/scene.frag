#version 460
// Shading: 0 lit surfaces, 1 unlit lines, 2 text panels (atlas in set 1).
layout(constant_id = 3) const int SHADING = 0;
// Text colours in linear RGB (the palette in colour.hpp); the target's sRGB
// encoding turns them back into the display values they were chosen as.
layout(constant_id = 4) const float INK_R = 1.0;
layout(constant_id = 5) const float INK_G = 1.0;
layout(constant_id = 6) const float INK_B = 1.0;
layout(constant_id = 7) const float PAPER_R = 0.0;
layout(constant_id = 8) const float PAPER_G = 0.0;
layout(constant_id = 9) const float PAPER_B = 0.0;

layout(set = 1, binding = 0) uniform sampler2D text_atlas;

layout(location = 0) in vec4 in_color;
layout(location = 1) in vec2 in_light;
layout(location = 0) out vec4 out_color;

void main() {
  if (SHADING == 1) {
    out_color = vec4(in_color.rgb, 1.0);
    return;
  }
  if (SHADING == 2) {
    // Text panels carry their atlas coordinates in the colour's xy.
    float coverage = texture(text_atlas, in_color.xy).r;
    out_color = vec4(mix(vec3(PAPER_R, PAPER_G, PAPER_B), vec3(INK_R, INK_G, INK_B), coverage), 1.0);
    return;
  }
  // Shading in linear light. A headlight (lights what faces the eye, two-sided) plus a soft key light
  // from the model's own "up", so shapes read in a headset without shadows.
  float head = abs(in_light.x);
  float key = 0.5 + 0.5 * clamp(in_light.y, -1.0, 1.0);
  float shade = 0.22 + 0.50 * head + 0.33 * key;
  out_color = vec4(in_color.rgb * shade, 1.0);
}
