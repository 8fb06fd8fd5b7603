#version 460
// A tube (the cue stick) as a screen-space ribbon. Each vertex is a point of
// the tube's centre line; the shader projects it and places the vertex on one
// side of the projected line, at the tube's projected half-width plus a
// margin, so that every pixel the tube touches is covered once. The fragment
// shader (tube.frag) computes each pixel's coverage and the cylinder's shading
// from the distances carried here, in pixels.
layout(constant_id = 0) const int NATIVE_VIEW = 0;  // 0 tourist, 1 native
layout(constant_id = 1) const int CURVATURE = 0;    // k: +1 S3, 0 E3, −1 H3
layout(constant_id = 2) const int BACK = 0;         // 1: S3 back hemisphere

#include "curved.glsl"

layout(set = 0, binding = 0) uniform View {
  mat4 proj_front;
  mat4 proj_back;
  mat4 eye_from_nose;
  vec4 params;  // x: rho (m), y: width (px), z: height (px)
} view;

layout(push_constant) uniform Draw {
  mat4 model_view;
  vec4 tint;
} draw;

layout(location = 0) in vec4 in_axis;
layout(location = 1) in vec4 in_tangent;
layout(location = 2) in vec4 in_up;
layout(location = 3) in vec4 in_side;
layout(location = 4) in vec4 in_design;
layout(location = 5) in vec4 in_place;

// Signed distance from the projected centre line and the half-width, in px.
layout(location = 0) noperspective out float out_across_px;
layout(location = 1) noperspective out float out_half_px;
layout(location = 2) out float out_u;  // metres along the centre line
// x: how much of the toward-the-viewer direction lies in the cross-section;
// y, z: the model "up" components of the cross-section's silhouette and
// toward-the-viewer directions (the key light, as in scene.vert).
layout(location = 3) out vec3 out_light;
// The image of the tube's cross-section circle about the centre line's
// point: the points r toward the viewer (c) and r across the line of sight
// (s) lie at these offsets in px, along the projected centre line (x: c,
// y: s) and across it (z: c, w: s) ...
layout(location = 6) out vec4 out_circle;
// ... with clip w these times the centre line's (x: c, y: s).
layout(location = 7) out vec2 out_circle_w;
layout(location = 4) flat out vec4 out_design;
layout(location = 5) flat out vec4 out_tint;

// Pixels beyond the tube's edge and ends that the ribbon also covers: a pixel
// partly covered has its centre within half a pixel of the edge, and its
// samples lie within another half.
const float MARGIN_PX = 1.5;

vec4 clip_of(vec4 p) {
  float rho = view.params.x;
  // Back onto the space (the offsets below leave it by O(r²/rho)); the
  // tourist projection ignores the scale, the native log map needs it.
  p *= rho * inversesqrt(max(curv_point_form(p, p, CURVATURE), 1.0e-30));
  return curv_clip(p, rho, CURVATURE, NATIVE_VIEW, BACK,
                   BACK != 0 ? view.proj_back : view.proj_front, view.eye_from_nose);
}

vec2 to_px(vec4 clip) { return (clip.xy / clip.w * 0.5 + 0.5) * view.params.yz; }

void main() {
  float rho = view.params.x;
  float r = in_place.w;
  vec4 p = draw.model_view * in_axis;
  vec4 t = draw.model_view * in_tangent;
  vec4 n_up = draw.model_view * in_up;
  vec4 n_side = draw.model_view * in_side;
  vec4 clip = clip_of(p);
  out_design = in_design;
  out_tint = draw.tint;
  if (clip.w <= 0.0) {
    // Behind the eye: beyond the far plane, so nothing of it is drawn.
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);
    out_across_px = 0.0;
    out_half_px = 0.0;
    out_u = in_place.z;
    out_light = vec3(0.0);
    out_circle = vec4(0.0);
    out_circle_w = vec2(1.0);
    return;
  }
  // The cross-section's directions toward the viewer (c) and across the line
  // of sight (s), lit as the antipodal twin in the back hemisphere.
  float sign_back = BACK != 0 ? -1.0 : 1.0;
  vec4 toward = curv_toward_viewer(sign_back * p, rho, CURVATURE);
  float a = curv_vector_form(toward, sign_back * n_up, CURVATURE);
  float b = curv_vector_form(toward, sign_back * n_side, CURVATURE);
  float m = length(vec2(a, b));
  vec2 cs = m > 1.0e-6 ? vec2(a, b) / m : vec2(0.0, 1.0);  // c = cs.x up + cs.y side
  vec4 c = cs.x * n_up + cs.y * n_side;
  vec4 s = -cs.y * n_up + cs.x * n_side;
  out_light = vec3(m, -cs.y * in_up.y + cs.x * in_side.y, cs.x * in_up.y + cs.y * in_side.y);

  // The projected centre line's direction, and the half-width of the
  // projected cross-section across it (the support of the circle's image).
  vec2 centre = to_px(clip);
  vec2 along = to_px(clip_of(p + r * t)) - centre;
  float px_per_m = length(along) / r;
  vec2 dir = px_per_m > 0.0 ? along / (px_per_m * r) : vec2(1.0, 0.0);
  vec2 normal = vec2(-dir.y, dir.x);
  vec4 front = clip_of(p + sign_back * r * c);
  vec4 aside = clip_of(p + r * s);
  vec2 to_front = to_px(front) - centre;
  vec2 to_aside = to_px(aside) - centre;
  out_circle = vec4(dot(dir, to_front), dot(dir, to_aside), dot(normal, to_front), dot(normal, to_aside));
  out_circle_w = vec2(front.w, aside.w) / clip.w;
  float half_px = length(out_circle.zw);

  float across = in_place.x * (half_px + MARGIN_PX);
  vec2 at = centre + across * normal;
  float u = in_place.z;
  if (in_place.y != 0.0) {
    // Past an end by more than its rim can reach, and the margin.
    float beyond = 1.25 * length(out_circle.xy) + MARGIN_PX;
    at += in_place.y * beyond * dir;
    u += in_place.y * beyond / max(px_per_m, 1.0e-6);
  }
  // Depth of the tube's front, so that it meets other objects as a tube would.
  gl_Position = vec4((at / view.params.yz * 2.0 - 1.0) * clip.w, front.z / front.w * clip.w, clip.w);
  out_across_px = across;
  out_half_px = half_px;
  out_u = u;
}
