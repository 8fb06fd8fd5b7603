#include "curvlab/harness/protocol/settings.hpp"

#include "curvlab/geometry/enum_names.hpp"
#include "curvlab/geometry/perception.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace curvlab::harness::protocol {

std::string_view to_string(StickAnchor a) {
  switch (a) {
    case StickAnchor::head: return "head";
    case StickAnchor::table: return "table";
  }
  return "?";
}
std::string_view to_string(OnTrackingLoss o) {
  switch (o) {
    case OnTrackingLoss::repeat: return "repeat";
    case OnTrackingLoss::flag: return "flag";
    case OnTrackingLoss::abort: return "abort";
  }
  return "?";
}
std::optional<StickAnchor> parse_stick_anchor(std::string_view text) {
  return geometry::parse_name(kStickAnchors, text);
}
std::optional<OnTrackingLoss> parse_on_tracking_loss(std::string_view text) {
  return geometry::parse_name(kOnTrackingLosses, text);
}

namespace {

using K = SettingKind;

std::vector<SettingInfo> make_registry() {
  // Ranges are what a lab can physically mean, wide enough for pilots; they
  // catch unit slips (millimetres written as metres, seconds as ms).
  return {
      {"space.kind", K::enumeration, 0, 0, {"S3", "E3", "H3"}, "the space"},
      {"space.radius_m", K::number_or_from_table, 0.01, 1000.0, {},
       "ρ in metres, or \"from_table\": ρ = table.edge_m / side_rad"},
      {"space.table_sides", K::integer, 3, 12, {},
       "sides of the right-angled virtual table (S3 3, E3 4, H3 ≥ 5)"},
      {"space.e3_radius_m", K::number, 0.01, 1000.0, {},
       "the radius that defines Euclidean radians in E3"},
      {"tracking.algorithm", K::enumeration, 0, 0, geometry::names_of(geometry::kTrackingAlgorithms),
       "body-coherent tracking algorithm (paper, sections 4–5)"},
      {"tracking.loss_ms", K::integer, 10, 10000, {},
       "how long the head may be untracked before the trial counts tracking as lost"},
      {"tracking.on_loss", K::enumeration, 0, 0, geometry::names_of(kOnTrackingLosses),
       "tracking lost: repeat the trial, flag it and go on, or mark it aborted"},
      {"tracking.max_attempts", K::integer, 0, 100, {},
       "attempts a trial is given before it is marked aborted (0: no limit)"},
      {"viewing.preset", K::enumeration, 0, 0, geometry::names_of(geometry::kViewPresets),
       "sets projection and eyes: tourist = tourist/both, native = native/both, "
       "monocular = native/dominant"},
      {"viewing.projection", K::enumeration, 0, 0, geometry::names_of(renderer::kProjections),
       "tourist (true optics) or native (azimuthal-equidistant) projection"},
      {"viewing.eyes", K::enumeration, 0, 0, geometry::names_of(renderer::kEyeSelections),
       "which eyes see the scene; the other shows the background"},
      {"viewing.back_hemisphere", K::boolean, 0, 0, {}, "S3: draw the antipodal images"},
      {"viewing.ipd_m", K::number, 0.045, 0.085, {},
       "default interpupillary distance (used when the runtime gives none)"},
      {"viewing.msaa", K::integer, 1, 8, {"1", "2", "4", "8"},
       "samples per pixel for anti-aliased edges (1: none); clamped to what the device supports"},
      {"timeline.fixation_ms", K::integer, 0, 60000, {}, "fixation mark before the stimulus"},
      {"timeline.stimulus_ms", K::integer, 1, 600000, {}, "stimulus duration"},
      {"timeline.response_ms", K::integer, 1, 600000, {}, "response window"},
      {"timeline.iti_ms", K::integer, 0, 60000, {}, "inter-trial interval"},
      {"timeline.stimulus_during_response", K::boolean, 0, 0, {},
       "keep the stimulus visible during the response window"},
      {"stimulus.stick_length_m", K::number, 0.05, 5.0, {}, "cue stick length"},
      {"stimulus.stick_radius_m", K::number, 0.001, 0.1, {}, "cue stick radius"},
      {"stimulus.stick_sagitta_m", K::number, -1.0, 1.0, {},
       "signed bend of the stick at its middle; + bows toward the viewer"},
      {"stimulus.stick_anchor", K::enumeration, 0, 0, geometry::names_of(kStickAnchors),
       "the stick's pose is relative to the head or to the table"},
      {"stimulus.stick_distance_m", K::number, 0.0, 20.0, {},
       "distance from the eyes (head anchor, at least 0.1) or from the table centre toward "
       "the participant's edge (table anchor)"},
      {"stimulus.stick_height_m", K::number, -2.0, 2.0, {},
       "height relative to the eyes (head) or to the table top (table)"},
      {"stimulus.stick_yaw_deg", K::number, -180.0, 180.0, {},
       "rotation about the vertical; 0 lies across the line of sight"},
      {"stimulus.stick_marks", K::enumeration, 0, 0, geometry::names_of(renderer::kStickMarks),
       "marks along the stick: none, or light rings at 0.1, 0.3, 0.5, 0.7 and 0.9 of its length"},
      {"stimulus.show_stick", K::boolean, 0, 0, {}, "draw the cue stick"},
      {"stimulus.show_table", K::boolean, 0, 0, {}, "draw the billiards table"},
      {"stimulus.table_sagitta_m", K::number, -1.0, 1.0, {},
       "signed convexity of the table top at its centre; + bulges up"},
      {"stimulus.balls", K::integer, 0, 16, {}, "number of balls on the table"},
      {"stimulus.ball_radius_m", K::number, 0.005, 0.2, {}, "ball radius"},
      {"table.edge_m", K::number, 0.2, 5.0, {}, "physical table edge length"},
      {"table.height_m", K::number, 0.3, 1.5, {}, "physical table top height above the floor"},
  };
}

std::string number_text(double v) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string choices_text(const SettingInfo& info) {
  std::string out;
  for (std::size_t i = 0; i < info.choices.size(); ++i) {
    if (i) out += ", ";
    out += '"';
    out += info.choices[i];
    out += '"';
  }
  return out;
}

// The allowed integers, as a protocol writes them (no quotes).
std::string values_text(const SettingInfo& info) {
  std::string out;
  for (std::size_t i = 0; i < info.choices.size(); ++i) {
    if (i) out += ", ";
    out += info.choices[i];
  }
  return out;
}

std::string range_text(const SettingInfo& info) {
  std::string out = "[";
  out += number_text(info.min);
  out += ", ";
  out += number_text(info.max);
  out += ']';
  return out;
}

std::optional<double> as_number(const SettingValue& v) {
  if (const auto* i = std::get_if<std::int64_t>(&v)) return static_cast<double>(*i);
  if (const auto* d = std::get_if<double>(&v)) return *d;
  return std::nullopt;
}

}  // namespace

