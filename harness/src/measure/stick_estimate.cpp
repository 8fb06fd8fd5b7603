// Triangulating the rings and fitting the stick (stick.hpp), the perception
// model's value for the same scene, and the JSON records.
#include "curvlab/harness/measure/stick.hpp"

#include "curvlab/geometry/enum_names.hpp"

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace curvlab::harness::measure {
namespace {

using geometry::Vec3;

Error bad(std::string m) { return Error{Error::Kind::bad_input, std::move(m)}; }

// The perception model's sagitta of three points (geometry/perception.hpp).
using geometry::bow_toward_viewer;

// The whole distance of the middle from the chord, with the sign of the bow.
double bend_in_plane(const Vec3& end_a, const Vec3& middle, const Vec3& end_b) {
  Vec3 chord = end_b - end_a;
  const double cl = glm::length(chord);
  chord = cl > 0.0 ? chord / cl : Vec3(1.0, 0.0, 0.0);
  Vec3 off = middle - 0.5 * (end_a + end_b);
  off -= glm::dot(off, chord) * chord;
  return std::copysign(glm::length(off), bow_toward_viewer(end_a, middle, end_b));
}

// The least-squares intersection of two lines: the midpoint of their common
// perpendicular (geometry/perception.hpp).
Vec3 intersect(const geometry::SightLine& l1, const geometry::SightLine& l2) {
  return geometry::closest_approach(l1, l2).point;
}

// Least-squares polynomial coefficients (degree + 1 of them) of values v
// against t: Gauss–Jordan on the normal equations.
template <std::size_t N>
std::array<double, N> fit_polynomial(const std::vector<double>& t, const std::vector<double>& v) {
  std::array<std::array<double, N + 1>, N> a{};
  for (std::size_t i = 0; i < t.size(); ++i) {
    std::array<double, N> basis{};
    double power = 1.0;
    for (auto& b : basis) b = power, power *= t[i];
    for (std::size_t r = 0; r < N; ++r) {
      for (std::size_t c = 0; c < N; ++c) a[r][c] += basis[r] * basis[c];
      a[r][N] += basis[r] * v[i];
    }
  }
  for (std::size_t k = 0; k < N; ++k)
    for (std::size_t r = 0; r < N; ++r) {
      if (r == k || a[k][k] == 0.0) continue;
      const double q = a[r][k] / a[k][k];
      for (std::size_t c = k; c <= N; ++c) a[r][c] -= q * a[k][c];
    }
  std::array<double, N> out{};
  for (std::size_t k = 0; k < N; ++k) out[k] = a[k][k] != 0.0 ? a[k][N] / a[k][k] : 0.0;
  return out;
}

template <std::size_t N>
double polynomial_at(const std::array<double, N>& c, double t) {
  double v = 0.0;
  for (std::size_t k = N; k-- > 0;) v = v * t + c[k];
  return v;
}

// The perceived stick as a curve read against its chord: the position along
// the chord as a cubic in the position along the stick, u, and the offset
// from the chord as a quadratic in the position along the chord. A bow is a
// shape in space, and a quadratic in u would read it through how evenly the
// rings are seen spaced: in a curved space's tourist view they are not (H3
// crowds the far ends together), and the quadratic's ends, extrapolated
// past the outer rings, overstate the bow by several per cent. In E3 both
// readings are exact.
struct StickCurve {
  Vec3 origin{0.0}, chord{1.0, 0.0, 0.0};
  std::array<double, 4> along{};                 // chord coordinate (m) against u (m)
  std::array<std::array<double, 3>, 3> offset{};  // per nose-frame axis, against the chord coordinate
  [[nodiscard]] Vec3 at(double u) const {
    const double s = polynomial_at(along, u);
    Vec3 p = origin + s * chord;
    for (int k = 0; k < 3; ++k) p[k] += polynomial_at(offset[static_cast<std::size_t>(k)], s);
    return p;
  }
};

StickCurve fit_curve(const std::vector<double>& u, const std::vector<Vec3>& p, const Vec3& chord) {
  StickCurve c;
  c.chord = chord;
  for (const auto& q : p) c.origin += q;
  c.origin /= static_cast<double>(p.size());
  std::vector<double> s;
  std::array<std::vector<double>, 3> off;
  for (const auto& q : p) {
    const Vec3 d = q - c.origin;
    s.push_back(glm::dot(d, c.chord));
    const Vec3 o = d - s.back() * c.chord;
    for (int k = 0; k < 3; ++k) off[static_cast<std::size_t>(k)].push_back(o[k]);
  }
  c.along = fit_polynomial<4>(u, s);
  for (std::size_t k = 0; k < 3; ++k) c.offset[k] = fit_polynomial<3>(s, off[k]);
  return c;
}

nlohmann::ordered_json matrix_json(const glm::dmat4& m) {
  auto out = nlohmann::ordered_json::array();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) out.push_back(m[c][r]);
  return out;
}

glm::dmat4 matrix_from(const nlohmann::json& j) {
  glm::dmat4 m(1.0);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[c][r] = j.at(static_cast<std::size_t>(c * 4 + r)).get<double>();
  return m;
}

// The triangulated point lies on the part of the ring that faces the eyes.
// Averaged over the image rows that cross the stick (uniform in the
// projected height r·sin α of the visible half circle), its offset toward
// the eyes is r·⟨cos α⟩ (π r / 4 over the whole half circle; more when the
// rows along the outline are left out); move it back onto the centre line,
// away from the viewer, perpendicular to the stick's chord.
Vec3 onto_centre_line(const Vec3& p, const Vec3& cyclops, const Vec3& chord, double offset_m) {
  Vec3 away = p - cyclops;
  away -= glm::dot(away, chord) * chord;
  const double len = glm::length(away);
  return len > 0.0 ? p + offset_m * away / len : p;
}

}  // namespace

