// Questionnaires in the protocol file (docs/questionnaires.md): the
// [instruments.<name>] tables a protocol defines, and the instrument a
// questionnaire block names — the built-in "ssq" or one of those.
#include "loader_impl.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace curvlab::harness::protocol {
namespace {

namespace tr = toml_reader;
using tr::type_name;

constexpr std::size_t kMaxScalePoints = 9;  // one digit key each
constexpr std::size_t kMaxItems = 500;

}  // namespace

void Loader::read_instruments(const toml::table& root, Protocol& p) {
  const toml::table* all = sub_table(root, "instruments", "");
  if (!all) return;
  for (auto&& [k, v] : *all) {
    Instrument ins;
    ins.name = std::string(k.str());
    ins.pos = pos_of(k.source());
    const std::string prefix = "instruments." + ins.name;
    if (!is_identifier(ins.name))
      error(ins.pos, prefix, "instrument names are lower-case identifiers (a-z, 0-9, _ and -)");
    else if (ins.name == kSsqName)
      error(ins.pos, prefix, "\"ssq\" is the built-in Simulator Sickness Questionnaire: give this instrument "
                             "another name, or remove it and use instrument = \"ssq\"");
    const auto* t = v.as_table();
    if (!t) {
      error(pos_of(v), prefix, "expected a table with title, scale, items and subscales, found " + type_name(v));
      continue;
    }
    check_keys(*t, prefix, {"title", "scale", "items", "subscales"});
    ins.title = get_string(*t, "title", prefix, false).value_or("");
    read_scale(*t, prefix, ins);
    read_items(*t, prefix, ins);
    read_subscales(*t, prefix, ins);
    p.instruments.push_back(std::move(ins));
  }
}

void Loader::read_scale(const toml::table& t, const std::string& prefix, Instrument& ins) {
  const std::string sp = prefix + ".scale";
  const toml::table* s = sub_table(t, "scale", prefix);
  if (!s) {
    if (!t.contains("scale"))
      error(pos_of(t), sp, "missing required table scale: values = [1, 2, 3, 4, 5] and labels = [\"…\", …]");
    return;
  }
  check_keys(*s, sp, {"values", "labels"});
  const toml::node* vn = s->get("values");
  const auto* values = vn ? vn->as_array() : nullptr;
  if (!values || values->size() < 2 || values->size() > kMaxScalePoints) {
    error(vn ? pos_of(*vn) : pos_of(*s), sp + ".values",
          "expected an array of 2 to " + std::to_string(kMaxScalePoints) +
              " distinct integers, the scale's values in the order shown (e.g. [1, 2, 3, 4, 5, 6, 7] or "
              "[-3, -2, -1, 0, 1, 2, 3])" + (vn ? ", found " + (values ? std::to_string(values->size()) + " values"
                                                                        : type_name(*vn))
                                              : std::string()));
    return;
  }
  const std::vector<std::string> labels = get_string_array(*s, "labels", sp);
  if (!s->contains("labels"))
    error(pos_of(*s), sp + ".labels", "missing required array of labels, one per value (\"\" leaves a point unlabelled)");
  else if (labels.size() != values->size())
    error(pos_of(*s->get("labels")), sp + ".labels",
          "expected " + std::to_string(values->size()) + " labels, one per value, found " +
              std::to_string(labels.size()));
  std::set<std::int64_t> seen;
  for (std::size_t i = 0; i < values->size(); ++i) {
    const toml::node& e = (*values)[i];
    const std::string field = sp + ".values[" + std::to_string(i + 1) + "]";
    const auto* iv = e.as_integer();
    if (!iv || iv->get() < -1000 || iv->get() > 1000) {
      error(pos_of(e), field, with_found("expected an integer from -1000 to 1000", e));
      continue;
    }
    if (!seen.insert(iv->get()).second) {
      error(pos_of(e), field, "duplicate value " + std::to_string(iv->get()));
      continue;
    }
    ins.scale.push_back({iv->get(), i < labels.size() ? labels[i] : std::string(), "", ""});
  }
  bind_scale_controls(ins.scale);
}

void Loader::read_items(const toml::table& t, const std::string& prefix, Instrument& ins) {
  const std::string ip = prefix + ".items";
  const toml::node* n = t.get("items");
  const auto* arr = n ? n->as_array() : nullptr;
  if (!arr || arr->empty() || arr->size() > kMaxItems) {
    error(n ? pos_of(*n) : pos_of(t), ip,
          "expected an array of 1 to " + std::to_string(kMaxItems) +
              " items, each { id = \"…\", text = \"…\" } (reversed = true to score it mirrored)" +
              (n && !arr ? ", found " + type_name(*n) : std::string()));
    return;
  }
  std::set<std::string> ids;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::node& e = (*arr)[i];
    const std::string field = ip + "[" + std::to_string(i + 1) + "]";
    const auto* it = e.as_table();
    if (!it) {
      error(pos_of(e), field, "expected a table { id = \"…\", text = \"…\" }, found " + type_name(e));
      continue;
    }
    check_keys(*it, field, {"id", "text", "reversed"});
    QuestionnaireItem item;
    item.id = get_string(*it, "id", field, true).value_or("");
    item.text = get_string(*it, "text", field, true).value_or("");
    item.reversed = get_bool(*it, "reversed", field).value_or(false);
    if (it->contains("id") && it->get("id")->is_string()) {
      if (!is_identifier(item.id))
        error(pos_of(*it->get("id")), field + ".id", "item ids are lower-case identifiers (a-z, 0-9, _ and -)");
      else if (!ids.insert(item.id).second)
        error(pos_of(*it->get("id")), field + ".id", "duplicate item id \"" + item.id + "\"");
    }
    if (it->contains("text") && it->get("text")->is_string() && item.text.empty())
      error(pos_of(*it->get("text")), field + ".text", "expected the item's text, found an empty string");
    ins.items.push_back(std::move(item));
  }
}