const std::vector<SettingInfo>& all_settings() {
  static const std::vector<SettingInfo> registry = make_registry();
  return registry;
}

const SettingInfo* find_setting(std::string_view path) {
  for (const auto& s : all_settings())
    if (s.path == path) return &s;
  return nullptr;
}

std::vector<std::string> setting_keys(std::string_view section) {
  std::vector<std::string> keys;
  for (const auto& s : all_settings()) {
    const auto dot = s.path.find('.');
    if (s.path.substr(0, dot) == section) keys.emplace_back(s.path.substr(dot + 1));
  }
  return keys;
}

bool is_setting_section(std::string_view section) { return !setting_keys(section).empty(); }

std::string value_label(const SettingValue& v) {
  if (const auto* b = std::get_if<bool>(&v)) return *b ? "true" : "false";
  if (const auto* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const auto* d = std::get_if<double>(&v)) return number_text(*d);
  return std::get<std::string>(v);
}

namespace {

// What check_setting found wrong: the protocol's to fix (bad_input).
Error setting_problem(std::string message) { return {Error::Kind::bad_input, std::move(message)}; }

// apply_setting is given only values check_setting accepted, so a name that
// does not parse there is a broken contract: it names the value and the
// choices, and stops.
template <class E>
E checked(std::optional<E> parsed, const SettingInfo& info, const std::string& text) {
  if (parsed) return *parsed;
  std::fprintf(stderr, "curvlab: %s = \"%s\" was applied unchecked: expected one of %s\n",
               std::string(info.path).c_str(), text.c_str(), choices_text(info).c_str());
  std::abort();
}

}  // namespace

