// `type = "adjustment"`: the method of adjustment. The participant moves the
// judgement's parameter with decrease and increase inputs from a start value
// drawn for each trial, then confirms; the confirmed value is the answer.
// The state of one attempt is an Adjustment (adjustment.hpp).
#include "judgement_format.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace curvlab::harness::protocol {

namespace {

struct AdjustmentTable final : JudgementSpec {
  explicit AdjustmentTable(const AdjustmentSpec& s) : spec(s) {}
  AdjustmentSpec spec;
};

// The judgement's spec; null when it has none (a judgement built by hand).
const AdjustmentSpec* spec_of(const Judgement& j) {
  const auto* table = dynamic_cast<const AdjustmentTable*>(j.spec.get());
  return table ? &table->spec : nullptr;
}

// Presses 80 ms apart, then the confirm 200 ms after the last.
constexpr std::int64_t kPressGapNs = 80'000'000;
constexpr std::int64_t kConfirmGapNs = 200'000'000;

class MethodOfAdjustment final : public JudgementType {
 public:
  [[nodiscard]] std::string_view name() const override { return "adjustment"; }
  [[nodiscard]] std::string_view summary() const override { return "method of adjustment"; }

  void fields(JudgementFields& out) const override;
  void read(JudgementSection& section, Judgement& out) const override;

  [[nodiscard]] std::vector<double> reachable_values(const Judgement& j) const override {
    const auto* a = spec_of(j);
    return a ? std::vector<double>{a->min, a->max} : std::vector<double>{};
  }

  void plan_trial(const Judgement& j, PlannedTrial& t, Engine& rng) const override {
    const auto* a = spec_of(j);
    if (!a) return;
    const double u = uniform01(rng);
    t.adjustment_start = a->start_min + u * (a->start_max - a->start_min);
  }

  [[nodiscard]] std::optional<Adjustment> adjustment(const Judgement& j, const PlannedTrial& t) const override {
    const auto* a = spec_of(j);
    if (!a) return std::nullopt;
    return Adjustment(*a, t.adjustment_start.value_or(a->start_min));
  }

  [[nodiscard]] std::vector<AnswerBinding> answer_bindings(const Judgement& j) const override {
    const AdjustmentSpec& a = *spec_of(j);
    return {{"decrease", a.keys_decrease, a.buttons_decrease, InputVerdict{InputUse::decrease, 0}},
            {"increase", a.keys_increase, a.buttons_increase, InputVerdict{InputUse::increase, 0}},
            {"confirm", a.keys_confirm, a.buttons_confirm, InputVerdict{InputUse::confirm, 0}}};
  }

  [[nodiscard]] AnswerPlan plan_answer(const Judgement& j, Respondent& who, std::int64_t t_ns,
                                       const std::optional<Adjustment>& adjustment) const override;

  [[nodiscard]] Forecast forecast() const override { return Forecast::none; }

  [[nodiscard]] std::optional<OnsetValue> onset_value(const Judgement& j, const PlannedTrial& t) const override {
    const auto* a = spec_of(j);
    if (!t.adjustment_start || !a) return std::nullopt;
    char value[64];
    std::snprintf(value, sizeof value, "%.4f", *t.adjustment_start);
    return OnsetValue{*t.adjustment_start, "adjustment start of trial " + std::to_string(t.index) + ", " +
                                               j.parameter + " = " + value + " (each trial draws its own from " +
                                               interval_label(a->start_min, a->start_max) + ")"};
  }

  [[nodiscard]] std::vector<std::pair<std::string, std::string>> settings_summary(const Judgement& j) const override {
    const auto* a = spec_of(j);
    if (!a) return {};
    return {{"start", "drawn for each trial from " + interval_label(a->start_min, a->start_max)},
            {"step", number_label(a->step) + " per press" +
                         (a->fine_step > 0.0 ? ", fine step " + number_label(a->fine_step) : std::string())},
            {"range", interval_label(a->min, a->max)}};
  }
};

void MethodOfAdjustment::fields(JudgementFields& out) const {
  using namespace schema_json;
  const auto* keys = &key_names();
  const auto* buttons = &button_names();
  out.add_parameter();
  out.add("start_min", {{"type", "number"},
                        {"description", "start values are drawn from [start_min, start_max]; min ≤ start_min"}});
  out.add("start_max", {{"type", "number"}, {"description", "start_min ≤ start_max ≤ max"}});
  out.add("step", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "one press; step ≤ max − min"}});
  out.add("fine_step", {{"type", "number"}, {"exclusiveMinimum", 0}, {"description", "a finer step (≤ step)"}});
  out.add("min", {{"type", "number"},
                  {"description", "the adjustable range, inside the setting's own range, min < max"}});
  out.add("max", {{"type", "number"}, {"description", "the adjustable range's upper end"}});
  out.add("keys_decrease", with_default(string_array("keys that decrease the value", keys), Json::array({"left"})));
  out.add("keys_increase", with_default(string_array("keys that increase the value", keys), Json::array({"right"})));
  out.add("keys_confirm", with_default(string_array("keys that confirm the value", keys), Json::array({"space"})));
  out.add("buttons_decrease", string_array("buttons that decrease the value", buttons));
  out.add("buttons_increase", string_array("buttons that increase the value", buttons));
  out.add("buttons_confirm", string_array("buttons that confirm the value", buttons));
  out.require({"parameter", "min", "max", "start_min", "start_max", "step"});
}

