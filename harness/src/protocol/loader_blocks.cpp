// The protocol file's factors, judgements, blocks and counterbalancing:
// the levels a block crosses, what each trial asks, and the order blocks
// run in for each participant.
#include "loader_impl.hpp"

#include "curvlab/geometry/billiards.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace curvlab::harness::protocol {
namespace {

namespace tr = toml_reader;
using tr::type_name;

}  // namespace

void Loader::read_factors(const toml::table& root, Protocol& p) {
  const toml::table* fs = sub_table(root, "factors", "");
  if (!fs) return;
  std::map<std::string, std::string> varied;  // setting path → factor
  for (auto&& [k, v] : *fs) {
    Factor f;
    f.name = std::string(k.str());
    f.pos = pos_of(k.source());
    const std::string prefix = "factors." + f.name;
    if (!is_identifier(f.name))
      error(f.pos, prefix, "factor names are lower-case identifiers (a-z, 0-9, _ and -)");
    const auto* t = v.as_table();
    if (!t) {
      error(pos_of(v), prefix, "expected a table with sets and levels, found " + type_name(v));
      continue;
    }
    check_keys(*t, prefix, {"sets", "levels", "description"});
    f.description = get_string(*t, "description", prefix, false).value_or("");
    const SettingInfo* info = nullptr;
    if (auto sets = get_string(*t, "sets", prefix, false)) {
      info = find_setting(*sets);
      if (!info) {
        std::vector<std::string> paths;
        for (const auto& s : all_settings()) paths.emplace_back(s.path);
        std::string msg = "unknown setting \"" + *sets + "\"";
        const std::string guess = closest_match(*sets, paths);
        if (!guess.empty()) msg += "; did you mean \"" + guess + "\"?";
        msg += " Expected a setting path such as \"space.kind\" or \"viewing.preset\"";
        error(pos_of(*t->get("sets")), prefix + ".sets", msg);
      } else {
        f.sets = *sets;
        const auto overlaps = [&](const std::string& a, const std::string& b) {
          const bool view_a = a == "viewing.preset", view_b = b == "viewing.preset";
          return a == b || (view_a && (b == "viewing.projection" || b == "viewing.eyes")) ||
                 (view_b && (a == "viewing.projection" || a == "viewing.eyes"));
        };
        for (const auto& [path, other] : varied)
          if (overlaps(path, f.sets))
            error(pos_of(*t->get("sets")), prefix + ".sets",
                  "\"" + f.sets + "\" is already varied by factor \"" + other + "\"");
        varied[f.sets] = f.name;
      }
    }
    const toml::node* ln = t->get("levels");
    if (!ln) {
      error(pos_of(*t), prefix + ".levels", "missing required array of levels");
    } else if (const auto* arr = ln->as_array(); !arr) {
      error(pos_of(*ln), prefix + ".levels", "expected an array of levels, found " + type_name(*ln));
    } else if (arr->empty()) {
      error(pos_of(*ln), prefix + ".levels", "expected at least one level");
    } else {
      std::set<std::string> labels;
      for (std::size_t i = 0; i < arr->size(); ++i) {
        const toml::node& e = (*arr)[i];
        const std::string field = prefix + ".levels[" + std::to_string(i + 1) + "]";
        const auto value = to_value(e);
        if (!value) {
          error(pos_of(e), field, "expected a level value, found " + type_name(e));
          continue;
        }
        if (info) {
          if (const auto checked = check_setting(*info, *value); !checked) {
            error(pos_of(e), field, with_found(checked.error().message, e) + " (levels of " + f.sets + ")");
            rejected_levels_[f.name].insert(value_label(*value));
            continue;
          }
        } else if (!std::holds_alternative<std::string>(*value) && !t->contains("sets")) {
          error(pos_of(e), field, "a factor without \"sets\" only labels trials: expected a string");
          rejected_levels_[f.name].insert(value_label(*value));
          continue;
        }
        Level level{value_label(*value), *value, pos_of(e)};
        if (!labels.insert(level.label).second) {
          error(pos_of(e), field, "duplicate level \"" + level.label + "\"");
          continue;
        }
        f.levels.push_back(level);
      }
    }
    p.factors.push_back(std::move(f));
  }
}

