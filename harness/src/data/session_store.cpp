#include "curvlab/harness/data/session_store.hpp"

#include "curvlab/harness/data/sha256.hpp"
#include "curvlab/harness/data/uuid.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

namespace curvlab::harness::data {

const char* to_string(DominantEye eye) {
  switch (eye) {
    case DominantEye::left: return "left";
    case DominantEye::right: return "right";
    case DominantEye::unknown: return "unknown";
  }
  return "unknown";
}
const char* to_string(Backend backend) {
  switch (backend) {
    case Backend::headless: return "headless";
    case Backend::desktop: return "desktop";
    case Backend::xr: return "xr";
  }
  return "unknown";
}
const char* to_string(SessionStatus status) {
  switch (status) {
    case SessionStatus::running: return "running";
    case SessionStatus::paused: return "paused";
    case SessionStatus::completed: return "completed";
    case SessionStatus::aborted: return "aborted";
    case SessionStatus::interrupted: return "interrupted";
  }
  return "interrupted";
}
const char* to_string(TrialStatus status) {
  switch (status) {
    case TrialStatus::pending: return "pending";
    case TrialStatus::running: return "running";
    case TrialStatus::completed: return "completed";
    case TrialStatus::skipped: return "skipped";
    case TrialStatus::aborted: return "aborted";
  }
  return "pending";
}

std::optional<Backend> parse_backend(std::string_view text) {
  for (auto v : {Backend::headless, Backend::desktop, Backend::xr})
    if (text == to_string(v)) return v;
  return std::nullopt;
}

std::optional<SessionStatus> parse_session_status(std::string_view text) {
  for (auto v : {SessionStatus::running, SessionStatus::paused, SessionStatus::completed, SessionStatus::aborted,
                 SessionStatus::interrupted})
    if (text == to_string(v)) return v;
  return std::nullopt;
}

std::optional<TrialStatus> parse_trial_status(std::string_view text) {
  for (auto v : {TrialStatus::pending, TrialStatus::running, TrialStatus::completed, TrialStatus::skipped,
                 TrialStatus::aborted})
    if (text == to_string(v)) return v;
  return std::nullopt;
}

const char* to_string(TrackedDevice device) {
  switch (device) {
    case TrackedDevice::head: return "head";
    case TrackedDevice::left_hand: return "left_hand";
    case TrackedDevice::right_hand: return "right_hand";
    case TrackedDevice::other: return "other";
  }
  return "other";
}

namespace {

// A byte as a message shows it: itself when printable ASCII, else \xNN.
std::string shown(char c) {
  static constexpr char hex[] = "0123456789abcdef";
  const auto byte = static_cast<unsigned char>(c);
  if (byte >= 0x20 && byte < 0x7f) return std::string(1, c);
  return std::string("\\x") + hex[byte >> 4] + hex[byte & 0xf];
}

// The first date in `text` (see check_pseudonym), or nothing.
std::optional<std::string> date_in(const std::string& text) {
  struct Run {
    std::size_t begin, end;
  };
  std::vector<Run> runs;  // maximal runs of digits
  for (std::size_t i = 0; i < text.size();) {
    if (!std::isdigit(static_cast<unsigned char>(text[i]))) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < text.size() && std::isdigit(static_cast<unsigned char>(text[j]))) ++j;
    runs.push_back({i, j});
    i = j;
  }
  // The number of `len` digits at `at`; the run lengths checked keep it small.
  auto number = [&](std::size_t at, std::size_t len) { return std::stoi(text.substr(at, len)); };
  auto year = [&](std::size_t at, std::size_t len) {
    return len == 4 && number(at, len) >= 1900 && number(at, len) <= 2099;
  };
  auto month = [&](std::size_t at, std::size_t len) {
    return len >= 1 && len <= 2 && number(at, len) >= 1 && number(at, len) <= 12;
  };
  auto day = [&](std::size_t at, std::size_t len) {
    return len >= 1 && len <= 2 && number(at, len) >= 1 && number(at, len) <= 31;
  };
  for (const Run& r : runs) {
    if (r.end - r.begin != 8) continue;
    const std::size_t b = r.begin;
    if ((year(b, 4) && month(b + 4, 2) && day(b + 6, 2)) || (day(b, 2) && month(b + 2, 2) && year(b + 4, 4)) ||
        (month(b, 2) && day(b + 2, 2) && year(b + 4, 4)))
      return text.substr(b, 8);
  }
  auto joined = [&](const Run& a, const Run& b) {
    return b.begin == a.end + 1 && std::string_view("-_./ ").find(text[a.end]) != std::string_view::npos;
  };
  for (std::size_t i = 0; i + 2 < runs.size(); ++i) {
    const Run &a = runs[i], &b = runs[i + 1], &c = runs[i + 2];
    if (!joined(a, b) || !joined(b, c)) continue;
    const std::size_t la = a.end - a.begin, lb = b.end - b.begin, lc = c.end - c.begin;
    if (la > 4 || lb > 4 || lc > 4) continue;
    if ((year(a.begin, la) && month(b.begin, lb) && day(c.begin, lc)) ||
        (year(c.begin, lc) && ((day(a.begin, la) && month(b.begin, lb)) || (month(a.begin, la) && day(b.begin, lb)))))
      return text.substr(a.begin, c.end - a.begin);
  }
  return std::nullopt;
}

}  // namespace

