// Balls in motion on the cloth: closed-form and developed motion between
// events, the root search that finds every event, and the collisions.
#include "curvlab/geometry/billiards.hpp"

#include "billiards_math.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace curvlab::geometry::billiards {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A contact is resolved once the gap is this small and closing.
constexpr double kContact_m = 1e-12;
// The most a touching, non-closing pair may close within one step of the
// search (below the invariants' 1e-9 m).
constexpr double kOverlap_m = 1e-10;
// A touching pair or cushion is a contact only when it closes faster than
// this fraction of its speeds: slower, the closing is rounding (the search's
// rate and the collision's normal speed are the same quantity computed two
// ways, and may differ in sign there), and a contact the collision then
// finds not closing would be found again at the same instant for ever. A
// pair closing that slowly overlaps by at most 1e-12 m per metre travelled.
constexpr double kClosingRel = 1e-12;
// How long two billiard balls stay in contact in a collision (about 200 µs;
// a ball struck again sooner is in a cluster, see resolve).
constexpr double kContactTime_s = 2e-4;
// The shortest step of the root search away from a touching contact.
constexpr double kMinStep_s = 1e-9;
// How far ahead one pass of the search looks before it stops to check.
constexpr double kHorizon_s = 1.0;
// Sliding paths in S3 and H3 are developed with Magnus steps this short.
constexpr double kMaxKnot_s = 1e-3;
constexpr double kMaxKnot_rad = 2e-3;

double spin_decay_rad_s2(const Parameters& p) {
  return 2.5 * p.mu_spin * p.g_m_s2 / p.radius_m;
}
double spin_rate(double w0, double alpha, double tau) {
  const double left = std::abs(w0) - alpha * tau;
  return left > 0.0 ? std::copysign(left, w0) : 0.0;
}
double spin_angle(double w0, double alpha, double tau) {
  const double a = std::abs(w0);
  if (alpha <= 0.0) return w0 * tau;
  const double t_stop = a / alpha;
  const double tt = std::min(tau, t_stop);
  return std::copysign(a * tt - 0.5 * alpha * tt * tt, w0);
}

Vec2 rot90(Vec2 n) { return {-n.y, n.x}; }

glm::dvec3 ambient(const Frame& f, Vec2 v) { return f[0] * v.x + f[1] * v.y; }

// One fourth-order Magnus step (two Gauss points) of F' = F·X(V(τ)/ρ) from τ
// to τ + h, V(τ) = v0 − a τ ŝ. Exact where the generators commute (E3, or
// a slip along the velocity).
Mat3 magnus_step(double k, double rho, Vec2 v0, double a, Vec2 s, double tau, double h) {
  const double g1 = tau + (0.5 - std::sqrt(3.0) / 6.0) * h;
  const double g2 = tau + (0.5 + std::sqrt(3.0) / 6.0) * h;
  const Vec2 V1 = (v0 - a * g1 * s) / rho;
  const Vec2 V2 = (v0 - a * g2 * s) / rho;
  const detail::Generator x1{V1.x, V1.y, 0.0};
  const detail::Generator x2{V2.x, V2.y, 0.0};
  const detail::Generator c = detail::commutator(k, x1, x2);
  const double w = std::sqrt(3.0) / 12.0 * h * h;
  const detail::Generator omega{0.5 * h * (x1.a + x2.a) + w * c.a, 0.5 * h * (x1.b + x2.b) + w * c.b,
                                w * c.c};
  return detail::exp(k, omega);
}

// The ball's orientation after it turned through the angle vector theta
// (radians, in the frame's coordinates).
Quat turned(const Quat& q0, const glm::dvec3& theta) {
  const double angle = glm::length(theta);
  if (angle < 1e-300) return q0;
  return glm::normalize(glm::angleAxis(angle, theta / angle) * q0);
}

// The 2-D ball's velocity and spin in a contact basis (N, up, T) and back.
struct Local {
  double vn, vt, wn, wu, wt;
};
Local to_local(const Ball& b, Vec2 n) {
  const Vec2 t = rot90(n);
  const Vec2 wh{b.w.x, b.w.z};
  return {glm::dot(b.v, n), glm::dot(b.v, t), glm::dot(wh, n), b.w.y, glm::dot(wh, t)};
}
void from_local(Ball& b, Vec2 n, const Local& l) {
  const Vec2 t = rot90(n);
  b.v = l.vn * n + l.vt * t;
  const Vec2 wh = l.wn * n + l.wt * t;
  b.w = {wh.x, l.wu, wh.y};
}

}  // namespace

