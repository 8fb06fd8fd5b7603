// The trial state machine driven frame by frame with made-up facts: no
// backend, no clock, no database.
#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/devices/responses.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/trial_state.hpp"
#include "curvlab/harness/xr/actions.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;

namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kPeriod = 11'111'111;  // 90 Hz
constexpr std::int64_t kLatency = 20 * kMs;   // frame start → display

pr::Timeline timeline() {
  pr::Timeline t;
  t.fixation_ms = 500;
  t.stimulus_ms = 1000;
  t.response_ms = 2000;
  return t;
}

rn::FrameFacts frame(std::int64_t k, bool tracked = true, rn::Signal signal = rn::Signal::none) {
  return {k * kPeriod, k * kPeriod + kLatency, tracked, signal};
}

struct Press {
  std::string name;
  bool pressed = true;
};

// One frame's presses as their sources give them: a button box's continue
// button for "continue", keys of the keyboard for the others.
std::vector<curvlab::harness::io::InputEvent> inputs(const std::vector<Press>& presses) {
  std::vector<curvlab::harness::io::InputEvent> out;
  for (const auto& p : presses)
    out.push_back(p.name == "continue" ? curvlab::harness::devices::response_input(0, "box", p.name, p.pressed)
                                       : curvlab::harness::desktop::key_input(0, p.name, p.pressed));
  return out;
}

curvlab::harness::io::InputEvent key(const char* name) { return curvlab::harness::desktop::key_input(0, name, true); }
curvlab::harness::io::InputEvent button(const char* name) {
  return curvlab::harness::xr::controller_input(0, false, name, true);
}

}  // namespace

TEST(TrialState, PhasesFollowTheTimelineAndTheOnsetIsOneFrame) {
  rn::Attempt a(timeline(), {}, 0);
  std::vector<rn::Phase> phases;
  int onsets = 0;
  std::int64_t k = 0;
  for (;; ++k) {
    const auto step = a.advance(frame(k));
    ASSERT_FALSE(step.abort);
    phases.push_back(step.phase);
    onsets += step.onset ? 1 : 0;
    if (step.onset) {
      EXPECT_EQ(step.phase, rn::Phase::stimulus);
      EXPECT_GE(k * kPeriod, 500 * kMs);
      EXPECT_LT((k - 1) * kPeriod, 500 * kMs);
    }
    if (a.over(k * kPeriod)) break;  // after the frame was shown
  }
  EXPECT_EQ(onsets, 1);
  EXPECT_EQ(phases.front(), rn::Phase::fixation);
  EXPECT_EQ(phases.back(), rn::Phase::response);
  // The window ends stimulus + response after the onset frame.
  const std::int64_t onset_frame = *a.onset_frame_ns();
  EXPECT_GE(k * kPeriod - onset_frame, 3000 * kMs);
  EXPECT_LT((k - 1) * kPeriod - onset_frame, 3000 * kMs);
  EXPECT_EQ(*a.onset_display_ns(), onset_frame + kLatency);
}

TEST(TrialState, AnswersCountOnlyFromTheOnsetsDisplayTime) {
  rn::Attempt a(timeline(), {}, 0);
  std::int64_t k = 0;
  while (!a.advance(frame(k)).onset) {
    EXPECT_FALSE(a.answerable(k * kPeriod));
    ++k;
  }
  const std::int64_t display = k * kPeriod + kLatency;
  EXPECT_FALSE(a.answerable(display - 1));  // in the onset frame, before the image is shown
  EXPECT_TRUE(a.answerable(display));
  EXPECT_FALSE(a.over(k * kPeriod));
  a.answered();
  EXPECT_TRUE(a.over(k * kPeriod));
}

