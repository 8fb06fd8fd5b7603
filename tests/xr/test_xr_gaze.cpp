// Eye tracking through the scripted runtime (CURVLAB_TEST_XR_GAZE,
// tests/xr/runtime/eyes.hpp): whole `curvlab run --backend xr` sessions with
// per-eye gaze (XR_FB_eye_tracking_social), with combined gaze only
// (XR_EXT_eye_gaze_interaction) and without eye tracking; what the database
// stores, what the exports write and what the BIDS validator says of it.
#include "../cli/run_cli.hpp"
#include "runtime_env.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <unistd.h>
#include <utility>
#include <vector>

namespace {

using curvlab::testing::run_cli;
using curvlab::testing::run_shell;
using curvlab::testing::RuntimeEnv;
namespace fs = std::filesystem;

const std::string kProtocol = std::string(CURVLAB_SOURCE_DIR) + "/tests/xr/demo_buttons.toml";
constexpr double kPi = std::numbers::pi;
// The scripted headset's eyes are 64 mm apart (runtime/script.hpp, kIpdM).
constexpr double kIpdM = 0.064;
// Poses cross the OpenXR interface as floats: directions and positions hold
// about 7 significant digits, so angles agree to 1e-5 rad and origins to
// 1e-6 m; the tolerances leave a factor of ten.
constexpr double kAngleTolRad = 1e-4;
// How trials.csv writes an empty cell.
const std::string kMissing = "NA";

fs::path fresh_dir(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("curvlab_xr_gaze_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

using Rows = std::vector<std::vector<std::string>>;

Rows query(const fs::path& db_path, const std::string& sql) {
  Rows rows;
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(db);
    return rows;
  }
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt, nullptr) == SQLITE_OK) {
    while (sqlite3_step(stmt) == SQLITE_ROW) {
      std::vector<std::string> row;
      for (int c = 0; c < sqlite3_column_count(stmt); ++c) {
        const auto* text = sqlite3_column_text(stmt, c);
        row.emplace_back(text == nullptr ? "NULL" : reinterpret_cast<const char*>(text));
      }
      rows.push_back(std::move(row));
    }
  } else {
    ADD_FAILURE() << sqlite3_errmsg(db) << ": " << sql;
  }
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  return rows;
}

// trials.csv as name → column of cells (the demo's cells hold no quoted commas).
std::map<std::string, std::vector<std::string>> read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::vector<std::string> names;
  std::map<std::string, std::vector<std::string>> cols;
  auto split = [](const std::string& l) {
    std::vector<std::string> out;
    std::string cell;
    bool quoted = false;
    for (char c : l) {
      if (c == '"') quoted = !quoted;
      else if (c == ',' && !quoted) {
        out.push_back(cell);
        cell.clear();
      } else {
        cell += c;
      }
    }
    out.push_back(cell);
    return out;
  };
  if (std::getline(in, line)) names = split(line);
  while (std::getline(in, line)) {
    const auto cells = split(line);
    for (std::size_t i = 0; i < names.size() && i < cells.size(); ++i) cols[names[i]].push_back(cells[i]);
  }
  return cols;
}

// A session's folder, removed when the test is done, passed or failed.
struct Session {
  fs::path dir, db, out;
  Session(fs::path d, fs::path b, fs::path o) : dir(std::move(d)), db(std::move(b)), out(std::move(o)) {}
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  Session(Session&& o) noexcept : dir(std::exchange(o.dir, {})), db(std::move(o.db)), out(std::move(o.out)) {}
  ~Session() {
    std::error_code ec;
    if (!dir.empty()) fs::remove_all(dir, ec);
  }
};

// One XR session of the demo answered with the controllers
// (tests/xr/runtime_env.hpp), then exported in every format.
Session run_session(const std::string& name, std::map<std::string, std::string> vars) {
  Session s{fresh_dir(name), {}, {}};
  s.db = s.dir / "xr.db";
  s.out = s.dir / "export";
  vars["CURVLAB_TEST_XR_PRESS"] = curvlab::testing::kScriptedPresses;
  RuntimeEnv env(vars);
  const auto r = run_cli("run " + kProtocol + " --participant G01 --backend xr --db " + s.db.string());
  EXPECT_EQ(r.exit_code, 0) << r.out;
  for (const char* format : {"csv", "bids-motion", "psychds"}) {
    const auto e = run_cli("export --db " + s.db.string() + " --format " + format + " --out " + s.out.string());
    EXPECT_EQ(e.exit_code, 0) << e.out;
  }
  return s;
}