System::System(Cloth cloth, Parameters params, std::vector<Ball> balls)
    : cloth_(std::move(cloth)), params_(params) {
  const std::size_t n = balls.size();
  segments_.resize(n);
  version_.assign(n, 0u);
  pairs_.resize(n * n);
  walls_.resize(n);
  last_hit_s_.assign(n, -kInf);
  for (std::size_t i = 0; i < n; ++i) begin_segment(i, 0.0, balls[i]);
  energy_ref_j_ = energy_last_j_ = kinetic_energy_j();
}

void System::begin_segment(std::size_t i, double t_s, Ball b) {
  const double k = cloth_.k();
  const double rho = cloth_.radius_m;
  Segment s;
  s.t0_s = t_s;
  b.frame = detail::reorthonormalize(k, b.frame);
  if (b.motion != Motion::pocketed) b.motion = classify(params_, b.v, b.w);
  const double g = params_.g_m_s2;
  switch (b.motion) {
    case Motion::pocketed:
    case Motion::stationary:
      b.v = Vec2{0.0};
      b.w = glm::dvec3{0.0};
      s.end_s = kInf;
      break;
    case Motion::spinning: {
      b.v = Vec2{0.0};
      b.w = {0.0, b.w.y, 0.0};
      const double alpha = spin_decay_rad_s2(params_);
      s.end_s = alpha > 0.0 ? t_s + std::abs(b.w.y) / alpha : kInf;
      s.end_kind = EventKind::stop;
      break;
    }
    case Motion::rolling: {
      const glm::dvec3 roll = rolling_spin(params_, b.v);
      b.w = {roll.x, b.w.y, roll.z};
      const double speed = glm::length(b.v);
      const double a = params_.mu_roll * g;
      s.accel_m_s2 = a;
      s.max_speed_m_s = speed;
      s.end_s = a > 0.0 ? t_s + speed / a : kInf;
      const double alpha = spin_decay_rad_s2(params_);
      const double spin_left = spin_rate(b.w.y, alpha, speed / std::max(a, 1e-300));
      s.end_kind = (a > 0.0 && std::abs(spin_left) > detail::kStillSpin_rad_s) ? EventKind::spinning
                                                                               : EventKind::stop;
      break;
    }
    case Motion::sliding: {
      const Vec2 u = detail::slip(params_, b.v, b.w);
      const double slip = glm::length(u);
      s.slip_dir = u / slip;
      const double a = params_.mu_slide * g;
      s.accel_m_s2 = a;
      const double duration = a > 0.0 ? slip / (3.5 * a) : kInf;
      s.end_s = t_s + duration;
      s.end_kind = EventKind::rolling;
      const double v_end =
          std::isfinite(duration) ? glm::length(b.v - a * duration * s.slip_dir) : glm::length(b.v);
      s.max_speed_m_s = std::max(glm::length(b.v), v_end);
      // The developed path: Magnus knots, needed only where the generators
      // do not commute (S3 and H3, slip not along the velocity).
      const double cross = std::abs(b.v.x * s.slip_dir.y - b.v.y * s.slip_dir.x);
      if (k != 0.0 && a > 0.0 && cross > 1e-15 * std::max(1.0, glm::length(b.v))) {
        const double h_max =
            std::min(kMaxKnot_s, kMaxKnot_rad * rho / std::max(s.max_speed_m_s, 1e-9));
        const auto steps = static_cast<std::size_t>(std::ceil(duration / h_max));
        s.h_s = duration / static_cast<double>(std::max<std::size_t>(steps, 1));
        s.knots.reserve(steps + 1);
        s.knots.push_back(b.frame);
        for (std::size_t n = 0; n < steps; ++n) {
          Frame next = s.knots.back() * magnus_step(k, rho, b.v, a, s.slip_dir,
                                                    static_cast<double>(n) * s.h_s, s.h_s);
          if ((n + 1) % 64 == 0) next = detail::reorthonormalize(k, next);
          s.knots.push_back(next);
        }
      }
      break;
    }
  }
  s.start = b;
  segments_[i] = std::move(s);
  ++version_[i];
}

