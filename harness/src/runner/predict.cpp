#include "curvlab/harness/runner/predict.hpp"

#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

namespace curvlab::harness::runner {

namespace {

// Regularized incomplete beta I_x(a, b) by its continued fraction (modified
// Lentz), using the symmetry I_x(a,b) = 1 − I_{1−x}(b,a) where it converges
// slowly (Abramowitz & Stegun 26.5.8).
double incomplete_beta(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  if (x > (a + 1.0) / (a + b + 2.0)) return 1.0 - incomplete_beta(b, a, 1.0 - x);
  const double log_front = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) +
                           b * std::log1p(-x);
  const double tiny = 1e-300;
  double c = 1.0;
  double d = 1.0 - (a + b) * x / (a + 1.0);
  d = std::abs(d) < tiny ? tiny : d;
  d = 1.0 / d;
  double f = d;
  for (int m = 1; m <= 300; ++m) {
    const double md = m;
    const double even = md * (b - md) * x / ((a + 2.0 * md - 1.0) * (a + 2.0 * md));
    d = 1.0 + even * d;
    d = std::abs(d) < tiny ? tiny : d;
    c = 1.0 + even / c;
    c = std::abs(c) < tiny ? tiny : c;
    d = 1.0 / d;
    f *= d * c;
    const double odd = -(a + md) * (a + b + md) * x / ((a + 2.0 * md) * (a + 2.0 * md + 1.0));
    d = 1.0 + odd * d;
    d = std::abs(d) < tiny ? tiny : d;
    c = 1.0 + odd / c;
    c = std::abs(c) < tiny ? tiny : c;
    d = 1.0 / d;
    const double delta = d * c;
    f *= delta;
    if (std::abs(delta - 1.0) < 1e-14) break;
  }
  return std::exp(log_front) * f / a;
}

// The mean observer's P(positive) in one staircase condition, as a function
// of the staircase's parameter; and the target crossings on [min, max].
void locate_target(const protocol::PlannedTrial& t, const protocol::Judgement& j, const World& world,
                   const SimulatedObserver& observer, bool physical, StaircasePrediction& out) {
  std::size_t positive = 0;
  for (std::size_t k = 0; k < j.options.size(); ++k)
    if (j.options[k].value == out.positive) positive = k;
  const geometry::Isometry head = standing_head(world, t.settings);  // the same for every value
  auto p_positive = [&](double x) {
    protocol::Settings s = t.settings;
    protocol::set_numeric_setting(s, j.parameter, x);
    const double perceived = physical ? physical_sagitta_m(s)
                                      : perceived_sagitta_m(world, s, place_stimulus(world, s, head), head);
    return observer.choice_probabilities(perceived, j.options.size())[positive];
  };
  constexpr int kSamples = 120;
  auto g = [&](double x) { return p_positive(x) - out.target_p; };
  double x0 = out.min;
  double g0 = g(x0);
  out.p_at_min = g0 + out.target_p;
  for (int i = 1; i <= kSamples; ++i) {
    const double x1 = out.min + (out.max - out.min) * i / kSamples;
    const double g1 = g(x1);
    if ((g0 < 0.0) != (g1 < 0.0) || g1 == 0.0) {
      ++out.crossings;
      if (!out.target_value) {
        double lo = x0, hi = x1, glo = g0;
        for (int it = 0; it < 50; ++it) {
          const double mid = 0.5 * (lo + hi);
          const double gm = g(mid);
          if ((gm < 0.0) == (glo < 0.0)) {
            lo = mid;
            glo = gm;
          } else {
            hi = mid;
          }
        }
        out.target_value = 0.5 * (lo + hi);
      }
    }
    x0 = x1;
    g0 = g1;
  }
  out.p_at_max = g0 + out.target_p;
}

std::int64_t binomial(protocol::Engine& rng, std::int64_t n, double p) {
  std::int64_t k = 0;
  for (std::int64_t i = 0; i < n; ++i) k += protocol::uniform01(rng) < p ? 1 : 0;
  return k;
}

}  // namespace

double student_t_two_sided_p(double t, double df) {
  if (!std::isfinite(t)) return 0.0;
  return incomplete_beta(df / 2.0, 0.5, df / (df + t * t));
}

