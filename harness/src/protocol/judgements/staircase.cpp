// `type = "staircase"`: interleaved n-up/m-down staircases (Levitt 1971) on
// the judgement's parameter. Every cell of the block runs its own set, each
// staircase given max_trials slots; the slots are shuffled together, and the
// runner skips the slots of a staircase that has stopped. The algorithm is
// the pure Staircase of staircase.hpp.
#include "judgement_format.hpp"

#include "curvlab/harness/protocol/staircase.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

namespace curvlab::harness::protocol {

namespace {

namespace tr = toml_reader;

struct StaircaseTable final : JudgementSpec {
  std::string positive;  // the option value that counts as positive
  std::vector<StaircaseSpec> staircases;
};

const StaircaseTable* table_of(const Judgement& j) { return dynamic_cast<const StaircaseTable*>(j.spec.get()); }

// A staircase block's slot names its staircase; the design always sets it.
std::size_t staircase_of(const PlannedTrial& t) {
  if (!t.staircase) {
    std::fprintf(stderr, "curvlab: trial %zu of staircase block '%s' has no staircase slot\n", t.index,
                 t.block.c_str());
    std::abort();
  }
  return t.staircase->index;
}

// One cell's interleaved staircases.
class StaircaseSet final : public AdaptiveState {
 public:
  explicit StaircaseSet(const StaircaseTable& table) : positive_(table.positive), stairs_(table.staircases) {}

  [[nodiscard]] std::optional<std::string> skip_reason(const PlannedTrial& t) const override {
    if (stairs_.at(staircase_of(t)).finished()) return "staircase_finished";
    return std::nullopt;
  }
  [[nodiscard]] double value(const PlannedTrial& t) const override { return stairs_.at(staircase_of(t)).value(); }
  [[nodiscard]] bool positive(std::string_view answer) const override { return answer == positive_; }

  AdaptiveStep record(const PlannedTrial& t, bool positive) override {
    Staircase& s = stairs_.at(staircase_of(t));
    AdaptiveStep step{s.spec().name, s.trials(), s.value(), positive, false, 0.0, std::nullopt};
    const int reversals = s.reversals();
    s.respond(positive);
    step.reversal = s.reversals() > reversals;
    step.next_value = s.value();
    return step;
  }

 private:
  std::string positive_;
  InterleavedStaircases stairs_;
};

class InterleavedStaircaseJudgement final : public JudgementType {
 public:
  [[nodiscard]] std::string_view name() const override { return "staircase"; }
  [[nodiscard]] std::string_view summary() const override { return "interleaved staircases"; }

  void fields(JudgementFields& out) const override;
  void read(JudgementSection& section, Judgement& out) const override;

  [[nodiscard]] std::optional<std::string> repetitions_problem(int repetitions) const override {
    if (repetitions <= 1) return std::nullopt;
    return "expected 1 in a staircase block, got " + std::to_string(repetitions) +
           " (its length comes from the stop rule); add staircases instead";
  }

  [[nodiscard]] std::vector<double> reachable_values(const Judgement& j) const override {
    std::vector<double> ends;
    for (const auto& s : stairs(j)) {
      ends.push_back(s.min);
      ends.push_back(s.max);
    }
    return ends;
  }

  [[nodiscard]] bool stops_early() const override { return true; }

  [[nodiscard]] std::size_t trials_per_cell(const Block& b) const override {
    std::size_t n = 0;
    for (const auto& s : stairs(b.judgement)) n += static_cast<std::size_t>(s.max_trials);
    return n;
  }

  [[nodiscard]] std::vector<DesignSlot> slots(const Block& b, std::size_t cells, Engine& rng) const override;

  [[nodiscard]] std::vector<std::pair<std::string, std::string>> conditions(const Judgement& j,
                                                                            const PlannedTrial& t) const override {
    if (!t.staircase) return {};
    return {{"staircase", stairs(j).at(t.staircase->index).name}};
  }

  [[nodiscard]] std::unique_ptr<AdaptiveState> adaptive_state(const Judgement& j) const override {
    const auto* table = table_of(j);
    if (!table) return nullptr;
    return std::make_unique<StaircaseSet>(*table);
  }

  [[nodiscard]] Forecast forecast() const override { return Forecast::convergence; }

  [[nodiscard]] std::vector<ConvergenceTarget> convergence(const Judgement& j) const override {
    std::vector<ConvergenceTarget> out;
    const auto* table = table_of(j);
    if (!table) return out;
    for (const auto& s : table->staircases)
      out.push_back({s.name, table->positive, std::to_string(s.up) + "-up/" + std::to_string(s.down) + "-down", s.up,
                     s.down, s.min, s.max, staircase_target_probability(s.up, s.down)});
    return out;
  }