Ball System::evaluate(const Segment& s, double t_s, Orientation orientation) const {
  Ball b = s.start;
  const bool orient = orientation == Orientation::track;
  double tau = std::max(0.0, t_s - s.t0_s);
  if (std::isfinite(s.end_s)) tau = std::min(tau, s.end_s - s.t0_s);
  const double k = cloth_.k();
  const double rho = cloth_.radius_m;
  const double alpha = spin_decay_rad_s2(params_);
  const Space space = cloth_.space();
  switch (b.motion) {
    case Motion::pocketed:
    case Motion::stationary: return b;
    case Motion::spinning:
      b.w.y = spin_rate(s.start.w.y, alpha, tau);
      if (orient) b.orientation = turned(b.orientation, {0.0, spin_angle(s.start.w.y, alpha, tau), 0.0});
      return b;
    case Motion::rolling: {
      const double v0 = glm::length(s.start.v);
      const Vec2 u = s.start.v / v0;
      const double dist = v0 * tau - 0.5 * s.accel_m_s2 * tau * tau;
      const double t = dist / rho;
      b.frame = s.start.frame * detail::translation(k, space.C(t), space.S(t), u);
      b.v = (v0 - s.accel_m_s2 * tau) * u;
      const glm::dvec3 roll = rolling_spin(params_, b.v);
      b.w = {roll.x, spin_rate(s.start.w.y, alpha, tau), roll.z};
      if (orient) {
        const glm::dvec3 turn = rolling_spin(params_, dist * u);
        b.orientation = turned(b.orientation, {turn.x, spin_angle(s.start.w.y, alpha, tau), turn.z});
      }
      return b;
    }
    case Motion::sliding: {
      const double a = s.accel_m_s2;
      const Vec2 sd = s.slip_dir;
      b.v = s.start.v - a * tau * sd;
      const double rate = 2.5 * a / params_.radius_m;  // dω/dt = (5μg/2R) (up × ŝ)
      b.w = {s.start.w.x + rate * tau * sd.y, spin_rate(s.start.w.y, alpha, tau),
             s.start.w.z - rate * tau * sd.x};
      if (s.knots.empty()) {
        b.frame = s.start.frame * magnus_step(k, rho, s.start.v, a, sd, 0.0, tau);
      } else {
        const auto last = s.knots.size() - 1;
        const auto n = std::min(static_cast<std::size_t>(tau / s.h_s), last);
        const double from = static_cast<double>(n) * s.h_s;
        b.frame = s.knots[n] * magnus_step(k, rho, s.start.v, a, sd, from, tau - from);
      }
      if (orient) {
        const glm::dvec3 turn{s.start.w.x * tau + 0.5 * rate * tau * tau * sd.y,
                              spin_angle(s.start.w.y, alpha, tau),
                              s.start.w.z * tau - 0.5 * rate * tau * tau * sd.x};
        b.orientation = turned(b.orientation, turn);
      }
      return b;
    }
  }
  return b;
}

Ball System::ball_at(std::size_t i, double t_s) const { return evaluate(segments_[i], t_s); }

bool System::all_still() const {
  return std::all_of(segments_.begin(), segments_.end(), [](const Segment& s) {
    return s.start.motion == Motion::stationary || s.start.motion == Motion::pocketed;
  });
}

void System::set_motion(std::size_t i, Vec2 v, const glm::dvec3& w) {
  Ball b = ball(i);
  if (b.motion == Motion::pocketed) return;
  b.v = v;
  b.w = w;
  b.motion = Motion::sliding;  // classified again by begin_segment
  begin_segment(i, t_s_, b);
  energy_ref_j_ = energy_last_j_ = kinetic_energy_j();
}

double System::kinetic_energy_j() const {
  const double m = params_.mass_kg;
  const double inertia = 0.4 * m * params_.radius_m * params_.radius_m;
  double e = 0.0;
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    const Ball b = evaluate(segments_[i], t_s_, Orientation::skip);
    e += 0.5 * m * glm::dot(b.v, b.v) + 0.5 * inertia * glm::dot(b.w, b.w);
  }
  return e;
}