Expected<Done> check_pseudonym(const std::string& p) {
  std::string problem;
  if (p.empty()) {
    problem = "is empty";
  } else if (p.size() > 32) {
    problem = "is longer than 32 characters";
  } else if (p.front() == '-') {
    problem = "begins with '-', so it would read as an option";
  } else if (p.find('@') != std::string::npos) {
    problem = "contains '@', as an e-mail address does";
  } else if (const auto date = date_in(p)) {
    problem = "contains the date " + *date;
  } else if (const auto bad = std::find_if(p.begin(), p.end(), [](char ch) {
               return !((ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
                        ch == '-' || ch == '_');
             });
             bad != p.end()) {
    problem = "contains '" + shown(*bad) + "', which is not one of A-Z a-z 0-9 - _";
  } else {
    return Done{};
  }
  std::string quoted;
  for (char c : p) quoted += shown(c);
  return DataError{DataError::Kind::bad_input,
                   "pseudonym \"" + quoted + "\" " + problem +
                       "; a pseudonym is 1-32 characters of A-Z a-z 0-9 - _, not beginning with '-', with no name, "
                       "e-mail address or date in it"};
}

bool valid_pseudonym(const std::string& p) { return check_pseudonym(p).has_value(); }

namespace {

constexpr const char* utc_now = "strftime('%Y-%m-%dT%H:%M:%fZ', 'now')";

// Runs `body` and turns SQLite failures into DataError values naming the file.
template <class T>
struct Flatten {
  using type = Expected<T>;
};
template <class T>
struct Flatten<Expected<T>> {
  using type = Expected<T>;
};
template <class F>
auto guarded(Database& db, F&& body) -> typename Flatten<decltype(body())>::type {
  try {
    return body();
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, db.path());
  }
}

}  // namespace

