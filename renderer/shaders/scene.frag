#version 460
// Shading: 0 lit surfaces, 1 unlit lines, 2 text panels (atlas in set 1).
layout(constant_id = 3) const int SHADING = 0;

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
    out_color = vec4(mix(vec3(0.06, 0.07, 0.10), vec3(0.96, 0.96, 0.92), coverage), 1.0);
    return;
  }
  // A headlight (lights what faces the eye, two-sided) plus a soft key light
  // from the model's own "up", so shapes read in a headset without shadows.
  float head = abs(in_light.x);
  float key = 0.5 + 0.5 * clamp(in_light.y, -1.0, 1.0);
  float shade = 0.22 + 0.50 * head + 0.33 * key;
  out_color = vec4(in_color.rgb * shade, 1.0);
}
