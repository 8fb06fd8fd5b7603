#include "curvlab/harness/tracking/trajectory_csv.hpp"

#include "curvlab/harness/lab_volume.hpp"
#include "curvlab/harness/utf8.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace curvlab::harness {
namespace {

using geometry::Device;
using geometry::kDeviceCount;
using geometry::LabPose;
using geometry::PhysicalTable;

constexpr const char* kDevicePrefix[kDeviceCount] = {"head", "left", "right"};
constexpr const char* kPoseFields[8] = {"x_m", "y_m", "z_m", "qw", "qx", "qy", "qz", ""};

std::string build_trajectory_header() {
  std::string h = "t_ns";
  for (const char* d : kDevicePrefix) {
    h.append(",").append(d).append("_valid");
    for (int f = 0; f < 7; ++f) h.append(",").append(d).append("_").append(kPoseFields[f]);
  }
  return h;
}

std::string build_tracking_header() {
  // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on long
  // operator+ chains of std::string.
  std::string h =
      "t_ns,physical_edge,virtual_edge,anchor_fraction,physical_laps,virtual_laps,"
      "head_over_centre";
  for (const char* d : kDevicePrefix) h.append(",").append(d).append("_tracked");
  for (const char* d : {"left", "right"}) {
    for (const char* f : {"_coherence_measured", "_coherence_error_m", "_coherence_error_rad",
                          "_head_frame_error_m", "_head_frame_error_rad", "_table_frame_error_m",
                          "_table_frame_error_rad"})
      h.append(",").append(d).append(f);
  }
  for (const char* d : kDevicePrefix)
    for (char r = '0'; r < '4'; ++r)
      for (char c = '0'; c < '4'; ++c) h.append(",").append(d).append("_m").append(1, r).append(1, c);
  return h;
}

// One comma-separated field with its 1-based column.
struct Field {
  std::string_view text;
  std::size_t column = 1;
};

std::vector<Field> split(std::string_view line) {
  std::vector<Field> out;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= line.size(); ++i) {
    if (i == line.size() || line[i] == ',') {
      std::string_view f = line.substr(start, i - start);
      std::size_t lead = 0;
      while (lead < f.size() && (f[lead] == ' ' || f[lead] == '\t')) ++lead;
      std::size_t end = f.size();
      while (end > lead && (f[end - 1] == ' ' || f[end - 1] == '\t' || f[end - 1] == '\r')) --end;
      out.push_back({f.substr(lead, end - lead), start + lead + 1});
      start = i + 1;
    }
  }
  return out;
}

class Reader {
 public:
  explicit Reader(const std::string& name) : name_(name) {}

  [[nodiscard]] Error error(std::size_t line, std::size_t column, const std::string& field,
                            const std::string& what) const {
    std::ostringstream os;
    os << name_ << ':' << line << ':' << column << ": field '" << field << "': " << what;
    return {Error::Kind::bad_input, os.str()};
  }

  std::optional<Error> number(std::size_t line, const Field& f, const std::string& field,
                                   double* out) const {
    double v = 0.0;
    const auto* first = f.text.data();
    const auto* last = f.text.data() + f.text.size();
    const auto [ptr, ec] = std::from_chars(first, last, v);
    if (f.text.empty() || ec != std::errc() || ptr != last || !std::isfinite(v))
      return error(line, f.column, field,
                   "expected a finite number, got '" + std::string(f.text) + "'");
    *out = v;
    return std::nullopt;
  }

  // A number that is also a lab coordinate (lab_volume.hpp).
  std::optional<Error> lab_metres(std::size_t line, const Field& f, const std::string& field, double* out) const {
    if (auto e = number(line, f, field, out)) return e;
    if (within_lab(*out)) return std::nullopt;
    return error(line, f.column, field,
                 "expected a lab coordinate in metres within ±100 (the lab volume), got '" + std::string(f.text) +
                     "'");
  }

 private:
  std::string name_;
};

std::optional<Error> parse_table_line(const Reader& r, std::size_t line_no,
                                           std::string_view line, PhysicalTable* table) {
  // "# physical_table key=value key=value …"
  const std::string_view tag = "physical_table";
  std::size_t pos = line.find(tag) + tag.size();
  while (pos < line.size()) {
    while (pos < line.size() && line[pos] == ' ') ++pos;
    if (pos >= line.size()) break;
    std::size_t end = line.find(' ', pos);
    if (end == std::string_view::npos) end = line.size();
    const std::string_view token = line.substr(pos, end - pos);
    const std::size_t eq = token.find('=');
    if (eq == std::string_view::npos)
      return r.error(line_no, pos + 1, "physical_table",
                     "expected key=value, got '" + std::string(token) + "'");
    const std::string key(token.substr(0, eq));
    double* target = key == "centre_x_m" ? &table->centre_x_m
                     : key == "centre_z_m" ? &table->centre_z_m
                     : key == "yaw_rad"    ? &table->yaw_rad
                     : key == "edge_m"     ? &table->edge_m
                     : key == "height_m"   ? &table->height_m
                                           : nullptr;
    if (target == nullptr)
      return r.error(line_no, pos + 1, "physical_table",
                     "unknown key '" + key +
                         "' (expected centre_x_m, centre_z_m, yaw_rad, edge_m, height_m)");
    const Field value{token.substr(eq + 1), pos + eq + 2};
    const std::string field = "physical_table " + key;
    auto e = key == "yaw_rad" ? r.number(line_no, value, field, target) : r.lab_metres(line_no, value, field, target);
    if (e) return e;
    if (key == "edge_m" && !(table->edge_m > 0.0))
      return r.error(line_no, pos + eq + 2, "physical_table edge_m",
                     "expected a positive number of metres");
    pos = end;
  }
  return std::nullopt;
}

