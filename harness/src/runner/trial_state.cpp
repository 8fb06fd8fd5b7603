#include "curvlab/harness/runner/trial_state.hpp"

namespace curvlab::harness::runner {

namespace {

constexpr std::int64_t ms(std::int64_t v) { return v * 1'000'000; }

}  // namespace

bool TrackingLossMonitor::update(std::int64_t now_ns, bool tracked) {
  if (tracked) {
    finish(now_ns);
    untracked_since_ = -1;
    return false;
  }
  if (untracked_since_ < 0) untracked_since_ = now_ns;
  if (now_ns - untracked_since_ < ms(policy_.loss_ms)) return false;
  if (policy_.on_loss != protocol::OnTrackingLoss::flag) return true;
  in_spell_ = true;
  return false;
}

void TrackingLossMonitor::finish(std::int64_t now_ns) {
  if (!in_spell_) return;
  lost_ns_ += now_ns - untracked_since_;
  ++spells_;
  in_spell_ = false;
}

Attempt::Attempt(const protocol::Timeline& timeline, const protocol::TrackingLoss& loss, std::int64_t start_ns)
    : timeline_(timeline), loss_(loss), start_ns_(start_ns) {}

AttemptStep Attempt::advance(const FrameFacts& frame) {
  AttemptStep step;
  switch (frame.signal) {
    case Signal::quit: step.abort = AbortReason::quit; return step;
    case Signal::pause: step.abort = AbortReason::pause; break;
    case Signal::recenter: step.abort = AbortReason::recenter; break;
    case Signal::repeat: step.abort = AbortReason::repeat; break;
    case Signal::skip: step.abort = AbortReason::skip; break;
    default: break;
  }
  // The loss is tracked even when the frame is aborted for another reason,
  // so that a spell's time is complete.
  const bool lost = loss_.update(frame.now_ns, frame.head_tracked);
  if (!step.abort && lost) step.abort = AbortReason::tracking_lost;
  if (step.abort) return step;

  if (!onset_frame_ns_ && frame.now_ns - start_ns_ >= ms(timeline_.fixation_ms)) {
    onset_frame_ns_ = frame.now_ns;
    onset_display_ns_ = frame.display_ns;
    step.onset = true;
  }
  if (!onset_frame_ns_) step.phase = Phase::fixation;
  else if (frame.now_ns - *onset_frame_ns_ < ms(timeline_.stimulus_ms)) step.phase = Phase::stimulus;
  else step.phase = Phase::response;
  return step;
}

bool Attempt::over(std::int64_t now_ns) const {
  if (answered_) return true;
  return onset_frame_ns_ && now_ns - *onset_frame_ns_ >= ms(timeline_.stimulus_ms + timeline_.response_ms);
}

AfterAbort after_abort(AbortReason reason, std::int64_t attempt, const protocol::TrackingLoss& policy) {
  // A quit attempt is run again when the session is resumed.
  if (reason == AbortReason::quit) return AfterAbort::repeat;
  // The operator decides for these two, whatever the protocol's cap.
  if (reason == AbortReason::skip) return AfterAbort::give_up;
  if (reason == AbortReason::repeat) return AfterAbort::repeat;
  if (reason == AbortReason::tracking_lost && policy.on_loss == protocol::OnTrackingLoss::abort)
    return AfterAbort::give_up;
  if (policy.max_attempts > 0 && attempt >= policy.max_attempts) return AfterAbort::give_up;
  return AfterAbort::repeat;
}

InputVerdict classify_input(const protocol::Judgement& j, const std::string& name, bool answerable) {
  if (!answerable) return {InputUse::early};
  return j.type->classify(j, name);
}

bool Page::is_continue(const std::string& name) {
  return name == "space" || name == "enter" || name == "return" || name == "continue";
}

}  // namespace curvlab::harness::runner