namespace {

bool translating(Motion m) { return m == Motion::sliding || m == Motion::rolling; }

// The first t in [from, to] where gap(t) reaches 0 while closing faster
// than min_closing (m/s), given |gap''| ≤ bound. Each step goes as far as the lower bound
// gap + gap'·h − ½·bound·h² stays positive, so no root is stepped over.
template <class GapFn>
std::optional<double> first_contact(GapFn&& gap, double from, double to, double bound, double min_closing,
                                    long long& steps) {
  double t = from;
  bound = std::max(bound, 1e-300);
  while (t <= to) {
    ++steps;
    const auto [g, rate] = gap(t);
    if (g <= kContact_m && rate < -min_closing) return t;
    const double gp = std::max(g, 0.0);
    // The positive root of gap + rate·h − ½·bound·h² = 0, in the form that
    // does not cancel.
    const double root = std::sqrt(rate * rate + 2.0 * bound * gp);
    double h = rate < 0.0 ? 2.0 * gp / (root - rate) : (rate + root) / bound;
    // Touching and not closing (sliding along a cushion, two balls moving
    // together): a step that lets the gap close by at most kOverlap_m.
    if (g <= kContact_m) h = std::max({h, kMinStep_s, std::sqrt(2.0 * kOverlap_m / bound)});
    if (!(h > 0.0)) h = kMinStep_s;
    if (t + h == t) return t;  // no progress left in double: touching here
    t += h;
  }
  return std::nullopt;
}

}  // namespace

void System::search_pair(std::size_t i, std::size_t j, Search& s, double to_s) {
  const Segment& si = segments_[i];
  const Segment& sj = segments_[j];
  const double end = std::min({to_s, si.end_s, sj.end_s});
  if (s.found || s.searched_to_s >= end) return;
  if (si.start.motion == Motion::pocketed || sj.start.motion == Motion::pocketed ||
      (!translating(si.start.motion) && !translating(sj.start.motion))) {
    s.searched_to_s = std::min(si.end_s, sj.end_s);
    return;
  }
  const Space space = cloth_.space();
  const double k = cloth_.k();
  const double rho = cloth_.radius_m;
  const double two_r = 2.0 * params_.radius_m;
  const auto gap = [&](double t) {
    const Ball bi = evaluate(si, t, Orientation::skip);
    const Ball bj = evaluate(sj, t, Orientation::skip);
    const glm::dvec3 pi = bi.frame[2] * rho;
    const glm::dvec3 pj = bj.frame[2] * rho;
    const double d = detail::distance_rad(space, pi, pj) * rho;
    const double rate = -detail::vector_form(k, ambient(bi.frame, bi.v), detail::direction(space, pi, pj)) -
                        detail::vector_form(k, ambient(bj.frame, bj.v), detail::direction(space, pj, pi));
    return std::pair{d - two_r, rate};
  };
  const double speeds = si.max_speed_m_s + sj.max_speed_m_s;
  const double bound = si.accel_m_s2 + sj.accel_m_s2 + speeds * speeds * (1.0 / two_r + 1.0 / rho);
  const auto t = first_contact(gap, s.searched_to_s, end, bound, kClosingRel * speeds, root_steps_);
  if (t) {
    Event e;
    e.t_s = *t;
    e.kind = EventKind::ball;
    e.a = static_cast<int>(i);
    e.b = static_cast<int>(j);
    s.found = e;
    s.searched_to_s = *t;
  } else {
    s.searched_to_s = end;
  }
}

namespace {

// The first σ ≥ σ_now where A·C(σ) + B·S(σ) falls through c (a ball rolling
// along a geodesic reaching R from an edge's line), in closed form per
// space, polished by two Newton steps; nothing where it never does.
std::optional<double> first_descending_root(const Space& space, double A, double B, double c, double sigma_now) {
  const double k = space.k();
  const auto f = [&](double x) { return A * space.C(x) + B * space.S(x); };
  const auto fd = [&](double x) { return -k * A * space.S(x) + B * space.C(x); };
  std::optional<double> sigma;
  const auto consider = [&](double x) {
    if (!std::isfinite(x) || x < sigma_now - 1e-12 || fd(x) >= 0.0) return;
    if (!sigma || x < *sigma) sigma = x;
  };
  if (k == 0.0) {
    if (B < 0.0) consider((c - A) / B);
  } else if (k > 0.0) {
    const double M = std::hypot(A, B);
    if (M > c) {
      const double phi = std::atan2(B, A);
      double x = phi + std::acos(c / M);
      const double turn = 2.0 * std::numbers::pi;
      x -= turn * std::floor((x - sigma_now + 1e-9) / turn);
      consider(x);
    }
  } else {
    const double P = A + B, Q = A - B;
    const double disc = c * c - P * Q;
    if (disc >= 0.0) {
      const double q = c + std::sqrt(disc);
      if (P != 0.0 && q / P > 0.0) consider(std::log(q / P));
      if (Q / q > 0.0) consider(std::log(Q / q));
    }
  }
  if (!sigma) return std::nullopt;
  double x = *sigma;
  for (int it = 0; it < 2; ++it) {
    const double d = fd(x);
    if (d != 0.0) x -= (f(x) - c) / d;
  }
  return x;
}

}  // namespace

