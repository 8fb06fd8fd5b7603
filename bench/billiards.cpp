// Billiards on the curved cloth (docs/billiards.md, "Benchmarks"). Prints:
//  (a) time against error: the exact event-based System against a naive
//      fixed-step integrator of the same physics (the same motion states and
//      collision laws, but contacts found by overlap after each step and
//      resolved then), at steps of 1, 0.1 and 0.01 ms, on a break, a fast
//      straight shot into a ball near a cushion and a thin cut, in S3, E3, H3;
//  (b) a 16-ball break per space: events and time per break;
//  (c) the per-frame cost of play: the 16 balls' states at a 90 Hz frame's
//      time during a break, against the headset's 11.1 ms frame;
//  (d) with --stress [EVENTS] (default 10⁶): a conservative table (no
//      friction, restitution 1, no pockets) run for EVENTS events per space,
//      with the worst invariants and events per second;
//  (e) random breaks with the real parameters (aim, cue speed and tip drawn
//      at random, seeded): events per break, the breaks that reach the event
//      limit a shot stops at (20 000, harness billiards/shot.hpp), the worst
//      overlap and energy rise, and time per break.
// Usage: bench_billiards [--quick] [--stress [EVENTS]]
//   --quick runs tiny versions of every table (a smoke run).
#include "curvlab/geometry/billiards.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <variant>
#include <vector>