TEST(TrialState, SignalsAbortTheAttempt) {
  for (const auto& [signal, reason] :
       {std::pair{rn::Signal::pause, rn::AbortReason::pause},
        std::pair{rn::Signal::recenter, rn::AbortReason::recenter},
        std::pair{rn::Signal::quit, rn::AbortReason::quit}}) {
    rn::Attempt a(timeline(), {}, 0);
    EXPECT_FALSE(a.advance(frame(0)).abort);
    const auto step = a.advance(frame(1, true, signal));
    ASSERT_TRUE(step.abort);
    EXPECT_EQ(*step.abort, reason);
  }
  // A resume signal is not an abort.
  rn::Attempt a(timeline(), {}, 0);
  EXPECT_FALSE(a.advance(frame(0, true, rn::Signal::resume)).abort);
}

TEST(TrialState, TrackingLostLongerThanTheThresholdAborts) {
  pr::TrackingLoss loss;
  loss.loss_ms = 250;
  rn::Attempt a(timeline(), loss, 0);
  // Lost from frame 3: frames until 250 ms later go on, then the abort.
  std::int64_t k = 0;
  for (; k < 3; ++k) EXPECT_FALSE(a.advance(frame(k)).abort);
  std::optional<rn::AbortReason> reason;
  for (; !reason; ++k) reason = a.advance(frame(k, false)).abort;
  EXPECT_EQ(*reason, rn::AbortReason::tracking_lost);
  const std::int64_t lost_for = (k - 1 - 3) * kPeriod;
  EXPECT_GE(lost_for, 250 * kMs);
  EXPECT_LT(lost_for - kPeriod, 250 * kMs);
  // A short loss does not.
  rn::Attempt b(timeline(), loss, 0);
  for (k = 0; k < 10; ++k) EXPECT_FALSE(b.advance(frame(k, k < 5 || k > 7)).abort);
}

TEST(TrialState, TheHeadMeetsWhatTheProtocolRequires) {
  using R = pr::HeadRequirement;
  const curvlab::harness::io::HeadTracking tracked{true, true};
  const curvlab::harness::io::HeadTracking orientation_only{true, false};
  const curvlab::harness::io::HeadTracking inferred{false, false};
  EXPECT_TRUE(rn::head_meets(R::position, true, tracked));
  EXPECT_FALSE(rn::head_meets(R::position, true, orientation_only));
  EXPECT_TRUE(rn::head_meets(R::orientation, true, orientation_only));
  EXPECT_FALSE(rn::head_meets(R::orientation, true, inferred));
  // An unusable pose is untracked for both, whatever the flags say.
  EXPECT_FALSE(rn::head_meets(R::position, false, tracked));
  EXPECT_FALSE(rn::head_meets(R::orientation, false, tracked));
  // none: the head never stops a trial.
  EXPECT_TRUE(rn::head_meets(R::none, false, inferred));
}

TEST(TrialState, FlagCountsLostSpellsAndTheirTime) {
  pr::TrackingLoss loss;
  loss.loss_ms = 100;
  loss.on_loss = pr::OnTrackingLoss::flag;
  rn::Attempt a(timeline(), loss, 0);
  // Two spells of 30 frames (333 ms) and one of 3 frames (below the threshold).
  for (std::int64_t k = 0; k < 200; ++k) {
    const bool lost = (k >= 10 && k < 40) || (k >= 80 && k < 110) || (k >= 150 && k < 153);
    EXPECT_FALSE(a.advance(frame(k, !lost)).abort) << k;
  }
  a.finish(200 * kPeriod);
  EXPECT_EQ(a.loss().spells(), 2);
  EXPECT_EQ(a.loss().lost_ns(), 60 * kPeriod);
  // A spell still open when the attempt ends is closed at its end.
  rn::Attempt b(timeline(), loss, 0);
  for (std::int64_t k = 0; k < 50; ++k) b.advance(frame(k, k < 20));
  b.finish(50 * kPeriod);
  EXPECT_EQ(b.loss().spells(), 1);
  EXPECT_EQ(b.loss().lost_ns(), 30 * kPeriod);
}

