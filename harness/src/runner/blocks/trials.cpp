// The trials block kind: the block's planned trials in order, each run as
// attempts of the pure state machine of trial_state.hpp —
//   fixation → stimulus → response window → inter-trial interval —
// with breaks between them, repeats after an abort, and an adaptive
// method's or an adjustment's value set on each attempt.
#include "../block_kind.hpp"
#include "../session_records.hpp"

#include "curvlab/harness/numbered_files.hpp"
#include "curvlab/harness/protocol/adjustment.hpp"
#include "curvlab/harness/runner/image_observer.hpp"
#include "curvlab/harness/runner/trial_state.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>

namespace curvlab::harness::runner {

namespace {

using geometry::Isometry;
using protocol::PlannedTrial;
using protocol::Settings;

std::string trial_line(const PlannedTrial& t) {
  std::string line = t.block + "  trial " + std::to_string(t.trial_in_block + 1);
  for (const auto& [f, l] : t.levels) line += "  " + f + "=" + l;
  return line;
}

// How long the attempt's current phase lasts after `now_ns`.
std::int64_t phase_left(const Attempt& a, Phase phase, const protocol::Timeline& tl, std::int64_t now_ns) {
  const auto onset = a.onset_frame_ns();
  switch (phase) {
    case Phase::fixation: return std::max<std::int64_t>(0, a.start_ns() + ms_to_ns(tl.fixation_ms) - now_ns);
    case Phase::stimulus:
      return onset ? std::max<std::int64_t>(0, *onset + ms_to_ns(tl.stimulus_ms) - now_ns) : -1;
    case Phase::response:
      return onset ? std::max<std::int64_t>(0, *onset + ms_to_ns(tl.stimulus_ms + tl.response_ms) - now_ns) : -1;
    default: return -1;
  }
}

struct TrialRun {
  std::size_t index = 0;
  std::int64_t id = 0;
  const PlannedTrial* planned = nullptr;
  const protocol::Judgement* judgement = nullptr;
  Settings settings;
  std::optional<double> adaptive_value;  // the value an adaptive method shows
  std::string line;
  std::int64_t attempts = 0;  // attempts made so far, stored ones included
  std::int64_t aborts = 0;    // of which ended in a logged abort
};

struct AttemptRun {
  std::int64_t number = 1;
  std::optional<protocol::Adjustment> adjustment;
  Isometry head_at_onset;
  Placement placement;
  OnsetView onset_view;  // the eyes at onset (the image observer, the images' record)
  OnsetNote note;        // what the watchers (or the human model) made of the onset
  std::optional<std::pair<std::string, io::InputEvent>> answer;
  std::optional<AbortReason> abort;
  bool display_ended = false;  // begin_frame gave no frame: no abort event
  std::optional<std::int64_t> onset_ns;
  int lost_spells = 0;
  std::int64_t lost_ns = 0;
};

// What the pilot window shows beside the scene during an attempt: the
// trial's line, the question and its answers (shown while the runner waits
// for one). Made once per attempt; each frame sets only the phase and the
// value (set_overlay_value).
io::Overlay attempt_overlay(const TrialRun& t) {
  io::Overlay o{Phase::fixation, t.line, false};
  const auto& j = *t.judgement;
  o.prompt = j.prompt;
  for (const auto& b : j.type->answer_bindings(j)) o.answers.push_back({b.answer, b.keys, b.buttons});
  return o;
}

// The value a method varies, as the overlay shows it: written again only
// when it changed (an adjustment step), not every frame.
void set_overlay_value(io::Overlay& o, const TrialRun& t, const AttemptRun& a, std::optional<double>& written) {
  std::optional<double> shown = t.adaptive_value;
  if (a.adjustment) shown = a.adjustment->value();
  if (!shown || shown == written) return;
  written = shown;
  char buf[64];
  std::snprintf(buf, sizeof buf, " = %.6g", *shown);
  o.value = t.judgement->parameter + buf;
}

// One trials block as a run meets it.
class TrialsBlock {
 public:
  explicit TrialsBlock(BlockRun& run) : run_(run), f_(run.frames) {}