void System::search_walls(std::size_t i, Search& s, double to_s) {
  const Segment& seg = segments_[i];
  const double end = std::min(to_s, seg.end_s);
  if (s.found || s.searched_to_s >= end) return;
  if (!translating(seg.start.motion)) {
    s.searched_to_s = seg.end_s;
    return;
  }
  const Space space = cloth_.space();
  const double k = cloth_.k();
  const double rho = cloth_.radius_m;
  const double R = params_.radius_m;
  std::optional<Event> best;
  const auto offer = [&](double t, EventKind kind, int index) {
    if (t > end || (best && best->t_s <= t)) return;
    Event e;
    e.t_s = t;
    e.kind = kind;
    e.a = static_cast<int>(i);
    (kind == EventKind::cushion ? e.cushion : e.pocket) = index;
    best = e;
  };
  const int sides = cloth_.table.sides;
  for (int edge = 0; edge < sides; ++edge) {
    const glm::dvec3& nu = cloth_.edges[static_cast<std::size_t>(edge)];
    if (seg.start.motion == Motion::rolling) {
      // Closed form along the geodesic: A·C(σ) + B·S(σ) = ρ·S(R/ρ).
      const double v0 = glm::length(seg.start.v);
      const Vec2 u = seg.start.v / v0;
      const double A = glm::dot(seg.start.frame[2] * rho, nu);
      const double B = rho * glm::dot(ambient(seg.start.frame, u), nu);
      const double c = rho * space.S(R / rho);
      const double a = seg.accel_m_s2;
      const double tau_now = s.searched_to_s - seg.t0_s;
      const double sigma_now = (v0 * tau_now - 0.5 * a * tau_now * tau_now) / rho;
      const std::optional<double> sigma = first_descending_root(space, A, B, c, sigma_now);
      if (!sigma) continue;
      const double dist = *sigma * rho;
      const double disc = v0 * v0 - 2.0 * a * dist;
      if (disc < 0.0) continue;
      const double tau = 2.0 * dist / (v0 + std::sqrt(disc));
      ++root_steps_;
      offer(std::max(seg.t0_s + tau, s.searched_to_s), EventKind::cushion, edge);
    } else {
      const auto gap = [&](double t) {
        const Ball b = evaluate(seg, t, Orientation::skip);
        const glm::dvec3 p = b.frame[2] * rho;
        const double sd = glm::dot(p, nu) / rho;
        const double d = space.S_inv(sd) * rho;
        const double rate = glm::dot(ambient(b.frame, b.v), nu) / space.C(d / rho);
        return std::pair{d - R, rate};
      };
      const double bound =
          seg.accel_m_s2 + seg.max_speed_m_s * seg.max_speed_m_s * (k != 0.0 ? 2.0 / rho : 0.0);
      if (auto t = first_contact(gap, s.searched_to_s, end, bound, kClosingRel * seg.max_speed_m_s, root_steps_))
        offer(*t, EventKind::cushion, edge);
    }
  }
  if (params_.pocket_radius_m > 0.0) {
    for (int corner = 0; corner < sides; ++corner) {
      const glm::dvec3& q = cloth_.corners[static_cast<std::size_t>(corner)];
      const auto gap = [&](double t) {
        const Ball b = evaluate(seg, t, Orientation::skip);
        const glm::dvec3 p = b.frame[2] * rho;
        const double d = detail::distance_rad(space, p, q) * rho;
        const double rate = -detail::vector_form(k, ambient(b.frame, b.v), detail::direction(space, p, q));
        return std::pair{d - params_.pocket_radius_m, rate};
      };
      const double bound = seg.accel_m_s2 + seg.max_speed_m_s * seg.max_speed_m_s *
                                                (1.0 / params_.pocket_radius_m + 1.0 / rho);
      if (auto t = first_contact(gap, s.searched_to_s, end, bound, 0.0, root_steps_))
        offer(*t, EventKind::pocket, corner);
    }
  }
  if (best) {
    s.found = best;
    s.searched_to_s = best->t_s;
  } else {
    s.searched_to_s = end;
  }
}

