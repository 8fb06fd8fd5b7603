// Pages and holds, shown between a block kind's own frames: instructions,
// breaks, the closing page, pauses and waits for the head.
#include "session_frames.hpp"

#include "curvlab/harness/runner/trial_state.hpp"

#include <cstdio>
#include <cstdlib>

namespace curvlab::harness::runner {

namespace {

// The event a page is logged as; pages are shown only in these three phases.
data::EventKind page_event(Phase phase) {
  switch (phase) {
    case Phase::instructions: return data::EventKind::instructions;
    case Phase::break_page: return data::EventKind::break_page;
    case Phase::done: return data::EventKind::done;
    case Phase::fixation:
    case Phase::stimulus:
    case Phase::response:
    case Phase::iti:
    case Phase::paused:
    case Phase::tracking_lost:
    case Phase::calibration: break;
  }
  std::fprintf(stderr, "curvlab: a page shown in phase %s\n", std::string(to_string(phase)).c_str());
  std::abort();
}

}  // namespace

Outcome SessionFrames::pages(const std::vector<std::string>& texts, Phase phase, std::int64_t min_ns,
                             std::optional<std::int64_t> trial_id) {
  for (std::size_t k = 0; k < texts.size(); ++k)
    if (page(texts[k], k, phase, min_ns, trial_id) == Outcome::quit) return Outcome::quit;
  scene_->show(Phase::iti, false);
  return Outcome::done;
}

Outcome SessionFrames::page(const std::string& text, std::size_t k, Phase phase, std::int64_t min_ns,
                            std::optional<std::int64_t> trial_id) {
  Frame f;
  if (!begin(f)) return Outcome::quit;
  // The protocol's text, then how to go on with the devices at hand.
  const std::string shown_text = continue_line_.empty() ? text : text + "\n\n" + continue_line_;
  if (auto shown = scene_->set_page(shown_text); !shown) throw Stop{shown.error()};
  scene_->show(phase, false);
  Page state(f.timing.now_ns, min_ns, continues_);
  for (TrialWatcher* w : watchers) w->page_shown(f.timing.now_ns, min_ns);
  event(trial_id, data::events::Page{page_event(phase), k, shown_text}, f.timing.predicted_display_ns);
  // The page waits for a key once its shortest time has passed (a break's
  // break_min_ms): a key before then does not turn it.
  io::Overlay overlay{phase, shown_text, true};
  const std::int64_t open_ns = f.timing.now_ns + min_ns;
  for (;;) {
    overlay.waiting_for_input = f.timing.now_ns >= open_ns;
    const bool advance = state.frame(f.timing.now_ns, f.inputs);
    if (f.signal == Signal::quit) return Outcome::quit;
    if (f.signal == Signal::pause) {
      // The page stays; keys pressed while paused or held from then do not count.
      if (hold(phase, trial_id) == Outcome::quit) return Outcome::quit;
      state.restart();
    } else {
      end(f, overlay, false, trial_id);
      if (advance) return Outcome::done;
    }
    if (!begin(f)) return Outcome::quit;
  }
}

Outcome SessionFrames::hold(Phase phase, std::optional<std::int64_t> trial_id) {
  const std::int64_t from = clock.now_ns();
  event(trial_id, data::events::Paused{std::string(to_string(phase))});
  if (wait_until_ready(AbortReason::pause, trial_id) == Outcome::quit) return Outcome::quit;
  event(trial_id, data::events::Unpaused{std::string(to_string(phase)),
                                         static_cast<double>(clock.now_ns() - from) * 1e-6});
  return Outcome::done;
}

// So that one loss does not abort the trials after it as well. The head is
// waited for at most [tracking] head_wait_ms: a headset that never tracks
// what head_requires asks for stops the session, resumable.
Outcome SessionFrames::wait_until_ready(AbortReason reason, std::optional<std::int64_t> trial_id) {
  const bool paused = reason == AbortReason::pause;
  if (paused) writer.journal(data::StatusChange{session_id, data::SessionStatus::paused, false});
  scene_->show(Phase::iti, false);
  const io::Overlay overlay{paused ? Phase::paused : Phase::tracking_lost, "waiting", false};
  const std::int64_t since_ns = clock.now_ns();
  for (;;) {
    Frame f;
    if (!begin(f)) return Outcome::quit;
    end(f, overlay, false, trial_id);
    if (f.signal == Signal::quit) return Outcome::quit;
    if (paused ? f.signal == Signal::resume : f.head_tracked) break;
    if (!paused && f.timing.now_ns - since_ns >= ms_to_ns(settings_.tracking_loss.head_wait_ms))
      throw Stop{head_never_came(reason)};
  }
  if (paused) writer.journal(data::StatusChange{session_id, data::SessionStatus::running, false});
  return Outcome::done;
}

Error SessionFrames::head_never_came(AbortReason reason) const {
  const auto& policy = settings_.tracking_loss;
  std::string reported = station.poses->describe_head_tracking();
  if (reported.empty()) reported = tracker_ && tracker_->output().tracked[0] ? "tracked" : "not tracked";
  char waited[32];
  std::snprintf(waited, sizeof waited, "%.3g s", static_cast<double>(policy.head_wait_ms) * 1e-3);
  return Error{Error::Kind::device,
               "the head was not tracked as [tracking] head_requires = \"" +
                   std::string(to_string(policy.head_requires)) + "\" asks for " + waited +
                   " after the attempt ended (" + std::string(to_string(reason)) +
                   "); the headset reports the head " + reported +
                   ". Check the headset's tracking, or for a headset that tracks no position set "
                   "head_requires = \"orientation\""};
}

}  // namespace curvlab::harness::runner
