#version 460
// Coverage and shading of a tube ribbon (tube.vert). Coverage is the exact
// fraction of the pixel's footprint (a 1 px box across the edge) inside the
// tube, across its width and along its length; colour joints are filtered the
// same way. The result is blended over what is behind it, so an edge's image
// position is carried by the pixel values to a small fraction of a pixel
// whatever the sample count.
layout(constant_id = 10) const float BUTT_R = 0.0;
layout(constant_id = 11) const float BUTT_G = 0.0;
layout(constant_id = 12) const float BUTT_B = 0.0;
layout(constant_id = 13) const float SHAFT_R = 0.0;
layout(constant_id = 14) const float SHAFT_G = 0.0;
layout(constant_id = 15) const float SHAFT_B = 0.0;
layout(constant_id = 16) const float TIP_R = 0.0;
layout(constant_id = 17) const float TIP_G = 0.0;
layout(constant_id = 18) const float TIP_B = 0.0;
layout(constant_id = 19) const float RING_R = 0.0;
layout(constant_id = 20) const float RING_G = 0.0;
layout(constant_id = 21) const float RING_B = 0.0;
// Ring centres as fractions of the length (mesh.hpp kStickRingFractions) and
// the bands' half-width in metres.
layout(constant_id = 22) const float RING_0 = -0.4;
layout(constant_id = 23) const float RING_1 = -0.2;
layout(constant_id = 24) const float RING_2 = 0.0;
layout(constant_id = 25) const float RING_3 = 0.2;
layout(constant_id = 26) const float RING_4 = 0.4;
layout(constant_id = 27) const float RING_HALF_M = 0.012;

layout(location = 0) noperspective in float in_across_px;
layout(location = 1) noperspective in float in_half_px;
layout(location = 2) in float in_u;
layout(location = 3) in vec3 in_light;
layout(location = 4) flat in vec4 in_design;
layout(location = 5) flat in vec4 in_tint;
layout(location = 0) out vec4 out_color;

// How much of the pixel interval [x − ½, x + ½] lies inside [lo, hi].
float covered(float x, float lo, float hi) {
  return clamp(min(x + 0.5, hi) - max(x - 0.5, lo), 0.0, 1.0);
}

void main() {
  float half_len = in_design.z;
  // Metres of centre line per pixel here.
  float m_per_px = max(length(vec2(dFdx(in_u), dFdy(in_u))), 1.0e-9);
  float x = in_u / m_per_px;
  float coverage = covered(in_across_px, -in_half_px, in_half_px) *
                   covered(x, -half_len / m_per_px, half_len / m_per_px);
  if (coverage <= 0.0) discard;

  // Wood: butt, then shaft from the joint, tip from its start; each joint
  // filtered over the pixel.
  vec3 butt = vec3(BUTT_R, BUTT_G, BUTT_B);
  vec3 shaft = vec3(SHAFT_R, SHAFT_G, SHAFT_B);
  vec3 tip = vec3(TIP_R, TIP_G, TIP_B);
  vec3 wood = mix(butt, shaft, covered(x, in_design.x / m_per_px, 1.0e30));
  wood = mix(wood, tip, covered(x, in_design.y / m_per_px, 1.0e30));
  if (in_design.w > 0.5) {
    float len = 2.0 * half_len;
    float w = 0.0;
    for (int i = 0; i < 5; ++i) {
      float f = i == 0 ? RING_0 : i == 1 ? RING_1 : i == 2 ? RING_2 : i == 3 ? RING_3 : RING_4;
      w = max(w, 1.0 - abs(in_u - f * len) / RING_HALF_M);
    }
    wood = mix(wood, vec3(RING_R, RING_G, RING_B), w);
  }

  // The cylinder's normal at this pixel: q across the silhouette direction,
  // sqrt(1 − q²) toward the viewer; lit as scene.frag lights a surface.
  float q = clamp(in_across_px / max(in_half_px, 1.0e-6), -1.0, 1.0);
  float facing = sqrt(1.0 - q * q);
  float head = facing * in_light.x;
  float key = 0.5 + 0.5 * clamp(q * in_light.y + facing * in_light.z, -1.0, 1.0);
  float shade = 0.22 + 0.50 * head + 0.33 * key;
  out_color = vec4(wood * shade * in_tint.rgb, coverage * in_tint.a);
}