  Outcome run() {
    const std::size_t first = run_.block.first_trial + run_.from;
    const std::size_t end = run_.block.first_trial + run_.block.trial_count;
    for (std::size_t i = first; i < end; ++i) {
      const PlannedTrial& t = f_.design.trials[i];
      if (take_break(i, first) == Outcome::quit) return Outcome::quit;
      if (const auto reason = skip_reason(t)) {
        f_.writer.journal(data::EndUnanswered{f_.trial_ids[i], false, *reason});
        ++f_.summary.trials_skipped;
        f_.report_trial(i, data::TrialStatus::skipped, *reason);
        continue;
      }
      if (run_trial(i) == Outcome::quit) return Outcome::quit;
      f_.update_progress();
    }
    return Outcome::done;
  }

 private:
  Outcome take_break(std::size_t i, std::size_t first) {
    const PlannedTrial& t = f_.design.trials[i];
    if (!t.break_before || i == first) return Outcome::done;
    const auto& b = block_of(f_.protocol, t);
    return f_.pages({b.break_text.empty() ? std::string("Break") : b.break_text}, Phase::break_page,
                    ms_to_ns(b.break_min_ms), f_.trial_ids[i]);
  }

  // A slot an adaptive method no longer needs (a stopped staircase's).
  std::optional<std::string> skip_reason(const PlannedTrial& t) {
    const protocol::AdaptiveState* state = f_.adaptive_for(t);
    return state ? state->skip_reason(t) : std::nullopt;
  }

  TrialRun start_trial(std::size_t i) {
    TrialRun t;
    t.index = i;
    t.id = f_.trial_ids[i];
    t.planned = &f_.design.trials[i];
    t.judgement = &block_of(f_.protocol, *t.planned).judgement;
    t.settings = t.planned->settings;
    t.line = trial_line(*t.planned);
    if (const auto* state = f_.adaptive_for(*t.planned)) {
      t.adaptive_value = state->value(*t.planned);
      protocol::set_numeric_setting(t.settings, t.judgement->parameter, *t.adaptive_value);
    }
    if (!f_.resumed_trial.taken) {
      t.attempts = f_.resumed_trial.attempts;
      t.aborts = f_.resumed_trial.aborts;
      f_.resumed_trial.taken = true;
    }
    f_.set_current_trial(i);
    auto& status = f_.room.status;
    status.late_trial = 0;
    status.block = t.planned->block;
    status.trial = static_cast<std::int64_t>(i + 1);
    status.condition.clear();
    for (const auto& [factor, level] : t.planned->levels) status.condition += factor + "=" + level + "  ";
    return t;
  }

  Outcome run_trial(std::size_t i) {
    TrialRun t = start_trial(i);
    for (;;) {
      AttemptRun a = run_attempt(t);
      if (!a.abort) {
        complete(t, a);
        const Outcome o = inter_trial_interval(t);
        f_.set_current_trial(std::nullopt);
        if (o == Outcome::done) f_.report_trial(t.index, data::TrialStatus::completed, "");
        return o;
      }
      if (a.display_ended) return Outcome::quit;
      f_.event(t.id, data::events::TrialAborted{std::string(to_string(*a.abort)), a.number});
      if (*a.abort == AbortReason::quit) return Outcome::quit;
      ++t.aborts;
      if (*a.abort == AbortReason::skip) {
        end_unanswered(t, data::TrialStatus::skipped, "operator", data::events::TrialSkipped{"operator", t.attempts});
        return Outcome::done;
      }
      // The operator's repeat starts again at once; the others wait for the
      // resume or for the head.
      if (*a.abort != AbortReason::repeat && f_.wait_until_ready(*a.abort, t.id) == Outcome::quit)
        return Outcome::quit;
      if (after_abort(*a.abort, a.number, t.settings.tracking_loss) == AfterAbort::give_up) {
        const std::string reason(to_string(*a.abort));
        end_unanswered(t, data::TrialStatus::aborted, reason, data::events::TrialAbandoned{reason, a.number});
        return Outcome::done;
      }
      f_.event(t.id, data::events::TrialRepeated{std::string(to_string(*a.abort))});
    }
  }

