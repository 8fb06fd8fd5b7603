#include "pilot_body.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace curvlab::harness::desktop {
namespace {

constexpr double kMaxPitchRad = 85.0 * std::numbers::pi / 180.0;
// Hands rest below and in front of the eyes, about where they would hold a cue.
constexpr glm::dvec3 kLeftRestM{-0.18, -0.45, -0.35};
constexpr glm::dvec3 kRightRestM{0.18, -0.45, -0.35};

glm::dquat heading(double yaw_rad) { return glm::angleAxis(yaw_rad, glm::dvec3(0.0, 1.0, 0.0)); }

}  // namespace

PilotBody::PilotBody(PilotBodyOptions options) : options_(options) { reset(); }

void PilotBody::reset() {
  head_m_ = options_.start_head_m;
  const glm::dvec3 d = options_.look_at_m - options_.start_head_m;
  // Forward is −z: yaw turns −z toward the target horizontally, pitch tilts it.
  yaw_rad_ = std::atan2(-d.x, -d.z);
  pitch_rad_ = std::clamp(std::atan2(d.y, std::hypot(d.x, d.z)), -kMaxPitchRad, kMaxPitchRad);
  left_offset_m_ = kLeftRestM;
  right_offset_m_ = kRightRestM;
}

void PilotBody::walk(double forward, double right, double up, double dt_s) {
  const glm::dquat h = heading(yaw_rad_);
  const glm::dvec3 fwd = h * glm::dvec3(0.0, 0.0, -1.0);
  const glm::dvec3 rgt = h * glm::dvec3(1.0, 0.0, 0.0);
  head_m_ += (fwd * forward + rgt * right) * (options_.walk_m_per_s * dt_s);
  head_m_.y += up * options_.rise_m_per_s * dt_s;
  head_m_.y = std::clamp(head_m_.y, 0.3, 2.5);  // stay a person's height above the floor
}

void PilotBody::look(double dx_px, double dy_px) {
  turn(-dx_px * options_.look_rad_per_px, -dy_px * options_.look_rad_per_px);
}

void PilotBody::turn(double left_rad, double up_rad) {
  yaw_rad_ = std::remainder(yaw_rad_ + left_rad, 2.0 * std::numbers::pi);
  pitch_rad_ = std::clamp(pitch_rad_ + up_rad, -kMaxPitchRad, kMaxPitchRad);
}

void PilotBody::move_hand(Hand hand, double dx_px, double dy_px, double scroll_steps) {
  glm::dvec3& offset = hand == Hand::left ? left_offset_m_ : right_offset_m_;
  offset.x += dx_px * options_.hand_m_per_px;
  offset.y -= dy_px * options_.hand_m_per_px;
  offset.z -= scroll_steps * options_.hand_m_per_scroll;
  // An arm's reach.
  const double reach = glm::length(offset);
  if (reach > 0.9) offset *= 0.9 / reach;
}

void PilotBody::place_hand(Hand hand, const glm::dvec3& lab_m) {
  // The offset is kept in the heading frame (frame() turns it back).
  (hand == Hand::left ? left_offset_m_ : right_offset_m_) = glm::inverse(heading(yaw_rad_)) * (lab_m - head_m_);
}

geometry::LabFrame PilotBody::frame() const {
  geometry::LabFrame f;
  const glm::dquat h = heading(yaw_rad_);
  f[geometry::Device::head].position_m = head_m_;
  f[geometry::Device::head].orientation =
      h * glm::angleAxis(pitch_rad_, glm::dvec3(1.0, 0.0, 0.0));
  f[geometry::Device::left_hand].position_m = head_m_ + h * left_offset_m_;
  f[geometry::Device::left_hand].orientation = h;
  f[geometry::Device::right_hand].position_m = head_m_ + h * right_offset_m_;
  f[geometry::Device::right_hand].orientation = h;
  return f;
}

}  // namespace curvlab::harness::desktop
