// `curvlab sessions`: what a data file holds, one line per session — who,
// which protocol, how far it got, whether a process writes it now, and the
// command that continues it. The file is opened read-only, as export opens
// it, so the listing never writes and works while sessions are being written.
#include "common.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/session_list.hpp"
#include "curvlab/harness/protocol/loader.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string_view>

namespace curvlab::harness::cli {

// `path` as one shell word: quoted when it holds anything a shell reads.
std::string shell_word(const std::string& path) {
  constexpr std::string_view safe = "/._-+,:=@%";
  const bool plain = !path.empty() && std::all_of(path.begin(), path.end(), [&](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || safe.find(c) != std::string_view::npos;
  });
  if (plain) return path;
  std::string out = "'";
  for (char c : path) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

namespace {

struct SessionsArgs {
  std::string db;
  bool json = false;
};


std::string resume_command(const std::string& db, std::int64_t session_id) {
  return "curvlab resume --db " + shell_word(db) + " --session " + std::to_string(session_id);
}

// Each stored protocol's version (the [protocol] table of its text), read by
// the protocol loader; nullopt when the stored text no longer loads.
class ProtocolVersions {
 public:
  explicit ProtocolVersions(data::Database& db) : db_(db) {}
  std::optional<std::string> of(const std::string& sha256) {
    if (const auto it = known_.find(sha256); it != known_.end()) return it->second;
    std::optional<std::string> version;
    if (auto text = data::read_protocol_text(db_, sha256)) {
      const auto loaded = harness::protocol::load_protocol_text(text.value(), "stored protocol");
      if (loaded && !loaded->meta.version.empty()) version = loaded->meta.version;
    }
    known_.emplace(sha256, version);
    return version;
  }

 private:
  data::Database& db_;
  std::map<std::string, std::optional<std::string>> known_;
};

Json writer_json(const std::optional<data::LockHolder>& writer) {
  if (!writer) return nullptr;
  return {{"pid", writer->pid}, {"host", writer->host}, {"since_utc", writer->since_utc}};
}

Json session_json(const data::ListedSession& s, const std::optional<std::string>& version, const std::string& db) {
  const auto& m = s.summary;
  Json j;
  j["session_id"] = m.session_id;
  j["session_uuid"] = m.session_uuid.empty() ? Json(nullptr) : Json(m.session_uuid);
  j["session_number"] = m.session_number;
  j["participant"] = m.pseudonym;
  j["protocol"] = m.protocol_name;
  j["protocol_version"] = version ? Json(*version) : Json(nullptr);
  j["protocol_sha256"] = m.protocol_sha256;
  j["status"] = data::to_string(s.status);
  j["stored_status"] = data::to_string(m.stored_status);
  j["ended_without_closing"] = s.ended_without_closing;
  j["trials_planned"] = m.trials.planned;
  j["trials_completed"] = m.trials.completed;
  j["trials_skipped"] = m.trials.skipped;
  j["trials_aborted"] = m.trials.aborted;
  j["started_utc"] = m.started_utc;
  j["ended_utc"] = m.ended_utc ? Json(*m.ended_utc) : Json(nullptr);
  j["last_activity_utc"] = m.last_activity_utc;
  j["backend"] = m.backend ? data::to_string(*m.backend) : "unknown";
  j["writer"] = writer_json(s.writer);
  j["resume_command"] = s.resumable ? Json(resume_command(db, m.session_id)) : Json(nullptr);
  return j;
}

// "2025-11-25T10:31:02.123Z" as "2025-11-25 10:31:02" (the header says UTC).
std::string readable_utc(const std::string& utc) {
  if (utc.size() < 19 || utc[10] != 'T') return utc;
  std::string out = utc.substr(0, 19);
  out[10] = ' ';
  return out;
}

std::string continue_column(const data::ListedSession& s, const std::string& db) {
  if (s.writer) return "being written by process " + std::to_string(s.writer->pid) + " on " + s.writer->host;
  if (s.resumable) return resume_command(db, s.summary.session_id);
  if (s.status == data::SessionStatus::completed) return "-";
  return "cannot be resumed: its session_start event is missing";
}

using Row = std::vector<std::string>;

// Columns two blanks apart; numbers right-aligned; the last column unpadded.
void print_table(const std::vector<Row>& rows, const std::vector<bool>& right) {
  std::vector<std::size_t> width(rows.front().size(), 0);
  for (const auto& row : rows)
    for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
  for (const auto& row : rows) {
    std::string line;
    for (std::size_t c = 0; c < row.size(); ++c) {
      const std::string pad(width[c] - row[c].size(), ' ');
      if (c + 1 == row.size()) line += right[c] ? pad + row[c] : row[c];
      else line += (right[c] ? pad + row[c] : row[c] + pad) + "  ";
    }
    std::cout << line << '\n';
  }
}

Row table_row(const data::ListedSession& s, const std::optional<std::string>& version, const std::string& db) {
  const auto& m = s.summary;
  return {std::to_string(m.session_id),
          m.pseudonym,
          m.protocol_name + (version ? " " + *version : ""),
          m.protocol_sha256.substr(0, 8),
          data::to_string(s.status),
          std::to_string(m.trials.completed) + "/" + std::to_string(m.trials.planned),
          std::to_string(m.trials.skipped),
          std::to_string(m.trials.aborted),
          m.backend ? data::to_string(*m.backend) : "unknown",
          readable_utc(m.started_utc),
          readable_utc(m.last_activity_utc),
          continue_column(s, db)};
}

void print_text(const std::vector<data::ListedSession>& sessions, ProtocolVersions& versions, const std::string& db) {
  if (sessions.empty()) {
    std::cout << db << ": no sessions\n";
    return;
  }
  std::vector<Row> rows{{"id", "participant", "protocol", "sha256", "status", "done", "skipped", "aborted", "backend",
                         "started (UTC)", "last activity (UTC)", "continue"}};
  for (const auto& s : sessions) rows.push_back(table_row(s, versions.of(s.summary.protocol_sha256), db));
  print_table(rows, {true, false, false, false, false, true, true, true, false, false, false, false});
  for (const auto& s : sessions)
    if (s.ended_without_closing)
      std::cout << "session " << s.summary.session_id << " is stored " << data::to_string(s.summary.stored_status)
                << " but no process writes it: it ended without closing (killed, crashed or the machine went "
                   "down); its completed trials are kept\n";
}

// The --db file opened read-only, and its sessions.
std::pair<data::Database, std::vector<data::ListedSession>> open_listing(const std::string& path) {
  if (std::error_code ec; std::filesystem::is_directory(path, ec))
    throw UsageError("--db " + path + ": is a folder; expected a curvlab data file");
  auto db = data::Database::open(path, data::OpenMode::read_only);
  if (!db) raise(db.error());
  auto sessions = data::list_sessions(db.value());
  if (!sessions) raise(sessions.error());
  return {std::move(db).value(), std::move(sessions).value()};
}

void sessions_command(const SessionsArgs& a) {
  auto [database, sessions] = open_listing(a.db);
  ProtocolVersions versions(database);
  if (!a.json) {
    print_text(sessions, versions, a.db);
    return;
  }
  Json doc = Json::array();
  for (const auto& s : sessions)
    doc.push_back(session_json(s, versions.of(s.summary.protocol_sha256), a.db));
  std::cout << doc.dump(2) << '\n';
}

// ---- curvlab participants -------------------------------------------------

struct ParticipantsArgs {
  std::string db;
  bool json = false;
};

// Each pseudonym of the file with its sessions, in order of first session.
std::vector<std::pair<std::string, std::vector<const data::ListedSession*>>> by_participant(
    const std::vector<data::ListedSession>& sessions) {
  std::vector<std::pair<std::string, std::vector<const data::ListedSession*>>> out;
  for (const auto& s : sessions) {
    auto it = std::find_if(out.begin(), out.end(), [&](const auto& p) { return p.first == s.summary.pseudonym; });
    if (it == out.end()) it = out.insert(out.end(), {s.summary.pseudonym, {}});
    it->second.push_back(&s);
  }
  return out;
}

// "session 1 (demo 1.0, completed 8/8, started 2025-11-25 10:31:02)"
std::string session_line(const data::ListedSession& s, ProtocolVersions& versions) {
  const auto& m = s.summary;
  const auto version = versions.of(m.protocol_sha256);
  return "session " + std::to_string(m.session_id) + " (" + m.protocol_name + (version ? " " + *version : "") + ", " +
         std::string(data::to_string(s.status)) + " " + std::to_string(m.trials.completed) + "/" +
         std::to_string(m.trials.planned) + ", started " + readable_utc(m.started_utc) + " UTC)";
}

void participants_command(const ParticipantsArgs& a) {
  auto [database, sessions] = open_listing(a.db);
  ProtocolVersions versions(database);
  const auto people = by_participant(sessions);
  if (a.json) {
    Json doc = Json::array();
    for (const auto& [pseudonym, list] : people) {
      Json ids = Json::array();
      for (const auto* s : list) ids.push_back(session_json(*s, versions.of(s->summary.protocol_sha256), a.db));
      doc.push_back({{"participant", pseudonym}, {"sessions", ids}});
    }
    std::cout << doc.dump(2) << '\n';
    return;
  }
  if (people.empty()) {
    std::cout << a.db << ": no participants\n";
    return;
  }
  std::vector<Row> rows{{"participant", "sessions", "completed", "first started (UTC)", "last activity (UTC)", "which"}};
  for (const auto& [pseudonym, list] : people) {
    int completed = 0;
    std::string which, last;
    for (const auto* s : list) {
      if (s->status == data::SessionStatus::completed) ++completed;
      which += (which.empty() ? "" : ", ") + std::to_string(s->summary.session_id) + " " +
               s->summary.protocol_name + " " + std::string(data::to_string(s->status));
      last = std::max(last, s->summary.last_activity_utc);
    }
    rows.push_back({pseudonym, std::to_string(list.size()), std::to_string(completed),
                    readable_utc(list.front()->summary.started_utc), readable_utc(last), which});
  }
  print_table(rows, {false, true, true, false, false, false});
}

}  // namespace

std::vector<std::pair<std::string, int>> participants_in(const std::string& db_path) {
  std::vector<std::pair<std::string, int>> out;
  std::error_code ec;
  if (!std::filesystem::exists(db_path, ec)) return out;
  auto [database, sessions] = open_listing(db_path);
  for (const auto& [pseudonym, list] : by_participant(sessions))
    out.emplace_back(pseudonym, static_cast<int>(list.size()));
  return out;
}

void check_participant_is_new(const std::string& db_path, const std::string& pseudonym) {
  std::error_code ec;
  if (!std::filesystem::exists(db_path, ec)) return;
  auto db = data::Database::open(db_path, data::OpenMode::read_only);
  if (!db) return;  // the run itself reports a file it cannot use
  auto sessions = data::list_sessions(db.value());
  if (!sessions) return;
  ProtocolVersions versions(db.value());
  std::string earlier;
  std::optional<std::int64_t> unfinished;
  for (const auto& s : sessions.value()) {
    if (s.summary.pseudonym != pseudonym) continue;
    earlier += (earlier.empty() ? "" : "; ") + session_line(s, versions);
    if (s.resumable && !unfinished) unfinished = s.summary.session_id;
  }
  if (earlier.empty()) return;
  throw UsageError("--participant " + pseudonym + " already has " + earlier + " in " + db_path +
                   ". A new session of the same pseudonym gets the same participant number, so the same trial order "
                   "and counterbalancing row. Check the pseudonym (curvlab participants --db " + shell_word(db_path) +
                   " lists them), " +
                   (unfinished ? "continue the unfinished one (" + resume_command(db_path, *unfinished) + "), " : "") +
                   "or add --new-session to start another session of this participant");
}

void add_sessions_commands(CLI::App& app) {
  auto pa = std::make_shared<ParticipantsArgs>();
  auto* people = app.add_subcommand("participants", "list the participants (pseudonyms) of a data file and their "
                                                    "sessions");
  people->add_option("--db", pa->db, "curvlab data file (opened read-only)")->required();
  people->add_flag("--json", pa->json, "print one JSON array of participants with their sessions");
  people->callback([pa] { participants_command(*pa); });

  auto args = std::make_shared<SessionsArgs>();
  auto* cmd =
      app.add_subcommand("sessions", "list the sessions of a data file, their progress and how to continue them");
  cmd->add_option("--db", args->db, "curvlab data file (opened read-only)")->required();
  cmd->add_flag("--json", args->json, "print one JSON array of sessions");
  cmd->callback([args] { sessions_command(*args); });
}

}  // namespace curvlab::harness::cli
