// BIDS motion: each tracked device is one tracking system (its samples share
// one clock and rate), written as a header-less *_motion.tsv whose columns
// are the rows of *_channels.tsv, with a *_motion.json sidecar giving the
// nominal and the effective sampling rate. Lab poses only: the curved-space
// pose is not a Cartesian position and stays in the database.
#include "export_common.hpp"

#include "curvlab/harness/data/sqlite.hpp"
#include "curvlab/harness/version.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace curvlab::data {

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

// The dataset in `root` (the bids folder).
Expected<ExportSummary> write_dataset(Database& db, const std::vector<SessionInfo>& sessions, const std::string& root) {
  ExportSummary summary;

  OJson description;
  description["Name"] = "curvlab motion data";
  description["BIDSVersion"] = "1.10.0";
  description["DatasetType"] = "raw";
  description["GeneratedBy"] = OJson::array(
      {{{"Name", "curvlab"}, {"Version", std::string(software_version())}}});
  if (auto e = write_text(root + "/dataset_description.json", description.dump(2) + "\n")) return *e;
  summary.files.push_back("bids/dataset_description.json");

  std::string participants = "participant_id\tipd_m\tdominant_eye\n";
  std::vector<std::string> seen_subjects;
  std::map<std::string, std::string> sessions_of;  // subject label → its _sessions.tsv rows
  try {
    for (const SessionInfo& s : sessions) {
      const std::string sub = alnum_label(s.pseudonym);
      if (std::find(seen_subjects.begin(), seen_subjects.end(), sub) == seen_subjects.end()) {
        seen_subjects.push_back(sub);
        participants += "sub-";
        participants += sub;
        participants += '\t';
        participants += s.ipd_m ? number(*s.ipd_m) : std::string("n/a");
        participants += '\t';
        participants += s.dominant_eye;
        participants += '\n';
      }
      const std::string ses = std::to_string(s.session_number);
      const std::string task = alnum_label(s.protocol_name);
      const std::string ses_dir = "sub-" + sub + "/ses-" + ses;
      if (auto e = make_dir(root + "/" + ses_dir + "/motion")) return *e;
      std::string scans = "filename\tacq_time\n";

      Statement devices(db.connection(),
                        "SELECT DISTINCT device FROM tracking_samples WHERE session_id = ?1 "
                        "ORDER BY device");
      devices.bind(1, s.session_id);
      std::vector<std::string> device_names;
      while (devices.step()) device_names.push_back(devices.column_text(0));

      for (const std::string& device : device_names) {
        const auto channels = channels_for(device);
        Statement rows(db.connection(),
                       "SELECT t_ns, lab_px_m, lab_py_m, lab_pz_m, lab_qx, lab_qy, lab_qz, "
                       "lab_qw, position_valid, orientation_valid, coherence_error_m, "
                       "coherence_error_rad FROM tracking_samples WHERE session_id = ?1 AND "
                       "device = ?2 ORDER BY t_ns, sample_id");
        rows.bind(1, s.session_id).bind(2, std::string_view(device));
        std::string tsv;
        std::vector<std::int64_t> times;
        while (rows.step()) {
          const std::int64_t t = rows.column_int(0);
          times.push_back(t);
          char latency[40];
          std::snprintf(latency, sizeof latency, "%.9f",
                        static_cast<double>(t - times.front()) * 1e-9);
          tsv += latency;
          for (int c = 1; c <= 7; ++c) {
            tsv += '\t';
            tsv += number(rows.column_double(c));
          }
          for (int c = 8; c <= 9; ++c) {
            tsv += '\t';
            tsv += std::to_string(rows.column_int(c));
          }
          for (int c = 10; c <= 11; ++c) {
            tsv += '\t';
            tsv += rows.is_null(c) ? std::string("n/a") : number(rows.column_double(c));
          }
          tsv += '\n';
        }
        const std::size_t n = times.size();
        double duration_s = n > 1 ? static_cast<double>(times.back() - times.front()) * 1e-9 : 0.0;
        double effective_hz = duration_s > 0 ? static_cast<double>(n - 1) / duration_s : 0.0;
        double nominal_hz = 0.0;
        if (n > 1) {
          std::vector<std::int64_t> dt;
          for (std::size_t i = 1; i < n; ++i) dt.push_back(times[i] - times[i - 1]);
          std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
          const auto median = dt[dt.size() / 2];
          if (median > 0) nominal_hz = std::round(1e9 / static_cast<double>(median));
        }
        const std::string base = ses_dir + "/motion/sub-" + sub + "_ses-" + ses + "_task-" + task +
                                 "_tracksys-" + alnum_label(device);
        if (auto e = write_text(root + "/" + base + "_motion.tsv", tsv)) return *e;

        std::string ch_tsv = "name\tcomponent\ttype\ttracked_point\tunits\treference_frame\tdescription\n";
        for (const auto& c : channels) {
          const std::string frame = c.type == "POS" || c.type == "ORNT" ? "lab" : "n/a";
          for (const std::string* field :
               {&c.name, &c.component, &c.type, &c.tracked_point, &c.units, &frame}) {
            ch_tsv += *field;
            ch_tsv += '\t';
          }
          ch_tsv += tsv_field(c.description);
          ch_tsv += '\n';
        }
        if (auto e = write_text(root + "/" + base + "_channels.tsv", ch_tsv)) return *e;

        OJson ch_json;
        ch_json["reference_frame"]["Description"] = "Frame the positions and orientations are in";
        // Orientations are unit quaternions, so no Euler rotation order
        // applies; RotationOrder (a SHOULD) is left out rather than given
        // as "n/a", which the BIDS validator's channels schema refuses.
        ch_json["reference_frame"]["Levels"]["lab"] = {
            {"Description",
             "Tracking space of the lab, origin at the runtime's stage origin; orientations as unit quaternions "
             "(x, y, z, w)"},
            {"SpatialAxes", "RSP"},
            {"RotationRule", "right-hand"}};
        if (auto e = write_text(root + "/" + base + "_channels.json", ch_json.dump(2) + "\n")) return *e;

        int pos = 0, ornt = 0, misc = 0, lat = 0;
        for (const auto& c : channels) {
          if (c.type == "POS") ++pos;
          else if (c.type == "ORNT") ++ornt;
          else if (c.type == "LATENCY") ++lat;
          else ++misc;
        }
        OJson sidecar;
        sidecar["TaskName"] = s.protocol_name;
        sidecar["TaskDescription"] = "curvlab protocol " + s.protocol_name + " (sha256 " +
                                     s.protocol_sha256 + ")";
        // The nominal rate is the median sample interval rounded to whole Hz
        // (the runtime's rate is not recorded); the effective rate is exact.
        if (n > 1) sidecar["SamplingFrequency"] = nominal_hz; else sidecar["SamplingFrequency"] = "n/a";
        sidecar["SamplingFrequencyEffective"] = effective_hz;
        sidecar["TrackingSystemName"] = "curvlab " + device;
        sidecar["Manufacturer"] = "n/a";
        sidecar["ManufacturersModelName"] = "n/a";
        sidecar["SoftwareVersions"] = "curvlab " + std::string(software_version());
        sidecar["RecordingType"] = "continuous";
        sidecar["RecordingDuration"] = duration_s;
        sidecar["MotionChannelCount"] = channels.size();
        sidecar["LATENCYChannelCount"] = lat;
        sidecar["POSChannelCount"] = pos;
        sidecar["ORNTChannelCount"] = ornt;
        sidecar["MISCChannelCount"] = misc;
        sidecar["TrackedPointsCount"] = 1;
        sidecar["SubjectArtefactDescription"] = "n/a";
        if (auto e = write_text(root + "/" + base + "_motion.json", sidecar.dump(2) + "\n")) return *e;

        const std::string acq = bids_time(s.started_utc);
        scans += base.substr(ses_dir.size() + 1);
        scans += "_motion.tsv\t";
        scans += acq;
        scans += '\n';
        for (const char* suffix : {"_motion.tsv", "_motion.json", "_channels.tsv", "_channels.json"})
          summary.files.push_back("bids/" + base + suffix);
        summary.rows += n;
      }
      sessions_of[sub] += "ses-" + ses + "\t" + bids_time(s.started_utc) + "\t" + s.session_uuid + "\n";
      const std::string scans_name = ses_dir + "/sub-" + sub + "_ses-" + ses + "_scans.tsv";
      if (auto e = write_text(root + "/" + scans_name, scans)) return *e;
      summary.files.push_back("bids/" + scans_name);
    }
  } catch (const SqliteFailure& f) {
    return to_data_error(f, db.path());
  }
  for (const auto& [sub, rows] : sessions_of)
    if (auto e = write_sessions_file(root, sub, rows, summary)) return *e;
  if (auto e = write_text(root + "/participants.tsv", participants)) return *e;
  summary.files.push_back("bids/participants.tsv");
  OJson pj;
  pj["participant_id"]["Description"] = "Pseudonym of the participant (no identifying data)";
  pj["ipd_m"] = {{"Description", "Interpupillary distance"}, {"Units", "m"}};
  pj["dominant_eye"]["Description"] = "Dominant eye: left, right or unknown";
  if (auto e = write_text(root + "/participants.json", pj.dump(2) + "\n")) return *e;
  summary.files.push_back("bids/participants.json");
  if (auto e = write_text(root + "/README", bids_readme())) return *e;
  summary.files.push_back("bids/README");
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

}  // namespace curvlab::data
