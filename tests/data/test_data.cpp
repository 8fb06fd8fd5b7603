#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/events.hpp"
#include "curvlab/harness/data/export.hpp"
#include "curvlab/harness/data/sample_writer.hpp"
#include "curvlab/harness/data/session_reader.hpp"
#include "curvlab/harness/data/session_store.hpp"
#include "curvlab/harness/data/uuid.hpp"
#include "curvlab/harness/data/sha256.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

using namespace curvlab::harness::data;
namespace fs = std::filesystem;

namespace {

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("curvlab_data_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// (type, name, tbl_name, sql) of every schema object, sorted by name.
std::vector<std::string> master_rows(Connection& c, bool normalize) {
  Statement s(c, "SELECT type, name, tbl_name, sql FROM sqlite_master ORDER BY name");
  std::vector<std::string> rows;
  while (s.step()) {
    std::string sql = s.column_text(3);
    if (normalize) {
      sql = std::regex_replace(sql, std::regex("--[^\n]*"), "");
      sql = std::regex_replace(sql, std::regex("\\s+"), " ");
      // ALTER TABLE ADD COLUMN (migrations) splices ", column" in before the
      // closing parenthesis: spacing around it carries no meaning.
      sql = std::regex_replace(sql, std::regex(" ?([,)])"), "$1");
      sql = std::regex_replace(sql, std::regex("\"(\\w+)\""), "$1");
    }
    rows.push_back(s.column_text(0) + "|" + s.column_text(1) + "|" + s.column_text(2) + "|" + sql);
  }
  return rows;
}

SessionStore make_store(const fs::path& db) {
  auto opened = Database::open(db.string(), OpenMode::create_or_open);
  EXPECT_TRUE(opened) << (opened ? "" : opened.error().message);
  return SessionStore(std::move(opened).value());
}

std::int64_t make_session(SessionStore& store, const std::string& pseudonym) {
  const auto protocol = store.add_protocol("billiards", "name = \"billiards\"\n").value();
  const auto participant = store.add_participant({pseudonym, 0.064, DominantEye::left}).value();
  SessionRecord r;
  r.protocol_id = protocol;
  r.participant_id = participant;
  r.software_version = "0.1.0";
  r.software_commit = "abc";
  r.renderer_device = "llvmpipe";
  r.renderer_driver = "mesa";
  r.display_refresh_hz = 90.0;
  r.seed = 7;
  r.table_calibration_json = "{\"edge_m\":1.2}";
  return store.create_session(r).value();
}

std::vector<BlockPlan> two_blocks() {
  BlockPlan practice{"practice", true, "{}", {{"{\"space\":\"E3\",\"mode\":\"tourist\"}", "{\"sagitta_m\":0.0}"}}};
  BlockPlan main{"main", false, "{}", {}};
  for (const char* space : {"S3", "H3"})
    main.trials.push_back({std::string("{\"space\":\"") + space + "\",\"mode\":\"native\",\"eyes\":2}",
                           "{\"sagitta_m\":0.01,\"note\":\"a, \\\"quoted\\\" value\"}"});
  return {practice, main};
}

}  // namespace

TEST(Sha256, KnownVectors) {
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex(std::string(1000, 'a')),
            "41edece42d63e8d9bf515a9ba6932e1c20cbc9f5a5d134645adb5db1b9737ea3");
  // FIPS 180-4 examples (NIST CSRC): the two-block message and one million 'a'.
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256_hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  // Bytes above 0x7F are hashed as unsigned bytes (UTF-8 protocol texts).
  EXPECT_EQ(sha256_hex("\xc3\xa9"), "4a99557e4033c3539de2eb65472017cad5f9557f7a0625a09f1c3f6e2ba69c4c");
}

TEST(Schema, CreatedSchemaEqualsDataSchemaSql) {
  const auto dir = fresh_dir("schema");
  auto db = Database::open((dir / "a.db").string(), OpenMode::create_or_open);
  ASSERT_TRUE(db) << db.error().message;
  EXPECT_EQ(db.value().schema_version(), current_schema_version);

  auto reference = Connection::open(":memory:", OpenFlags::read_write_create);
  reference.exec(read_file(fs::path(CURVLAB_SCHEMA_DIR) / "schema.sql"));
  EXPECT_EQ(reference.query_int("PRAGMA user_version"), current_schema_version);
  const auto expected = master_rows(reference, false);
  ASSERT_GE(expected.size(), 10u);
  EXPECT_EQ(master_rows(db.value().connection(), false), expected);
  EXPECT_EQ(db.value().connection().query_int("PRAGMA application_id"), curvlab_application_id);
  Statement mode(db.value().connection(), "PRAGMA journal_mode");
  ASSERT_TRUE(mode.step());
  EXPECT_EQ(mode.column_text(0), "wal");
}

TEST(Schema, MigratesVersion1FileAndKeepsItsData) {
  const auto dir = fresh_dir("migrate");
  const auto path = (dir / "old.db").string();
  {
    auto c = Connection::open(path, OpenFlags::read_write_create);
    c.exec(read_file(fs::path(CURVLAB_SCHEMA_DIR) / "v1.sql"));
    c.exec("INSERT INTO protocols VALUES (1, '" + sha256_hex("p") + "', 'p');"
           "INSERT INTO participants VALUES (1, 'P07');"
           "INSERT INTO sessions VALUES (1, 1, 1, 99, 'crashed', '2025-03-01T10:00:00Z');"
           "INSERT INTO trials VALUES (1, 1, 0, '{\"space\":\"S3\"}', 'convex', 512.5, 'completed');"
           "INSERT INTO trials VALUES (2, 1, 1, '{\"space\":\"H3\"}', NULL, NULL, 'pending');"
           "INSERT INTO events VALUES (1, 1, 5, 'note', 'free text');");
  }
  auto db = Database::open(path, OpenMode::open_existing);
  ASSERT_TRUE(db) << db.error().message;
  EXPECT_EQ(db.value().schema_version(), current_schema_version);
  EXPECT_EQ(db.value().integrity_check(), "ok");

  auto fresh = Database::open((dir / "new.db").string(), OpenMode::create_or_open);
  ASSERT_TRUE(fresh);
  auto fresh_db = std::move(fresh).value();
  EXPECT_EQ(master_rows(db.value().connection(), true), master_rows(fresh_db.connection(), true));

  Statement t(db.value().connection(),
              "SELECT rt_ns, status, attempt, response FROM trials ORDER BY trial_index");
  ASSERT_TRUE(t.step());
  EXPECT_EQ(t.column_int(0), 512'500'000);
  EXPECT_EQ(t.column_text(1), "completed");
  EXPECT_EQ(t.column_int(2), 1);
  EXPECT_EQ(t.column_text(3), "convex");
  ASSERT_TRUE(t.step());
  EXPECT_TRUE(t.is_null(0));
  EXPECT_EQ(t.column_text(1), "pending");
  EXPECT_EQ(db.value().connection().query_int(
                "SELECT count(*) FROM sessions WHERE status = 'interrupted' AND seed = 99"), 1);
  // A migrated session resumes where it stopped.
  SessionStore store(std::move(db).value());
  auto next = store.next_incomplete_trial(1).value();
  ASSERT_TRUE(next);
  EXPECT_EQ(next->trial_index, 1);
}