geometry::SightLine sight_line(const renderer::EyeOffset& eye, std::uint32_t width_px,
                               std::uint32_t height_px, const glm::dvec2& px) {
  const double l = std::tan(eye.fov.angle_left_rad), r = std::tan(eye.fov.angle_right_rad);
  const double u = std::tan(eye.fov.angle_up_rad), d = std::tan(eye.fov.angle_down_rad);
  const double tx = l + px.x / width_px * (r - l);
  const double ty = u - px.y / height_px * (u - d);
  return {eye.position_m, glm::normalize(eye.rotation * Vec3(tx, ty, -1.0))};
}

glm::dvec2 project_px(const renderer::EyeOffset& eye, std::uint32_t width_px, std::uint32_t height_px,
                      const Vec3& p_m) {
  const Vec3 q = glm::transpose(eye.rotation) * (p_m - eye.position_m);
  const double tx = q.x / -q.z, ty = q.y / -q.z;
  const double l = std::tan(eye.fov.angle_left_rad), r = std::tan(eye.fov.angle_right_rad);
  const double u = std::tan(eye.fov.angle_up_rad), d = std::tan(eye.fov.angle_down_rad);
  return {(tx - l) / (r - l) * width_px, (u - ty) / (u - d) * height_px};
}

namespace {

geometry::EyeOffsets eyes_of(const StickScene& scene) {
  return {scene.rig.eyes[0].position_m, scene.rig.eyes[1].position_m};
}

// Which rings each eye cannot see, by the recorded geometry: each ring's
// line of sight from the eye (the view's optics, perception.hpp) against the
// eye's field of view. "" when every ring is in both views. Names the eye,
// the ring (1 at the butt end … 5 at the tip) and how far off it lies.
std::string rings_out_of_view(const StickScene& scene) {
  const auto eyes = eyes_of(scene);
  const auto& fractions = renderer::kStickRingFractions;
  std::string out;
  for (int e = 0; e < 2; ++e) {
    const auto& eye = scene.rig.eyes[static_cast<std::size_t>(e)];
    std::string lost;
    for (std::size_t i = 0; i < fractions.size(); ++i) {
      const geometry::Point q =
          scene.stick.centre_point(scene.space, scene.stick_pose, fractions[i] * scene.stick.length_m);
      const Vec3 d = glm::transpose(eye.rotation) *
                     geometry::sight_lines(scene.space, scene.head, eyes, scene.preset, q)[static_cast<std::size_t>(e)]
                         .direction;
      const double x = std::atan2(d.x, -d.z), y = std::atan2(d.y, -d.z);
      const bool inside = d.z < 0.0 && x >= eye.fov.angle_left_rad && x <= eye.fov.angle_right_rad &&
                          y >= eye.fov.angle_down_rad && y <= eye.fov.angle_up_rad;
      if (inside) continue;
      char buf[160];
      const double deg = 180.0 / 3.14159265358979323846;
      std::snprintf(buf, sizeof buf, "ring %zu%s (%.0f° %s; the view reaches %.0f°)", i + 1,
                    i == 0 ? " at the butt end" : i + 1 == fractions.size() ? " at the tip" : "",
                    std::abs(x) * deg, x < 0.0 ? "left" : "right",
                    (x < 0.0 ? -eye.fov.angle_left_rad : eye.fov.angle_right_rad) * deg);
      lost += std::string(lost.empty() ? "" : ", ") + buf;
    }
    if (!lost.empty())
      out += std::string(out.empty() ? "" : "; ") + "the " + (e == 0 ? "left" : "right") + " eye loses " + lost;
  }
  return out;
}

// The perceived ends and middle of the stick's centre line: the ideal
// geometer's, or the human observer's fixating the middle.
std::array<Vec3, 3> model_points(const StickScene& scene, const geometry::HumanVision* vision) {
  const auto eyes = eyes_of(scene);
  const double half = scene.stick.length_m / 2.0;
  std::vector<geometry::Point> q;
  for (const double u : {-half, 0.0, half}) q.push_back(scene.stick.centre_point(scene.space, scene.stick_pose, u));
  if (vision != nullptr) {
    const auto p = geometry::perceive_human_at(scene.space, scene.head, eyes, scene.preset, q, 1, *vision).points_m;
    return {p[0], p[1], p[2]};
  }
  const auto seen = [&](const geometry::Point& x) {
    return geometry::perceive_point(scene.space, scene.head, eyes, scene.preset, x).position_m;
  };
  return {seen(q[0]), seen(q[1]), seen(q[2])};
}


// The radius a round stick must have to look as thick as it does at the
// distance it is seen at (no knowledge of the true radius: in a curved
// space's tourist view the seen depth scale differs from the true one).
double radius_seen(const renderer::EyeOffset& eye, const StickScene& scene, const RingSighting& ring,
                   const Vec3& p) {
  const auto a = sight_line(eye, scene.width_px, scene.height_px, ring.px);
  const auto b = sight_line(eye, scene.width_px, scene.height_px, ring.px + glm::dvec2(0.0, ring.half_thickness_px));
  const double angle = std::acos(std::clamp(glm::dot(a.direction, b.direction), -1.0, 1.0));
  return glm::length(p - eye.position_m) * std::tan(angle);
}

// One ring seen in both eyes, at the same depth on the ring (the disparity
// of a point of the ring, not of two points at different depths), and the
// two lines of sight through it.
StickFeature sighted(const StickScene& scene, double fraction, const RingSighting& left, const RingSighting& right,
                     std::array<geometry::SightLine, 2>& lines) {
  StickFeature f;
  char name[32];
  std::snprintf(name, sizeof name, "ring %+.2f", fraction);
  f.name = name;
  f.u_m = fraction * scene.stick.length_m;
  f.depth_radii = 0.5 * (left.depth_radii + right.depth_radii);
  f.left_px = left.at_depth(f.depth_radii);
  f.right_px = right.at_depth(f.depth_radii);
  f.rows = std::min(left.rows, right.rows);
  lines = {sight_line(scene.rig.eyes[0], scene.width_px, scene.height_px, f.left_px),
           sight_line(scene.rig.eyes[1], scene.width_px, scene.height_px, f.right_px)};
  return f;
}

// The ring placed where the observer perceives it, with its reprojection
// residuals and seen radius.
void place(const StickScene& scene, const RingSighting& left, const RingSighting& right, const Vec3& position,
           StickFeature& f) {
  const auto& rig = scene.rig;
  f.position_m = position;
  f.residual_left_px = glm::length(project_px(rig.eyes[0], scene.width_px, scene.height_px, f.position_m) - f.left_px);
  f.residual_right_px =
      glm::length(project_px(rig.eyes[1], scene.width_px, scene.height_px, f.position_m) - f.right_px);
  f.radius_seen_m = 0.5 * (radius_seen(rig.eyes[0], scene, left, f.position_m) +
                           radius_seen(rig.eyes[1], scene, right, f.position_m));
}

// How much deeper than wide a small offset of the stick looks at perceived
// distance D from the eyes, from the recorded space (S, C: sin and cos of
// d/ρ times ρ and 1 in S3, sinh and cosh in H3, d and 1 in E3). Tourist:
// the eyes converge as if at D = S(d)/C(d), so a step toward them looks
// 1/C(d)² as long and a step across 1/C(d): ratio 1/C(d). Native: distances
// from the nose are kept and widths scaled by d/S(d): ratio S(d)/d. Where D
// cannot be inverted (S3 past the quarter circumference) the ratio is 1.
double depth_to_width(const StickScene& scene, double perceived_m) {
  const double rho = scene.space.radius_m;
  const double x = perceived_m / rho;
  switch (scene.space.kind) {
    case geometry::SpaceKind::E3: return 1.0;
    case geometry::SpaceKind::H3:
      if (geometry::true_optics(scene.preset)) return x < 1.0 ? std::sqrt(1.0 - x * x) : 1.0;
      return x > 0.0 ? std::sinh(x) / x : 1.0;
    case geometry::SpaceKind::S3:
      if (geometry::true_optics(scene.preset)) return x > 0.0 ? std::sqrt(1.0 + x * x) : 1.0;
      return x > 0.0 && x < std::numbers::pi ? std::sin(x) / x : 1.0;
  }
  return 1.0;
}

// The curve through the rings' centre-line points (StickCurve) gives the
// perceived ends and middle; their bow is the estimate. In a tourist view the
// human observer scales every disparity by its own perceived distance
// instead of reading depth in the true optics' ratio to width, so its
// surface-to-centre step takes the seen radius as it is (with the optics'
// ratio its H3 tourist sagitta missed the model's by 0.9 mm at the proposed
// study's geometry; without, by 0.3 mm).
void fit_stick(const StickScene& scene, StickEstimate& e) {
  const Vec3 cyclops = 0.5 * (scene.rig.eyes[0].position_m + scene.rig.eyes[1].position_m);
  const Vec3 chord = glm::normalize(e.features.back().position_m - e.features.front().position_m);
  std::vector<double> u;
  std::vector<Vec3> p;
  for (auto& f : e.features) {
    const double stretch = e.human && geometry::true_optics(scene.preset)
                               ? 1.0
                               : depth_to_width(scene, glm::length(f.position_m - cyclops));
    f.position_m = onto_centre_line(f.position_m, cyclops, chord, f.depth_radii * f.radius_seen_m * stretch);
    u.push_back(f.u_m);
    p.push_back(f.position_m);
  }
  const StickCurve q = fit_curve(u, p, chord);
  double sq = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i) sq += glm::dot(q.at(u[i]) - p[i], q.at(u[i]) - p[i]);
  e.fit_rms_m = std::sqrt(sq / static_cast<double>(u.size()));
  const double half = scene.stick.length_m / 2.0;
  e.estimated_sagitta_m = bow_toward_viewer(q.at(-half), q.at(0.0), q.at(half));
  e.estimated_bend_m = bend_in_plane(q.at(-half), q.at(0.0), q.at(half));
}

}  // namespace

