// The trial state machine (DESIGN.md §6), free of backends, clocks and
// storage so that tests can drive it frame by frame with made-up facts.
//
// One attempt of a trial runs fixation → stimulus → response. Each frame the
// session hands the attempt what the frame says (its time, its predicted
// display time, whether the head is tracked, the backend's signal) and gets
// back the phase to show, whether this frame is the stimulus onset, and
// whether the attempt is aborted. Responses count from the onset's display
// time to the end of the response window; a press time-stamped before the
// stimulus reached the display is an anticipation (early_input).
//
// An aborted attempt is repeated or given up by after_abort() from the
// protocol's [tracking] policy; "flag" keeps the attempt going and counts the
// lost spells instead.
#pragma once

#include "curvlab/harness/io/pose_source.hpp"
#include "curvlab/harness/io/response_source.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/protocol/settings.hpp"
#include "curvlab/harness/runner/phase.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::runner {

struct FrameFacts {
  std::int64_t now_ns = 0;         // when the frame began (session clock)
  std::int64_t display_ns = 0;     // when its image will be shown
  bool head_tracked = true;
  Signal signal = Signal::none;
};

struct AttemptStep {
  Phase phase = Phase::fixation;     // what this frame shows
  bool onset = false;                // this frame puts the stimulus up
  std::optional<AbortReason> abort;  // the attempt ends here, without this frame
};

// How long the head has been lost; under on_loss = "flag", the spells past
// the threshold and their total time. Pure: fed one frame at a time.
class TrackingLossMonitor {
 public:
  explicit TrackingLossMonitor(const protocol::TrackingLoss& policy) : policy_(policy) {}
  // True when the loss aborts the attempt at this frame.
  bool update(std::int64_t now_ns, bool tracked);
  // Closes a spell still open at `now_ns` (the attempt ended while lost).
  void finish(std::int64_t now_ns);
  [[nodiscard]] int spells() const { return spells_; }
  [[nodiscard]] std::int64_t lost_ns() const { return lost_ns_; }

 private:
  protocol::TrackingLoss policy_;
  std::int64_t untracked_since_ = -1;
  bool in_spell_ = false;
  int spells_ = 0;
  std::int64_t lost_ns_ = 0;
};

// One attempt of one trial. Not thread-safe; a value type.
class Attempt {
 public:
  Attempt(const protocol::Timeline& timeline, const protocol::TrackingLoss& loss, std::int64_t start_ns);

  AttemptStep advance(const FrameFacts& frame);
  // Whether a press at `t_ns` may answer: after the onset reached the display.
  [[nodiscard]] bool answerable(std::int64_t t_ns) const { return onset_display_ns_ && t_ns >= *onset_display_ns_; }
  void answered() { answered_ = true; }
  // After the frame at `now_ns` was shown: answered, or the window is over.
  [[nodiscard]] bool over(std::int64_t now_ns) const;
  [[nodiscard]] std::optional<std::int64_t> onset_display_ns() const { return onset_display_ns_; }
  [[nodiscard]] std::optional<std::int64_t> onset_frame_ns() const { return onset_frame_ns_; }
  [[nodiscard]] std::int64_t start_ns() const { return start_ns_; }
  void finish(std::int64_t now_ns) { loss_.finish(now_ns); }
  [[nodiscard]] const TrackingLossMonitor& loss() const { return loss_; }

 private:
  protocol::Timeline timeline_;
  TrackingLossMonitor loss_;
  std::int64_t start_ns_;
  std::optional<std::int64_t> onset_frame_ns_;    // frame start of the onset frame
  std::optional<std::int64_t> onset_display_ns_;  // its predicted display time
  bool answered_ = false;
};

enum class AfterAbort { repeat, give_up };
// Whether an aborted attempt (numbered from 1) is run again.
AfterAbort after_abort(AbortReason reason, std::int64_t attempt, const protocol::TrackingLoss& policy);

// Whether the head counts as tracked for a trial under [tracking]
// head_requires: `pose_tracked` is the tracker's (the head's pose usable),
// `head` what the pose source says beyond it.
bool head_meets(protocol::HeadRequirement need, bool pose_tracked, const io::HeadTracking& head);

// What an input does in the response phase of a trial: an anticipation
// before the onset reached the display, else what the answer it gives does
// (its key through the judgement's answer keys, its button through their
// buttons: io::answer_index; judgement.hpp), or nothing.
using protocol::InputUse;
using protocol::InputVerdict;
InputVerdict classify_input(const protocol::Judgement& judgement, const io::InputEvent& input, bool answerable);

// An instruction, break or closing page: it advances on an input its source
// means as "continue" (io::Intent::continue_page: the keyboard's space,
// enter or return, a controller's trigger or A, a HID button named
// continue) once `min_ns` has passed, ignoring a key held from before the
// page (or from before a pause).
// Every input bound to an answer of any of the protocol's judgements: pages
// continue on these too (a control of that name, key or button), so a
// participant who knows how to answer knows how to go on.
std::vector<std::string> page_continues(const protocol::Protocol& p);

// The line under every page telling the participant how to go on, from what
// the session's response sources can press ("" when none can): each source's
// own way ("press space", "pull a trigger or press A"), and any answer when a
// source can give one of the protocol's.
std::string continue_line(const std::vector<io::Reach>& sources, const protocol::Protocol& p);

// What the participant reads in the response window: the judgement's
// question, then each answer's label with the input that gives it from the
// sources at hand ("[1] straight"), keys where a source has them, else
// buttons; with no sources (preview, replay) the keys. An answer's label and
// input are never split across lines.
std::string response_panel_text(const protocol::Judgement& j, const std::vector<io::Reach>& sources);

// A protocol answer that none of `sources` can give: "the answer 'convex'
// (keys 1)", naming the block; nullopt when every answer can be given.
std::optional<std::string> unreachable_answer(const std::vector<io::Reach>& sources, const protocol::Protocol& p);

class Page {
 public:
  // `continues`: the controls that turn the page besides those whose source
  // means them to (the protocol's answer bindings; page_continues()).
  Page(std::int64_t shown_ns, std::int64_t min_ns, const std::vector<std::string>& continues)
      : shown_ns_(shown_ns), min_ns_(min_ns), continues_(continues) {}
  // One frame's presses; true when the page is done after this frame.
  bool frame(std::int64_t now_ns, const std::vector<io::InputEvent>& inputs) {
    bool go = false;
    for (const auto& in : inputs)
      if (!fresh_ && in.pressed && is_continue(in) && now_ns - shown_ns_ >= min_ns_) go = true;
    fresh_ = false;
    return go;
  }
  // After a pause: keys pressed before it do not count.
  void restart() { fresh_ = true; }
  [[nodiscard]] bool is_continue(const io::InputEvent& input) const;

 private:
  std::int64_t shown_ns_;
  std::int64_t min_ns_;
  const std::vector<std::string>& continues_;
  bool fresh_ = true;
};

}  // namespace curvlab::harness::runner
