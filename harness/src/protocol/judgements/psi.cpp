// `type = "psi"`: the psi method (Kontsevich & Tyler 1999, "Bayesian adaptive
// estimation of psychometric slope and threshold", Vision Research 39,
// 2729–2737), in the notation of its generalisation QUEST+ (Watson 2017,
// "QUEST+: a general multidimensional Bayesian adaptive psychometric method",
// Journal of Vision 17(3):10).
//
// Every cell of the block keeps a posterior over a grid of the parameters of
//   P(positive | x) = λ/2 + (1 − λ) Φ(β (x − α)),
// the PSE α (linear grid), the slope β (log-spaced grid) and the lapse rate λ
// (fixed, or a linear grid). The prior is uniform over the grid: flat in α,
// flat in log β, flat in λ. Each trial shows the value x of the stimulus grid
// whose answer is expected to leave the least posterior entropy (the psi
// rule); the answer updates the posterior by Bayes' rule. Answers are binary:
// the option named `positive` against all the others.
//
// The design lists `trials` slots per cell, shuffled; once the posterior SD
// of α is at most `stop_sd`, the runner skips the cell's remaining slots.
// Everything is deterministic given the answers, so a resumed session that
// replays them reaches the same posterior and shows the same next values.
#include "judgement_format.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <tuple>

namespace curvlab::harness::protocol {

namespace {

namespace tr = toml_reader;

// `count` points from `min` to `max`, evenly spaced, or evenly in log.
struct Grid {
  double min = 0.0, max = 0.0;
  int count = 2;
  bool log = false;

