// What every judgement type does unless it says otherwise (judgement.hpp):
// the behaviour of a plain choice, and the registry's look-ups.
#include "curvlab/harness/protocol/judgement.hpp"

#include <algorithm>

namespace curvlab::harness::protocol {

KeyPress first_input(std::int64_t t_ns, const std::vector<std::string>& keys, const std::vector<std::string>& buttons) {
  if (!keys.empty()) return {t_ns, keys.front(), false};
  if (!buttons.empty()) return {t_ns, buttons.front(), true};
  return {t_ns, {}, false};
}

bool binds(const std::vector<std::string>& keys, const std::vector<std::string>& buttons, const std::string& input) {
  return std::find(keys.begin(), keys.end(), input) != keys.end() ||
         std::find(buttons.begin(), buttons.end(), input) != buttons.end();
}

std::optional<std::string> JudgementType::repetitions_problem(int) const { return std::nullopt; }

std::vector<double> JudgementType::reachable_values(const Judgement&) const { return {}; }

bool JudgementType::stops_early() const { return false; }

std::size_t JudgementType::trials_per_cell(const Block& b) const { return static_cast<std::size_t>(b.repetitions); }

std::vector<DesignSlot> JudgementType::slots(const Block& b, std::size_t cells, Engine& rng) const {
  std::vector<DesignSlot> slots;
  for (int r = 0; r < b.repetitions; ++r) {
    std::vector<DesignSlot> rep;
    for (std::size_t c = 0; c < cells; ++c) rep.push_back({c, r, std::nullopt});
    if (b.randomize == RandomizeMode::shuffle_within_repetition) shuffle(rep, rng);
    slots.insert(slots.end(), rep.begin(), rep.end());
  }
  if (b.randomize == RandomizeMode::shuffle) shuffle(slots, rng);
  return slots;
}

void JudgementType::plan_trial(const Judgement&, PlannedTrial&, Engine&) const {}

std::vector<std::pair<std::string, std::string>> JudgementType::conditions(const Judgement&,
                                                                           const PlannedTrial&) const {
  return {};
}

std::unique_ptr<AdaptiveState> JudgementType::adaptive_state(const Judgement&) const { return nullptr; }

std::optional<Adjustment> JudgementType::adjustment(const Judgement&, const PlannedTrial&) const {
  return std::nullopt;
}

std::vector<AnswerBinding> JudgementType::answer_bindings(const Judgement& j) const {
  std::vector<AnswerBinding> out;
  for (std::size_t k = 0; k < j.options.size(); ++k)
    out.push_back({j.options[k].value, j.options[k].keys, j.options[k].buttons, InputVerdict{InputUse::choose, k}});
  return out;
}

InputVerdict JudgementType::classify(const Judgement& j, const std::string& input) const {
  for (const auto& a : answer_bindings(j))
    if (binds(a.keys, a.buttons, input)) return a.verdict;
  return {};
}

AnswerPlan JudgementType::plan_answer(const Judgement& j, Respondent& who, std::int64_t t_ns,
                                      const std::optional<Adjustment>&) const {
  AnswerPlan out;
  out.perceived_m = who.judged();
  const auto& option = j.options.at(who.choose(out.perceived_m, j.options.size()));
  KeyPress press = first_input(t_ns, option.keys, option.buttons);
  if (press.name.empty()) press.name = option.value;
  out.keys.push_back(std::move(press));
  return out;
}

Forecast JudgementType::forecast() const { return Forecast::proportions; }

std::vector<ConvergenceTarget> JudgementType::convergence(const Judgement&) const { return {}; }

std::optional<OnsetValue> JudgementType::onset_value(const Judgement&, const PlannedTrial&) const {
  return std::nullopt;
}

std::vector<std::pair<std::string, std::string>> JudgementType::settings_summary(const Judgement&) const {
  return {};
}

const JudgementType* find_judgement_type(std::string_view name) {
  for (const JudgementType* t : judgement_types())
    if (t->name() == name) return t;
  return nullptr;
}

std::string judgement_type_alternatives() {
  const auto& types = judgement_types();
  std::string out;
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (i > 0) out += i + 1 == types.size() ? " or " : ", ";
    out.append("\"").append(types[i]->name()).append("\"");
  }
  return out;
}

}  // namespace curvlab::harness::protocol
