#version 460
// One vertex shader for every draw; variants by specialization constants.
layout(constant_id = 0) const int NATIVE_VIEW = 0;  // 0 tourist, 1 native
layout(constant_id = 1) const int CURVATURE = 0;    // k: +1 S3, 0 E3, −1 H3
layout(constant_id = 2) const int BACK = 0;         // 1: S3 back hemisphere
layout(constant_id = 28) const int OVERLAY = 0;     // 1: head-locked panel, model_view is clip ← model

#include "curved.glsl"

layout(set = 0, binding = 0) uniform View {
  mat4 proj_front;
  mat4 proj_back;
  mat4 eye_from_nose;  // native only: Euclidean eye offset in the tangent space
  vec4 params;         // x: rho (m)
} view;

layout(push_constant) uniform Draw {
  mat4 model_view;  // model → viewer, composed in double on the CPU
  vec4 tint;
} draw;

layout(location = 0) in vec4 in_position;
layout(location = 1) in vec4 in_normal;
layout(location = 2) in vec4 in_color;

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec2 out_light;  // x: toward the viewer, y: from above

void main() {
  if (OVERLAY != 0) {
    gl_Position = draw.model_view * in_position;
    out_color = in_color * draw.tint;
    out_light = vec2(1.0);
    return;
  }
  float rho = view.params.x;
  vec4 p = draw.model_view * in_position;
  vec4 n = draw.model_view * in_normal;
  gl_Position = curv_clip(p, rho, CURVATURE, NATIVE_VIEW, BACK,
                          BACK != 0 ? view.proj_back : view.proj_front, view.eye_from_nose);
  // The antipodal map is an isometry: light the twin −p with normal −n.
  if (BACK != 0) { p = -p; n = -n; }
  vec4 toward = curv_toward_viewer(p, rho, CURVATURE);
  out_light = vec2(curv_vector_form(n, toward, CURVATURE), in_normal.y);
  out_color = in_color * draw.tint;
}
