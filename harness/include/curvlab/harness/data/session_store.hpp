// The synchronous half of the logger: protocol, participant, session and
// trial rows. Every call that changes data commits its own transaction
// before it returns, so a completed trial is on disk before the next trial
// starts (DESIGN.md §7). A failure (disk full, read-only) is returned, the
// database is left as it was, and the same call may be retried after the
// cause is fixed: complete_trial is idempotent.
#pragma once

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/records.hpp"
#include "curvlab/harness/data/session_reader.hpp"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::data {

struct StartedSession {
  std::int64_t session_id = 0;
  std::vector<std::int64_t> trial_ids;  // in the plan's order
};

// Owns a Database and its prepared statements. Move-only; not thread-safe:
// use it from the session (trial) thread only. Tracking samples and frame
// records go through SampleWriter instead.
class SessionStore {
 public:
  explicit SessionStore(Database db);
  SessionStore(SessionStore&&) noexcept;
  SessionStore& operator=(SessionStore&&) noexcept;
  ~SessionStore();


  // Stores the full protocol text with its SHA-256; the same text twice
  // returns the same id. Of source_path only the file name is kept (a
  // folder can name a person); it labels diagnostics when the stored text
  // is loaded again (resume, replay).
  Expected<std::int64_t> add_protocol(const std::string& name, const std::string& text,
                                      const std::string& source_path = {});
  // Returns the existing id when the pseudonym is already known.
  Expected<std::int64_t> add_participant(const ParticipantRecord& participant);
  Expected<std::int64_t> create_session(const SessionRecord& session);
  // A session, its whole plan and its start events (their session_id is
  // set to the new session's) in one transaction: a kill at any instant
  // leaves either all of it or none, so a stored session can always be
  // resumed. `before_commit` runs with the new session's id inside that
  // transaction (the session's writer lock is claimed there, so no other
  // process can see the session unlocked); its error rolls everything back.
  const std::string& path() const { return db_.path(); }
  Expected<StartedSession> start_session(
      const SessionRecord& session, const std::vector<BlockPlan>& blocks, const std::vector<EventRecord>& events,
      const std::function<Expected<Done>(std::int64_t session_id)>& before_commit = {});
  // Stores every block and trial of the session in one transaction; the
  // returned ids follow the plan's order. Fails if the session has a plan.
  Expected<std::vector<std::int64_t>> store_plan(std::int64_t session_id,
                                                 const std::vector<BlockPlan>& blocks);
  // The first trial (by trial_index) that is pending or was started but not
  // completed — where a resumed session continues. nullopt: all done.
  Expected<std::optional<PlannedTrialRecord>> next_incomplete_trial(std::int64_t session_id);
  // Marks the trial running and counts the attempt; returns the attempt number.
  Expected<std::int64_t> begin_trial(std::int64_t trial_id);
  // Commits the response (and its staircase step) in one transaction.
  Expected<Done> complete_trial(const TrialResult& result);
  // A trial that ends without an answer: skipped (a stopped staircase's
  // slot) or aborted (given up after interruptions). Either is final;
  // `reason` (trials.end_reason) says why, empty for none.
  Expected<Done> skip_trial(std::int64_t trial_id, const std::string& reason = {});
  Expected<Done> abort_trial(std::int64_t trial_id, const std::string& reason = {});
  Expected<std::int64_t> record_event(const EventRecord& event);
  // Several events in one transaction, in order.
  Expected<Done> record_events(const std::vector<EventRecord>& events);
  // A play block's shot, in its own transaction.
  Expected<Done> record_shot(const ShotRecord& shot);
  // The shots stored for a play block's trial, in order.
  Expected<std::vector<ShotRecord>> shots(std::int64_t trial_id);
  // A questionnaire item's answer, in its own transaction; an item answered
  // again (the participant went back) replaces its row.
  Expected<Done> record_answer(const QuestionnaireAnswer& answer);
  // The answers stored for a questionnaire block's trial, by item.
  Expected<std::vector<QuestionnaireAnswer>> answers(std::int64_t trial_id);
  // A questionnaire block's scores, replacing any stored for its trial.
  Expected<Done> record_scores(const std::vector<QuestionnaireScore>& scores);
  Expected<Done> set_session_status(std::int64_t session_id, SessionStatus status);
  // Sets the final status and the end time.
  Expected<Done> close_session(std::int64_t session_id, SessionStatus status);
  Expected<std::int64_t> count_trials(std::int64_t session_id, std::optional<TrialStatus> status);

  // Reading the session back to resume it, through this store's connection
  // (the same functions as session_reader.hpp's).
  Expected<std::vector<StoredTrial>> trial_list(std::int64_t session_id) { return read_trial_list(db_, session_id); }
  Expected<std::int64_t> last_frame_index(std::int64_t session_id) { return read_last_frame_index(db_, session_id); }
  Expected<std::vector<StoredStaircaseResponse>> staircase_responses(std::int64_t session_id) {
    return read_staircase_responses(db_, session_id);
  }
  Expected<std::int64_t> trial_event_count(std::int64_t trial_id, EventKind kind) {
    return read_trial_event_count(db_, trial_id, kind);
  }

 private:
  Expected<Done> end_unanswered(std::int64_t trial_id, const char* status, const std::string& reason);
  // Statement bodies without a transaction of their own; they throw SqliteFailure.
  std::int64_t insert_session(const SessionRecord& session);
  Expected<std::vector<std::int64_t>> insert_plan(std::int64_t session_id, const std::vector<BlockPlan>& blocks);
  void insert_event(const EventRecord& event);
  struct Statements;
  Database db_;
  std::unique_ptr<Statements> stmts_;
};

}  // namespace curvlab::harness::data
