// Billiards on the cloth of a curved table: exact, event-based ball physics
// in S3, E3 and H3 (DESIGN.md §3b; docs/billiards.md).
//
// The cloth is the totally geodesic surface through the table, y = 0 in the
// table's frame: a 2-sphere, a plane or a hyperbolic plane of the space's
// radius ρ. Its points are 3-vectors (x, z, w) in metres with
// k(x² + z²) + w² = ρ², the table frame's 4-vectors with y dropped. The game
// is two-dimensional on it: a ball is a disk of radius R whose centre (its
// contact point) moves on the cloth; its velocity and spin live in a frame
// carried along by parallel transport. Drawing the sphere on that point
// neglects terms of order R²/ρ².
//
// Motion between events is closed form (rolling along a geodesic with
// constant deceleration, spinning in place, resting) or, for sliding, the
// Euclidean parabola developed onto the cloth with a fourth-order Magnus
// integrator (exact in E3). Events — ball–ball contact, cushion contact,
// pocket, and the changes of state — are found by a root search with
// rigorous bounds on the gap's second derivative, so none is stepped over;
// a contact is resolved when the gap is within 1e-12 m of touching, never
// after overlap.
#pragma once

#include "curvlab/geometry/isometry.hpp"
#include "curvlab/geometry/table.hpp"