Result<StickEstimate> measure_stick(const renderer::Rgba8Image& left, const renderer::Rgba8Image& right,
                                    const StickScene& scene, const geometry::HumanVision* vision) {
  if (left.width != static_cast<int>(scene.width_px) || left.height != static_cast<int>(scene.height_px) ||
      right.width != left.width || right.height != left.height)
    return bad("the images are " + std::to_string(left.width) + "x" + std::to_string(left.height) + " and " +
               std::to_string(right.width) + "x" + std::to_string(right.height) + "; the recorded eye geometry is " +
               std::to_string(scene.width_px) + "x" + std::to_string(scene.height_px));
  StickEstimate e;
  if (geometry::binocular(scene.preset)) {  // one eye: no disparity, 0
    const auto p = model_points(scene, vision);
    e.model_sagitta_m = bow_toward_viewer(p[0], p[1], p[2]);
    e.model_bend_m = bend_in_plane(p[0], p[1], p[2]);
  }
  const auto left_stick = find_stick(left), right_stick = find_stick(right);
  if (!left_stick && !right_stick) return bad("neither image shows a stick");
  if (!left_stick || !right_stick) {
    e.binocular = false;  // one eye: no disparity, nothing to triangulate
    return e;
  }
  if (scene.marks != renderer::StickMarks::rings)
    return bad("a plain stick has no features along its length to match between the eyes; "
               "mark it with rings (render --stick-marks rings, protocol stimulus.stick_marks = \"rings\")");
  auto l = find_rings(left, *left_stick, scene.stick.radius_m);
  auto r = l ? find_rings(right, *right_stick, scene.stick.radius_m) : l;
  if (!l || !r) {
    // Say which eye lost which ring where the recorded geometry shows it.
    const std::string lost = rings_out_of_view(scene);
    const Error& err = !l ? l.error() : r.error();
    return Error{err.kind, std::string(!l ? "left" : "right") + " image: " + err.message +
                               (lost.empty() ? "" : "; out of view: " + lost +
                                                        " (a shorter stick, a farther one or a wider field of view "
                                                        "keeps every ring in both eyes)")};
  }
  const auto& fractions = renderer::kStickRingFractions;
  std::vector<std::array<geometry::SightLine, 2>> lines(fractions.size());
  std::size_t middle = 0;
  for (std::size_t i = 0; i < fractions.size(); ++i) {
    e.features.push_back(sighted(scene, fractions[i], l.value()[i], r.value()[i], lines[i]));
    if (std::abs(fractions[i]) < std::abs(fractions[middle])) middle = i;
  }
  if (vision != nullptr) e.human = geometry::perceive_human(*vision, eyes_of(scene), lines, middle);
  for (std::size_t i = 0; i < fractions.size(); ++i)
    place(scene, l.value()[i], r.value()[i],
          e.human ? e.human->points_m[i] : intersect(lines[i][0], lines[i][1]), e.features[i]);
  fit_stick(scene, e);
  return e;
}