  // A trial given up (aborted) or skipped by the operator (stored `skipped`,
  // end_reason "operator", so a resumed session never runs it again).
  void end_unanswered(const TrialRun& t, data::TrialStatus status, const std::string& reason, const data::Event& e) {
    const bool aborted = status == data::TrialStatus::aborted;
    f_.writer.journal(data::EndUnanswered{t.id, aborted, reason});
    f_.event(t.id, e);
    ++(aborted ? f_.summary.trials_aborted : f_.summary.trials_skipped);
    f_.set_current_trial(std::nullopt);
    f_.report_trial(t.index, status, reason);
  }

  // A new attempt: the stimulus from its start values, the watchers told
  // (the observer's stream for session, trial and attempt), the attempt
  // counted in the store.
  AttemptRun begin_attempt(TrialRun& t) {
    AttemptRun a;
    a.number = ++t.attempts;
    f_.room.status.attempt = a.number;
    if (a.number > 1) ++f_.summary.attempts_repeated;
    const auto& j = *t.judgement;
    a.adjustment = j.type->adjustment(j, *t.planned);
    if (a.adjustment) protocol::set_numeric_setting(t.settings, j.parameter, a.adjustment->value());
    f_.prepare(t.settings, f_.response_panel(j));
    f_.writer.journal(data::BeginTrial{t.id});
    for (TrialWatcher* w : f_.watchers) w->attempt_begins(t.index, t.aborts + 1);
    return a;
  }

  AttemptRun run_attempt(TrialRun& t) {
    AttemptRun a = begin_attempt(t);
    Frame f;
    if (!f_.begin(f)) {
      a.abort = AbortReason::quit;
      a.display_ended = true;
      return a;
    }
    Attempt state(t.settings.timeline, t.settings.tracking_loss, f.timing.now_ns);
    io::Overlay overlay = attempt_overlay(t);
    std::optional<double> value_written;
    auto& scene = f_.scene();
    scene.place(place_stimulus(f_.world(), t.settings, f_.head()), f_.head());
    for (;;) {
      const AttemptStep step = state.advance(f.facts());
      if (step.abort) {
        a.abort = step.abort;
        break;
      }
      if (step.onset) present_onset(t, a, f);
      take_inputs(t, a, state, f);
      scene.show(step.phase, t.settings.timeline.stimulus_during_response);
      overlay.phase = step.phase;
      overlay.waiting_for_input = step.phase == Phase::response || step.phase == Phase::stimulus;
      set_overlay_value(overlay, t, a, value_written);
      f_.room.phase_left_ns = phase_left(state, step.phase, t.settings.timeline, f.timing.now_ns);
      const auto stats = f_.end(f, overlay, step.onset, t.id);
      if (step.onset) log_onset(t, a, stats, f.timing.predicted_display_ns);
      if (state.over(f.timing.now_ns)) break;
      if (!f_.begin(f)) {
        a.abort = AbortReason::quit;
        a.display_ended = true;
        break;
      }
    }
    state.finish(f_.clock.now_ns());
    a.onset_ns = state.onset_display_ns();
    a.lost_spells = state.loss().spells();
    a.lost_ns = state.loss().lost_ns();
    return a;
  }

  // Onset: the stimulus is placed once, from the head at this frame.
  void present_onset(const TrialRun& t, AttemptRun& a, const Frame& f) {
    a.head_at_onset = f_.head();
    a.placement = place_stimulus(f_.world(), t.settings, a.head_at_onset);
    f_.scene().place(a.placement, a.head_at_onset);
    const auto& p = f_.protocol;
    a.onset_view = {view_settings(t.settings, f_.dominant()), a.head_at_onset, f_.station.display->rig(f.timing, f_.ipd()),
                    static_cast<std::uint32_t>(p.resolution_width), static_cast<std::uint32_t>(p.resolution_height)};
    a.note = {};
    const OnsetFacts facts{f_.world(), *t.judgement, t.settings, a.placement, a.head_at_onset,
                           f.timing.now_ns, a.adjustment, a.onset_view};
    bool noted = false;
    for (TrialWatcher* w : f_.watchers)
      if (auto note = w->onset(facts)) {
        a.note = std::move(*note);
        noted = true;
      }
    // Where the eyes are tracked, the human model's account of the stimulus
    // is stored with the onset all the same: its vergence demand is what the
    // measured vergence is compared with (docs/xr.md, "Eye tracking").
    if (!noted && f_.station.poses->gaze())
      a.note.account = perceive(f_.world(), t.settings, a.placement, a.head_at_onset, ObserverParams{}).human;
  }

