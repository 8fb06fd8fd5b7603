#include "curvlab/harness/runner/predict.hpp"

#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <functional>
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

// printf into a string of whatever length it needs.
[[gnu::format(printf, 1, 2)]] std::string formatted(const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  std::va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  std::string out(static_cast<std::size_t>(std::max(n, 0)), '\0');
  std::vsnprintf(out.data(), out.size() + 1, format, again);
  va_end(again);
  return out;
}

Error predict_error(std::string message) { return Error{Error::Kind::usage, std::move(message)}; }

// "factor=level factor=level".
std::string label_of(const std::vector<std::pair<std::string, std::string>>& levels) {
  std::string label;
  for (const auto& [f, l] : levels) label += (label.empty() ? "" : " ") + f + "=" + l;
  return label;
}

// One condition of the design (a block's cell) and what its percepts need:
// the world and the head of a participant standing at the table; the
// percepts of the values an adaptive method shows, computed once each.
struct Condition {
  const protocol::Block* block = nullptr;
  protocol::PlannedTrial first;  // its first trial in participant 1's design
  std::vector<protocol::PlannedTrial> trials;  // every slot, in run order (adaptive tracks)
  std::string judged;
  World world;
  geometry::Isometry head;
  std::map<double, Percept> by_value;

  // The mean observer's percept of the trial's stimulus, or of it with the
  // judgement's parameter set to `value`.
  const Percept& percept(const ObserverParams& observer, std::optional<double> value = std::nullopt) {
    if (!value) {
      if (!onset) onset = perceive(world, first.settings, place_stimulus(world, first.settings, head), head, observer);
      return *onset;
    }
    auto it = by_value.find(*value);
    if (it == by_value.end()) {
      protocol::Settings s = first.settings;
      protocol::set_numeric_setting(s, block->judgement.parameter, *value);
      it = by_value.emplace(*value, perceive(world, s, place_stimulus(world, s, head), head, observer)).first;
    }
    return it->second;
  }
  std::optional<Percept> onset;
};

// Sort key: block order, then each factor's level order (the protocol's).
std::vector<std::size_t> order_key(const protocol::Protocol& p, std::size_t protocol_block,
                                   const std::vector<std::pair<std::string, std::string>>& levels) {
  std::vector<std::size_t> key;
  key.push_back(protocol_block);
  for (const auto& f : p.factors) {
    std::size_t index = f.levels.size();
    for (const auto& [name, label] : levels)
      if (name == f.name)
        for (std::size_t k = 0; k < f.levels.size(); ++k)
          if (f.levels[k].label == label) index = k;
    key.push_back(index);
  }
  return key;
}

// P(an answer counted positive) for the percept, from the options' shares.
double p_positive(const SimulatedObserver& observer, const protocol::Judgement& j,
                  const protocol::AdaptiveState& state, const Percept& percept, double noise_scale) {
  const auto probs =
      observer.choice_probabilities(percept.sagitta_m, j.options.size(), percept.noise_sd_m * noise_scale);
  double p = 0.0;
  for (std::size_t k = 0; k < probs.size(); ++k) p += state.positive(j.options[k].value) ? probs[k] : 0.0;
  return p;
}

