#include "script.hpp"

#include "eyes.hpp"

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <sstream>

namespace curvlab::test_runtime {

Quat multiply(const Quat& a, const Quat& b) {
  return {a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
          a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z};
}

Quat conjugate(const Quat& q) { return {-q.x, -q.y, -q.z, q.w}; }

Vec3 rotate(const Quat& q, const Vec3& v) {
  const Quat r = multiply(multiply(q, Quat{v.x, v.y, v.z, 0.0}), conjugate(q));
  return {r.x, r.y, r.z};
}

Pose compose(const Pose& a, const Pose& b) {
  const Vec3 p = rotate(a.orientation, b.position_m);
  return {multiply(a.orientation, b.orientation),
          {a.position_m.x + p.x, a.position_m.y + p.y, a.position_m.z + p.z}};
}

Pose inverse(const Pose& p) {
  const Quat c = conjugate(p.orientation);
  const Vec3 t = rotate(c, p.position_m);
  return {c, {-t.x, -t.y, -t.z}};
}

namespace {

Quat axis_angle(const Vec3& axis, double angle_rad) {
  const double s = std::sin(angle_rad / 2.0);
  return {axis.x * s, axis.y * s, axis.z * s, std::cos(angle_rad / 2.0)};
}

std::optional<double> number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, sep))
    if (!item.empty()) out.push_back(item);
  return out;
}

const char* env(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? v : nullptr;
}

// "right:a@1.0", "right:a@1.0/1.2" (every 1.2 s), "…~0.2" (held 0.2 s).
std::optional<Press> parse_press(const std::string& item) {
  Press p;
  const auto colon = item.find(':');
  const auto at = item.find('@');
  if (colon == std::string::npos || at == std::string::npos || at < colon) return std::nullopt;
  p.hand = item.substr(0, colon);
  p.button = item.substr(colon + 1, at - colon - 1);
  if (p.hand != "left" && p.hand != "right") return std::nullopt;
  static const std::vector<std::string> buttons = {"a", "b", "x", "y", "menu", "trigger", "squeeze"};
  bool known = false;
  for (const auto& b : buttons) known = known || b == p.button;
  if (!known) return std::nullopt;
  std::string rest = item.substr(at + 1);
  if (const auto tilde = rest.find('~'); tilde != std::string::npos) {
    const auto hold = number(rest.substr(tilde + 1));
    if (!hold || *hold <= 0.0) return std::nullopt;
    p.hold_s = *hold;
    rest = rest.substr(0, tilde);
  }
  if (const auto slash = rest.find('/'); slash != std::string::npos) {
    const auto every = number(rest.substr(slash + 1));
    if (!every || *every <= p.hold_s) return std::nullopt;
    p.every_s = *every;
    rest = rest.substr(0, slash);
  }
  const auto start = number(rest);
  if (!start || *start < 0.0) return std::nullopt;
  p.at_s = *start;
  return p;
}

// "right@1.5=0.45,0.76,-0.45": the right grip at that point from 1.5 s on.
std::optional<Placement> parse_placement(const std::string& item) {
  Placement p;
  const auto at = item.find('@');
  const auto eq = item.find('=');
  if (at == std::string::npos || eq == std::string::npos || eq < at) return std::nullopt;
  const std::string hand = item.substr(0, at);
  if (hand != "left" && hand != "right") return std::nullopt;
  p.hand = hand == "left" ? 0 : 1;
  const auto start = number(item.substr(at + 1, eq - at - 1));
  const auto xyz = split(item.substr(eq + 1), ',');
  if (!start || *start < 0.0 || xyz.size() != 3) return std::nullopt;
  p.at_s = *start;
  double* out[3] = {&p.position_m.x, &p.position_m.y, &p.position_m.z};
  for (std::size_t i = 0; i < 3; ++i) {
    const auto v = number(xyz[i]);
    if (!v || std::abs(*v) > 10.0) return std::nullopt;
    *out[i] = *v;
  }
  return p;
}

}  // namespace