TEST(Schema, MigratesVersion3FileGivingEachSessionAUuid) {
  const auto dir = fresh_dir("migrate3");
  const auto path = (dir / "v3.db").string();
  {
    auto c = Connection::open(path, OpenFlags::read_write_create);
    c.exec(read_file(fs::path(CURVLAB_SCHEMA_DIR) / "v3.sql"));
    c.exec("PRAGMA application_id = " + std::to_string(curvlab_application_id));
    c.exec("INSERT INTO protocols VALUES (1, 'p', '" + sha256_hex("p") + "', 'p', NULL);"
           "INSERT INTO participants VALUES (1, 'P07', NULL, 'left', '2026-01-01T00:00:00Z');"
           "INSERT INTO sessions (protocol_id, participant_id, session_number, software_version, "
           "software_commit, backend, renderer_device, renderer_driver, seed, status, started_utc) "
           "VALUES (1, 1, 1, '0.3', 'c', 'xr', 'd', 'r', 5, 'completed', 't'),"
           " (1, 1, 2, '0.3', 'c', 'xr', 'd', 'r', 6, 'running', 't');"
           "INSERT INTO blocks (session_id, block_index, name) VALUES (1, 0, 'b'), (2, 0, 'b');"
           "INSERT INTO trials (session_id, block_id, trial_index, trial_in_block, conditions, "
           "status, response) VALUES (1, 1, 0, 0, '{}', 'completed', 'convex'),"
           " (2, 2, 0, 0, '{}', 'skipped', NULL), (2, 2, 1, 1, '{}', 'pending', NULL);"
           "INSERT INTO frames (session_id, frame_index, t_ns, cpu_time_ns, views, passes, draws, "
           "triangles) VALUES (1, 0, 10, 5, 2, 2, 4, 100);");
  }
  auto db = Database::open(path, OpenMode::open_existing);
  ASSERT_TRUE(db) << db.error().message;
  EXPECT_EQ(db.value().schema_version(), current_schema_version);
  EXPECT_EQ(db.value().integrity_check(), "ok");
  auto fresh = Database::open((dir / "new.db").string(), OpenMode::create_or_open);
  ASSERT_TRUE(fresh);
  auto fresh_db = std::move(fresh).value();
  EXPECT_EQ(master_rows(db.value().connection(), true), master_rows(fresh_db.connection(), true));

  auto& c = db.value().connection();
  Statement u(c, "SELECT session_uuid FROM sessions ORDER BY session_id");
  std::vector<std::string> uuids;
  while (u.step()) uuids.push_back(u.column_text(0));
  ASSERT_EQ(uuids.size(), 2u);
  for (const auto& id : uuids) {
    EXPECT_TRUE(is_session_uuid(id)) << id;
    EXPECT_EQ(id[14], '4') << id;  // random UUIDs for sessions made before version 4
  }
  EXPECT_NE(uuids[0], uuids[1]);
  EXPECT_EQ(c.query_int("SELECT count(*) FROM trials WHERE status = 'skipped' AND end_reason IS NULL"), 1);
  EXPECT_EQ(c.query_int("SELECT count(*) FROM trials t JOIN blocks b USING (block_id) "
                        "WHERE t.session_id = b.session_id"), 3);
  EXPECT_EQ(c.query_int("SELECT late FROM frames"), 0);
  EXPECT_EQ(c.query_int("SELECT count(*) FROM frames WHERE display_period_ns IS NULL"), 1);
  // The unfinished session resumes where it stopped.
  SessionStore store(std::move(db).value());
  auto next = store.next_incomplete_trial(2).value();
  ASSERT_TRUE(next);
  EXPECT_EQ(next->trial_index, 1);
}

TEST(SessionUuid, Rfc9562Version7LayoutAndUniqueness) {
  // RFC 9562 Appendix A.6, the version 7 example.
  EXPECT_EQ(session_uuid_v7(0x017F22E279B0ull, 0xCC3, 0x18C4DC0C0C07398Full),
            "017f22e2-79b0-7cc3-98c4-dc0c0c07398f");
  EXPECT_TRUE(is_session_uuid("017f22e2-79b0-7cc3-98c4-dc0c0c07398f"));
  EXPECT_FALSE(is_session_uuid("017F22E2-79B0-7CC3-98C4-DC0C0C07398F"));  // canonical is lower case
  EXPECT_FALSE(is_session_uuid("017f22e2-79b0-7cc3-c8c4-dc0c0c07398f"));  // variant 110
  EXPECT_FALSE(is_session_uuid("017f22e279b07cc398c4dc0c0c07398f"));
  std::set<std::string> seen;
  for (int i = 0; i < 1000; ++i) {
    const std::string id = new_session_uuid();
    ASSERT_TRUE(is_session_uuid(id)) << id;
    EXPECT_EQ(id[14], '7');
    seen.insert(id);
  }
  EXPECT_EQ(seen.size(), 1000u);
}

TEST(SessionUuid, EachStoredSessionGetsOneAndAGivenOneIsKept) {
  const auto dir = fresh_dir("uuid");
  auto store = make_store(dir / "u.db");
  const auto a = make_session(store, "P01");
  const auto b = make_session(store, "P01");
  auto c = Connection::open((dir / "u.db").string(), OpenFlags::read_only);
  {
    Statement s(c, "SELECT session_uuid FROM sessions WHERE session_id IN (?1, ?2) ORDER BY session_id");
    s.bind(1, a).bind(2, b);
    ASSERT_TRUE(s.step());
    const std::string first = s.column_text(0);
    ASSERT_TRUE(s.step());
    EXPECT_TRUE(is_session_uuid(first));
    EXPECT_NE(first, s.column_text(0));
  }  // ends the read transaction, so the reads below see later commits
  SessionRecord r;
  r.protocol_id = 1;
  r.participant_id = 1;
  r.session_uuid = "017f22e2-79b0-7cc3-98c4-dc0c0c07398f";
  ASSERT_TRUE(store.create_session(r));
  EXPECT_EQ(c.query_int("SELECT count(*) FROM sessions WHERE session_uuid = "
                        "'017f22e2-79b0-7cc3-98c4-dc0c0c07398f'"), 1);
  r.session_number = 9;
  auto again = store.create_session(r);  // the same identity twice is refused
  ASSERT_FALSE(again);
  r.session_uuid = "not-a-uuid";
  EXPECT_FALSE(store.create_session(r));
}