double num(const std::string& cell) { return std::stod(cell); }

// Per trial (in trial_index order), the frames shown during its stimulus:
// those of the trial whose predicted display time lies within the 300 ms
// from its onset (tests/xr/demo_buttons.toml). At 90 Hz that is 27 or 28;
// fewer where the loop missed refreshes on a busy machine.
std::vector<std::string> stimulus_frames(const fs::path& db) {
  std::vector<std::string> out;
  for (const auto& r : query(db, "SELECT (SELECT count(*) FROM frames f WHERE f.trial_id = t.trial_id AND "
                                 "f.predicted_display_ns >= t.onset_ns AND f.predicted_display_ns < t.onset_ns + "
                                 "300000000) FROM trials t ORDER BY t.trial_index"))
    out.push_back(r[0]);
  return out;
}

// The official BIDS validator (as tests/standards/bids_validator.sh runs it):
// the number of errors it reports, or -1 when it gave no answer.
int bids_errors(const fs::path& dataset, const fs::path& scratch) {
  const std::string validator = std::string(CURVLAB_SOURCE_DIR) + "/tools/node_modules/.bin/bids-validator";
  if (!fs::exists(validator)) return -1;
  const auto json = scratch / "bids_result.json";
  (void)run_shell("HOME=" + scratch.string() + " " + validator + " " + dataset.string() + " --json > " +
                  json.string() + " 2>/dev/null");
  const auto r = run_shell("/usr/bin/python3 -c \"import json,sys; d=json.load(open(sys.argv[1]))['issues']; "
                           "print(len(d['errors'])); [print(i['key'], i['reason'][:200]) for i in d['errors']]\" " +
                           json.string());
  if (r.exit_code != 0) return -1;
  if (std::stoi(r.out) != 0) ADD_FAILURE() << "bids-validator: " << r.out;
  return std::stoi(r.out);
}