TEST(TrialState, AfterAnAbortThePolicyRepeatsOrGivesUp) {
  pr::TrackingLoss repeat;
  EXPECT_EQ(rn::after_abort(rn::AbortReason::tracking_lost, 7, repeat), rn::AfterAbort::repeat);
  EXPECT_EQ(rn::after_abort(rn::AbortReason::pause, 1, repeat), rn::AfterAbort::repeat);
  pr::TrackingLoss abort = repeat;
  abort.on_loss = pr::OnTrackingLoss::abort;
  EXPECT_EQ(rn::after_abort(rn::AbortReason::tracking_lost, 1, abort), rn::AfterAbort::give_up);
  EXPECT_EQ(rn::after_abort(rn::AbortReason::recenter, 1, abort), rn::AfterAbort::repeat);
  pr::TrackingLoss capped = repeat;
  capped.max_attempts = 2;
  EXPECT_EQ(rn::after_abort(rn::AbortReason::pause, 1, capped), rn::AfterAbort::repeat);
  EXPECT_EQ(rn::after_abort(rn::AbortReason::pause, 2, capped), rn::AfterAbort::give_up);
  // A quit attempt runs again when the session is resumed.
  EXPECT_EQ(rn::after_abort(rn::AbortReason::quit, 9, capped), rn::AfterAbort::repeat);
}

TEST(TrialState, InputsAreChoicesAdjustmentsOrAnticipations) {
  pr::Judgement choice;
  choice.type = pr::find_judgement_type("choice");
  choice.options = {{"convex", "", {"1"}, {"x"}}, {"straight", "", {"2"}, {}}, {"concave", "", {"3"}, {"b"}}};
  EXPECT_EQ(rn::classify_input(choice, key("1"), false).use, rn::InputUse::early);
  EXPECT_EQ(rn::classify_input(choice, key("9"), true).use, rn::InputUse::ignored);
  const auto by_button = rn::classify_input(choice, button("b"), true);
  EXPECT_EQ(by_button.use, rn::InputUse::choose);
  EXPECT_EQ(by_button.option, 2u);
  EXPECT_EQ(rn::classify_input(choice, key("2"), true).option, 1u);

  pr::AdjustmentSpec spec;
  spec.keys_increase = {"up"};
  spec.keys_decrease = {"down"};
  spec.buttons_confirm = {"a"};
  const pr::Judgement adjust = pr::adjustment_judgement(spec, "stimulus.stick_sagitta_m");
  EXPECT_EQ(rn::classify_input(adjust, key("up"), true).use, rn::InputUse::increase);
  EXPECT_EQ(rn::classify_input(adjust, key("down"), true).use, rn::InputUse::decrease);
  EXPECT_EQ(rn::classify_input(adjust, button("a"), true).use, rn::InputUse::confirm);
  EXPECT_EQ(rn::classify_input(adjust, key("up"), false).use, rn::InputUse::early);
}

TEST(TrialState, PagesIgnoreHeldKeysAndWaitTheirMinimumTime) {
  const std::vector<std::string> none;
  rn::Page page(0, 1000 * kMs, none);
  const auto space = inputs({{"space"}});
  EXPECT_FALSE(page.frame(2000 * kMs, space));  // first frame: a key held from before
  EXPECT_TRUE(page.frame(2000 * kMs, space));
  rn::Page early(0, 1000 * kMs, none);
  early.frame(0, inputs({}));
  EXPECT_FALSE(early.frame(500 * kMs, space));  // too soon
  EXPECT_FALSE(early.frame(1500 * kMs, inputs({{"space", false}})));  // a release
  EXPECT_FALSE(early.frame(1500 * kMs, inputs({{"x"}})));
  EXPECT_TRUE(early.frame(1500 * kMs, inputs({{"continue"}})));
  early.restart();  // after a pause: the next frame's keys were held through it
  EXPECT_FALSE(early.frame(1600 * kMs, space));
  EXPECT_TRUE(early.frame(1700 * kMs, space));
}

