// The simulated observer's key presses for one trial (DESIGN.md §5): the
// session schedules them on the session clock and feeds each to the trial as
// an input when its time has come, exactly as a participant's presses arrive.
#pragma once

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/io/response_source.hpp"
#include "curvlab/harness/protocol/adjustment.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/runner/observer.hpp"
#include "curvlab/harness/runner/percept.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

namespace curvlab::harness::runner {

using ScheduledKey = protocol::KeyPress;

// What the observer presses for a trial, and the onset's percept behind it.
struct ObserverAnswer {
  protocol::AnswerPlan plan;
  Percept percept;
};

// The seed of the observer's random stream for one attempt of one trial:
// from the observer's and the session's seeds, the trial's index and the
// attempt (numbered from 1), never from what happened before, so that a
// resumed session draws what the uninterrupted one would have.
std::uint64_t attempt_seed(std::uint64_t observer_seed, std::uint64_t session_seed, std::size_t trial_index,
                           std::int64_t attempt);

// What `observer` presses for a trial whose stimulus came up at `onset_ns`
// (session clock of the onset frame) with the head at `head`: after its
// response time, what the judgement's type plans. `seen`: the percept as
// read from the onset images (the image observer's); otherwise the model's.
// The simulated observer's presses as a response source: the session
// schedules them as it plans each answer, and each reaches the session,
// stamped with its planned time, in the first frame that begins at or after
// that time. Its answers press the key or button the plan names (a control
// the protocol binds); a page is continued by a press that means just that.
class ObserverKeys final : public io::ResponseSource {
 public:
  explicit ObserverKeys(const io::Clock& clock) : clock_(clock) {}
  // Continues the page on screen at `t_ns`.
  void press_continue(std::int64_t t_ns);
  // The presses of an answer plan, instead of any still due.
  void replace(const std::vector<ScheduledKey>& keys);
  void clear() { due_.clear(); }
  io::Signal poll(std::vector<io::InputEvent>& out) override;
  // Presses what each answer plan asks; pages continue on space.
  [[nodiscard]] io::Reach reach() const override {
    io::Reach r;
    r.kind = io::SourceKind::observer;
    r.intents = {io::Intent::continue_page};
    r.simulated = true;
    r.continue_phrase = "press space";
    return r;
  }

 private:
  const io::Clock& clock_;
  std::deque<io::InputEvent> due_;  // in time order
};

ObserverAnswer plan_answer(SimulatedObserver& observer, const World& world, const protocol::Judgement& j,
                           const protocol::Settings& s, const Placement& placement,
                           const geometry::Isometry& head, std::int64_t onset_ns,
                           const std::optional<protocol::Adjustment>& adjustment,
                           std::optional<Percept> seen = std::nullopt);

}  // namespace curvlab::harness::runner