// The header row: the columns of trajectory_csv_header(), in order, and no more.
std::optional<Error> check_header(const Reader& r, std::size_t line_no, std::string_view line,
                                  const std::vector<Field>& fields, const std::vector<Field>& header) {
  for (std::size_t i = 0; i < header.size(); ++i) {
    if (i >= fields.size() || fields[i].text != header[i].text) {
      const std::size_t col = i < fields.size() ? fields[i].column : line.size() + 1;
      return r.error(line_no, col, "header",
                     "expected column " + std::to_string(i + 1) + " to be '" + std::string(header[i].text) +
                         "' (header: " + trajectory_csv_header() + ")");
    }
  }
  if (fields.size() != header.size())
    return r.error(line_no, fields[header.size()].column, "header",
                   "unexpected extra column '" + std::string(fields[header.size()].text) + "'");
  return std::nullopt;
}

std::optional<Error> check_field_count(const Reader& r, std::size_t line_no, std::string_view line,
                                       const std::vector<Field>& fields, const std::vector<Field>& header) {
  if (fields.size() == header.size()) return std::nullopt;
  const std::size_t col = fields.size() > header.size() ? fields[header.size()].column : line.size() + 1;
  return r.error(line_no, col,
                 fields.size() > header.size() ? "(extra)" : std::string(header[fields.size()].text),
                 "expected " + std::to_string(header.size()) + " fields, got " + std::to_string(fields.size()));
}

// The row's time: an integer number of nanoseconds after the previous row's.
Result<std::int64_t> read_time(const Reader& r, std::size_t line_no, const Field& f,
                               const std::vector<geometry::TrajectorySample>& earlier) {
  std::int64_t t = 0;
  const auto [ptr, ec] = std::from_chars(f.text.data(), f.text.data() + f.text.size(), t);
  if (f.text.empty() || ec != std::errc() || ptr != f.text.data() + f.text.size())
    return r.error(line_no, f.column, "t_ns",
                   "expected an integer number of nanoseconds, got '" + std::string(f.text) + "'");
  if (!earlier.empty() && t <= earlier.back().t_ns)
    return r.error(line_no, f.column, "t_ns",
                   "expected a time after the previous row's " + std::to_string(earlier.back().t_ns) +
                       " ns, got " + std::to_string(t));
  return t;
}

// Device d's validity flag and pose, from its eight columns after t_ns.
std::optional<Error> read_pose(const Reader& r, std::size_t line_no, const std::vector<Field>& fields,
                               const std::vector<Field>& header, std::size_t d, LabPose& pose) {
  const std::size_t base = 1 + 8 * d;
  const Field& vf = fields[base];
  if (vf.text != "0" && vf.text != "1")
    return r.error(line_no, vf.column, std::string(header[base].text),
                   "expected 1 (tracked) or 0 (lost), got '" + std::string(vf.text) + "'");
  pose.valid = vf.text == "1";
  if (!pose.valid) {
    // A lost device's pose is ignored; it may be empty or not a number.
    pose.position_m = geometry::Vec3(0.0);
    pose.orientation = geometry::Quat(1.0, 0.0, 0.0, 0.0);
    return std::nullopt;
  }
  double v[7] = {0, 0, 0, 1, 0, 0, 0};
  for (std::size_t k = 0; k < 7; ++k) {
    const Field& f = fields[base + 1 + k];
    const std::string field(header[base + 1 + k].text);
    if (auto e = k < 3 ? r.lab_metres(line_no, f, field, &v[k]) : r.number(line_no, f, field, &v[k])) return e;
  }
  pose.position_m = geometry::Vec3(v[0], v[1], v[2]);
  pose.orientation = geometry::Quat(v[3], v[4], v[5], v[6]);
  const double norm = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
  if (std::abs(norm - 1.0) > 1e-3) {
    std::ostringstream os;
    os << "expected a unit quaternion (qw,qx,qy,qz with norm 1 ± 1e-3), got norm " << norm;
    return r.error(line_no, fields[base + 4].column, std::string(header[base + 4].text), os.str());
  }
  return std::nullopt;
}