namespace {

using namespace curvlab::geometry;
using namespace curvlab::geometry::billiards;
using Clock = std::chrono::steady_clock;

constexpr std::array kKinds{SpaceKind::S3, SpaceKind::E3, SpaceKind::H3};
// The longest simulated time of any shot here; every shot stops long before.
constexpr double kUntil_s = 120.0;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

Cloth table_cloth(SpaceKind kind) {
  const auto shape =
      std::get<TableShape>(right_angled_table_from_edge(kind, 1.0, default_table_sides(kind), 1.0));
  return make_cloth(Space{kind, shape.radius_m}, shape);
}

Ball ball_at_native(const Cloth& c, Vec2 native_m) {
  Ball b;
  b.frame = frame_at(c, from_native(c, native_m));
  return b;
}

// A contact, counted by what touched what: (kind, ball, other ball or
// cushion or pocket).
using ContactKey = std::tuple<int, int, int>;
ContactKey key_of(EventKind kind, int a, int b, int cushion, int pocket) {
  if (kind == EventKind::ball) return {0, std::min(a, b), std::max(a, b)};
  if (kind == EventKind::cushion) return {1, a, cushion};
  return {2, a, pocket};
}

// ---- the shots -----------------------------------------------------------

struct Shot {
  std::string name;
  std::vector<Ball> balls;  // at rest
  std::size_t cue = 0;
  Vec2 v{0.0};              // the cue ball's velocity and spin after the strike
  glm::dvec3 w{0.0};
};

// The rack of 15 and the cue ball, broken by a centre-ball strike.
Shot break_shot(const Cloth& c, const Parameters& p, double cue_speed_m_s) {
  Shot s;
  s.name = "break";
  const auto rb = std::get<std::vector<RackBall>>(rack(c, p, 15));
  for (const auto& b : rb) s.balls.push_back(ball_at_native(c, b.native_m));
  const Vec2 aim = direction_toward(c, s.balls[0].frame, from_native(c, rb[1].native_m));
  const Strike st = cue_strike(p, aim, cue_speed_m_s, {0.0, 0.0});
  s.v = st.v;
  s.w = st.w;
  return s;
}

// A stun shot at 10 m/s straight into a ball 5 mm off cushion 0.
Shot straight_shot(const Cloth& c, const Parameters& p) {
  Shot s;
  s.name = "straight 10 m/s";
  const double a = c.table.apothem_m();
  const Vec2 object{0.0, a - p.radius_m - 0.005};
  s.balls = {ball_at_native(c, {0.0, -0.25 * a}), ball_at_native(c, object)};
  s.v = 10.0 * direction_toward(c, s.balls[0].frame, from_native(c, object));
  return s;
}

// A rolling ball at 3 m/s that meets the object ball 1.9 R off its centre line.
Shot thin_cut(const Cloth& c, const Parameters& p) {
  Shot s;
  s.name = "thin cut";
  const double a = c.table.apothem_m();
  s.balls = {ball_at_native(c, {0.0, 0.4 * a}), ball_at_native(c, {0.0, -0.2 * a})};
  const Vec2 aim_at{1.9 * p.radius_m, -0.2 * a};
  s.v = 3.0 * direction_toward(c, s.balls[0].frame, from_native(c, aim_at));
  s.w = rolling_spin(p, s.v);
  return s;
}

// ---- the exact run -------------------------------------------------------

struct Outcome {
  std::map<ContactKey, int> contacts;
  std::vector<glm::dvec3> final;  // positions
  long events = 0;
  double end_s = 0.0;
};

Outcome run_exact(const Cloth& c, const Parameters& p, const Shot& shot) {
  System s(c, p, shot.balls);
  s.set_motion(shot.cue, shot.v, shot.w);
  Outcome out;
  while (auto e = s.next_event(kUntil_s)) {
    ++out.events;
    if (e->kind == EventKind::ball || e->kind == EventKind::cushion || e->kind == EventKind::pocket)
      ++out.contacts[key_of(e->kind, e->a, e->b, e->cushion, e->pocket)];
  }
  for (std::size_t i = 0; i < s.size(); ++i) out.final.push_back(frame_position(c, s.ball(i).frame));
  out.end_s = s.time_s();
  return out;
}

// ---- a naive fixed-step integrator of the same physics ------------------
//
// Each step advances every ball by its motion state's accelerations (the
// velocity by Euler, the position by the mean velocity along the geodesic),
// snaps sliding to rolling when the slip has turned over and rolling to rest
// when the speed would, then looks for balls that overlap a ball, a cushion
// or a pocket and resolves the contact with the same laws as the System.

Frame translation(const Space& space, Vec2 u, double t_rad) {
  const double C = space.C(t_rad), S = space.S(t_rad), k = space.k();
  Frame m{1.0};
  m[0] = {1.0 + (C - 1.0) * u.x * u.x, (C - 1.0) * u.x * u.y, -k * S * u.x};
  m[1] = {(C - 1.0) * u.y * u.x, 1.0 + (C - 1.0) * u.y * u.y, -k * S * u.y};
  m[2] = {S * u.x, S * u.y, C};
  return m;
}

double vector_form(double k, const glm::dvec3& a, const glm::dvec3& b) {
  return a.x * b.x + a.y * b.y + k * a.z * b.z;
}
double point_form(double k, const glm::dvec3& a, const glm::dvec3& b) {
  return k * (a.x * b.x + a.y * b.y) + a.z * b.z;
}

// Gram–Schmidt in the cloth's metric, keeping the position column.
Frame reorthonormalize(double k, Frame f) {
  glm::dvec3 p = f[2] / std::sqrt(point_form(k, f[2], f[2]));
  f[2] = p;
  for (int i = 0; i < 2; ++i) {
    glm::dvec3 e = f[i] - point_form(k, f[i], p) * p;
    for (int j = 0; j < i; ++j) e -= vector_form(k, e, f[j]) * f[j];
    f[i] = e / std::sqrt(vector_form(k, e, e));
  }
  return f;
}

Vec2 slip_of(const Parameters& p, const Ball& b) {
  return {b.v.x + p.radius_m * b.w.z, b.v.y - p.radius_m * b.w.x};
}
double decayed(double w, double by) {
  const double left = std::abs(w) - by;
  return left > 0.0 ? std::copysign(left, w) : 0.0;
}

class Stepper {
 public:
  Stepper(const Cloth& c, const Parameters& p, const Shot& shot)
      : c_(c), p_(p), space_(c.space()), balls_(shot.balls) {
    balls_[shot.cue].v = shot.v;
    balls_[shot.cue].w = shot.w;
    for (Ball& b : balls_) b.motion = classify(p_, b.v, b.w);
    const double rho = c.radius_m, R = p.radius_m;
    // Chord lengths that match the distances 2R (balls) and the pocket
    // radius, and p·ν/ρ at distance R from an edge line.
    ball_chord2_ = std::pow(2.0 * rho * space_.S(R / rho), 2.0);
    pocket_chord2_ = std::pow(2.0 * rho * space_.S(0.5 * p.pocket_radius_m / rho), 2.0);
    cushion_s_ = space_.S(R / rho);
  }

