// The psi judgement (judgements/psi.cpp) through the judgement interface: its
// posterior is Bayes' rule over the grid, its next value the expected-entropy
// minimum, both recomputed here by brute force with code of the test's own;
// its stop rule ends a condition; a bad table is reported field by field at
// its line.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/loader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

using namespace curvlab::harness::protocol;

namespace {

const std::string kHead = "[protocol]\nname = \"t\"\nversion = \"1\"\n[randomization]\nseed = 3\n";
const std::string kOptions =
    "options = [{ value = \"yes\", keys = [\"1\"] }, { value = \"no\", keys = [\"2\"] }]\n";

Protocol load(const std::string& judgement) {
  const auto r = load_protocol_text(kHead + judgement, "t.toml");
  if (!r)
    for (const auto& d : r.error().diagnostics) ADD_FAILURE() << format_diagnostic(d);
  return *r;
}

// The grid and its posterior, written out the long way: every grid point
// (α, β, λ) with its probability.
struct Point {
  double alpha, beta, lapse, p;
};

std::vector<double> linear(double lo, double hi, int n) {
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(lo + (hi - lo) * i / (n - 1));
  return v;
}
std::vector<double> logarithmic(double lo, double hi, int n) {
  std::vector<double> v;
  for (int i = 0; i < n; ++i) v.push_back(lo * std::pow(hi / lo, static_cast<double>(i) / (n - 1)));
  return v;
}

double p_yes(double x, const Point& q) {
  return q.lapse / 2.0 + (1.0 - q.lapse) * 0.5 * (1.0 + std::erf(q.beta * (x - q.alpha) / std::sqrt(2.0)));
}

struct Model {
  std::vector<double> xs;
  std::vector<Point> grid;  // the uniform prior
};

Model model(const std::vector<double>& lapses) {
  Model m;
  m.xs = linear(-0.05, 0.05, 11);
  for (const double a : linear(-0.06, 0.06, 13))
    for (const double b : logarithmic(20.0, 400.0, 5))
      for (const double l : lapses) m.grid.push_back({a, b, l, 0.0});
  for (auto& q : m.grid) q.p = 1.0 / static_cast<double>(m.grid.size());
  return m;
}

const std::string kSmallGrids = "values = { min = -0.05, max = 0.05, count = 11 }\n"
                                "pse = { min = -0.06, max = 0.06, count = 13 }\n"
                                "slope = { min = 20.0, max = 400.0, count = 5 }\n";

std::string psi_table(const std::string& extra) {
  return "[judgement]\ntype = \"psi\"\nparameter = \"stimulus.stick_sagitta_m\"\npositive = \"yes\"\n" + kOptions +
         kSmallGrids + extra;
}

// Posterior after the answers, from the prior by Bayes' rule, point by point.
std::vector<Point> bayes(const Model& m, const std::vector<std::pair<double, bool>>& answers) {
  std::vector<Point> post = m.grid;
  for (auto& q : post) {
    double log_like = 0.0;
    for (const auto& [x, yes] : answers) log_like += std::log(yes ? p_yes(x, q) : 1.0 - p_yes(x, q));
    q.p *= std::exp(log_like);
  }
  double total = 0.0;
  for (const auto& q : post) total += q.p;
  for (auto& q : post) q.p /= total;
  return post;
}

double entropy(const std::vector<Point>& post) {
  double h = 0.0;
  for (const auto& q : post)
    if (q.p > 0.0) h -= q.p * std::log(q.p);
  return h;
}

// Mean and SD of one coordinate.
std::pair<double, double> mean_sd(const std::vector<Point>& post, double Point::*coordinate) {
  double m = 0.0, m2 = 0.0;
  for (const auto& q : post) {
    m += q.p * (q.*coordinate);
    m2 += q.p * (q.*coordinate) * (q.*coordinate);
  }
  return {m, std::sqrt(std::max(0.0, m2 - m * m))};
}

// The expected entropy after showing x: each answer's posterior, weighted by
// its predictive probability.
double expected_entropy(const std::vector<Point>& post, double x) {
  double h = 0.0;
  for (const bool yes : {true, false}) {
    std::vector<Point> after = post;
    double z = 0.0;
    for (auto& q : after) {
      q.p *= yes ? p_yes(x, q) : 1.0 - p_yes(x, q);
      z += q.p;
    }
    for (auto& q : after) q.p /= z;
    h += z * entropy(after);
  }
  return h;
}

// A fixed answer sequence: not what any observer would give, so the
// posterior goes where the test sends it.
const std::vector<bool> kAnswers{true, false, false, true, true, false, true, false, true, true, false, false};

void check_steps_against_bayes(const std::string& extra, const std::vector<double>& lapses) {
  const Protocol p = load(psi_table(extra));
  const Judgement& j = p.blocks.at(0).judgement;
  const Design d = expand_design(p, 1);
  auto state = j.type->adaptive_state(j);
  ASSERT_NE(state, nullptr);
  const Model m = model(lapses);
  std::vector<std::pair<double, bool>> answers;
  for (std::size_t k = 0; k < kAnswers.size(); ++k) {
    SCOPED_TRACE("answer " + std::to_string(k + 1));
    // (2) The value shown minimises the expected entropy over the stimulus
    // grid (equal expected entropies are a tie, which either may break).
    const auto post = bayes(m, answers);
    const double shown = state->value(d.trials.at(k));
    double best = INFINITY;
    for (const double x : m.xs) best = std::min(best, expected_entropy(post, x));
    EXPECT_NEAR(expected_entropy(post, shown), best, 1e-12);
    bool on_grid = false;
    for (const double x : m.xs) on_grid |= std::abs(x - shown) < 1e-12;
    EXPECT_TRUE(on_grid) << shown;

    // (1) The posterior after the answer is Bayes' rule over the grid.
    const AdaptiveStep step = state->record(d.trials.at(k), kAnswers[k]);
    EXPECT_EQ(step.step, static_cast<int>(k));
    EXPECT_EQ(step.value, shown);
    answers.emplace_back(shown, kAnswers[k]);
    const auto after = bayes(m, answers);
    ASSERT_TRUE(step.posterior.has_value());
    const PosteriorSummary& s = *step.posterior;
    const auto [am, asd] = mean_sd(after, &Point::alpha);
    const auto [bm, bsd] = mean_sd(after, &Point::beta);
    EXPECT_NEAR(s.pse_mean, am, 1e-9);
    EXPECT_NEAR(s.pse_sd, asd, 1e-9);
    EXPECT_NEAR(s.slope_mean, bm, 1e-6);
    EXPECT_NEAR(s.slope_sd, bsd, 1e-6);
    EXPECT_NEAR(s.entropy_nats, entropy(after), 1e-9);
    if (lapses.size() > 1) {
      const auto [lm, lsd] = mean_sd(after, &Point::lapse);
      ASSERT_TRUE(s.lapse_mean && s.lapse_sd);
      EXPECT_NEAR(*s.lapse_mean, lm, 1e-9);
      EXPECT_NEAR(*s.lapse_sd, lsd, 1e-9);
    } else {
      EXPECT_FALSE(s.lapse_mean.has_value());
    }
    EXPECT_EQ(step.next_value, state->value(d.trials.at(k + 1)));
  }
}

// A table with one thing wrong, read; its diagnostics.
std::vector<Diagnostic> problems_of(const std::string& judgement) {
  const auto r = load_protocol_text(kHead + judgement, "bad.toml");
  if (r) return {};
  return r.error().diagnostics;
}

bool reported(const std::vector<Diagnostic>& all, int line, const std::string& field, const std::string& words) {
  for (const auto& d : all)
    if (d.pos.line == line && d.field == field && d.message.find(words) != std::string::npos && d.file == "bad.toml")
      return true;
  return false;
}

std::string listed(const std::vector<Diagnostic>& all) {
  std::string out;
  for (const auto& d : all) out += format_diagnostic(d) + "\n";
  return out;
}

}  // namespace