  [[nodiscard]] std::vector<double> points() const {
    std::vector<double> out(static_cast<std::size_t>(count));
    const double lo = log ? std::log(min) : min, hi = log ? std::log(max) : max;
    for (int i = 0; i < count; ++i) {
      const double v = lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(count - 1);
      out[static_cast<std::size_t>(i)] = log ? std::exp(v) : v;
    }
    // The ends exactly as written, whatever the rounding of exp(log(·)).
    out.front() = min;
    out.back() = max;
    return out;
  }
};

// The grids' product is one condition's table of P(positive): 8 bytes each.
constexpr double kMaxGridPoints = 4'000'000;
constexpr int kMaxCount = 1001;
constexpr int kMaxSlopeCount = 200;
constexpr int kMaxLapseCount = 50;
constexpr double kDefaultLapse = 0.02;
constexpr int kDefaultSlopeCount = 20;

struct PsiTable final : JudgementSpec {
  std::string positive;  // the option value that counts as positive
  Grid values;           // the stimulus grid
  Grid pse;              // α
  Grid slope;            // β, log-spaced
  double lapse = kDefaultLapse;
  std::optional<Grid> lapse_grid;  // λ estimated over this grid instead
  int trials = 50;                 // slots per cell
  std::optional<double> stop_sd;   // stop once the posterior SD of α is at most this
};

const PsiTable* table_of(const Judgement& j) { return dynamic_cast<const PsiTable*>(j.spec.get()); }

double phi(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

// x log x, 0 at 0.
double x_log_x(double x) { return x > 0.0 ? x * std::log(x) : 0.0; }

// The posterior over (α, β, λ) and the psi rule. Pure; not thread-safe.
class PsiPosterior {
 public:
  explicit PsiPosterior(const PsiTable& t)
      : xs_(t.values.points()), alphas_(t.pse.points()), betas_(t.slope.points()),
        lapses_(t.lapse_grid ? t.lapse_grid->points() : std::vector<double>{t.lapse}),
        estimates_lapse_(t.lapse_grid.has_value()) {
    const std::size_t n = alphas_.size() * betas_.size() * lapses_.size();
    prior_.assign(n, 1.0 / static_cast<double>(n));
    // P(positive | x, θ) for every stimulus x and grid point θ, row by row.
    p_positive_.resize(xs_.size() * n);
    for (std::size_t x = 0; x < xs_.size(); ++x) {
      double* row = &p_positive_[x * n];
      std::size_t k = 0;
      for (const double a : alphas_)
        for (const double b : betas_)
          for (const double l : lapses_) row[k++] = 0.5 * l + (1.0 - l) * phi(b * (xs_[x] - a));
    }
    next_ = best_value_index();
  }

  [[nodiscard]] double next_value() const { return xs_[next_]; }
  [[nodiscard]] int answers() const { return answers_; }

  // Bayes' rule for the answer to the value shown now; then the next value.
  void update(bool positive) {
    const double* row = &p_positive_[next_ * prior_.size()];
    double total = 0.0;
    for (std::size_t k = 0; k < prior_.size(); ++k) {
      prior_[k] *= positive ? row[k] : 1.0 - row[k];
      total += prior_[k];
    }
    for (double& p : prior_) p /= total;
    ++answers_;
    next_ = best_value_index();
  }

  [[nodiscard]] PosteriorSummary summary() const {
    PosteriorSummary s;
    const std::size_t nb = betas_.size(), nl = lapses_.size();
    std::vector<double> pa(alphas_.size(), 0.0), pb(nb, 0.0), pl(nl, 0.0);
    double entropy = 0.0;
    for (std::size_t k = 0; k < prior_.size(); ++k) {
      pa[k / (nb * nl)] += prior_[k];
      pb[(k / nl) % nb] += prior_[k];
      pl[k % nl] += prior_[k];
      entropy -= x_log_x(prior_[k]);
    }
    std::tie(s.pse_mean, s.pse_sd) = moments(alphas_, pa);
    std::tie(s.slope_mean, s.slope_sd) = moments(betas_, pb);
    if (estimates_lapse_) {
      const auto [mean, sd] = moments(lapses_, pl);
      s.lapse_mean = mean;
      s.lapse_sd = sd;
    }
    s.entropy_nats = entropy;
    return s;
  }

 private:
  // The psi rule: the stimulus whose answer leaves the least expected
  // entropy. With p⁺ = prior·P(positive) and p⁻ = prior − p⁺ over the grid,
  // Z± = Σ p±, the posterior after answer ± is p±/Z± and
  //   E[H] = Σ± Z± H(p±/Z±) = Σ± (Z± log Z± − Σ p± log p±).
  // The first minimum wins, so a tie is broken the same way every time.
  [[nodiscard]] std::size_t best_value_index() const {
    std::size_t best = 0;
    double best_h = std::numeric_limits<double>::infinity();
    const std::size_t n = prior_.size();
    for (std::size_t x = 0; x < xs_.size(); ++x) {
      const double* row = &p_positive_[x * n];
      double z_pos = 0.0, z_neg = 0.0, s_pos = 0.0, s_neg = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        const double pos = prior_[k] * row[k], neg = prior_[k] - pos;
        z_pos += pos;
        z_neg += neg;
        s_pos += x_log_x(pos);
        s_neg += x_log_x(neg);
      }
      const double h = x_log_x(z_pos) - s_pos + x_log_x(z_neg) - s_neg;
      if (h < best_h) {
        best_h = h;
        best = x;
      }
    }
    return best;
  }

  static std::pair<double, double> moments(const std::vector<double>& at, const std::vector<double>& p) {
    double mean = 0.0;
    for (std::size_t i = 0; i < at.size(); ++i) mean += p[i] * at[i];
    double var = 0.0;
    for (std::size_t i = 0; i < at.size(); ++i) var += p[i] * (at[i] - mean) * (at[i] - mean);
    return {mean, std::sqrt(var)};
  }

  std::vector<double> xs_, alphas_, betas_, lapses_;
  bool estimates_lapse_ = false;
  std::vector<double> prior_;       // the posterior so far, index (α·nβ + β)·nλ + λ
  std::vector<double> p_positive_;  // [x][θ]
  std::size_t next_ = 0;            // index into xs_ of the value shown next
  int answers_ = 0;
};

// One cell's psi.
class PsiState final : public AdaptiveState {
 public:
  explicit PsiState(const PsiTable& table)
      : positive_(table.positive), stop_sd_(table.stop_sd), posterior_(table) {}

  [[nodiscard]] std::optional<std::string> skip_reason(const PlannedTrial&) const override {
    if (stopped_) return "psi_finished";
    return std::nullopt;
  }
  [[nodiscard]] double value(const PlannedTrial&) const override { return posterior_.next_value(); }
  [[nodiscard]] bool positive(std::string_view answer) const override { return answer == positive_; }

