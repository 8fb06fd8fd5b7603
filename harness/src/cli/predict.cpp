// `curvlab predict`: expected response proportions and power of a protocol
// from the simulated observer, before a study runs.
#include "common.hpp"
#include "observer_args.hpp"

#include "curvlab/harness/runner/stimulus_checks.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/predict.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>
#include <string>

namespace curvlab::harness::cli {
namespace {

namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;

struct PredictArgs {
  std::string protocol;
  int participants = 20;
  int simulations = 400;
  std::string effect;
  ObserverArgs observer;
  double bias_sd_m = 0.004;
  bool json = false;
};

// --effect FACTOR:LEVEL_A,LEVEL_B: the effect whose power is estimated.
void set_effect(const std::string& effect, const pr::Protocol& p, rn::PredictOptions& o) {
  const auto colon = effect.find(':');
  const auto comma = effect.find(',', colon == std::string::npos ? 0 : colon);
  if (colon == std::string::npos || comma == std::string::npos)
    throw UsageError("--effect expects FACTOR:LEVEL_A,LEVEL_B (e.g. view:native,tourist), got '" + effect + "'");
  o.factor = effect.substr(0, colon);
  o.level_a = effect.substr(colon + 1, comma - colon - 1);
  o.level_b = effect.substr(comma + 1);
  if (!p.find_factor(o.factor)) throw UsageError("--effect: the protocol has no factor \"" + o.factor + "\"");
}

rn::PredictOptions predict_options(const PredictArgs& a, const pr::Protocol& p) {
  rn::PredictOptions o;
  o.participants = a.participants;
  o.simulations = a.simulations;
  o.bias_sd_m = a.bias_sd_m;
  if (!(a.bias_sd_m >= 0.0 && a.bias_sd_m < 1.0)) throw UsageError("--bias-sd-m must lie in [0, 1) m");
  auto obs = observer_params(a.observer, a.observer.seed.value_or(1));
  if (!obs) throw UsageError("predict needs a simulated observer (--observer none makes no sense here)");
  o.observer = *obs;
  if (!a.effect.empty()) set_effect(a.effect, p, o);
  return o;
}

Json condition_json(const rn::ConditionPrediction& c) {
  Json cj;
  for (const auto& [f, l] : c.levels) cj[f] = l;
  cj["judged"] = c.judged;
  cj["trials_per_participant"] = c.trials_per_participant;
  cj["perceived_sagitta_m"] = c.perceived_m;
  cj["noise_sd_m"] = c.noise_sd_m;
  if (c.human) cj["human"] = Json::parse(rn::human_account_json(*c.human));
  cj["diverging_sight_lines"] = c.diverging_points;
  Json props;
  for (std::size_t k = 0; k < c.options.size(); ++k) props[c.options[k]] = c.proportions[k];
  cj["proportions"] = props;
  return cj;
}

Json staircase_json(const rn::StaircasePrediction& sp) {
  Json sj;
  sj["block"] = sp.block;
  for (const auto& [f, l] : sp.levels) sj[f] = l;
  sj["judged"] = sp.judged;
  sj["staircase"] = sp.staircase;
  sj["parameter"] = sp.parameter;
  sj["rule"] = sp.rule;
  sj["target_p_" + sp.positive] = sp.target_p;
  sj["range"] = Json::array({sp.min, sp.max});
  sj["converges_on"] = sp.target_value ? Json(*sp.target_value) : Json(nullptr);
  sj["p_at_min"] = sp.p_at_min;
  sj["p_at_max"] = sp.p_at_max;
  sj["crossings"] = sp.crossings;
  return sj;
}

Json prediction_json(const pr::Protocol& p, const rn::PredictOptions& o, const rn::Prediction& pred) {
  Json doc;
  doc["protocol"] = p.meta.name;
  doc["participants"] = pred.participants;
  doc["observer"] = Json::parse(rn::observer_json(o.observer));
  doc["bias_sd_m"] = o.bias_sd_m;
  Json conds = Json::array();
  for (const auto& c : pred.conditions) conds.push_back(condition_json(c));
  doc["conditions"] = conds;
  Json power = Json::array();
  for (const auto& pe : pred.power)
    power.push_back({{"factor", pe.factor}, {"level_a", pe.level_a}, {"level_b", pe.level_b},
                     {"measure", pe.measure}, {"predicted_difference", pe.predicted_difference}, {"power", pe.power},
                     {"simulations", pe.simulations}, {"test", "paired t, two-sided, alpha 0.05"}});
  doc["power"] = power;
  Json stairs = Json::array();
  for (const auto& sp : pred.staircases) stairs.push_back(staircase_json(sp));
  doc["staircases"] = stairs;
  doc["notes"] = pred.notes;
  Json warnings = Json::array();
  for (const auto& w : rn::stimulus_warnings(p))
    warnings.push_back({{"kind", rn::to_string(w.kind)}, {"block", w.block}, {"condition", w.condition},
                        {"message", w.message}});
  doc["warnings"] = warnings;
  return doc;
}

// "factor=level factor=level " for a condition's label.
std::string levels_label(const std::vector<std::pair<std::string, std::string>>& levels) {
  std::string label;
  for (const auto& [f, l] : levels) label += f + "=" + l + " ";
  return label;
}

void print_staircase(const rn::StaircasePrediction& sp) {
  const std::string label = sp.block + " " + levels_label(sp.levels);
  std::printf("  %-40s %-12s %s %4.1f%% %s: ", label.c_str(), sp.staircase.c_str(), sp.rule.c_str(),
              100.0 * sp.target_p, sp.positive.c_str());
  if (sp.target_value)
    std::printf("%s = %+.4f in [%g, %g]%s\n", sp.parameter.c_str(), *sp.target_value, sp.min, sp.max,
                sp.crossings > 1 ? " (not monotone: more than one crossing)" : "");
  else
    std::printf("outside [%g, %g]\n", sp.min, sp.max);
}

void print_condition(const rn::ConditionPrediction& c) {
  std::printf("  %-52s %-5s %+8.4f", levels_label(c.levels).c_str(), c.judged.c_str(), c.perceived_m);
  if (c.human)
    std::printf(" %+8.0f %6.0f %+7.2f %-5s %5.2f", c.human->signal_arcsec, c.human->threshold_arcsec, c.human->d_prime,
                c.human->fused ? "yes" : "no", c.human->perceived_distance_m);
  for (std::size_t k = 0; k < c.options.size(); ++k) std::printf(" %s %.2f", c.options[k].c_str(), c.proportions[k]);
  std::printf("\n");
}

void print_prediction(const pr::Protocol& p, const rn::Prediction& pred) {
  if (!pred.conditions.empty()) {
    std::printf("%s: expected response proportions, %d participants\n", p.meta.name.c_str(), pred.participants);
    const bool human = pred.conditions.front().human.has_value();
    std::printf("  %-52s %-5s %8s", "condition", "", "s (m)");
    if (human) std::printf(" %8s %6s %7s %-5s %5s", "signal\"", "thr\"", "d'", "fused", "D' m");
    std::printf(" proportions\n");
    if (human)
      std::printf("  (s: perceived sagitta; signal: the disparity it amounts to at the perceived distance D'; thr: "
                  "stereo threshold; arcseconds)\n");
  }
  for (const auto& c : pred.conditions) print_condition(c);
  if (!pred.staircases.empty())
    std::printf("adaptive tracks: the value each converges on for the mean observer (m-up/n-down target, Levitt "
                "1971; psi: the 50 %% point its PSE estimate approaches)\n");
  for (const auto& sp : pred.staircases) print_staircase(sp);
  if (!pred.power.empty()) std::printf("power (level a vs b, paired t across participants, alpha 0.05):\n");
  for (const auto& pe : pred.power)
    std::printf("  %-12s %s vs %s: %s difference %+.4g, power %.2f (%d simulated studies)\n", pe.factor.c_str(),
                pe.level_a.c_str(), pe.level_b.c_str(), pe.measure.c_str(), pe.predicted_difference, pe.power,
                pe.simulations);
  for (const auto& n : pred.notes) std::printf("note: %s\n", n.c_str());
  for (const auto& w : rn::stimulus_warnings(p)) std::printf("warning: %s\n", w.message.c_str());
}

void predict_command(const PredictArgs& a) {
  const pr::Protocol p = load_protocol_or_usage(a.protocol);
  const rn::PredictOptions o = predict_options(a, p);
  auto r = rn::predict(p, o);
  if (!r) raise(r.error());
  const auto& pred = r.value();
  const Json doc = prediction_json(p, o, pred);
  if (a.json) {
    print_result(doc, true);
    return;
  }
  print_prediction(p, pred);
}

}  // namespace

void add_predict_command(CLI::App& app) {
  auto pa = std::make_shared<PredictArgs>();
  auto* p = app.add_subcommand("predict", "expected response proportions and power from the simulated observer");
  p->add_option("protocol", pa->protocol, "protocol file (TOML)")->required();
  p->add_option("--participants", pa->participants, "participants per simulated study (default 20)");
  p->add_option("--simulations", pa->simulations, "simulated studies for the power (default 400)");
  p->add_option("--effect", pa->effect, "the effect to test, FACTOR:LEVEL_A,LEVEL_B (default: every factor)");
  p->add_option("--bias-sd-m", pa->bias_sd_m, "between-participant SD of the bias (default 0.004 m)");
  add_observer_options(p, pa->observer);
  p->add_flag("--json", pa->json, "print JSON");
  p->callback([pa] { predict_command(*pa); });
}

}  // namespace curvlab::harness::cli