std::optional<Script> read_script(std::string& error) {
  Script s;
  if (const char* v = env("CURVLAB_TEST_XR_PRESS")) {
    for (const auto& item : split(v, ',')) {
      auto p = parse_press(item);
      if (!p) {
        error = "CURVLAB_TEST_XR_PRESS: '" + item +
                "': expected HAND:BUTTON@SECONDS[/EVERY][~HOLD] with HAND left or right and BUTTON one "
                "of a b x y menu trigger squeeze";
        return std::nullopt;
      }
      s.presses.push_back(*p);
    }
  }
  if (const char* v = env("CURVLAB_TEST_XR_HAND")) {
    for (const auto& item : split(v, ';')) {
      auto p = parse_placement(item);
      if (!p) {
        error = "CURVLAB_TEST_XR_HAND: '" + item +
                "': expected HAND@SECONDS=X,Y,Z with HAND left or right and X, Y, Z in metres (each within 10)";
        return std::nullopt;
      }
      s.placements.push_back(*p);
    }
  }
  if (const char* v = env("CURVLAB_TEST_XR_UNFOCUS")) {
    for (const auto& item : split(v, ',')) {
      const auto plus = item.find('+');
      const auto at = number(item.substr(0, plus));
      const auto len = plus == std::string::npos ? std::nullopt : number(item.substr(plus + 1));
      if (!at || !len || *at < 0.0 || *len <= 0.0) {
        error = "CURVLAB_TEST_XR_UNFOCUS: '" + item + "': expected SECONDS+DURATION, e.g. 4.2+0.5";
        return std::nullopt;
      }
      s.unfocus.push_back({*at, *len});
    }
  }
  if (const char* v = env("CURVLAB_TEST_XR_EXIT")) {
    const auto at = number(v);
    if (!at || *at < 0.0) {
      error = std::string("CURVLAB_TEST_XR_EXIT: '") + v + "': expected seconds after focus";
      return std::nullopt;
    }
    s.exit_at_s = *at;
  }
  if (const char* v = env("CURVLAB_TEST_XR_RESTART")) {
    const std::string item = v;
    const auto plus = item.find('+');
    const auto at = number(item.substr(0, plus));
    const auto idle = plus == std::string::npos ? std::nullopt : number(item.substr(plus + 1));
    if (!at || !idle || *at < 0.0 || *idle < 0.0) {
      error = "CURVLAB_TEST_XR_RESTART: '" + item + "': expected SECONDS+IDLE_SECONDS, e.g. 3.15+0.5";
      return std::nullopt;
    }
    s.restart = Restart{*at, *idle};
  }
  if (const char* v = env("CURVLAB_TEST_XR_LOSS")) {
    const auto at = number(v);
    if (!at || *at < 0.0) {
      error = std::string("CURVLAB_TEST_XR_LOSS: '") + v + "': expected seconds after focus";
      return std::nullopt;
    }
    s.loss_at_s = *at;
  }
  if (const char* v = env("CURVLAB_TEST_XR_FAIL")) {
    const std::string text(v);
    const auto at = text.find('@');
    const auto colon = text.find(':', at == std::string::npos ? 0 : at);
    Fault f;
    f.call = text.substr(0, at);
    const auto seconds = at == std::string::npos || colon == std::string::npos
                             ? std::nullopt
                             : number(text.substr(at + 1, colon - at - 1));
    f.result = colon == std::string::npos ? "" : text.substr(colon + 1);
    if ((f.call != "xrWaitFrame" && f.call != "xrEndFrame") || !seconds || *seconds < 0.0 ||
        (f.result != "XR_ERROR_SESSION_LOST" && f.result != "XR_ERROR_RUNTIME_FAILURE" &&
         f.result != "XR_ERROR_INSTANCE_LOST")) {
      error = "CURVLAB_TEST_XR_FAIL: '" + text +
              "': expected CALL@SECONDS:RESULT with CALL xrWaitFrame or xrEndFrame and RESULT "
              "XR_ERROR_SESSION_LOST, XR_ERROR_RUNTIME_FAILURE or XR_ERROR_INSTANCE_LOST";
      return std::nullopt;
    }
    f.at_s = *seconds;
    s.fault = f;
  }
  if (const char* v = env("CURVLAB_TEST_XR_HEAD")) {
    const std::string mode = v;
    if (mode != "tracked" && mode != "orientation_only") {
      error = "CURVLAB_TEST_XR_HEAD: '" + mode + "': expected tracked or orientation_only";
      return std::nullopt;
    }
    s.head_position_tracked = mode == "tracked";
  }
  if (const char* v = env("CURVLAB_TEST_XR_CAPTURE_DIR")) s.capture_dir = v;
  if (const char* v = env("CURVLAB_TEST_XR_CAPTURE_EVERY")) {
    const auto n = number(v);
    if (!n || *n < 1.0 || *n != std::floor(*n)) {
      error = std::string("CURVLAB_TEST_XR_CAPTURE_EVERY: '") + v + "': expected a whole number ≥ 1";
      return std::nullopt;
    }
    s.capture_every = static_cast<int>(*n);
  }
  if (const char* v = env("CURVLAB_TEST_XR_LATE")) {
    for (const auto& item : split(v, ',')) {
      const bool hidden = !item.empty() && item.back() == '!';
      const auto n = number(hidden ? item.substr(0, item.size() - 1) : item);
      if (!n || *n < 0.0 || *n != std::floor(*n)) {
        error = "CURVLAB_TEST_XR_LATE: '" + item +
                "': expected FRAME (its display time skips a period) or FRAME! (shouldRender false), "
                "FRAME a whole number ≥ 0";
        return std::nullopt;
      }
      (hidden ? s.late_hidden : s.late_skip).insert(static_cast<std::int64_t>(*n));
    }
  }
  if (const char* v = env("CURVLAB_TEST_XR_LOG")) s.log_path = v;
  if (const char* v = env("CURVLAB_TEST_XR_SIZE")) {
    const std::string text = v;
    const auto x = text.find('x');
    const auto w = number(text.substr(0, x));
    const auto h = x == std::string::npos ? std::nullopt : number(text.substr(x + 1));
    if (!w || !h || *w < 16.0 || *h < 16.0 || *w > 4096.0 || *h > 4096.0) {
      error = "CURVLAB_TEST_XR_SIZE: '" + text + "': expected WxH between 16 and 4096, e.g. 320x320";
      return std::nullopt;
    }
    s.eye_width_px = static_cast<std::uint32_t>(*w);
    s.eye_height_px = static_cast<std::uint32_t>(*h);
  }
  s.gaze = read_gaze_script(error);
  if (!error.empty()) return std::nullopt;
  return s;
}