  // Steps of dt until every ball has stopped translating (or until_s).
  Outcome run(double dt, double until_s) {
    long n = 0;
    while (t_ < until_s && moving()) {
      for (Ball& b : balls_) advance(b, dt);
      if (++n % 256 == 0)
        for (Ball& b : balls_) b.frame = reorthonormalize(c_.k(), b.frame);
      collide();
      t_ += dt;
    }
    out_.final.clear();
    for (const Ball& b : balls_) out_.final.push_back(frame_position(c_, b.frame));
    out_.end_s = t_;
    return out_;
  }

 private:
  bool moving() const {
    return std::any_of(balls_.begin(), balls_.end(), [](const Ball& b) {
      return b.motion == Motion::sliding || b.motion == Motion::rolling;
    });
  }

  void advance(Ball& b, double dt) const {
    const double g = p_.g_m_s2, R = p_.radius_m;
    const double spin_decay = 2.5 * p_.mu_spin * g / R * dt;
    const Vec2 v0 = b.v;
    switch (b.motion) {
      case Motion::pocketed:
      case Motion::stationary: return;
      case Motion::spinning:
        b.w.y = decayed(b.w.y, spin_decay);
        if (b.w.y == 0.0) b.motion = Motion::stationary;
        return;
      case Motion::rolling: {
        const double speed = glm::length(b.v);
        const double left = std::max(0.0, speed - p_.mu_roll * g * dt);
        b.v *= left / speed;
        const glm::dvec3 roll = rolling_spin(p_, b.v);
        b.w = {roll.x, decayed(b.w.y, spin_decay), roll.z};
        if (left == 0.0) b.motion = b.w.y != 0.0 ? Motion::spinning : Motion::stationary;
        break;
      }
      case Motion::sliding: {
        const Vec2 u = slip_of(p_, b);
        const Vec2 sd = u / glm::length(u);
        const double a = p_.mu_slide * g;
        const double rate = 2.5 * a / R;
        b.v -= a * dt * sd;
        b.w = {b.w.x + rate * dt * sd.y, decayed(b.w.y, spin_decay), b.w.z - rate * dt * sd.x};
        if (glm::dot(slip_of(p_, b), sd) <= 0.0) {
          const glm::dvec3 roll = rolling_spin(p_, b.v);
          b.w = {roll.x, b.w.y, roll.z};
        }
        b.motion = classify(p_, b.v, b.w);
        break;
      }
    }
    const Vec2 d = 0.5 * (v0 + b.v) * dt;
    const double len = glm::length(d);
    if (len > 0.0) b.frame = b.frame * translation(space_, d / len, len / c_.radius_m);
  }

  static bool away(const Ball& b) { return b.motion == Motion::pocketed; }

