// The only code that knows the protocol file is TOML. It walks the document
// once, reporting every problem with its position, then checks the design as
// a whole (every factor-level combination of every block), so an author sees
// all errors in one pass.
#include "curvlab/harness/protocol/loader.hpp"

#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/latin_square.hpp"
#include "judgements/judgement_format.hpp"
#include "table_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace curvlab::harness::protocol {
namespace {

constexpr std::size_t kMaxFileBytes = 1u << 20;
constexpr std::size_t kMaxCells = 100000;
constexpr std::size_t kMaxTrials = 1000000;

namespace tr = toml_reader;
using tr::type_name;

// Every problem of a file as one failure; the message names the first, for
// a caller that shows only the message.
Error load_failure(Error::Kind kind, std::vector<Diagnostic> diagnostics) {
  std::string message = format_diagnostic(diagnostics.front());
  if (diagnostics.size() > 1) message += " (and " + std::to_string(diagnostics.size() - 1) + " more)";
  return {kind, std::move(message), std::move(diagnostics)};
}

class Loader : private TableReader {
 public:
  explicit Loader(std::string file) : TableReader(std::move(file)) {}

  Result<Protocol> run(std::string_view text) {
    auto parsed = tr::parse(text, file());
    if (const auto* problem = std::get_if<tr::SyntaxProblem>(&parsed)) {
      error(to_source_pos(problem->pos), "syntax", problem->message);
      return load_failure(Error::Kind::bad_input, take_diagnostics());
    }
    const toml::table& root = std::get<toml::table>(parsed);
    Protocol p;
    p.file = file();
    p.text = std::string(text);
    read_root(root, p);
    if (!failed()) check_design(p, root);
    if (auto diagnostics = take_diagnostics(); !diagnostics.empty())
      return load_failure(Error::Kind::bad_input, std::move(diagnostics));
    return p;
  }

 private:
  // ---- settings sections (session level and per block) ----------------
  void read_settings(const toml::table& t, const std::string& prefix, std::vector<SettingOverride>& out) {
    for (const char* section : {"space", "tracking", "viewing", "timeline", "stimulus", "table"}) {
      const std::string sp = join(prefix, section);
      const toml::table* st = sub_table(t, section, prefix);
      if (!st) continue;
      check_keys(*st, sp, setting_keys(section));
      if (st->contains("preset") && (st->contains("projection") || st->contains("eyes")))
        error(pos_of(*st->get("preset")), sp + ".preset",
              "a preset sets projection and eyes; give either the preset or projection/eyes");
      for (auto&& [k, v] : *st) {
        const std::string path = std::string(section) + "." + std::string(k.str());
        const SettingInfo* info = find_setting(path);
        if (!info) continue;  // reported by check_keys
        const auto value = to_value(v);
        if (!value) {
          error(pos_of(v), join(prefix, path), with_found("expected a value, found " + type_name(v), v));
          continue;
        }
        if (const auto checked = check_setting(*info, *value); !checked) {
          error(pos_of(v), join(prefix, path), with_found(checked.error().message, v));
          continue;
        }
        out.push_back({path, *value, pos_of(v)});
      }
    }
  }

  // ---- top level ---------------------------------------------------------
  void read_root(const toml::table& root, Protocol& p) {
    check_keys(root, "", {"protocol", "space", "tracking", "viewing", "timeline", "stimulus",
                          "table", "backend", "calibration", "responses", "randomization", "counterbalance", "session",
                          "factors", "judgement", "instructions", "blocks"});
    read_metadata(root, p);
    read_settings(root, "", p.session_overrides);
    read_backend(root, p);
    read_calibration(root, p);
    if (const toml::table* r = sub_table(root, "responses", "")) {
      check_keys(*r, "responses", {"hid"});
      p.hid_mappings = get_string_array(*r, "hid", "responses");
    }
    read_randomization(root, p);
    read_factors(root, p);
    // A top-level [judgement] is required unless every block has its own
    // (checked in read_blocks, where that is known).
    has_root_judgement_ = root.contains("judgement");
    if (const toml::table* j = sub_table(root, "judgement", "")) p.judgement = read_judgement(*j, "judgement", p);
    // A session value for a setting a factor varies would never be used.
    for (const auto& o : p.session_overrides)
      for (const auto& f : p.factors)
        if (f.sets == o.path)
          error(o.pos, o.path, "factor \"" + f.name + "\" varies " + f.sets +
                                   ", so this value would never be used; remove it");
    if (const toml::table* ins = sub_table(root, "instructions", "")) {
      check_keys(*ins, "instructions", {"start", "end"});
      p.instructions_start = get_string_array(*ins, "start", "instructions");
      p.instructions_end = get_string_array(*ins, "end", "instructions");
    }
    read_blocks(root, p);
    read_counterbalance(root, p);
  }

