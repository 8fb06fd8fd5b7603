// Judgement types as one family (DESIGN.md §1, §6): what the participant
// answers, and everything that depends on it. Each type — n-alternative
// `choice`, method of `adjustment`, interleaved `staircase`, Bayesian
// adaptive `psi` — is one class in
// one file under harness/src/protocol/judgements/, registered once in
// judgements/registry.cpp; the loader, the schema generator, the design
// expander, the runner, `predict` and `preview` ask the type of a judgement
// (Judgement::type) instead of naming types themselves.
//
// The interface is pure: no clock, no backend, no storage. What the runner
// needs at run time comes back as values (an input's use, the key presses a
// simulated participant makes, the value an adaptive method shows next); the
// runner keeps the state objects a type hands it. An adaptive method that
// keeps a posterior per condition and chooses the next stimulus value (psi,
// QUEST+) is a type whose AdaptiveState holds the posterior, and reports it
// with every step (PosteriorSummary).
//
// Types are stateless singletons: thread-safe. AdaptiveState objects are
// owned by one session loop and are not thread-safe.
#pragma once

#include "curvlab/harness/protocol/adjustment.hpp"
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/protocol/random.hpp"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace curvlab::harness::protocol {

// What a type keeps of its table beyond the fields every judgement has
// (prompt, options, parameter); each type defines and reads its own.
class JudgementSpec {
 public:
  virtual ~JudgementSpec() = default;
};

// The protocol-file contexts a type reads and declares its table through;
// defined inside curvlab_protocol (judgements/judgement_format.hpp), so that
// this header does not expose toml++ or the JSON library.
class JudgementSection;
class JudgementFields;

// What an input does in a trial's response window. A type classifies the
// inputs that answer; `early` (an input before the stimulus reached the
// display) is the trial state machine's verdict (runner/trial_state.hpp).
enum class InputUse { ignored, early, choose, increase, decrease, confirm };
struct InputVerdict {
  InputUse use = InputUse::ignored;
  std::size_t option = 0;  // choose: the judgement's option index
};

// A simulated participant as a judgement type sees one (the runner's
// simulated observer stands behind it): it judges the stimulus, picks one of
// n ordered answers, or settles on a value of a parameter.
class Respondent {
 public:
  virtual ~Respondent() = default;
  // The judged quantity of the stimulus as shown at onset (metres).
  virtual double judged() = 0;
  // The judged quantity with `parameter` set to `value`.
  virtual double judged_at(const std::string& parameter, double value) = 0;
  // Which of `n` ordered options the judged quantity gets (may draw noise).
  virtual std::size_t choose(double judged, std::size_t n) = 0;
  // The value of `parameter` in [min, max] it settles on (may draw noise).
  virtual double settle(const std::string& parameter, double min, double max) = 0;
};

// A key or button press at a time on the session clock.
struct KeyPress {
  std::int64_t t_ns = 0;
  std::string name;
  bool button = false;  // the name is one of an answer's `buttons`, else of its `keys`
};

// Whether `input` is one of `keys` or `buttons`.
bool binds(const std::vector<std::string>& keys, const std::vector<std::string>& buttons, const std::string& input);
// What a simulated participant presses at `t_ns` for an answer bound to
// `keys` and `buttons`: the first key, else the first button, else a key
// named "".
KeyPress first_input(std::int64_t t_ns, const std::vector<std::string>& keys, const std::vector<std::string>& buttons);

// What a simulated participant presses for one trial.
struct AnswerPlan {
  std::vector<KeyPress> keys;  // in time order
  double perceived_m = 0.0;    // the judged quantity at onset (logged with the onset)
};

// What a Bayesian adaptive method believes after an answer, for a
// psychometric function P(positive | x) = λ/2 + (1 − λ) Φ(β (x − α)): the
// marginal posterior mean and SD of the PSE α (the parameter's unit), of the
// slope β (per parameter unit) and, when it is estimated, of the lapse rate
// λ, and the entropy of the joint posterior over the grid (nats).
struct PosteriorSummary {
  double pse_mean = 0.0, pse_sd = 0.0;
  double slope_mean = 0.0, slope_sd = 0.0;
  std::optional<double> lapse_mean, lapse_sd;  // nullopt: λ is fixed
  double entropy_nats = 0.0;
};

// One answered step of an adaptive method, as the store keeps it
// (data::StaircaseStep, with the posterior as the trial's `posterior` event).
struct AdaptiveStep {
  std::string track;        // the track's name within its condition (a staircase's name)
  int step = 0;             // steps of the track answered before this one
  double value = 0.0;       // the value shown
  bool positive = false;
  bool reversal = false;    // the answer reversed the track's direction
  double next_value = 0.0;  // the value the track shows next
  std::optional<PosteriorSummary> posterior = std::nullopt;  // Bayesian methods: after this answer
};

// What an adaptive type keeps for one condition (a block's cell) across its
// trials: an interleaved set of staircases, a posterior. Created by
// JudgementType::adaptive_state, one per condition, fed every answer in
// order (a resumed session replays the stored ones first).
class AdaptiveState {
 public:
  virtual ~AdaptiveState() = default;
  // Why the planned slot is not run (stored as its end reason), or nullopt.
  [[nodiscard]] virtual std::optional<std::string> skip_reason(const PlannedTrial& t) const = 0;
  // The value of the judgement's parameter the slot shows.
  [[nodiscard]] virtual double value(const PlannedTrial& t) const = 0;
  // Whether an answer (an option value) counts as positive.
  [[nodiscard]] virtual bool positive(std::string_view answer) const = 0;
  // Records the answer to value(t).
  virtual AdaptiveStep record(const PlannedTrial& t, bool positive) = 0;
};

