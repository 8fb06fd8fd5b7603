#version 460
// A tube (the cue stick) as a screen-space ribbon; the computation is
// tube_vertex in tube.glsl, which a compute shader also runs to compare it
// with its C++ twin (tube_clip_position).
layout(constant_id = 0) const int NATIVE_VIEW = 0;  // 0 tourist, 1 native
layout(constant_id = 1) const int CURVATURE = 0;    // k: +1 S3, 0 E3, −1 H3
layout(constant_id = 2) const int BACK = 0;         // 1: S3 back hemisphere

#include "curved.glsl"
#include "tube.glsl"

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

// What tube.frag needs, as TubeVertexOut (tube.glsl) describes it.
layout(location = 0) noperspective out float out_across_px;
layout(location = 1) noperspective out float out_half_px;
layout(location = 2) out float out_u;
layout(location = 3) out vec3 out_light;
layout(location = 6) out vec4 out_circle;
layout(location = 7) out vec2 out_circle_w;
layout(location = 4) flat out vec4 out_design;
layout(location = 5) flat out vec4 out_tint;

void main() {
  TubeView v = TubeView(view.proj_front, view.proj_back, view.eye_from_nose, view.params, NATIVE_VIEW,
                        CURVATURE, BACK);
  TubeVertexOut o = tube_vertex(v, draw.model_view, in_axis, in_tangent, in_up, in_side, in_place);
  gl_Position = o.position;
  out_across_px = o.across_px;
  out_half_px = o.half_px;
  out_u = o.u;
  out_light = o.light;
  out_circle = o.circle;
  out_circle_w = o.circle_w;
  out_design = in_design;
  out_tint = draw.tint;
}