  void read_metadata(const toml::table& root, Protocol& p) {
    const toml::table* m = sub_table(root, "protocol", "");
    if (!m) {
      if (!root.contains("protocol"))
        error({1, 1}, "protocol", "missing required table [protocol] with name and version");
      return;
    }
    check_keys(*m, "protocol", {"name", "version", "description"});
    p.meta.name = get_string(*m, "name", "protocol", true).value_or("");
    p.meta.version = get_string(*m, "version", "protocol", true).value_or("");
    p.meta.description = get_string(*m, "description", "protocol", false).value_or("");
    if (m->contains("name") && m->get("name")->is_string() && p.meta.name.empty())
      error(pos_of(*m->get("name")), "protocol.name", "expected a non-empty name");
  }

  void read_backend(const toml::table& root, Protocol& p) {
    const toml::table* b = sub_table(root, "backend", "");
    if (!b) return;
    check_keys(*b, "backend", {"preferred", "refresh_hz", "resolution"});
    p.backend_preferred = get_enum(*b, "preferred", "backend", {"headless", "desktop", "xr"}).value_or("headless");
    p.refresh_hz = static_cast<int>(get_int(*b, "refresh_hz", "backend", 30, 240, false).value_or(90));
    if (const toml::node* r = b->get("resolution")) {
      const auto* arr = r->as_array();
      const toml::value<std::int64_t>* wn = arr && arr->size() == 2 ? (*arr)[0].as_integer() : nullptr;
      const toml::value<std::int64_t>* hn = arr && arr->size() == 2 ? (*arr)[1].as_integer() : nullptr;
      if (!wn || !hn) {
        error(pos_of(*r), "backend.resolution", "expected [width, height] in pixels, two integers");
      } else {
        const auto w = wn->get(), h = hn->get();
        if (w < 16 || w > 8192 || h < 16 || h > 8192)
          error(pos_of(*r), "backend.resolution",
                "expected each size in [16, 8192] pixels, got [" + std::to_string(w) + ", " + std::to_string(h) +
                    "]");
        else {
          p.resolution_width = static_cast<int>(w);
          p.resolution_height = static_cast<int>(h);
        }
      }
    }
  }

  void read_calibration(const toml::table& root, Protocol& p) {
    const toml::table* c = sub_table(root, "calibration", "");
    if (!c) return;
    check_keys(*c, "calibration", {"at_start", "tip_offset_m", "max_residual_mm"});
    p.calibration.at_start = get_bool(*c, "at_start", "calibration").value_or(false);
    if (const toml::node* t = c->get("tip_offset_m")) {
      const auto* arr = t->as_array();
      bool ok = arr != nullptr && arr->size() == 3;
      for (std::size_t i = 0; ok && i < 3; ++i) {
        const auto v = node_number((*arr)[i]);
        ok = v && std::abs(*v) <= 0.5;
        if (ok) p.calibration.tip_offset_m[i] = *v;
      }
      if (!ok)
        error(pos_of(*t), "calibration.tip_offset_m",
              with_found("expected [x, y, z] in metres, three numbers in [-0.5, 0.5]", *t));
    }
    if (const auto mm = get_number(*c, "max_residual_mm", "calibration", false)) {
      if (*mm < 1.0 || *mm > 100.0)
        error(pos_of(*c->get("max_residual_mm")), "calibration.max_residual_mm",
              with_found("expected a number in [1, 100] millimetres", *c->get("max_residual_mm")));
      else
        p.calibration.max_residual_mm = *mm;
    }
  }

  void read_randomization(const toml::table& root, Protocol& p) {
    const toml::table* r = sub_table(root, "randomization", "");
    if (!r) {
      if (!root.contains("randomization"))
        error({1, 1}, "randomization",
              "missing required table [randomization] with an explicit seed (it is logged with every session)");
      return;
    }
    check_keys(*r, "randomization", {"seed", "trials", "per_participant"});
    if (const auto seed = get_int(*r, "seed", "randomization", 0, std::numeric_limits<std::int64_t>::max(), true))
      p.seed = static_cast<std::uint64_t>(*seed);
    const auto mode = get_enum(*r, "trials", "randomization", {"none", "shuffle", "shuffle_within_repetition"});
    default_randomize_ = parse_mode(mode.value_or("shuffle"));
    p.seed_per_participant = get_bool(*r, "per_participant", "randomization").value_or(true);
  }

