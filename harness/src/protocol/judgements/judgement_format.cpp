#include "judgement_format.hpp"

#include <algorithm>
#include <numeric>
#include <set>

namespace curvlab::harness::protocol {

namespace tr = toml_reader;
using tr::type_name;

std::vector<ResponseOption> JudgementSection::options() {
  std::vector<ResponseOption> out;
  const toml::node* n = table.get("options");
  if (!n) {
    reader.error(pos_of(table), prefix + ".options",
                 "missing required array of options ([[" + prefix + ".options]] tables)");
    return out;
  }
  const auto* arr = n->as_array();
  if (!arr) {
    reader.error(pos_of(*n), prefix + ".options", "expected an array of tables, found " + type_name(*n));
    return out;
  }
  std::set<std::string> values, bound;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::node& e = (*arr)[i];
    const std::string op = prefix + ".options[" + std::to_string(i + 1) + "]";
    const auto* t = e.as_table();
    if (!t) {
      reader.error(pos_of(e), op, "expected a table with value, label, keys and buttons, found " + type_name(e));
      continue;
    }
    reader.check_keys(*t, op, {"value", "label", "keys", "buttons"});
    ResponseOption o;
    o.value = reader.get_string(*t, "value", op, true).value_or("");
    if (t->contains("value") && t->get("value")->is_string() && !is_identifier(o.value))
      reader.error(pos_of(*t->get("value")), op + ".value", "expected a lower-case identifier (stored in the data)");
    o.label = reader.get_string(*t, "label", op, false).value_or(o.value);
    o.keys = reader.get_string_array(*t, "keys", op, &key_names());
    o.buttons = reader.get_string_array(*t, "buttons", op, &button_names());
    if (!t->contains("keys") && !t->contains("buttons"))
      reader.error(pos_of(*t), op, "expected at least one of keys or buttons to answer with");
    if (!o.value.empty() && !values.insert(o.value).second)
      reader.error(pos_of(*t), op + ".value", "duplicate option value \"" + o.value + "\"");
    for (const auto& key : o.keys)
      if (!bound.insert("key:" + key).second)
        reader.error(pos_of(*t->get("keys")), op + ".keys", "key \"" + key + "\" is bound to two options");
    for (const auto& b : o.buttons)
      if (!bound.insert("button:" + b).second)
        reader.error(pos_of(*t->get("buttons")), op + ".buttons", "button \"" + b + "\" is bound to two options");
    out.push_back(std::move(o));
  }
  if (arr->size() < 2)
    reader.error(pos_of(*n), prefix + ".options", "expected at least 2 options, found " + std::to_string(arr->size()));
  return out;
}

std::string JudgementSection::parameter() {
  const auto param = reader.get_string(table, "parameter", prefix, true);
  if (!param) return "";
  const SourcePos at = pos_of(*table.get("parameter"));
  const auto paths = numeric_setting_paths();
  if (std::find(paths.begin(), paths.end(), *param) == paths.end()) {
    std::string msg = "unknown parameter \"" + *param + "\"";
    const std::string guess = closest_match(*param, paths);
    if (!guess.empty()) msg += "; did you mean \"" + guess + "\"?";
    if (protocol.find_factor(*param)) msg += " (\"" + *param + "\" is a factor, not a numeric setting)";
    msg += " Expected a numeric setting: " + quoted_list(paths);
    reader.error(at, prefix + ".parameter", msg);
    return "";
  }
  for (const auto& f : protocol.factors)
    if (f.sets == *param)
      reader.error(at, prefix + ".parameter", "\"" + *param + "\" is also varied by factor \"" + f.name +
                                                  "\"; a trial's value cannot come from both");
  return *param;
}

bool check_range(TableReader& reader, const std::string& param, double lo, double hi, const toml::table& at,
                 const std::string& field) {
  const std::string got = ", got min = " + number_label(lo) + ", max = " + number_label(hi);
  if (!(lo < hi)) {
    reader.error(pos_of(at), field, "expected min < max" + got);
    return false;
  }
  const SettingInfo* info = param.empty() ? nullptr : find_setting(param);
  if (info && (lo < info->min || hi > info->max)) {
    reader.error(pos_of(at), field,
                 "expected " + number_label(info->min) + " ≤ min < max ≤ " + number_label(info->max) + " (" +
                     param + "'s range)" + got);
    return false;
  }
  return true;
}

namespace {

using schema_json::Json;

Json option_schema() {
  using namespace schema_json;
  Json props = {
      {"value", {{"type", "string"}, {"pattern", kIdentifierPattern},
                 {"description", "stored in the data; a lower-case identifier, unique"}}},
      {"label", string_field("shown on the panel (default: the value)")},
      {"keys", string_array("keyboard keys that give this answer", &key_names())},
      {"buttons", string_array("controller or HID buttons that give this answer", &button_names())},
  };
  Json j = closed_object(props, "one answer");
  j["required"] = Json::array({"value"});
  j["anyOf"] = Json::array({Json{{"required", Json::array({"keys"})}}, Json{{"required", Json::array({"buttons"})}}});
  return j;
}

}  // namespace

void JudgementFields::add_options() {
  add("options", {{"type", "array"}, {"minItems", 2}, {"items", option_schema()},
                  {"description", "one table per answer"}});
}

void JudgementFields::add_parameter() {
  add("parameter", {{"type", "string"}, {"enum", schema_json::strings(numeric_setting_paths())},
                    {"description", "the numeric setting that is varied; not one a factor varies"}});
}

JudgementFields fields_of(const JudgementType& type) {
  JudgementFields f;
  type.fields(f);
  return f;
}

std::vector<std::string> table_keys(const JudgementType& type) {
  std::vector<std::string> keys{"type", "prompt", "feedback"};
  const JudgementFields fields = fields_of(type);
  for (const auto& [key, schema] : fields.keys()) keys.push_back(key);
  return keys;
}

std::vector<TypeKey> type_keys() {
  const auto& registered = judgement_types();
  std::vector<JudgementFields> fields;
  for (const JudgementType* t : registered) fields.push_back(fields_of(*t));
  std::vector<std::size_t> order(registered.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return fields[a].keys().size() < fields[b].keys().size(); });
  std::vector<TypeKey> out;
  const auto find = [&](const std::string& key) {
    return std::find_if(out.begin(), out.end(), [&](const TypeKey& k) { return k.key == key; });
  };
  for (const std::size_t i : order)
    for (const auto& field : fields[i].keys())
      if (find(field.first) == out.end()) out.push_back({field.first, field.second, {}});
  // The types that take each key, in registration order.
  for (std::size_t i = 0; i < registered.size(); ++i)
    for (const auto& field : fields[i].keys()) find(field.first)->types.push_back(registered[i]);
  return out;
}

std::vector<std::string> any_table_keys() {
  std::vector<std::string> keys{"type", "prompt", "feedback"};
  for (const auto& k : type_keys()) keys.push_back(k.key);
  return keys;
}

}  // namespace curvlab::harness::protocol