struct SessionStore::Statements {
  explicit Statements(Connection& c)
      : insert_protocol(c, "INSERT OR IGNORE INTO protocols (name, sha256, text, source_path) "
                           "VALUES (?1, ?2, ?3, ?4)"),
        find_protocol(c, "SELECT protocol_id FROM protocols WHERE sha256 = ?1"),
        find_participant(c, "SELECT participant_id FROM participants WHERE pseudonym = ?1"),
        insert_participant(c, std::string("INSERT INTO participants (pseudonym, ipd_m, "
                                          "dominant_eye, created_utc) VALUES (?1, ?2, ?3, ") +
                                  utc_now + ")"),
        next_session_number(c, "SELECT coalesce(max(session_number), 0) + 1 FROM sessions "
                               "WHERE participant_id = ?1"),
        insert_session(c, std::string("INSERT INTO sessions (protocol_id, participant_id, "
                                      "session_number, software_version, software_commit, "
                                      "backend, renderer_device, renderer_driver, "
                                      "display_refresh_hz, seed, table_calibration, status, "
                                      "started_utc, session_uuid) VALUES (?1, ?2, ?3, ?4, ?5, ?6, "
                                      "?7, ?8, ?9, ?10, ?11, 'running', ") +
                              utc_now + ", ?12)"),
        count_plan(c, "SELECT count(*) FROM blocks WHERE session_id = ?1"),
        insert_block(c, "INSERT INTO blocks (session_id, block_index, name, is_practice, "
                        "settings) VALUES (?1, ?2, ?3, ?4, ?5)"),
        insert_trial(c, "INSERT INTO trials (session_id, block_id, trial_index, trial_in_block, "
                        "conditions, stimulus) VALUES (?1, ?2, ?3, ?4, ?5, ?6)"),
        next_trial(c, "SELECT t.trial_id, t.block_id, b.block_index, t.trial_index, "
                      "t.trial_in_block, t.attempt, t.conditions, t.stimulus FROM trials t "
                      "JOIN blocks b ON b.block_id = t.block_id WHERE t.session_id = ?1 AND "
                      "t.status IN ('pending', 'running') ORDER BY t.trial_index LIMIT 1"),
        begin_trial(c, "UPDATE trials SET status = 'running', attempt = attempt + 1 "
                       "WHERE trial_id = ?1 AND status IN ('pending', 'running') "
                       "RETURNING attempt"),
        complete_trial(c, std::string("UPDATE trials SET status = 'completed', onset_ns = ?2, "
                                      "response_ns = ?3, response = ?4, rt_ns = ?3 - ?2, "
                                      "response_device = ?5, stimulus = COALESCE(?6, stimulus), "
                                      "completed_utc = ") +
                              utc_now + " WHERE trial_id = ?1 AND status != 'completed'"),
        trial_status(c, "SELECT status, session_id FROM trials WHERE trial_id = ?1"),
        insert_step(c, "INSERT OR REPLACE INTO staircase_steps (session_id, staircase, "
                       "step_index, trial_id, intensity, response_correct, is_reversal, "
                       "next_intensity) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)"),
        end_unanswered(c, "UPDATE trials SET status = ?2, end_reason = ?3 WHERE trial_id = ?1 AND "
                          "status IN ('pending', 'running')"),
        insert_event(c, "INSERT INTO events (session_id, trial_id, t_ns, kind, detail) "
                        "VALUES (?1, ?2, ?3, ?4, ?5)"),
        set_status(c, "UPDATE sessions SET status = ?2 WHERE session_id = ?1"),
        close_session(c, std::string("UPDATE sessions SET status = ?2, ended_utc = ") + utc_now +
                             " WHERE session_id = ?1"),
        count_trials(c, "SELECT count(*) FROM trials WHERE session_id = ?1 AND "
                        "(?2 = '' OR status = ?2)") {}

  Statement insert_protocol, find_protocol, find_participant, insert_participant,
      next_session_number, insert_session, count_plan, insert_block, insert_trial, next_trial,
      begin_trial, complete_trial, trial_status, insert_step, end_unanswered, insert_event,
      set_status, close_session, count_trials;
};

SessionStore::SessionStore(Database db)
    : db_(std::move(db)), stmts_(std::make_unique<Statements>(db_.connection())) {}
SessionStore::SessionStore(SessionStore&&) noexcept = default;
SessionStore& SessionStore::operator=(SessionStore&&) noexcept = default;
// Statements are destroyed before the connection (member order), and
// sqlite3_close_v2 tolerates the other order anyway.
SessionStore::~SessionStore() = default;

Expected<std::int64_t> SessionStore::add_protocol(const std::string& name,
                                                  const std::string& text,
                                                  const std::string& source_path) {
  return guarded(db_, [&]() -> std::int64_t {
    const std::string digest = sha256_hex(text);
    Transaction txn(db_.connection());
    auto& s = stmts_->insert_protocol;
    s.bind(1, std::string_view(name)).bind(2, std::string_view(digest)).bind(3, std::string_view(text));
    // The file name only: the folder can name a person (/home/<name>/…).
    const std::string file_name = std::filesystem::path(source_path).filename().string();
    if (file_name.empty()) s.bind_null(4); else s.bind(4, std::string_view(file_name));
    s.run();
    auto& f = stmts_->find_protocol;
    f.bind(1, std::string_view(digest));
    f.step();
    const std::int64_t id = f.column_int(0);
    f.reset();
    txn.commit();
    return id;
  });
}

