// BIDS motion: each tracked device is one tracking system (its samples share
// one clock and rate), written as a header-less *_motion.tsv whose columns
// are the rows of *_channels.tsv, with a *_motion.json sidecar giving the
// nominal and the effective sampling rate. Lab poses only: the curved-space
// pose is not a Cartesian position and stays in the database. Eye tracking
// (gaze_samples) goes beside it as BIDS eye-tracking physio files.
#include "export_common.hpp"

#include "curvlab/harness/data/sqlite.hpp"
#include "curvlab/harness/version.hpp"

#include <nlohmann/json.hpp>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

namespace curvlab::harness::data {

using namespace exporting;
using OJson = nlohmann::ordered_json;

namespace {

struct Channel {
  std::string name, component, type, tracked_point, units, description;
};

std::string tracked_point_name(const std::string& device) {
  if (device == "head") return "Head";
  if (device == "left_hand") return "LeftHand";
  if (device == "right_hand") return "RightHand";
  return "Other";
}

std::vector<Channel> channels_for(const std::string& device) {
  const std::string p = tracked_point_name(device);
  const std::string d = alnum_label(device);
  std::vector<Channel> ch;
  ch.push_back({"latency", "n/a", "LATENCY", p, "s", "Time since the file's first sample"});
  for (const char* axis : {"x", "y", "z"})
    ch.push_back({d + "_pos_" + axis, axis, "POS", p, "m", "Lab position (x right, y up, z back)"});
  for (const char* q : {"quat_x", "quat_y", "quat_z", "quat_w"})
    ch.push_back({d + "_" + q, q, "ORNT", p, "n/a", "Lab orientation quaternion"});
  ch.push_back({d + "_pos_valid", "n/a", "MISC", p, "n/a", "1 when the position was tracked"});
  ch.push_back({d + "_ornt_valid", "n/a", "MISC", p, "n/a", "1 when the orientation was tracked"});
  ch.push_back({d + "_coherence_error_m", "n/a", "MISC", p, "m",
                "Seen-vs-felt position error of the body-coherent tracking"});
  ch.push_back({d + "_coherence_error_rad", "n/a", "MISC", p, "rad",
                "Seen-vs-felt rotation error of the body-coherent tracking"});
  return ch;
}

// What a reader of the dataset needs before opening a file; long enough that
// the BIDS validator does not flag it as a placeholder (README_FILE_SMALL).
std::string bids_readme() {
  return "Motion data of perception experiments in curved spaces (S3, E3, H3), exported by curvlab " +
         std::string(software_version()) +
         ".\n\n"
         "Each participant (sub-<pseudonym>, no identifying data) has one folder per session (ses-<n>). "
         "Each tracked device (head, left hand, right hand) is one tracking system (tracksys-<device>) "
         "with its own clock and rate: *_motion.tsv holds its samples without a header row, one column "
         "per row of *_channels.tsv (latency in seconds since the first sample, lab position in metres, "
         "orientation as a unit quaternion, validity flags, and the seen-vs-felt coherence error of the "
         "body-coherent tracking). *_motion.json gives the nominal and effective sampling rates, and "
         "*_channels.json the lab reference frame (x right, y up, z back).\n\n"
         "Sessions run with an eye-tracking headset also have beh/*_recording-eye1_physio.tsv.gz and "
         "recording-eye2 (BIDS eye tracking, PhysioType eyetrack): each eye's gaze ray in the lab, its "
         "azimuth and elevation, validity, confidence and the vergence of both eyes; a headset with only a "
         "combined gaze ray gives one recording, eye1, RecordedEye cyclopean.\n\n"
         "Positions are in the physical lab; the curved-space pose that was rendered is not Cartesian and "
         "stays in the curvlab database, together with the trials, the protocol and its SHA-256.\n";
}

std::string number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// acq_time as BIDS writes it: ISO 8601 without the zone letter.
std::string bids_time(std::string utc) {
  if (!utc.empty() && utc.back() == 'Z') utc.pop_back();
  return utc;
}

// sub-<label>/sub-<label>_sessions.tsv: each session's label, start and UUID
// (its identity across files and machines), with the column described.
std::optional<DataError> write_sessions_file(const std::string& root, const std::string& sub,
                                             const std::string& rows, ExportSummary& summary) {
  const std::string base = "sub-" + sub + "/sub-" + sub + "_sessions";
  if (auto e = write_text(root + "/" + base + ".tsv", "session_id\tacq_time\tsession_uuid\n" + rows)) return e;
  OJson doc;
  doc["session_uuid"]["Description"] =
      "The session's identity across files and machines (RFC 9562 UUID); session labels are numbered per "
      "participant and may be renumbered when files are pooled";
  if (auto e = write_text(root + "/" + base + ".json", doc.dump(2) + "\n")) return e;
  summary.files.push_back("bids/" + base + ".tsv");
  summary.files.push_back("bids/" + base + ".json");
  return std::nullopt;
}

std::optional<DataError> write_description(const std::string& root, ExportSummary& summary) {
  OJson description;
  description["Name"] = "curvlab motion data";
  description["BIDSVersion"] = "1.10.0";
  description["DatasetType"] = "raw";
  description["GeneratedBy"] = OJson::array({{{"Name", "curvlab"}, {"Version", std::string(software_version())}}});
  if (auto e = write_text(root + "/dataset_description.json", description.dump(2) + "\n")) return e;
  summary.files.push_back("bids/dataset_description.json");
  return std::nullopt;
}

// One device's samples of a session as _motion.tsv rows, with their times.
struct Recording {
  std::string tsv;
  std::vector<std::int64_t> times;
};

Recording read_recording(Database& db, std::int64_t session_id, const std::string& device) {
  Statement rows(db.connection(),
                 "SELECT t_ns, lab_px_m, lab_py_m, lab_pz_m, lab_qx, lab_qy, lab_qz, "
                 "lab_qw, position_valid, orientation_valid, coherence_error_m, "
                 "coherence_error_rad FROM tracking_samples WHERE session_id = ?1 AND "
                 "device = ?2 ORDER BY t_ns, sample_id");
  rows.bind(1, session_id).bind(2, std::string_view(device));
  Recording r;
  while (rows.step()) {
    const std::int64_t t = rows.column_int(0);
    r.times.push_back(t);
    char latency[40];
    std::snprintf(latency, sizeof latency, "%.9f", static_cast<double>(t - r.times.front()) * 1e-9);
    r.tsv += latency;
    for (int c = 1; c <= 7; ++c) {
      r.tsv += '\t';
      r.tsv += number(rows.column_double(c));
    }
    for (int c = 8; c <= 9; ++c) {
      r.tsv += '\t';
      r.tsv += std::to_string(rows.column_int(c));
    }
    for (int c = 10; c <= 11; ++c) {
      r.tsv += '\t';
      r.tsv += rows.is_null(c) ? std::string("n/a") : number(rows.column_double(c));
    }
    r.tsv += '\n';
  }
  return r;
}

// The nominal rate is the median sample interval rounded to whole Hz (the
// runtime's rate is not recorded); the effective rate is exact.
struct Rates {
  double duration_s = 0.0;
  double effective_hz = 0.0;
  double nominal_hz = 0.0;
};

Rates rates_of(const std::vector<std::int64_t>& times) {
  Rates r;
  const std::size_t n = times.size();
  if (n < 2) return r;
  r.duration_s = static_cast<double>(times.back() - times.front()) * 1e-9;
  r.effective_hz = r.duration_s > 0 ? static_cast<double>(n - 1) / r.duration_s : 0.0;
  std::vector<std::int64_t> dt;
  for (std::size_t i = 1; i < n; ++i) dt.push_back(times[i] - times[i - 1]);
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  const auto median = dt[dt.size() / 2];
  if (median > 0) r.nominal_hz = std::round(1e9 / static_cast<double>(median));
  return r;
}

std::string channels_tsv(const std::vector<Channel>& channels) {
  std::string out = "name\tcomponent\ttype\ttracked_point\tunits\treference_frame\tdescription\n";
  for (const auto& c : channels) {
    const std::string frame = c.type == "POS" || c.type == "ORNT" ? "lab" : "n/a";
    for (const std::string* field : {&c.name, &c.component, &c.type, &c.tracked_point, &c.units, &frame}) {
      out += *field;
      out += '\t';
    }
    out += tsv_field(c.description);
    out += '\n';
  }
  return out;
}

OJson channels_json() {
  OJson j;
  j["reference_frame"]["Description"] = "Frame the positions and orientations are in";
  // Orientations are unit quaternions, so no Euler rotation order applies;
  // RotationOrder (a SHOULD) is left out rather than given as "n/a", which
  // the BIDS validator's channels schema refuses.
  j["reference_frame"]["Levels"]["lab"] = {
      {"Description",
       "Tracking space of the lab, origin at the runtime's stage origin; orientations as unit quaternions "
       "(x, y, z, w)"},
      {"SpatialAxes", "RSP"},
      {"RotationRule", "right-hand"}};
  return j;
}

OJson motion_sidecar(const SessionInfo& s, const std::string& device, const std::vector<Channel>& channels,
                     const Rates& rates, std::size_t samples) {
  int pos = 0, ornt = 0, misc = 0, lat = 0;
  for (const auto& c : channels) {
    if (c.type == "POS") ++pos;
    else if (c.type == "ORNT") ++ornt;
    else if (c.type == "LATENCY") ++lat;
    else ++misc;
  }
  OJson j;
  j["TaskName"] = s.protocol_name;
  j["TaskDescription"] = "curvlab protocol " + s.protocol_name + " (sha256 " + s.protocol_sha256 + ")";
  if (samples > 1) j["SamplingFrequency"] = rates.nominal_hz; else j["SamplingFrequency"] = "n/a";
  j["SamplingFrequencyEffective"] = rates.effective_hz;
  j["TrackingSystemName"] = "curvlab " + device;
  j["Manufacturer"] = "n/a";
  j["ManufacturersModelName"] = "n/a";
  j["SoftwareVersions"] = "curvlab " + std::string(software_version());
  j["RecordingType"] = "continuous";
  j["RecordingDuration"] = rates.duration_s;
  j["MotionChannelCount"] = channels.size();
  j["LATENCYChannelCount"] = lat;
  j["POSChannelCount"] = pos;
  j["ORNTChannelCount"] = ornt;
  j["MISCChannelCount"] = misc;
  j["TrackedPointsCount"] = 1;
  j["SubjectArtefactDescription"] = "n/a";
  return j;
}

// Where a session's files go: sub-<sub>/ses-<n>/, and its recordings' stem.
struct SessionPlace {
  std::string sub;
  std::string ses;
  std::string dir;  // sub-<sub>/ses-<n>
  std::string recording_stem(const SessionInfo& s, const std::string& device) const {
    return dir + "/motion/sub-" + sub + "_ses-" + ses + "_task-" + alnum_label(s.protocol_name) + "_tracksys-" +
           alnum_label(device);
  }
};

// A device's four files (_motion.tsv/.json, _channels.tsv/.json); its row
// of the session's _scans.tsv is appended to `scans`.
std::optional<DataError> write_recording(Database& db, const std::string& root, const SessionInfo& s,
                                         const SessionPlace& place, const std::string& device, std::string& scans,
                                         ExportSummary& summary) {
  const auto channels = channels_for(device);
  const Recording rec = read_recording(db, s.session_id, device);
  const std::string base = place.recording_stem(s, device);
  if (auto e = write_text(root + "/" + base + "_motion.tsv", rec.tsv)) return e;
  if (auto e = write_text(root + "/" + base + "_channels.tsv", channels_tsv(channels))) return e;
  if (auto e = write_text(root + "/" + base + "_channels.json", channels_json().dump(2) + "\n")) return e;
  const OJson sidecar = motion_sidecar(s, device, channels, rates_of(rec.times), rec.times.size());
  if (auto e = write_text(root + "/" + base + "_motion.json", sidecar.dump(2) + "\n")) return e;
  scans += base.substr(place.dir.size() + 1);
  scans += "_motion.tsv\t";
  scans += bids_time(s.started_utc);
  scans += '\n';
  for (const char* suffix : {"_motion.tsv", "_motion.json", "_channels.tsv", "_channels.json"})
    summary.files.push_back("bids/" + base + suffix);
  summary.rows += rec.times.size();
  return std::nullopt;
}

// ---- eye tracking: BIDS physio (PhysioType eyetrack, BIDS 1.10) ---------

// One eye's (or the combined gaze's) recording (gaze_samples' column
// prefixes). The BIDS validator takes eye1 and eye2 as the recording labels
// of eye tracking: with per-eye gaze those are the left and the right eye;
// a session with only the combined gaze writes it as eye1, its RecordedEye
// "cyclopean". The combined gaze of a session that also has per-eye gaze
// stays in the database.
struct GazeRecording {
  const char* label;   // recording-<label>
  const char* prefix;  // gaze_samples columns
  const char* eye;     // RecordedEye
  bool per_eye;
};
constexpr GazeRecording kGazeRecordings[] = {
    {"eye1", "left", "left", true}, {"eye2", "right", "right", true}, {"eye1", "combined", "cyclopean", false}};

std::vector<std::pair<std::string, OJson>> gaze_columns(const GazeRecording& r) {
  const auto col = [](const char* d, const char* units) {
    OJson j{{"Description", d}};
    if (units != nullptr) j["Units"] = units;
    return j;
  };
  std::vector<std::pair<std::string, OJson>> c = {
      {"timestamp", col("Time on the session's monotonic clock (the frame's predicted display time)", "s")},
      {"x_coordinate", col("Gaze direction's azimuth in the lab, positive to the right of -z", "deg")},
      {"y_coordinate", col("Gaze direction's elevation in the lab, positive up", "deg")},
      {"origin_x", col("Gaze ray's origin, lab x (right)", "m")},
      {"origin_y", col("Gaze ray's origin, lab y (up)", "m")},
      {"origin_z", col("Gaze ray's origin, lab z (back)", "m")},
      {"direction_x", col("Gaze ray's unit direction, lab x", nullptr)},
      {"direction_y", col("Gaze ray's unit direction, lab y", nullptr)},
      {"direction_z", col("Gaze ray's unit direction, lab z", nullptr)},
      {"valid", col("1 when the runtime reported the gaze valid, 0 when tracking was lost", nullptr)}};
  if (r.per_eye) {
    c.emplace_back("confidence", col("The runtime's confidence in this eye's gaze, 0-1; n/a when not reported", nullptr));
    c.emplace_back("vergence",
                   col("Vergence of both eyes' gaze (left eye's yaw toward its ray minus the right eye's, in the plane "
                       "of the eyes' axis and the head's forward direction): positive converging, negative diverging "
                       "beyond parallel; n/a unless both eyes are valid",
                       "deg"));
  }
  return c;
}

std::optional<DataError> write_gzip(const std::string& path, const std::string& text) {
  gzFile f = gzopen(path.c_str(), "wb");
  if (f == nullptr) return DataError{DataError::Kind::io, path + ": cannot be written"};
  const int written = text.empty() ? 0 : gzwrite(f, text.data(), static_cast<unsigned>(text.size()));
  const int closed = gzclose(f);
  if ((!text.empty() && written != static_cast<int>(text.size())) || closed != Z_OK)
    return DataError{DataError::Kind::io, path + ": cannot be written (disk full?)"};
  return std::nullopt;
}

// The recording's rows (no header, BIDS physio) and their times.
Recording read_gaze(Database& db, std::int64_t session_id, const GazeRecording& r) {
  const std::string p = r.prefix;
  std::string sql = "SELECT t_ns, " + p + "_valid, " + p + "_ox_m, " + p + "_oy_m, " + p + "_oz_m, " + p + "_dx, " + p +
                    "_dy, " + p + "_dz, " + (r.per_eye ? p + "_confidence" : std::string("NULL")) +
                    ", vergence_rad FROM gaze_samples WHERE session_id = ?1 AND " + p +
                    "_valid IS NOT NULL ORDER BY t_ns, gaze_id";
  Statement rows(db.connection(), sql);
  rows.bind(1, session_id);
  Recording out;
  constexpr double deg = 180.0 / 3.141592653589793;
  while (rows.step()) {
    const std::int64_t t = rows.column_int(0);
    out.times.push_back(t);
    const double dx = rows.column_double(5), dy = rows.column_double(6), dz = rows.column_double(7);
    char ts[40];
    std::snprintf(ts, sizeof ts, "%.9f", static_cast<double>(t) * 1e-9);
    out.tsv += ts;
    for (double v : {std::atan2(dx, -dz) * deg, std::atan2(dy, std::hypot(dx, dz)) * deg, rows.column_double(2),
                     rows.column_double(3), rows.column_double(4), dx, dy, dz}) {
      out.tsv += '\t';
      out.tsv += number(v);
    }
    out.tsv += '\t';
    out.tsv += std::to_string(rows.column_int(1));
    if (r.per_eye) {
      for (int c : {8, 9}) {
        out.tsv += '\t';
        out.tsv += rows.is_null(c) ? std::string("n/a") : number(rows.column_double(c) * (c == 9 ? deg : 1.0));
      }
    }
    out.tsv += '\n';
  }
  return out;
}

OJson gaze_sidecar(const SessionInfo& s, const GazeRecording& r, const Recording& rec) {
  const Rates rates = rates_of(rec.times);
  OJson j;
  j["TaskName"] = s.protocol_name;
  j["PhysioType"] = "eyetrack";
  j["SamplingFrequency"] = rec.times.size() > 1 ? OJson(rates.nominal_hz) : OJson("n/a");
  j["StartTime"] = 0;
  OJson names = OJson::array();
  for (const auto& [name, desc] : gaze_columns(r)) {
    names.push_back(name);
    j[name] = desc;
  }
  j["Columns"] = names;
  j["RecordedEye"] = r.eye;
  j["SampleCoordinateSystem"] = "gaze-in-world";
  j["SampleCoordinateUnits"] = "deg";
  j["EnvironmentCoordinates"] = "lab frame of the headset's STAGE space: x right, y up, z back (-z forward)";
  j["Manufacturer"] = "n/a";
  j["ManufacturersModelName"] = "n/a";
  j["SoftwareVersions"] = "curvlab " + std::string(software_version());
  j["RecordingType"] = "continuous";
  j["EyeTrackingMethod"] = r.per_eye ? "OpenXR XR_FB_eye_tracking_social (per-eye gaze)"
                                     : "OpenXR XR_EXT_eye_gaze_interaction (combined gaze)";
  return j;
}

// Each gaze recording the session has: _physio.tsv.gz and _physio.json
// (BIDS 1.10, "Physiological recordings", PhysioType eyetrack).
std::optional<DataError> write_gaze(Database& db, const std::string& root, const SessionInfo& s,
                                    const SessionPlace& place, ExportSummary& summary) {
  bool per_eye = false;
  for (const GazeRecording& r : kGazeRecordings) {
    if (!r.per_eye && per_eye) break;
    const Recording rec = read_gaze(db, s.session_id, r);
    if (rec.times.empty()) continue;
    per_eye = per_eye || r.per_eye;
    // In beh/: the BIDS validator takes eye-tracking physio files there (the
    // behavioural task's), not beside the motion recordings.
    if (auto e = make_dir(root + "/" + place.dir + "/beh")) return e;
    const std::string base = place.dir + "/beh/sub-" + place.sub + "_ses-" + place.ses + "_task-" +
                             alnum_label(s.protocol_name) + "_recording-" + r.label + "_physio";
    if (auto e = write_gzip(root + "/" + base + ".tsv.gz", rec.tsv)) return e;
    if (auto e = write_text(root + "/" + base + ".json", gaze_sidecar(s, r, rec).dump(2) + "\n")) return e;
    summary.files.push_back("bids/" + base + ".tsv.gz");
    summary.files.push_back("bids/" + base + ".json");
    summary.rows += rec.times.size();
  }
  return std::nullopt;
}

// A session's recordings, one per tracked device, and its _scans.tsv.
std::optional<DataError> write_session(Database& db, const std::string& root, const SessionInfo& s,
                                       const SessionPlace& place, ExportSummary& summary) {
  if (auto e = make_dir(root + "/" + place.dir + "/motion")) return e;
  Statement devices(db.connection(),
                    "SELECT DISTINCT device FROM tracking_samples WHERE session_id = ?1 ORDER BY device");
  devices.bind(1, s.session_id);
  std::vector<std::string> device_names;
  while (devices.step()) device_names.push_back(devices.column_text(0));
  std::string scans = "filename\tacq_time\n";
  for (const std::string& device : device_names)
    if (auto e = write_recording(db, root, s, place, device, scans, summary)) return e;
  if (auto e = write_gaze(db, root, s, place, summary)) return e;
  const std::string scans_name = place.dir + "/sub-" + place.sub + "_ses-" + place.ses + "_scans.tsv";
  if (auto e = write_text(root + "/" + scans_name, scans)) return e;
  summary.files.push_back("bids/" + scans_name);
  return std::nullopt;
}

std::string participant_row(const std::string& sub, const SessionInfo& s) {
  return "sub-" + sub + '\t' + (s.ipd_m ? number(*s.ipd_m) : std::string("n/a")) + '\t' + s.dominant_eye + '\n';
}

std::optional<DataError> write_participants(const std::string& root, const std::string& rows,
                                            ExportSummary& summary) {
  if (auto e = write_text(root + "/participants.tsv", "participant_id\tipd_m\tdominant_eye\n" + rows)) return e;
  summary.files.push_back("bids/participants.tsv");
  OJson pj;
  pj["participant_id"]["Description"] = "Pseudonym of the participant (no identifying data)";
  pj["ipd_m"] = {{"Description", "Interpupillary distance"}, {"Units", "m"}};
  pj["dominant_eye"]["Description"] = "Dominant eye: left, right or unknown";
  if (auto e = write_text(root + "/participants.json", pj.dump(2) + "\n")) return e;
  summary.files.push_back("bids/participants.json");
  if (auto e = write_text(root + "/README", bids_readme())) return e;
  summary.files.push_back("bids/README");
  return std::nullopt;
}

// The dataset in `root` (the bids folder): the description, each session's
// recordings, then the per-subject session lists and the participants.
Expected<ExportSummary> write_dataset(Database& db, const std::vector<SessionInfo>& sessions, const std::string& root) {
  ExportSummary summary;
  if (auto e = write_description(root, summary)) return *e;
  std::string participants;
  std::set<std::string> seen_subjects;
  std::map<std::string, std::string> sessions_of;  // subject label → its _sessions.tsv rows
  try {
    for (const SessionInfo& s : sessions) {
      SessionPlace place{alnum_label(s.pseudonym), std::to_string(s.session_number), ""};
      place.dir = "sub-" + place.sub + "/ses-" + place.ses;
      if (seen_subjects.insert(place.sub).second) participants += participant_row(place.sub, s);
      if (auto e = write_session(db, root, s, place, summary)) return *e;
      sessions_of[place.sub] += "ses-" + place.ses + "\t" + bids_time(s.started_utc) + "\t" + s.session_uuid + "\n";
    }
  } catch (const SqliteFailure& f) {
    return to_data_error(f, db.path());
  }
  for (const auto& [sub, rows] : sessions_of)
    if (auto e = write_sessions_file(root, sub, rows, summary)) return *e;
  if (auto e = write_participants(root, participants, summary)) return *e;
  return summary;
}

}  // namespace

Expected<ExportSummary> export_bids_motion(Database& db, const ExportOptions& options) {
  auto sessions = load_sessions(db, options);
  if (!sessions) return sessions.error();
  if (auto e = check_labels(sessions.value(), origin(db, options))) return *e;
  return write_staged(options.out_dir, "bids", true,
                      [&](const std::string& root) { return write_dataset(db, sessions.value(), root); });
}

}  // namespace curvlab::harness::data