void MethodOfAdjustment::read(JudgementSection& section, Judgement& out) const {
  TableReader& r = section.reader;
  const toml::table& j = section.table;
  const std::string& prefix = section.prefix;
  AdjustmentSpec a;
  out.parameter = section.parameter();
  const auto mn = r.get_number(j, "min", prefix, true), mx = r.get_number(j, "max", prefix, true);
  const auto s0 = r.get_number(j, "start_min", prefix, true), s1 = r.get_number(j, "start_max", prefix, true);
  const auto step = r.get_number(j, "step", prefix, true);
  a.fine_step = r.get_number(j, "fine_step", prefix, false).value_or(0.0);
  bool range_ok = false;
  if (mn && mx) {
    a.min = *mn;
    a.max = *mx;
    range_ok = check_range(r, out.parameter, a.min, a.max, j, prefix);
  }
  // The start and the steps only against a range that is one (min ≥ max is
  // reported above), the fine step only against a step that was given.
  if (s0 && s1 && range_ok) {
    a.start_min = *s0;
    a.start_max = *s1;
    if (!(a.min <= a.start_min && a.start_min <= a.start_max && a.start_max <= a.max))
      r.error(pos_of(*j.get("start_min")), prefix + ".start_min",
              "expected " + number_label(a.min) + " ≤ start_min ≤ start_max ≤ " + number_label(a.max) +
                  ", got start_min = " + number_label(a.start_min) + ", start_max = " + number_label(a.start_max));
  }
  if (step) {
    a.step = *step;
    if (!(a.step > 0.0))
      r.error(pos_of(*j.get("step")), prefix + ".step", "expected 0 < step, got " + number_label(a.step));
    else if (range_ok && a.step > a.max - a.min)
      r.error(pos_of(*j.get("step")), prefix + ".step",
              "expected 0 < step ≤ max − min = " + number_label(a.max - a.min) + ", got " + number_label(a.step));
  }
  if (a.fine_step < 0.0)
    r.error(pos_of(*j.get("fine_step")), prefix + ".fine_step",
            "expected 0 < fine_step, got " + number_label(a.fine_step));
  else if (step && a.step > 0.0 && a.fine_step > a.step)
    r.error(pos_of(*j.get("fine_step")), prefix + ".fine_step",
            "expected 0 < fine_step ≤ step = " + number_label(a.step) + ", got " + number_label(a.fine_step));
  a.keys_decrease = r.get_string_array(j, "keys_decrease", prefix, &key_names());
  a.keys_increase = r.get_string_array(j, "keys_increase", prefix, &key_names());
  a.keys_confirm = r.get_string_array(j, "keys_confirm", prefix, &key_names());
  a.buttons_decrease = r.get_string_array(j, "buttons_decrease", prefix, &button_names());
  a.buttons_increase = r.get_string_array(j, "buttons_increase", prefix, &button_names());
  a.buttons_confirm = r.get_string_array(j, "buttons_confirm", prefix, &button_names());
  if (a.keys_decrease.empty() && a.buttons_decrease.empty()) a.keys_decrease = {"left"};
  if (a.keys_increase.empty() && a.buttons_increase.empty()) a.keys_increase = {"right"};
  if (a.keys_confirm.empty() && a.buttons_confirm.empty()) a.keys_confirm = {"space"};
  out.spec = std::make_shared<AdjustmentTable>(a);
}

// Coarse steps toward the value the participant settles on, then the confirm.
AnswerPlan MethodOfAdjustment::plan_answer(const Judgement& j, Respondent& who, std::int64_t t_ns,
                                           const std::optional<Adjustment>& adjustment) const {
  const AdjustmentSpec& a = *spec_of(j);
  const double start = adjustment->value();
  const double target = who.settle(j.parameter, a.min, a.max);
  AnswerPlan out;
  out.perceived_m = who.judged_at(j.parameter, start);
  const KeyPress up = first_input(0, a.keys_increase, a.buttons_increase);
  const KeyPress down = first_input(0, a.keys_decrease, a.buttons_decrease);
  double v = start;
  for (int presses = 0; std::abs(target - v) > a.step / 2.0 && presses < 400; ++presses) {
    const bool inc = target > v;
    KeyPress press = inc ? up : down;
    press.t_ns = t_ns;
    out.keys.push_back(std::move(press));
    v = std::clamp(v + (inc ? a.step : -a.step), a.min, a.max);
    t_ns += kPressGapNs;
  }
  out.keys.push_back(first_input(t_ns + kConfirmGapNs, a.keys_confirm, a.buttons_confirm));
  return out;
}

}  // namespace

const JudgementType& adjustment_judgement_type() {
  static const MethodOfAdjustment type;
  return type;
}

Judgement adjustment_judgement(const AdjustmentSpec& spec, std::string parameter) {
  Judgement j;
  j.type = &adjustment_judgement_type();
  j.parameter = std::move(parameter);
  j.spec = std::make_shared<AdjustmentTable>(spec);
  return j;
}

}  // namespace curvlab::harness::protocol
