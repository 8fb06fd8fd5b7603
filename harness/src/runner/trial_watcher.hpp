// What watches a trial besides the participant (DESIGN.md §5–6): a
// simulated participant is a response source like any other, wired beside
// the devices, and also hears what a person would see — a page shown, an
// attempt begun, the stimulus at onset — so that it can plan its presses.
// The frame loop tells every watcher the same things and knows no kind.
#pragma once

#include "curvlab/harness/protocol/adjustment.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/runner/image_observer.hpp"
#include "curvlab/harness/runner/percept.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <cstdint>
#include <optional>

namespace curvlab::harness::runner {

// The stimulus as it came up at onset.
struct OnsetFacts {
  const World& world;
  const protocol::Judgement& judgement;
  const protocol::Settings& settings;
  const Placement& placement;
  const geometry::Isometry& head;  // the nose at onset
  std::int64_t onset_ns = 0;       // session clock of the onset frame
  const std::optional<protocol::Adjustment>& adjustment;
  const OnsetView& view;
};

// What a watcher made of the onset, stored with it (the onset event's
// perceived_sagitta_m and percept).
struct OnsetNote {
  std::optional<double> perceived_m;
  std::optional<HumanAccount> account;
};

// A questionnaire item as it came up (questionnaire blocks).
struct ItemFacts {
  std::size_t trial_index = 0;  // the block's planned trial
  std::size_t item = 0;         // in the instrument's order
  const protocol::Instrument& instrument;
  std::int64_t shown_ns = 0;  // session clock of the item's first frame
};

class TrialWatcher {
 public:
  virtual ~TrialWatcher() = default;
  TrialWatcher() = default;
  TrialWatcher(const TrialWatcher&) = delete;
  TrialWatcher& operator=(const TrialWatcher&) = delete;
  // A page is up from `shown_ns`; it can be continued from shown_ns + min_ns.
  virtual void page_shown(std::int64_t shown_ns, std::int64_t min_ns) = 0;
  // Attempt `draw` (1 for the first, one more after each logged abort) of
  // the design's trial `trial_index` begins.
  virtual void attempt_begins(std::size_t trial_index, std::int64_t draw) = 0;
  virtual std::optional<OnsetNote> onset(const OnsetFacts& facts) = 0;
  // A questionnaire item is up, waiting for its answer.
  virtual void item_shown(const ItemFacts& facts) { (void)facts; }
};

}  // namespace curvlab::harness::runner
