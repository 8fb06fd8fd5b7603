// The per-trial settings a protocol controls, and the registry that names
// each of them by a dotted path ("viewing.projection", "stimulus.stick_sagitta_m").
// The same registry checks a value written in a session section, in a block
// override and as a factor level, so the three can never disagree about what
// is allowed. Values resolve session → block → factor level (UXF's fallback
// from trial to block to session, with the factor level winning).
//
// Each registry entry also reads and writes its field of Settings, so that
// applying a value, the staircase's numeric access, the JSON Schema's
// defaults and the settings records (settings_json.hpp) all walk the one
// table: a new setting is a field here and an entry in settings.cpp.
#pragma once

#include "curvlab/geometry/space.hpp"
#include "curvlab/geometry/tracking.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/renderer/vocabulary.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace curvlab::harness::protocol {

// The tracking algorithm (geometry/tracking.hpp), the projection, eyes and
// stick marks (renderer/vocabulary.hpp) are the lower layers' types; these
// two are the protocol's own.
enum class StickAnchor { head, table };
inline constexpr std::array kStickAnchors{StickAnchor::head, StickAnchor::table};
// What a trial does when the head has been untracked for `loss_ms`.
enum class OnTrackingLoss { repeat, flag, abort };
inline constexpr std::array kOnTrackingLosses{OnTrackingLoss::repeat, OnTrackingLoss::flag, OnTrackingLoss::abort};
// What a trial needs of the head for it to count as tracked: position and
// orientation tracked; orientation tracked (a headset without positional
// tracking, or a simulated one, whose position is valid but inferred); or
// nothing (the head's tracking never stops a trial).
enum class HeadRequirement { position, orientation, none };
inline constexpr std::array kHeadRequirements{HeadRequirement::position, HeadRequirement::orientation,
                                              HeadRequirement::none};

std::string_view to_string(StickAnchor a);
std::string_view to_string(OnTrackingLoss o);
std::string_view to_string(HeadRequirement r);
std::optional<StickAnchor> parse_stick_anchor(std::string_view text);
std::optional<OnTrackingLoss> parse_on_tracking_loss(std::string_view text);
std::optional<HeadRequirement> parse_head_requirement(std::string_view text);

struct SpaceSettings {
  geometry::SpaceKind kind = geometry::SpaceKind::E3;
  // nullopt: derived from the physical table's edge, ρ = L / side_rad
  // (paper, "Construction of the billiards tables"); E3 then uses e3_radius_m.
  std::optional<double> radius_m;
  int table_sides = 0;  // 0: the space's default (S3 3, E3 4, H3 5)
  double e3_radius_m = 1.0;  // the radius that defines Euclidean radians
};

// Interruptions of a trial. Tracking loss follows `on_loss`: the attempt is
// dropped and the trial runs again once the head is tracked (repeat), the
// trial goes on and is flagged (flag), or the trial is marked aborted and
// the session moves on (abort). A recenter or a pause always drops the
// attempt. `max_attempts` (0: no limit) marks a trial aborted instead of
// starting it again after that many attempts. What counts as tracked is
// `head_requires`; after a loss the session waits at most `head_wait_ms` for
// the head, then stops `interrupted` (resumable) with the tracking the
// pose source reported, instead of waiting for a head that never comes.
struct TrackingLoss {
  std::int64_t loss_ms = 250;
  OnTrackingLoss on_loss = OnTrackingLoss::repeat;
  std::int64_t max_attempts = 0;
  HeadRequirement head_requires = HeadRequirement::position;
  std::int64_t head_wait_ms = 10000;
};

struct Viewing {
  renderer::Projection projection = renderer::Projection::tourist;
  renderer::EyeSelection eyes = renderer::EyeSelection::both;
  bool back_hemisphere = true;  // S3 only: draw the antipodal images
  double ipd_m = 0.063;
  // A line of the participant's panels (instructions, prompts, answers),
  // ascent to descent, in degrees of visual angle: head-locked, so the same
  // in every space.
  double text_height_deg = 2.0;
  // Samples per pixel for anti-aliasing (1, 2, 4 or 8), clamped by the
  // renderer to what the device supports; nullopt ("auto"): the renderer's
  // choice for its device, 4 on a GPU and 1 on a CPU device
  // (renderer::automatic_msaa).
  std::optional<std::uint32_t> msaa;
};