Expected<std::int64_t> SessionStore::add_participant(const ParticipantRecord& p) {
  if (auto ok = check_pseudonym(p.pseudonym); !ok) return ok.error();
  if (p.ipd_m && !(*p.ipd_m > 0.04 && *p.ipd_m < 0.09))
    return DataError{DataError::Kind::bad_input,
                     "participant IPD " + std::to_string(*p.ipd_m) +
                         " m is outside 0.04-0.09 m (give metres, not millimetres)"};
  return guarded(db_, [&]() -> std::int64_t {
    Transaction txn(db_.connection());
    auto& f = stmts_->find_participant;
    f.bind(1, std::string_view(p.pseudonym));
    if (f.step()) {
      const std::int64_t id = f.column_int(0);
      f.reset();
      return id;  // nothing written; the transaction rolls back harmlessly
    }
    f.reset();
    auto& s = stmts_->insert_participant;
    s.bind(1, std::string_view(p.pseudonym)).bind(2, p.ipd_m).bind_static(3, to_string(p.dominant_eye));
    s.run();
    const std::int64_t id = db_.connection().last_insert_rowid();
    txn.commit();
    return id;
  });
}

std::int64_t SessionStore::insert_session(const SessionRecord& r) {
  std::int64_t number = 0;
  if (r.session_number) {
    number = *r.session_number;
  } else {
    auto& n = stmts_->next_session_number;
    n.bind(1, r.participant_id);
    n.step();
    number = n.column_int(0);
    n.reset();
  }
  auto& s = stmts_->insert_session;
  s.bind(1, r.protocol_id).bind(2, r.participant_id).bind(3, number);
  s.bind(4, std::string_view(r.software_version)).bind(5, std::string_view(r.software_commit));
  s.bind_static(6, to_string(r.backend));
  s.bind(7, std::string_view(r.renderer_device)).bind(8, std::string_view(r.renderer_driver));
  s.bind(9, r.display_refresh_hz).bind(10, r.seed);
  if (r.table_calibration_json) s.bind(11, std::string_view(*r.table_calibration_json));
  else s.bind_null(11);
  if (!r.session_uuid.empty() && !is_session_uuid(r.session_uuid))
    throw SqliteFailure(SQLITE_CONSTRAINT, "session_uuid \"" + r.session_uuid + "\" is not an RFC 9562 UUID");
  const std::string uuid = r.session_uuid.empty() ? new_session_uuid() : r.session_uuid;
  s.bind(12, std::string_view(uuid));
  s.run();
  return db_.connection().last_insert_rowid();
}

Expected<std::vector<std::int64_t>> SessionStore::insert_plan(std::int64_t session_id,
                                                              const std::vector<BlockPlan>& blocks) {
  auto& count = stmts_->count_plan;
  count.bind(1, session_id);
  count.step();
  const std::int64_t existing = count.column_int(0);
  count.reset();
  if (existing != 0)
    return DataError{DataError::Kind::bad_input, "session " + std::to_string(session_id) + " already has a trial plan"};
  std::vector<std::int64_t> ids;
  std::int64_t trial_index = 0;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const BlockPlan& block = blocks[b];
    auto& ib = stmts_->insert_block;
    ib.bind(1, session_id).bind(2, static_cast<std::int64_t>(b)).bind(3, std::string_view(block.name));
    ib.bind(4, block.is_practice ? 1 : 0).bind(5, std::string_view(block.settings_json));
    ib.run();
    const std::int64_t block_id = db_.connection().last_insert_rowid();
    for (std::size_t t = 0; t < block.trials.size(); ++t) {
      auto& it = stmts_->insert_trial;
      it.bind(1, session_id).bind(2, block_id).bind(3, trial_index++);
      it.bind(4, static_cast<std::int64_t>(t));
      it.bind(5, std::string_view(block.trials[t].conditions_json));
      it.bind(6, std::string_view(block.trials[t].stimulus_json));
      it.run();
      ids.push_back(db_.connection().last_insert_rowid());
    }
  }
  return ids;
}