std::optional<Event> System::next_event(double until_s) {
  const std::size_t n = segments_.size();
  while (true) {
    if (all_still()) return std::nullopt;
    // The earliest change of state bounds how far the contacts are searched.
    std::optional<Event> best;
    double best_t = std::min(until_s, t_s_ + kHorizon_s);
    for (std::size_t i = 0; i < n; ++i) {
      const Segment& s = segments_[i];
      if (s.end_s <= best_t && std::isfinite(s.end_s)) {
        Event e;
        e.t_s = s.end_s;
        e.kind = s.end_kind;
        e.a = static_cast<int>(i);
        best = e;
        best_t = s.end_s;
      }
    }
    const auto consider = [&](Search& s) {
      if (s.found && s.found->t_s < best_t) {
        best = s.found;
        best_t = s.found->t_s;
      }
    };
    for (std::size_t i = 0; i < n; ++i) {
      Search& w = walls_[i];
      if (w.vi != version_[i]) w = Search{version_[i], 0u, t_s_, std::nullopt};
      search_walls(i, w, best_t);
      consider(w);
    }
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) {
        Search& p = pairs_[i * n + j];
        if (p.vi != version_[i] || p.vj != version_[j])
          p = Search{version_[i], version_[j], t_s_, std::nullopt};
        search_pair(i, j, p, best_t);
        consider(p);
      }
    if (best) {
      resolve(*best);
      return best;
    }
    t_s_ = best_t;
    if (t_s_ >= until_s) return std::nullopt;
  }
}

void System::resolve(const Event& e) {
  t_s_ = std::max(t_s_, e.t_s);
  const auto i = static_cast<std::size_t>(e.a);
  Ball a = evaluate(segments_[i], e.t_s);
  switch (e.kind) {
    case EventKind::rolling:
    case EventKind::spinning:
    case EventKind::stop:
      // classify() in begin_segment snaps the state: no slip, no speed, no spin.
      if (e.kind == EventKind::rolling) {
        const glm::dvec3 roll = rolling_spin(params_, a.v);
        a.w = {roll.x, a.w.y, roll.z};
      } else {
        a.v = Vec2{0.0};
        a.w = {0.0, e.kind == EventKind::spinning ? a.w.y : 0.0, 0.0};
      }
      begin_segment(i, e.t_s, a);
      break;
    case EventKind::pocket:
      a.motion = Motion::pocketed;
      a.pocket = e.pocket;
      begin_segment(i, e.t_s, a);
      break;
    case EventKind::cushion:
      if (collide_cushion(cloth_, params_, a, e.cushion)) a.motion = Motion::sliding;
      begin_segment(i, e.t_s, a);
      break;
    case EventKind::ball: {
      const auto j = static_cast<std::size_t>(e.b);
      Ball b = evaluate(segments_[j], e.t_s);
      // A ball struck again within the contact time of its last collision
      // is in a cluster: that collision is elastic, so the cluster does not
      // collapse into ever smaller bounces (the TC model of event-driven
      // granular simulation: Luding & McNamara 1998, Granular Matter 1, 113).
      Parameters p = params_;
      if (e.t_s - last_hit_s_[i] < kContactTime_s || e.t_s - last_hit_s_[j] < kContactTime_s) p.restitution_ball = 1.0;
      last_hit_s_[i] = last_hit_s_[j] = e.t_s;
      if (collide_balls(cloth_, p, a, b)) a.motion = b.motion = Motion::sliding;
      begin_segment(i, e.t_s, a);
      begin_segment(j, e.t_s, b);
      break;
    }
  }
  check_after(e);
}