Judgement Loader::read_judgement(const toml::table& j, const std::string& prefix, const Protocol& p) {
  Judgement out;
  out.pos = pos_of(j);
  std::vector<std::string> names;
  for (const JudgementType* t : judgement_types()) names.emplace_back(t->name());
  const auto type = get_enum(j, "type", prefix, names);
  if (!j.contains("type"))
    error(pos_of(j), prefix + ".type", "missing required type: " + judgement_type_alternatives());
  if (!type) {
    check_keys(j, prefix, any_table_keys());
    return out;
  }
  out.prompt = get_string(j, "prompt", prefix, false).value_or("");
  out.feedback = get_bool(j, "feedback", prefix).value_or(false);
  out.type = find_judgement_type(*type);
  check_keys(j, prefix, table_keys(*out.type));
  JudgementSection section(*this, j, prefix, p);
  out.type->read(section, out);
  return out;
}

void Loader::read_blocks(const toml::table& root, Protocol& p) {
  std::int64_t reps = 1, every = 0, break_ms = 0;
  std::string break_text = "Take a short break.";
  if (const toml::table* s = sub_table(root, "session", "")) {
    check_keys(*s, "session", {"repetitions", "break_every_trials", "break_text", "break_min_ms"});
    reps = get_int(*s, "repetitions", "session", 1, 1000, false).value_or(1);
    every = get_int(*s, "break_every_trials", "session", 0, 100000, false).value_or(0);
    break_text = get_string(*s, "break_text", "session", false).value_or(break_text);
    break_ms = get_int(*s, "break_min_ms", "session", 0, 3600000, false).value_or(0);
  }
  const toml::node* n = root.get("blocks");
  if (!n) {
    Block b;
    b.name = "main";
    b.repetitions = static_cast<int>(reps);
    b.randomize = default_randomize_;
    b.judgement = p.judgement;
    if (!has_root_judgement_)
      error({1, 1}, "judgement", "missing required table [judgement] (type = " + judgement_type_alternatives() + ")");
    b.break_every_trials = static_cast<int>(every);
    b.break_text = break_text;
    b.break_min_ms = break_ms;
    b.pos = {1, 1};
    p.blocks.push_back(std::move(b));
    return;
  }
  const auto* arr = n->as_array();
  if (!arr || arr->empty()) {
    error(pos_of(*n), "blocks", "expected one or more [[blocks]] tables");
    return;
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::node& e = (*arr)[i];
    const std::string bp = "blocks[" + std::to_string(i + 1) + "]";
    const auto* t = e.as_table();
    if (!t) {
      error(pos_of(e), bp, "expected a table, found " + type_name(e));
      continue;
    }
    check_keys(*t, bp, {"name", "kind", "practice", "repetitions", "randomize", "levels", "instructions",
                        "break_every_trials", "break_text", "break_min_ms", "space", "tracking",
                        "viewing", "timeline", "stimulus", "table", "judgement", "duration_s", "shots",
                        "until", "rack", "physics", "instrument"});
    Block b;
    b.pos = pos_of(*t);
    b.name = get_string(*t, "name", bp, true).value_or("");
    b.kind = get_enum(*t, "kind", bp, block_kind_names()).value_or(block_kind_names().front());
    if (t->contains("name") && t->get("name")->is_string()) {
      if (!is_identifier(b.name))
        error(pos_of(*t->get("name")), bp + ".name", "block names are lower-case identifiers (a-z, 0-9, _ and -)");
      else if (!names.insert(b.name).second)
        error(pos_of(*t->get("name")), bp + ".name", "duplicate block name \"" + b.name + "\"");
    }
    read_play(*t, bp, b);
    read_questionnaire(*t, bp, p, b);
    b.practice = get_bool(*t, "practice", bp).value_or(false);
    b.repetitions = static_cast<int>(get_int(*t, "repetitions", bp, 1, 1000, false).value_or(reps));
    const auto mode = get_enum(*t, "randomize", bp, {"none", "shuffle", "shuffle_within_repetition"});
    b.randomize = mode ? parse_mode(*mode) : default_randomize_;
    b.instructions = get_string_array(*t, "instructions", bp);
    b.break_every_trials = static_cast<int>(get_int(*t, "break_every_trials", bp, 0, 100000, false).value_or(every));
    b.break_text = get_string(*t, "break_text", bp, false).value_or(break_text);
    b.break_min_ms = get_int(*t, "break_min_ms", bp, 0, 3600000, false).value_or(break_ms);
    read_settings(*t, bp, b.overrides);
    for (const auto& o : b.overrides)
      for (const auto& f : p.factors)
        if (!f.sets.empty() && (f.sets == o.path ||
                                (f.sets == "viewing.preset" && (o.path == "viewing.projection" || o.path == "viewing.eyes")) ||
                                (o.path == "viewing.preset" && (f.sets == "viewing.projection" || f.sets == "viewing.eyes"))))
          error(o.pos, bp + "." + o.path,
                "factor \"" + f.name + "\" varies " + f.sets +
                    "; restrict its levels with levels." + f.name + " instead of overriding it");
    if (const toml::table* lv = sub_table(*t, "levels", bp)) read_block_levels(*lv, bp + ".levels", p, b);
    if (const toml::table* j = sub_table(*t, "judgement", bp)) b.judgement = read_judgement(*j, bp + ".judgement", p);
    else if (has_root_judgement_) b.judgement = p.judgement;
    else error(b.pos, bp + ".judgement",
               b.kind == "trials" ? "this block has no judgement: add a top-level [judgement] or one for the block"
                                  : "a " + b.kind + " block is stored as one trial, and every trial carries a "
                                    "judgement: add a top-level [judgement] (the block asks none of it)");
    if (const auto problem = b.judgement.type && b.kind == "trials" ? b.judgement.type->repetitions_problem(b.repetitions) : std::nullopt)
      error(t->contains("repetitions") ? pos_of(*t->get("repetitions")) : b.pos, bp + ".repetitions", *problem);
    p.blocks.push_back(std::move(b));
  }
}