TEST(Psi, PosteriorIsBayesRuleOverTheGridAndEachValueMinimisesExpectedEntropy) {
  check_steps_against_bayes("lapse = 0.04\n", {0.04});
}

TEST(Psi, AnEstimatedLapseRateIsPartOfTheGrid) {
  check_steps_against_bayes("lapse = { min = 0.0, max = 0.1, count = 3 }\n", {0.0, 0.05, 0.1});
}

// The design lists `trials` slots per cell; the stop rule skips the rest of a
// cell once the PSE's posterior SD is small enough, and only that cell's.
TEST(Psi, TrialsPerCellAndTheStopRule) {
  const Protocol p = load("[factors.space]\nsets = \"space.kind\"\nlevels = [\"E3\", \"H3\"]\n" +
                          psi_table("trials = 30\nstop_sd = 0.01\n"));
  const Judgement& j = p.blocks.at(0).judgement;
  EXPECT_TRUE(j.type->stops_early());
  const Design d = expand_design(p, 1);
  ASSERT_EQ(d.trials.size(), 60u);
  std::size_t in_cell0 = 0;
  for (const auto& t : d.trials) in_cell0 += t.cell == 0 ? 1 : 0;
  EXPECT_EQ(in_cell0, 30u);

  auto state = j.type->adaptive_state(j);
  EXPECT_TRUE(state->positive("yes"));
  EXPECT_FALSE(state->positive("no"));
  // An observer at α = 0.01, steep: the answer is "yes" above the PSE.
  int answered = 0;
  for (const auto& t : d.trials) {
    if (t.cell != 0) continue;
    if (state->skip_reason(t)) break;
    const AdaptiveStep s = state->record(t, state->value(t) > 0.01);
    ++answered;
    EXPECT_EQ(s.track, "psi");
    EXPECT_EQ(state->skip_reason(t).has_value(), s.posterior->pse_sd <= 0.01) << answered;
  }
  EXPECT_LT(answered, 30);
  EXPECT_EQ(state->skip_reason(d.trials.back()), "psi_finished");
  // Another cell keeps its own posterior.
  EXPECT_FALSE(j.type->adaptive_state(j)->skip_reason(d.trials.front()).has_value());
}

