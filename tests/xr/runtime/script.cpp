#include "script.hpp"

#include "eyes.hpp"

#include <algorithm>
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
    const auto hold = parse_number(rest.substr(tilde + 1));
    if (!hold || *hold <= 0.0) return std::nullopt;
    p.hold_s = *hold;
    rest = rest.substr(0, tilde);
  }
  if (const auto slash = rest.find('/'); slash != std::string::npos) {
    const auto every = parse_number(rest.substr(slash + 1));
    if (!every || *every <= p.hold_s) return std::nullopt;
    p.every_s = *every;
    rest = rest.substr(0, slash);
  }
  const auto start = parse_number(rest);
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
  const auto start = parse_number(item.substr(at + 1, eq - at - 1));
  const auto xyz = split(item.substr(eq + 1), ',');
  if (!start || *start < 0.0 || xyz.size() != 3) return std::nullopt;
  p.at_s = *start;
  double* out[3] = {&p.position_m.x, &p.position_m.y, &p.position_m.z};
  for (std::size_t i = 0; i < 3; ++i) {
    const auto v = parse_number(xyz[i]);
    if (!v || std::abs(*v) > 10.0) return std::nullopt;
    *out[i] = *v;
  }
  return p;
}

// "key=value,key=value": the pairs, or nullopt when an item has no '='.
std::optional<std::vector<std::pair<std::string, std::string>>> pairs(const std::string& text) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& item : split(text, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) return std::nullopt;
    out.emplace_back(item.substr(0, eq), item.substr(eq + 1));
  }
  return out;
}

// "jitter=1.5,miss=0.05,seed=7".
bool parse_timing(const std::string& text, Timing& t) {
  const auto kv = pairs(text);
  if (!kv || kv->empty()) return false;
  for (const auto& [k, v] : *kv) {
    const auto n = parse_number(v);
    if (!n) return false;
    if (k == "jitter" && *n >= 0.0 && *n <= 4.0) t.jitter_ms = *n;
    else if (k == "miss" && *n >= 0.0 && *n <= 0.5) t.miss = *n;
    else if (k == "seed" && *n >= 0.0 && *n == std::floor(*n)) t.seed = static_cast<std::uint64_t>(*n);
    else return false;
  }
  return true;
}

// "ready=0.5,visible=20,focused=30".
bool parse_bring_up(const std::string& text, BringUp& b) {
  const auto kv = pairs(text);
  if (!kv || kv->empty()) return false;
  for (const auto& [k, v] : *kv) {
    const auto n = parse_number(v);
    if (!n || *n < 0.0) return false;
    if (k == "ready" && *n <= 60.0) b.ready_s = *n;
    else if ((k == "visible" || k == "focused") && *n == std::floor(*n) && *n <= 10000.0)
      (k == "visible" ? b.visible_frames : b.focused_frames) = static_cast<int>(*n);
    else return false;
  }
  return true;
}

// "2.0=0.3,0,-0.2,20" or "…!" (the runtime does not know the move).
std::optional<StageMove> parse_stage_move(std::string text) {
  StageMove m;
  if (!text.empty() && text.back() == '!') {
    m.pose_valid = false;
    text.pop_back();
  }
  const auto eq = text.find('=');
  if (eq == std::string::npos) return std::nullopt;
  const auto at = parse_number(text.substr(0, eq));
  const auto parts = split(text.substr(eq + 1), ',');
  if (!at || *at < 0.0 || (parts.size() != 3 && parts.size() != 4)) return std::nullopt;
  m.at_s = *at;
  double v[4] = {0.0, 0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const auto n = parse_number(parts[i]);
    if (!n || std::abs(*n) > (i < 3 ? 10.0 : 180.0)) return std::nullopt;
    v[i] = *n;
  }
  m.origin = {axis_angle({0.0, 1.0, 0.0}, v[3] * std::numbers::pi / 180.0), {v[0], v[1], v[2]}};
  return m;
}

// "cant=10,ipd=0.058:0.070,fov=0.05".
bool parse_views(const std::string& text, Views& w) {
  const auto kv = pairs(text);
  if (!kv || kv->empty()) return false;
  for (const auto& [k, v] : *kv) {
    if (k == "ipd") {
      const auto colon = v.find(':');
      const auto lo = parse_number(v.substr(0, colon));
      const auto hi = colon == std::string::npos ? std::nullopt : parse_number(v.substr(colon + 1));
      if (!lo || !hi || *lo < 0.04 || *hi > 0.08 || *lo > *hi) return false;
      w.ipd_min_m = *lo;
      w.ipd_max_m = *hi;
      continue;
    }
    const auto n = parse_number(v);
    if (!n) return false;
    if (k == "cant" && *n >= 0.0 && *n <= 30.0) w.cant_deg = *n;
    else if (k == "fov" && *n >= 0.0 && *n <= 0.2) w.fov_change = *n;
    else return false;
  }
  return true;
}