nlohmann::ordered_json scene_json(const StickScene& s) {
  nlohmann::ordered_json j;
  j["space"] = std::string(geometry::to_string(s.space.kind));
  j["radius_m"] = s.space.radius_m;
  j["view_mode"] = std::string(geometry::to_string(s.preset));
  j["head"] = matrix_json(s.head.m);
  j["width_px"] = s.width_px;
  j["height_px"] = s.height_px;
  auto eyes = nlohmann::ordered_json::array();
  for (const auto& e : s.rig.eyes) {
    nlohmann::ordered_json eye;
    eye["position_m"] = {e.position_m.x, e.position_m.y, e.position_m.z};
    auto rot = nlohmann::ordered_json::array();
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) rot.push_back(e.rotation[c][r]);
    eye["rotation"] = rot;
    eye["fov_rad"] = {e.fov.angle_left_rad, e.fov.angle_right_rad, e.fov.angle_up_rad, e.fov.angle_down_rad};
    eyes.push_back(eye);
  }
  j["eyes"] = eyes;
  j["stick"] = {{"length_m", s.stick.length_m},
                {"radius_m", s.stick.radius_m},
                {"sagitta_m", s.stick.sagitta_m},
                {"marks", std::string(renderer::to_string(s.marks))},
                {"pose", matrix_json(s.stick_pose.m)}};
  return j;
}

