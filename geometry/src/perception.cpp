#include "curvlab/geometry/perception.hpp"

#include "curvlab/geometry/enum_names.hpp"
#include "curvlab/geometry/maps.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

namespace curvlab::geometry {
namespace {

// The observer's model of the eyes: the interocular axis (left → right) and
// the forward direction orthogonal to it in the plane containing −z.
struct EyeAxes {
  Vec3 axis{1.0, 0.0, 0.0};
  Vec3 forward{0.0, 0.0, -1.0};
};

EyeAxes eye_axes(const EyeOffsets& eyes) {
  EyeAxes a;
  const Vec3 d = eyes.right_m - eyes.left_m;
  const double len = glm::length(d);
  if (len > 0.0) a.axis = d / len;
  const Vec3 minus_z(0.0, 0.0, -1.0);
  const Vec3 f = minus_z - glm::dot(minus_z, a.axis) * a.axis;
  const double flen = glm::length(f);
  if (flen > 0.0) a.forward = f / flen;
  return a;
}

double yaw_toward(const EyeAxes& a, const Vec3& dir) {
  return std::atan2(glm::dot(dir, a.axis), glm::dot(dir, a.forward));
}

Vec3 unit_or_forward(const Vec3& v) {
  const double len = glm::length(v);
  return len > 0.0 ? v / len : Vec3(0.0, 0.0, -1.0);
}

}  // namespace

std::string_view to_string(ViewPreset preset) {
  switch (preset) {
    case ViewPreset::tourist: return "tourist";
    case ViewPreset::native: return "native";
    case ViewPreset::monocular: return "monocular";
  }
  return "?";
}

std::optional<ViewPreset> parse_view_preset(std::string_view text) { return parse_name(kViewPresets, text); }

bool true_optics(ViewPreset preset) {
  switch (preset) {
    case ViewPreset::tourist: return true;
    case ViewPreset::native:
    case ViewPreset::monocular: return false;
  }
  std::abort();  // not a ViewPreset: a broken contract
}

bool binocular(ViewPreset preset) {
  switch (preset) {
    case ViewPreset::tourist:
    case ViewPreset::native: return true;
    case ViewPreset::monocular: return false;
  }
  std::abort();  // not a ViewPreset: a broken contract
}

EyeOffsets eyes_from_ipd(double ipd_m) {
  return {Vec3(-0.5 * ipd_m, 0.0, 0.0), Vec3(0.5 * ipd_m, 0.0, 0.0)};
}

std::array<SightLine, 2> sight_lines(const Space& space, const Isometry& nose,
                                     const EyeOffsets& eyes, ViewPreset preset, const Point& q) {
  const Vec3 offsets[2] = {eyes.left_m, eyes.right_m};
  std::array<SightLine, 2> out;
  if (true_optics(preset)) {
    // True optics: each eye is the nose translated along a geodesic, so its
    // axes are the nose's parallel-transported; the initial direction of the
    // geodesic to q, read in those axes, is where the eye looks.
    for (int i = 0; i < 2; ++i) {
      const Isometry eye = nose * translation_m(space, offsets[i]);
      out[static_cast<std::size_t>(i)] = {offsets[i], unit_or_forward(log_at(space, eye, q))};
    }
  } else {
    // Nose space → Euclidean tangent space (azimuthal-equidistant) → eye.
    const Vec3 image = log_at(space, nose, q);
    for (int i = 0; i < 2; ++i)
      out[static_cast<std::size_t>(i)] = {offsets[i], unit_or_forward(image - offsets[i])};
  }
  return out;
}

PerceivedPoint perceive_point(const Space& space, const Isometry& nose, const EyeOffsets& eyes,
                              ViewPreset preset, const Point& q) {
  PerceivedPoint p;
  if (!binocular(preset)) {
    p.position_m = log_at(space, nose, q);
    p.has_disparity = false;
    return p;
  }
  const auto lines = sight_lines(space, nose, eyes, preset, q);
  const EyeAxes axes = eye_axes(eyes);
  p.vergence_rad = yaw_toward(axes, lines[0].direction) - yaw_toward(axes, lines[1].direction);
  const LineMeeting m = closest_approach(lines[0], lines[1]);
  if (m.parallel) {
    p.parallel = true;
    p.position_m = m.point + 1e9 * unit_or_forward(lines[0].direction + lines[1].direction);
    return p;
  }
  p.diverging = m.s < 0.0 && m.u < 0.0;
  p.position_m = m.point;
  return p;
}

LineMeeting closest_approach(const SightLine& a, const SightLine& b) {
  const Vec3& d1 = a.direction;
  const Vec3& d2 = b.direction;
  const Vec3 w0 = a.origin_m - b.origin_m;
  const double cos = glm::dot(d1, d2);
  const double d = glm::dot(d1, w0);
  const double e = glm::dot(d2, w0);
  const double den = 1.0 - cos * cos;
  LineMeeting m;
  if (den <= 1e-24) {
    m.parallel = true;
    m.point = 0.5 * (a.origin_m + b.origin_m);
    return m;
  }
  m.s = (cos * e - d) / den;
  m.u = (e - cos * d) / den;
  m.point = 0.5 * (a.origin_m + m.s * d1 + b.origin_m + m.u * d2);
  return m;
}

double distance_from_vergence_m(double vergence_rad, double ipd_m) {
  const double t = std::tan(0.5 * vergence_rad);
  if (t == 0.0) return std::numeric_limits<double>::infinity();
  return 0.5 * ipd_m / t;
}

VergenceReading vergence_straight_ahead(const Space& space, double ipd_m, double d_m) {
  const EyeOffsets eyes = eyes_from_ipd(ipd_m);
  const Point q = exp_origin(space, Vec3(0.0, 0.0, -d_m));
  const Isometry nose = Isometry::identity();
  VergenceReading r;
  r.vergence_rad = perceive_point(space, nose, eyes, ViewPreset::tourist, q).vergence_rad;
  r.tourist_distance_m = distance_from_vergence_m(r.vergence_rad, ipd_m);
  r.native_distance_m = -perceive_point(space, nose, eyes, ViewPreset::native, q).position_m.z;
  return r;
}

Isometry stick_frame(const Space& space, double distance_m) {
  return translation_rad(space, Vec3(0.0, 0.0, -1.0), distance_m / space.radius_m);
}

StickPerception perceive_stick(const Space& space, const BentStick& stick, double mid_distance_m,
                               const EyeOffsets& eyes, ViewPreset preset) {
  const Isometry frame = stick_frame(space, mid_distance_m);
  const Isometry nose = Isometry::identity();
  const Point o = origin(space);
  StickPerception out;
  for (int i = 0; i < 5; ++i) {
    const double u = stick.length_m * (static_cast<double>(i) / 4.0 - 0.5);
    const Point q = stick.centre_point(space, frame, u);
    out.distances_m[static_cast<std::size_t>(i)] = distance_m(space, o, q);
    out.perceived_m[static_cast<std::size_t>(i)] =
        perceive_point(space, nose, eyes, preset, q).position_m;
  }
  if (!binocular(preset)) return out;
  out.perceived_sagitta_m = bow_toward_viewer(out.perceived_m[0], out.perceived_m[2], out.perceived_m[4]);
  return out;
}

double bow_toward_viewer(const Vec3& end_a, const Vec3& middle, const Vec3& end_b) {
  const Vec3 mid = 0.5 * (end_a + end_b);
  const Vec3 chord = unit_or_forward(end_b - end_a);
  // The unit normal to the chord pointing from the chord toward the nose.
  Vec3 toward = -mid - glm::dot(-mid, chord) * chord;
  const double len = glm::length(toward);
  toward = len > 0.0 ? toward / len : Vec3(0.0, 0.0, 1.0);
  return glm::dot(middle - mid, toward);
}

double height_above_rim(const std::vector<Vec3>& rim, const Vec3& centre, const Vec3& up) {
  if (rim.size() < 3) return 0.0;
  Vec3 centroid(0.0);
  for (const auto& m : rim) centroid += m;
  centroid /= static_cast<double>(rim.size());
  Vec3 normal(0.0);
  for (std::size_t i = 0; i < rim.size(); ++i)
    normal += glm::cross(rim[i] - centroid, rim[(i + 1) % rim.size()] - centroid);
  const double nl = glm::length(normal);
  if (!(nl > 0.0)) return 0.0;
  normal /= nl;
  if (glm::dot(normal, up) < 0.0) normal = -normal;
  return glm::dot(centre - centroid, normal);
}

}  // namespace curvlab::geometry
