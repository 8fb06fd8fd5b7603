// The simulated body of the desktop pilot: a head moved by the keyboard and
// turned by the mouse, and two hands held in front of it, as lab poses
// (metres; x right, y up, −z forward — geometry/tracking.hpp). The person
// starts where a participant stands at the physical table: outside its +z
// edge, eyes 1.55 m above the floor, looking at the table-top centre. Pure
// state, no window: the key and mouse mapping is tested without a display.
// Not thread-safe.
#pragma once

#include "curvlab/geometry/tracking.hpp"

namespace curvlab::harness::desktop {

struct PilotBodyOptions {
  glm::dvec3 start_head_m{0.0, 1.55, 0.9};
  glm::dvec3 look_at_m{0.0, 0.76, 0.0};  // the table-top centre (tables are ~0.76 m high)
  double walk_m_per_s = 0.8;
  double rise_m_per_s = 0.4;
  double look_rad_per_px = 0.003;
  double hand_m_per_px = 0.002;
  double hand_m_per_scroll = 0.02;
};

enum class Hand { left, right };

class PilotBody {
 public:
  explicit PilotBody(PilotBodyOptions options = {});

  // Moves the head for dt_s: forward/right/up each −1, 0 or +1 (W/S, D/A,
  // E/Q), in the horizontal plane of the head's heading.
  void walk(double forward, double right, double up, double dt_s);
  // Turns the head by a mouse movement in pixels (right and down positive);
  // pitch stops short of straight up and down.
  void look(double dx_px, double dy_px);
  // Turns the head left (+) and up (+) by angles (scripted pilots).
  void turn(double left_rad, double up_rad);
  // Moves a hand in the head's heading frame: right, up (mouse, pixels) and
  // forward (scroll steps).
  void move_hand(Hand hand, double dx_px, double dy_px, double scroll_steps);
  // Puts a hand at a lab position (scripted pilots: a touch on a table
  // corner), wherever the head is; the hand then moves with the head as
  // before. Not limited to an arm's reach.
  void place_hand(Hand hand, const glm::dvec3& lab_m);
  // Back to the start pose, hands included.
  void reset();

  [[nodiscard]] geometry::LabFrame frame() const;
  [[nodiscard]] double yaw_rad() const { return yaw_rad_; }
  [[nodiscard]] double pitch_rad() const { return pitch_rad_; }
  [[nodiscard]] const glm::dvec3& head_m() const { return head_m_; }

 private:
  PilotBodyOptions options_;
  glm::dvec3 head_m_;
  double yaw_rad_ = 0.0;    // left (+) about +y
  double pitch_rad_ = 0.0;  // up (+) about the head's x
  // Hand positions in the heading frame (yaw only), relative to the head.
  glm::dvec3 left_offset_m_;
  glm::dvec3 right_offset_m_;
};

}  // namespace curvlab::harness::desktop