// Per-trial timeline in milliseconds: fixation → stimulus → response window
// → inter-trial interval.
struct Timeline {
  std::int64_t fixation_ms = 500;
  std::int64_t stimulus_ms = 1500;
  std::int64_t response_ms = 4000;
  std::int64_t iti_ms = 500;
  bool stimulus_during_response = true;
  [[nodiscard]] std::int64_t total_ms() const {
    return fixation_ms + stimulus_ms + response_ms + iti_ms;
  }
};

struct Stimulus {
  double stick_length_m = 1.0;
  double stick_radius_m = 0.012;
  // Signed sagitta of the stick's bend: positive bows toward the viewer.
  double stick_sagitta_m = 0.0;
  StickAnchor stick_anchor = StickAnchor::head;
  double stick_distance_m = 1.0;  // from the eyes (head) or the table centre (table)
  double stick_height_m = 0.0;    // relative to eye height (head) or table top (table)
  double stick_yaw_deg = 0.0;     // rotation about the vertical, 0 = across the view
  renderer::StickMarks stick_marks = renderer::StickMarks::none;
  bool show_stick = true;
  bool show_table = true;
  double table_sagitta_m = 0.0;   // signed convexity of the table top, + bulges up
  std::int64_t balls = 0;
  double ball_radius_m = 0.028575;  // 57.15 mm balls (paper, "VR needs explicit units")
};

struct TableSettings {
  double edge_m = 1.0;
  double height_m = 0.76;
};

struct Settings {
  SpaceSettings space;
  geometry::TrackingAlgorithm tracking = geometry::TrackingAlgorithm::table_anchored;
  TrackingLoss tracking_loss;
  Viewing viewing;
  Timeline timeline;
  Stimulus stimulus;
  TableSettings table;
};

// A value as written in the protocol (TOML integers stay integers).
using SettingValue = std::variant<bool, std::int64_t, double, std::string>;

enum class SettingKind { boolean, integer, number, enumeration, number_or_from_table, integer_or_auto };

struct SettingInfo {
  std::string_view path;  // "section.key"
  SettingKind kind;
  double min = 0.0;  // inclusive range for integer and number kinds
  double max = 0.0;
  // enumeration kind; for the integer kind, the only values allowed (none:
  // any in the range)
  std::vector<std::string_view> choices;
  std::string_view meaning;  // one line, with the unit
  // The setting's value in `s` as a protocol writes it (an enumeration's
  // name, "from_table"); nullopt where it holds no value of its own:
  // viewing.preset only sets projection and eyes, and space.table_sides' 0
  // stands for the space's default.
  std::optional<SettingValue> (*get)(const Settings& s) = nullptr;
  // Writes a value into `s`; false, leaving `s` as it was, for a value
  // check_setting refuses.
  bool (*set)(Settings& s, const SettingValue& value) = nullptr;
};

// Every setting, in documentation order.
const std::vector<SettingInfo>& all_settings();
const SettingInfo* find_setting(std::string_view path);
// Keys allowed in one section ("viewing" → projection, eyes, …).
std::vector<std::string> setting_keys(std::string_view section);
bool is_setting_section(std::string_view section);

// Done when the value fits; otherwise an Error (bad_input) saying what was
// expected — a fragment the loader places and completes with what was found.
Result<Done> check_setting(const SettingInfo& info, const SettingValue& value);
// Applies a value that check_setting accepted (one it refuses is a broken
// contract: the process stops, naming the setting and the value).
void apply_setting(Settings& s, const SettingInfo& info, const SettingValue& value);
// Reads a numeric setting (for staircases and adjustment): the number kind
// only; nullopt for any other path.
std::optional<double> numeric_setting(const Settings& s, std::string_view path);
// The paths numeric_setting reads: what a staircase's or an adjustment's
// parameter may name (the loader checks it, the JSON Schema lists it).
std::vector<std::string> numeric_setting_paths();
// Writes a numeric setting (staircase/adjustment value for one trial); false
// for a path numeric_setting does not read.
bool set_numeric_setting(Settings& s, std::string_view path, double value);

// A level's label: strings as written, numbers in shortest round-trip form.
std::string value_label(const SettingValue& v);

}  // namespace curvlab::harness::protocol