  void collide() {
    const double rho = c_.radius_m, k = c_.k();
    const std::size_t n = balls_.size();
    for (std::size_t i = 0; i < n; ++i) {
      if (away(balls_[i])) continue;
      for (std::size_t j = i + 1; j < n; ++j) {
        if (away(balls_[j])) continue;
        const glm::dvec3 d = (balls_[i].frame[2] - balls_[j].frame[2]) * rho;
        if (vector_form(k, d, d) < ball_chord2_) ball_ball(i, j);
      }
    }
    for (std::size_t i = 0; i < n; ++i) {
      Ball& b = balls_[i];
      if (away(b)) continue;
      for (int e = 0; e < c_.table.sides; ++e)
        if (glm::dot(b.frame[2], c_.edges[static_cast<std::size_t>(e)]) < cushion_s_) cushion(i, e);
      if (p_.pocket_radius_m <= 0.0) continue;
      for (int q = 0; q < c_.table.sides; ++q) {
        const glm::dvec3 d = b.frame[2] * rho - c_.corners[static_cast<std::size_t>(q)];
        if (vector_form(k, d, d) < pocket_chord2_) {
          b.motion = Motion::pocketed;
          b.v = Vec2{0.0};
          b.w = glm::dvec3{0.0};
          ++out_.contacts[key_of(EventKind::pocket, static_cast<int>(i), -1, -1, q)];
          break;
        }
      }
    }
  }

  void ball_ball(std::size_t i, std::size_t j) {
    Ball& a = balls_[i];
    Ball& b = balls_[j];
    if (!collide_balls(c_, p_, a, b)) return;
    a.motion = classify(p_, a.v, a.w);
    b.motion = classify(p_, b.v, b.w);
    ++out_.contacts[key_of(EventKind::ball, static_cast<int>(i), static_cast<int>(j), -1, -1)];
  }

  void cushion(std::size_t i, int edge) {
    Ball& a = balls_[i];
    if (!collide_cushion(c_, p_, a, edge)) return;
    a.motion = classify(p_, a.v, a.w);
    ++out_.contacts[key_of(EventKind::cushion, static_cast<int>(i), -1, edge, -1)];
  }