Result<Done> check_setting(const SettingInfo& info, const SettingValue& value) {
  switch (info.kind) {
    case K::boolean:
      if (!std::holds_alternative<bool>(value)) return setting_problem("expected true or false");
      return Done{};
    case K::integer: {
      const auto* i = std::get_if<std::int64_t>(&value);
      if (!i) return setting_problem("expected an integer in " + range_text(info));
      if (static_cast<double>(*i) < info.min || static_cast<double>(*i) > info.max)
        return setting_problem("expected an integer in " + range_text(info) + ", found " + std::to_string(*i));
      if (!info.choices.empty() &&
          std::find(info.choices.begin(), info.choices.end(), std::to_string(*i)) == info.choices.end())
        return setting_problem("expected one of " + values_text(info) + ", found " + std::to_string(*i));
      return Done{};
    }
    case K::number_or_from_table:
      if (const auto* s = std::get_if<std::string>(&value)) {
        if (*s == "from_table") return Done{};
        return setting_problem("expected a number of metres in " + range_text(info) +
               " or \"from_table\", found \"" + *s + "\"");
      }
      [[fallthrough]];
    case K::number: {
      const auto n = as_number(value);
      if (!n) return setting_problem("expected a number in " + range_text(info));
      if (!std::isfinite(*n) || *n < info.min || *n > info.max)
        return setting_problem("expected a number in " + range_text(info) + ", found " + number_text(*n));
      return Done{};
    }
    case K::enumeration: {
      const auto* s = std::get_if<std::string>(&value);
      if (!s) return setting_problem("expected one of " + choices_text(info));
      for (auto c : info.choices)
        if (c == *s) return Done{};
      return setting_problem("unknown value \"" + *s + "\": expected one of " + choices_text(info));
    }
  }
  return setting_problem("unsupported setting");
}

