#version 460
// Runs the shader formulas on a buffer of viewer-relative points so the
// formula_parity test can compare them with the C++ twins.
layout(local_size_x = 64) in;

#include "curved.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Inputs { vec4 points[]; } inputs;
layout(std430, set = 0, binding = 1) writeonly buffer Outputs { vec4 values[]; } outputs;

layout(std140, set = 0, binding = 2) uniform Params {
  mat4 proj;
  mat4 eye_from_nose;
  vec4 rho_k_count;  // x: rho, y: k, z: number of points
} params;

// Per point, 6 vec4: log, back log, tourist front, tourist back, native
// front, native back.
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(params.rho_k_count.z)) return;
  float rho = params.rho_k_count.x;
  int k = int(params.rho_k_count.y);
  vec4 p = inputs.points[i];
  uint o = 6u * i;
  outputs.values[o + 0u] = vec4(curv_log(p, rho, k), curv_theta(p, rho, k));
  outputs.values[o + 1u] = vec4(k > 0 ? curv_back_log(p, rho) : vec3(0.0), 0.0);
  outputs.values[o + 2u] = curv_clip(p, rho, k, 0, 0, params.proj, params.eye_from_nose);
  outputs.values[o + 3u] = curv_clip(p, rho, k, 0, 1, params.proj, params.eye_from_nose);
  outputs.values[o + 4u] = curv_clip(p, rho, k, 1, 0, params.proj, params.eye_from_nose);
  outputs.values[o + 5u] = k > 0 ? curv_clip(p, rho, k, 1, 1, params.proj, params.eye_from_nose)
                                 : vec4(0.0);
}