void Loader::read_play(const toml::table& t, const std::string& bp, Block& b) {
  const bool play = b.kind == "play";
  for (const char* key : {"duration_s", "shots", "until", "rack", "physics"})
    if (!play && t.contains(key))
      error(pos_of(*t.get(key)), bp + "." + key, "only a play block (kind = \"play\") takes " + std::string(key));
  if (!play) return;
  PlaySettings& s = b.play;
  if (const auto d = get_number(t, "duration_s", bp, false)) {
    if (!(*d > 0.0) || *d > 86400.0)
      error(pos_of(*t.get("duration_s")), bp + ".duration_s", "expected seconds above 0 and at most 86400");
    else
      s.duration_s = *d;
  }
  s.shots = static_cast<int>(get_int(t, "shots", bp, 0, 100000, false).value_or(0));
  if (const auto u = get_enum(t, "until", bp, {"all_pocketed", "time"})) s.until_all_pocketed = *u == "all_pocketed";
  s.rack = static_cast<int>(get_int(t, "rack", bp, 0, 15, false).value_or(15));
  if (const toml::table* ph = sub_table(t, "physics", bp)) {
    geometry::billiards::Parameters params;
    for (auto&& [k, v] : *ph) {
      const std::string name(k.str());
      const std::string field = bp + ".physics." + name;
      const auto value = node_number(v);
      if (!value) {
        error(pos_of(v), field, with_found("expected a number", v));
        continue;
      }
      if (const auto problem = geometry::billiards::set_parameter(params, name, *value)) {
        error(pos_of(k.source()), field, *problem);
        continue;
      }
      s.physics.emplace_back(name, *value);
    }
  }
}