TEST(Schema, NewerFileIsRefusedAndLeftUntouched) {
  const auto dir = fresh_dir("newer");
  const auto path = (dir / "future.db").string();
  {
    auto db = Database::open(path, OpenMode::create_or_open);
    ASSERT_TRUE(db);
    db.value().connection().exec("PRAGMA user_version = " + std::to_string(current_schema_version + 1));
  }
  auto db = Database::open(path, OpenMode::create_or_open);
  ASSERT_FALSE(db);
  EXPECT_EQ(db.error().kind, DataError::Kind::newer_schema);
  EXPECT_NE(db.error().message.find("schema version " + std::to_string(current_schema_version + 1)),
            std::string::npos);
  auto c = Connection::open(path, OpenFlags::read_only);
  EXPECT_EQ(c.query_int("PRAGMA user_version"), current_schema_version + 1);
}

// What version 6 added: the Lab Streaming Layer's tables.
constexpr const char* kDropLslTables =
    "DROP INDEX lsl_samples_by_stream_time; DROP INDEX lsl_clock_by_session_time; DROP TABLE lsl_samples; "
    "DROP TABLE lsl_streams; DROP TABLE lsl_clock;";

// What version 9 added: the partner's poses in a shared game.
constexpr const char* kDropPartnerTable =
    "DROP INDEX partner_samples_by_session_time; DROP TABLE partner_samples; ";

// What version 8 added: the questionnaire blocks' tables (and what came after).
const std::string kDropQuestionnaireTables =
    std::string(kDropPartnerTable) + "DROP TABLE questionnaire_answers; DROP TABLE questionnaire_scores;";

namespace {

// A new file set back to schema `version` by `undo` (SQL removing what the
// later versions added), opened again: it is migrated to the current version,
// with the same tables, indexes and triggers as a new file, the `added`
// tables empty, and the migration past `version` recorded once.
void expect_migrated_from(int version, const std::string& undo, std::initializer_list<const char*> added) {
  const auto dir = fresh_dir("migrate" + std::to_string(version));
  const auto path = (dir / ("v" + std::to_string(version) + ".db")).string();
  {
    auto db = Database::open(path, OpenMode::create_or_open);
    ASSERT_TRUE(db);
    db.value().connection().exec(undo + "DELETE FROM schema_migrations; PRAGMA user_version = " +
                                 std::to_string(version));
  }
  auto db = Database::open(path, OpenMode::open_existing);
  ASSERT_TRUE(db) << db.error().message;
  EXPECT_EQ(db.value().schema_version(), current_schema_version);
  auto fresh = Database::open((dir / "new.db").string(), OpenMode::create_or_open);
  ASSERT_TRUE(fresh);
  EXPECT_EQ(master_rows(db.value().connection(), true), master_rows(fresh.value().connection(), true));
  for (const char* table : added)
    EXPECT_EQ(db.value().connection().query_int(std::string("SELECT count(*) FROM ") + table), 0) << table;
  EXPECT_EQ(db.value().connection().query_int("SELECT count(*) FROM schema_migrations WHERE version = " +
                                              std::to_string(version + 1)),
            1);
}

}  // namespace

// A file of version 4 (before gaze_samples) gets the table, as a new file
// has it, and keeps its sessions.
TEST(Schema, MigratesVersion4FileAddingTheGazeTable) {
  expect_migrated_from(4,
                       std::string(kDropLslTables) + kDropQuestionnaireTables +
                           "DROP TABLE shots; DROP INDEX gaze_samples_by_session_time; DROP TABLE gaze_samples; ",
                       {"gaze_samples"});
}

// A file of version 5 (before the Lab Streaming Layer) gets its tables.
TEST(Schema, MigratesVersion5FileAddingTheLslTables) {
  expect_migrated_from(5, kDropLslTables + kDropQuestionnaireTables + "DROP TABLE shots; ",
                       {"lsl_streams", "lsl_samples", "lsl_clock"});
}

// A file of version 6 (before play blocks) gets the shots table, as a new
// file has it.
TEST(Schema, MigratesVersion6FileAddingTheShotsTable) {
  expect_migrated_from(6, kDropQuestionnaireTables + "DROP TABLE shots; ", {"shots"});
}

// A file of version 7 (before questionnaire blocks) gets their tables, as a
// new file has them, empty.
TEST(Schema, MigratesVersion7FileAddingTheQuestionnaireTables) {
  expect_migrated_from(7, kDropQuestionnaireTables, {"questionnaire_answers", "questionnaire_scores"});
}

// A file of version 8 (before shared games stored the partner's poses) gets
// the partner_samples table, as a new file has it, empty.
TEST(Schema, MigratesVersion8FileAddingThePartnerTable) {
  expect_migrated_from(8, kDropPartnerTable, {"partner_samples"});
}

TEST(Schema, BadPathsGiveClearErrors) {
  const auto dir = fresh_dir("badpath");
  auto missing_dir = Database::open((dir / "nope" / "a.db").string(), OpenMode::create_or_open);
  ASSERT_FALSE(missing_dir);
  EXPECT_NE(missing_dir.error().message.find("does not exist"), std::string::npos);
  auto folder = Database::open(dir.string(), OpenMode::create_or_open);
  ASSERT_FALSE(folder);
  EXPECT_NE(folder.error().message.find("is a folder"), std::string::npos);
  auto missing = Database::open((dir / "absent.db").string(), OpenMode::open_existing);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().message.find("no such file"), std::string::npos);
  std::ofstream((dir / "text.db").string()) << "this is not a database, just some text that is long enough";
  auto garbage = Database::open((dir / "text.db").string(), OpenMode::open_existing);
  ASSERT_FALSE(garbage);
  EXPECT_EQ(garbage.error().kind, DataError::Kind::not_curvlab);  // not SQLite at all (result.hpp)
  {
    auto other = Connection::open((dir / "other.db").string(), OpenFlags::read_write_create);
    other.exec("CREATE TABLE t (x INTEGER)");
  }
  auto other = Database::open((dir / "other.db").string(), OpenMode::open_existing);
  ASSERT_FALSE(other);
  EXPECT_EQ(other.error().kind, DataError::Kind::not_curvlab);
}

