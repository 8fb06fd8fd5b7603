#include "curvlab/harness/runner/session.hpp"

#include "session_loop.hpp"
#include "session_records.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/sample_writer.hpp"
#include "curvlab/harness/data/session_store.hpp"
#include "curvlab/harness/data/sqlite.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <filesystem>

namespace curvlab::harness::runner {

namespace {

ObserverParams observer_from_json(const Json& d) {
  ObserverParams o;
  o.model = parse_observer_model(d.value("model", std::string("perception"))).value_or(ObserverModel::perception);
  o.bias_m = d.value("bias_m", 0.0);
  o.slope_per_m = d.value("slope_per_m", 300.0);
  o.lapse = d.value("lapse", 0.02);
  o.criterion_m = d.value("criterion_m", 0.006);
  o.rt_base_ms = d.value("rt_base_ms", 450.0);
  o.rt_mean_extra_ms = d.value("rt_mean_extra_ms", 250.0);
  o.seed = d.value("seed", std::uint64_t{1});
  return o;
}

Result<Done> read_provenance(data::Connection& c, const std::string& db_path, std::int64_t session_id,
                             StoredSession& out) {
  data::Statement s(c,
                    "SELECT pr.text, pr.source_path, p.pseudonym, se.seed, se.status, se.backend, "
                    "se.table_calibration FROM sessions se JOIN protocols pr ON pr.protocol_id = se.protocol_id "
                    "JOIN participants p ON p.participant_id = se.participant_id WHERE se.session_id = ?1");
  s.bind(1, session_id);
  if (!s.step()) return Error{Error::Kind::not_found, db_path + ": no session with id " + std::to_string(session_id)};
  out.protocol_text = s.column_text(0);
  out.protocol_source = s.column_opt_text(1).value_or("stored protocol");
  out.participant = s.column_text(2);
  out.seed = s.column_int(3);
  out.status = s.column_text(4);
  out.backend = s.column_text(5);
  if (const auto text = s.column_opt_text(6)) {
    auto fit = parse_calibration_json(*text);
    if (auto* f = std::get_if<geometry::PhysicalTableFit>(&fit)) out.calibration = *f;
  }
  data::Statement last(c,
                       "SELECT MAX(COALESCE((SELECT MAX(t_ns) FROM frames WHERE session_id = ?1), 0), "
                       "COALESCE((SELECT MAX(t_ns) FROM events WHERE session_id = ?1), 0))");
  last.bind(1, session_id);
  if (last.step()) out.last_t_ns = last.column_int(0);
  return Done{};
}

Result<Done> read_start_events(data::Connection& c, const std::string& db_path, std::int64_t session_id,
                               StoredSession& out) {
  data::Statement ev(c,
                     "SELECT kind, detail FROM events WHERE session_id = ?1 AND kind IN "
                     "('session_start', 'observer') ORDER BY event_id");
  ev.bind(1, session_id);
  bool found = false;
  while (ev.step()) {
    const Json d = Json::parse(ev.column_text(1), nullptr, false);
    if (d.is_discarded()) continue;
    if (ev.column_text(0) == "session_start") {
      out.participant_number = d.value("participant_number", std::uint64_t{1});
      found = true;
    } else {
      out.observer = observer_from_json(d);
    }
  }
  if (!found)
    return Error{Error::Kind::corrupt, db_path + ": session " + std::to_string(session_id) +
                                           " has no session_start event; it cannot be resumed"};
  return Done{};
}

// What a resumed run needs besides the stored session: the trial ids (the
// stored list checked against the re-expanded design), the frames logged,
// the first incomplete trial with its attempts and logged aborts, and the
// staircases' committed answers.
struct ResumePoint {
  std::vector<std::int64_t> trial_ids;
  std::int64_t frame_offset = 0;
  std::size_t first = 0;
  std::int64_t attempts = 0;
  std::int64_t aborts = 0;
  std::vector<std::pair<std::int64_t, bool>> staircase_history;
};

Result<ResumePoint> read_resume_point(data::SessionStore& store, const std::string& db_path, std::int64_t session_id,
                                      const protocol::Protocol& p, const protocol::Design& design) {
  ResumePoint rp;
  auto& c = store.database().connection();
  data::Statement s(c, "SELECT trial_id, conditions FROM trials WHERE session_id = ?1 ORDER BY trial_index");
  s.bind(1, session_id);
  while (s.step()) {
    const std::size_t k = rp.trial_ids.size();
    if (k >= design.trials.size() || s.column_text(1) != conditions_json(p, design.trials[k]))
      return Error{Error::Kind::bad_input, db_path + ": the stored trial list of session " + std::to_string(session_id) +
                                               " differs from its protocol's design at trial " + std::to_string(k)};
    rp.trial_ids.push_back(s.column_int(0));
  }
  if (rp.trial_ids.size() != design.trials.size())
    return Error{Error::Kind::bad_input, db_path + ": session " + std::to_string(session_id) + " stores " +
                                             std::to_string(rp.trial_ids.size()) + " trials, its design has " +
                                             std::to_string(design.trials.size())};
  data::Statement fr(c, "SELECT COALESCE(MAX(frame_index), -1) FROM frames WHERE session_id = ?1");
  fr.bind(1, session_id);
  if (fr.step()) rp.frame_offset = fr.column_int(0) + 1;
  auto next = store.next_incomplete_trial(session_id);
  if (!next) return next.error();
  rp.first = rp.trial_ids.size();
  if (next.value()) {
    rp.first = static_cast<std::size_t>(next.value()->trial_index);
    rp.attempts = next.value()->attempt;
    data::Statement ab(c, "SELECT COUNT(*) FROM events WHERE trial_id = ?1 AND kind = 'trial_aborted'");
    ab.bind(1, next.value()->trial_id);
    if (ab.step()) rp.aborts = ab.column_int(0);
  }
  data::Statement st(c,
                     "SELECT trial_id, response_correct FROM staircase_steps WHERE session_id = ?1 "
                     "AND response_correct IS NOT NULL ORDER BY step_id");
  st.bind(1, session_id);
  while (st.step()) rp.staircase_history.emplace_back(st.column_int(0), st.column_int(1) != 0);
  return rp;
}

}  // namespace

Result<StoredSession> read_stored_session(const std::string& db_path, std::int64_t session_id) {
  if (!std::filesystem::exists(db_path)) return Error{Error::Kind::not_found, db_path + ": no such database"};
  auto db = data::Database::open(db_path, data::OpenMode::open_existing);
  if (!db) return db.error();
  StoredSession out;
  try {
    if (auto r = read_provenance(db->connection(), db_path, session_id, out); !r) return r.error();
    if (auto r = read_start_events(db->connection(), db_path, session_id, out); !r) return r.error();
  } catch (const data::SqliteFailure& f) {
    return data::to_data_error(f, db_path);
  }
  return out;
}

RunResult resume_session(const std::string& db_path, std::int64_t session_id, const StoredSession& stored,
                         const protocol::Protocol& p, const RunOptions& options, Backend& backend,
                         const devices::Clock& clock) {
  if (stored.status == "completed")
    return Error{Error::Kind::usage, db_path + ": session " + std::to_string(session_id) + " is already completed"};
  protocol::Design design = protocol::expand_design(p, stored.participant_number);
  if (static_cast<std::int64_t>(design.seed) != stored.seed)
    return Error{Error::Kind::bad_input, "the stored seed does not match the re-expanded design"};
  auto db = data::Database::open(db_path, data::OpenMode::create_or_open);
  if (!db) return db.error();
  data::SessionStore store(std::move(db).value());
  Result<ResumePoint> point = Error{};
  try {
    point = read_resume_point(store, db_path, session_id, p, design);
  } catch (const data::SqliteFailure& f) {
    return data::to_data_error(f, db_path);
  }
  if (!point) return point.error();
  if (auto r = store.set_session_status(session_id, data::SessionStatus::running); !r) return r.error();
  Json detail{{"from_trial", point->first}, {"backend", backend.info().name}};
  if (auto r = store.record_event({session_id, std::nullopt, clock.now_ns(), "resume", detail.dump()}); !r)
    return r.error();
  auto writer = data::SampleWriter::open(db_path);
  if (!writer) return writer.error();

  SessionSetup setup;
  setup.protocol = &p;
  setup.design = std::move(design);
  setup.store = &store;
  setup.writer = writer.value().get();
  setup.backend = &backend;
  setup.clock = &clock;
  setup.options = options;
  setup.options.participant = stored.participant;
  setup.options.participant_number = stored.participant_number;
  if (!setup.options.observer) setup.options.observer = stored.observer;
  if (!setup.options.calibration) setup.options.calibration = stored.calibration;
  setup.session_id = session_id;
  setup.trial_ids = std::move(point->trial_ids);
  setup.frame_offset = point->frame_offset;
  setup.first_trial_attempts = point->attempts;
  setup.first_trial_aborts = point->aborts;
  setup.staircase_history = std::move(point->staircase_history);
  auto result = SessionLoop(std::move(setup)).run(point->first, false);
  if (result) result->db_path = db_path;
  return result;
}

}  // namespace curvlab::harness::runner
