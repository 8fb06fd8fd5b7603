// Curved-space formulas shared by every shader that needs them. Each one has a
// C++ twin in renderer/src/view.cpp (and geometry/maps.hpp); the vulkan test
// formula_parity runs both on the same inputs.
//
// k is the curvature sign (+1 S3, 0 E3, −1 H3), rho the radius in metres.
// Points are 4-vectors in metres relative to the viewer (DESIGN.md §2).

const float CURV_PI = 3.14159265358979;

// Distance from the viewer in radians: atan2 in S3, asinh in H3 — never
// acos/acosh of a ratio near 1 (DESIGN.md §2).
float curv_theta(vec4 p, float rho, int k) {
  float r = length(p.xyz);
  if (k > 0) return atan(r, p.w);
  if (k < 0) return asinh(r / rho);
  return r / rho;
}

// The azimuthal-equidistant image (paper, "Native-inhabitant view vs. tourist
// view"): rho·theta·xyz/|xyz|. theta/S(theta) uses its series near 0, and the
// exact S3 antipode maps to rho·pi straight ahead, as log_origin does.
vec3 curv_log(vec4 p, float rho, int k) {
  float r = length(p.xyz);
  float t = curv_theta(p, rho, k);
  if (r == 0.0) return t == 0.0 ? vec3(0.0) : vec3(0.0, 0.0, -rho * t);
  if (t < 1.0e-2) {
    float t2 = t * t;
    float f = 1.0 + float(k) * t2 / 6.0 + 7.0 * t2 * t2 / 360.0;
    return f * p.xyz;
  }
  return (rho * t / r) * p.xyz;
}

// S3 back hemisphere: q is also seen in the opposite direction at distance
// 2·pi − theta, i.e. −rho(2pi − theta)·xyz/|xyz| applied to q's own
// coordinates (DESIGN.md §2; the paper's (pi+theta)/sin theta holds only for
// the antipodal twin −q).
vec3 curv_back_log(vec4 p, float rho) {
  float r = length(p.xyz);
  float back = 2.0 * CURV_PI - atan(r, p.w);
  if (r == 0.0) return vec3(0.0, 0.0, rho * back);
  return (-rho * back / r) * p.xyz;
}

// Clip position of a viewer-relative point. Tourist: one 4×4 projection acts
// on (x, y, z, w) directly — w/|z| falls monotonically with distance in every
// space (DESIGN.md §4) — and the back hemisphere is the antipodal twin −p
// (paper, "The 3-sphere"). Native: log map, Euclidean eye offset, Euclidean
// projection of (e, 1).
vec4 curv_clip(vec4 p, float rho, int k, int native_view, int back, mat4 proj,
               mat4 eye_from_nose) {
  if (native_view == 0) return proj * (back != 0 ? -p : p);
  vec3 q = back != 0 ? curv_back_log(p, rho) : curv_log(p, rho, k);
  return proj * (eye_from_nose * vec4(q, 1.0));
}

// P(a, b) = k a.xyz·b.xyz + a.w b.w and g(a, b) = a.xyz·b.xyz + k a.w b.w.
float curv_point_form(vec4 a, vec4 b, int k) { return float(k) * dot(a.xyz, b.xyz) + a.w * b.w; }
float curv_vector_form(vec4 a, vec4 b, int k) { return dot(a.xyz, b.xyz) + float(k) * a.w * b.w; }

// Unit tangent at p pointing along the geodesic toward the viewer at the
// origin (0,0,0,rho): o − P(o,p)/rho² · p, normalized with g.
vec4 curv_toward_viewer(vec4 p, float rho, int k) {
  vec4 o = vec4(0.0, 0.0, 0.0, rho);
  vec4 t = o - (curv_point_form(o, p, k) / (rho * rho)) * p;
  float n2 = curv_vector_form(t, t, k);
  return n2 > 0.0 ? t * inversesqrt(n2) : vec4(0.0, 0.0, 1.0, 0.0);
}
