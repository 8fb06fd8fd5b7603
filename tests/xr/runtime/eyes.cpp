#include "eyes.hpp"

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <sstream>
#include <vector>

namespace curvlab::test_runtime {
namespace {

std::optional<std::vector<double>> numbers(const std::string& text, std::size_t n) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto v = parse_number(item);
    if (!v) return std::nullopt;
    out.push_back(*v);
  }
  if (out.size() != n) return std::nullopt;
  return out;
}

double length(const Vec3& v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }

// The shortest rotation taking −Z to the unit vector d.
Quat looking_along(const Vec3& d) {
  const Vec3 from{0.0, 0.0, -1.0};
  const double c = from.x * d.x + from.y * d.y + from.z * d.z;
  Vec3 axis{from.y * d.z - from.z * d.y, from.z * d.x - from.x * d.z, from.x * d.y - from.y * d.x};
  const double s = length(axis);
  if (s < 1e-12) return c > 0.0 ? Quat{} : Quat{0.0, 1.0, 0.0, 0.0};
  const double angle = std::atan2(s, c);
  const double h = std::sin(angle / 2.0) / s;
  return {axis.x * h, axis.y * h, axis.z * h, std::cos(angle / 2.0)};
}

Vec3 toward(const Vec3& from, const Vec3& to) {
  const Vec3 d{to.x - from.x, to.y - from.y, to.z - from.z};
  const double n = length(d);
  return {d.x / n, d.y / n, d.z / n};
}

}  // namespace

std::optional<GazeScript> read_gaze_script(std::string& error) {
  const char* v = std::getenv("CURVLAB_TEST_XR_GAZE");
  if (v == nullptr || *v == '\0') return std::nullopt;
  const std::string text = v;
  auto bad = [&]() -> std::optional<GazeScript> {
    error = "CURVLAB_TEST_XR_GAZE: '" + text +
            "': expected KIND:TARGET[:LEFT,RIGHT], KIND both|per_eye|combined, TARGET fixate=X,Y,Z or "
            "vergence=DEGREES, confidences 0-1, e.g. per_eye:vergence=1.5:0.9,0.8";
    return std::nullopt;
  };
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string p; std::getline(in, p, ':');) parts.push_back(p);
  if (parts.size() < 2 || parts.size() > 3) return bad();
  GazeScript g;
  if (parts[0] == "per_eye") g.combined = false;
  else if (parts[0] == "combined") g.per_eye = false;
  else if (parts[0] != "both") return bad();
  if (parts[1].rfind("fixate=", 0) == 0) {
    const auto p = numbers(parts[1].substr(7), 3);
    if (!p) return bad();
    g.fixate_m = Vec3{(*p)[0], (*p)[1], (*p)[2]};
  } else if (parts[1].rfind("vergence=", 0) == 0) {
    const auto d = parse_number(parts[1].substr(9));
    if (!d || std::abs(*d) >= 90.0) return bad();
    g.vergence_deg = *d;
  } else {
    return bad();
  }
  if (parts.size() == 3) {
    const auto c = numbers(parts[2], 2);
    if (!c || (*c)[0] < 0.0 || (*c)[0] > 1.0 || (*c)[1] < 0.0 || (*c)[1] > 1.0) return bad();
    g.confidence = {(*c)[0], (*c)[1]};
  }
  return g;
}

std::array<Pose, 2> eye_gaze_poses(const GazeScript& gaze, const Pose& head) {
  std::array<Pose, 2> out;
  for (int i = 0; i < 2; ++i) {
    const double side = i == 0 ? -1.0 : 1.0;
    const Pose eye = compose(head, Pose{Quat{}, {side * kIpdM / 2.0, 0.0, 0.0}});
    if (gaze.fixate_m) {
      out[static_cast<std::size_t>(i)] = {looking_along(toward(eye.position_m, *gaze.fixate_m)), eye.position_m};
    } else {
      // Each eye turned inward by half the vergence about the head's up
      // axis: the left eye's line of sight toward +x for a positive angle.
      const double half = gaze.vergence_deg * std::numbers::pi / 360.0;
      const double turn = i == 0 ? -half : half;
      const Quat yaw{0.0, std::sin(turn / 2.0), 0.0, std::cos(turn / 2.0)};
      out[static_cast<std::size_t>(i)] = {multiply(head.orientation, yaw), eye.position_m};
    }
  }
  return out;
}

Pose combined_gaze_pose(const GazeScript& gaze, const Pose& head) {
  if (!gaze.fixate_m) return head;
  return {looking_along(toward(head.position_m, *gaze.fixate_m)), head.position_m};
}

}  // namespace curvlab::test_runtime