// One data row: its time and every device's pose.
Result<geometry::TrajectorySample> read_sample(const Reader& r, std::size_t line_no,
                                               const std::vector<Field>& fields, const std::vector<Field>& header,
                                               const std::vector<geometry::TrajectorySample>& earlier) {
  geometry::TrajectorySample s;
  auto t = read_time(r, line_no, fields[0], earlier);
  if (!t) return t.error();
  s.t_ns = t.value();
  for (std::size_t d = 0; d < kDeviceCount; ++d)
    if (auto e = read_pose(r, line_no, fields, header, d, s.frame.pose[d])) return *e;
  return s;
}

void put(std::ostream& out, double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 17);
  out.write(buf, res.ptr - buf);
}

}  // namespace

const std::string& trajectory_csv_header() {
  static const std::string h = build_trajectory_header();
  return h;
}

const std::string& tracking_csv_header() {
  static const std::string h = build_tracking_header();
  return h;
}

Result<TrajectoryFile> parse_trajectory_csv(std::istream& in, const std::string& name) {
  const Reader r(name);
  TrajectoryFile file;
  std::string line;
  std::size_t line_no = 0;
  bool header_seen = false;
  const std::vector<Field> header_fields = split(trajectory_csv_header());
  while (std::getline(in, line)) {
    ++line_no;
    if (const auto fault = find_invalid_utf8(line, line_no))
      return Error{Error::Kind::bad_input, utf8_fault_message(name, "the trajectory file", *fault)};
    std::string_view view(line);
    if (!view.empty() && view.back() == '\r') view.remove_suffix(1);
    if (view.find_first_not_of(" \t") == std::string_view::npos) continue;
    if (view.front() == '#') {
      if (view.find("physical_table") != std::string_view::npos) {
        if (auto e = parse_table_line(r, line_no, view, &file.table)) return *e;
        file.table_given = true;
      }
      continue;
    }
    const std::vector<Field> fields = split(view);
    if (!header_seen) {
      if (auto e = check_header(r, line_no, view, fields, header_fields)) return *e;
      header_seen = true;
      continue;
    }
    if (auto e = check_field_count(r, line_no, view, fields, header_fields)) return *e;
    auto sample = read_sample(r, line_no, fields, header_fields, file.samples);
    if (!sample) return sample.error();
    file.samples.push_back(sample.value());
  }
  if (!header_seen)
    return r.error(line_no + 1, 1, "header",
                   "missing header row (expected: " + trajectory_csv_header() + ")");
  if (file.samples.empty())
    return r.error(line_no + 1, 1, "t_ns", "expected at least one data row");
  return file;
}

Result<TrajectoryFile> read_trajectory_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Error{Error::Kind::not_found, path + ": cannot open the trajectory file for reading"};
  return parse_trajectory_csv(in, path);
}

void write_trajectory_csv(std::ostream& out, const geometry::Trajectory& trajectory,
                          const PhysicalTable& table) {
  out << "# curvlab trajectory v1: timed lab poses (metres, unit quaternions w,x,y,z)\n";
  out << "# physical_table centre_x_m=";
  put(out, table.centre_x_m);
  out << " centre_z_m=";
  put(out, table.centre_z_m);
  out << " yaw_rad=";
  put(out, table.yaw_rad);
  out << " edge_m=";
  put(out, table.edge_m);
  out << " height_m=";
  put(out, table.height_m);
  out << '\n' << trajectory_csv_header() << '\n';
  for (const auto& s : trajectory) {
    out << s.t_ns;
    for (const LabPose& p : s.frame.pose) {
      out << ',' << (p.valid ? '1' : '0');
      const double v[7] = {p.position_m.x,    p.position_m.y,    p.position_m.z,
                           p.orientation.w, p.orientation.x, p.orientation.y,
                           p.orientation.z};
      for (double x : v) {
        out << ',';
        put(out, x);
      }
    }
    out << '\n';
  }
}

void write_tracking_csv_row(std::ostream& out, std::int64_t t_ns,
                            const geometry::TrackingOutput& f) {
  const auto& st = f.state;
  out << t_ns << ',' << st.physical_edge << ',' << st.virtual_edge << ',';
  put(out, st.anchor_fraction);
  out << ',';
  put(out, st.physical_laps);
  out << ',';
  put(out, st.virtual_laps);
  out << ',' << (st.head_over_centre ? 1 : 0);
  for (bool t : f.tracked) out << ',' << (t ? 1 : 0);
  for (const auto& c : f.coherence) {
    out << ',' << (c.measured ? 1 : 0);
    for (double v : {c.error_m, c.error_rad, c.head_frame_m, c.head_frame_rad, c.table_frame_m,
                     c.table_frame_rad}) {
      out << ',';
      put(out, v);
    }
  }
  for (const auto& iso : f.pose)
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) {
        out << ',';
        put(out, iso.m[c][r]);
      }
  out << '\n';
}

}  // namespace curvlab::harness
