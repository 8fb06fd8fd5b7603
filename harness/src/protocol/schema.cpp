// Builds the protocol's JSON Schema. Settings come from the registry, so a
// new setting reaches the editors without touching this file; the other
// sections mirror the loader's readers (loader.cpp), and
// tests/protocol/schema_tests.cpp holds the two together key by key.
#include "curvlab/harness/protocol/schema.hpp"

#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/settings.hpp"

#include <nlohmann/json.hpp>

#include <limits>

namespace curvlab::harness::protocol {
namespace {

using Json = nlohmann::ordered_json;

constexpr const char* kIdentifierPattern = "^[a-z_][a-z0-9_-]{0,63}$";

Json strings(const std::vector<std::string>& items) {
  Json a = Json::array();
  for (const auto& s : items) a.push_back(s);
  return a;
}

Json integer(std::int64_t lo, std::int64_t hi, std::string description) {
  return {{"type", "integer"}, {"minimum", lo}, {"maximum", hi}, {"description", std::move(description)}};
}

Json with_default(Json j, Json value) {
  j["default"] = std::move(value);
  return j;
}

Json string_field(std::string description) {
  return {{"type", "string"}, {"description", std::move(description)}};
}

Json enum_field(const std::vector<std::string>& values, std::string description) {
  return {{"type", "string"}, {"enum", strings(values)}, {"description", std::move(description)}};
}

Json string_array(std::string description, const std::vector<std::string>* names = nullptr) {
  Json items = {{"type", "string"}};
  if (names) items["enum"] = strings(*names);
  return {{"type", "array"}, {"items", items}, {"description", std::move(description)}};
}

Json closed_object(Json properties, std::string description) {
  return {{"type", "object"},
          {"description", std::move(description)},
          {"properties", std::move(properties)},
          {"additionalProperties", false}};
}

// ---- settings: one schema per registry entry -------------------------------

std::string section_of(std::string_view path) { return std::string(path.substr(0, path.find('.'))); }
std::string key_of(std::string_view path) { return std::string(path.substr(path.find('.') + 1)); }

// The built-in default of a setting, read from a default-constructed
// Settings; null where the default depends on something else.
Json default_of(const SettingInfo& info) {
  const Settings s;
  const std::string_view p = info.path;
  if (p == "space.kind") return std::string(geometry::to_string(s.space.kind));
  if (p == "space.radius_m") return s.space.radius_m ? Json(*s.space.radius_m) : Json("from_table");
  if (p == "space.table_sides" || p == "viewing.preset") return nullptr;
  if (p == "tracking.algorithm") return std::string(to_string(s.tracking));
  if (p == "tracking.loss_ms") return s.tracking_loss.loss_ms;
  if (p == "tracking.on_loss") return std::string(to_string(s.tracking_loss.on_loss));
  if (p == "tracking.max_attempts") return s.tracking_loss.max_attempts;
  if (p == "viewing.projection") return std::string(to_string(s.viewing.projection));
  if (p == "viewing.eyes") return std::string(to_string(s.viewing.eyes));
  if (p == "viewing.back_hemisphere") return s.viewing.back_hemisphere;
  if (p == "viewing.msaa") return s.viewing.msaa;
  if (p == "timeline.fixation_ms") return s.timeline.fixation_ms;
  if (p == "timeline.stimulus_ms") return s.timeline.stimulus_ms;
  if (p == "timeline.response_ms") return s.timeline.response_ms;
  if (p == "timeline.iti_ms") return s.timeline.iti_ms;
  if (p == "timeline.stimulus_during_response") return s.timeline.stimulus_during_response;
  if (p == "stimulus.stick_anchor") return std::string(to_string(s.stimulus.stick_anchor));
  if (p == "stimulus.stick_marks") return std::string(to_string(s.stimulus.stick_marks));
  if (p == "stimulus.show_stick") return s.stimulus.show_stick;
  if (p == "stimulus.show_table") return s.stimulus.show_table;
  if (p == "stimulus.balls") return s.stimulus.balls;
  if (const auto v = numeric_setting(s, p)) return *v;
  return nullptr;
}

// What one value of the setting may be: the same rule check_setting applies.
Json value_schema(const SettingInfo& info) {
  switch (info.kind) {
    case SettingKind::boolean: return {{"type", "boolean"}};
    case SettingKind::integer: {
      Json j = {{"type", "integer"},
                {"minimum", static_cast<std::int64_t>(info.min)},
                {"maximum", static_cast<std::int64_t>(info.max)}};
      if (!info.choices.empty()) {
        Json values = Json::array();
        for (auto c : info.choices) values.push_back(std::stoll(std::string(c)));
        j["enum"] = values;
      }
      return j;
    }
    case SettingKind::number: return {{"type", "number"}, {"minimum", info.min}, {"maximum", info.max}};
    case SettingKind::number_or_from_table:
      return {{"anyOf", Json::array({Json{{"type", "number"}, {"minimum", info.min}, {"maximum", info.max}},
                                     Json{{"const", "from_table"}}})}};
    case SettingKind::enumeration: {
      Json values = Json::array();
      for (auto c : info.choices) values.push_back(std::string(c));
      return {{"type", "string"}, {"enum", values}};
    }
  }
  return Json::object();
}

Json setting_schema(const SettingInfo& info) {
  Json j = value_schema(info);
  j["description"] = std::string(info.meaning);
  if (Json d = default_of(info); !d.is_null()) j["default"] = d;
  return j;
}

Json settings_section(const std::string& section, const std::string& description) {
  Json props = Json::object();
  for (const auto& info : all_settings())
    if (section_of(info.path) == section) props[key_of(info.path)] = setting_schema(info);
  Json j = closed_object(props, description);
  if (section == "viewing")  // the loader's rule: a preset sets projection and eyes itself
    j["not"] = {{"anyOf", Json::array({Json{{"required", Json::array({"preset", "projection"})}},
                                       Json{{"required", Json::array({"preset", "eyes"})}}})}};
  return j;
}

const std::vector<std::pair<std::string, std::string>>& settings_sections() {
  static const std::vector<std::pair<std::string, std::string>> sections = {
      {"space", "the space: S3, E3 or H3, its radius and the virtual table"},
      {"tracking", "body-coherent tracking (paper, sections 4–5) and what tracking loss does"},
      {"viewing", "projection and eyes (or a preset that sets both), back hemisphere, IPD"},
      {"timeline", "per-trial timeline in milliseconds: fixation → stimulus → response → ITI"},
      {"stimulus", "cue stick, table and balls"},
      {"table", "the physical table in the lab"},
  };
  return sections;
}

void add_settings_sections(Json& props, const std::string& where) {
  for (const auto& [name, description] : settings_sections())
    props[name] = settings_section(name, description + " (" + where + ")");
}

// ---- factors ----------------------------------------------------------------

Json factor_schema() {
  Json paths = Json::array();
  for (const auto& info : all_settings()) paths.push_back(std::string(info.path));
  Json props = {
      {"sets", {{"type", "string"},
                {"enum", paths},
                {"description", "the setting this factor varies; without it the factor only labels trials "
                                "(its levels are strings)"}}},
      {"levels", {{"type", "array"},
                  {"minItems", 1},
                  {"uniqueItems", true},
                  {"items", {{"type", Json::array({"string", "number", "boolean"})}}},
                  {"description", "the levels, each checked as if written in the setting's section"}}},
      {"description", string_field("free text")},
  };
  Json j = closed_object(props, "a factor: the setting it varies and its levels");
  j["required"] = Json::array({"levels"});
  // Each `sets` value constrains the levels to that setting's values.
  Json all = Json::array();
  for (const auto& info : all_settings())
    all.push_back({{"if", {{"properties", {{"sets", {{"const", std::string(info.path)}}}}}, {"required", Json::array({"sets"})}}},
                   {"then", {{"properties", {{"levels", {{"items", value_schema(info)}}}}}}}});
  all.push_back({{"if", {{"not", {{"required", Json::array({"sets"})}}}}},
                 {"then", {{"properties", {{"levels", {{"items", {{"type", "string"}}}}}}}}}});
  j["allOf"] = all;
  return j;
}

// ---- judgements -------------------------------------------------------------

Json option_schema() {
  Json props = {
      {"value", {{"type", "string"}, {"pattern", kIdentifierPattern},
                 {"description", "stored in the data; a lower-case identifier, unique"}}},
      {"label", string_field("shown on the panel (default: the value)")},
      {"keys", string_array("keyboard keys that give this answer", &response_key_names())},
      {"buttons", string_array("controller or HID buttons that give this answer", &response_button_names())},
  };
  Json j = closed_object(props, "one answer");
  j["required"] = Json::array({"value"});
  j["anyOf"] = Json::array({Json{{"required", Json::array({"keys"})}}, Json{{"required", Json::array({"buttons"})}}});
  return j;
}

Json staircase_schema() {
  Json props = {
      {"name", string_field("unique within the judgement")},
      {"start", {{"type", "number"}, {"description", "the first value; min ≤ start ≤ max"}}},
      {"up", with_default(integer(1, 5, "consecutive negative responses before the value goes up"), 1)},
      {"down", with_default(integer(1, 5, "consecutive positive responses before the value goes down"), 2)},
      {"step_sizes", {{"type", "array"},
                      {"minItems", 1},
                      {"items", {{"type", "number"}, {"exclusiveMinimum", 0}}},
                      {"description", "step k is used after k reversals; the last repeats"}}},
      {"stop_reversals", with_default(integer(1, 100, "stop after this many reversals"), 8)},
      {"max_trials", with_default(integer(1, 1000, "or after this many trials, whichever comes first"), 50)},
      {"discard_reversals",
       with_default(integer(0, 99, "reversals left out of the threshold estimate (< stop_reversals)"), 2)},
      {"min", {{"type", "number"}, {"description", "the value is clamped to [min, max]"}}},
      {"max", {{"type", "number"}, {"description", "the value is clamped to [min, max]"}}},
  };
  Json j = closed_object(props, "one n-up/m-down staircase (Levitt 1971)");
  j["required"] = Json::array({"name", "start", "step_sizes", "min", "max"});
  return j;
}

Json judgement_schema() {
  const auto& keys = response_key_names();
  const auto& buttons = response_button_names();
  Json props = {
      {"type", enum_field({"choice", "adjustment", "staircase"},
                          "n-alternative choice, method of adjustment, or interleaved staircases")},
      {"prompt", string_field("shown on the in-headset panel")},
      {"options", {{"type", "array"}, {"minItems", 2}, {"items", option_schema()},
                   {"description", "choice and staircase: one table per answer"}}},
      {"parameter", {{"type", "string"}, {"enum", strings(numeric_setting_paths())},
                     {"description", "adjustment and staircase: the numeric setting that is varied; "
                                     "not one a factor varies"}}},
      {"positive", string_field("staircase: the option value that counts as a positive response")},
      {"staircases", {{"type", "array"}, {"minItems", 1}, {"items", staircase_schema()},
                      {"description", "staircase: interleaved staircases for every cell"}}},
      {"start_min", {{"type", "number"}, {"description", "adjustment: start values are drawn from "
                                                         "[start_min, start_max]; min ≤ start_min"}}},
      {"start_max", {{"type", "number"}, {"description", "adjustment: start_min ≤ start_max ≤ max"}}},
      {"step", {{"type", "number"}, {"exclusiveMinimum", 0},
                {"description", "adjustment: one press; step ≤ max − min"}}},
      {"fine_step", {{"type", "number"}, {"exclusiveMinimum", 0},
                     {"description", "adjustment: a finer step (≤ step)"}}},
      {"min", {{"type", "number"}, {"description", "adjustment: the adjustable range, inside the "
                                                   "setting's own range, min < max"}}},
      {"max", {{"type", "number"}, {"description", "adjustment: the adjustable range's upper end"}}},
      {"keys_decrease", with_default(string_array("adjustment: keys that decrease the value", &keys),
                                     Json::array({"left"}))},
      {"keys_increase", with_default(string_array("adjustment: keys that increase the value", &keys),
                                     Json::array({"right"}))},
      {"keys_confirm", with_default(string_array("adjustment: keys that confirm the value", &keys),
                                    Json::array({"space"}))},
      {"buttons_decrease", string_array("adjustment: buttons that decrease the value", &buttons)},
      {"buttons_increase", string_array("adjustment: buttons that increase the value", &buttons)},
      {"buttons_confirm", string_array("adjustment: buttons that confirm the value", &buttons)},
  };
  Json j = closed_object(props, "what the participant answers");
  j["required"] = Json::array({"type"});
  const auto only = [](const char* type, std::vector<std::string> allowed, std::vector<std::string> required) {
    return Json{{"if", {{"properties", {{"type", {{"const", type}}}}}, {"required", Json::array({"type"})}}},
                {"then", {{"propertyNames", {{"enum", strings(allowed)}}}, {"required", strings(required)}}}};
  };
  j["allOf"] = Json::array({
      only("choice", {"type", "prompt", "options"}, {"options"}),
      only("adjustment",
           {"type", "prompt", "parameter", "start_min", "start_max", "step", "fine_step", "min", "max",
            "keys_decrease", "keys_increase", "keys_confirm", "buttons_decrease", "buttons_increase",
            "buttons_confirm"},
           {"parameter", "min", "max", "start_min", "start_max", "step"}),
      only("staircase", {"type", "prompt", "options", "parameter", "positive", "staircases"},
           {"parameter", "options", "positive", "staircases"}),
  });
  return j;
}

// ---- blocks and the top level -----------------------------------------------

const std::vector<std::string> kRandomize = {"none", "shuffle", "shuffle_within_repetition"};

Json break_fields(Json props) {
  props["break_every_trials"] = integer(0, 100000, "a break before every k-th trial of a block (0: none)");
  props["break_text"] = string_field("panel text during a break");
  props["break_min_ms"] = integer(0, 3600000, "minimum break length in milliseconds");
  return props;
}

Json block_schema() {
  Json props = {
      {"name", {{"type", "string"}, {"pattern", kIdentifierPattern},
                {"description", "unique; a lower-case identifier"}}},
      {"practice", with_default(Json{{"type", "boolean"},
                                     {"description", "practice blocks run first, in file order, and are "
                                                     "not counterbalanced"}},
                                false)},
      {"repetitions", integer(1, 1000, "repetitions of every factor-level combination (default: [session])")},
      {"randomize", enum_field(kRandomize, "trial order in this block (default: [randomization] trials)")},
      {"levels", {{"type", "object"},
                  {"description", "restricts factors to some of their levels in this block: "
                                  "factor name → a level or an array of levels"},
                  {"propertyNames", {{"pattern", kIdentifierPattern}}},
                  {"additionalProperties",
                   {{"anyOf", Json::array({Json{{"type", Json::array({"string", "number", "boolean"})}},
                                           Json{{"type", "array"}, {"minItems", 1}}})}}}}},
      {"instructions", string_array("instruction pages shown before the block")},
  };
  props = break_fields(props);
  add_settings_sections(props, "this block; overrides the top-level section");
  props["judgement"] = judgement_schema();
  props["judgement"]["description"] = "this block's judgement; replaces the top-level [judgement]";
  Json j = closed_object(props, "a block of trials");
  j["required"] = Json::array({"name"});
  return j;
}

Json root_schema() {
  Json props = Json::object();
  Json meta = closed_object({{"name", {{"type", "string"}, {"minLength", 1},
                                        {"description", "non-empty; stored with each session"}}},
                             {"version", string_field("the protocol's own version, e.g. \"1.2.0\"")},
                             {"description", string_field("free text")}},
                            "metadata");
  meta["required"] = Json::array({"name", "version"});
  props["protocol"] = meta;
  add_settings_sections(props, "session level; blocks inherit it");
  props["backend"] = closed_object(
      {{"preferred", with_default(enum_field({"headless", "desktop", "xr"}, "the backend this protocol expects"),
                                  "headless")},
       {"refresh_hz", with_default(integer(30, 240, "display refresh rate in Hz"), 90)},
       {"resolution", {{"type", "array"},
                       {"minItems", 2},
                       {"maxItems", 2},
                       {"items", {{"type", "integer"}, {"minimum", 16}, {"maximum", 8192}}},
                       {"description", "[width, height] in pixels"}}}},
      "the backend and display");
  Json randomization = closed_object(
      {{"seed", integer(0, std::numeric_limits<std::int64_t>::max(),
                        "the protocol's seed: every order is reproducible from it")},
       {"trials", with_default(enum_field(kRandomize, "default trial order in every block"), "shuffle")},
       {"per_participant",
        with_default(Json{{"type", "boolean"}, {"description", "mix the participant number into the seed"}},
                     true)}},
      "seeded randomization");
  randomization["required"] = Json::array({"seed"});
  props["randomization"] = randomization;
  props["counterbalance"] = closed_object(
      {{"blocks", with_default(enum_field({"fixed", "latin_square", "random"},
                                          "order of the non-practice blocks across participants"),
                               "fixed")},
       {"square", {{"type", "array"},
                   {"minItems", 1},
                   {"items", {{"type", "array"}, {"items", {{"type", "string"}}}}},
                   {"description", "explicit Latin square of block names (default: a Williams design)"}}}},
      "block order across participants");
  props["session"] = closed_object(
      break_fields({{"repetitions", with_default(integer(1, 1000, "repetitions of every factor-level "
                                                                  "combination"),
                                                 1)}}),
      "defaults for every block");
  props["factors"] = {{"type", "object"},
                      {"description", "factor name (a lower-case identifier) → what it varies and its levels; "
                                      "factors are crossed in name order"},
                      {"propertyNames", {{"pattern", kIdentifierPattern}}},
                      {"additionalProperties", factor_schema()}};
  props["judgement"] = judgement_schema();
  props["instructions"] = closed_object({{"start", string_array("pages shown before the first block")},
                                         {"end", string_array("pages shown after the last block")}},
                                        "instruction pages");
  props["blocks"] = {{"type", "array"}, {"minItems", 1}, {"items", block_schema()},
                     {"description", "blocks of trials; without any, one block \"main\" crosses all factors"}};
  Json root = {{"$schema", "http://json-schema.org/draft-07/schema#"},
               {"title", "curvlab protocol"},
               {"description", "A curvlab experiment protocol (docs/protocols.md). Generated by `curvlab schema`; "
                               "`curvlab validate` also checks the rules across fields."},
               {"type", "object"},
               {"properties", props},
               {"additionalProperties", false},
               {"required", Json::array({"protocol", "randomization"})}};
  return root;
}

}  // namespace

std::string protocol_json_schema() { return root_schema().dump(2) + "\n"; }

}  // namespace curvlab::harness::protocol