// Replaying the same answers into a new state (a resumed session) gives the
// same values and the same posterior.
TEST(Psi, ReplayedAnswersGiveTheSameNextValues) {
  const Protocol p = load(psi_table(""));
  const Judgement& j = p.blocks.at(0).judgement;
  const Design d = expand_design(p, 1);
  auto first = j.type->adaptive_state(j);
  std::vector<bool> given;
  for (std::size_t k = 0; k < 20; ++k) {
    const bool yes = first->value(d.trials[k]) > -0.012;
    given.push_back(yes);
    first->record(d.trials[k], yes);
  }
  auto again = j.type->adaptive_state(j);
  for (std::size_t k = 0; k < 20; ++k) again->record(d.trials[k], given[k]);
  EXPECT_EQ(again->value(d.trials[20]), first->value(d.trials[20]));
  EXPECT_EQ(again->record(d.trials[20], true).posterior->pse_mean,
            first->record(d.trials[20], true).posterior->pse_mean);
}

TEST(Psi, ConvergesOnTheFiftyPercentPointAndStartsFromThePrior) {
  const Protocol p = load(psi_table(""));
  const Judgement& j = p.blocks.at(0).judgement;
  EXPECT_EQ(j.type->forecast(), Forecast::convergence);
  const auto targets = j.type->convergence(j);
  ASSERT_EQ(targets.size(), 1u);
  EXPECT_EQ(targets[0].rule, "psi");
  EXPECT_EQ(targets[0].positive, "yes");
  EXPECT_EQ(targets[0].target_p, 0.5);
  EXPECT_EQ(targets[0].min, -0.05);
  EXPECT_EQ(targets[0].max, 0.05);
  const Design d = expand_design(p, 1);
  const auto onset = j.type->onset_value(j, d.trials[0]);
  ASSERT_TRUE(onset.has_value());
  EXPECT_EQ(onset->value, j.type->adaptive_state(j)->value(d.trials[0]));
  bool has_grid = false;
  for (const auto& [label, text] : j.type->settings_summary(j)) has_grid |= label == "slope grid (β)";
  EXPECT_TRUE(has_grid);
}