TEST(TrialState, NamesRoundTrip) {
  for (auto p : {rn::Phase::instructions, rn::Phase::fixation, rn::Phase::stimulus, rn::Phase::response,
                 rn::Phase::iti, rn::Phase::break_page, rn::Phase::done, rn::Phase::paused, rn::Phase::tracking_lost,
                 rn::Phase::calibration})
    EXPECT_EQ(rn::parse_phase(rn::to_string(p)), p);
  for (auto r : {rn::AbortReason::pause, rn::AbortReason::recenter, rn::AbortReason::tracking_lost,
                 rn::AbortReason::quit})
    EXPECT_EQ(rn::parse_abort_reason(rn::to_string(r)), r);
  EXPECT_EQ(rn::to_string(rn::Phase::break_page), "break");
  EXPECT_FALSE(rn::parse_phase("Stimulus"));
}

namespace {

pr::Protocol example(const std::string& name) {
  auto loaded = pr::load_protocol_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/" + name + ".toml");
  EXPECT_TRUE(loaded.has_value());
  return *loaded;
}

curvlab::harness::io::Reach keyboard() {
  curvlab::harness::io::Reach r;
  r.every_key = true;
  r.continue_phrase = "press space";
  return r;
}

curvlab::harness::io::Reach controllers() {
  curvlab::harness::io::Reach r;
  r.buttons = {"left_trigger", "right_trigger", "a", "b", "x", "y"};
  r.continue_phrase = "pull a trigger or press A";
  return r;
}

}  // namespace

TEST(TrialState, PagesAlsoContinueOnEveryAnswerTheProtocolBinds) {
  const pr::Protocol demo = example("demo");
  const auto continues = rn::page_continues(demo);
  EXPECT_EQ(continues, (std::vector<std::string>{"1", "2", "3"}));
  rn::Page page(0, 0, continues);
  page.frame(0, inputs({}));
  EXPECT_FALSE(page.frame(kMs, inputs({{"q"}})));
  EXPECT_TRUE(page.frame(2 * kMs, inputs({{"2"}})));
}

TEST(TrialState, TheContinueLineSaysWhatTheDevicesAtHandCanDo) {
  const pr::Protocol demo = example("demo");              // keys only
  const pr::Protocol study = example("proposed_study");   // keys and controller buttons
  EXPECT_EQ(rn::continue_line({keyboard()}, demo), "To continue: press space, or give any answer.");
  // The headset cannot give the demo's keys: only its own way is offered.
  EXPECT_EQ(rn::continue_line({controllers()}, demo), "To continue: pull a trigger or press A.");
  EXPECT_EQ(rn::continue_line({controllers()}, study), "To continue: pull a trigger or press A, or give any answer.");
  EXPECT_EQ(rn::continue_line({}, demo), "");
}

TEST(TrialState, AnAnswerNoDeviceCanGiveIsNamed) {
  const pr::Protocol demo = example("demo");
  const auto missing = rn::unreachable_answer({controllers()}, demo);
  ASSERT_TRUE(missing.has_value());
  EXPECT_NE(missing->find("'convex' (keys 1)"), std::string::npos) << *missing;
  EXPECT_NE(missing->find("choice"), std::string::npos) << *missing;
  EXPECT_FALSE(rn::unreachable_answer({keyboard()}, demo).has_value());
  EXPECT_FALSE(rn::unreachable_answer({controllers()}, example("proposed_study")).has_value());
  // The adjustment's decrease, increase and confirm each need an input.
  EXPECT_FALSE(rn::unreachable_answer({keyboard()}, example("body_coherence")).has_value());
  const auto adjust = rn::unreachable_answer({controllers()}, example("body_coherence"));
  ASSERT_TRUE(adjust.has_value());
  EXPECT_NE(adjust->find("'decrease'"), std::string::npos) << *adjust;
}