namespace {

using PredictResult = Result<Prediction>;

Error predict_error(std::string message) { return Error{Error::Kind::usage, std::move(message)}; }

std::string condition_key(const protocol::PlannedTrial& t, const std::string& judged_name) {
  std::string key = t.block + "|" + judged_name;
  for (const auto& [f, l] : t.levels) key += "|" + f + "=" + l;
  return key;
}

std::string staircase_note(const StaircasePrediction& sp) {
  std::string label;
  for (const auto& [f, l] : sp.levels) label += (label.empty() ? "" : " ") + f + "=" + l;
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "block %s, %s, staircase %s: the value it converges on lies outside [%g, %g] "
                "(P(%s) is %.2f at %g and %.2f at %g; it targets %.2f): widen the range or change "
                "the stimulus",
                sp.block.c_str(), label.c_str(), sp.staircase.c_str(), sp.min, sp.max, sp.positive.c_str(),
                sp.p_at_min, sp.min, sp.p_at_max, sp.max, sp.target_p);
  return buf;
}

// Where each adaptive track of a condition converges for the mean observer.
Result<Done> predict_staircases(const protocol::Protocol& p, const protocol::PlannedTrial& t,
                                const std::string& judged_name, const SimulatedObserver& mean_observer,
                                bool physical, Prediction& out) {
  const protocol::Block* block = nullptr;
  for (const auto& b : p.blocks)
    if (b.name == t.block) block = &b;
  if (block == nullptr) return Done{};
  auto made = make_world(t.settings);
  if (!made) return made.error();
  const World world = std::move(made).value();
  const auto& j = block->judgement;
  for (const auto& track : j.type->convergence(j)) {
    StaircasePrediction sp;
    sp.block = t.block;
    sp.levels = t.levels;
    sp.judged = judged_name;
    sp.staircase = track.track;
    sp.parameter = j.parameter;
    sp.positive = track.positive;
    sp.rule = track.rule;
    sp.up = track.up;
    sp.down = track.down;
    sp.min = track.min;
    sp.max = track.max;
    sp.target_p = track.target_p;
    locate_target(t, j, world, mean_observer, physical, sp);
    if (!sp.target_value) out.notes.push_back(staircase_note(sp));
    out.staircases.push_back(std::move(sp));
  }
  return Done{};
}

// A choice condition: the judged quantity for a participant standing at the table.
Result<ConditionPrediction> predict_condition(const protocol::Protocol& p, const protocol::PlannedTrial& t,
                                              const std::string& judged_name, bool physical) {
  auto made = make_world(t.settings);
  if (!made) return made.error();
  const World world = std::move(made).value();
  const geometry::Isometry head = standing_head(world, t.settings);
  const Placement placement = place_stimulus(world, t.settings, head);
  ConditionPrediction c;
  c.levels = t.levels;
  c.judged = judged_name;
  c.perceived_m = physical ? physical_sagitta_m(t.settings) : perceived_sagitta_m(world, t.settings, placement, head);
  if (!physical) {
    const SightLineCount lines = diverging_sight_lines(world, t.settings, placement, head);
    c.diverging_points = lines.diverging;
    c.judged_points = lines.points;
  }
  for (const auto& b : p.blocks)
    if (b.name == t.block)
      for (const auto& opt : b.judgement.options) c.options.push_back(opt.value);
  return c;
}

// "a, b and c".
std::string listed(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  return out;
}

// "adjustment blocks are not predicted (choice and staircase only)".
std::string not_predicted_note() {
  std::vector<std::string> not_predicted, predicted;
  for (const auto* type : protocol::judgement_types())
    (type->forecast() == protocol::Forecast::none ? not_predicted : predicted).emplace_back(type->name());
  return listed(not_predicted) + " blocks are not predicted (" + listed(predicted) + " only)";
}