  // Responses count from the onset's display to the end of the window; a
  // press before the stimulus was on the display is an anticipation.
  void take_inputs(TrialRun& t, AttemptRun& a, Attempt& state, const Frame& f) {
    for (const auto& in : f.inputs) {
      if (!in.pressed || a.answer) continue;
      const auto verdict = classify_input(*t.judgement, in, state.answerable(in.t_ns));
      switch (verdict.use) {
        case InputUse::ignored: break;
        case InputUse::early: f_.event(t.id, data::events::EarlyInput{in.control.name, io::to_string(in.source), in.t_ns}); break;
        case InputUse::choose:
          a.answer = std::pair{t.judgement->options[verdict.option].value, in};
          state.answered();
          break;
        case InputUse::increase:
        case InputUse::decrease:
          verdict.use == InputUse::increase ? a.adjustment->increase() : a.adjustment->decrease();
          protocol::set_numeric_setting(t.settings, t.judgement->parameter, a.adjustment->value());
          a.placement = place_stimulus(f_.world(), t.settings, a.head_at_onset);
          f_.scene().set_stimulus(t.settings, a.placement);
          f_.event(t.id, data::events::AdjustmentEvent{a.adjustment->value(), f_.frame_index()});
          break;
        case InputUse::confirm: {
          a.adjustment->confirm();
          char buf[64];
          std::snprintf(buf, sizeof buf, "%.9g", a.adjustment->value());
          a.answer = std::pair{std::string(buf), in};
          state.answered();
          break;
        }
      }
    }
  }

  void log_onset(const TrialRun& t, const AttemptRun& a, const renderer::FrameStats& stats, std::int64_t display_ns) {
    data::events::Onset onset;
    onset.frame_index = f_.frame_index() - 1;
    onset.predicted_display_ns = display_ns;
    onset.attempt = a.number;
    onset.head_pose = pose16(a.head_at_onset);
    onset.stick_pose = pose16(a.placement.stick_pose);
    onset.views = stats.views;
    onset.draws = stats.draws;
    onset.stimulus_ms = t.settings.timeline.stimulus_ms;
    if (a.note.perceived_m) onset.perceived_sagitta_m = *a.note.perceived_m;
    if (a.note.account) onset.percept_json = human_account_json(*a.note.account);
    const auto& o = f_.options();
    if (!o.images_dir.empty() && o.drawing != FrameDrawing::none) onset.images = save_onset_images(t, a);
    f_.event(t.id, onset);
  }

  // A trial run again (a later attempt, a resumed session, another session
  // into the same folder) gets trial_NNNN_2, …: none is replaced. The
  // files' names are stored, not the folder: a folder can name a person.
  std::vector<std::string> save_onset_images(const TrialRun& t, const AttemptRun& a) {
    const auto& dir = f_.options().images_dir;
    char stem[32];
    std::snprintf(stem, sizeof stem, "trial_%04zu", t.index);
    const auto path = std::filesystem::path(dir) / unused_stem(dir, stem);
    const auto files = f_.station.display->save_frame(path.string());
    if (!files.empty())
      f_.check(write_onset_record(path.string() + ".json", f_.world(), t.settings, a.placement, a.onset_view));
    std::vector<std::string> names;
    for (const auto& file : files) names.push_back(std::filesystem::path(file).filename().string());
    f_.summary.images.insert(f_.summary.images.end(), files.begin(), files.end());
    return names;
  }