void SessionStore::insert_event(const EventRecord& e) {
  auto& s = stmts_->insert_event;
  s.bind(1, e.session_id).bind(2, e.trial_id).bind(3, e.t_ns);
  s.bind(4, std::string_view(e.kind)).bind(5, std::string_view(e.detail_json));
  s.run();
}

Expected<std::int64_t> SessionStore::create_session(const SessionRecord& r) {
  return guarded(db_, [&]() -> std::int64_t {
    Transaction txn(db_.connection());
    const std::int64_t id = insert_session(r);
    txn.commit();
    return id;
  });
}

Expected<std::vector<std::int64_t>> SessionStore::store_plan(std::int64_t session_id,
                                                             const std::vector<BlockPlan>& blocks) {
  return guarded(db_, [&]() -> Expected<std::vector<std::int64_t>> {
    Transaction txn(db_.connection());
    auto ids = insert_plan(session_id, blocks);
    if (ids) txn.commit();
    return ids;
  });
}

Expected<StartedSession> SessionStore::start_session(
    const SessionRecord& session, const std::vector<BlockPlan>& blocks, const std::vector<EventRecord>& events,
    const std::function<Expected<Done>(std::int64_t session_id)>& before_commit) {
  return guarded(db_, [&]() -> Expected<StartedSession> {
    Transaction txn(db_.connection());
    StartedSession out;
    out.session_id = insert_session(session);
    auto ids = insert_plan(out.session_id, blocks);
    if (!ids) return ids.error();
    out.trial_ids = std::move(ids).value();
    for (EventRecord e : events) {
      e.session_id = out.session_id;
      insert_event(e);
    }
    if (before_commit)
      if (auto ok = before_commit(out.session_id); !ok) return ok.error();
    txn.commit();
    return out;
  });
}

Expected<std::optional<PlannedTrialRecord>> SessionStore::next_incomplete_trial(std::int64_t session_id) {
  return guarded(db_, [&]() -> std::optional<PlannedTrialRecord> {
    auto& s = stmts_->next_trial;
    s.bind(1, session_id);
    std::optional<PlannedTrialRecord> out;
    if (s.step()) {
      PlannedTrialRecord t;
      t.trial_id = s.column_int(0);
      t.block_id = s.column_int(1);
      t.block_index = s.column_int(2);
      t.trial_index = s.column_int(3);
      t.trial_in_block = s.column_int(4);
      t.attempt = s.column_int(5);
      t.conditions_json = s.column_text(6);
      t.stimulus_json = s.column_text(7);
      out = std::move(t);
    }
    s.reset();
    return out;
  });
}

Expected<std::int64_t> SessionStore::begin_trial(std::int64_t trial_id) {
  return guarded(db_, [&]() -> Expected<std::int64_t> {
    Transaction txn(db_.connection());
    auto& s = stmts_->begin_trial;
    s.bind(1, trial_id);
    if (!s.step()) {
      s.reset();
      return DataError{DataError::Kind::not_found,
                       "trial " + std::to_string(trial_id) + " does not exist or is finished"};
    }
    const std::int64_t attempt = s.column_int(0);
    s.reset();
    txn.commit();
    return attempt;
  });
}

Expected<Done> SessionStore::complete_trial(const TrialResult& r) {
  if (r.response_ns < r.onset_ns)
    return DataError{DataError::Kind::bad_input,
                     "trial " + std::to_string(r.trial_id) + ": response_ns " +
                         std::to_string(r.response_ns) + " is before onset_ns " +
                         std::to_string(r.onset_ns)};
  return guarded(db_, [&]() -> Expected<Done> {
    Transaction txn(db_.connection());
    auto& st = stmts_->trial_status;
    st.bind(1, r.trial_id);
    if (!st.step()) {
      st.reset();
      return DataError{DataError::Kind::not_found,
                       "trial " + std::to_string(r.trial_id) + " does not exist"};
    }
    const auto status = parse_trial_status(st.column_text(0));
    const std::int64_t session_id = st.column_int(1);
    st.reset();
    if (status == TrialStatus::completed) return Done{};  // a retry after a commit that did succeed
    auto& s = stmts_->complete_trial;
    s.bind(1, r.trial_id).bind(2, r.onset_ns).bind(3, r.response_ns);
    s.bind(4, std::string_view(r.response)).bind(5, std::string_view(r.response_device));
    if (r.stimulus_json) s.bind(6, std::string_view(*r.stimulus_json)); else s.bind_null(6);
    s.run();
    if (r.staircase_step) {
      const StaircaseStep& step = *r.staircase_step;
      auto& is = stmts_->insert_step;
      is.bind(1, session_id).bind(2, std::string_view(step.staircase)).bind(3, step.step_index);
      is.bind(4, r.trial_id).bind(5, step.intensity);
      if (step.response_correct) is.bind(6, *step.response_correct ? 1 : 0); else is.bind_null(6);
      is.bind(7, step.is_reversal ? 1 : 0).bind(8, step.next_intensity);
      is.run();
      if (step.posterior)
        insert_event(event_record(session_id, r.trial_id, r.response_ns,
                                  events::Posterior{step.staircase, step.step_index, *step.posterior}));
    }
    txn.commit();
    return Done{};
  });
}

