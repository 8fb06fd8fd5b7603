#include "curvlab/geometry/space.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace curvlab::geometry {

std::string_view to_string(SpaceKind kind) {
  switch (kind) {
    case SpaceKind::S3: return "S3";
    case SpaceKind::E3: return "E3";
    case SpaceKind::H3: return "H3";
  }
  return "?";
}

std::optional<SpaceKind> parse_space_kind(std::string_view text) {
  if (text == "S3" || text == "s3") return SpaceKind::S3;
  if (text == "E3" || text == "e3") return SpaceKind::E3;
  if (text == "H3" || text == "h3") return SpaceKind::H3;
  return std::nullopt;
}

double Space::k() const {
  switch (kind) {
    case SpaceKind::S3: return 1.0;
    case SpaceKind::E3: return 0.0;
    case SpaceKind::H3: return -1.0;
  }
  return 0.0;
}

double Space::C(double t) const {
  switch (kind) {
    case SpaceKind::S3: return std::cos(t);
    case SpaceKind::E3: return 1.0;
    case SpaceKind::H3: return std::cosh(t);
  }
  return 1.0;
}

double Space::S(double t) const {
  switch (kind) {
    case SpaceKind::S3: return std::sin(t);
    case SpaceKind::E3: return t;
    case SpaceKind::H3: return std::sinh(t);
  }
  return t;
}

// Below this |t| the Taylor series S(t)/t = 1 + k t²/6 + t⁴/120 (k² = 1)
// is exact to double precision (the next term is t⁶/5040 < 1e-20).
static constexpr double kSeriesLimit = 1e-3;

double Space::sinc(double t) const {
  const double kk = k();
  if (std::abs(t) < kSeriesLimit) {
    const double t2 = t * t;
    return 1.0 - kk * t2 / 6.0 + kk * kk * t2 * t2 / 120.0;
  }
  return S(t) / t;
}

double Space::inv_sinc(double t) const {
  const double kk = k();
  if (std::abs(t) < kSeriesLimit) {
    // t/S(t) = 1 + k t²/6 + 7 k² t⁴/360 + …
    const double t2 = t * t;
    return 1.0 + kk * t2 / 6.0 + 7.0 * kk * kk * t2 * t2 / 360.0;
  }
  return t / S(t);
}

double Space::S_inv(double s) const {
  switch (kind) {
    case SpaceKind::S3: return std::asin(std::clamp(s, -1.0, 1.0));
    case SpaceKind::E3: return s;
    case SpaceKind::H3: return std::asinh(s);
  }
  return s;
}

double Space::C_inv(double c) const {
  switch (kind) {
    case SpaceKind::S3: return std::acos(std::clamp(c, -1.0, 1.0));
    case SpaceKind::E3: return 0.0;
    case SpaceKind::H3: return std::acosh(std::max(c, 1.0));
  }
  return 0.0;
}

double Space::arc(double s, double c) const {
  switch (kind) {
    case SpaceKind::S3: return std::atan2(s, c);
    case SpaceKind::E3: return s;
    case SpaceKind::H3: return std::asinh(s);
  }
  return s;
}

double point_form(const Space& space, const Vec4& a, const Vec4& b) {
  return space.k() * (a.x * b.x + a.y * b.y + a.z * b.z) + a.w * b.w;
}

double vector_form(const Space& space, const Vec4& a, const Vec4& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z + space.k() * a.w * b.w;
}

Point origin(const Space& space) { return {0.0, 0.0, 0.0, space.radius_m}; }

double off_space_error(const Space& space, const Point& p) {
  for (int i = 0; i < 4; ++i)
    if (!std::isfinite(p[i])) return std::numeric_limits<double>::infinity();
  const double rho2 = space.radius_m * space.radius_m;
  if (space.kind == SpaceKind::H3 && p.w <= 0.0)
    return std::numeric_limits<double>::infinity();
  if (space.kind == SpaceKind::E3) return std::abs(p.w - space.radius_m) / space.radius_m;
  // In H3 both terms of P can be huge: measure relative to w² as well, so a
  // far point is judged by its own magnitude, not by ρ² alone.
  const double scale = std::max(rho2, p.w * p.w);
  return std::abs(point_form(space, p, p) - rho2) / scale;
}

double norm3(double x, double y, double z) {
  const double m = std::max({std::abs(x), std::abs(y), std::abs(z)});
  if (m > 1e150 || (m < 1e-150 && m > 0.0)) {
    const double a = x / m, b = y / m, c = z / m;
    return m * std::sqrt(a * a + b * b + c * c);
  }
  return std::sqrt(x * x + y * y + z * z);
}

bool nearly_equal(double a, double b, double tol, double magnitude) {
  return std::abs(a - b) <= tol * std::max(1.0, std::abs(magnitude));
}

}  // namespace curvlab::geometry