  // The answer (or the timeout), the adaptive method's step and the lost
  // tracking, journalled; durable before the next trial starts.
  void complete(TrialRun& t, const AttemptRun& a) {
    if (a.lost_spells > 0) {
      f_.event(t.id, data::events::TrackingFlagged{static_cast<double>(a.lost_ns) * 1e-6, a.lost_spells, a.number});
      ++f_.summary.trials_flagged;
    }
    data::TrialResult r;
    r.trial_id = t.id;
    r.onset_ns = *a.onset_ns;
    if (a.answer) {
      r.response = a.answer->first;
      r.response_ns = a.answer->second.t_ns;
      r.response_device = io::to_string(a.answer->second.source);
    } else {
      r.response = "timeout";
      r.response_ns = f_.clock.now_ns();
      r.response_device = "none";
    }
    if (t.adaptive_value && a.answer) {
      auto& state = *f_.adaptive_for(*t.planned);
      const auto step = state.record(*t.planned, state.positive(a.answer->first));
      r.staircase_step = data::StaircaseStep{staircase_key(f_.protocol, *t.planned, step.track),
                                             step.step,
                                             step.value,
                                             step.positive,
                                             step.reversal,
                                             step.next_value,
                                             step_posterior(step.posterior)};
    }
    // A staircase's or an adjustment's value is stored with the trial.
    if (!t.judgement->parameter.empty()) r.stimulus_json = shown_stimulus_json(f_.protocol, *t.planned, t.settings);
    if (a.answer) f_.mark_response(r);
    f_.room.status.last_response = r.response;
    f_.room.status.last_rt_ms = a.answer ? static_cast<double>(r.response_ns - r.onset_ns) * 1e-6 : -1.0;
    feedback_.clear();
    if (t.judgement->feedback) {
      feedback_ = "No answer";
      if (a.answer) {
        feedback_ = "Your answer: " + a.answer->first;
        for (const auto& o : t.judgement->options)
          if (o.value == a.answer->first && !o.label.empty()) feedback_ = "Your answer: " + o.label;
      }
    }
    completed_ticket_ = f_.writer.journal(std::move(r));
  }

  // The answer's feedback on the page panel, when the judgement asks for it.
  void show_feedback(const TrialRun& t) {
    if (feedback_.empty()) return;
    if (auto shown = f_.scene().show_page(feedback_); !shown) throw Stop{shown.error()};
    f_.event(t.id, data::events::Page{data::EventKind::feedback, 0, feedback_});
  }

  // Nothing on screen. A pause here holds the session; the interval starts
  // again after it. The trial just completed is on disk before this returns.
  Outcome inter_trial_interval(const TrialRun& t) {
    const auto iti_ns = ms_to_ns(t.settings.timeline.iti_ms);
    std::int64_t iti_end = f_.clock.now_ns() + iti_ns;
    f_.scene().show(Phase::iti, false);
    show_feedback(t);
    for (;;) {
      Frame g;
      if (!f_.begin(g)) return Outcome::quit;
      if (g.signal == Signal::pause) {
        if (f_.hold(Phase::iti, t.id) == Outcome::quit) return Outcome::quit;
        f_.scene().show(Phase::iti, false);
        iti_end = f_.clock.now_ns() + iti_ns;
        continue;
      }
      f_.room.phase_left_ns = std::max<std::int64_t>(0, iti_end - g.timing.now_ns);
      f_.end(g, io::Overlay{Phase::iti, t.line, false}, false, std::nullopt);
      if (g.signal == Signal::quit) return Outcome::quit;
      // While another program holds the file's lock the inter-trial
      // interval lasts until the trial is on disk: frames go on, nothing
      // waits on the disk (data/sample_writer.hpp).
      if (g.timing.now_ns >= iti_end && (f_.writer.durable(completed_ticket_) || f_.writer.lock_wait_s() == 0.0))
        break;
    }
    f_.check(f_.writer.wait_durable(completed_ticket_));
    return Outcome::done;
  }

  BlockRun& run_;
  SessionFrames& f_;
  std::uint64_t completed_ticket_ = 0;
  std::string feedback_;  // shown in the inter-trial interval; "" none
};

class TrialsKind final : public BlockKind {
 public:
  [[nodiscard]] std::string_view name() const override { return "trials"; }
  [[nodiscard]] std::size_t resume_position(const protocol::PlannedBlock& block,
                                            std::size_t first_trial) const override {
    return first_trial - block.first_trial;
  }
  Outcome run(BlockRun& run) const override { return TrialsBlock(run).run(); }
};

}  // namespace

const BlockKind& trials_block_kind() {
  static const TrialsKind kind;
  return kind;
}

}  // namespace curvlab::harness::runner
