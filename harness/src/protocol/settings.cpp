#include "curvlab/harness/protocol/settings.hpp"

#include "curvlab/geometry/enum_names.hpp"
#include "curvlab/geometry/perception.hpp"
#include "curvlab/harness/protocol/diagnostic.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <type_traits>
#include <utility>

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
std::string_view to_string(HeadRequirement r) {
  switch (r) {
    case HeadRequirement::position: return "position";
    case HeadRequirement::orientation: return "orientation";
    case HeadRequirement::none: return "none";
  }
  return "?";
}
std::optional<StickAnchor> parse_stick_anchor(std::string_view text) {
  return geometry::parse_name(kStickAnchors, text);
}
std::optional<OnTrackingLoss> parse_on_tracking_loss(std::string_view text) {
  return geometry::parse_name(kOnTrackingLosses, text);
}
std::optional<HeadRequirement> parse_head_requirement(std::string_view text) {
  return geometry::parse_name(kHeadRequirements, text);
}

namespace {

using K = SettingKind;

std::optional<double> as_number(const SettingValue& v) {
  if (const auto* i = std::get_if<std::int64_t>(&v)) return static_cast<double>(*i);
  if (const auto* d = std::get_if<double>(&v)) return *d;
  return std::nullopt;
}

// The space kinds in the order a protocol's documentation lists them.
constexpr std::array kSpaceKinds{geometry::SpaceKind::S3, geometry::SpaceKind::E3, geometry::SpaceKind::H3};

// ---- typed access: a field of Settings named by its member pointers --------

// The field `s.*m1.*m2…`: &Settings::tracking, or &Settings::stimulus followed
// by &Stimulus::stick_length_m.
template <auto... Members, class S>
auto& field(S& s) {
  return (s .* ... .* Members);
}

// A field's value as a protocol writes it, and back; false for a value of
// the wrong type.
SettingValue protocol_value(bool b) { return b; }
SettingValue protocol_value(std::int64_t i) { return i; }
SettingValue protocol_value(double d) { return d; }

bool assign(bool& to, const SettingValue& v) {
  const auto* b = std::get_if<bool>(&v);
  if (b) to = *b;
  return b != nullptr;
}
bool assign(std::int64_t& to, const SettingValue& v) {
  const auto* i = std::get_if<std::int64_t>(&v);
  if (i) to = *i;
  return i != nullptr;
}
bool assign(double& to, const SettingValue& v) {
  const auto n = as_number(v);  // a TOML integer is a number too
  if (n) to = *n;
  return n.has_value();
}

// An entry whose field is a bool, an integer or a number, read and written
// as it is.
template <auto... Members>
SettingInfo plain(std::string_view path, SettingKind kind, double min, double max,
                  std::vector<std::string_view> choices, std::string_view meaning) {
  return {path, kind, min, max, std::move(choices), meaning,
          [](const Settings& s) -> std::optional<SettingValue> { return protocol_value(field<Members...>(s)); },
          [](Settings& s, const SettingValue& v) { return assign(field<Members...>(s), v); }};
}

// The type of the field `Members` name; each kind below takes one type, so
// a kind that does not fit its field does not compile.
template <auto... Members>
using FieldType = std::remove_cvref_t<decltype(field<Members...>(std::declval<Settings&>()))>;

template <auto... Members>
SettingInfo boolean(std::string_view path, std::string_view meaning) {
  static_assert(std::is_same_v<FieldType<Members...>, bool>);
  return plain<Members...>(path, K::boolean, 0, 0, {}, meaning);
}
template <auto... Members>
SettingInfo integer(std::string_view path, double min, double max, std::string_view meaning,
                    std::vector<std::string_view> only = {}) {
  static_assert(std::is_same_v<FieldType<Members...>, std::int64_t>);
  return plain<Members...>(path, K::integer, min, max, std::move(only), meaning);
}
template <auto... Members>
SettingInfo number(std::string_view path, double min, double max, std::string_view meaning) {
  static_assert(std::is_same_v<FieldType<Members...>, double>);
  return plain<Members...>(path, K::number, min, max, {}, meaning);
}

// An entry whose field is an enumeration: written by name, one of `Values`
// (listed beside the enumeration's declaration; geometry/enum_names.hpp).
template <const auto& Values, auto... Members>
SettingInfo enumeration(std::string_view path, std::string_view meaning) {
  static_assert(std::is_same_v<FieldType<Members...>, typename std::remove_cvref_t<decltype(Values)>::value_type>);
  return {path, K::enumeration, 0, 0, geometry::names_of(Values), meaning,
          [](const Settings& s) -> std::optional<SettingValue> {
            return std::string(to_string(field<Members...>(s)));
          },
          [](Settings& s, const SettingValue& v) {
            const auto* name = std::get_if<std::string>(&v);
            const auto parsed = name ? geometry::parse_name(Values, *name) : std::nullopt;
            if (parsed) field<Members...>(s) = *parsed;
            return parsed.has_value();
          }};
}

// ---- the three settings that are not one plain field ------------------------

// space.radius_m: metres, or "from_table" (unset: derived from the table).
std::optional<SettingValue> get_radius(const Settings& s) {
  if (s.space.radius_m) return *s.space.radius_m;
  return std::string("from_table");
}
bool set_radius(Settings& s, const SettingValue& v) {
  if (const auto* text = std::get_if<std::string>(&v)) {
    if (*text != "from_table") return false;
    s.space.radius_m.reset();
    return true;
  }
  const auto n = as_number(v);
  if (n) s.space.radius_m = *n;
  return n.has_value();
}

// space.table_sides: 0 stands for the space's default and is never written.
std::optional<SettingValue> get_table_sides(const Settings& s) {
  if (s.space.table_sides == 0) return std::nullopt;
  return std::int64_t{s.space.table_sides};
}
bool set_table_sides(Settings& s, const SettingValue& v) {
  const auto* i = std::get_if<std::int64_t>(&v);
  if (i) s.space.table_sides = static_cast<int>(*i);
  return i != nullptr;
}

// viewing.msaa: a sample count, or "auto" (unset: the renderer picks for its
// device).
std::optional<SettingValue> get_msaa(const Settings& s) {
  if (s.viewing.msaa) return std::int64_t{*s.viewing.msaa};
  return std::string("auto");
}
bool set_msaa(Settings& s, const SettingValue& v) {
  if (const auto* text = std::get_if<std::string>(&v)) {
    if (*text != "auto") return false;
    s.viewing.msaa.reset();
    return true;
  }
  const auto* i = std::get_if<std::int64_t>(&v);
  if (i == nullptr || *i < 1 || *i > 8) return false;
  s.viewing.msaa = static_cast<std::uint32_t>(*i);
  return true;
}

// viewing.preset: a name for a projection and eyes pair, which it sets; it
// holds no value of its own.
std::optional<SettingValue> get_preset(const Settings&) { return std::nullopt; }
bool set_preset(Settings& s, const SettingValue& v) {
  const auto* name = std::get_if<std::string>(&v);
  const auto preset = name ? geometry::parse_view_preset(*name) : std::nullopt;
  if (!preset) return false;
  const auto viewing = renderer::preset_viewing(*preset);
  s.viewing.projection = viewing.projection;
  s.viewing.eyes = viewing.eyes;
  return true;
}

// ---- the registry -----------------------------------------------------------

using S = Settings;

std::vector<SettingInfo> make_registry() {
  // Ranges are what a lab can physically mean, wide enough for pilots; they
  // catch unit slips (millimetres written as metres, seconds as ms).
  return {
      enumeration<kSpaceKinds, &S::space, &SpaceSettings::kind>("space.kind", "the space"),
      {"space.radius_m", K::number_or_from_table, 0.01, 1000.0, {},
       "ρ in metres, or \"from_table\": ρ = table.edge_m / side_rad", get_radius, set_radius},
      {"space.table_sides", K::integer, 3, 12, {},
       "sides of the right-angled virtual table (S3 3, E3 4, H3 ≥ 5)", get_table_sides, set_table_sides},
      number<&S::space, &SpaceSettings::e3_radius_m>("space.e3_radius_m", 0.01, 1000.0,
                                                     "the radius that defines Euclidean radians in E3"),
      enumeration<geometry::kTrackingAlgorithms, &S::tracking>(
          "tracking.algorithm", "body-coherent tracking algorithm (paper, sections 4–5)"),
      integer<&S::tracking_loss, &TrackingLoss::loss_ms>(
          "tracking.loss_ms", 10, 10000,
          "how long the head may be untracked before the trial counts tracking as lost"),
      enumeration<kOnTrackingLosses, &S::tracking_loss, &TrackingLoss::on_loss>(
          "tracking.on_loss", "tracking lost: repeat the trial, flag it and go on, or mark it aborted"),
      integer<&S::tracking_loss, &TrackingLoss::max_attempts>(
          "tracking.max_attempts", 0, 100, "attempts a trial is given before it is marked aborted (0: no limit)"),
      enumeration<kHeadRequirements, &S::tracking_loss, &TrackingLoss::head_requires>(
          "tracking.head_requires",
          "what the head must be for a trial to count it tracked: position (and orientation) tracked, "
          "orientation tracked (position valid, possibly inferred), or none"),
      integer<&S::tracking_loss, &TrackingLoss::head_wait_ms>(
          "tracking.head_wait_ms", 0, 600000,
          "how long the session waits for the head after tracking was lost before it stops, interrupted "
          "and resumable"),
      {"viewing.preset", K::enumeration, 0, 0, geometry::names_of(geometry::kViewPresets),
       "sets projection and eyes: tourist = tourist/both, native = native/both, "
       "monocular = native/dominant",
       get_preset, set_preset},
      enumeration<renderer::kProjections, &S::viewing, &Viewing::projection>(
          "viewing.projection", "tourist (true optics) or native (azimuthal-equidistant) projection"),
      enumeration<renderer::kEyeSelections, &S::viewing, &Viewing::eyes>(
          "viewing.eyes", "which eyes see the scene; the other shows the background"),
      boolean<&S::viewing, &Viewing::back_hemisphere>("viewing.back_hemisphere", "S3: draw the antipodal images"),
      number<&S::viewing, &Viewing::ipd_m>("viewing.ipd_m", 0.045, 0.085,
                                           "default interpupillary distance (used when the runtime gives none)"),
      number<&S::viewing, &Viewing::text_height_deg>(
          "viewing.text_height_deg", 0.5, 6.0,
          "height of a line of the participant's panels (instructions, prompts, answers) in degrees of "
          "visual angle; the panels are fixed to the head, the same in every space"),
      {"viewing.msaa", K::integer_or_auto, 1, 8, {"1", "2", "4", "8"},
       "samples per pixel for anti-aliased edges (1: none), clamped to what the device supports; "
       "\"auto\": 4 on a GPU, 1 on a CPU device (lavapipe)",
       get_msaa, set_msaa},
      integer<&S::timeline, &Timeline::fixation_ms>("timeline.fixation_ms", 0, 60000,
                                                    "fixation mark before the stimulus"),
      integer<&S::timeline, &Timeline::stimulus_ms>("timeline.stimulus_ms", 1, 600000, "stimulus duration"),
      integer<&S::timeline, &Timeline::response_ms>("timeline.response_ms", 1, 600000, "response window"),
      integer<&S::timeline, &Timeline::iti_ms>("timeline.iti_ms", 0, 60000, "inter-trial interval"),
      boolean<&S::timeline, &Timeline::stimulus_during_response>(
          "timeline.stimulus_during_response", "keep the stimulus visible during the response window"),
      number<&S::stimulus, &Stimulus::stick_length_m>("stimulus.stick_length_m", 0.05, 5.0, "cue stick length"),
      number<&S::stimulus, &Stimulus::stick_radius_m>("stimulus.stick_radius_m", 0.001, 0.1, "cue stick radius"),
      number<&S::stimulus, &Stimulus::stick_sagitta_m>(
          "stimulus.stick_sagitta_m", -1.0, 1.0, "signed bend of the stick at its middle; + bows toward the viewer"),
      enumeration<kStickAnchors, &S::stimulus, &Stimulus::stick_anchor>(
          "stimulus.stick_anchor", "the stick's pose is relative to the head or to the table"),
      number<&S::stimulus, &Stimulus::stick_distance_m>(
          "stimulus.stick_distance_m", 0.0, 20.0,
          "distance from the eyes (head anchor, at least 0.1) or from the table centre toward "
          "the participant's edge (table anchor)"),
      number<&S::stimulus, &Stimulus::stick_height_m>(
          "stimulus.stick_height_m", -2.0, 2.0, "height relative to the eyes (head) or to the table top (table)"),
      number<&S::stimulus, &Stimulus::stick_yaw_deg>("stimulus.stick_yaw_deg", -180.0, 180.0,
                                                     "rotation about the vertical; 0 lies across the line of sight"),
      enumeration<renderer::kStickMarks, &S::stimulus, &Stimulus::stick_marks>(
          "stimulus.stick_marks",
          "marks along the stick: none, or light rings at 0.1, 0.3, 0.5, 0.7 and 0.9 of its length"),
      boolean<&S::stimulus, &Stimulus::show_stick>("stimulus.show_stick", "draw the cue stick"),
      boolean<&S::stimulus, &Stimulus::show_table>("stimulus.show_table", "draw the billiards table"),
      number<&S::stimulus, &Stimulus::table_sagitta_m>("stimulus.table_sagitta_m", -1.0, 1.0,
                                                       "signed convexity of the table top at its centre; + bulges up"),
      integer<&S::stimulus, &Stimulus::balls>("stimulus.balls", 0, 16, "number of balls on the table"),
      number<&S::stimulus, &Stimulus::ball_radius_m>("stimulus.ball_radius_m", 0.005, 0.2, "ball radius"),
      number<&S::table, &TableSettings::edge_m>("table.edge_m", 0.2, 5.0, "physical table edge length"),
      number<&S::table, &TableSettings::height_m>("table.height_m", 0.3, 1.5,
                                                  "physical table top height above the floor"),
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

}  // namespace

Result<Done> check_setting(const SettingInfo& info, const SettingValue& value) {
  switch (info.kind) {
    case K::boolean:
      if (!std::holds_alternative<bool>(value)) return setting_problem("expected true or false");
      return Done{};
    case K::integer_or_auto:
      if (const auto* s = std::get_if<std::string>(&value)) {
        if (*s == "auto") return Done{};
        return setting_problem("expected \"auto\" or one of " + values_text(info) + ", found \"" + *s + "\"");
      }
      if (!std::holds_alternative<std::int64_t>(value))
        return setting_problem("expected \"auto\" or one of " + values_text(info));
      [[fallthrough]];
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
                               " or \"from_table\", found \"" + *s + "\"" + did_you_mean(*s, {"from_table"}));
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
      return setting_problem(unknown_value(*s, {info.choices.begin(), info.choices.end()}));
    }
  }
  return setting_problem("unsupported setting");
}

