// The cloth, its frames and coordinates, the parameters, the cue and the
// rack. The moving system is in billiards_system.cpp.
#include "curvlab/geometry/billiards.hpp"

#include "billiards_math.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

namespace curvlab::geometry::billiards {
namespace {

constexpr std::array<ParameterInfo, 13> kParameters{{
    {"radius_m", &Parameters::radius_m, 1e-3, 0.5, "ball radius R (m)"},
    {"mass_kg", &Parameters::mass_kg, 1e-3, 100.0, "ball mass (kg)"},
    {"mu_slide", &Parameters::mu_slide, 0.0, 2.0, "sliding friction coefficient"},
    {"mu_roll", &Parameters::mu_roll, 0.0, 1.0, "rolling resistance coefficient"},
    {"mu_spin", &Parameters::mu_spin, 0.0, 2.0, "spin decay coefficient (vertical axis)"},
    {"restitution_ball", &Parameters::restitution_ball, 0.0, 1.0, "ball–ball restitution"},
    {"restitution_cushion", &Parameters::restitution_cushion, 0.0, 1.0, "ball–cushion restitution"},
    {"friction_ball", &Parameters::friction_ball, 0.0, 1.0, "ball–ball friction (0: no throw)"},
    {"friction_cushion", &Parameters::friction_cushion, 0.0, 2.0, "ball–cushion friction (0: none)"},
    {"g_m_s2", &Parameters::g_m_s2, 0.0, 100.0, "gravity (m/s²)"},
    {"pocket_radius_m", &Parameters::pocket_radius_m, 0.0, 0.5,
     "pocket radius at each corner (m; 0: no pockets)"},
    {"cue_mass_kg", &Parameters::cue_mass_kg, 0.01, 10.0, "cue mass (kg)"},
    {"miscue_fraction", &Parameters::miscue_fraction, 0.0, 1.0,
     "largest tip offset that does not miscue (fraction of R)"},
}};

}  // namespace

std::span<const ParameterInfo> parameter_table() { return kParameters; }

const ParameterInfo* find_parameter(std::string_view name) {
  for (const auto& info : kParameters)
    if (info.name == name) return &info;
  return nullptr;
}

std::optional<std::string> set_parameter(Parameters& p, std::string_view name, double value) {
  const ParameterInfo* info = find_parameter(name);
  if (info == nullptr) {
    std::string known;
    for (const auto& i : kParameters) known += (known.empty() ? "" : ", ") + std::string(i.name);
    return "unknown billiards parameter \"" + std::string(name) + "\": expected one of " + known;
  }
  if (!std::isfinite(value) || value < info->min || value > info->max) {
    std::ostringstream os;
    os << "billiards parameter " << name << " = " << value << " is out of range: expected "
       << info->meaning << " in [" << info->min << ", " << info->max << "]";
    return os.str();
  }
  p.*(info->field) = value;
  return std::nullopt;
}

std::string_view to_string(Motion motion) {
  switch (motion) {
    case Motion::sliding: return "sliding";
    case Motion::rolling: return "rolling";
    case Motion::spinning: return "spinning";
    case Motion::stationary: return "stationary";
    case Motion::pocketed: return "pocketed";
  }
  return "?";
}

std::string_view to_string(EventKind kind) {
  switch (kind) {
    case EventKind::ball: return "ball";
    case EventKind::cushion: return "cushion";
    case EventKind::pocket: return "pocket";
    case EventKind::rolling: return "rolling";
    case EventKind::spinning: return "spinning";
    case EventKind::stop: return "stop";
  }
  return "?";
}

// ---- the cloth -----------------------------------------------------------

Cloth make_cloth(const Space& space, const TableShape& table) {
  Cloth c;
  c.kind = space.kind;
  c.radius_m = space.radius_m;
  c.table = table;
  for (int j = 0; j < table.sides; ++j) {
    const Point p = table_corner(space, table, j);
    c.corners.emplace_back(p.x, p.z, p.w);
  }
  const double k = space.k();
  for (int j = 0; j < table.sides; ++j) {
    const glm::dvec3& a = c.corners[static_cast<std::size_t>(j)];
    const glm::dvec3& b = c.corners[static_cast<std::size_t>((j + 1) % table.sides)];
    glm::dvec3 nu = glm::cross(a, b);
    nu /= std::sqrt(nu.x * nu.x + nu.y * nu.y + k * nu.z * nu.z);
    if (nu.z < 0.0) nu = -nu;  // the centre (0, 0, ρ) is inside: p·ν > 0
    c.edges.push_back(nu);
  }
  return c;
}

double distance_m(const Cloth& cloth, const glm::dvec3& p, const glm::dvec3& q) {
  return detail::distance_rad(cloth.space(), p, q) * cloth.radius_m;
}

double edge_distance_m(const Cloth& cloth, const glm::dvec3& p, int edge) {
  const Space space = cloth.space();
  return space.S_inv(glm::dot(p, cloth.edges[static_cast<std::size_t>(edge)]) / cloth.radius_m) *
         cloth.radius_m;
}

double off_cloth_error(const Cloth& cloth, const glm::dvec3& p) {
  const double rho2 = cloth.radius_m * cloth.radius_m;
  return std::abs(detail::point_form(cloth.k(), p, p) - rho2) / rho2;
}

glm::dvec3 from_native(const Cloth& cloth, Vec2 native_m) {
  const Space space = cloth.space();
  const double d = glm::length(native_m);
  const double t = d / cloth.radius_m;
  // ρ S(t) u = sinc(t) · native, with u the native direction
  return {space.sinc(t) * native_m.x, space.sinc(t) * native_m.y, cloth.radius_m * space.C(t)};
}

Vec2 to_native(const Cloth& cloth, const glm::dvec3& p) {
  const Space space = cloth.space();
  const double r = std::hypot(p.x, p.y);
  const double t = space.arc(r / cloth.radius_m, p.z / cloth.radius_m);
  if (r == 0.0) return Vec2{0.0};
  // ρ t · (x, z)/r = (t / S(t)) · (x, z)
  return space.inv_sinc(t) * Vec2{p.x, p.y};
}

Frame frame_at(const Cloth& cloth, const glm::dvec3& p) {
  const Space space = cloth.space();
  const double r = std::hypot(p.x, p.y);
  if (r == 0.0) return Frame{1.0};
  const double t = space.arc(r / cloth.radius_m, p.z / cloth.radius_m);
  const Vec2 u{p.x / r, p.y / r};
  return detail::translation(cloth.k(), space.C(t), space.S(t), u);
}

glm::dvec3 frame_position(const Cloth& cloth, const Frame& f) { return f[2] * cloth.radius_m; }

Vec2 direction_toward(const Cloth& cloth, const Frame& f, const glm::dvec3& q) {
  const Space space = cloth.space();
  const glm::dvec3 p = frame_position(cloth, f);
  const glm::dvec3 dir = detail::direction(space, p, q);
  const double k = cloth.k();
  return glm::normalize(Vec2{detail::vector_form(k, dir, f[0]), detail::vector_form(k, dir, f[1])});
}

Isometry to_isometry(const Frame& f) {
  // Cloth coordinates (x, z, w) are the space's (x, z, w); y is untouched.
  Isometry iso;
  const int map[3] = {0, 2, 3};
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) iso.m[map[c]][map[r]] = f[c][r];
  return iso;
}