// "right:orientation_only@1.5+0.5".
std::optional<TrackingSpell> parse_tracking(const std::string& item) {
  TrackingSpell s;
  const auto colon = item.find(':');
  const auto at = item.find('@');
  const auto plus = item.find('+');
  if (colon == std::string::npos || at == std::string::npos || plus == std::string::npos || at < colon || plus < at)
    return std::nullopt;
  const std::string device = item.substr(0, colon);
  const std::string mode = item.substr(colon + 1, at - colon - 1);
  if (device == "head") s.device = 0;
  else if (device == "left") s.device = 1;
  else if (device == "right") s.device = 2;
  else return std::nullopt;
  if (mode == "inferred") s.mode = TrackingMode::inferred;
  else if (mode == "orientation_only") s.mode = TrackingMode::orientation_only;
  else if (mode == "lost") s.mode = TrackingMode::lost;
  else return std::nullopt;
  const auto start = parse_number(item.substr(at + 1, plus - at - 1));
  const auto length = parse_number(item.substr(plus + 1));
  if (!start || !length || *start < 0.0 || *length <= 0.0) return std::nullopt;
  s.at_s = *start;
  s.for_s = *length;
  return s;
}

// "72,90,120@72".
bool parse_refresh(const std::string& text, Refresh& r) {
  const auto at = text.find('@');
  r.rates.clear();
  for (const auto& item : split(text.substr(0, at), ',')) {
    const auto n = parse_number(item);
    if (!n || *n < 30.0 || *n > 240.0) return false;
    r.rates.push_back(static_cast<float>(*n));
  }
  if (r.rates.empty()) return false;
  std::sort(r.rates.begin(), r.rates.end());
  r.start_hz = r.rates.front();
  if (at != std::string::npos) {
    const auto n = parse_number(text.substr(at + 1));
    if (!n || std::find(r.rates.begin(), r.rates.end(), static_cast<float>(*n)) == r.rates.end()) return false;
    r.start_hz = static_cast<float>(*n);
  }
  return true;
}

// VkFormat numbers (vulkan_core.h) of the formats the runtime can offer.
const std::vector<std::pair<std::string, std::int64_t>>& format_names() {
  static const std::vector<std::pair<std::string, std::int64_t>> names = {
      {"R8G8B8A8_UNORM", 37}, {"R8G8B8A8_SRGB", 43}, {"B8G8R8A8_UNORM", 44}, {"B8G8R8A8_SRGB", 50}};
  return names;
}

}  // namespace

std::optional<double> parse_number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

