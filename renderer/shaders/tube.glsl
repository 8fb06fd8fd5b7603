// A tube (the cue stick) as a screen-space ribbon: the whole vertex
// computation of tube.vert, as a function of the view and the vertex, so that
// a compute shader (tube_formulas.comp) can run the same code on the inputs
// its C++ twin, tube_clip_position in renderer/src/mesh.cpp, sees; the vulkan
// test TubeShaderMatchesCpp compares them. Needs curved.glsl.
//
// Each vertex is a point of the tube's centre line; the vertex is placed on
// one side of the projected line, at the tube's projected half-width plus a
// margin, so that every pixel the tube touches is covered once. The fragment
// shader (tube.frag) computes each pixel's coverage and the cylinder's shading
// from the distances carried here, in pixels.

// The eye's view: tube.vert's View block and specialization constants.
struct TubeView {
  mat4 proj_front;
  mat4 proj_back;
  mat4 eye_from_nose;
  vec4 params;      // x: rho (m), y: width (px), z: height (px)
  int native_view;  // 0 tourist, 1 native
  int k;            // +1 S3, 0 E3, −1 H3
  int back;         // 1: S3 back hemisphere
};

struct TubeVertexOut {
  vec4 position;
  // Signed distance from the projected centre line and the half-width, in px.
  float across_px;
  float half_px;
  float u;  // metres along the centre line
  // x: how much of the toward-the-viewer direction lies in the cross-section;
  // y, z: the model "up" components of the cross-section's silhouette and
  // toward-the-viewer directions (the key light, as in scene.vert).
  vec3 light;
  // The image of the tube's cross-section circle about the centre line's
  // point: the points r toward the viewer (c) and r across the line of sight
  // (s) lie at these offsets in px, along the projected centre line (x: c,
  // y: s) and across it (z: c, w: s) ...
  vec4 circle;
  // ... with clip w these times the centre line's (x: c, y: s).
  vec2 circle_w;
};

// Pixels beyond the tube's edge and ends that the ribbon also covers: a pixel
// partly covered has its centre within half a pixel of the edge, and its
// samples lie within another half.
const float TUBE_MARGIN_PX = 1.5;

vec4 tube_clip_of(TubeView view, vec4 p) {
  float rho = view.params.x;
  // Back onto the space (the offsets below leave it by O(r²/rho)); the
  // tourist projection ignores the scale, the native log map needs it.
  p *= rho * inversesqrt(max(curv_point_form(p, p, view.k), 1.0e-30));
  return curv_clip(p, rho, view.k, view.native_view, view.back,
                   view.back != 0 ? view.proj_back : view.proj_front, view.eye_from_nose);
}

vec2 tube_to_px(TubeView view, vec4 clip) { return (clip.xy / clip.w * 0.5 + 0.5) * view.params.yz; }

// One ribbon vertex (the attributes of renderer::TubeVertex, design aside).
TubeVertexOut tube_vertex(TubeView view, mat4 model_view, vec4 in_axis, vec4 in_tangent, vec4 in_up,
                          vec4 in_side, vec4 in_place) {
  TubeVertexOut o;
  float rho = view.params.x;
  float r = in_place.w;
  vec4 p = model_view * in_axis;
  vec4 t = model_view * in_tangent;
  vec4 n_up = model_view * in_up;
  vec4 n_side = model_view * in_side;
  vec4 clip = tube_clip_of(view, p);
  if (clip.w <= 0.0) {
    // Behind the eye: beyond the far plane, so nothing of it is drawn.
    o.position = vec4(0.0, 0.0, 2.0, 1.0);
    o.across_px = 0.0;
    o.half_px = 0.0;
    o.u = in_place.z;
    o.light = vec3(0.0);
    o.circle = vec4(0.0);
    o.circle_w = vec2(1.0);
    return o;
  }
  // The cross-section's directions toward the viewer (c) and across the line
  // of sight (s), lit as the antipodal twin in the back hemisphere.
  float sign_back = view.back != 0 ? -1.0 : 1.0;
  vec4 toward = curv_toward_viewer(sign_back * p, rho, view.k);
  float a = curv_vector_form(toward, sign_back * n_up, view.k);
  float b = curv_vector_form(toward, sign_back * n_side, view.k);
  float m = length(vec2(a, b));
  vec2 cs = m > 1.0e-6 ? vec2(a, b) / m : vec2(0.0, 1.0);  // c = cs.x up + cs.y side
  vec4 c = cs.x * n_up + cs.y * n_side;
  vec4 s = -cs.y * n_up + cs.x * n_side;
  o.light = vec3(m, -cs.y * in_up.y + cs.x * in_side.y, cs.x * in_up.y + cs.y * in_side.y);

  // The projected centre line's direction, and the half-width of the
  // projected cross-section across it (the support of the circle's image).
  vec2 centre = tube_to_px(view, clip);
  vec2 along = tube_to_px(view, tube_clip_of(view, p + r * t)) - centre;
  float px_per_m = length(along) / r;
  vec2 dir = px_per_m > 0.0 ? along / (px_per_m * r) : vec2(1.0, 0.0);
  vec2 normal = vec2(-dir.y, dir.x);
  vec4 front = tube_clip_of(view, p + sign_back * r * c);
  vec4 aside = tube_clip_of(view, p + r * s);
  vec2 to_front = tube_to_px(view, front) - centre;
  vec2 to_aside = tube_to_px(view, aside) - centre;
  o.circle = vec4(dot(dir, to_front), dot(dir, to_aside), dot(normal, to_front), dot(normal, to_aside));
  o.circle_w = vec2(front.w, aside.w) / clip.w;
  float half_px = length(o.circle.zw);

  float across = in_place.x * (half_px + TUBE_MARGIN_PX);
  vec2 at = centre + across * normal;
  float u = in_place.z;
  if (in_place.y != 0.0) {
    // Past an end by more than its rim can reach, and the margin.
    float beyond = 1.25 * length(o.circle.xy) + TUBE_MARGIN_PX;
    at += in_place.y * beyond * dir;
    u += in_place.y * beyond / max(px_per_m, 1.0e-6);
  }
  // Depth of the tube's front, so that it meets other objects as a tube would.
  o.position = vec4((at / view.params.yz * 2.0 - 1.0) * clip.w, front.z / front.w * clip.w, clip.w);
  o.across_px = across;
  o.half_px = half_px;
  o.u = u;
  return o;
}
