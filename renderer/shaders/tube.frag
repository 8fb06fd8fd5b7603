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
layout(location = 6) in vec4 in_circle;
layout(location = 7) in vec2 in_circle_w;

// The offset along the projected centre line of the circle's point at angle
// phi (0: toward the viewer), exact in perspective: the circle's points are
// linear in clip coordinates.
float along_at(float phi) {
  float cp = cos(phi), sp = sin(phi);
  return (cp * in_circle.x * in_circle_w.x + sp * in_circle.y * in_circle_w.y) /
         (1.0 + cp * (in_circle_w.x - 1.0) + sp * (in_circle_w.y - 1.0));
}
layout(location = 0) out vec4 out_color;

// How much of the pixel interval [x − ½, x + ½] lies inside [lo, hi].
float covered(float x, float lo, float hi) {
  return clamp(min(x + 0.5, hi) - max(x - 0.5, lo), 0.0, 1.0);
}

void main() {
  float half_len = in_design.z;
  // The cylinder's normal at this pixel: q across the silhouette direction,
  // sqrt(1 − q²) toward the viewer.
  float q = clamp(in_across_px / max(in_half_px, 1.0e-6), -1.0, 1.0);
  float facing = sqrt(1.0 - q * q);
  // Metres of centre line per pixel here.
  float m_per_px = max(length(vec2(dFdx(in_u), dFdy(in_u))), 1.0e-9);
  float x = in_u / m_per_px;
  // The surface shown here: the circle's points whose image lies at this
  // pixel's distance across the centre line, X = across(phi), solved exactly
  // (a cos phi + b sin phi = X): one on the front half, one on the back.
  float X = in_across_px;
  float a = in_circle.z * in_circle_w.x - X * (in_circle_w.x - 1.0);
  float b = in_circle.w * in_circle_w.y - X * (in_circle_w.y - 1.0);
  float phase = atan(a, b);
  float s_phi = asin(clamp(X / max(length(vec2(a, b)), 1.0e-6), -1.0, 1.0));
  float offset_front = along_at(s_phi - phase);
  float offset_back = along_at(3.14159265 - s_phi - phase);
  // The shown point's distance along the centre line.
  float u_surface = in_u - offset_front * m_per_px;
  // Each end shows the far side of its rim: the front rim where the end
  // face is turned away, the back rim (the face's outline) where it faces
  // the viewer; in both cases the rim point furthest out.
  float reach_tip = max(offset_front, offset_back);
  float reach_butt = max(-offset_front, -offset_back);
  float coverage = covered(in_across_px, -in_half_px, in_half_px) *
                   covered(x, -half_len / m_per_px - reach_butt, half_len / m_per_px + reach_tip);
  if (coverage <= 0.0) discard;
  float xs = u_surface / m_per_px;

  // Wood: butt, then shaft from the joint, tip from its start; each joint
  // filtered over the pixel.
  vec3 butt = vec3(BUTT_R, BUTT_G, BUTT_B);
  vec3 shaft = vec3(SHAFT_R, SHAFT_G, SHAFT_B);
  vec3 tip = vec3(TIP_R, TIP_G, TIP_B);
  vec3 wood = mix(butt, shaft, covered(xs, in_design.x / m_per_px, 1.0e30));
  wood = mix(wood, tip, covered(xs, in_design.y / m_per_px, 1.0e30));
  if (in_design.w > 0.5) {
    float len = 2.0 * half_len;
    float w = 0.0;
    for (int i = 0; i < 5; ++i) {
      float f = i == 0 ? RING_0 : i == 1 ? RING_1 : i == 2 ? RING_2 : i == 3 ? RING_3 : RING_4;
      w = max(w, 1.0 - abs(u_surface - f * len) / RING_HALF_M);
    }
    wood = mix(wood, vec3(RING_R, RING_G, RING_B), w);
  }

  // Lit as scene.frag lights a surface.
  float head = facing * in_light.x;
  float key = 0.5 + 0.5 * clamp(q * in_light.y + facing * in_light.z, -1.0, 1.0);
  float shade = 0.22 + 0.50 * head + 0.33 * key;
  out_color = vec4(wood * shade * in_tint.rgb, coverage * in_tint.a);
}