TEST(Session, PlanResumeAndIdempotentCompletion) {
  const auto dir = fresh_dir("session");
  auto store = make_store(dir / "s.db");
  const auto session = make_session(store, "P01");
  EXPECT_EQ(store.add_participant({"P01", std::nullopt, DominantEye::unknown}).value(),
            store.add_participant({"P01", std::nullopt, DominantEye::unknown}).value());
  EXPECT_FALSE(store.add_participant({"Jane Doe", std::nullopt, DominantEye::unknown}));
  EXPECT_FALSE(store.add_participant({"P02", 64.0, DominantEye::unknown}));  // millimetres
  const auto ids = store.store_plan(session, two_blocks()).value();
  ASSERT_EQ(ids.size(), 3u);
  EXPECT_FALSE(store.store_plan(session, two_blocks()));

  auto first = store.next_incomplete_trial(session).value();
  ASSERT_TRUE(first);
  EXPECT_EQ(first->trial_id, ids[0]);
  EXPECT_EQ(store.begin_trial(first->trial_id).value(), 1);
  // A crash here: the running trial is offered again, with its attempt count.
  auto again = store.next_incomplete_trial(session).value();
  ASSERT_TRUE(again);
  EXPECT_EQ(again->trial_id, ids[0]);
  EXPECT_EQ(again->attempt, 1);
  EXPECT_EQ(store.begin_trial(first->trial_id).value(), 2);
  // The stimulus as shown (a staircase's value) replaces the planned record.
  TrialResult r{first->trial_id, 1'000, 351'000, "convex", "keyboard",
                StaircaseStep{"s1", 0, 0.02, true, false, 0.015}, "{\"sagitta_m\":0.02}"};
  ASSERT_TRUE(store.complete_trial(r));
  ASSERT_TRUE(store.complete_trial(r));  // retried after an uncertain commit
  EXPECT_FALSE(store.complete_trial({ids[1], 10, 5, "x", "k", std::nullopt, std::nullopt}));  // response before onset
  auto next = store.next_incomplete_trial(session).value();
  ASSERT_TRUE(next);
  EXPECT_EQ(next->trial_id, ids[1]);
  EXPECT_EQ(next->block_index, 1);
  ASSERT_TRUE(store.skip_trial(ids[1]));
  EXPECT_EQ(store.count_trials(session, TrialStatus::completed).value(), 1);
  auto check = Database::open((dir / "s.db").string(), OpenMode::read_only);  // its own connection
  ASSERT_TRUE(check);
  EXPECT_EQ(check->connection().query_int("SELECT rt_ns FROM trials WHERE trial_id = " + std::to_string(ids[0])),
            350'000);
  EXPECT_EQ(check->connection().query_int("SELECT count(*) FROM staircase_steps"), 1);
  EXPECT_EQ(check->connection().query_int("SELECT ROUND(1000 * json_extract(stimulus, '$.sagitta_m')) FROM trials "
                                          "WHERE trial_id = " + std::to_string(ids[0])),
            20);
  // Without one, the plan's record stays.
  EXPECT_EQ(check->connection().query_int("SELECT ROUND(1000 * json_extract(stimulus, '$.sagitta_m')) FROM trials "
                                          "WHERE trial_id = " + std::to_string(ids[1])),
            10);
  ASSERT_TRUE(store.close_session(session, SessionStatus::completed));
  EXPECT_FALSE(store.close_session(session + 100, SessionStatus::completed));
}

TEST(SampleWriter, CommitsEverythingAndCountsDropsWhenFull) {
  const auto dir = fresh_dir("writer");
  const auto path = dir / "w.db";
  std::int64_t session = 0;
  {
    auto store = make_store(path);
    session = make_session(store, "P01");
  }
  {
    auto writer = SampleWriter::open(path.string()).value();
    for (int i = 0; i < 5000; ++i) {
      TrackingSample s;
      s.session_id = session;
      s.t_ns = i;
      s.device = static_cast<TrackedDevice>(i % 3);
      s.has_virtual_pose = true;
      s.virtual_pose[15] = 1.0;
      while (!writer->push_tracking(s)) std::this_thread::yield();
      if (i % 11 == 0) {
        FrameRecord f;
        f.session_id = session;
        f.frame_index = i / 11;
        while (!writer->push_frame(f)) std::this_thread::yield();
      }
    }
    ASSERT_TRUE(writer->flush());
    EXPECT_EQ(writer->stats().committed_tracking, 5000u);
  }
  {
    // The writer sleeps for a minute unless flushed, so a ring of 4 takes 4
    // records and drops the rest, deterministically.
    SampleWriterConfig cfg;
    cfg.tracking_capacity = 4;
    cfg.batch_interval = std::chrono::minutes(1);
    auto writer = SampleWriter::open(path.string(), cfg).value();
    int accepted = 0;
    for (int i = 0; i < 100; ++i) {
      TrackingSample s;
      s.session_id = session;
      s.t_ns = 10'000 + i;
      accepted += writer->push_tracking(s) ? 1 : 0;
    }
    EXPECT_EQ(accepted, 4);
    ASSERT_TRUE(writer->flush());
    const auto st = writer->stats();
    EXPECT_EQ(st.dropped_tracking, 96u);
    EXPECT_EQ(st.committed_tracking, 4u);
  }
  auto db = Database::open(path.string(), OpenMode::open_existing).value();
  EXPECT_EQ(db.connection().query_int("SELECT count(*) FROM tracking_samples"), 5004);
  EXPECT_EQ(db.connection().query_int("SELECT count(*) FROM frames"), 455);
  EXPECT_EQ(db.connection().query_int("SELECT json_extract(detail, '$.dropped_tracking') FROM "
                                      "events WHERE kind = 'logger_drops'"), 96);
  EXPECT_EQ(db.connection().query_int(
                "SELECT count(*) FROM tracking_samples WHERE length(virtual_pose) = 128"), 5000);
}

// Another program's write transaction (DB Browser with unsaved edits) makes
// the writer wait, not fail: what is journalled meanwhile reaches the file
// once the lock is free, with the wait stored; past its patience it fails.
TEST(SampleWriter, WaitsOutAnotherProgramsLockWithinItsPatienceThenFails) {
  const auto dir = fresh_dir("patience");
  const auto path = dir / "p.db";
  std::int64_t session = 0;
  {
    auto store = make_store(path);
    session = make_session(store, "P01");
  }
  for (const auto patience : {std::chrono::milliseconds(60'000), std::chrono::milliseconds(200)}) {
    SampleWriterConfig cfg;
    cfg.lock_patience = patience;
    cfg.retry_interval = std::chrono::milliseconds(50);
    auto writer = SampleWriter::open(path.string(), cfg).value();
    Connection other = Connection::open(path.string(), OpenFlags::read_write);
    sqlite3_busy_timeout(other.get(), 0);
    other.exec("BEGIN IMMEDIATE");
    TrackingSample s;
    s.session_id = session;
    ASSERT_TRUE(writer->push_tracking(s));
    const auto ticket = writer->journal(StatusChange{session, SessionStatus::interrupted, false});
    // The writer's busy timeout is 5 s: hold the lock past one attempt.
    const auto waited = writer->wait_durable(ticket, std::chrono::milliseconds(patience.count() > 1000 ? 7000 : 12000));
    EXPECT_FALSE(waited) << "the lock is still held";
    if (patience.count() > 1000) {
      EXPECT_EQ(waited.error().kind, DataError::Kind::busy);
      EXPECT_NE(waited.error().message.find("timed out"), std::string::npos) << "a wait, not a failure";
      EXPECT_GT(writer->lock_wait_s(), 0.0);
      other.exec("ROLLBACK");
      EXPECT_TRUE(writer->wait_durable(ticket));
      EXPECT_TRUE(writer->flush());
      EXPECT_EQ(writer->lock_wait_s(), 0.0);
    } else {
      EXPECT_NE(waited.error().message.find("paused"), std::string::npos) << "past its patience it fails";
      other.exec("ROLLBACK");
    }
  }
  auto db = Database::open(path.string(), OpenMode::read_only).value();
  EXPECT_EQ(db.connection().query_int("SELECT count(*) FROM events WHERE kind = 'logger_waited' AND "
                                      "json_extract(detail, '$.waited_ms') >= 5000"),
            2);
  EXPECT_EQ(db.connection().query_int("SELECT count(*) FROM tracking_samples"), 2);
}

// Gaze rows: what a headset does not track is NULL, lost tracking is a row
// with valid 0, a diverging vergence has no distance; a full ring drops and
// counts gaze samples as it does tracking samples.
TEST(SampleWriter, StoresGazeWithNullsForWhatIsNotTracked) {
  const auto dir = fresh_dir("writer_gaze");
  const auto path = dir / "g.db";
  std::int64_t session = 0;
  {
    auto store = make_store(path);
    session = make_session(store, "P01");
  }
  {
    SampleWriterConfig cfg;
    cfg.gaze_capacity = 4;
    cfg.batch_interval = std::chrono::minutes(1);
    auto writer = SampleWriter::open(path.string(), cfg).value();
    GazeSample per_eye;
    per_eye.session_id = session;
    per_eye.t_ns = 100;
    per_eye.has_eyes = true;
    per_eye.eyes[0] = {true, 0.5, {-0.032, 1.6, 0.0}, {0.0, 0.0, -1.0}};
    per_eye.eyes[1] = {true, -1.0, {0.032, 1.6, 0.0}, {0.0, 0.0, -1.0}};
    per_eye.has_vergence = true;
    per_eye.vergence_rad = -0.01;
    GazeSample combined;
    combined.session_id = session;
    combined.t_ns = 200;
    combined.has_combined = true;
    combined.combined = {false, -1.0, {0.0, 1.6, 0.0}, {0.0, 0.0, -1.0}};
    EXPECT_TRUE(writer->push_gaze(per_eye));
    EXPECT_TRUE(writer->push_gaze(combined));
    int accepted = 2;
    for (int i = 0; i < 10; ++i) accepted += writer->push_gaze(combined) ? 1 : 0;
    EXPECT_EQ(accepted, 4);
    ASSERT_TRUE(writer->flush());
    EXPECT_EQ(writer->stats().dropped_gaze, 8u);
  }
  auto db = Database::open(path.string(), OpenMode::open_existing).value();
  auto& c = db.connection();
  EXPECT_EQ(c.query_int("SELECT count(*) FROM gaze_samples"), 4);
  EXPECT_EQ(c.query_int("SELECT count(*) FROM gaze_samples WHERE t_ns = 100 AND combined_valid IS NULL AND "
                        "combined_dx IS NULL AND left_valid = 1 AND left_confidence = 0.5 AND right_confidence IS NULL "
                        "AND vergence_rad = -0.01 AND vergence_distance_m IS NULL AND trial_id IS NULL"),
            1);
  EXPECT_EQ(c.query_int("SELECT count(*) FROM gaze_samples WHERE t_ns = 200 AND combined_valid = 0 AND "
                        "combined_oy_m = 1.6 AND left_valid IS NULL AND right_ox_m IS NULL AND vergence_rad IS NULL"),
            3);
  EXPECT_EQ(c.query_int("SELECT json_extract(detail, '$.dropped_gaze') FROM events WHERE kind = 'logger_drops'"), 8);
}

// What resume reads back: provenance with the session_start and observer
// events, the plan in trial_index order, the last frame, staircase outcomes.
TEST(SessionReader, ReadsWhatResumeNeeds) {
  const auto dir = fresh_dir("reader");
  auto store = make_store(dir / "r.db");
  const auto session = make_session(store, "P03");
  const auto ids = store.store_plan(session, two_blocks()).value();
  ASSERT_TRUE(store.record_event({session, std::nullopt, 5, "session_start", "{\"participant_number\":3}"}));
  ASSERT_TRUE(store.record_event({session, std::nullopt, 6, "observer",
                                  "{\"model\":\"physical\",\"bias_m\":0.002,\"seed\":11}"}));
  ASSERT_TRUE(store.record_event({session, ids[0], 9'000, "note", "{}"}));
  ASSERT_TRUE(store.begin_trial(ids[0]));
  ASSERT_TRUE(store.complete_trial({ids[0], 1'000, 2'000, "convex", "keyboard",
                                    StaircaseStep{"s1", 0, 0.02, false, false, 0.025}, std::nullopt}));

  auto db = Database::open((dir / "r.db").string(), OpenMode::read_only).value();
  const auto prov = read_session_provenance(db, session);
  ASSERT_TRUE(prov) << prov.error().message;
  EXPECT_EQ(prov->protocol_text, "name = \"billiards\"\n");
  EXPECT_FALSE(prov->protocol_source_path);
  EXPECT_EQ(prov->pseudonym, "P03");
  EXPECT_EQ(prov->dominant_eye, DominantEye::left);
  EXPECT_EQ(prov->seed, 7);
  EXPECT_EQ(prov->status, SessionStatus::running);
  EXPECT_EQ(prov->backend, Backend::headless);
  EXPECT_EQ(prov->table_calibration_json, "{\"edge_m\":1.2}");
  EXPECT_EQ(prov->participant_number, 3u);
  ASSERT_TRUE(prov->observer);
  EXPECT_EQ(prov->observer->json, "{\"model\":\"physical\",\"bias_m\":0.002,\"seed\":11}");
  EXPECT_EQ(prov->last_t_ns, 9'000);
  const auto missing = read_session_provenance(db, session + 1);
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().kind, DataError::Kind::not_found);

  const auto trials = store.trial_list(session).value();
  ASSERT_EQ(trials.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(trials[i].trial_id, ids[i]);
    EXPECT_EQ(trials[i].trial_index, static_cast<std::int64_t>(i));
  }
  EXPECT_EQ(trials[0].conditions_json, "{\"space\":\"E3\",\"mode\":\"tourist\"}");
  EXPECT_EQ(store.last_frame_index(session).value(), -1);
  const auto steps = store.staircase_responses(session).value();
  ASSERT_EQ(steps.size(), 1u);
  EXPECT_EQ(steps[0].trial_id, ids[0]);
  EXPECT_EQ(steps[0].response_correct, false);
  EXPECT_EQ(read_staircase_intensity(db, ids[0]).value(), 0.02);
  EXPECT_FALSE(read_staircase_intensity(db, ids[1]).value());
}

namespace {

ViewGeometry test_views(double fov_left_rad) {
  ViewGeometry g;
  g.width_px = 320;
  g.height_px = 300;
  g.eyes[0].position_m = {-0.032, 0.001, 0.0};
  g.eyes[1].position_m = {0.032, 0.001, 0.0};
  g.eyes[0].fov_rad = {fov_left_rad, 0.72, 0.80, -0.88};
  g.eyes[1].fov_rad = {-0.72, 0.87, 0.80, -0.88};
  g.eyes[1].rotation = {0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0};
  return g;
}

}  // namespace

// Replay's reads: the onset, the head pose of a frame (its blob's size
// checked), the adjustment in force, and the eye geometry — stored by the
// writer only when it changes, read back as in force at any frame.
TEST(SessionReader, ReadsWhatReplayNeeds) {
  const auto dir = fresh_dir("replay_reads");
  const auto path = dir / "r.db";
  std::int64_t session = 0;
  std::vector<std::int64_t> ids;
  {
    auto store = make_store(path);
    session = make_session(store, "P04");
    ids = store.store_plan(session, two_blocks()).value();
    std::string pose = "[";
    for (int i = 0; i < 16; ++i) pose += std::string(i ? "," : "") + (i % 5 == 0 ? "1" : "0");
    pose += "]";
    ASSERT_TRUE(store.record_event({session, ids[1], 10, "onset",
                                    "{\"frame_index\":3,\"predicted_display_ns\":40,\"attempt\":1,\"head_pose\":" +
                                        pose + ",\"stick_pose\":" + pose + "}"}));
    ASSERT_TRUE(store.record_event({session, ids[1], 11, "adjustment", "{\"value\":0.01,\"frame_index\":5}"}));
    ASSERT_TRUE(store.record_event({session, ids[1], 12, "trial_aborted", "{\"reason\":\"pause\"}"}));
    ASSERT_TRUE(store.record_event({session, ids[1], 20, "onset",
                                    "{\"frame_index\":7,\"predicted_display_ns\":80,\"attempt\":2,\"head_pose\":" +
                                        pose + ",\"stick_pose\":" + pose + "}"}));
    ASSERT_TRUE(store.record_event({session, ids[1], 21, "adjustment", "{\"value\":0.02,\"frame_index\":8}"}));
    ASSERT_TRUE(store.record_event({session, ids[1], 22, "adjustment", "{\"value\":0.03,\"frame_index\":9}"}));
    ASSERT_TRUE(store.record_event({session, ids[2], 30, "onset", "{\"frame_index\":9,\"head_pose\":[1,2]}"}));
  }
  {
    auto writer = SampleWriter::open(path.string()).value();
    for (int i = 0; i < 12; ++i) {
      FrameRecord f;
      f.session_id = session;
      f.trial_id = ids[1];
      f.frame_index = i;
      f.has_view_geometry = i != 0;  // frame 0 knows none
      f.view_geometry = test_views(i < 6 ? -0.87 : -0.90);
      while (!writer->push_frame(f)) std::this_thread::yield();
      TrackingSample s;
      s.session_id = session;
      s.trial_id = ids[1];
      s.frame_index = i;
      s.t_ns = 100 + i;
      s.has_virtual_pose = true;
      s.virtual_pose[0] = i;
      while (!writer->push_tracking(s)) std::this_thread::yield();
    }
    ASSERT_TRUE(writer->flush());
  }
  auto db = Database::open(path.string(), OpenMode::read_only).value();
  // Stored twice: frame 1 (the first that knew it) and frame 6 (the change).
  EXPECT_EQ(db.connection().query_int("SELECT count(*) FROM frames WHERE eye_views IS NOT NULL"), 2);
  {
    Statement stored(db.connection(), "SELECT group_concat(frame_index) FROM frames WHERE eye_views IS NOT NULL");
    ASSERT_TRUE(stored.step());
    EXPECT_EQ(stored.column_text(0), "1,6");
  }
  EXPECT_FALSE(read_view_geometry(db, session, 0).value());
  EXPECT_EQ(read_view_geometry(db, session, 1).value(), test_views(-0.87));
  EXPECT_EQ(read_view_geometry(db, session, 5).value(), test_views(-0.87));
  EXPECT_EQ(read_view_geometry(db, session, 6).value(), test_views(-0.90));
  EXPECT_EQ(read_view_geometry(db, session, 11).value(), test_views(-0.90));

  EXPECT_EQ(read_trial_id(db, session, 1).value(), ids[1]);
  EXPECT_EQ(read_trial_id(db, session, 9).error().kind, DataError::Kind::not_found);
  const auto onset = read_onset(db, ids[1]).value();
  ASSERT_TRUE(onset);  // the last attempt's
  EXPECT_EQ(onset->frame_index, 7);
  EXPECT_EQ(onset->attempt, 2);
  EXPECT_EQ(onset->predicted_display_ns, 80);
  EXPECT_EQ(onset->head_pose[5], 1.0);
  EXPECT_FALSE(read_onset(db, ids[0]).value());
  EXPECT_EQ(read_onset(db, ids[2]).error().kind, DataError::Kind::corrupt);
  // Only this attempt's changes count, each from its frame on.
  EXPECT_FALSE(read_adjustment_at(db, ids[1], onset->event_id, 7).value());
  EXPECT_EQ(read_adjustment_at(db, ids[1], onset->event_id, 8).value(), 0.02);
  EXPECT_EQ(read_adjustment_at(db, ids[1], onset->event_id, 20).value(), 0.03);

  const auto head = read_head_at_frame(db, session, 4).value();
  ASSERT_TRUE(head);
  EXPECT_EQ(head->virtual_pose[0], 4.0);
  EXPECT_EQ(head->t_ns, 104);
  EXPECT_EQ(head->trial_id, ids[1]);
  EXPECT_FALSE(read_head_at_frame(db, session, 40).value());
  const auto span = read_trial_frame_span(db, ids[1]).value();
  ASSERT_TRUE(span);
  EXPECT_EQ(span->first, 0);
  EXPECT_EQ(span->last, 11);
  EXPECT_EQ(read_last_frame_index(db, session).value(), 11);
}

// A pose or eye-geometry blob of the wrong size is a clear error, not a
// read past its end. (The schema's CHECK keeps curvlab from writing one; a
// file edited by other tools may still hold one, so CHECKs are bypassed
// here the way such a tool could, with ignore_check_constraints.)
TEST(SessionReader, WrongSizedBlobsAreReportedAsCorrupt) {
  const auto dir = fresh_dir("blobs");
  const auto path = dir / "b.db";
  std::int64_t session = 0;
  {
    auto store = make_store(path);
    session = make_session(store, "P05");
  }
  {
    auto c = Connection::open(path.string(), OpenFlags::read_write);
    c.exec("PRAGMA ignore_check_constraints = ON");
    c.exec("INSERT INTO tracking_samples (session_id, frame_index, device, t_ns, lab_px_m, lab_py_m, lab_pz_m, "
           "lab_qx, lab_qy, lab_qz, lab_qw, position_valid, orientation_valid, virtual_pose) VALUES (" +
           std::to_string(session) + ", 2, 'head', 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, zeroblob(40))");
    c.exec("INSERT INTO frames (session_id, frame_index, t_ns, cpu_time_ns, views, passes, draws, triangles, "
           "eye_width_px, eye_height_px, eye_views) VALUES (" +
           std::to_string(session) + ", 2, 0, 0, 2, 2, 1, 1, 64, 64, zeroblob(100))");
  }
  auto db = Database::open(path.string(), OpenMode::read_only).value();
  const auto head = read_head_at_frame(db, session, 2);
  ASSERT_FALSE(head);
  EXPECT_EQ(head.error().kind, DataError::Kind::corrupt);
  EXPECT_NE(head.error().message.find("40 bytes, not 128"), std::string::npos) << head.error().message;
  const auto views = read_view_geometry(db, session, 3);
  ASSERT_FALSE(views);
  EXPECT_EQ(views.error().kind, DataError::Kind::corrupt);
  EXPECT_NE(views.error().message.find("100 bytes, not 256"), std::string::npos) << views.error().message;
}

TEST(Crash, KillNineNeverLosesACommittedTrial) {
  const auto dir = fresh_dir("crash");
  const auto path = (dir / "crash.db").string();
  std::mt19937 rng(12345);
  std::uniform_int_distribution<int> delay_us(20'000, 250'000);
  std::int64_t total_checked = 0;
  for (int run = 0; run < 25; ++run) {
    int pipe_fd[2];
    ASSERT_EQ(::pipe(pipe_fd), 0);
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      ::dup2(pipe_fd[1], STDOUT_FILENO);
      ::close(pipe_fd[0]);
      ::close(pipe_fd[1]);
      ::execl(CURVLAB_CRASH_WRITER, CURVLAB_CRASH_WRITER, path.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(pipe_fd[1]);
    std::this_thread::sleep_for(std::chrono::microseconds(delay_us(rng)));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    std::string out;
    char buf[4096];
    ssize_t n = 0;
    while ((n = ::read(pipe_fd[0], buf, sizeof buf)) > 0) out.append(buf, static_cast<std::size_t>(n));
    ::close(pipe_fd[0]);
    std::int64_t last = -1;
    std::istringstream lines(out);
    std::string word;
    std::int64_t index = 0;
    while (lines >> word >> index) last = index;

    auto db = Database::open(path, OpenMode::open_existing);
    ASSERT_TRUE(db) << "run " << run << ": " << db.error().message;
    ASSERT_EQ(db.value().integrity_check(), "ok") << "run " << run;
    const auto session = db.value().connection().query_int("SELECT max(session_id) FROM sessions");
    if (last >= 0) {
      const auto completed = db.value().connection().query_int(
          "SELECT count(*) FROM trials WHERE session_id = " + std::to_string(session) +
          " AND status = 'completed' AND trial_index <= " + std::to_string(last));
      EXPECT_EQ(completed, last + 1) << "run " << run << " lost a committed trial";
      total_checked += last + 1;
    }
  }
  EXPECT_GT(total_checked, 0) << "the helper never got to commit a trial";
}

namespace {
int run_cli(const std::string& args, std::string* err) {
  const std::string cmd = std::string(CURVLAB_BIN) + " " + args + " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  char buf[512];
  while (std::fgets(buf, sizeof buf, p)) *err += buf;
  const int status = ::pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void fill_export_db(const fs::path& path) {
  auto store = make_store(path);
  const auto session = make_session(store, "P-01");
  const auto ids = store.store_plan(session, two_blocks()).value();
  ASSERT_TRUE(store.begin_trial(ids[0]));
  ASSERT_TRUE(store.complete_trial({ids[0], 100, 450'000'100, "convex", "keyboard", std::nullopt, std::nullopt}));
  auto writer = SampleWriter::open(path.string()).value();
  for (int i = 0; i < 1000; ++i) {
    for (int d = 0; d < 2; ++d) {
      TrackingSample s;
      s.session_id = session;
      s.t_ns = 5'000'000 + i * 1'000'000 + d;
      s.device = static_cast<TrackedDevice>(d);
      s.position_valid = s.orientation_valid = true;
      s.lab_position_m = {0.1 * d, 1.6, -0.001 * i};
      s.has_state = d == 0;
      ASSERT_TRUE(writer->push_tracking(s));
    }
  }
  ASSERT_TRUE(writer->flush());
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, sep)) out.push_back(cell);
  return out;
}
}  // namespace

TEST(Export, FilesCarryWhatTheirStandardsRequire) {
  const auto dir = fresh_dir("export");
  fill_export_db(dir / "e.db");
  auto db = Database::open((dir / "e.db").string(), OpenMode::open_existing).value();
  const ExportOptions opt{(dir / "out").string(), std::nullopt};

  const auto csv = export_trials_csv(db, opt);
  ASSERT_TRUE(csv) << csv.error().message;
  std::istringstream csv_in(read_file(dir / "out" / "trials.csv"));
  std::string header, row1;
  std::getline(csv_in, header);
  std::getline(csv_in, row1);
  EXPECT_EQ(header.rfind("session_id,session_uuid,participant,session_number,protocol_sha256,block_index", 0), 0u);
  EXPECT_NE(header.find(",cond_space,cond_mode,cond_eyes,stim_sagitta_m,stim_note"), std::string::npos);
  EXPECT_NE(row1.find(",450000000,convex,keyboard,"), std::string::npos) << row1;
  EXPECT_NE(row1.find(",E3,tourist,NA,0.0,NA"), std::string::npos) << row1;
  EXPECT_NE(read_file(dir / "out" / "trials.csv").find("\"a, \"\"quoted\"\" value\""), std::string::npos);

  const auto pds = export_psychds(db, opt);
  ASSERT_TRUE(pds) << pds.error().message;
  const auto desc = nlohmann::json::parse(read_file(dir / "out" / "psychds" / "dataset_description.json"));
  EXPECT_EQ(desc["@context"], "https://schema.org/");
  EXPECT_EQ(desc["@type"], "Dataset");
  EXPECT_TRUE(desc["name"].is_string());
  EXPECT_TRUE(desc["description"].is_string());
  std::set<std::string> described;
  for (const auto& v : desc["variableMeasured"]) {
    EXPECT_EQ(v["@type"], "PropertyValue");
    EXPECT_FALSE(v["description"].get<std::string>().empty());
    described.insert(v["name"].get<std::string>());
  }
  const fs::path data_file = dir / "out" / "psychds" / "data" / "study-billiards_subject-P01_session-1_data.csv";
  ASSERT_TRUE(fs::exists(data_file));
  std::istringstream pin(read_file(data_file));
  std::string pheader;
  std::getline(pin, pheader);
  if (!pheader.empty() && pheader.back() == '\r') pheader.pop_back();
  for (const auto& col : split(pheader, ',')) EXPECT_TRUE(described.count(col)) << col;
  EXPECT_TRUE(std::regex_match(data_file.filename().string(),
                               std::regex("([a-z]+-[A-Za-z0-9]+_)+data\\.csv")));

  const auto bids = export_bids_motion(db, opt);
  ASSERT_TRUE(bids) << bids.error().message;
  const fs::path motion = dir / "out" / "bids" / "sub-P01" / "ses-1" / "motion";
  const std::string base = "sub-P01_ses-1_task-billiards_tracksys-head";
  const auto channels = read_file(motion / (base + "_channels.tsv"));
  std::istringstream ch_in(channels);
  std::string ch_header, line;
  std::getline(ch_in, ch_header);
  const auto ch_cols = split(ch_header, '\t');
  for (const char* required : {"name", "component", "type", "tracked_point", "units"})
    EXPECT_NE(std::find(ch_cols.begin(), ch_cols.end(), required), ch_cols.end()) << required;
  std::size_t channel_rows = 0;
  while (std::getline(ch_in, line)) ++channel_rows;
  std::istringstream m_in(read_file(motion / (base + "_motion.tsv")));
  std::size_t motion_rows = 0;
  while (std::getline(m_in, line)) {
    if (motion_rows == 0) {
      EXPECT_EQ(line.rfind("0.000000000\t", 0), 0u) << "no header row allowed";
    }
    EXPECT_EQ(split(line, '\t').size(), channel_rows);
    ++motion_rows;
  }
  EXPECT_EQ(motion_rows, 1000u);
  const auto sidecar = nlohmann::json::parse(read_file(motion / (base + "_motion.json")));
  EXPECT_EQ(sidecar["TaskName"], "billiards");
  EXPECT_DOUBLE_EQ(sidecar["SamplingFrequency"].get<double>(), 1000.0);
  EXPECT_NEAR(sidecar["SamplingFrequencyEffective"].get<double>(), 1000.0, 1e-6);
  EXPECT_EQ(sidecar["MotionChannelCount"].get<std::size_t>(), channel_rows);
  EXPECT_TRUE(sidecar.contains("TrackingSystemName"));
  EXPECT_TRUE(fs::exists(motion / (base + "_channels.json")));
  EXPECT_TRUE(fs::exists(motion / "sub-P01_ses-1_task-billiards_tracksys-lefthand_motion.tsv"));
  const auto ds = nlohmann::json::parse(read_file(dir / "out" / "bids" / "dataset_description.json"));
  EXPECT_TRUE(ds.contains("Name"));
  EXPECT_TRUE(ds.contains("BIDSVersion"));
  EXPECT_TRUE(fs::exists(dir / "out" / "bids" / "participants.tsv"));
  EXPECT_TRUE(fs::exists(dir / "out" / "bids" / "sub-P01" / "ses-1" / "sub-P01_ses-1_scans.tsv"));
  const auto sessions = read_file(dir / "out" / "bids" / "sub-P01" / "sub-P01_sessions.tsv");
  EXPECT_TRUE(std::regex_search(sessions, std::regex("^session_id\tacq_time\tsession_uuid\nses-1\t[0-9T:.-]+\t"
                                                     "[0-9a-f]{8}-[0-9a-f]{4}-7[0-9a-f]{3}-")))
      << sessions;
}

TEST(Cli, ExportCommandAndItsErrors) {
  const auto dir = fresh_dir("cli");
  fill_export_db(dir / "c.db");
  std::string out;
  EXPECT_EQ(run_cli("export --db " + (dir / "c.db").string() + " --out " + (dir / "o").string(), &out), 0) << out;
  EXPECT_TRUE(fs::exists(dir / "o" / "trials.csv"));
  EXPECT_TRUE(fs::exists(dir / "o" / "psychds" / "dataset_description.json"));
  out.clear();
  EXPECT_EQ(run_cli("export --db " + (dir / "missing.db").string() + " --out " + (dir / "o").string(), &out), 2);
  EXPECT_NE(out.find("missing.db: no such file"), std::string::npos) << out;
  out.clear();
  EXPECT_EQ(run_cli("export --db " + (dir / "c.db").string() + " --out " + (dir / "o").string() +
                        " --session 42", &out), 2);
  EXPECT_NE(out.find("no session with id 42"), std::string::npos) << out;
  out.clear();
  std::ofstream((dir / "blocker").string()) << "x";
  EXPECT_EQ(run_cli("export --db " + (dir / "c.db").string() + " --out " + (dir / "blocker" / "x").string(), &out), 1);
  EXPECT_NE(out.find("cannot create output folder"), std::string::npos) << out;
}

// The stored event kinds are what analyses select on (codebook.md): the
// typed events must keep their names, and every name reads back.
TEST(Events, KindsKeepTheirStoredNamesAndReadBack) {
  const auto kind_of = [](const Event& e) { return event_record(1, std::nullopt, 0, e).kind; };
  EXPECT_EQ(kind_of(events::Page{EventKind::instructions, 0, "a"}), "instructions");
  EXPECT_EQ(kind_of(events::Page{EventKind::break_page, 0, "a"}), "break");
  EXPECT_EQ(kind_of(events::Page{EventKind::done, 0, "a"}), "done");
  EXPECT_EQ(kind_of(events::OperatorActionEvent{"note", "window", 5, std::string("x")}), "operator_note");
  EXPECT_EQ(kind_of(events::OperatorActionEvent{"pause", "window", 5, std::nullopt}), "operator_action");
  EXPECT_EQ(kind_of(events::SessionEnd{SessionStatus::interrupted}), "session_end");
  EXPECT_EQ(event_record(1, std::nullopt, 0, events::SessionEnd{SessionStatus::interrupted}).detail_json,
            R"({"status":"interrupted"})");
  for (int k = 0; k <= static_cast<int>(EventKind::partner_back); ++k) {
    const auto kind = static_cast<EventKind>(k);
    EXPECT_EQ(parse_event_kind(to_string(kind)), kind) << to_string(kind);
  }
  events::Onset onset;
  onset.frame_index = 41;
  onset.head_pose[15] = 1.0;
  onset.stick_pose[0] = 2.0;
  const auto back = parse_onset(event_record(1, 2, 3, onset).detail_json);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->frame_index, 41);
  EXPECT_EQ(back->head_pose[15], 1.0);
  EXPECT_EQ(back->stick_pose[0], 2.0);
  EXPECT_FALSE(parse_session_start(R"({"participant_number":"one"})"));
}
