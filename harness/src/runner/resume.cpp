#include "curvlab/harness/runner/session.hpp"

#include "session_loop.hpp"
#include "simulated_participant.hpp"
#include "session_records.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/sample_writer.hpp"
#include "curvlab/harness/data/session_store.hpp"
#include "curvlab/harness/data/session_reader.hpp"
#include "curvlab/harness/data/writer_lock.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <filesystem>

namespace curvlab::harness::runner {

namespace {

// What a resumed run needs besides the stored session: the trial ids (the
// stored list checked against the re-expanded design), the frames logged,
// the first incomplete trial with its attempts and logged aborts, and the
// staircases' committed answers.
struct StoredProgress {
  std::vector<std::int64_t> trial_ids;
  std::int64_t frame_offset = 0;
  std::size_t first = 0;
  std::int64_t attempts = 0;
  std::int64_t aborts = 0;
  std::vector<std::pair<std::int64_t, bool>> staircase_history;
};

Result<std::vector<std::int64_t>> checked_trial_ids(data::SessionStore& store, const std::string& db_path,
                                                   std::int64_t session_id, const protocol::Protocol& p,
                                                   const protocol::Design& design) {
  auto stored = store.trial_list(session_id);
  if (!stored) return stored.error();
  const std::string session = db_path + ": session " + std::to_string(session_id);
  if (stored->size() != design.trials.size())
    return Error{Error::Kind::bad_input, session + " stores " + std::to_string(stored->size()) +
                                             " trials, its design has " + std::to_string(design.trials.size())};
  std::vector<std::int64_t> ids;
  for (std::size_t k = 0; k < stored->size(); ++k) {
    if ((*stored)[k].conditions_json != conditions_json(p, design.trials[k]))
      return Error{Error::Kind::bad_input, "the stored trial list of " + session +
                                               " differs from its protocol's design at trial " + std::to_string(k)};
    ids.push_back((*stored)[k].trial_id);
  }
  return ids;
}

Result<StoredProgress> read_resume_point(data::SessionStore& store, const std::string& db_path, std::int64_t session_id,
                                      const protocol::Protocol& p, const protocol::Design& design) {
  StoredProgress rp;
  auto ids = checked_trial_ids(store, db_path, session_id, p, design);
  if (!ids) return ids.error();
  rp.trial_ids = std::move(ids).value();
  auto last_frame = store.last_frame_index(session_id);
  if (!last_frame) return last_frame.error();
  rp.frame_offset = *last_frame + 1;
  auto next = store.next_incomplete_trial(session_id);
  if (!next) return next.error();
  rp.first = rp.trial_ids.size();
  if (*next) {
    rp.first = static_cast<std::size_t>((*next)->trial_index);
    rp.attempts = (*next)->attempt;
    auto aborts = store.trial_event_count((*next)->trial_id, data::EventKind::trial_aborted);
    if (!aborts) return aborts.error();
    rp.aborts = *aborts;
  }
  auto steps = store.staircase_responses(session_id);
  if (!steps) return steps.error();
  for (const auto& step : *steps)
    if (step.response_correct) rp.staircase_history.emplace_back(step.trial_id, *step.response_correct);
  return rp;
}

}  // namespace

Result<StoredSession> read_stored_session(const std::string& db_path, std::int64_t session_id) {
  if (!std::filesystem::exists(db_path)) return Error{Error::Kind::not_found, db_path + ": no such database"};
  auto db = data::Database::open(db_path, data::OpenMode::read_only);
  if (!db) return db.error();
  auto prov = data::read_session_provenance(*db, session_id);
  if (!prov) return prov.error();
  if (!prov->participant_number)
    return Error{Error::Kind::corrupt, db_path + ": session " + std::to_string(session_id) +
                                           " has no session_start event; it cannot be resumed"};
  StoredSession out;
  out.protocol_text = prov->protocol_text;
  out.protocol_source = prov->protocol_source_path.value_or("stored protocol");
  out.participant = prov->pseudonym;
  out.participant_number = *prov->participant_number;
  out.seed = prov->seed;
  out.status = prov->status;
  out.backend = prov->backend ? data::to_string(*prov->backend) : "unknown";
  if (prov->table_calibration_json) {
    auto fit = parse_calibration_json(*prov->table_calibration_json);
    if (fit) out.calibration = *fit;
  }
  if (prov->observer) {
    auto observer = observer_from_json(prov->observer->json);
    if (!observer)
      return Error{observer.error().kind,
                   db_path + ": session " + std::to_string(session_id) + ": " + observer.error().message};
    out.observer = *observer;
  }
  out.last_t_ns = prov->last_t_ns;
  out.run_options_json = prov->run_options_json;
  return out;
}

RunResult resume_session(const std::string& db_path, std::int64_t session_id, const StoredSession& stored,
                         const protocol::Protocol& p, const RunOptions& options, const io::Station& station,
                         const io::Clock& clock) {
  auto lock = data::WriterLock::for_session(db_path, session_id);
  if (!lock) return lock.error();
  if (stored.status == data::SessionStatus::completed)
    return Error{Error::Kind::usage, db_path + ": session " + std::to_string(session_id) + " is already completed"};
  protocol::Design design = protocol::expand_design(p, stored.participant_number);
  if (static_cast<std::int64_t>(design.seed) != stored.seed)
    return Error{Error::Kind::bad_input, "the stored seed does not match the re-expanded design"};
  auto db = data::Database::open(db_path, data::OpenMode::create_or_open);
  if (!db) return db.error();
  data::SessionStore store(std::move(db).value());
  auto point = read_resume_point(store, db_path, session_id, p, design);
  if (!point) return point.error();
  if (auto r = store.set_session_status(session_id, data::SessionStatus::running); !r) return r.error();
  data::events::Resume resumed{point->first, data::to_string(station.display->info().backend), std::nullopt};
  if (!options.run_options_json.empty()) resumed.run_options_json = options.run_options_json;
  if (auto r = store.record_event(data::event_record(session_id, std::nullopt, clock.now_ns(), resumed)); !r)
    return r.error();
  auto writer = data::SampleWriter::open(db_path);
  if (!writer) return writer.error();

  RunOptions o = options;
  o.participant = stored.participant;
  o.participant_number = stored.participant_number;
  if (!o.observer) o.observer = stored.observer;
  if (!o.calibration) o.calibration = stored.calibration;
  auto setup = SessionSetup::of(p, std::move(design), store, *writer.value(), station, clock, std::move(o),
                                session_id, std::move(point->trial_ids));
  setup.lock = &lock.value();
  setup.frame_offset = point->frame_offset;
  setup.first_trial_attempts = point->attempts;
  setup.first_trial_aborts = point->aborts;
  setup.staircase_history = std::move(point->staircase_history);
  const auto participant = SimulatedParticipant::seat(setup);
  const ResumePoint from = resume_point(setup.design, point->first);
  auto result = SessionLoop(std::move(setup)).run(from, false);
  if (result) result->db_path = db_path;
  return result;
}

}  // namespace curvlab::harness::runner
