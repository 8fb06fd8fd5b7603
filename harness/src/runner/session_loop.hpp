// One run of a session's frame loop (DESIGN.md §6), for run_session and
// resume_session: Session → Block → Trial, each trial's attempts driven by
// the pure state machine of trial_state.hpp, each frame
//   poses → tracking → input → trial state → scene → submit → log.
// Everything the loop writes — samples, frames, events, trial state — goes
// through the SampleWriter, so the frame loop never waits on the disk; a
// completed trial is on disk before the next trial starts.
//
// Owned and used by one thread (the frame thread). Not copyable.
#pragma once

#include "curvlab/harness/data/sample_writer.hpp"
#include "curvlab/harness/data/writer_lock.hpp"
#include "curvlab/harness/data/session_store.hpp"
#include "curvlab/harness/runner/session.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace curvlab::harness::runner {

class TrialWatcher;

// Ends the run with an error; caught at the top of SessionLoop::run.
struct Stop {
  Error error;
};

struct SessionSetup {
  const protocol::Protocol* protocol = nullptr;
  protocol::Design design;
  data::SessionStore* store = nullptr;  // reads only while the loop runs
  data::SampleWriter* writer = nullptr;
  io::Station station;
  const io::Clock* clock = nullptr;
  RunOptions options;
  std::int64_t session_id = 0;
  std::vector<std::int64_t> trial_ids;  // in the design's order
  std::int64_t frame_offset = 0;        // frames logged before (resume)
  // Where a resumed session continues: that trial's attempts so far, and how
  // many of them ended in a logged abort (the observer's stream counts those).
  std::int64_t first_trial_attempts = 0;
  std::int64_t first_trial_aborts = 0;
  // Committed staircase answers, in order (resume): trial id → positive.
  std::vector<std::pair<std::int64_t, bool>> staircase_history;
  // The session's writer lock; its disk reserve is freed when the disk fills.
  data::WriterLock* lock = nullptr;
  // Told what a participant sees (trial_watcher.hpp): a simulated
  // participant, seated with the station's sources.
  std::vector<TrialWatcher*> watchers;

  // What every run sets; a resumed run adds where it continues.
  static SessionSetup of(const protocol::Protocol& p, protocol::Design design, data::SessionStore& store,
                         data::SampleWriter& writer, const io::Station& station, const io::Clock& clock,
                         RunOptions options, std::int64_t session_id, std::vector<std::int64_t> trial_ids) {
    SessionSetup s;
    s.protocol = &p;
    s.design = std::move(design);
    s.store = &store;
    s.writer = &writer;
    s.station = station;
    s.clock = &clock;
    s.options = std::move(options);
    s.session_id = session_id;
    s.trial_ids = std::move(trial_ids);
    return s;
  }
};

class SessionLoop {
 public:
  explicit SessionLoop(SessionSetup setup);
  ~SessionLoop();
  SessionLoop(const SessionLoop&) = delete;
  SessionLoop& operator=(const SessionLoop&) = delete;

  // Runs from `from`; `start_pages`: show the opening instructions. Ends
  // the session completed or interrupted; a failure leaves it interrupted
  // and resumable, with every completed trial kept.
  RunResult run(ResumePoint from, bool start_pages);

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace curvlab::harness::runner