  static RandomizeMode parse_mode(const std::string& m) {
    if (m == "none") return RandomizeMode::none;
    if (m == "shuffle_within_repetition") return RandomizeMode::shuffle_within_repetition;
    return RandomizeMode::shuffle;
  }

  void read_factors(const toml::table& root, Protocol& p) {
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

  // ---- judgements -------------------------------------------------------
  // The common keys here; the rest is the type's (judgement.hpp).
  Judgement read_judgement(const toml::table& j, const std::string& prefix, const Protocol& p) {
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
    out.type = find_judgement_type(*type);
    check_keys(j, prefix, table_keys(*out.type));
    JudgementSection section(*this, j, prefix, p);
    out.type->read(section, out);
    return out;
  }

  // ---- blocks ------------------------------------------------------------
  void read_blocks(const toml::table& root, Protocol& p) {
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
      check_keys(*t, bp, {"name", "practice", "repetitions", "randomize", "levels", "instructions",
                          "break_every_trials", "break_text", "break_min_ms", "space", "tracking",
                          "viewing", "timeline", "stimulus", "table", "judgement"});
      Block b;
      b.pos = pos_of(*t);
      b.name = get_string(*t, "name", bp, true).value_or("");
      if (t->contains("name") && t->get("name")->is_string()) {
        if (!is_identifier(b.name))
          error(pos_of(*t->get("name")), bp + ".name", "block names are lower-case identifiers (a-z, 0-9, _ and -)");
        else if (!names.insert(b.name).second)
          error(pos_of(*t->get("name")), bp + ".name", "duplicate block name \"" + b.name + "\"");
      }
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
                 "this block has no judgement: add a top-level [judgement] or one for the block");
      if (const auto problem = b.judgement.type ? b.judgement.type->repetitions_problem(b.repetitions) : std::nullopt)
        error(t->contains("repetitions") ? pos_of(*t->get("repetitions")) : b.pos, bp + ".repetitions", *problem);
      p.blocks.push_back(std::move(b));
    }
  }