  AdaptiveStep record(const PlannedTrial&, bool positive) override {
    AdaptiveStep step{"psi", posterior_.answers(), posterior_.next_value(), positive, false, 0.0, std::nullopt};
    posterior_.update(positive);
    step.next_value = posterior_.next_value();
    step.posterior = posterior_.summary();
    if (stop_sd_ && step.posterior->pse_sd <= *stop_sd_) stopped_ = true;
    return step;
  }

 private:
  std::string positive_;
  std::optional<double> stop_sd_;
  PsiPosterior posterior_;
  bool stopped_ = false;
};

std::string grid_label(const Grid& g) {
  return std::to_string(g.count) + (g.log ? " log-spaced values in " : " values in ") + interval_label(g.min, g.max);
}

class PsiJudgement final : public JudgementType {
 public:
  [[nodiscard]] std::string_view name() const override { return "psi"; }
  [[nodiscard]] std::string_view summary() const override { return "Bayesian adaptive psi method"; }

  void fields(JudgementFields& out) const override;
  void read(JudgementSection& section, Judgement& out) const override;

  [[nodiscard]] std::optional<std::string> repetitions_problem(int repetitions) const override {
    if (repetitions <= 1) return std::nullopt;
    return "expected 1 in a psi block, got " + std::to_string(repetitions) +
           " (its length is the judgement's trials); raise trials instead";
  }

  [[nodiscard]] std::vector<double> reachable_values(const Judgement& j) const override {
    const auto* t = table_of(j);
    if (!t) return {};
    return {t->values.min, t->values.max};
  }

  [[nodiscard]] bool stops_early() const override { return true; }

  [[nodiscard]] std::size_t trials_per_cell(const Block& b) const override {
    const auto* t = table_of(b.judgement);
    return t ? static_cast<std::size_t>(t->trials) : 0;
  }

  // `trials` slots per cell, round-robin; shuffling interleaves the cells.
  [[nodiscard]] std::vector<DesignSlot> slots(const Block& b, std::size_t cells, Engine& rng) const override {
    std::vector<DesignSlot> out;
    const std::size_t per_cell = trials_per_cell(b);
    for (std::size_t k = 0; k < per_cell; ++k)
      for (std::size_t c = 0; c < cells; ++c) out.push_back({c, 0, std::nullopt});
    if (b.randomize != RandomizeMode::none) shuffle(out, rng);
    return out;
  }

  [[nodiscard]] std::unique_ptr<AdaptiveState> adaptive_state(const Judgement& j) const override {
    const auto* t = table_of(j);
    if (!t) return nullptr;
    return std::make_unique<PsiState>(*t);
  }

  [[nodiscard]] Forecast forecast() const override { return Forecast::convergence; }

  // The PSE estimate converges on the value where P(positive) = 0.5.
  [[nodiscard]] std::vector<ConvergenceTarget> convergence(const Judgement& j) const override {
    const auto* t = table_of(j);
    if (!t) return {};
    return {{"psi", t->positive, "psi", 1, 1, t->values.min, t->values.max, 0.5}};
  }

  [[nodiscard]] std::optional<OnsetValue> onset_value(const Judgement& j, const PlannedTrial&) const override {
    const auto* t = table_of(j);
    if (!t) return std::nullopt;
    const double first = PsiPosterior(*t).next_value();
    return OnsetValue{first, "psi at its first value (chosen from the prior), " + j.parameter + " = " +
                                 number_label(first)};
  }

  [[nodiscard]] std::vector<std::pair<std::string, std::string>> settings_summary(const Judgement& j) const override {
    const auto* t = table_of(j);
    if (!t) return {};
    std::vector<std::pair<std::string, std::string>> rows{
        {"positive answer", t->positive + " (every other answer counts as not positive)"},
        {"model", "P(" + t->positive + ") = λ/2 + (1 − λ) Φ(β (x − α)), uniform prior over the grid"},
        {"stimulus grid", grid_label(t->values)},
        {"PSE grid (α)", grid_label(t->pse)},
        {"slope grid (β)", grid_label(t->slope)},
        {"lapse (λ)", t->lapse_grid ? grid_label(*t->lapse_grid) : "fixed at " + number_label(t->lapse)},
        {"trials", std::to_string(t->trials) + " per condition" +
                       (t->stop_sd ? ", or fewer: stops once the PSE's posterior SD ≤ " + number_label(*t->stop_sd)
                                   : std::string())},
        {"next value", "the one minimising the expected posterior entropy (Kontsevich & Tyler 1999)"},
    };
    return rows;
  }