  const Cloth& c_;
  Parameters p_;
  Space space_;
  std::vector<Ball> balls_;
  double t_ = 0.0;
  double ball_chord2_ = 0.0, pocket_chord2_ = 0.0, cushion_s_ = 0.0;
  Outcome out_;
};

int total(const std::map<ContactKey, int>& m) {
  int n = 0;
  for (const auto& [key, count] : m) n += count;
  return n;
}
int missed(const std::map<ContactKey, int>& exact, const std::map<ContactKey, int>& stepped) {
  int n = 0;
  for (const auto& [key, count] : exact) {
    const auto it = stepped.find(key);
    n += std::max(0, count - (it == stepped.end() ? 0 : it->second));
  }
  return n;
}
int extra(const std::map<ContactKey, int>& exact, const std::map<ContactKey, int>& stepped) {
  return missed(stepped, exact);
}

std::string duration_text(double s) {
  char buf[32];
  if (s < 1e-3)
    std::snprintf(buf, sizeof buf, "%.1f us", s * 1e6);
  else if (s < 1.0)
    std::snprintf(buf, sizeof buf, "%.2f ms", s * 1e3);
  else
    std::snprintf(buf, sizeof buf, "%.2f s", s);
  return buf;
}

// ---- (a) ----------------------------------------------------------------

void time_against_error(bool quick) {
  std::printf("(a) time against error: exact events against fixed steps (default parameters)\n");
  std::printf("    missed: contacts of the exact run the stepped run lacks; extra: the reverse;\n");
  std::printf("    error: the largest distance between a ball's final positions, metres\n\n");
  std::printf("%-5s %-16s %-8s %8s %8s %7s %11s %12s %10s\n", "space", "shot", "method", "contacts",
              "missed", "extra", "error m", "time/shot", "sim s");
  const std::vector<double> steps = quick ? std::vector<double>{1e-3} : std::vector<double>{1e-3, 1e-4, 1e-5};
  const int repeats = quick ? 1 : 20;
  for (SpaceKind kind : kKinds) {
    const Cloth c = table_cloth(kind);
    const Parameters p;
    std::vector<Shot> shots;
    if (!quick) shots.push_back(break_shot(c, p, 8.0));
    shots.push_back(straight_shot(c, p));
    if (!quick) shots.push_back(thin_cut(c, p));
    for (const Shot& shot : shots) {
      const auto t0 = Clock::now();
      Outcome exact;
      for (int r = 0; r < repeats; ++r) exact = run_exact(c, p, shot);
      const double exact_s = seconds_since(t0) / repeats;
      std::printf("%-5s %-16s %-8s %8d %8s %7s %11s %12s %10.3f\n", std::string(to_string(kind)).c_str(),
                  shot.name.c_str(), "events", total(exact.contacts), "-", "-", "-",
                  duration_text(exact_s).c_str(), exact.end_s);
      for (double dt : steps) {
        const auto t1 = Clock::now();
        Stepper stepper(c, p, shot);
        const Outcome stepped = stepper.run(dt, exact.end_s + 30.0);
        const double stepped_s = seconds_since(t1);
        double error = 0.0;
        for (std::size_t i = 0; i < exact.final.size(); ++i)
          error = std::max(error, distance_m(c, exact.final[i], stepped.final[i]));
        char method[16];
        std::snprintf(method, sizeof method, "%g ms", dt * 1e3);
        std::printf("%-5s %-16s %-8s %8d %8d %7d %11.3e %12s %10.3f\n", "", "", method,
                    total(stepped.contacts), missed(exact.contacts, stepped.contacts),
                    extra(exact.contacts, stepped.contacts), error, duration_text(stepped_s).c_str(),
                    stepped.end_s);
        std::fflush(stdout);
      }
    }
  }
  std::printf("\n");
}

// ---- (b) and (c) --------------------------------------------------------

void break_cost(bool quick) {
  const int repeats = quick ? 2 : 50;
  std::printf("(b) 16-ball break (15 object balls and the cue ball, default parameters, cue 8 m/s),\n");
  std::printf("    mean of %d breaks; pooltool reports 0.36 s for a 9-ball break (Python)\n\n", repeats);
  std::printf("%-5s %7s %8s %10s %12s %12s %12s\n", "space", "events", "contacts", "sim s", "root steps",
              "time/break", "us/event");
  for (SpaceKind kind : kKinds) {
    const Cloth c = table_cloth(kind);
    const Parameters p;
    const Shot shot = break_shot(c, p, 8.0);
    long events = 0, steps = 0;
    int contacts = 0;
    double end_s = 0.0;
    const auto t0 = Clock::now();
    for (int r = 0; r < repeats; ++r) {
      System s(c, p, shot.balls);
      s.set_motion(shot.cue, shot.v, shot.w);
      events = 0;
      contacts = 0;
      while (auto e = s.next_event(kUntil_s)) {
        ++events;
        contacts += e->kind == EventKind::ball || e->kind == EventKind::cushion || e->kind == EventKind::pocket;
      }
      steps = s.root_steps();
      end_s = s.time_s();
    }
    const double per_break = seconds_since(t0) / repeats;
    std::printf("%-5s %7ld %8d %10.3f %12ld %12s %12.2f\n", std::string(to_string(kind)).c_str(), events,
                contacts, end_s, steps, duration_text(per_break).c_str(),
                per_break / static_cast<double>(events) * 1e6);
    std::fflush(stdout);
  }
  std::printf("\n");
}

void frame_cost(bool quick) {
  constexpr double kFrame_s = 1.0 / 90.0;
  constexpr int kInner = 64;  // ball_at sweeps timed together, for resolution
  // The same break is played several times and each frame keeps its fastest
  // time: the simulation is deterministic, so what differs between repeats
  // is the machine (other programs, the scheduler's ticks), not the frame.
  const int repeats = quick ? 2 : 7;
  std::printf("(c) per-frame cost of play during a break, 90 Hz frames (budget 11.1 ms), each frame the\n");
  std::printf("    fastest of %d plays of the same break:\n", repeats);
  std::printf("    states: System::ball_at for all 16 balls at the frame time;\n");
  std::printf("    advance: next_event(frame time) until the clock stands there, with the events between;\n");
  std::printf("    worst: the frame whose advance took longest, its time after the strike and its events;\n");
  std::printf("    of budget: states and advance of the mean frame\n\n");
  std::printf("%-5s %7s %10s %14s %15s %15s %8s %7s %10s\n", "space", "frames", "states ns", "states max ns",
              "advance mean ns", "advance max ns", "worst s", "events", "of budget");
  volatile double sink = 0.0;
  for (SpaceKind kind : kKinds) {
    const Cloth c = table_cloth(kind);
    const Parameters p;
    const Shot shot = break_shot(c, p, 8.0);
    std::vector<double> states_s, advance_s;
    std::vector<long> frame_events;
    const long max_frames = quick ? 90 : 1L << 30;
    for (int r = 0; r < repeats; ++r) {
      System s(c, p, shot.balls);
      s.set_motion(shot.cue, shot.v, shot.w);
      for (std::size_t f = 0; !s.all_still() && static_cast<long>(f) < max_frames; ++f) {
        const double t = static_cast<double>(f + 1) * kFrame_s;
        const auto t0 = Clock::now();
        long events = 0;
        while (s.next_event(t)) ++events;
        const double adv = seconds_since(t0);
        const auto t1 = Clock::now();
        double acc = 0.0;
        for (int k = 0; k < kInner; ++k)
          for (std::size_t i = 0; i < s.size(); ++i) acc += s.ball_at(i, t).frame[2].x;
        const double states = seconds_since(t1) / kInner;
        sink = sink + acc;
        if (f == advance_s.size()) {
          advance_s.push_back(adv);
          states_s.push_back(states);
          frame_events.push_back(events);
        } else {
          advance_s[f] = std::min(advance_s[f], adv);
          states_s[f] = std::min(states_s[f], states);
        }
      }
    }
    const std::size_t frames = std::max<std::size_t>(advance_s.size(), 1);
    double states_sum = 0.0, states_max = 0.0, adv_sum = 0.0;
    std::size_t worst = 0;
    for (std::size_t f = 0; f < advance_s.size(); ++f) {
      states_sum += states_s[f];
      states_max = std::max(states_max, states_s[f]);
      adv_sum += advance_s[f];
      if (advance_s[f] > advance_s[worst]) worst = f;
    }
    const double fr = static_cast<double>(frames);
    std::printf("%-5s %7zu %10.0f %14.0f %15.0f %15.0f %8.3f %7ld %9.4f%%\n", std::string(to_string(kind)).c_str(),
                advance_s.size(), states_sum / fr * 1e9, states_max * 1e9, adv_sum / fr * 1e9,
                advance_s.empty() ? 0.0 : advance_s[worst] * 1e9, static_cast<double>(worst + 1) * kFrame_s,
                frame_events.empty() ? 0L : frame_events[worst], (states_sum + adv_sum) / fr / kFrame_s * 100.0);
    std::fflush(stdout);
  }
  std::printf("\n");
}

// ---- (d) ----------------------------------------------------------------

void stress(long events) {
  std::printf("(d) stress: %ld events per space, 16 balls, mu_slide = mu_roll = mu_spin = 0,\n", events);
  std::printf("    restitution 1, no friction, no pockets; cue 8 m/s into the rack\n\n");
  std::printf("%-5s %9s %10s %16s %14s %18s %18s %12s %10s\n", "space", "events", "sim s", "max_off_surface",
              "max_overlap_m", "energy_change_rel", "max_energy_rise", "events/s", "wall s");
  for (SpaceKind kind : kKinds) {
    const Cloth c = table_cloth(kind);
    Parameters p;
    p.mu_slide = p.mu_roll = p.mu_spin = 0.0;
    p.restitution_ball = p.restitution_cushion = 1.0;
    p.friction_ball = p.friction_cushion = 0.0;
    p.pocket_radius_m = 0.0;
    const Shot shot = break_shot(c, p, 8.0);
    System s(c, p, shot.balls);
    s.set_motion(shot.cue, shot.v, shot.w);
    long n = 0;
    const auto t0 = Clock::now();
    while (n < events && s.next_event(std::numeric_limits<double>::infinity())) ++n;
    const double wall = seconds_since(t0);
    const Invariants& inv = s.invariants();
    std::printf("%-5s %9ld %10.2f %16.3e %14.3e %18.3e %18.3e %12.0f %10.2f\n", std::string(to_string(kind)).c_str(),
                n, s.time_s(), inv.max_off_surface_rel, std::max(0.0, inv.max_overlap_m), inv.energy_change_rel,
                inv.max_energy_rise_rel, static_cast<double>(n) / wall, wall);
    std::fflush(stdout);
  }
  std::printf("\n");
}

// ---- (e) ----------------------------------------------------------------

void random_breaks(int per_space) {
  constexpr long kLimit = 20000;
  std::printf("(e) random breaks: %d per space, real parameters, aim within 0.08 m of the rack's axis, cue\n", per_space);
  std::printf("    0.3-9 m/s, tip within 0.6 R (seeded); a break stops at %ld events\n\n", kLimit);
  std::printf("%-5s %7s %12s %11s %12s %14s %16s %12s\n", "space", "breaks", "mean events", "max events",
              "at limit", "max_overlap_m", "max_energy_rise", "ms/break");
  std::mt19937_64 rng(20261128);
  std::uniform_real_distribution<double> aim(-0.08, 0.08), speed(0.3, 9.0), tip(-0.6, 0.6);
  for (SpaceKind kind : kKinds) {
    const Cloth c = table_cloth(kind);
    const Parameters p;
    const auto rb = std::get<std::vector<RackBall>>(rack(c, p, 15));
    long total = 0, most = 0;
    int at_limit = 0;
    double overlap = 0.0, rise = 0.0;
    const auto t0 = Clock::now();
    for (int k = 0; k < per_space; ++k) {
      std::vector<Ball> balls;
      for (const auto& b : rb) balls.push_back(ball_at_native(c, b.native_m));
      System s(c, p, balls);
      const Vec2 toward = direction_toward(c, s.ball(0).frame, from_native(c, Vec2{aim(rng), -0.3}));
      const double v = speed(rng), side = tip(rng), height = tip(rng);
      const Strike st = cue_strike(p, toward, v, {side, height});
      if (!st.miscue) s.set_motion(0, st.v, st.w);
      long n = 0;
      while (n < kLimit && s.next_event(kUntil_s)) ++n;
      total += n;
      most = std::max(most, n);
      at_limit += n == kLimit ? 1 : 0;
      overlap = std::max(overlap, s.invariants().max_overlap_m);
      rise = std::max(rise, s.invariants().max_energy_rise_rel);
    }
    const double wall = seconds_since(t0);
    std::printf("%-5s %7d %12.1f %11ld %12d %14.3e %16.3e %12.2f\n", std::string(to_string(kind)).c_str(), per_space,
                static_cast<double>(total) / per_space, most, at_limit, std::max(0.0, overlap), rise,
                wall / per_space * 1e3);
    std::fflush(stdout);
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  long stress_events = 0;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[i], "--stress") == 0) {
      stress_events = 1000000;
      if (i + 1 < argc && argv[i + 1][0] != '-') {
        char* end = nullptr;
        stress_events = std::strtol(argv[i + 1], &end, 10);
        if (end == argv[i + 1] || *end != '\0' || stress_events <= 0) {
          std::fprintf(stderr, "--stress: expected a positive number of events, found \"%s\"\n", argv[i + 1]);
          return 2;
        }
        ++i;
      }
    } else {
      std::fprintf(stderr, "usage: bench_billiards [--quick] [--stress [EVENTS]]\n");
      return 2;
    }
  }
  if (stress_events > 0 && !quick) {
    stress(stress_events);
    return 0;
  }
  time_against_error(quick);
  break_cost(quick);
  frame_cost(quick);
  random_breaks(quick ? 4 : 200);
  if (quick) stress(stress_events > 0 ? std::min(stress_events, 20000L) : 20000L);
  return 0;
}