Expected<Done> SessionStore::end_unanswered(std::int64_t trial_id, const char* status,
                                            const std::string& reason) {
  return guarded(db_, [&]() -> Done {
    Transaction txn(db_.connection());
    auto& s = stmts_->end_unanswered;
    s.bind(1, trial_id).bind(2, std::string_view(status));
    if (reason.empty()) s.bind_null(3); else s.bind(3, std::string_view(reason));
    s.run();
    txn.commit();
    return Done{};
  });
}

Expected<Done> SessionStore::skip_trial(std::int64_t trial_id, const std::string& reason) {
  return end_unanswered(trial_id, "skipped", reason);
}

Expected<Done> SessionStore::abort_trial(std::int64_t trial_id, const std::string& reason) {
  return end_unanswered(trial_id, "aborted", reason);
}

Expected<Done> SessionStore::record_shot(const ShotRecord& r) {
  return guarded(db_, [&]() -> Done {
    Transaction txn(db_.connection());
    Statement s(db_.connection(),
                "INSERT OR REPLACE INTO shots (session_id, trial_id, shot_index, t_ns, rest_ns, player, ball, "
                "aim_x, aim_z, speed_m_s, cue_speed_m_s, tip_side, tip_height, miscue, cue_pose, "
                "table_settings, before_state, shot, events, rest_state, pocketed, event_count) VALUES "
                "(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19, ?20, ?21, ?22)");
    s.bind(1, r.session_id).bind(2, r.trial_id).bind(3, r.shot_index).bind(4, r.t_ns).bind(5, r.rest_ns);
    s.bind(6, std::string_view(r.player)).bind(7, std::string_view(r.ball)).bind(8, r.aim_x).bind(9, r.aim_z);
    s.bind(10, r.speed_m_s).bind(11, r.cue_speed_m_s).bind(12, r.tip_side).bind(13, r.tip_height);
    s.bind(14, std::int64_t{r.miscue ? 1 : 0}).bind(15, r.cue_pose);
    s.bind(16, std::string_view(r.table_settings)).bind(17, std::string_view(r.before_state));
    s.bind(18, std::string_view(r.shot)).bind(19, std::string_view(r.events));
    s.bind(20, std::string_view(r.rest_state)).bind(21, std::string_view(r.pocketed)).bind(22, r.event_count);
    s.run();
    txn.commit();
    return Done{};
  });
}

Expected<std::vector<ShotRecord>> SessionStore::shots(std::int64_t trial_id) { return read_shots(db_, trial_id); }

Expected<Done> SessionStore::record_answer(const QuestionnaireAnswer& a) {
  return guarded(db_, [&]() -> Done {
    Transaction txn(db_.connection());
    Statement s(db_.connection(),
                "INSERT OR REPLACE INTO questionnaire_answers (session_id, trial_id, instrument, item_index, "
                "item_id, item_text, value, label, shown_ns, t_ns, rt_ms, device) VALUES "
                "(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12)");
    s.bind(1, a.session_id).bind(2, a.trial_id).bind(3, std::string_view(a.instrument)).bind(4, a.item_index);
    s.bind(5, std::string_view(a.item_id)).bind(6, std::string_view(a.item_text)).bind(7, a.value);
    s.bind(8, std::string_view(a.label)).bind(9, a.shown_ns).bind(10, a.t_ns);
    s.bind(11, static_cast<double>(std::max<std::int64_t>(0, a.t_ns - a.shown_ns)) * 1e-6);
    s.bind(12, std::string_view(a.device));
    s.run();
    txn.commit();
    return Done{};
  });
}