// The distinct conditions of participant 1's design (every participant sees
// the same conditions; only order and counterbalancing differ).
Result<Done> collect_conditions(const protocol::Protocol& p, const PredictOptions& o, Prediction& out) {
  const protocol::Design design = protocol::expand_design(p, 1);
  std::map<std::string, std::size_t> index;  // condition key → out.conditions
  std::map<std::string, bool> adaptive_seen;
  const SimulatedObserver mean_observer(o.observer);
  const bool physical = o.observer.model == ObserverModel::physical;
  bool skipped_other = false;
  for (const auto& t : design.trials) {
    if (t.practice) continue;
    const std::string judged_name = judged(t.settings) == Judged::stick ? "stick" : "table";
    const std::string key = condition_key(t, judged_name);
    const protocol::Forecast forecast = t.judgement->forecast();
    if (forecast == protocol::Forecast::convergence) {
      if (!adaptive_seen.emplace(key, true).second) continue;
      if (auto r = predict_staircases(p, t, judged_name, mean_observer, physical, out); !r) return r.error();
      continue;
    }
    if (forecast == protocol::Forecast::none) {
      skipped_other = true;
      continue;
    }
    auto it = index.find(key);
    if (it == index.end()) {
      auto c = predict_condition(p, t, judged_name, physical);
      if (!c) return c.error();
      it = index.emplace(key, out.conditions.size()).first;
      if (c.value().diverging_points > 0) {
        std::string label;
        for (const auto& [f, l] : c.value().levels) label += (label.empty() ? "" : " ") + f + "=" + l;
        char text[400];
        std::snprintf(text, sizeof text,
                      "%s (%s): a tourist sees %d of its %d judged points only along diverging or parallel "
                      "lines of sight (S3, beyond the quarter circumference); the model meets them behind the "
                      "eyes, so s = %+.3g m is ill-conditioned (where nearly parallel lines meet, a few hundredths "
                      "of a pixel of disparity can change its sign). Place the stimulus nearer than the quarter "
                      "circumference for this view",
                      label.c_str(), c.value().judged.c_str(), c.value().diverging_points, c.value().judged_points,
                      c.value().perceived_m);
        out.notes.emplace_back(text);
      }
      out.conditions.push_back(std::move(c).value());
    }
    ++out.conditions[it->second].trials_per_participant;
  }
  if (skipped_other) out.notes.push_back(not_predicted_note());
  return Done{};
}

// Participants drawn from the population around the mean observer.
class Population {
 public:
  explicit Population(const PredictOptions& o)
      : o_(o), rng_(protocol::mix_seed(o.observer.seed ^ 0x70726564696374ULL)) {}
  ObserverParams draw() {
    ObserverParams q = o_.observer;
    q.bias_m += o_.bias_sd_m * standard_normal(rng_);
    q.slope_per_m *= std::exp(o_.slope_sd_log * standard_normal(rng_));
    return q;
  }
  protocol::Engine& rng() { return rng_; }

 private:
  const PredictOptions& o_;
  protocol::Engine rng_;
};

// Expected proportions per condition: the mean over 400 drawn participants.
void expected_proportions(Population& population, Prediction& out) {
  constexpr int n = 400;
  for (auto& c : out.conditions) c.proportions.assign(c.options.size(), 0.0);
  std::vector<ObserverParams> people;
  for (int k = 0; k < n; ++k) people.push_back(population.draw());
  for (const auto& q : people) {
    SimulatedObserver obs(q);
    for (auto& c : out.conditions) {
      const auto probs = obs.choice_probabilities(c.perceived_m, c.options.size());
      for (std::size_t k = 0; k < probs.size(); ++k) c.proportions[k] += probs[k] / n;
    }
  }
}

std::string level_of(const ConditionPrediction& c, const std::string& f) {
  for (const auto& [name, label] : c.levels)
    if (name == f) return label;
  return {};
}