  [[nodiscard]] std::optional<OnsetValue> onset_value(const Judgement& j, const PlannedTrial& t) const override {
    const auto& all = stairs(j);
    if (all.empty()) return std::nullopt;
    const auto& sc = all[t.staircase ? t.staircase->index : 0];
    return OnsetValue{sc.start, "staircase \"" + sc.name + "\" at its start value, " + j.parameter + " = " +
                                    number_label(sc.start)};
  }

  [[nodiscard]] std::vector<std::pair<std::string, std::string>> settings_summary(const Judgement& j) const override;

 private:
  static const std::vector<StaircaseSpec>& stairs(const Judgement& j) {
    static const std::vector<StaircaseSpec> none;
    const auto* table = table_of(j);
    return table ? table->staircases : none;
  }
  void read_staircases(JudgementSection& section, const std::string& parameter, StaircaseTable& out) const;
  static StaircaseSpec read_staircase(TableReader& r, const toml::table& t, const std::string& sp,
                                      const std::string& parameter, std::set<std::string>& names);
  static void read_step_sizes(TableReader& r, const toml::table& t, const std::string& sp, StaircaseSpec& s);
};

void InterleavedStaircaseJudgement::fields(JudgementFields& out) const {
  using namespace schema_json;
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
  Json staircase = closed_object(props, "one n-up/m-down staircase (Levitt 1971)");
  staircase["required"] = Json::array({"name", "start", "step_sizes", "min", "max"});
  out.add_options();
  out.add_parameter();
  out.add("positive", string_field("the option value that counts as a positive response"));
  out.add("staircases", {{"type", "array"}, {"minItems", 1}, {"items", staircase},
                         {"description", "interleaved staircases for every cell"}});
  out.require({"parameter", "options", "positive", "staircases"});
}

void InterleavedStaircaseJudgement::read(JudgementSection& section, Judgement& out) const {
  const toml::table& j = section.table;
  auto table = std::make_shared<StaircaseTable>();
  out.options = section.options();
  out.parameter = section.parameter();
  if (auto pos = section.reader.get_string(j, "positive", section.prefix, true)) {
    const bool known = std::any_of(out.options.begin(), out.options.end(),
                                   [&](const ResponseOption& o) { return o.value == *pos; });
    if (!known) {
      std::vector<std::string> values;
      for (const auto& o : out.options) values.push_back(o.value);
      section.reader.error(pos_of(*j.get("positive")), section.prefix + ".positive",
                           "\"" + *pos + "\" is not an option value" + expected_one_of(*pos, values));
    }
    table->positive = *pos;
  }
  read_staircases(section, out.parameter, *table);
  out.spec = std::move(table);
}

void InterleavedStaircaseJudgement::read_staircases(JudgementSection& section, const std::string& parameter,
                                                    StaircaseTable& out) const {
  const toml::node* n = section.table.get("staircases");
  const std::string field = section.prefix + ".staircases";
  if (!n) {
    section.reader.error(pos_of(section.table), field, "missing required [[" + field + "]] tables");
    return;
  }
  const auto* arr = n->as_array();
  if (!arr || arr->empty()) {
    section.reader.error(pos_of(*n), field, "expected at least one staircase table");
    return;
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < arr->size(); ++i) {
    const toml::node& e = (*arr)[i];
    const std::string sp = field + "[" + std::to_string(i + 1) + "]";
    const auto* t = e.as_table();
    if (!t) {
      section.reader.error(pos_of(e), sp, "expected a table, found " + tr::type_name(e));
      continue;
    }
    StaircaseSpec s = read_staircase(section.reader, *t, sp, parameter, names);
    read_step_sizes(section.reader, *t, sp, s);
    out.staircases.push_back(std::move(s));
  }
}

StaircaseSpec InterleavedStaircaseJudgement::read_staircase(TableReader& r, const toml::table& t,
                                                            const std::string& sp, const std::string& parameter,
                                                            std::set<std::string>& names) {
  r.check_keys(t, sp, {"name", "start", "up", "down", "step_sizes", "stop_reversals", "max_trials",
                       "discard_reversals", "min", "max"});
  StaircaseSpec s;
  s.name = r.get_string(t, "name", sp, true).value_or("");
  if (!s.name.empty() && !names.insert(s.name).second)
    r.error(pos_of(*t.get("name")), sp + ".name", "duplicate staircase name \"" + s.name + "\"");
  const auto start = r.get_number(t, "start", sp, true);
  s.up = static_cast<int>(r.get_int(t, "up", sp, 1, 5, false).value_or(1));
  s.down = static_cast<int>(r.get_int(t, "down", sp, 1, 5, false).value_or(2));
  s.stop_reversals = static_cast<int>(r.get_int(t, "stop_reversals", sp, 1, 100, false).value_or(8));
  s.max_trials = static_cast<int>(r.get_int(t, "max_trials", sp, 1, 1000, false).value_or(50));
  s.discard_reversals = static_cast<int>(r.get_int(t, "discard_reversals", sp, 0, 99, false).value_or(2));
  if (t.contains("discard_reversals") && s.discard_reversals >= s.stop_reversals)
    r.error(pos_of(*t.get("discard_reversals")), sp + ".discard_reversals",
            "expected discard_reversals < stop_reversals = " + std::to_string(s.stop_reversals) + ", got " +
                std::to_string(s.discard_reversals) + " (no reversal would be left for the estimate)");
  const auto mn = r.get_number(t, "min", sp, true), mx = r.get_number(t, "max", sp, true);
  if (mn && mx) {
    s.min = *mn;
    s.max = *mx;
    check_range(r, parameter, s.min, s.max, t, sp);
  }
  if (start) {
    s.start = *start;
    // Only against a range that is one: min ≥ max is reported above.
    if (mn && mx && s.min < s.max && (s.start < s.min || s.start > s.max))
      r.error(pos_of(*t.get("start")), sp + ".start",
              "expected " + number_label(s.min) + " ≤ start ≤ " + number_label(s.max) + ", got " +
                  number_label(s.start));
  }
  return s;
}

void InterleavedStaircaseJudgement::read_step_sizes(TableReader& r, const toml::table& t, const std::string& sp,
                                                    StaircaseSpec& s) {
  const toml::node* st = t.get("step_sizes");
  if (!st) {
    r.error(pos_of(t), sp + ".step_sizes", "missing required array of step sizes");
    return;
  }
  const auto* sa = st->as_array();
  if (!sa || sa->empty()) {
    r.error(pos_of(*st), sp + ".step_sizes", "expected a non-empty array of positive numbers");
    return;
  }
  for (std::size_t k = 0; k < sa->size(); ++k) {
    const auto v = TableReader::node_number((*sa)[k]);
    if (!v || !(*v > 0.0) || !std::isfinite(*v)) {
      r.error(pos_of((*sa)[k]), sp + ".step_sizes[" + std::to_string(k + 1) + "]",
              "expected a positive number, " +
                  (v ? "got " + number_label(*v) : "found " + tr::type_name((*sa)[k])));
      continue;
    }
    s.step_sizes.push_back(*v);
  }
}

std::vector<std::pair<std::string, std::string>> InterleavedStaircaseJudgement::settings_summary(
    const Judgement& j) const {
  const auto* table = table_of(j);
  if (!table) return {};
  std::vector<std::pair<std::string, std::string>> rows{{"positive answer", table->positive}};
  for (const auto& s : table->staircases) {
    std::string steps;
    for (const double step : s.step_sizes) steps += (steps.empty() ? "" : ", ") + number_label(step);
    const std::string rule = std::to_string(s.up) + "-up/" + std::to_string(s.down) + "-down";
    char target[32];
    std::snprintf(target, sizeof target, "%.1f", 100.0 * staircase_target_probability(s.up, s.down));
    rows.emplace_back("staircase \"" + s.name + "\"",
                      "start " + number_label(s.start) + "; step sizes " + steps +
                          " (step k after k reversals, the last repeating); " + rule + ", converging on " + target +
                          " % \"" + table->positive + "\"; stops after " + std::to_string(s.stop_reversals) +
                          " reversals or " + std::to_string(s.max_trials) +
                          " trials; threshold: mean of the reversals after the first " +
                          std::to_string(s.discard_reversals) + "; clamped to " + interval_label(s.min, s.max));
  }
  return rows;
}

// Round-robin slots, max_trials per staircase per cell; shuffling interleaves
// them so the participant cannot follow one track.
std::vector<DesignSlot> InterleavedStaircaseJudgement::slots(const Block& b, std::size_t cells, Engine& rng) const {
  const auto& all = stairs(b.judgement);
  int most = 0;
  for (const auto& s : all) most = std::max(most, s.max_trials);
  std::vector<DesignSlot> slots;
  for (int t = 0; t < most; ++t)
    for (std::size_t c = 0; c < cells; ++c)
      for (std::size_t s = 0; s < all.size(); ++s)
        if (t < all[s].max_trials) slots.push_back({c, 0, StaircaseSlot{s}});
  if (b.randomize != RandomizeMode::none) shuffle(slots, rng);
  return slots;
}

}  // namespace

const JudgementType& staircase_judgement_type() {
  static const InterleavedStaircaseJudgement type;
  return type;
}

}  // namespace curvlab::harness::protocol