Expected<std::vector<QuestionnaireAnswer>> SessionStore::answers(std::int64_t trial_id) {
  return guarded(db_, [&]() -> std::vector<QuestionnaireAnswer> {
    Statement s(db_.connection(),
                "SELECT session_id, trial_id, instrument, item_index, item_id, item_text, value, label, shown_ns, "
                "t_ns, device FROM questionnaire_answers WHERE trial_id = ?1 ORDER BY item_index");
    s.bind(1, trial_id);
    std::vector<QuestionnaireAnswer> out;
    while (s.step()) {
      QuestionnaireAnswer a;
      s.columns(a.session_id, a.trial_id, a.instrument, a.item_index, a.item_id, a.item_text, a.value, a.label,
                a.shown_ns, a.t_ns, a.device);
      out.push_back(std::move(a));
    }
    return out;
  });
}

Expected<Done> SessionStore::record_scores(const std::vector<QuestionnaireScore>& scores) {
  return guarded(db_, [&]() -> Done {
    Transaction txn(db_.connection());
    Statement s(db_.connection(),
                "INSERT OR REPLACE INTO questionnaire_scores (session_id, trial_id, instrument, subscale_index, "
                "subscale, rule, weight, items, answered, raw, score) VALUES "
                "(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)");
    for (const auto& r : scores) {
      s.bind(1, r.session_id).bind(2, r.trial_id).bind(3, std::string_view(r.instrument)).bind(4, r.subscale_index);
      s.bind(5, std::string_view(r.subscale)).bind(6, std::string_view(r.rule)).bind(7, r.weight);
      s.bind(8, r.items).bind(9, r.answered).bind(10, r.raw).bind(11, r.score);
      s.run();
    }
    txn.commit();
    return Done{};
  });
}

Expected<std::int64_t> SessionStore::record_event(const EventRecord& e) {
  return guarded(db_, [&]() -> std::int64_t {
    Transaction txn(db_.connection());
    insert_event(e);
    const std::int64_t id = db_.connection().last_insert_rowid();
    txn.commit();
    return id;
  });
}

Expected<Done> SessionStore::record_events(const std::vector<EventRecord>& events) {
  return guarded(db_, [&]() -> Done {
    Transaction txn(db_.connection());
    for (const auto& e : events) insert_event(e);
    txn.commit();
    return Done{};
  });
}

Expected<Done> SessionStore::set_session_status(std::int64_t session_id, SessionStatus status) {
  return guarded(db_, [&]() -> Expected<Done> {
    Transaction txn(db_.connection());
    stmts_->set_status.bind(1, session_id).bind_static(2, to_string(status)).run();
    if (db_.connection().changes() == 0)
      return DataError{DataError::Kind::not_found,
                       "session " + std::to_string(session_id) + " does not exist"};
    txn.commit();
    return Done{};
  });
}

Expected<Done> SessionStore::close_session(std::int64_t session_id, SessionStatus status) {
  return guarded(db_, [&]() -> Expected<Done> {
    Transaction txn(db_.connection());
    stmts_->close_session.bind(1, session_id).bind_static(2, to_string(status)).run();
    if (db_.connection().changes() == 0)
      return DataError{DataError::Kind::not_found,
                       "session " + std::to_string(session_id) + " does not exist"};
    txn.commit();
    return Done{};
  });
}

Expected<std::int64_t> SessionStore::count_trials(std::int64_t session_id, std::optional<TrialStatus> status) {
  return guarded(db_, [&]() -> std::int64_t {
    auto& s = stmts_->count_trials;
    s.bind(1, session_id).bind_static(2, status ? std::string_view(to_string(*status)) : std::string_view());
    s.step();
    const std::int64_t n = s.column_int(0);
    s.reset();
    return n;
  });
}

}  // namespace curvlab::harness::data
