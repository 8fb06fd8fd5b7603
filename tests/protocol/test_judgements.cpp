// The judgement types through their one interface (judgement.hpp): the
// registry the loader names them from, a staircase condition's state as the
// runner drives it, and the presses a simulated participant makes for each
// way of answering.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/loader.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using namespace curvlab::harness::protocol;

namespace {

const std::string kHead = "[protocol]\nname = \"t\"\nversion = \"1\"\n[randomization]\nseed = 3\n";

Protocol load(const std::string& judgement) {
  const auto r = load_protocol_text(kHead + judgement, "t.toml");
  if (!r)
    for (const auto& d : r.error().diagnostics) ADD_FAILURE() << format_diagnostic(d);
  return *r;
}

// Answers as a test says: a fixed choice, a fixed value to settle on, and a
// judged quantity that is the parameter's value itself.
class Scripted final : public Respondent {
 public:
  Scripted(std::size_t choice, double settle_on) : choice_(choice), settle_on_(settle_on) {}
  double judged() override { return 0.25; }
  double judged_at(const std::string&, double value) override { return value; }
  std::size_t choose(double, std::size_t) override { return choice_; }
  double settle(const std::string&, double, double) override { return settle_on_; }

 private:
  std::size_t choice_;
  double settle_on_;
};

constexpr std::int64_t kMs = 1'000'000;

}  // namespace

TEST(Judgements, TheLoaderNamesEveryRegisteredTypeInOrder) {
  std::vector<std::string> names;
  for (const JudgementType* t : judgement_types()) names.emplace_back(t->name());
  EXPECT_EQ(names, (std::vector<std::string>{"choice", "adjustment", "staircase", "psi"}));
  for (const auto& name : names) EXPECT_EQ(find_judgement_type(name)->name(), name);
  EXPECT_EQ(find_judgement_type("quest"), nullptr);

  const auto r = load_protocol_text(kHead + "[judgement]\nprompt = \"x\"\n", "t.toml");
  ASSERT_FALSE(r.has_value());
  bool named = false;
  for (const auto& d : r.error().diagnostics)
    named |= d.message == "missing required type: \"choice\", \"adjustment\", \"staircase\" or \"psi\"";
  EXPECT_TRUE(named) << format_diagnostic(r.error().diagnostics.front());
}

// One 1-up/1-down staircase that stops at its first reversal: the state the
// runner keeps for the condition shows the staircase's value, records each
// answer as a step, and then skips the condition's remaining slots.
TEST(Judgements, AStaircaseConditionRecordsStepsAndSkipsOnceStopped) {
  const Protocol p = load(
      "[judgement]\ntype = \"staircase\"\nparameter = \"stimulus.stick_sagitta_m\"\npositive = \"a\"\n"
      "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n"
      "staircases = [{ name = \"s\", start = 0.0, up = 1, down = 1, step_sizes = [0.01], stop_reversals = 1, "
      "discard_reversals = 0, max_trials = 10, min = -0.1, max = 0.1 }]\n");
  const Judgement& j = p.blocks.at(0).judgement;
  EXPECT_TRUE(j.type->stops_early());
  const Design d = expand_design(p, 1);
  ASSERT_EQ(d.trials.size(), 10u);
  const PlannedTrial& t = d.trials[0];
  ASSERT_TRUE(t.staircase.has_value());
  EXPECT_EQ(j.type->conditions(j, t), (std::vector<std::pair<std::string, std::string>>{{"staircase", "s"}}));

  auto state = j.type->adaptive_state(j);
  ASSERT_NE(state, nullptr);
  EXPECT_TRUE(state->positive("a"));
  EXPECT_FALSE(state->positive("b"));
  EXPECT_EQ(state->value(t), 0.0);
  EXPECT_FALSE(state->skip_reason(t).has_value());

  const AdaptiveStep down = state->record(t, true);
  EXPECT_EQ(down.track, "s");
  EXPECT_EQ(down.step, 0);
  EXPECT_EQ(down.value, 0.0);
  EXPECT_FALSE(down.reversal);
  EXPECT_NEAR(down.next_value, -0.01, 1e-12);
  EXPECT_NEAR(state->value(d.trials[1]), -0.01, 1e-12);

  const AdaptiveStep up = state->record(d.trials[1], false);
  EXPECT_EQ(up.step, 1);
  EXPECT_TRUE(up.reversal);
  EXPECT_NEAR(up.next_value, 0.0, 1e-12);
  EXPECT_EQ(state->skip_reason(d.trials[2]), "staircase_finished");

  // Types that are not adaptive keep no state.
  const Protocol c = load("[judgement]\ntype = \"choice\"\n"
                          "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n");
  const Judgement& cj = c.blocks.at(0).judgement;
  EXPECT_EQ(cj.type->adaptive_state(cj), nullptr);
}

TEST(Judgements, AChoiceIsAnsweredWithTheFirstKeyOrElseButtonOfTheChosenOption) {
  const Protocol p = load("[judgement]\ntype = \"choice\"\n"
                          "options = [{ value = \"a\", keys = [\"1\", \"2\"] }, { value = \"b\", buttons = [\"x\"] }]\n");
  const Judgement& j = p.blocks.at(0).judgement;
  Scripted picks_a(0, 0.0), picks_b(1, 0.0);
  const AnswerPlan a = j.type->plan_answer(j, picks_a, 7 * kMs, std::nullopt);
  ASSERT_EQ(a.keys.size(), 1u);
  EXPECT_EQ(a.keys[0].name, "1");
  EXPECT_EQ(a.keys[0].t_ns, 7 * kMs);
  EXPECT_EQ(a.perceived_m, 0.25);
  const AnswerPlan b = j.type->plan_answer(j, picks_b, 7 * kMs, std::nullopt);
  ASSERT_EQ(b.keys.size(), 1u);
  EXPECT_EQ(b.keys[0].name, "x");
  EXPECT_EQ(j.type->classify(j, "2").use, InputUse::choose);
  EXPECT_EQ(j.type->classify(j, "x").option, 1u);
}

// An adjustment is answered by steps toward the value the participant
// settles on, 80 ms apart, and a confirm 200 ms after the last step.
TEST(Judgements, AnAdjustmentIsAnsweredByStepsTowardTheSettledValueThenAConfirm) {
  const Protocol p = load("[judgement]\ntype = \"adjustment\"\nparameter = \"stimulus.stick_sagitta_m\"\n"
                          "min = -0.1\nmax = 0.1\nstart_min = 0.0\nstart_max = 0.0\nstep = 0.01\n");
  const Judgement& j = p.blocks.at(0).judgement;
  const Design d = expand_design(p, 1);
  const auto adjustment = j.type->adjustment(j, d.trials.at(0));
  ASSERT_TRUE(adjustment.has_value());
  EXPECT_EQ(adjustment->value(), 0.0);
  Scripted settles(0, 0.03);
  const AnswerPlan plan = j.type->plan_answer(j, settles, 0, adjustment);
  std::vector<std::string> names;
  for (const auto& k : plan.keys) names.push_back(k.name);
  EXPECT_EQ(names, (std::vector<std::string>{"right", "right", "right", "space"}));
  EXPECT_EQ(plan.keys[2].t_ns, 160 * kMs);
  EXPECT_EQ(plan.keys[3].t_ns, 440 * kMs);
  EXPECT_EQ(plan.perceived_m, 0.0);  // the judged quantity at the start value
  EXPECT_EQ(j.type->classify(j, "left").use, InputUse::decrease);
  EXPECT_EQ(j.type->classify(j, "space").use, InputUse::confirm);
  EXPECT_EQ(j.type->forecast(), Forecast::none);
}