// ---- balls ---------------------------------------------------------------

glm::dvec3 rolling_spin(const Parameters& p, Vec2 v) {
  // No slip at the contact point: u = (v_x + R w_z, v_z − R w_x) = 0.
  return {v.y / p.radius_m, 0.0, -v.x / p.radius_m};
}

Motion classify(const Parameters& p, Vec2 v, const glm::dvec3& w) {
  const Vec2 u = detail::slip(p, v, w);
  const double speed = glm::length(v);
  if (glm::length(u) > detail::kSlipTolerance_m_s) return Motion::sliding;
  if (speed > detail::kStillSpeed_m_s) return Motion::rolling;
  if (std::abs(w.y) > detail::kStillSpin_rad_s) return Motion::spinning;
  return Motion::stationary;
}

double speed_m_s(const Ball& b) { return glm::length(b.v); }

Strike cue_strike(const Parameters& p, Vec2 aim_unit, double cue_speed_m_s, Vec2 tip_fraction) {
  Strike s;
  if (glm::length(tip_fraction) > p.miscue_fraction) {
    s.miscue = true;
    return s;
  }
  // A level cue's instantaneous impulse J through the contact point at
  // side a and height b (metres) from the centre: the ball leaves along the
  // aim with J/m and turns with (r × J)/I (Marlow 1995; pooltool's
  // instantaneous point model with the cue elevation 0).
  const double R = p.radius_m;
  const double a = tip_fraction.x * R;
  const double b = tip_fraction.y * R;
  const double m = p.mass_kg;
  const double inertia = 0.4 * m * R * R;
  const double impulse =
      2.0 * m * cue_speed_m_s / (1.0 + m / p.cue_mass_kg + 2.5 * (a * a + b * b) / (R * R));
  const glm::dvec3 d{aim_unit.x, 0.0, aim_unit.y};
  const glm::dvec3 up{0.0, 1.0, 0.0};
  const glm::dvec3 side = glm::cross(d, up);  // to the right of the aim
  s.v = aim_unit * (impulse / m);
  s.w = (impulse / inertia) * (a * up - b * side);
  return s;
}

