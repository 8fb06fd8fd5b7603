// The simulated participant (DESIGN.md §5) wired into a session as a
// response source and a trial watcher: at each onset its observer model
// (or, for --observer image, its reading of the onset images) plans what it
// presses and when, and its presses reach the session as a person's do.
#pragma once

#include "observer_keys.hpp"
#include "session_loop.hpp"
#include "trial_watcher.hpp"

#include <memory>
#include <vector>
#include <optional>

namespace curvlab::harness::runner {

// The scale point a simulated participant answers a questionnaire item
// with: drawn from (session seed, trial, item) alone, so a resumed session
// answers as the uninterrupted one would. SSQ symptoms are mostly None or
// Slight, a little worse after a play block; other scales centre on their
// middle point.
std::size_t simulated_item_answer(std::uint64_t session_seed, const ItemFacts& facts, bool after_play);

class SimulatedParticipant final : public io::ResponseSource, public TrialWatcher {
 public:
  SimulatedParticipant(const ObserverParams& params, std::uint64_t session_seed, const io::Clock& clock);
  // One for the setup's observer option (none without one), added to its
  // station's response sources and to its watchers.
  static std::unique_ptr<SimulatedParticipant> seat(SessionSetup& setup);

  io::Signal poll(std::vector<io::InputEvent>& out) override { return keys_.poll(out); }
  [[nodiscard]] io::Reach reach() const override { return keys_.reach(); }
  void page_shown(std::int64_t shown_ns, std::int64_t min_ns) override;
  void attempt_begins(std::size_t trial_index, std::int64_t draw) override;
  std::optional<OnsetNote> onset(const OnsetFacts& facts) override;
  void item_shown(const ItemFacts& facts) override;

 private:
  ObserverParams params_;
  std::uint64_t session_seed_;
  ObserverKeys keys_;
  std::optional<SimulatedObserver> observer_;  // this attempt's stream
  std::unique_ptr<OnsetReader> onset_reader_;  // --observer image only
  std::vector<bool> after_play_;               // per design trial
};

}  // namespace curvlab::harness::runner
