#version 460
// The plain Vulkan baseline for bench/render_accuracy: clip positions computed
// on the CPU (clip_position, the twin of scene.vert), colours as given;
// no curved-space work.
layout(location = 0) in vec4 in_position;
layout(location = 1) in vec4 in_color;
layout(location = 0) out vec4 out_color;
void main() {
  gl_Position = in_position;
  out_color = in_color;
}