 private:
  static std::optional<Grid> read_grid(JudgementSection& section, std::string_view key, bool required, bool log,
                                       int max_count, const std::string& parameter);
  static void read_lapse(JudgementSection& section, PsiTable& out);
  static void read_positive(JudgementSection& section, const Judgement& j, PsiTable& out);
};

schema_json::Json grid_schema(const std::string& what, int max_count, bool positive) {
  using namespace schema_json;
  Json bound = {{"type", "number"}};
  if (positive) bound["exclusiveMinimum"] = 0;
  Json min = bound, max = bound;
  min["description"] = "the first grid value; min < max";
  max["description"] = "the last grid value";
  Json props = {{"min", min}, {"max", max}, {"count", integer(2, max_count, "how many grid values")}};
  Json j = closed_object(props, what);
  j["required"] = Json::array({"min", "max", "count"});
  return j;
}

void PsiJudgement::fields(JudgementFields& out) const {
  using namespace schema_json;
  out.add_options();
  out.add_parameter();
  out.add("positive", string_field("the option value that counts as a positive response"));
  out.add("values", grid_schema("the stimulus grid: the parameter's values a trial may show (evenly spaced)",
                                kMaxCount, false));
  out.add("pse", grid_schema("the grid of the PSE α, evenly spaced (default: the stimulus grid)", kMaxCount, false));
  out.add("slope", grid_schema("the grid of the slope β per parameter unit, log-spaced (default: 20 values from "
                               "1/(max − min) to 4 (count − 1)/(max − min) of the stimulus grid)",
                               kMaxSlopeCount, true));
  Json lapse_grid = grid_schema("a grid of the lapse rate λ, evenly spaced in [0, 0.5]", kMaxLapseCount, false);
  out.add("lapse", {{"anyOf", Json::array({Json{{"type", "number"}, {"minimum", 0}, {"maximum", 0.5}}, lapse_grid})},
                    {"default", kDefaultLapse},
                    {"description", "the lapse rate λ: a fixed number, or a {min, max, count} grid to estimate it"}});
  out.add("trials", with_default(integer(1, 1000, "trials per condition (at most, with stop_sd)"), 50));
  out.add("stop_sd", {{"type", "number"},
                      {"exclusiveMinimum", 0},
                      {"description", "stop a condition once the posterior SD of its PSE is at most this"}});
  out.require({"parameter", "options", "positive", "values"});
}

void PsiJudgement::read(JudgementSection& section, Judgement& out) const {
  auto table = std::make_shared<PsiTable>();
  out.options = section.options();
  out.parameter = section.parameter();
  read_positive(section, out, *table);
  const toml::table& j = section.table;
  const auto values = read_grid(section, "values", true, false, kMaxCount, out.parameter);
  if (values) table->values = *values;
  const auto pse = read_grid(section, "pse", false, false, kMaxCount, "");
  table->pse = pse ? *pse : table->values;
  if (const auto slope = read_grid(section, "slope", false, true, kMaxSlopeCount, "")) {
    table->slope = *slope;
  } else if (values) {
    const double range = values->max - values->min;
    table->slope = {1.0 / range, 4.0 * (values->count - 1) / range, kDefaultSlopeCount, true};
  }
  read_lapse(section, *table);
  table->trials = static_cast<int>(section.reader.get_int(j, "trials", section.prefix, 1, 1000, false).value_or(50));
  if (const auto sd = section.reader.get_number(j, "stop_sd", section.prefix, false)) {
    if (*sd > 0.0)
      table->stop_sd = *sd;
    else
      section.reader.error(pos_of(*j.get("stop_sd")), section.prefix + ".stop_sd",
                           "expected a positive number, got " + number_label(*sd));
  }
  const double points = static_cast<double>(table->values.count) * table->pse.count * table->slope.count *
                        (table->lapse_grid ? table->lapse_grid->count : 1);
  if (points > kMaxGridPoints)
    section.reader.error(pos_of(j), section.prefix,
                         "expected at most " + number_label(kMaxGridPoints) +
                             " points in values × pse × slope × lapse together, got " + number_label(points) +
                             " (each condition keeps a table of that size); use coarser grids");
  out.spec = std::move(table);
}

// A psi's answers are binary: `positive` against the rest. With three or more
// ordered options (convex, straight, concave) the positive one must be an end
// of the list, so that P(positive) rises monotonically with the parameter.
void PsiJudgement::read_positive(JudgementSection& section, const Judgement& j, PsiTable& out) {
  const toml::table& t = section.table;
  const auto pos = section.reader.get_string(t, "positive", section.prefix, true);
  if (!pos) return;
  out.positive = *pos;
  const std::string field = section.prefix + ".positive";
  const auto it = std::find_if(j.options.begin(), j.options.end(),
                               [&](const ResponseOption& o) { return o.value == *pos; });
  if (it == j.options.end()) {
    std::vector<std::string> values;
    for (const auto& o : j.options) values.push_back(o.value);
    section.reader.error(pos_of(*t.get("positive")), field,
                         "\"" + *pos + "\" is not an option value" + expected_one_of(*pos, values));
    return;
  }
  if (it != j.options.begin() && it + 1 != j.options.end())
    section.reader.error(pos_of(*t.get("positive")), field,
                         "expected the first (\"" + j.options.front().value + "\") or the last (\"" +
                             j.options.back().value + "\") option: \"" + *pos +
                             "\" lies between others, so P(positive) would not rise with the parameter");
}

std::optional<Grid> PsiJudgement::read_grid(JudgementSection& section, std::string_view key, bool required, bool log,
                                            int max_count, const std::string& parameter) {
  TableReader& r = section.reader;
  const std::string field = join(section.prefix, key);
  const toml::node* n = section.table.get(key);
  if (!n) {
    if (required) r.error(pos_of(section.table), field, "missing required table { min, max, count }");
    return std::nullopt;
  }
  const auto* t = n->as_table();
  if (!t) {
    r.error(pos_of(*n), field, "expected a table { min, max, count }, found " + tr::type_name(*n));
    return std::nullopt;
  }
  r.check_keys(*t, field, {"min", "max", "count"});
  const auto mn = r.get_number(*t, "min", field, true), mx = r.get_number(*t, "max", field, true);
  const auto count = r.get_int(*t, "count", field, 2, max_count, true);
  if (!mn || !mx || !count) return std::nullopt;
  Grid g{*mn, *mx, static_cast<int>(*count), log};
  if (log && !(g.min > 0.0)) {
    r.error(pos_of(*t->get("min")), field + ".min",
            "expected a positive number (the grid is log-spaced), got " + number_label(g.min));
    return std::nullopt;
  }
  if (!check_range(r, parameter, g.min, g.max, *t, field)) return std::nullopt;
  return g;
}

void PsiJudgement::read_lapse(JudgementSection& section, PsiTable& out) {
  TableReader& r = section.reader;
  const std::string field = section.prefix + ".lapse";
  const toml::node* n = section.table.get("lapse");
  if (!n) return;
  if (n->is_table()) {
    out.lapse_grid = read_grid(section, "lapse", false, false, kMaxLapseCount, "");
    if (out.lapse_grid && (out.lapse_grid->min < 0.0 || out.lapse_grid->max > 0.5)) {
      r.error(pos_of(*n), field,
              "expected 0 ≤ min < max ≤ 0.5, got min = " + number_label(out.lapse_grid->min) +
                  ", max = " + number_label(out.lapse_grid->max));
      out.lapse_grid.reset();
    }
    return;
  }
  const auto v = TableReader::node_number(*n);
  if (!v || !std::isfinite(*v) || *v < 0.0 || *v > 0.5) {
    r.error(pos_of(*n), field,
            "expected a number in [0, 0.5] or a table { min, max, count }, " +
                (v ? "got " + number_label(*v) : "found " + tr::type_name(*n)));
    return;
  }
  out.lapse = *v;
}

}  // namespace

const JudgementType& psi_judgement_type() {
  static const PsiJudgement type;
  return type;
}

}  // namespace curvlab::harness::protocol