// (5) Every problem of a psi table at its line, with its dotted field.
TEST(Psi, BadTablesAreReportedAtTheirLineAndField) {
  const std::string start = "[judgement]\ntype = \"psi\"\nparameter = \"stimulus.stick_sagitta_m\"\n";  // lines 6–8
  // Line 9 onwards: options, then the keys under test.
  const auto all = problems_of(start +
                               "options = [{ value = \"yes\", keys = [\"1\"] }, { value = \"no\", keys = [\"2\"] }]\n"
                               "positive = \"maybe\"\n"                                // 10
                               "values = { min = 0.05, max = -0.05, count = 11 }\n"    // 11
                               "pse = { min = -0.05, max = 0.05, count = 1 }\n"        // 12
                               "slope = { min = 0.0, max = 100.0, count = 5 }\n"       // 13
                               "lapse = 0.7\n"                                         // 14
                               "stop_sd = -0.001\n"                                    // 15
                               "trials = 0\n");                                        // 16
  EXPECT_TRUE(reported(all, 10, "judgement.positive", "\"maybe\" is not an option value")) << listed(all);
  EXPECT_TRUE(reported(all, 11, "judgement.values", "expected min < max")) << listed(all);
  EXPECT_TRUE(reported(all, 12, "judgement.pse.count", "expected an integer in [2, 1001], found 1")) << listed(all);
  EXPECT_TRUE(reported(all, 13, "judgement.slope.min", "log-spaced")) << listed(all);
  EXPECT_TRUE(reported(all, 14, "judgement.lapse", "expected a number in [0, 0.5]")) << listed(all);
  EXPECT_TRUE(reported(all, 15, "judgement.stop_sd", "expected a positive number")) << listed(all);
  EXPECT_TRUE(reported(all, 16, "judgement.trials", "expected an integer in [1, 1000]")) << listed(all);

  // Three ordered options: the positive one must be an end of the list.
  const auto middle = problems_of(start +
                                  "options = [{ value = \"convex\", keys = [\"1\"] }, { value = \"straight\", "
                                  "keys = [\"2\"] }, { value = \"concave\", keys = [\"3\"] }]\n"
                                  "positive = \"straight\"\n"
                                  "values = { min = -0.05, max = 0.05, count = 11 }\n");
  EXPECT_TRUE(reported(middle, 10, "judgement.positive", "expected the first (\"convex\") or the last")) << listed(middle);

  // A grid outside the parameter's own range, a missing stimulus grid, an
  // unknown key in a grid, a lapse grid beyond 0.5 and grids too large.
  const auto more = problems_of(start + kOptions + "positive = \"yes\"\n"
                                "pse = { min = -0.05, max = 0.05, count = 11, step = 2 }\n"            // 11
                                "lapse = { min = 0.0, max = 0.6, count = 3 }\n");                      // 12
  EXPECT_TRUE(reported(more, 6, "judgement.values", "missing required table")) << listed(more);
  EXPECT_TRUE(reported(more, 11, "judgement.pse.step", "unknown key")) << listed(more);
  EXPECT_TRUE(reported(more, 12, "judgement.lapse", "expected 0 ≤ min < max ≤ 0.5")) << listed(more);
  const auto range = problems_of(start + kOptions + "positive = \"yes\"\n"
                                 "values = { min = -50.0, max = 50.0, count = 11 }\n");
  EXPECT_TRUE(reported(range, 11, "judgement.values", "stimulus.stick_sagitta_m's range")) << listed(range);
  const auto huge = problems_of(start + kOptions + "positive = \"yes\"\n"
                                "values = { min = -0.05, max = 0.05, count = 1001 }\n"
                                "pse = { min = -0.05, max = 0.05, count = 1001 }\n"
                                "slope = { min = 1.0, max = 100.0, count = 50 }\n");
  EXPECT_TRUE(reported(huge, 6, "judgement", "points in values × pse × slope × lapse together")) << listed(huge);

  // A psi block runs once; its length is `trials`.
  const auto repeated = problems_of(psi_table("") + "[[blocks]]\nname = \"b\"\nrepetitions = 3\n");
  bool repetitions = false;
  for (const auto& d : repeated) repetitions |= d.field == "blocks[1].repetitions";
  EXPECT_TRUE(repetitions) << listed(repeated);
}