// The mean observer's P(positive) in one adaptive condition, as a function
// of the judgement's parameter; and the target crossings on [min, max].
void locate_target(Condition& c, const SimulatedObserver& observer, StaircasePrediction& out) {
  const auto& j = c.block->judgement;
  const auto state = j.type->adaptive_state(j);
  auto g = [&](double x) {
    return p_positive(observer, j, *state, c.percept(observer.params(), x), 1.0) - out.target_p;
  };
  constexpr int kSamples = 120;
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

std::string staircase_note(const StaircasePrediction& sp) {
  return formatted("block %s, %s, %s: the value it converges on lies outside [%g, %g] (P(%s) is %.2f at %g and "
                   "%.2f at %g; it targets %.2f): widen the range or change the stimulus",
                   sp.block.c_str(), label_of(sp.levels).c_str(), sp.staircase.c_str(), sp.min, sp.max,
                   sp.positive.c_str(), sp.p_at_min, sp.min, sp.p_at_max, sp.max, sp.target_p);
}

// Where each adaptive track of a condition converges for the mean observer.
void predict_tracks(Condition& c, const SimulatedObserver& mean_observer, Prediction& out) {
  const auto& j = c.block->judgement;
  for (const auto& track : j.type->convergence(j)) {
    StaircasePrediction sp;
    sp.block = c.first.block;
    sp.levels = c.first.levels;
    sp.judged = c.judged;
    sp.staircase = track.track;
    sp.parameter = j.parameter;
    sp.positive = track.positive;
    sp.rule = track.rule;
    sp.up = track.up;
    sp.down = track.down;
    sp.min = track.min;
    sp.max = track.max;
    sp.target_p = track.target_p;
    locate_target(c, mean_observer, sp);
    if (!sp.target_value) out.notes.push_back(staircase_note(sp));
    out.staircases.push_back(std::move(sp));
  }
}

// A choice condition as the mean observer perceives it.
ConditionPrediction predict_condition(Condition& c, const ObserverParams& observer) {
  ConditionPrediction out;
  out.levels = c.first.levels;
  out.judged = c.judged;
  const Percept& percept = c.percept(observer);
  out.perceived_m = percept.sagitta_m;
  out.noise_sd_m = percept.noise_sd_m;
  out.human = percept.human;
  if (observer.model == ObserverModel::triangulation) {
    const auto& s = c.first.settings;
    const SightLineCount lines = diverging_sight_lines(c.world, s, place_stimulus(c.world, s, c.head), c.head);
    out.diverging_points = lines.diverging;
    out.judged_points = lines.points;
  }
  for (const auto& opt : c.block->judgement.options) out.options.push_back(opt.value);
  return out;
}

std::string diverging_note(const ConditionPrediction& c) {
  return formatted("%s (%s): a tourist sees %d of its %d judged points only along diverging or parallel lines of "
                   "sight (S3, beyond the quarter circumference); the triangulation model meets them behind the "
                   "eyes, so s = %+.3g m is ill-conditioned (where nearly parallel lines meet, a few hundredths of "
                   "a pixel of disparity can change its sign). The human model (the default) reads such a stimulus "
                   "from its relative disparities at a finite perceived distance",
                   label_of(c.levels).c_str(), c.judged.c_str(), c.diverging_points, c.judged_points, c.perceived_m);
}

std::string double_note(const ConditionPrediction& c) {
  return formatted("%s (%s): seen double — a disparity %.1f times the fusional limit (the eyes asked to verge "
                   "%+.1f arcmin, %+.1f beyond their reach); the observer answers from monocular information, as "
                   "with one eye",
                   label_of(c.levels).c_str(), c.judged.c_str(), c.human->worst_fusion,
                   c.human->vergence_demand_arcmin, c.human->pedestal_arcmin);
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

// The adaptive pool's size: this many participants per participant of a
// study, and at least the minimum.
constexpr int kAdaptivePoolPerParticipant = 3;
constexpr int kAdaptivePoolMin = 60;

// Participants drawn from the population around the mean observer: bias,
// and the scale of the noise (slope and stereo threshold together).
struct Participant {
  SimulatedObserver observer;
  double noise_scale = 1.0;  // this participant's noise SD over the mean observer's
};

class Population {
 public:
  explicit Population(const PredictOptions& o)
      : o_(o), rng_(protocol::mix_seed(o.observer.seed ^ 0x70726564696374ULL)) {}
  Participant draw() {
    ObserverParams q = o_.observer;
    q.bias_m += o_.bias_sd_m * standard_normal(rng_);
    const double scale = std::exp(o_.slope_sd_log * standard_normal(rng_));
    q.slope_per_m *= scale;
    q.vision.threshold_arcsec /= scale;
    return {SimulatedObserver(q), 1.0 / scale};
  }
  protocol::Engine& rng() { return rng_; }

 private:
  const PredictOptions& o_;
  protocol::Engine rng_;
};

// Everything predict works on: the distinct conditions of participant 1's
// design (every participant sees the same conditions; only order and
// counterbalancing differ), choice and adaptive apart, in protocol order.
struct Conditions {
  std::vector<Condition> choice;    // parallel to Prediction::conditions
  std::vector<Condition> adaptive;
};

Result<Conditions> collect_conditions(const protocol::Protocol& p, Prediction& out) {
  const protocol::Design design = protocol::expand_design(p, 1);
  std::map<std::vector<std::size_t>, Condition> choice, adaptive;
  bool skipped_other = false;
  bool skipped_kind = false;
  for (const auto& t : design.trials) {
    if (t.practice) continue;
    // A play or questionnaire block's one trial is not a judgement.
    if (p.blocks.at(t.protocol_block).kind != "trials") {
      skipped_kind = true;
      continue;
    }
    const protocol::Forecast forecast = t.judgement->forecast();
    if (forecast == protocol::Forecast::none) {
      skipped_other = true;
      continue;
    }
    auto key = order_key(p, t.protocol_block, t.levels);
    key.push_back(judged_index(t.settings));
    auto& into = forecast == protocol::Forecast::convergence ? adaptive : choice;
    auto it = into.find(key);
    if (it == into.end()) {
      Condition c;
      c.block = &p.blocks.at(t.protocol_block);
      c.first = t;
      c.judged = std::string(judged_kind(t.settings).name());
      auto made = make_world(t.settings);
      if (!made) return made.error();
      c.world = std::move(made).value();
      c.head = standing_head(c.world, t.settings);
      it = into.emplace(key, std::move(c)).first;
    }
    it->second.trials.push_back(t);
  }
  if (skipped_other) out.notes.push_back(not_predicted_note());
  if (skipped_kind) out.notes.push_back("play and questionnaire blocks are not predicted (they ask no judgement)");
  Conditions all;
  for (auto& [key, c] : choice) all.choice.push_back(std::move(c));
  for (auto& [key, c] : adaptive) all.adaptive.push_back(std::move(c));
  return all;
}

// Expected proportions per condition: the mean over 400 drawn participants.
void expected_proportions(Population& population, Prediction& out) {
  constexpr int n = 400;
  for (auto& c : out.conditions) c.proportions.assign(c.options.size(), 0.0);
  for (int k = 0; k < n; ++k) {
    const Participant who = population.draw();
    for (auto& c : out.conditions) {
      const auto probs =
          who.observer.choice_probabilities(c.perceived_m, c.options.size(), c.noise_sd_m * who.noise_scale);
      for (std::size_t i = 0; i < probs.size(); ++i) c.proportions[i] += probs[i] / n;
    }
  }
}

std::string level_of(const std::vector<std::pair<std::string, std::string>>& levels, const std::string& f) {
  for (const auto& [name, label] : levels)
    if (name == f) return label;
  return {};
}

std::int64_t binomial(protocol::Engine& rng, std::int64_t n, double p) {
  std::int64_t k = 0;
  for (std::int64_t i = 0; i < n; ++i) k += protocol::uniform01(rng) < p ? 1 : 0;
  return k;
}

// A participant's measure at levels a and b of a factor.
struct LevelSums {
  double a = 0.0, na = 0.0, b = 0.0, nb = 0.0;
  void add(bool at_a, double value, double weight) {
    (at_a ? a : b) += value;
    (at_a ? na : nb) += weight;
  }
  [[nodiscard]] double difference() const { return a / na - b / nb; }
};

// The factor and levels compared, with what the comparison measures.
struct Effect {
  std::string factor, a, b;
};

// One participant's proportion of the first option at a minus at b.
double choice_difference(const Participant& who, const Prediction& out, const Effect& e, protocol::Engine& rng) {
  LevelSums sums;
  for (const auto& c : out.conditions) {
    const auto l = level_of(c.levels, e.factor);
    if (l != e.a && l != e.b) continue;
    const double pf =
        who.observer.choice_probabilities(c.perceived_m, c.options.size(), c.noise_sd_m * who.noise_scale)[0];
    sums.add(l == e.a, static_cast<double>(binomial(rng, c.trials_per_participant, pf)),
             static_cast<double>(c.trials_per_participant));
  }
  return sums.difference();
}

// One participant's adaptive tracks in one condition, trial by trial through
// the judgement type: the mean value shown over the second half of its
// trials (what the tracks settle on).
double settled_value(Condition& c, const Participant& who, const ObserverParams& mean, protocol::Engine& rng) {
  const auto& j = c.block->judgement;
  const auto state = j.type->adaptive_state(j);
  std::vector<double> shown;
  for (const auto& t : c.trials) {
    if (state->skip_reason(t)) continue;
    const double x = state->value(t);
    const double p = p_positive(who.observer, j, *state, c.percept(mean, x), who.noise_scale);
    const bool positive = protocol::uniform01(rng) < p;
    state->record(t, positive);
    shown.push_back(x);
  }
  if (shown.empty()) return 0.0;
  const std::size_t from = shown.size() / 2;
  double sum = 0.0;
  for (std::size_t i = from; i < shown.size(); ++i) sum += shown[i];
  return sum / static_cast<double>(shown.size() - from);
}

// Simulated participants run once through every adaptive condition (an
// adaptive method can cost a millisecond a trial, so studies draw their
// participants from this pool rather than simulating each afresh): each
// row holds one participant's settled value per condition.
struct AdaptivePool {
  std::vector<std::vector<double>> settled;
};

AdaptivePool simulate_pool(Population& population, std::vector<Condition>& conditions, const PredictOptions& o) {
  AdaptivePool pool;
  const int size = std::max(kAdaptivePoolMin, kAdaptivePoolPerParticipant * o.participants);
  for (int k = 0; k < size; ++k) {
    const Participant who = population.draw();
    std::vector<double> row;
    for (auto& c : conditions) row.push_back(settled_value(c, who, o.observer, population.rng()));
    pool.settled.push_back(std::move(row));
  }
  return pool;
}

// A participant of the pool's settled value at level a minus at b.
double adaptive_difference(const std::vector<double>& settled, const std::vector<Condition>& conditions,
                           const Effect& e) {
  LevelSums sums;
  for (std::size_t i = 0; i < conditions.size(); ++i) {
    const auto l = level_of(conditions[i].first.levels, e.factor);
    if (l != e.a && l != e.b) continue;
    sums.add(l == e.a, settled[i], 1.0);
  }
  return sums.difference();
}

// The paired differences of one simulated study, tested with Student's t.
// True when significant; `mean_difference` accumulates the study's mean.
bool significant(const std::vector<double>& d, double alpha, double& mean_difference) {
  const double n = static_cast<double>(d.size());
  double sum = 0.0, sum2 = 0.0;
  for (const double x : d) {
    sum += x;
    sum2 += x * x;
  }
  const double mean = sum / n;
  mean_difference += mean;
  const double var = (sum2 - n * mean * mean) / (n - 1.0);
  const double t =
      var > 0.0 ? mean / std::sqrt(var / n) : (mean != 0.0 ? std::numeric_limits<double>::infinity() : 0.0);
  return student_t_two_sided_p(t, n - 1.0) < alpha;
}

// The levels of factor f present among `levels_seen` (each condition's),
// with the measure's mean per level where known, to pick the pair to
// compare: the options' when given, else the pair whose means differ most.
Result<std::optional<Effect>> effect_for(const std::map<std::string, std::pair<double, double>>& by_level,
                                         const PredictOptions& o, const std::string& f) {
  if (by_level.size() < 2 && o.factor.empty()) return std::optional<Effect>{};
  if (!o.factor.empty()) {
    for (const auto* l : {&o.level_a, &o.level_b})
      if (!by_level.count(*l)) return std::optional<Effect>{};
    return std::optional<Effect>{Effect{f, o.level_a, o.level_b}};
  }
  Effect best{f, {}, {}};
  double widest = -1.0;
  for (const auto& [la, va] : by_level)
    for (const auto& [lb, vb] : by_level) {
      const double d = std::abs(va.first / va.second - vb.first / vb.second);
      if (la < lb && d > widest) {
        widest = d;
        best.a = la;
        best.b = lb;
      }
    }
  return std::optional<Effect>{best};
}

// Simulated studies of o.participants participants, each giving its paired
// difference (`one_participant` draws a participant and returns theirs).
PowerEstimate power_of(const Effect& e, std::string measure, const PredictOptions& o,
                       const std::function<double()>& one_participant) {
  PowerEstimate pe{e.factor, e.a, e.b, std::move(measure), 0.0, 0.0, o.simulations};
  int hits = 0;
  double mean_difference = 0.0;
  for (int sim = 0; sim < o.simulations; ++sim) {
    std::vector<double> d;
    for (int k = 0; k < o.participants; ++k) d.push_back(one_participant());
    if (significant(d, o.alpha, mean_difference)) ++hits;
  }
  pe.power = static_cast<double>(hits) / o.simulations;
  pe.predicted_difference = mean_difference / o.simulations;
  return pe;
}

// Power to detect factor f's effect: on P(first option) among the choice
// conditions, and on the settled value among the adaptive ones; none when
// f has fewer than two levels among either (an error when it was asked for).
Result<Done> estimate_power(Population& population, Prediction& out, Conditions& conditions, const PredictOptions& o,
                            const std::string& f, std::optional<AdaptivePool>& pool) {
  std::map<std::string, std::pair<double, double>> choice_levels, adaptive_levels;  // label → (sum, count)
  for (const auto& c : out.conditions)
    if (const auto l = level_of(c.levels, f); !l.empty() && !c.proportions.empty()) {
      choice_levels[l].first += c.proportions[0];
      choice_levels[l].second += 1.0;
    }
  for (const auto& sp : out.staircases)
    if (const auto l = level_of(sp.levels, f); !l.empty()) {
      adaptive_levels[l].first += sp.target_value.value_or(0.5 * (sp.min + sp.max));
      adaptive_levels[l].second += 1.0;
    }
  auto choice = effect_for(choice_levels, o, f);
  auto adaptive = effect_for(adaptive_levels, o, f);
  if (!choice) return choice.error();
  if (!adaptive) return adaptive.error();
  if (!o.factor.empty() && !choice.value() && !adaptive.value())
    return predict_error("--effect: factor \"" + f + "\" has no choice or adaptive trials outside practice at both " +
                         "levels \"" + o.level_a + "\" and \"" + o.level_b + "\"");
  if (const auto& e = choice.value())
    out.power.push_back(power_of(*e, "P(first option)", o, [&] {
      return choice_difference(population.draw(), out, *e, population.rng());
    }));
  if (const auto& e = adaptive.value()) {
    std::string measure = conditions.adaptive.front().block->judgement.parameter;
    if (!pool) pool = simulate_pool(population, conditions.adaptive, o);
    out.power.push_back(power_of(*e, measure, o, [&] {
      const auto k = static_cast<std::size_t>(protocol::uniform01(population.rng()) *
                                              static_cast<double>(pool->settled.size()));
      return adaptive_difference(pool->settled[std::min(k, pool->settled.size() - 1)], conditions.adaptive, *e);
    }));
  }
  return Done{};
}

}  // namespace

double student_t_two_sided_p(double t, double df) {
  if (!std::isfinite(t)) return 0.0;
  return incomplete_beta(df / 2.0, 0.5, df / (df + t * t));
}

Result<Prediction> predict(const protocol::Protocol& p, const PredictOptions& o) {
  if (o.participants < 2) return predict_error("--participants must be at least 2");
  if (o.simulations < 1) return predict_error("--simulations must be at least 1");
  if (auto ok = check_observer(o.observer); !ok) return predict_error("observer: " + ok.error().message);
  Prediction out;
  out.participants = o.participants;
  auto collected = collect_conditions(p, out);
  if (!collected) return collected.error();
  Conditions& conditions = collected.value();
  if (conditions.choice.empty() && conditions.adaptive.empty())
    return predict_error("the protocol has no choice or adaptive trials outside practice to predict");
  const SimulatedObserver mean_observer(o.observer);
  for (auto& c : conditions.choice) {
    ConditionPrediction cp = predict_condition(c, o.observer);
    cp.trials_per_participant = static_cast<std::int64_t>(c.trials.size());
    if (cp.diverging_points > 0) out.notes.push_back(diverging_note(cp));
    if (cp.human && !cp.human->fused) out.notes.push_back(double_note(cp));
    out.conditions.push_back(std::move(cp));
  }
  for (auto& c : conditions.adaptive) predict_tracks(c, mean_observer, out);
  Population population(o);
  expected_proportions(population, out);
  std::vector<std::string> factors;
  if (!o.factor.empty()) factors.push_back(o.factor);
  else
    for (const auto& f : p.factors) factors.push_back(f.name);
  std::optional<AdaptivePool> pool;
  for (const auto& f : factors)
    if (auto r = estimate_power(population, out, conditions, o, f, pool); !r) return r.error();
  return out;
}

std::vector<StaircasePrediction> predict_convergence(const protocol::Protocol& p, const ObserverParams& observer) {
  Prediction out;
  auto collected = collect_conditions(p, out);
  if (!collected) return {};
  const SimulatedObserver mean_observer(observer);
  for (auto& c : collected.value().adaptive) predict_tracks(c, mean_observer, out);
  return out.staircases;
}

}  // namespace curvlab::harness::runner