void apply_setting(Settings& s, const SettingInfo& info, const SettingValue& value) {
  const std::string_view p = info.path;
  const auto num = as_number(value).value_or(0.0);
  const auto integer = std::holds_alternative<std::int64_t>(value) ? std::get<std::int64_t>(value) : 0;
  const bool flag = std::holds_alternative<bool>(value) && std::get<bool>(value);
  const std::string text = std::holds_alternative<std::string>(value) ? std::get<std::string>(value) : "";
  if (p == "space.kind") {
    s.space.kind = checked(geometry::parse_space_kind(text), info, text);
  } else if (p == "space.radius_m") {
    if (text == "from_table") s.space.radius_m.reset();
    else s.space.radius_m = num;
  } else if (p == "space.table_sides") {
    s.space.table_sides = static_cast<int>(integer);
  } else if (p == "space.e3_radius_m") {
    s.space.e3_radius_m = num;
  } else if (p == "tracking.algorithm") {
    s.tracking = checked(geometry::parse_tracking_algorithm(text), info, text);
  } else if (p == "tracking.loss_ms") {
    s.tracking_loss.loss_ms = integer;
  } else if (p == "tracking.on_loss") {
    s.tracking_loss.on_loss = checked(parse_on_tracking_loss(text), info, text);
  } else if (p == "tracking.max_attempts") {
    s.tracking_loss.max_attempts = integer;
  } else if (p == "viewing.preset") {
    const auto viewing = renderer::preset_viewing(checked(geometry::parse_view_preset(text), info, text));
    s.viewing.projection = viewing.projection;
    s.viewing.eyes = viewing.eyes;
  } else if (p == "viewing.projection") {
    s.viewing.projection = checked(renderer::parse_projection(text), info, text);
  } else if (p == "viewing.eyes") {
    s.viewing.eyes = checked(renderer::parse_eye_selection(text), info, text);
  } else if (p == "viewing.back_hemisphere") {
    s.viewing.back_hemisphere = flag;
  } else if (p == "viewing.ipd_m") {
    s.viewing.ipd_m = num;
  } else if (p == "viewing.msaa") {
    s.viewing.msaa = integer;
  } else if (p == "timeline.fixation_ms") {
    s.timeline.fixation_ms = integer;
  } else if (p == "timeline.stimulus_ms") {
    s.timeline.stimulus_ms = integer;
  } else if (p == "timeline.response_ms") {
    s.timeline.response_ms = integer;
  } else if (p == "timeline.iti_ms") {
    s.timeline.iti_ms = integer;
  } else if (p == "timeline.stimulus_during_response") {
    s.timeline.stimulus_during_response = flag;
  } else if (p == "stimulus.stick_anchor") {
    s.stimulus.stick_anchor = checked(parse_stick_anchor(text), info, text);
  } else if (p == "stimulus.stick_marks") {
    s.stimulus.stick_marks = checked(renderer::parse_stick_marks(text), info, text);
  } else if (p == "stimulus.show_stick") {
    s.stimulus.show_stick = flag;
  } else if (p == "stimulus.show_table") {
    s.stimulus.show_table = flag;
  } else if (p == "stimulus.balls") {
    s.stimulus.balls = integer;
  } else {
    set_numeric_setting(s, p, num);
  }
}

namespace {
template <typename S>
auto numeric_field(S& s, std::string_view p) -> decltype(&s.space.e3_radius_m) {
  if (p == "space.radius_m") return nullptr;  // may be "from_table"; not adjustable
  if (p == "space.e3_radius_m") return &s.space.e3_radius_m;
  if (p == "viewing.ipd_m") return &s.viewing.ipd_m;
  if (p == "stimulus.stick_length_m") return &s.stimulus.stick_length_m;
  if (p == "stimulus.stick_radius_m") return &s.stimulus.stick_radius_m;
  if (p == "stimulus.stick_sagitta_m") return &s.stimulus.stick_sagitta_m;
  if (p == "stimulus.stick_distance_m") return &s.stimulus.stick_distance_m;
  if (p == "stimulus.stick_height_m") return &s.stimulus.stick_height_m;
  if (p == "stimulus.stick_yaw_deg") return &s.stimulus.stick_yaw_deg;
  if (p == "stimulus.table_sagitta_m") return &s.stimulus.table_sagitta_m;
  if (p == "stimulus.ball_radius_m") return &s.stimulus.ball_radius_m;
  if (p == "table.edge_m") return &s.table.edge_m;
  if (p == "table.height_m") return &s.table.height_m;
  return nullptr;
}
}  // namespace

std::vector<std::string> numeric_setting_paths() {
  std::vector<std::string> out;
  const Settings s;
  for (const auto& info : all_settings())
    if (numeric_setting(s, info.path)) out.emplace_back(info.path);
  return out;
}

std::optional<double> numeric_setting(const Settings& s, std::string_view path) {
  if (const double* f = numeric_field(s, path)) return *f;
  return std::nullopt;
}

bool set_numeric_setting(Settings& s, std::string_view path, double value) {
  if (double* f = numeric_field(s, path)) {
    *f = value;
    return true;
  }
  return false;
}

}  // namespace curvlab::harness::protocol