void Loader::read_subscales(const toml::table& t, const std::string& prefix, Instrument& ins) {
  const std::string sp = prefix + ".subscales";
  const toml::node* n = t.get("subscales");
  if (!n) return;
  const auto* arr = n->as_array();
  if (!arr) {
    error(pos_of(*n), sp, "expected [[" + sp + "]] tables, found " + type_name(*n));
    return;
  }
  std::vector<std::string> ids;
  for (const auto& item : ins.items) ids.push_back(item.id);
  std::set<std::string> names;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::node& e = (*arr)[i];
    const std::string field = sp + "[" + std::to_string(i + 1) + "]";
    const auto* st = e.as_table();
    if (!st) {
      error(pos_of(e), field, "expected a table with name, items, score and weight, found " + type_name(e));
      continue;
    }
    check_keys(*st, field, {"name", "items", "score", "weight"});
    Subscale s;
    s.name = get_string(*st, "name", field, true).value_or("");
    if (st->contains("name") && st->get("name")->is_string()) {
      if (!is_identifier(s.name))
        error(pos_of(*st->get("name")), field + ".name", "subscale names are lower-case identifiers (a-z, 0-9, _ and -)");
      else if (!names.insert(s.name).second)
        error(pos_of(*st->get("name")), field + ".name", "duplicate subscale name \"" + s.name + "\"");
    }
    const auto rule = get_enum(*st, "score", field, {"sum", "mean"});
    s.rule = rule && *rule == "mean" ? ScoreRule::mean : ScoreRule::sum;
    if (const auto w = get_number(*st, "weight", field, false)) {
      if (!std::isfinite(*w) || *w <= 0.0 || *w > 1e6)
        error(pos_of(*st->get("weight")), field + ".weight", "expected a number above 0 and at most 1e6");
      else
        s.weight = *w;
    }
    if (!st->contains("items")) {
      error(pos_of(*st), field + ".items", "missing required array of item ids");
    } else {
      const std::vector<std::string> listed = get_string_array(*st, "items", field);
      const auto* items_arr = st->get("items")->as_array();
      if (items_arr && items_arr->empty()) error(pos_of(*st->get("items")), field + ".items", "expected at least one item id");
      for (std::size_t k = 0; k < listed.size(); ++k) {
        const auto found = std::find(ids.begin(), ids.end(), listed[k]);
        if (found == ids.end()) {
          const toml::node* at = items_arr && k < items_arr->size() ? &(*items_arr)[k] : st->get("items");
          error(pos_of(*at), field + ".items[" + std::to_string(k + 1) + "]",
                "unknown item \"" + listed[k] + "\"" + expected_one_of(listed[k], ids));
          continue;
        }
        s.items.push_back(static_cast<std::size_t>(found - ids.begin()));
      }
    }
    ins.subscales.push_back(std::move(s));
  }
}

void Loader::read_questionnaire(const toml::table& t, const std::string& bp, const Protocol& p, Block& b) {
  const bool questionnaire = b.kind == "questionnaire";
  if (!questionnaire) {
    if (t.contains("instrument"))
      error(pos_of(*t.get("instrument")), bp + ".instrument",
            "only a questionnaire block (kind = \"questionnaire\") takes instrument");
    return;
  }
  std::vector<std::string> names{std::string(kSsqName)};
  for (const auto& ins : p.instruments) names.push_back(ins.name);
  const std::string expected = "\"ssq\" (the built-in Simulator Sickness Questionnaire) or the name of an "
                               "[instruments.<name>] table";
  const auto name = get_string(t, "instrument", bp, false);
  if (!t.contains("instrument")) {
    error(b.pos, bp + ".instrument", "missing required instrument: " + expected);
    return;
  }
  if (!name) return;
  if (*name == kSsqName) {
    b.instrument = ssq_instrument();
    return;
  }
  const auto it = std::find_if(p.instruments.begin(), p.instruments.end(),
                               [&](const Instrument& ins) { return ins.name == *name; });
  if (it == p.instruments.end()) {
    std::string msg = "unknown instrument \"" + *name + "\"";
    const std::string guess = closest_match(*name, names);
    if (!guess.empty()) msg += "; did you mean \"" + guess + "\"?";
    error(pos_of(*t.get("instrument")), bp + ".instrument", msg + " Expected " + expected);
    return;
  }
  b.instrument = *it;
}

}  // namespace curvlab::harness::protocol
