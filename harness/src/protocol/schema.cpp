// Builds the protocol's JSON Schema. Settings come from the registry and
// judgements from their types, so a new setting or judgement type reaches the
// editors without touching this file; the other sections mirror the loader's
// readers (loader.cpp), and
// tests/protocol/schema_tests.cpp holds the two together key by key.
#include "curvlab/harness/protocol/schema.hpp"

#include "curvlab/geometry/billiards.hpp"

#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/settings.hpp"
#include "judgements/judgement_format.hpp"
#include "schema_json.hpp"

#include <limits>

namespace curvlab::harness::protocol {
namespace {

using namespace schema_json;

// ---- settings: one schema per registry entry -------------------------------

std::string section_of(std::string_view path) { return std::string(path.substr(0, path.find('.'))); }
std::string key_of(std::string_view path) { return std::string(path.substr(path.find('.') + 1)); }

// The built-in default of a setting, read from a default-constructed
// Settings; null where the default depends on something else.
Json default_of(const SettingInfo& info) {
  const auto value = info.get(Settings{});
  if (!value) return nullptr;
  return std::visit([](const auto& v) { return Json(v); }, *value);
}

// An integer in the setting's range, one of its choices when it lists any.
Json integer_schema(const SettingInfo& info) {
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

// What one value of the setting may be: the same rule check_setting applies.
Json value_schema(const SettingInfo& info) {
  switch (info.kind) {
    case SettingKind::boolean: return {{"type", "boolean"}};
    case SettingKind::integer: return integer_schema(info);
    case SettingKind::integer_or_auto:
      return {{"anyOf", Json::array({integer_schema(info), Json{{"const", "auto"}}})}};
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

// "a, b, or c" (the types' summaries).
std::string summaries() {
  const auto& types = judgement_types();
  std::string out;
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (i > 0) out += i + 1 == types.size() ? (types.size() > 2 ? ", or " : " or ") : ", ";
    out += types[i]->summary();
  }
  return out;
}

// "choice and staircase: " for a key two types take.
std::string taken_by(const std::vector<const JudgementType*>& types) {
  std::string out;
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (i > 0) out += i + 1 == types.size() ? " and " : ", ";
    out += types[i]->name();
  }
  return out + ": ";
}

// The keys every type takes, then each type's own (judgements/), and for
// each type the keys it allows and requires.
Json judgement_schema() {
  std::vector<std::string> names;
  for (const JudgementType* t : judgement_types()) names.emplace_back(t->name());
  Json props = {
      {"type", enum_field(names, summaries())},
      {"prompt", string_field("shown on the in-headset panel")},
      {"feedback", with_default(Json{{"type", "boolean"},
                                     {"description", "after each answer, show the answer given (its label), or "
                                                     "\"No answer\" after a timeout, through the inter-trial interval"}},
                                false)},
  };
  for (auto& k : type_keys()) {
    k.schema["description"] = taken_by(k.types) + k.schema["description"].get<std::string>();
    props[k.key] = std::move(k.schema);
  }
  Json j = closed_object(props, "what the participant answers");
  j["required"] = Json::array({"type"});
  Json only = Json::array();
  for (const JudgementType* t : judgement_types())
    only.push_back({{"if", {{"properties", {{"type", {{"const", std::string(t->name())}}}}},
                            {"required", Json::array({"type"})}}},
                    {"then", {{"propertyNames", {{"enum", strings(table_keys(*t))}}},
                              {"required", strings(fields_of(*t).required())}}}});
  j["allOf"] = only;
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

// A play block's physics parameters by name (geometry/billiards.hpp).
Json play_physics_schema() {
  Json props = Json::object();
  for (const auto& info : geometry::billiards::parameter_table())
    props[std::string(info.name)] = {{"type", "number"},
                                     {"minimum", info.min},
                                     {"maximum", info.max},
                                     {"description", std::string(info.meaning)}};
  return closed_object(props, "play blocks: billiards physics parameters by name (docs/billiards.md)");
}

Json block_schema() {
  Json props = {
      {"name", {{"type", "string"}, {"pattern", kIdentifierPattern},
                {"description", "unique; a lower-case identifier"}}},
      {"kind", with_default(enum_field(block_kind_names(), "what the block's frames show: trials (judged "
                                                           "trials), play (curved-space billiards) or "
                                                           "questionnaire (an instrument's items)"),
                            block_kind_names().front())},
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
      {"duration_s", {{"type", "number"}, {"exclusiveMinimum", 0}, {"maximum", 86400}, {"default", 300},
                      {"description", "play blocks: seconds of play"}}},
      {"shots", integer(0, 100000, "play blocks: the most shots (0: no limit)")},
      {"until", with_default(enum_field({"all_pocketed", "time"},
                                        "play blocks: all_pocketed ends play when the last object ball is "
                                        "pocketed; time plays on for duration_s"),
                             "all_pocketed")},
      {"rack", integer(0, 15, "play blocks: object balls in the rack (default 15)")},
      {"physics", play_physics_schema()},
      {"instrument", {{"type", "string"},
                      {"pattern", kIdentifierPattern},
                      {"description", "questionnaire blocks: \"ssq\" (the built-in Simulator Sickness "
                                      "Questionnaire) or the name of an [instruments.<name>] table "
                                      "(docs/questionnaires.md)"}}},
  };
  props = break_fields(props);
  add_settings_sections(props, "this block; overrides the top-level section");
  props["judgement"] = judgement_schema();
  props["judgement"]["description"] = "this block's judgement; replaces the top-level [judgement]";
  Json j = closed_object(props, "a block of trials");
  j["required"] = Json::array({"name"});
  return j;
}

// [instruments.<name>]: a questionnaire the protocol defines
// (loader_questionnaires.cpp).
Json instrument_schema() {
  Json scale = closed_object(
      {{"values", {{"type", "array"},
                   {"minItems", 2},
                   {"maxItems", 9},
                   {"uniqueItems", true},
                   {"items", {{"type", "integer"}, {"minimum", -1000}, {"maximum", 1000}}},
                   {"description", "the scale's values in the order shown, e.g. [1, 2, 3, 4, 5, 6, 7] or "
                                   "[-3, -2, -1, 0, 1, 2, 3]"}}},
       {"labels", string_array("one label per value (\"\" leaves a point unlabelled)")}},
      "the response scale every item is answered on");
  scale["required"] = Json::array({"values", "labels"});
  Json item = closed_object({{"id", {{"type", "string"}, {"pattern", kIdentifierPattern},
                                     {"description", "unique in the instrument; a lower-case identifier"}}},
                             {"text", {{"type", "string"}, {"minLength", 1},
                                       {"description", "the item as shown to the participant"}}},
                             {"reversed", with_default(Json{{"type", "boolean"},
                                                            {"description", "scored mirrored on the scale "
                                                                            "(lowest + highest − value)"}},
                                                       false)}},
                            "one item");
  item["required"] = Json::array({"id", "text"});
  Json subscale = closed_object(
      {{"name", {{"type", "string"}, {"pattern", kIdentifierPattern}, {"description", "unique in the instrument"}}},
       {"items", {{"type", "array"},
                  {"minItems", 1},
                  {"items", {{"type", "string"}}},
                  {"description", "ids of the items it counts (an id listed twice counts twice)"}}},
       {"score", with_default(enum_field({"sum", "mean"}, "how its items' values combine"), "sum")},
       {"weight", with_default(Json{{"type", "number"},
                                    {"exclusiveMinimum", 0},
                                    {"maximum", 1e6},
                                    {"description", "the sum or mean is multiplied by this"}},
                               1.0)}},
      "a subscale: weight × (sum or mean of its items)");
  subscale["required"] = Json::array({"name", "items"});
  Json j = closed_object(
      {{"title", string_field("shown above each item")},
       {"scale", scale},
       {"items", {{"type", "array"}, {"minItems", 1}, {"maxItems", 500}, {"items", item},
                  {"description", "the items, in the order asked"}}},
       {"subscales", {{"type", "array"}, {"items", subscale},
                      {"description", "scores stored and exported when the block ends"}}}},
      "a questionnaire (docs/questionnaires.md)");
  j["required"] = Json::array({"scale", "items"});
  return j;
}

// [calibration]: the physical table's calibration as a session step (loader.cpp, read_calibration).
Json calibration_schema() {
  return closed_object(
      {{"at_start", with_default(Json{{"type", "boolean"},
                                      {"description", "calibrate the physical table by touching its corners "
                                                      "before the session (desktop and xr runs)"}},
                                 false)},
       {"tip_offset_m", {{"type", "array"},
                         {"minItems", 3},
                         {"maxItems", 3},
                         {"items", {{"type", "number"}, {"minimum", -0.5}, {"maximum", 0.5}}},
                         {"default", Json::array({0.0, 0.0, 0.0})},
                         {"description", "[x, y, z]: the touching tip in the right controller's grip frame, "
                                         "metres"}}},
       {"max_residual_mm", with_default(Json{{"type", "number"},
                                             {"minimum", 1},
                                             {"maximum", 100},
                                             {"description", "a touch farther than this from its fitted corner "
                                                             "is refused (millimetres)"}},
                                        15.0)}},
      "the physical table's calibration as a session step (docs/devices.md)");
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
  props["calibration"] = calibration_schema();
  props["responses"] = closed_object(
      {{"hid", {{"type", "array"},
                {"items", {{"type", "string"}, {"minLength", 1}}},
                {"description", "HID mapping files (relative to this file) whose devices answer in desktop and "
                                "xr runs, beside the keyboard or controllers (docs/devices.md)"}}}},
      "response devices besides the backend's own");
  props["lsl"] = closed_object(
      {{"outlets", with_default(Json{{"type", "boolean"},
                                     {"description", "stream markers, poses and gaze to the Lab Streaming Layer "
                                                     "during the session, as run --lsl does (docs/lsl.md)"}},
                                false)}},
      "Lab Streaming Layer outlets");
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
  props["instruments"] = {{"type", "object"},
                          {"description", "questionnaires for questionnaire blocks: name (a lower-case identifier, "
                                          "not \"ssq\") → its scale, items and subscales"},
                          {"propertyNames", {{"pattern", kIdentifierPattern}}},
                          {"additionalProperties", instrument_schema()}};
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