  void read_block_levels(const toml::table& lv, const std::string& prefix, const Protocol& p, Block& b) {
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

  void read_counterbalance(const toml::table& root, Protocol& p) {
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

  // ---- the design as a whole ---------------------------------------------
  void check_design(const Protocol& p, const toml::table& root) {
    std::size_t total = 0;
    for (std::size_t bi = 0; bi < p.blocks.size(); ++bi) {
      const Block& b = p.blocks[bi];
      const std::string bp = root.contains("blocks") ? "blocks[" + std::to_string(bi + 1) + "]" : "blocks";
      std::size_t cells = 1;
      for (const auto& f : p.factors) {
        const auto it = b.levels.find(f.name);
        const std::size_t n = it == b.levels.end() ? f.levels.size() : it->second.size();
        cells = n == 0 ? 0 : (cells > kMaxCells ? cells : cells * n);
      }
      if (cells > kMaxCells) {
        error(b.pos, bp, "the block crosses more than " + std::to_string(kMaxCells) + " factor-level combinations");
        return;
      }
      const std::size_t trials = cells * b.judgement.type->trials_per_cell(b);
      if (trials == 0) error(b.pos, bp, "the block has zero trials");
      total += trials;
      if (total > kMaxTrials) {
        error(b.pos, bp, "the session would exceed " + std::to_string(kMaxTrials) + " trials");
        return;
      }
      check_cells(p, b, bp);
    }
  }

  // Resolves every factor-level combination of a block and checks what can
  // only be checked on the combination (a table that cannot exist in a space,
  // a bend deeper than the stick allows).
  void check_cells(const Protocol& p, const Block& b, const std::string& bp) {
    // Where each setting got its value: position and the field as written.
    std::map<std::string, std::pair<SourcePos, std::string>> base_origin;
    for (const auto& o : p.session_overrides) base_origin[o.path] = {o.pos, o.path};
    const bool explicit_blocks = bp != "blocks";
    for (const auto& o : b.overrides)
      base_origin[o.path] = {o.pos, explicit_blocks ? bp + "." + o.path : o.path};
    const Settings base = p.block_settings(b);
    std::set<std::pair<std::string, std::string>> reported;
    for (const auto& cell : block_cells(p, b)) {
      Settings s = base;
      auto origin = base_origin;
      std::string where;
      for (std::size_t f = 0; f < p.factors.size(); ++f) {
        const Level& l = p.factors[f].levels[cell[f]];
        if (const auto* info = find_setting(p.factors[f].sets)) {
          apply_setting(s, *info, l.value);
          origin[p.factors[f].sets] = {l.pos, "factors." + p.factors[f].name + ".levels[" +
                                                     std::to_string(cell[f] + 1) + "]"};
        }
        where += (where.empty() ? "" : ", ") + p.factors[f].name + " = " + l.label;
      }
      const std::string suffix = where.empty() ? "" : " (in " + b.name + " with " + where + ")";
      const auto report = [&](const std::string& path, const std::string& msg) {
        if (!reported.insert({path, msg}).second) return;
        const auto it = origin.find(path);
        if (it != origin.end()) error(it->second.first, it->second.second, msg + suffix);
        else error(b.pos, bp, msg + suffix);
      };
      check_settings(s, report);
      // The values the judgement can reach must be possible too:
      // check both ends of every range, reported at the judgement.
      const std::string& param = b.judgement.parameter;
      const std::vector<double> ends = b.judgement.type->reachable_values(b.judgement);
      if (param.empty() || ends.empty()) continue;
      const std::string jfield = (b.judgement.pos.line == p.judgement.pos.line &&
                                  b.judgement.pos.column == p.judgement.pos.column)
                                     ? "judgement"
                                     : bp + ".judgement";
      for (double v : ends) {
        Settings reached = s;
        set_numeric_setting(reached, param, v);
        check_settings(reached, [&](const std::string& path, const std::string& msg) {
          const std::string full = msg + " when " + param + " reaches " +
                                   value_label(SettingValue(std::in_place_type<double>, v));
          if (reported.insert({path, full}).second) error(b.judgement.pos, jfield, full + suffix);
        });
      }
    }
  }

  // Checks that need a whole resolved set of settings.
  template <typename Report>
  static void check_settings(const Settings& s, const Report& report) {
    if (const auto derived = derive(s); !derived)
      report(s.space.table_sides > 0 ? "space.table_sides" : "space.kind", derived.error().message);
    if (s.stimulus.stick_anchor == StickAnchor::head && s.stimulus.stick_distance_m < 0.1)
      report("stimulus.stick_distance_m",
             "a head-anchored stick must be at least 0.1 m from the eyes, found " +
                 value_label(SettingValue(std::in_place_type<double>, s.stimulus.stick_distance_m)));
    if (std::abs(s.stimulus.stick_sagitta_m) >= s.stimulus.stick_length_m / 2)
      report("stimulus.stick_sagitta_m", "expected |sagitta| < stick_length_m / 2 = " +
                                             number_label(s.stimulus.stick_length_m / 2) + ", got " +
                                             number_label(s.stimulus.stick_sagitta_m));
  }

  RandomizeMode default_randomize_ = RandomizeMode::shuffle;
  bool has_root_judgement_ = false;
  // Factor → labels of its levels that were reported and left out; a block
  // naming one gets no second error.
  std::map<std::string, std::set<std::string>> rejected_levels_;
};

}  // namespace

Result<Protocol> load_protocol_text(std::string_view text, const std::string& file) {
  Loader loader(file);
  try {
    return loader.run(text);
  } catch (const std::exception& e) {
    // Only allocation failure can get here; report it rather than crash.
    return load_failure(Error::Kind::bad_input,
                        {{file, {}, "", std::string("internal failure while loading: ") + e.what()}});
  }
}

Result<Protocol> load_protocol_file(const std::string& path) {
  // A folder opens as a stream that reads nothing; say what it is instead of
  // reporting an empty protocol.
  if (std::error_code ec; std::filesystem::is_directory(path, ec))
    return load_failure(Error::Kind::bad_input, {{path, {}, "", "is a folder, not a protocol file"}});
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::error_code ec;
    const auto kind = std::filesystem::exists(path, ec) ? Error::Kind::io : Error::Kind::not_found;
    return load_failure(kind, {{path, {}, "", "cannot open the file for reading"}});
  }
  std::string text;
  char buf[65536];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxFileBytes)
      return load_failure(Error::Kind::bad_input,
                          {{path, {}, "", "the file is larger than 1 MiB; a protocol is a short text file"}});
  }
  if (in.bad()) return load_failure(Error::Kind::io, {{path, {}, "", "cannot read the file"}});
  return load_protocol_text(text, path);
}

}  // namespace curvlab::harness::protocol

namespace curvlab::harness::protocol {

const std::vector<std::string>& response_key_names() { return key_names(); }
const std::vector<std::string>& response_button_names() { return button_names(); }

}  // namespace curvlab::harness::protocol