bool collide_cushion(const Cloth& cloth, const Parameters& p, Ball& a, int edge) {
  const double m = p.mass_kg;
  const double R = p.radius_m;
  const double inertia = 0.4 * m * R * R;
  const glm::dvec3& nu = cloth.edges[static_cast<std::size_t>(edge)];
  const Vec2 inward{glm::dot(a.frame[0], nu), glm::dot(a.frame[1], nu)};
  const Vec2 n = -glm::normalize(inward);  // toward the cushion
  Local l = to_local(a, n);
  if (!(l.vn > 0.0)) return false;
  const double jn = m * (1.0 + p.restitution_cushion) * l.vn;
  l.vn = -p.restitution_cushion * l.vn;
  const double slip = l.vt - R * l.wu;
  const double jt = std::min(p.friction_cushion * jn, 2.0 * m * std::abs(slip) / 7.0);
  const double sign = slip > 0.0 ? 1.0 : -1.0;
  l.vt -= sign * jt / m;
  l.wu += sign * R * jt / inertia;
  from_local(a, n, l);
  return true;
}

bool collide_balls(const Cloth& cloth, const Parameters& p, Ball& a, Ball& b) {
  const Space space = cloth.space();
  const double k = cloth.k();
  const double rho = cloth.radius_m;
  const double m = p.mass_kg;
  const double R = p.radius_m;
  const double inertia = 0.4 * m * R * R;
  const glm::dvec3 pa = a.frame[2] * rho;
  const glm::dvec3 pb = b.frame[2] * rho;
  const glm::dvec3 da = detail::direction(space, pa, pb);
  const glm::dvec3 db = detail::direction(space, pb, pa);
  // Each ball's normal toward the other in its own frame; parallel
  // transport along the joining geodesic takes one to minus the other.
  const Vec2 na = glm::normalize(Vec2{detail::vector_form(k, da, a.frame[0]), detail::vector_form(k, da, a.frame[1])});
  const Vec2 nb = -glm::normalize(Vec2{detail::vector_form(k, db, b.frame[0]), detail::vector_form(k, db, b.frame[1])});
  Local la = to_local(a, na);
  Local lb = to_local(b, nb);
  const double closing = la.vn - lb.vn;
  if (!(closing > 0.0)) return false;
  const double jn = 0.5 * m * (1.0 + p.restitution_ball) * closing;
  la.vn -= jn / m;
  lb.vn += jn / m;
  const double slip = (la.vt - R * la.wu) - (lb.vt + R * lb.wu);
  const double jt = std::min(p.friction_ball * jn, m * std::abs(slip) / 7.0);
  const double sign = slip > 0.0 ? 1.0 : -1.0;
  la.vt -= sign * jt / m;
  lb.vt += sign * jt / m;
  la.wu += sign * R * jt / inertia;
  lb.wu += sign * R * jt / inertia;
  from_local(a, na, la);
  from_local(b, nb, lb);
  return true;
}

void System::check_after(const Event& e) {
  const double rho = cloth_.radius_m;
  const double R = params_.radius_m;
  const std::size_t n = segments_.size();
  const Space space = cloth_.space();
  std::vector<Ball> now(n);
  for (std::size_t i = 0; i < n; ++i) now[i] = evaluate(segments_[i], t_s_, Orientation::skip);
  for (int who : {e.a, e.b}) {
    if (who < 0) continue;
    const auto w = static_cast<std::size_t>(who);
    const glm::dvec3 p = now[w].frame[2] * rho;
    invariants_.max_off_surface_rel =
        std::max(invariants_.max_off_surface_rel, off_cloth_error(cloth_, p));
    if (now[w].motion == Motion::pocketed) continue;
    for (int edge = 0; edge < cloth_.table.sides; ++edge)
      invariants_.max_overlap_m =
          std::max(invariants_.max_overlap_m, R - edge_distance_m(cloth_, p, edge));
    for (std::size_t j = 0; j < n; ++j) {
      if (j == w || now[j].motion == Motion::pocketed) continue;
      const double d = detail::distance_rad(space, p, now[j].frame[2] * rho) * rho;
      invariants_.max_overlap_m = std::max(invariants_.max_overlap_m, 2.0 * R - d);
    }
  }
  const double energy = kinetic_energy_j();
  if (energy_ref_j_ > 0.0) {
    invariants_.energy_change_rel = (energy - energy_ref_j_) / energy_ref_j_;
    invariants_.max_energy_rise_rel =
        std::max(invariants_.max_energy_rise_rel, (energy - energy_last_j_) / energy_ref_j_);
  }
  energy_last_j_ = energy;
}

}  // namespace curvlab::geometry::billiards