TEST(XrGaze, PerEyeGazeIsStoredWithItsVergenceAndExported) {
  // The eyes hold 1.5° of convergence about the head's forward direction,
  // confidence 0.9 (left) and 0.7 (right); the combined gaze is offered too.
  const double vergence_rad = 1.5 * kPi / 180.0;
  const auto s = run_session("per_eye", {{"CURVLAB_TEST_XR_GAZE", "both:vergence=1.5:0.9,0.7"}});

  const auto rows = query(s.db,
                          "SELECT left_valid, right_valid, left_confidence, right_confidence, left_ox_m, left_oy_m, "
                          "left_oz_m, right_ox_m, right_oy_m, right_oz_m, left_dx, left_dy, left_dz, right_dx, right_dy, "
                          "right_dz, vergence_rad, vergence_distance_m, combined_valid FROM gaze_samples "
                          "WHERE left_valid = 1 AND right_valid = 1");
  ASSERT_GT(rows.size(), 100u);
  // One gaze row per frame, at the frame's predicted display time.
  EXPECT_EQ(query(s.db, "SELECT count(*) FROM gaze_samples g LEFT JOIN frames f ON f.session_id = g.session_id AND "
                        "f.frame_index = g.frame_index AND f.predicted_display_ns = g.t_ns WHERE f.frame_id IS NULL")[0][0],
            "0");
  // Independently of curvlab's vergence: the angle between the two stored
  // directions (the scripted eyes turn about the head's up axis only), and
  // where symmetric lines with that angle meet, 32 mm either side.
  const double expected_distance_m = kIpdM / 2.0 / std::tan(vergence_rad / 2.0);
  for (const auto& r : rows) {
    EXPECT_NEAR(num(r[2]), 0.9, 1e-6);
    EXPECT_NEAR(num(r[3]), 0.7, 1e-6);
    const double ox = num(r[7]) - num(r[4]), oy = num(r[8]) - num(r[5]), oz = num(r[9]) - num(r[6]);
    EXPECT_NEAR(std::sqrt(ox * ox + oy * oy + oz * oz), kIpdM, 1e-5);
    const double dot = num(r[10]) * num(r[13]) + num(r[11]) * num(r[14]) + num(r[12]) * num(r[15]);
    EXPECT_NEAR(std::acos(std::clamp(dot, -1.0, 1.0)), vergence_rad, kAngleTolRad);
    // Converging: the left eye looks further right (along the eyes' axis)
    // than the right eye does.
    EXPECT_GT((num(r[10]) - num(r[13])) * ox + (num(r[11]) - num(r[14])) * oy + (num(r[12]) - num(r[15])) * oz, 0.0);
    EXPECT_NEAR(num(r[16]), vergence_rad, kAngleTolRad);
    EXPECT_NEAR(num(r[17]), expected_distance_m, 0.01);
    EXPECT_EQ(r[18], "1");
  }

  // The trial CSV: per trial the mean vergence during the stimulus (90
  // arcmin), a sample for each frame of its 300 ms, all valid, and
  // beside it the perception model's vergence demand, stored with the onset
  // where the eyes are tracked (a stick about 1 m ahead: converging, less
  // than a point 0.3 m away demands).
  const auto csv = read_csv(s.out / "trials.csv");
  ASSERT_EQ(csv.at("status").size(), 8u);
  const auto frames = stimulus_frames(s.db);
  ASSERT_EQ(frames.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i) {
    SCOPED_TRACE("trial " + std::to_string(i));
    ASSERT_EQ(csv.at("status")[i], "completed");
    EXPECT_NEAR(num(csv.at("gaze_vergence_arcmin")[i]), 90.0, kAngleTolRad * 10800.0 / kPi);
    EXPECT_GT(num(frames[i]), 0.0);
    EXPECT_EQ(csv.at("gaze_samples")[i], frames[i]);
    EXPECT_EQ(csv.at("gaze_valid_samples")[i], frames[i]);
    ASSERT_NE(csv.at("vergence_demand_arcmin")[i], kMissing);
    EXPECT_GT(num(csv.at("vergence_demand_arcmin")[i]), 0.0);
    EXPECT_LT(num(csv.at("vergence_demand_arcmin")[i]), 2.0 * std::atan(0.032 / 0.3) * 10800.0 / kPi);
  }
  // Psych-DS carries the same columns.
  bool psychds_has_it = false;
  for (const auto& e : fs::recursive_directory_iterator(s.out / "psychds"))
    if (e.path().extension() == ".csv")
      psychds_has_it = psychds_has_it || read_csv(e.path()).count("gaze_vergence_arcmin") == 1;
  EXPECT_TRUE(psychds_has_it);

  // BIDS: one eye-tracking physio recording per eye, accepted by the validator.
  const auto beh = s.out / "bids" / "sub-G01" / "ses-1" / "beh";
  for (const char* eye : {"eye1", "eye2"}) {
    const auto stem = beh / ("sub-G01_ses-1_task-demo_recording-" + std::string(eye) + "_physio");
    EXPECT_TRUE(fs::exists(stem.string() + ".tsv.gz")) << stem;
    std::ifstream sidecar(stem.string() + ".json");
    std::stringstream text;
    text << sidecar.rdbuf();
    EXPECT_NE(text.str().find("\"PhysioType\": \"eyetrack\""), std::string::npos) << text.str();
    EXPECT_NE(text.str().find(std::string("\"RecordedEye\": \"") + (eye[3] == '1' ? "left" : "right")),
              std::string::npos);
  }
  EXPECT_EQ(bids_errors(s.out / "bids", s.dir), 0);

  // The report plots measured against predicted vergence, per condition.
  if (!fs::exists("/usr/bin/Rscript")) {
    GTEST_SKIP() << "Rscript not installed (apt-get install r-base-core): the report's figure is not checked";
  }
  const auto report = s.dir / "report";
  const auto r = run_shell("/usr/bin/Rscript " + std::string(CURVLAB_SOURCE_DIR) + "/analysis/report.R --db " +
                           s.db.string() + " --out " + report.string() + " --quiet 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  ASSERT_TRUE(fs::exists(report / "vergence.png")) << r.out;
  const auto png = run_shell("MPLBACKEND=Agg /usr/bin/python3 " + std::string(CURVLAB_SOURCE_DIR) +
                             "/tests/analysis/check_png.py " + (report / "vergence.png").string() + " 2>&1");
  EXPECT_EQ(png.exit_code, 0) << png.out;
  std::ifstream table(report / "vergence.csv");
  std::string header, line;
  std::getline(table, header);
  EXPECT_NE(header.find("gaze_vergence_arcmin"), std::string::npos) << header;
  int conditions = 0;
  while (std::getline(table, line)) ++conditions;
  EXPECT_EQ(conditions, 4);  // E3 and H3, tourist and native
}

TEST(XrGaze, CombinedGazeStoresTheRay) {
  // Only the combined gaze, on a point of the table top.
  const double px = 0.1, py = 0.75, pz = -0.2;
  const auto s = run_session("combined", {{"CURVLAB_TEST_XR_GAZE", "combined:fixate=0.1,0.75,-0.2"}});
  const auto rows = query(s.db,
                          "SELECT combined_ox_m, combined_oy_m, combined_oz_m, combined_dx, combined_dy, combined_dz, "
                          "left_valid, right_valid, vergence_rad FROM gaze_samples WHERE combined_valid = 1");
  ASSERT_GT(rows.size(), 100u);
  for (const auto& r : rows) {
    // The ray passes through the fixated point: its distance from the line.
    const double vx = px - num(r[0]), vy = py - num(r[1]), vz = pz - num(r[2]);
    const double dx = num(r[3]), dy = num(r[4]), dz = num(r[5]);
    const double along = vx * dx + vy * dy + vz * dz;
    EXPECT_GT(along, 0.0);
    const double off = std::sqrt(std::max(0.0, vx * vx + vy * vy + vz * vz - along * along));
    EXPECT_LT(off, 1e-4);
    EXPECT_EQ(r[6], "NULL");
    EXPECT_EQ(r[7], "NULL");
    EXPECT_EQ(r[8], "NULL");
  }
  const auto csv = read_csv(s.out / "trials.csv");
  ASSERT_EQ(csv.at("gaze_vergence_arcmin").size(), 8u);
  const auto frames = stimulus_frames(s.db);
  ASSERT_EQ(frames.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(csv.at("gaze_vergence_arcmin")[i], kMissing);
    EXPECT_GT(num(frames[i]), 0.0);
    EXPECT_EQ(csv.at("gaze_valid_samples")[i], frames[i]);
  }
  const auto eye1 = s.out / "bids" / "sub-G01" / "ses-1" / "beh" / "sub-G01_ses-1_task-demo_recording-eye1_physio.json";
  std::ifstream sidecar(eye1);
  std::stringstream text;
  text << sidecar.rdbuf();
  EXPECT_NE(text.str().find("\"RecordedEye\": \"cyclopean\""), std::string::npos) << eye1;
  EXPECT_FALSE(fs::exists(s.out / "bids" / "sub-G01" / "ses-1" / "beh" /
                          "sub-G01_ses-1_task-demo_recording-eye2_physio.json"));
  EXPECT_EQ(bids_errors(s.out / "bids", s.dir), 0);
}

TEST(XrGaze, WithoutEyeTrackingNothingIsLoggedAndTheColumnsAreEmpty) {
  const auto s = run_session("none", {});
  EXPECT_EQ(query(s.db, "SELECT count(*) FROM gaze_samples")[0][0], "0");
  // Nor is the model's account stored without a simulated observer.
  EXPECT_EQ(query(s.db, "SELECT count(*) FROM events WHERE kind = 'onset' AND json_extract(detail, '$.percept') "
                        "IS NOT NULL")[0][0],
            "0");
  const auto csv = read_csv(s.out / "trials.csv");
  ASSERT_EQ(csv.at("gaze_samples").size(), 8u);
  for (const char* col : {"gaze_samples", "gaze_valid_samples", "gaze_vergence_arcmin"})
    for (const auto& cell : csv.at(col)) EXPECT_EQ(cell, kMissing) << col;
  EXPECT_FALSE(fs::exists(s.out / "bids" / "sub-G01" / "ses-1" / "beh"));
}

}  // namespace