// How `curvlab predict` forecasts a type's conditions.
enum class Forecast {
  proportions,  // the expected share of each option
  convergence,  // the value each adaptive track settles on
  none,         // not predicted
};

// One answer and the inputs that give it: an option, or an adjustment's
// decrease, increase and confirm.
struct AnswerBinding {
  std::string answer;  // the option's value, or "decrease", "increase", "confirm"
  std::vector<std::string> keys;
  std::vector<std::string> buttons;
  InputVerdict verdict;  // what giving it does: choose the option, or step or confirm the value
};

// One adaptive track of a condition and the P(positive) it settles on.
struct ConvergenceTarget {
  std::string track;     // its name
  std::string positive;  // the option value that counts as positive
  std::string rule;      // how it converges, as predict and preview print it: "1-up/2-down", "psi"
  int up = 1, down = 1;  // the up/down rule (staircases)
  double min = 0.0, max = 0.0;
  double target_p = 0.5;
};

// The parameter's value at a trial's onset when it is not the planned
// settings' (an adjustment's start, a staircase's start), with the note the
// preview sheet shows.
struct OnsetValue {
  double value = 0.0;
  std::string note;
};

// The base class answers as a plain, non-adaptive choice does: one slot per
// cell and repetition, inputs and simulated answers from the options. A type
// overrides what differs.
class JudgementType {
 public:
  virtual ~JudgementType() = default;

  // ---- identity --------------------------------------------------------
  // The `type` value in the protocol, e.g. "choice".
  [[nodiscard]] virtual std::string_view name() const = 0;
  // A few words for the schema, e.g. "n-alternative choice".
  [[nodiscard]] virtual std::string_view summary() const = 0;

  // ---- the protocol file (loader.cpp, schema.cpp) ----------------------
  // The keys its table takes besides `type` and `prompt`, with their schema,
  // and which are required.
  virtual void fields(JudgementFields& out) const = 0;
  // Reads the table (its keys already checked) into `out`, reporting every
  // problem through `section`.
  virtual void read(JudgementSection& section, Judgement& out) const = 0;
  // Why a block of this type cannot repeat its cells `repetitions` times.
  [[nodiscard]] virtual std::optional<std::string> repetitions_problem(int repetitions) const;
  // The parameter values a trial can reach (each must give a possible
  // stimulus in every cell); empty when the type varies nothing.
  [[nodiscard]] virtual std::vector<double> reachable_values(const Judgement& j) const;

  // ---- the design (design.cpp) -----------------------------------------
  // Whether a block may end before its planned trials (an adaptive stop
  // rule): its trial counts are maxima.
  [[nodiscard]] virtual bool stops_early() const;
  // The trials one cell of the block plans (at most, when stops_early).
  [[nodiscard]] virtual std::size_t trials_per_cell(const Block& b) const;
  // The block's slots in run order: repetitions of every cell, shuffled as
  // the block says.
  [[nodiscard]] virtual std::vector<DesignSlot> slots(const Block& b, std::size_t cells, Engine& rng) const;
  // What the type draws for one trial (stored with it); the draws come from
  // the design's stream in trial order.
  virtual void plan_trial(const Judgement& j, PlannedTrial& t, Engine& rng) const;
  // Conditions the type adds to a trial's stored conditions (name → value).
  [[nodiscard]] virtual std::vector<std::pair<std::string, std::string>> conditions(const Judgement& j,
                                                                                    const PlannedTrial& t) const;

  // ---- the session (runner) --------------------------------------------
  // A condition's state, for adaptive types; null for the others.
  [[nodiscard]] virtual std::unique_ptr<AdaptiveState> adaptive_state(const Judgement& j) const;
  // An attempt's adjustable value, for types answered by adjusting.
  [[nodiscard]] virtual std::optional<Adjustment> adjustment(const Judgement& j, const PlannedTrial& t) const;
  // Every answer a participant must be able to give, with its inputs (the
  // CLI refuses devices that cannot give one; pages continue on any of them).
  [[nodiscard]] virtual std::vector<AnswerBinding> answer_bindings(const Judgement& j) const;
  // What an input named `input` that may answer does (never `early`): the
  // verdict of the first answer binding (above) whose keys or buttons name it.
  [[nodiscard]] InputVerdict classify(const Judgement& j, const std::string& input) const;
  // What a simulated participant presses, from `t_ns` on; `adjustment` is
  // the attempt's, for types answered by adjusting.
  [[nodiscard]] virtual AnswerPlan plan_answer(const Judgement& j, Respondent& who, std::int64_t t_ns,
                                               const std::optional<Adjustment>& adjustment) const;

  // ---- predict and preview ---------------------------------------------
  [[nodiscard]] virtual Forecast forecast() const;
  // Forecast::convergence: each track of a condition.
  [[nodiscard]] virtual std::vector<ConvergenceTarget> convergence(const Judgement& j) const;
  // The parameter's value at the trial's onset, when the type sets it.
  [[nodiscard]] virtual std::optional<OnsetValue> onset_value(const Judgement& j, const PlannedTrial& t) const;
  // The type's own settings as the preview sheet lists them, label → text
  // (each staircase's start, steps, up/down and stop rules; an adjustment's
  // start range and steps); empty for a type that has none beyond its
  // answers.
  [[nodiscard]] virtual std::vector<std::pair<std::string, std::string>> settings_summary(const Judgement& j) const;
};

// The registered types, in the order users see them (judgements/registry.cpp).
const std::vector<const JudgementType*>& judgement_types();
// The type named `name`, or null.
const JudgementType* find_judgement_type(std::string_view name);
// The registered names as a list to read: "\"a\", \"b\" or \"c\"".
std::string judgement_type_alternatives();

}  // namespace curvlab::harness::protocol
