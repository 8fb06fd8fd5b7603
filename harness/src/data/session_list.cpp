#include "curvlab/harness/data/session_list.hpp"

#include "curvlab/harness/data/events.hpp"
#include "curvlab/harness/data/sqlite.hpp"

#include <algorithm>
#include <cctype>

namespace curvlab::harness::data {
namespace {

// sessions ⋈ participants ⋈ protocols with each session's trial counts, in
// one pass over the trials (their (session_id, trial_index) index) and one
// over the events for the session_start kind.
constexpr const char* summary_sql =
    "SELECT s.session_id, s.session_uuid, s.session_number, p.pseudonym, pr.name, pr.sha256, s.status, "
    "s.backend, s.started_utc, s.ended_utc, "
    "(SELECT COUNT(*) FROM trials t WHERE t.session_id = s.session_id), "
    "(SELECT COUNT(*) FROM trials t WHERE t.session_id = s.session_id AND t.status = ?2), "
    "(SELECT COUNT(*) FROM trials t WHERE t.session_id = s.session_id AND t.status = ?3), "
    "(SELECT COUNT(*) FROM trials t WHERE t.session_id = s.session_id AND t.status = ?4), "
    "(SELECT MAX(t.completed_utc) FROM trials t WHERE t.session_id = s.session_id), "
    "s.session_id IN (SELECT e.session_id FROM events e WHERE e.kind = ?5) "
    "FROM sessions s JOIN participants p ON p.participant_id = s.participant_id "
    "JOIN protocols pr ON pr.protocol_id = s.protocol_id "
    "WHERE ?1 IS NULL OR s.session_id = ?1 ORDER BY s.session_id";

// A stored UTC text that is a time (files migrated from version 1 may hold
// 'unknown'); ISO 8601 texts of one form order as their times do.
bool is_time(const std::optional<std::string>& utc) {
  return utc && !utc->empty() && std::isdigit(static_cast<unsigned char>(utc->front()));
}

std::string latest(const std::string& started, const std::optional<std::string>& ended,
                   const std::optional<std::string>& last_trial) {
  std::string out = started;
  for (const auto* t : {&ended, &last_trial})
    if (is_time(*t) && (!is_time(out) || **t > out)) out = **t;
  return out;
}

Expected<SessionListEntry> summary_from(const Statement& s, const std::string& path) {
  SessionListEntry out;
  out.session_id = s.column_int(0);
  out.session_uuid = s.column_opt_text(1).value_or("");
  out.session_number = s.column_int(2);
  out.pseudonym = s.column_text(3);
  out.protocol_name = s.column_text(4);
  out.protocol_sha256 = s.column_text(5);
  const auto status = parse_session_status(s.column_text(6));
  if (!status)
    return corrupt_file_error(path, "session " + std::to_string(out.session_id) + " has an unknown status \"" +
                                        s.column_text(6) + "\"");
  out.stored_status = *status;
  out.backend = parse_backend(s.column_text(7));
  out.started_utc = s.column_text(8);
  out.ended_utc = s.column_opt_text(9);
  out.trials = {s.column_int(10), s.column_int(11), s.column_int(12), s.column_int(13)};
  out.last_activity_utc = latest(out.started_utc, out.ended_utc, s.column_opt_text(14));
  out.has_session_start = s.column_int(15) != 0;
  return out;
}

// The summaries of every session, or of one.
Expected<std::vector<SessionListEntry>> read_summaries(Database& db, std::optional<std::int64_t> session_id) {
  try {
    Statement s(db.connection(), summary_sql);
    s.bind(1, session_id)
        .bind_static(2, to_string(TrialStatus::completed))
        .bind_static(3, to_string(TrialStatus::skipped))
        .bind_static(4, to_string(TrialStatus::aborted))
        .bind_static(5, to_string(EventKind::session_start));
    std::vector<SessionListEntry> out;
    while (s.step()) {
      auto summary = summary_from(s, db.path());
      if (!summary) return summary.error();
      out.push_back(std::move(summary.value()));
    }
    return out;
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, db.path());
  }
}

bool stored_open(SessionStatus s) { return s == SessionStatus::running || s == SessionStatus::paused; }

ListedSession listed(SessionListEntry summary, std::optional<LockHolder> writer) {
  ListedSession out;
  out.status = listed_status(summary.stored_status, writer.has_value());
  out.ended_without_closing = !writer && stored_open(summary.stored_status);
  out.resumable = out.status != SessionStatus::completed && out.status != SessionStatus::running &&
                  summary.has_session_start;
  out.summary = std::move(summary);
  out.writer = std::move(writer);
  return out;
}

std::string list_for_message(const std::vector<ListedSession>& sessions) {
  constexpr std::size_t shown = 12;
  std::string out;
  for (std::size_t i = 0; i < std::min(shown, sessions.size()); ++i) {
    const auto& s = sessions[i];
    out += (i ? ", " : "") + std::to_string(s.summary.session_id) + " (" + s.summary.pseudonym + ", " +
           to_string(s.status) + ")";
  }
  if (sessions.size() > shown) out += " and " + std::to_string(sessions.size() - shown) + " more";
  return out;
}

}  // namespace

SessionStatus listed_status(SessionStatus stored, bool writer_alive) {
  if (stored == SessionStatus::completed) return stored;
  if (writer_alive) return SessionStatus::running;
  if (stored_open(stored)) return SessionStatus::interrupted;
  return stored;
}

Expected<std::vector<ListedSession>> list_sessions(Database& db) {
  auto summaries = read_summaries(db, std::nullopt);
  if (!summaries) return summaries.error();
  std::vector<ListedSession> out;
  for (auto& summary : summaries.value()) {
    auto writer = WriterLock::session_writer(db.path(), summary.session_id);
    if (!writer && stored_open(summary.stored_status)) {
      // Its writer may have closed it after the first read and then let go
      // of the lock: the row as it is now, after the lock was asked.
      auto again = read_summaries(db, summary.session_id);
      if (!again) return again.error();
      if (!again->empty()) summary = std::move(again->front());
    }
    out.push_back(listed(std::move(summary), std::move(writer)));
  }
  return out;
}

Expected<std::string> read_protocol_text(Database& db, const std::string& sha256) {
  try {
    Statement s(db.connection(), "SELECT text FROM protocols WHERE sha256 = ?1");
    s.bind(1, std::string_view(sha256));
    if (!s.step()) return DataError{DataError::Kind::not_found, db.path() + ": no protocol with SHA-256 " + sha256};
    return s.column_text(0);
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, db.path());
  }
}

DataError missing_session_error(Database& db, std::int64_t session_id) {
  std::string message = db.path() + ": no session with id " + std::to_string(session_id);
  const auto sessions = list_sessions(db);
  if (!sessions) return DataError{DataError::Kind::not_found, message};
  if (sessions->empty()) return DataError{DataError::Kind::not_found, message + "; the file holds no sessions"};
  return DataError{DataError::Kind::not_found, message + "; the file holds session" +
                                                   (sessions->size() > 1 ? "s " : " ") +
                                                   list_for_message(sessions.value()) + "; curvlab sessions --db " +
                                                   db.path() + " lists them with the command that continues each"};
}

}  // namespace curvlab::harness::data