Pose head_pose(double t_s) {
  constexpr double two_pi = 2.0 * std::numbers::pi;
  const double sway_x = 0.010 * std::sin(two_pi * 0.21 * t_s);
  const double sway_z = 0.008 * std::sin(two_pi * 0.13 * t_s + 1.0);
  const double yaw = 0.03 * std::sin(two_pi * 0.09 * t_s);
  const Quat turn = axis_angle({0.0, 1.0, 0.0}, yaw);
  const Quat pitch = axis_angle({1.0, 0.0, 0.0}, -25.0 * std::numbers::pi / 180.0);
  return {multiply(turn, pitch), {sway_x, 1.6, 0.85 + sway_z}};
}

Pose hand_pose(int hand, double t_s) {
  (void)t_s;
  return {Quat{}, {hand == 0 ? -0.25 : 0.25, 0.79, 0.52}};
}

Pose hand_pose(const Script& script, int hand, double t_s, double since_focus_s) {
  const Placement* latest = nullptr;
  for (const Placement& p : script.placements)
    if (p.hand == hand && p.at_s <= since_focus_s && (latest == nullptr || p.at_s >= latest->at_s)) latest = &p;
  return latest != nullptr ? Pose{Quat{}, latest->position_m} : hand_pose(hand, t_s);
}

std::optional<double> held_since(const Press& press, double t_s) {
  if (t_s < press.at_s) return std::nullopt;
  double start = press.at_s;
  if (press.every_s > 0.0) start += std::floor((t_s - press.at_s) / press.every_s) * press.every_s;
  if (t_s - start < press.hold_s) return start;
  return std::nullopt;
}

std::optional<double> last_change(const Press& press, double t_s) {
  if (t_s < press.at_s) return std::nullopt;
  double start = press.at_s;
  if (press.every_s > 0.0) start += std::floor((t_s - press.at_s) / press.every_s) * press.every_s;
  return t_s - start < press.hold_s ? start : start + press.hold_s;
}

}  // namespace curvlab::test_runtime
