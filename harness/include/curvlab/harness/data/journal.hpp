// The session's own writes during a run — events and trial state — as
// entries for the logger's writer thread (sample_writer.hpp), so that the
// frame loop never waits on the disk (DESIGN.md §7). The writer applies them
// in the order they were journalled, through a SessionStore on its own
// connection with synchronous = FULL: an entry is durable once applied.
#pragma once

#include "curvlab/harness/data/records.hpp"

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

namespace curvlab::harness::data {

// Marks a trial running and counts the attempt (SessionStore::begin_trial).
struct BeginTrial {
  std::int64_t trial_id = 0;
};
// A trial that ends without an answer: skipped (a stopped staircase's slot)
// or aborted (given up after interruptions).
struct EndUnanswered {
  std::int64_t trial_id = 0;
  bool aborted = false;
  std::string reason;  // trials.end_reason
};
// A session's status; `close` also sets its end time.
struct StatusChange {
  std::int64_t session_id = 0;
  SessionStatus status = SessionStatus::running;
  bool close = false;
};

// A questionnaire block's scores, stored together in one transaction.
struct QuestionnaireScores {
  std::vector<QuestionnaireScore> rows;
};

using JournalEntry = std::variant<EventRecord, BeginTrial, TrialResult, EndUnanswered, StatusChange, ShotRecord,
                                  QuestionnaireAnswer, QuestionnaireScores>;

}  // namespace curvlab::harness::data