double uniform(std::uint64_t seed, std::int64_t n, int stream) {
  // splitmix64 (Steele, Lea and Flood 2014) of the three, mixed.
  std::uint64_t z = seed * 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(n) * 0xbf58476d1ce4e5b9ULL +
                    static_cast<std::uint64_t>(stream) * 0x94d049bb133111ebULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

std::optional<TrackingMode> tracking_mode(const Script& script, int device, double since_focus_s) {
  for (const TrackingSpell& s : script.tracking)
    if (s.device == device && since_focus_s >= s.at_s && since_focus_s < s.at_s + s.for_s) return s.mode;
  return std::nullopt;
}

EyeView eye_view(const Script& script, int eye, double t_s) {
  constexpr double two_pi = 2.0 * std::numbers::pi;
  const Views& w = script.views;
  const double side = eye == 0 ? -1.0 : 1.0;
  double ipd = kIpdM;
  if (w.ipd_max_m > 0.0)
    ipd = w.ipd_min_m + (w.ipd_max_m - w.ipd_min_m) * (0.5 + 0.5 * std::sin(two_pi * 0.37 * t_s));
  EyeView v;
  // Outward: the left eye turns left (positive about +y), the right eye right.
  v.pose = {axis_angle({0.0, 1.0, 0.0}, -side * w.cant_deg * std::numbers::pi / 180.0), {side * ipd / 2.0, 0.0, 0.0}};
  // Asymmetric, wider on the outer side, like a real headset's lenses.
  const double outer = 0.87, inner = 0.72;
  const double scale = 1.0 + w.fov_change * std::sin(two_pi * 0.53 * t_s + eye);
  v.fov_rad[0] = -(eye == 0 ? outer : inner) * scale;
  v.fov_rad[1] = (eye == 0 ? inner : outer) * scale;
  v.fov_rad[2] = 0.80 * scale;
  v.fov_rad[3] = -0.88 * scale;
  return v;
}

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
      const auto at = parse_number(item.substr(0, plus));
      const auto len = plus == std::string::npos ? std::nullopt : parse_number(item.substr(plus + 1));
      if (!at || !len || *at < 0.0 || *len <= 0.0) {
        error = "CURVLAB_TEST_XR_UNFOCUS: '" + item + "': expected SECONDS+DURATION, e.g. 4.2+0.5";
        return std::nullopt;
      }
      s.unfocus.push_back({*at, *len});
    }
  }
  if (const char* v = env("CURVLAB_TEST_XR_EXIT")) {
    const auto at = parse_number(v);
    if (!at || *at < 0.0) {
      error = std::string("CURVLAB_TEST_XR_EXIT: '") + v + "': expected seconds after focus";
      return std::nullopt;
    }
    s.exit_at_s = *at;
  }
  if (const char* v = env("CURVLAB_TEST_XR_RESTART")) {
    const std::string item = v;
    const auto plus = item.find('+');
    const auto at = parse_number(item.substr(0, plus));
    const auto idle = plus == std::string::npos ? std::nullopt : parse_number(item.substr(plus + 1));
    if (!at || !idle || *at < 0.0 || *idle < 0.0) {
      error = "CURVLAB_TEST_XR_RESTART: '" + item + "': expected SECONDS+IDLE_SECONDS, e.g. 3.15+0.5";
      return std::nullopt;
    }
    s.restart = Restart{*at, *idle};
  }
  if (const char* v = env("CURVLAB_TEST_XR_LOSS")) {
    const auto at = parse_number(v);
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
                             : parse_number(text.substr(at + 1, colon - at - 1));
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
    const auto n = parse_number(v);
    if (!n || *n < 1.0 || *n != std::floor(*n)) {
      error = std::string("CURVLAB_TEST_XR_CAPTURE_EVERY: '") + v + "': expected a whole number ≥ 1";
      return std::nullopt;
    }
    s.capture_every = static_cast<int>(*n);
  }
  if (const char* v = env("CURVLAB_TEST_XR_LATE")) {
    for (const auto& item : split(v, ',')) {
      const bool hidden = !item.empty() && item.back() == '!';
      const auto n = parse_number(hidden ? item.substr(0, item.size() - 1) : item);
      if (!n || *n < 0.0 || *n != std::floor(*n)) {
        error = "CURVLAB_TEST_XR_LATE: '" + item +
                "': expected FRAME (its display time skips a period) or FRAME! (shouldRender false), "
                "FRAME a whole number ≥ 0";
        return std::nullopt;
      }
      (hidden ? s.late_hidden : s.late_skip).insert(static_cast<std::int64_t>(*n));
    }
  }
  if (const char* v = env("CURVLAB_TEST_XR_TIMING"); v != nullptr && !parse_timing(v, s.timing)) {
    error = std::string("CURVLAB_TEST_XR_TIMING: '") + v +
            "': expected jitter=MS,miss=P,seed=N (any of them; MS within 4, P within 0.5, N a whole number)";
    return std::nullopt;
  }
  if (const char* v = env("CURVLAB_TEST_XR_SWAPCHAIN_WAIT")) {
    const std::string text = v;
    const auto slash = text.find('/');
    const auto ms = parse_number(text.substr(0, slash));
    const auto every = slash == std::string::npos ? std::nullopt : parse_number(text.substr(slash + 1));
    if (!ms || !every || *ms <= 0.0 || *ms > 5000.0 || *every < 1.0 || *every != std::floor(*every)) {
      error = "CURVLAB_TEST_XR_SWAPCHAIN_WAIT: '" + text +
              "': expected MS/EVERY (every EVERY-th image acquired is busy for MS milliseconds), e.g. 40/50";
      return std::nullopt;
    }
    s.swapchain_stall = {*ms, static_cast<int>(*every)};
  }
  if (const char* v = env("CURVLAB_TEST_XR_STATES"); v != nullptr && !parse_bring_up(v, s.bring_up)) {
    error = std::string("CURVLAB_TEST_XR_STATES: '") + v +
            "': expected ready=SECONDS,visible=FRAMES,focused=FRAMES (any of them; SECONDS within 60, FRAMES "
            "whole numbers)";
    return std::nullopt;
  }
  if (const char* v = env("CURVLAB_TEST_XR_STAGE_MOVE")) {
    s.stage_move = parse_stage_move(v);
    if (!s.stage_move) {
      error = std::string("CURVLAB_TEST_XR_STAGE_MOVE: '") + v +
              "': expected SECONDS=X,Y,Z[,YAW_DEG][!] (the new STAGE origin in the old, metres within 10 and "
              "degrees; ! when the runtime does not know it)";
      return std::nullopt;
    }
  }
  if (const char* v = env("CURVLAB_TEST_XR_EVENTS_LOST")) {
    const std::string text = v;
    const auto x = text.find('x');
    const auto at = parse_number(text.substr(0, x));
    const auto count = x == std::string::npos ? std::optional<double>(1.0) : parse_number(text.substr(x + 1));
    if (!at || !count || *at < 0.0 || *count < 1.0 || *count > 1000.0 || *count != std::floor(*count)) {
      error = "CURVLAB_TEST_XR_EVENTS_LOST: '" + text + "': expected SECONDS[xCOUNT], e.g. 2.5x3";
      return std::nullopt;
    }
    s.events_lost_at_s = *at;
    s.events_lost = static_cast<std::uint32_t>(*count);
  }
  if (const char* v = env("CURVLAB_TEST_XR_FORMATS")) {
    for (const auto& item : split(v, ',')) {
      const auto& names = format_names();
      const auto it = std::find_if(names.begin(), names.end(), [&](const auto& n) { return n.first == item; });
      if (it == names.end() ||
          std::find(s.formats.begin(), s.formats.end(), it->second) != s.formats.end()) {
        error = "CURVLAB_TEST_XR_FORMATS: '" + item +
                "': expected distinct names among R8G8B8A8_SRGB B8G8R8A8_SRGB R8G8B8A8_UNORM B8G8R8A8_UNORM";
        return std::nullopt;
      }
      s.formats.push_back(it->second);
    }
    if (s.formats.empty()) {
      error = "CURVLAB_TEST_XR_FORMATS: expected at least one format";
      return std::nullopt;
    }
  }
  if (const char* v = env("CURVLAB_TEST_XR_VIEWS"); v != nullptr && !parse_views(v, s.views)) {
    error = std::string("CURVLAB_TEST_XR_VIEWS: '") + v +
            "': expected cant=DEG,ipd=MIN:MAX,fov=FRACTION (any of them; DEG within 30, MIN and MAX in metres "
            "within 0.04 to 0.08, FRACTION within 0.2)";
    return std::nullopt;
  }
  if (const char* v = env("CURVLAB_TEST_XR_TRACKING")) {
    for (const auto& item : split(v, ',')) {
      auto spell = parse_tracking(item);
      if (!spell) {
        error = "CURVLAB_TEST_XR_TRACKING: '" + item +
                "': expected DEVICE:MODE@SECONDS+DURATION with DEVICE head, left or right and MODE inferred, "
                "orientation_only or lost";
        return std::nullopt;
      }
      s.tracking.push_back(*spell);
    }
  }
  if (const char* v = env("CURVLAB_TEST_XR_REFRESH"); v != nullptr && !parse_refresh(v, s.refresh)) {
    error = std::string("CURVLAB_TEST_XR_REFRESH: '") + v +
            "': expected RATES[@START], rates in Hz between 30 and 240, START one of them, e.g. 72,90,120@72";
    return std::nullopt;
  }
  if (const char* v = env("CURVLAB_TEST_XR_REFRESH_CHANGE")) {
    const std::string text = v;
    const auto eq = text.find('=');
    const auto at = parse_number(text.substr(0, eq));
    const auto hz = eq == std::string::npos ? std::nullopt : parse_number(text.substr(eq + 1));
    const auto& rates = s.refresh.rates;
    if (!at || !hz || *at < 0.0 ||
        std::find(rates.begin(), rates.end(), static_cast<float>(*hz)) == rates.end()) {
      error = "CURVLAB_TEST_XR_REFRESH_CHANGE: '" + text +
              "': expected SECONDS=HZ with HZ one of the rates offered (CURVLAB_TEST_XR_REFRESH)";
      return std::nullopt;
    }
    s.refresh.change_at_s = *at;
    s.refresh.change_to_hz = static_cast<float>(*hz);
  }
  if (const char* v = env("CURVLAB_TEST_XR_LOG")) s.log_path = v;
  if (const char* v = env("CURVLAB_TEST_XR_SIZE")) {
    const std::string text = v;
    const auto x = text.find('x');
    const auto w = parse_number(text.substr(0, x));
    const auto h = x == std::string::npos ? std::nullopt : parse_number(text.substr(x + 1));
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