void apply_setting(Settings& s, const SettingInfo& info, const SettingValue& value) {
  if (info.set(s, value)) return;
  // Only values check_setting accepted may reach here: a broken contract.
  const auto checked = check_setting(info, value);
  std::fprintf(stderr, "curvlab: %s = %s was applied unchecked: %s\n", std::string(info.path).c_str(),
               value_label(value).c_str(), checked ? "the setting refused it" : checked.error().message.c_str());
  std::abort();
}

namespace {
// The settings a staircase or an adjustment may vary: plain numbers (not
// space.radius_m, which may be "from_table").
const SettingInfo* numeric_info(std::string_view path) {
  const SettingInfo* info = find_setting(path);
  return info && info->kind == K::number ? info : nullptr;
}
}  // namespace

std::vector<std::string> numeric_setting_paths() {
  std::vector<std::string> out;
  for (const auto& info : all_settings())
    if (info.kind == K::number) out.emplace_back(info.path);
  return out;
}

std::optional<double> numeric_setting(const Settings& s, std::string_view path) {
  const SettingInfo* info = numeric_info(path);
  if (!info) return std::nullopt;
  return as_number(info->get(s).value());
}

bool set_numeric_setting(Settings& s, std::string_view path, double value) {
  const SettingInfo* info = numeric_info(path);
  return info && info->set(s, SettingValue(std::in_place_type<double>, value));
}

}  // namespace curvlab::harness::protocol
