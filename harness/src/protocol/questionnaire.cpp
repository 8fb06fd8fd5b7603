#include "curvlab/harness/protocol/questionnaire.hpp"

#include <algorithm>

namespace curvlab::harness::protocol {

std::string_view to_string(ScoreRule r) { return r == ScoreRule::mean ? "mean" : "sum"; }

void bind_scale_controls(std::vector<ScalePoint>& scale) {
  const bool digits = std::all_of(scale.begin(), scale.end(), [](const ScalePoint& p) { return p.value >= 0 && p.value <= 9; });
  for (std::size_t k = 0; k < scale.size(); ++k) {
    const std::int64_t digit = digits ? scale[k].value : static_cast<std::int64_t>(k + 1);
    scale[k].key = std::to_string(digit);
    scale[k].button = "hid_" + std::to_string(k + 1);
  }
}

const Instrument& ssq_instrument() {
  static const Instrument ssq = [] {
    Instrument ins;
    ins.name = std::string(kSsqName);
    ins.title = "How much is each symptom affecting you right now?";
    const char* symptoms[] = {"General discomfort",       "Fatigue",
                              "Headache",                 "Eyestrain",
                              "Difficulty focusing",      "Salivation increasing",
                              "Sweating",                 "Nausea",
                              "Difficulty concentrating", "Fullness of the head",
                              "Blurred vision",           "Dizziness with eyes open",
                              "Dizziness with eyes closed", "Vertigo",
                              "Stomach awareness",        "Burping"};
    const char* ids[] = {"general_discomfort", "fatigue", "headache", "eyestrain", "difficulty_focusing",
                         "salivation_increasing", "sweating", "nausea", "difficulty_concentrating",
                         "fullness_of_head", "blurred_vision", "dizziness_eyes_open", "dizziness_eyes_closed",
                         "vertigo", "stomach_awareness", "burping"};
    for (std::size_t i = 0; i < 16; ++i) ins.items.push_back({ids[i], symptoms[i], false});
    ins.scale = {{0, "None", "", ""}, {1, "Slight", "", ""}, {2, "Moderate", "", ""}, {3, "Severe", "", ""}};
    bind_scale_controls(ins.scale);
    // Kennedy et al. (1993), Table 5: the items of each factor, numbered from 1.
    const std::vector<std::size_t> n{1, 6, 7, 8, 9, 15, 16}, o{1, 2, 3, 4, 5, 9, 11}, d{5, 8, 10, 11, 12, 13, 14};
    const auto from_one = [](std::vector<std::size_t> v) {
      for (auto& i : v) --i;
      return v;
    };
    std::vector<std::size_t> all = from_one(n);
    for (const auto& part : {from_one(o), from_one(d)}) all.insert(all.end(), part.begin(), part.end());
    ins.subscales = {{"nausea", from_one(n), ScoreRule::sum, 9.54},
                     {"oculomotor", from_one(o), ScoreRule::sum, 7.58},
                     {"disorientation", from_one(d), ScoreRule::sum, 13.92},
                     {"total", all, ScoreRule::sum, 3.74}};
    return ins;
  }();
  return ssq;
}

std::int64_t scored_value(const Instrument& ins, std::size_t item, std::int64_t value) {
  if (!ins.items[item].reversed || ins.scale.empty()) return value;
  const auto [lo, hi] = std::minmax_element(ins.scale.begin(), ins.scale.end(),
                                            [](const ScalePoint& a, const ScalePoint& b) { return a.value < b.value; });
  return lo->value + hi->value - value;
}

std::vector<SubscaleResult> score(const Instrument& ins, const std::vector<std::optional<std::int64_t>>& values) {
  std::vector<SubscaleResult> out;
  for (const Subscale& s : ins.subscales) {
    SubscaleResult r{s.name, s.rule, s.weight, s.items.size(), 0, std::nullopt, std::nullopt};
    double sum = 0.0;
    for (const std::size_t i : s.items) {
      if (i >= values.size() || !values[i]) continue;
      ++r.answered;
      sum += static_cast<double>(scored_value(ins, i, *values[i]));
    }
    if (r.answered == r.items && r.items > 0) {
      r.raw = s.rule == ScoreRule::mean ? sum / static_cast<double>(r.items) : sum;
      r.score = s.weight * *r.raw;
    }
    out.push_back(std::move(r));
  }
  return out;
}

std::string item_page(const Instrument& ins, std::size_t item) {
  std::string page;
  if (!ins.title.empty()) (page += ins.title) += "\n\n";
  page += ins.items[item].text;
  page += "\n\n";
  for (std::size_t k = 0; k < ins.scale.size(); ++k) {
    if (k > 0) page += "   ";
    ((page += ins.scale[k].key) += ' ') += ins.scale[k].label;
  }
  return page;
}

}  // namespace curvlab::harness::protocol