#include <glm/gtc/quaternion.hpp>
#include <glm/vec2.hpp>

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace curvlab::geometry::billiards {

using Vec2 = glm::dvec2;
using Quat = glm::dquat;

// Physical parameters, standard pool by default. Every field is settable by
// name (parameter_table()).
struct Parameters {
  double radius_m = 0.028575;
  double mass_kg = 0.170;
  double mu_slide = 0.2;            // sliding friction with the cloth
  double mu_roll = 0.01;            // rolling resistance
  double mu_spin = 0.044;           // decay of spin about the vertical
  double restitution_ball = 0.95;
  double restitution_cushion = 0.85;
  double friction_ball = 0.05;      // ball–ball friction (throw); 0: none
  double friction_cushion = 0.2;    // ball–cushion friction; 0: none
  double g_m_s2 = 9.81;
  double pocket_radius_m = 0.065;   // a pocket at each corner; 0: none
  double cue_mass_kg = 0.54;
  double miscue_fraction = 0.6;     // a tip offset beyond this × R miscues
};

struct ParameterInfo {
  std::string_view name;
  double Parameters::*field;
  double min;        // inclusive
  double max;        // inclusive
  std::string_view meaning;
};
std::span<const ParameterInfo> parameter_table();
const ParameterInfo* find_parameter(std::string_view name);
// Sets a parameter by name; an error message (naming the range) otherwise.
std::optional<std::string> set_parameter(Parameters& p, std::string_view name, double value);

enum class Motion { sliding, rolling, spinning, stationary, pocketed };
std::string_view to_string(Motion motion);

// A right-angled table's cloth: the 2-D space form, the table's corners and
// its edges as lines ν (a point p is on edge j's line when p·ν_j = 0, and
// S(d/ρ) = p·ν_j / ρ is its signed distance d, positive inside).
struct Cloth {
  SpaceKind kind = SpaceKind::E3;
  double radius_m = 1.0;
  TableShape table;
  std::vector<glm::dvec3> corners;  // (x, z, w), metres
  std::vector<glm::dvec3> edges;    // ν_j, edge j joins corner j to j+1

  [[nodiscard]] Space space() const { return Space{kind, radius_m}; }
  [[nodiscard]] double k() const { return space().k(); }
};
Cloth make_cloth(const Space& space, const TableShape& table);

// Points of the cloth and the native (azimuthal-equidistant) coordinates
// about the table's centre: a point d metres along the cloth from the centre
// in the direction (u_x, u_z) has native coordinates d·(u_x, u_z).
glm::dvec3 from_native(const Cloth& cloth, Vec2 native_m);
Vec2 to_native(const Cloth& cloth, const glm::dvec3& p);
double distance_m(const Cloth& cloth, const glm::dvec3& p, const glm::dvec3& q);
// Signed distance of p from edge j's line, metres (positive inside).
double edge_distance_m(const Cloth& cloth, const glm::dvec3& p, int edge);
// How far p is from the cloth, relative to ρ².
double off_cloth_error(const Cloth& cloth, const glm::dvec3& p);

// A frame on the cloth: 3×3, dimensionless; columns e_x, e_z (unit tangents)
// and p/ρ. F · (0, 0, ρ) is the position.
using Frame = Mat3;
Frame frame_at(const Cloth& cloth, const glm::dvec3& p);  // transported from the centre
glm::dvec3 frame_position(const Cloth& cloth, const Frame& f);
// The unit direction at f's position toward q, in f's tangent coordinates.
Vec2 direction_toward(const Cloth& cloth, const Frame& f, const glm::dvec3& q);
// The cloth frame as an isometry of the space in the table's frame (y kept).
Isometry to_isometry(const Frame& f);

// One ball. v is in the frame's tangent coordinates (x, z), metres per
// second; w is the angular velocity in the frame's 3-D coordinates (x, up,
// z), radians per second; orientation turns the ball's body into the frame.
struct Ball {
  Frame frame{1.0};
  Vec2 v{0.0};
  glm::dvec3 w{0.0};
  Quat orientation{1.0, 0.0, 0.0, 0.0};
  Motion motion = Motion::stationary;
  int pocket = -1;
};

// The state of a ball with velocity v and spin w (sliding, rolling, ...).
Motion classify(const Parameters& p, Vec2 v, const glm::dvec3& w);
// Rolling spin for velocity v (no slip at the contact point).
glm::dvec3 rolling_spin(const Parameters& p, Vec2 v);

// The cue's instantaneous strike (a level cue): the cue ball's velocity and
// spin from the cue's speed and the tip's offset from the ball's centre
// (side to the right of the aim, height up; fractions of R).
struct Strike {
  Vec2 v{0.0};
  glm::dvec3 w{0.0};
  bool miscue = false;
};
Strike cue_strike(const Parameters& p, Vec2 aim_unit, double cue_speed_m_s, Vec2 tip_fraction);

// The collision laws (docs/billiards.md, "Collisions"), on balls at the
// moment of contact: restitution along the line of centres in a common frame
// (one ball's carried to the other by parallel transport), Coulomb friction
// across it. Return false, changing nothing, where the balls are not
// closing. The balls' motions are left for the caller to classify.
bool collide_balls(const Cloth& cloth, const Parameters& p, Ball& a, Ball& b);
// A ball against edge `edge`'s cushion.
bool collide_cushion(const Cloth& cloth, const Parameters& p, Ball& a, int edge);

enum class EventKind { ball, cushion, pocket, rolling, spinning, stop };
std::string_view to_string(EventKind kind);

struct Event {
  double t_s = 0.0;
  EventKind kind = EventKind::stop;
  int a = -1;         // the ball
  int b = -1;         // the other ball (kind ball)
  int cushion = -1;   // kind cushion
  int pocket = -1;    // kind pocket
};

// The worst of the invariants seen so far.
struct Invariants {
  double max_off_surface_rel = 0.0;
  double max_overlap_m = 0.0;
  double energy_change_rel = 0.0;  // (E_now − E_start) / E_start; never > 0
  double max_energy_rise_rel = 0.0;
};

// A table of balls moving in time. Each call to next_event() advances to the
// next event, resolves it and returns it.
class System {
 public:
  System(Cloth cloth, Parameters params, std::vector<Ball> balls);

  [[nodiscard]] double time_s() const { return t_s_; }
  [[nodiscard]] const Cloth& cloth() const { return cloth_; }
  [[nodiscard]] const Parameters& parameters() const { return params_; }
  [[nodiscard]] std::size_t size() const { return segments_.size(); }
  // Ball i at time t ≥ time_s(), before the next event (at time_s() when
  // t is omitted).
  [[nodiscard]] Ball ball(std::size_t i) const { return ball_at(i, t_s_); }
  [[nodiscard]] Ball ball_at(std::size_t i, double t_s) const;
  [[nodiscard]] bool all_still() const;

  // Gives ball i a new velocity and spin now (a strike).
  void set_motion(std::size_t i, Vec2 v, const glm::dvec3& w);

  // The next event no later than until_s (which may be +∞); nothing when
  // none happens before it — the clock then stands at until_s, or, with an
  // infinite until_s, every ball is still.
  std::optional<Event> next_event(double until_s);

  [[nodiscard]] double kinetic_energy_j() const;
  [[nodiscard]] const Invariants& invariants() const { return invariants_; }
  // Steps of the root search so far (for benchmarks).
  [[nodiscard]] long long root_steps() const { return root_steps_; }

 private:
  // Ball i's motion from t0_s until its next change of state.
  struct Segment {
    double t0_s = 0.0;
    Ball start;
    double end_s = 0.0;           // the next change of state (∞: none)
    EventKind end_kind = EventKind::stop;
    Vec2 slip_dir{0.0};           // sliding: the contact point's slip direction
    double h_s = 0.0;             // sliding: knot spacing of the developed path
    std::vector<Frame> knots;     // sliding, S3 and H3: frames every h_s
    double max_speed_m_s = 0.0;   // over the segment
    double accel_m_s2 = 0.0;      // magnitude of the centre's acceleration
  };
  // What the root search knows about one pair, or one ball and the walls:
  // no event before searched_to_s, or the event found.
  struct Search {
    unsigned vi = ~0u, vj = ~0u;
    double searched_to_s = 0.0;
    std::optional<Event> found;
  };
  void begin_segment(std::size_t i, double t_s, Ball b);
  // The ball on segment s at t_s. The root search and the invariants read
  // only positions, velocities and spins; they skip the orientation, which
  // costs a quaternion's sine and cosine per call.
  enum class Orientation { track, skip };
  [[nodiscard]] Ball evaluate(const Segment& s, double t_s, Orientation orientation = Orientation::track) const;
  void search_pair(std::size_t i, std::size_t j, Search& s, double to_s);
  void search_walls(std::size_t i, Search& s, double to_s);
  void resolve(const Event& e);
  void check_after(const Event& e);

  Cloth cloth_;
  Parameters params_;
  std::vector<Segment> segments_;
  std::vector<unsigned> version_;
  std::vector<Search> pairs_;  // i·n + j, i < j
  std::vector<Search> walls_;
  std::vector<double> last_hit_s_;  // each ball's last collision with a ball
  double t_s_ = 0.0;
  double energy_ref_j_ = 0.0;
  double energy_last_j_ = 0.0;
  Invariants invariants_;
  long long root_steps_ = 0;
};

// A rack of n object balls (1 … 15) and the cue ball, fitted to the table:
// a triangle whose apex sits on the foot spot halfway from the centre to the
// edge opposite edge 0, the cue ball halfway to edge 0; gaps of 1e-4·R keep
// touching balls apart. Positions in native coordinates.
struct RackBall {
  std::string id;
  Vec2 native_m;
};
std::variant<std::vector<RackBall>, GeometryError> rack(const Cloth& cloth, const Parameters& p,
                                                        int object_balls);

// The ball's velocity at its frame's point as a native-coordinate speed.
double speed_m_s(const Ball& b);

}  // namespace curvlab::geometry::billiards
