#version 460
// Runs tube.vert's vertex computation (tube_vertex, tube.glsl) on a buffer of
// tube vertices, each with its model-view matrix, so that the vulkan test
// TubeShaderMatchesCpp can compare the clip positions with tube_clip_position,
// the C++ twin. The view comes as tube.vert gets it: the same specialization
// constants and View block.
layout(local_size_x = 64) in;

layout(constant_id = 0) const int NATIVE_VIEW = 0;  // 0 tourist, 1 native
layout(constant_id = 1) const int CURVATURE = 0;    // k: +1 S3, 0 E3, −1 H3
layout(constant_id = 2) const int BACK = 0;         // 1: S3 back hemisphere

#include "curved.glsl"
#include "tube.glsl"

layout(std140, set = 0, binding = 0) uniform View {
  mat4 proj_front;
  mat4 proj_back;
  mat4 eye_from_nose;
  vec4 params;  // x: rho (m), y: width (px), z: height (px)
} view;

// tube.vert's push constant and vertex attributes (renderer::TubeVertex less
// its colour design, which the vertex only passes on).
struct TubeInput {
  mat4 model_view;
  vec4 axis;
  vec4 tangent;
  vec4 up;
  vec4 side;
  vec4 place;
};
layout(std430, set = 0, binding = 1) readonly buffer Inputs { TubeInput vertices[]; } inputs;
layout(std430, set = 0, binding = 2) writeonly buffer Outputs { vec4 positions[]; } outputs;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(inputs.vertices.length())) return;
  TubeView v = TubeView(view.proj_front, view.proj_back, view.eye_from_nose, view.params, NATIVE_VIEW,
                        CURVATURE, BACK);
  TubeInput x = inputs.vertices[i];
  outputs.positions[i] = tube_vertex(v, x.model_view, x.axis, x.tangent, x.up, x.side, x.place).position;
}
