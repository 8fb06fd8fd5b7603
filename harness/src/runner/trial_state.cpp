#include "curvlab/harness/runner/trial_state.hpp"

#include <algorithm>

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

bool head_meets(protocol::HeadRequirement need, bool pose_tracked, const io::HeadTracking& head) {
  switch (need) {
    case protocol::HeadRequirement::position: return pose_tracked && head.orientation_tracked && head.position_tracked;
    case protocol::HeadRequirement::orientation: return pose_tracked && head.orientation_tracked;
    case protocol::HeadRequirement::none: return true;
  }
  return pose_tracked;
}

InputVerdict classify_input(const protocol::Judgement& j, const io::InputEvent& in, bool answerable) {
  if (!answerable) return {InputUse::early};
  const auto answers = j.type->answer_bindings(j);
  const auto k = io::answer_index(answers, in.control);
  return k ? answers[*k].verdict : InputVerdict{};
}

namespace {

// Each judgement of the protocol once: the session's, then each block's own.
template <class F>
void for_each_judgement(const protocol::Protocol& p, F&& f) {
  f(p.judgement, std::string("the session's judgement"));
  for (const auto& b : p.blocks)
    if (b.judgement.type != nullptr) f(b.judgement, "block '" + b.name + "'");
}

bool reachable(const std::vector<io::Reach>& sources, const protocol::AnswerBinding& a) {
  return std::any_of(sources.begin(), sources.end(), [&](const io::Reach& r) {
    return std::any_of(a.keys.begin(), a.keys.end(), [&](const std::string& k) { return r.gives_key(k); }) ||
           std::any_of(a.buttons.begin(), a.buttons.end(), [&](const std::string& b) { return r.gives_button(b); });
  });
}

std::string join(const std::vector<std::string>& words, const char* sep) {
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i) out += (i ? sep : "") + words[i];
  return out;
}

}  // namespace

std::vector<std::string> page_continues(const protocol::Protocol& p) {
  std::vector<std::string> out;
  auto add = [&out](const std::vector<std::string>& names) {
    for (const auto& n : names)
      if (std::find(out.begin(), out.end(), n) == out.end()) out.push_back(n);
  };
  for_each_judgement(p, [&](const protocol::Judgement& j, const std::string&) {
    if (j.type == nullptr) return;
    for (const auto& a : j.type->answer_bindings(j)) {
      add(a.keys);
      add(a.buttons);
    }
  });
  return out;
}

std::string continue_line(const std::vector<io::Reach>& sources, const protocol::Protocol& p) {
  std::vector<std::string> ways;
  for (const auto& r : sources)
    if (!r.continue_phrase.empty() && std::find(ways.begin(), ways.end(), r.continue_phrase) == ways.end())
      ways.push_back(r.continue_phrase);
  bool answers = false;
  for_each_judgement(p, [&](const protocol::Judgement& j, const std::string&) {
    if (j.type == nullptr) return;
    for (const auto& a : j.type->answer_bindings(j)) answers = answers || reachable(sources, a);
  });
  if (ways.empty() && !answers) return "";
  if (answers) ways.emplace_back("give any answer");
  return "To continue: " + join(ways, ", or ") + ".";
}

std::string response_panel_text(const protocol::Judgement& j, const std::vector<io::Reach>& sources) {
  if (j.type == nullptr) return j.prompt;
  const bool keyboard = sources.empty() || std::any_of(sources.begin(), sources.end(), [](const io::Reach& r) {
                          return r.gives_key("");
                        });
  constexpr const char* kNoBreak = "\u00a0";  // keeps an answer's input and label on one line
  auto readable = [&](std::string name) {
    std::replace(name.begin(), name.end(), '_', ' ');
    std::string out;
    for (const char c : name) out += c == ' ' ? std::string(kNoBreak) : std::string(1, c);
    return out;
  };
  std::vector<std::string> answers;
  for (const auto& a : j.type->answer_bindings(j)) {
    std::vector<std::string> inputs;
    if (keyboard) inputs = a.keys;
    for (const auto& b : a.buttons)
      if (std::any_of(sources.begin(), sources.end(), [&](const io::Reach& r) { return r.gives_button(b); }) &&
          (inputs.empty() || !keyboard))
        inputs.push_back(b);
    if (inputs.empty()) continue;
    std::string label = a.answer;
    for (const auto& o : j.options)
      if (o.value == a.answer && !o.label.empty()) label = o.label;
    std::vector<std::string> shown;
    for (const auto& in : inputs) shown.push_back(readable(in));
    std::string answer{"["};
    answer += join(shown, "/");
    answer += ']';
    answer += kNoBreak;
    answer += readable(label);
    answers.push_back(std::move(answer));
  }
  if (answers.empty()) return j.prompt;
  std::string text = j.prompt;
  if (!text.empty()) text += "\n\n";
  for (std::size_t i = 0; i < answers.size(); ++i) {
    if (i > 0) text += "     ";
    text += answers[i];
  }
  return text;
}

std::optional<std::string> unreachable_answer(const std::vector<io::Reach>& sources,
                                              const protocol::Protocol& p) {
  std::optional<std::string> out;
  for_each_judgement(p, [&](const protocol::Judgement& j, const std::string& where) {
    if (out || j.type == nullptr) return;
    for (const auto& a : j.type->answer_bindings(j)) {
      if (reachable(sources, a)) continue;
      std::string inputs;
      if (!a.keys.empty()) inputs += "keys " + join(a.keys, ", ");
      if (!a.buttons.empty()) inputs += std::string(inputs.empty() ? "" : "; ") + "buttons " + join(a.buttons, ", ");
      out = where + " (" + std::string(j.type->name()) + "): the answer '" + a.answer + "' (" + inputs + ")";
      return;
    }
  });
  return out;
}

bool Page::is_continue(const io::InputEvent& in) const {
  return in.intents.has(io::Intent::continue_page) ||
         std::find(continues_.begin(), continues_.end(), in.control.name) != continues_.end();
}

}  // namespace curvlab::harness::runner