// One simulated study: the paired difference in P(first option) between
// levels a and b, tested with Student's t. True when significant.
bool simulated_study_significant(Population& population, const Prediction& out, const PredictOptions& o,
                                 const std::string& f, const std::string& a, const std::string& b) {
  double sum = 0.0, sum2 = 0.0;
  for (int k = 0; k < o.participants; ++k) {
    const SimulatedObserver obs(population.draw());
    double na = 0.0, ka = 0.0, nb = 0.0, kb = 0.0;
    for (const auto& c : out.conditions) {
      const auto l = level_of(c, f);
      if (l != a && l != b) continue;
      const double pf = obs.choice_probabilities(c.perceived_m, c.options.size())[0];
      const auto hits = static_cast<double>(binomial(population.rng(), c.trials_per_participant, pf));
      const auto trials = static_cast<double>(c.trials_per_participant);
      if (l == a) {
        na += trials;
        ka += hits;
      } else {
        nb += trials;
        kb += hits;
      }
    }
    const double d = ka / na - kb / nb;
    sum += d;
    sum2 += d * d;
  }
  const double n = o.participants;
  const double mean = sum / n;
  const double var = (sum2 - n * mean * mean) / (n - 1.0);
  const double t =
      var > 0.0 ? mean / std::sqrt(var / n) : (mean != 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
  return student_t_two_sided_p(t, n - 1.0) < o.alpha;
}

// The two levels of factor f to compare: the options' when given, else the
// pair whose predicted P(first option) differs most.
Result<std::pair<std::string, std::string>> levels_to_compare(
    const std::map<std::string, std::pair<double, double>>& by_level, const PredictOptions& o, const std::string& f) {
  std::string a = o.level_a, b = o.level_b;
  if (!o.factor.empty() && (!by_level.count(a) || !by_level.count(b)))
    return predict_error("factor \"" + f + "\" has no choice trials at level \"" + (by_level.count(a) ? b : a) + "\"");
  if (a.empty()) {
    double best = -1.0;
    for (const auto& [la, va] : by_level)
      for (const auto& [lb, vb] : by_level) {
        const double d = std::abs(va.first / va.second - vb.first / vb.second);
        if (la < lb && d > best) {
          best = d;
          a = la;
          b = lb;
        }
      }
  }
  return std::pair{a, b};
}

// Power to detect factor f's effect on P(first option); nullopt when f has
// fewer than two levels among the choice trials (and was not asked for).
Result<std::optional<PowerEstimate>> estimate_power(Population& population, const Prediction& out,
                                                    const PredictOptions& o, const std::string& f) {
  std::map<std::string, std::pair<double, double>> by_level;  // label → (sum P, count)
  for (const auto& c : out.conditions) {
    const auto l = level_of(c, f);
    if (l.empty() || c.proportions.empty()) continue;
    by_level[l].first += c.proportions[0];
    by_level[l].second += 1.0;
  }
  if (by_level.size() < 2) {
    if (!o.factor.empty()) return predict_error("factor \"" + f + "\" has fewer than two levels among the choice trials");
    return std::optional<PowerEstimate>{};
  }
  auto levels = levels_to_compare(by_level, o, f);
  if (!levels) return levels.error();
  const auto& [a, b] = levels.value();
  PowerEstimate pe;
  pe.factor = f;
  pe.level_a = a;
  pe.level_b = b;
  pe.predicted_difference = by_level.at(a).first / by_level.at(a).second - by_level.at(b).first / by_level.at(b).second;
  pe.simulations = o.simulations;
  int significant = 0;
  for (int sim = 0; sim < o.simulations; ++sim)
    if (simulated_study_significant(population, out, o, f, a, b)) ++significant;
  pe.power = static_cast<double>(significant) / o.simulations;
  return std::optional<PowerEstimate>{pe};
}

}  // namespace

Result<Prediction> predict(const protocol::Protocol& p, const PredictOptions& o) {
  if (o.participants < 2) return predict_error("--participants must be at least 2");
  if (o.simulations < 1) return predict_error("--simulations must be at least 1");
  if (auto ok = check_observer(o.observer); !ok) return predict_error("observer: " + ok.error().message);
  Prediction out;
  out.participants = o.participants;
  if (auto r = collect_conditions(p, o, out); !r) return r.error();
  if (out.conditions.empty() && out.staircases.empty())
    return predict_error("the protocol has no choice or staircase trials outside practice to predict");
  if (out.conditions.empty()) return out;
  Population population(o);
  expected_proportions(population, out);
  std::vector<std::string> factors;
  if (!o.factor.empty()) factors.push_back(o.factor);
  else
    for (const auto& f : p.factors) factors.push_back(f.name);
  for (const auto& f : factors) {
    auto pe = estimate_power(population, out, o, f);
    if (!pe) return pe.error();
    if (pe.value()) out.power.push_back(*pe.value());
  }
  return out;
}

}  // namespace curvlab::harness::runner