namespace {

renderer::EyeOffset eye_from(const nlohmann::json& j) {
  renderer::EyeOffset e;
  const auto& p = j.at("position_m");
  e.position_m = {p.at(0).get<double>(), p.at(1).get<double>(), p.at(2).get<double>()};
  const auto& rot = j.at("rotation");
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) e.rotation[c][r] = rot.at(static_cast<std::size_t>(c * 3 + r)).get<double>();
  const auto& f = j.at("fov_rad");
  e.fov = {f.at(0).get<double>(), f.at(1).get<double>(), f.at(2).get<double>(), f.at(3).get<double>()};
  return e;
}

}  // namespace

Result<StickScene> parse_scene_json(const nlohmann::json& j) {
  StickScene s;
  try {
    const auto kind = geometry::parse_space_kind(j.at("space").get<std::string>());
    if (!kind) return bad("measure.space: expected S3, E3 or H3");
    s.space = geometry::Space{*kind, j.at("radius_m").get<double>()};
    const auto preset = geometry::parse_view_preset(j.at("view_mode").get<std::string>());
    if (!preset) return bad("measure.view_mode: expected " + geometry::alternatives_text(geometry::kViewPresets));
    s.preset = *preset;
    s.head = geometry::Isometry{matrix_from(j.at("head"))};
    s.width_px = j.at("width_px").get<std::uint32_t>();
    s.height_px = j.at("height_px").get<std::uint32_t>();
    for (std::size_t i = 0; i < 2; ++i) s.rig.eyes[i] = eye_from(j.at("eyes").at(i));
    const auto& st = j.at("stick");
    s.stick = geometry::BentStick{st.at("length_m").get<double>(), st.at("sagitta_m").get<double>(),
                                  st.at("radius_m").get<double>()};
    const auto marks = renderer::parse_stick_marks(st.at("marks").get<std::string>());
    if (!marks) return bad("measure.stick.marks: expected " + geometry::alternatives_text(renderer::kStickMarks));
    s.marks = *marks;
    s.stick_pose = geometry::Isometry{matrix_from(st.at("pose"))};
  } catch (const nlohmann::json::exception& e) {
    return bad(std::string("measure: ") + e.what() +
               " (expected space, radius_m, view_mode, head, width_px, height_px, eyes[2] with position_m, "
               "rotation, fov_rad, and stick with length_m, radius_m, sagitta_m, marks, pose)");
  }
  if (!(s.space.radius_m > 0.0) || s.width_px < 8 || s.height_px < 8 || !(s.stick.length_m > 0.0))
    return bad("measure: radius_m and stick.length_m must be positive and the images at least 8x8 px");
  return s;
}

nlohmann::ordered_json estimate_json(const StickEstimate& e) {
  nlohmann::ordered_json j;
  j["estimated_sagitta_m"] = e.estimated_sagitta_m;
  j["model_sagitta_m"] = e.model_sagitta_m;
  j["difference_m"] = e.estimated_sagitta_m - e.model_sagitta_m;
  j["estimated_bend_m"] = e.estimated_bend_m;
  j["model_bend_m"] = e.model_bend_m;
  j["binocular"] = e.binocular;
  j["fit_rms_m"] = e.fit_rms_m;
  auto features = nlohmann::ordered_json::array();
  for (const auto& f : e.features)
    features.push_back({{"name", f.name},
                        {"u_m", f.u_m},
                        {"left_px", {f.left_px.x, f.left_px.y}},
                        {"right_px", {f.right_px.x, f.right_px.y}},
                        {"position_m", {f.position_m.x, f.position_m.y, f.position_m.z}},
                        {"residual_left_px", f.residual_left_px},
                        {"residual_right_px", f.residual_right_px},
                        {"rows", f.rows},
                        {"depth_radii", f.depth_radii},
                        {"radius_seen_m", f.radius_seen_m}});
  j["features"] = features;
  return j;
}

}  // namespace curvlab::harness::measure