void Loader::read_block_levels(const toml::table& lv, const std::string& prefix, const Protocol& p, Block& b) {
  for (auto&& [k, v] : lv) {
    const std::string name(k.str());
    const std::string field = prefix + "." + name;
    const Factor* f = p.find_factor(name);
    if (!f) {
      std::vector<std::string> names;
      for (const auto& fa : p.factors) names.push_back(fa.name);
      std::string msg = "no factor named \"" + name + "\"";
      const std::string guess = closest_match(name, names);
      if (!guess.empty()) msg += "; did you mean \"" + guess + "\"?";
      msg += names.empty() ? " (the protocol declares no factors)" : " Declared factors: " + quoted_list(names);
      error(pos_of(k.source()), field, msg);
      continue;
    }
    std::vector<const toml::node*> items;
    if (const auto* arr = v.as_array()) {
      for (std::size_t i = 0; i < arr->size(); ++i) items.push_back(&(*arr)[i]);
      if (arr->empty()) error(pos_of(v), field, "expected at least one level (a block with no levels has no trials)");
    } else {
      items.push_back(&v);
    }
    std::vector<std::size_t> chosen;
    for (const toml::node* item : items) {
      const auto value = to_value(*item);
      const std::string label = value ? value_label(*value) : "";
      const auto it = std::find_if(f->levels.begin(), f->levels.end(),
                                   [&](const Level& l) { return l.label == label; });
      // A level the factor's own list got wrong is reported there, once.
      if (value && it == f->levels.end() && rejected_levels_[name].contains(label)) continue;
      if (!value || it == f->levels.end()) {
        std::vector<std::string> labels;
        for (const auto& l : f->levels) labels.push_back(l.label);
        error(pos_of(*item), field,
              value ? "unknown level \"" + label + "\"" + expected_one_of(label, labels)
                    : "expected a level, found " + type_name(*item) + ": expected one of " + quoted_list(labels));
        continue;
      }
      const auto idx = static_cast<std::size_t>(it - f->levels.begin());
      if (std::find(chosen.begin(), chosen.end(), idx) != chosen.end())
        error(pos_of(*item), field, "level \"" + label + "\" listed twice");
      else chosen.push_back(idx);
    }
    b.levels[name] = chosen;
  }
}

void Loader::read_counterbalance(const toml::table& root, Protocol& p) {
  const toml::table* c = sub_table(root, "counterbalance", "");
  if (!c) return;
  check_keys(*c, "counterbalance", {"blocks", "square"});
  const auto order = get_enum(*c, "blocks", "counterbalance", {"fixed", "latin_square", "random"});
  p.block_order = !order || *order == "fixed" ? BlockOrder::fixed
                  : *order == "random"        ? BlockOrder::random
                                              : BlockOrder::latin_square;
  std::vector<std::string> main;
  for (const auto& b : p.blocks)
    if (!b.practice) main.push_back(b.name);
  if (p.block_order == BlockOrder::latin_square && main.size() < 2)
    error(pos_of(*c->get("blocks")), "counterbalance.blocks",
          "a Latin square needs at least 2 non-practice blocks, found " + std::to_string(main.size()));
  const toml::node* sq = c->get("square");
  if (!sq) return;
  if (p.block_order != BlockOrder::latin_square) {
    error(pos_of(*sq), "counterbalance.square", "a square is used only with blocks = \"latin_square\"");
    return;
  }
  const auto* rows = sq->as_array();
  if (!rows || rows->empty()) {
    error(pos_of(*sq), "counterbalance.square", "expected an array of rows, each an array of block names");
    return;
  }
  Square square;
  for (std::size_t r = 0; r < rows->size(); ++r) {
    const toml::node& rn = (*rows)[r];
    const std::string field = "counterbalance.square[" + std::to_string(r + 1) + "]";
    const auto* row = rn.as_array();
    if (!row) {
      error(pos_of(rn), field, "expected an array of block names, found " + type_name(rn));
      return;
    }
    std::vector<std::size_t> idx;
    for (std::size_t k = 0; k < row->size(); ++k) {
      const toml::node& cell = (*row)[k];
      const auto* s = cell.as_string();
      const auto it = s ? std::find(main.begin(), main.end(), s->get()) : main.end();
      if (it == main.end()) {
        const bool practice = s && std::any_of(p.blocks.begin(), p.blocks.end(), [&](const Block& b) {
                                return b.practice && b.name == s->get();
                              });
        error(pos_of(cell), field + "[" + std::to_string(k + 1) + "]",
              !s         ? "expected the name of a non-practice block: " + quoted_list(main)
              : practice ? "\"" + s->get() + "\" is a practice block (practice runs first, in file order): " +
                               "expected one of " + quoted_list(main)
                         : "unknown block \"" + s->get() + "\"" + expected_one_of(s->get(), main));
        return;
      }
      idx.push_back(static_cast<std::size_t>(it - main.begin()));
    }
    square.push_back(idx);
  }
  if (const auto checked = check_latin(square, main.size()); !checked) {
    error(pos_of(*sq), "counterbalance.square",
          "not a Latin square over the " + std::to_string(main.size()) + " non-practice blocks: " +
              checked.error().message);
    return;
  }
  p.square = square;
}

}  // namespace curvlab::harness::protocol