// ---- the rack ------------------------------------------------------------

std::variant<std::vector<RackBall>, GeometryError> rack(const Cloth& cloth, const Parameters& p,
                                                        int object_balls) {
  if (object_balls < 0 || object_balls > 15)
    return GeometryError{"a rack holds 0 to 15 object balls, not " + std::to_string(object_balls)};
  const double R = p.radius_m;
  const double apothem = cloth.table.apothem_m();
  std::vector<Vec2> rows;  // the triangle, apex at (0, 0), growing toward −z
  for (int row = 0; static_cast<int>(rows.size()) < object_balls; ++row)
    for (int i = 0; i <= row && static_cast<int>(rows.size()) < object_balls; ++i)
      rows.emplace_back((i - row / 2.0), -row * std::sqrt(3.0) / 2.0);
  const double gap = 1e-4 * R;
  const auto fits = [&](const std::vector<glm::dvec3>& pts) {
    for (std::size_t i = 0; i < pts.size(); ++i) {
      for (int e = 0; e < cloth.table.sides; ++e)
        if (edge_distance_m(cloth, pts[i], e) < R + gap) return false;
      for (int c = 0; c < cloth.table.sides && p.pocket_radius_m > 0.0; ++c)
        if (distance_m(cloth, pts[i], cloth.corners[static_cast<std::size_t>(c)]) <
            p.pocket_radius_m + gap)
          return false;
    }
    return true;
  };
  const glm::dvec3 cue = from_native(cloth, {0.0, apothem / 2.0});
  // The apex on the foot spot, moved toward the centre until the rack fits;
  // the spacing widened until no two balls are closer than 2R + gap.
  for (double apex_z = -apothem / 2.0; apex_z <= 0.0; apex_z += apothem / 64.0) {
    double spacing = 2.0 * R + 2.0 * gap;
    std::vector<glm::dvec3> pts;
    for (int attempt = 0; attempt < 200; ++attempt) {
      pts.clear();
      for (const Vec2& r : rows) pts.push_back(from_native(cloth, Vec2{0.0, apex_z} + spacing * r));
      double closest = 1e300;
      for (std::size_t i = 0; i < pts.size(); ++i)
        for (std::size_t j = i + 1; j < pts.size(); ++j)
          closest = std::min(closest, distance_m(cloth, pts[i], pts[j]));
      if (closest >= 2.0 * R + gap) break;
      spacing *= (2.0 * R + 1.5 * gap) / closest;
    }
    pts.push_back(cue);
    bool apart = true;
    for (std::size_t i = 0; i + 1 < pts.size(); ++i)
      if (distance_m(cloth, pts[i], cue) < 2.0 * R + gap) apart = false;
    if (!apart || !fits(pts)) continue;
    std::vector<RackBall> out;
    out.push_back({"cue", to_native(cloth, cue)});
    for (std::size_t i = 0; i + 1 < pts.size(); ++i)
      out.push_back({std::to_string(i + 1), to_native(cloth, pts[i])});
    return out;
  }
  return GeometryError{"a rack of " + std::to_string(object_balls) +
                       " balls does not fit on this table"};
}

}  // namespace curvlab::geometry::billiards
