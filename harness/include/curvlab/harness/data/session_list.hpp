// What a data file holds, session by session: what `curvlab sessions` lists
// after an interruption, and what a command that names a missing session
// offers instead. Reads through any open Database (read_only for the
// listing, so it never writes and works while sessions are being written);
// asks the file's lock (writer_lock.hpp) which sessions a live process writes
// now. Like Database, one thread at a time.
#pragma once

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/records.hpp"
#include "curvlab/harness/data/writer_lock.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::data {

// A session's trials by trials.status; the rest of `planned` are pending or
// were running when the session stopped.
struct TrialCounts {
  std::int64_t planned = 0;
  std::int64_t completed = 0;
  std::int64_t skipped = 0;
  std::int64_t aborted = 0;
};

// One row of the sessions table with what the file says about it.
struct SessionListEntry {
  std::int64_t session_id = 0;
  std::string session_uuid;  // empty when the row has none
  std::int64_t session_number = 0;
  std::string pseudonym;
  std::string protocol_name;
  std::string protocol_sha256;
  SessionStatus stored_status = SessionStatus::running;  // sessions.status
  std::optional<Backend> backend;                         // nullopt: 'unknown' (migrated from version 1)
  TrialCounts trials;
  std::string started_utc;
  std::optional<std::string> ended_utc;
  // The latest wall-clock time the file records for the session: its start,
  // a trial's completion or its end. Frames, samples and events carry the
  // session's monotonic clock only, which is not wall time.
  std::string last_activity_utc;
  // The session_start event is there: resume can expand the design again.
  bool has_session_start = false;
};

// The status a listing shows. A completed session stays completed; a session
// a live process writes is running; one stored running or paused whose
// process is gone (killed, crashed, the machine went down) ended without
// closing and is interrupted; interrupted and aborted stay as stored.
SessionStatus listed_status(SessionStatus stored, bool writer_alive);

struct ListedSession {
  SessionListEntry summary;
  SessionStatus status = SessionStatus::running;  // listed_status()
  std::optional<LockHolder> writer;               // the live process writing it, if any
  // Stored running or paused, but no process writes it.
  bool ended_without_closing = false;
  // `curvlab resume` can continue it: not completed, not being written, and
  // it has its session_start event.
  bool resumable = false;
};

// Every session of the file in session_id order, with its live writer.
// A session stored open without a writer is read again after the lock was
// asked, so one that closed in between is not shown interrupted.
Expected<std::vector<ListedSession>> list_sessions(Database& db);

// The stored protocol text with this SHA-256; not_found when absent.
Expected<std::string> read_protocol_text(Database& db, const std::string& sha256);

// The not_found error for a session id the file lacks: names the sessions it
// does hold (id, participant, status; the first dozen) or says it holds none,
// and points to `curvlab sessions --db FILE`.
DataError missing_session_error(Database& db, std::int64_t session_id);

}  // namespace curvlab::harness::data
