#include "curvlab/harness/protocol/settings_json.hpp"

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string_view>
#include <vector>

namespace curvlab::harness::protocol {
namespace {

using Json = nlohmann::ordered_json;

// One key of a record: the values of the settings it names (one: that
// value; several: an array of theirs), or a value derive() computed.
struct RecordKey {
  std::string_view name;
  std::vector<std::string_view> paths;
  Json (*derived)(const Derived&) = nullptr;
};

// A setting under its key's name ("stimulus.stick_length_m" → stick_length_m)
// or under another name.
RecordKey setting(std::string_view path) { return {path.substr(path.find('.') + 1), {path}}; }
RecordKey setting(std::string_view path, std::string_view name) { return {name, {path}}; }

// The resolved space: ρ and the virtual table (space.radius_m may be
// "from_table" and space.table_sides 0 for the space's default).
const RecordKey kRadius{"radius_m", {}, [](const Derived& d) { return Json(d.radius_m); }};
const RecordKey kTableSides{"table_sides", {}, [](const Derived& d) { return Json(d.table_sides); }};
const RecordKey kSideRad{"table_side_rad", {}, [](const Derived& d) { return Json(d.side_rad); }};

const std::vector<RecordKey>& stimulus_record() {
  static const std::vector<RecordKey> keys = {
      setting("stimulus.stick_sagitta_m"),  setting("stimulus.table_sagitta_m"),
      setting("stimulus.stick_length_m"),   setting("stimulus.stick_distance_m"),
      setting("stimulus.stick_height_m"),   setting("stimulus.stick_anchor"),
      setting("stimulus.stick_marks"),      setting("stimulus.show_stick"),
      setting("stimulus.show_table"),       kRadius,
      kTableSides,                          setting("tracking.algorithm", "tracking"),
      setting("viewing.ipd_m"),
  };
  return keys;
}

const std::vector<RecordKey>& condition_record() {
  static const std::vector<RecordKey> keys = {
      setting("space.kind", "space"),
      kRadius,
      kTableSides,
      kSideRad,
      setting("tracking.algorithm", "tracking"),
      setting("viewing.projection"),
      setting("viewing.eyes"),
      setting("viewing.back_hemisphere"),
      setting("viewing.ipd_m"),
      {"timeline_ms", {"timeline.fixation_ms", "timeline.stimulus_ms", "timeline.response_ms", "timeline.iti_ms"}},
      setting("stimulus.stick_length_m"),
      setting("stimulus.stick_sagitta_m"),
      setting("stimulus.stick_anchor"),
      setting("stimulus.stick_marks"),
      setting("stimulus.stick_distance_m"),
      setting("stimulus.table_sagitta_m"),
      setting("table.edge_m", "table_edge_m"),
      setting("stimulus.stick_radius_m"),
      setting("stimulus.stick_height_m"),
      setting("stimulus.stick_yaw_deg"),
      setting("stimulus.show_stick"),
      setting("stimulus.show_table"),
      setting("stimulus.balls"),
      setting("stimulus.ball_radius_m"),
      setting("table.height_m", "table_height_m"),
      setting("timeline.stimulus_during_response"),
  };
  return keys;
}

// A record names only settings that hold a value of their own; anything
// else is a broken contract in the layouts above.
Json value_of(const Settings& s, std::string_view path) {
  const SettingInfo* info = find_setting(path);
  const auto value = info ? info->get(s) : std::nullopt;
  if (!value) {
    std::fprintf(stderr, "curvlab: a settings record names %s, which is no setting with a value\n",
                 std::string(path).c_str());
    std::abort();
  }
  return std::visit([](const auto& v) { return Json(v); }, *value);
}

// The name a record gives the setting at `path`, when it holds it alone
// under one key.
std::optional<std::string_view> name_in(const std::vector<RecordKey>& record, std::string_view path) {
  for (const RecordKey& key : record)
    if (!key.derived && key.paths.size() == 1 && key.paths.front() == path) return key.name;
  return std::nullopt;
}

}  // namespace

std::string stimulus_key(std::string_view path) {
  if (const auto name = name_in(stimulus_record(), path)) return std::string(*name);
  if (const auto name = name_in(condition_record(), path)) return std::string(*name);
  return std::string(path.substr(path.find('.') + 1));
}

Json settings_json(const Settings& s, const Derived& d, SettingsRecord record) {
  Json j = Json::object();
  for (const RecordKey& key : record == SettingsRecord::stimulus ? stimulus_record() : condition_record()) {
    Json& out = j[std::string(key.name)];
    if (key.derived) {
      out = key.derived(d);
    } else if (key.paths.size() == 1) {
      out = value_of(s, key.paths.front());
    } else {
      out = Json::array();
      for (const auto path : key.paths) out.push_back(value_of(s, path));
    }
  }
  return j;
}

}  // namespace curvlab::harness::protocol
