// `curvlab calibrate`: the physical table's calibration (docs/devices.md,
// "Physical-table calibration"), fitted offline from recorded touches
// (--touches FILE.csv) or made now by touching the corners with the desktop
// window's hand or the headset's right controller (--backend desktop|xr).
// Either way the result is the calibration file `curvlab run --calibration`
// reads.
#include "calibrate.hpp"

#include "curvlab/harness/lab_volume.hpp"
#include "curvlab/harness/protocol/settings.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/harness/utf8.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

namespace curvlab::harness::cli {

namespace rn = curvlab::harness::runner;

namespace {

struct CalibrateArgs {
  std::string touches;
  std::string out;
  bool json = false;
  std::optional<double> edge_m;
  std::optional<double> height_m;
  std::string protocol;  // the table as known: its [table] edge_m and height_m
  std::string tip_offset = "0,0,0";
  double max_residual_mm = 15.0;
  double ipd_m = 0.063;
  BackendArgs backend;
  bool backend_given = false;
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

std::vector<std::string> split_commas(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream in(line);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(trim(item));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

constexpr std::array<const char*, 3> kColumns = {"x_m", "y_m", "z_m"};

// One touch's coordinate: a number of metres within the lab volume
// (lab_volume.hpp). `where` is "FILE:LINE: ".
double touch_coordinate(const std::string& where, const char* column, const std::string& f) {
  double v = 0.0;
  const auto [end, ec] = std::from_chars(f.data(), f.data() + f.size(), v);
  if (f.empty() || ec != std::errc() || end != f.data() + f.size() || !std::isfinite(v))
    throw UsageError(where + column + ": expected a number in metres, got '" + f + "'");
  if (!harness::within_lab(v))
    throw UsageError(where + column + ": expected a lab coordinate in metres within ±100 (the lab volume), got '" +
                     f + "'");
  return v;
}

// Touches in touch order from `x_m,y_m,z_m` rows (metres, the lab's STAGE
// frame), after an optional header of exactly those names; blank lines are
// skipped. A bad row is a UsageError naming file, line and field.
std::vector<geometry::Vec3> read_touches_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw UsageError(path + ": cannot read the touches file");
  std::vector<geometry::Vec3> touches;
  std::string line;
  bool first = true;
  for (int number = 1; std::getline(in, line); ++number) {
    if (const auto fault = harness::find_invalid_utf8(line, static_cast<std::size_t>(number)))
      throw UsageError(harness::utf8_fault_message(path, "the touches file", *fault));
    if (trim(line).empty()) continue;
    const auto fields = split_commas(trim(line));
    const std::string where = path + ":" + std::to_string(number) + ": ";
    if (first && fields == std::vector<std::string>(kColumns.begin(), kColumns.end())) {
      first = false;
      continue;
    }
    first = false;
    if (fields.size() != 3)
      throw UsageError(where + "expected 3 values x_m,y_m,z_m (metres), got " + std::to_string(fields.size()));
    geometry::Vec3 p{0.0};
    for (std::size_t i = 0; i < 3; ++i)
      p[static_cast<glm::length_t>(i)] = touch_coordinate(where, kColumns[i], fields[i]);
    touches.push_back(p);
  }
  return touches;
}

geometry::CalibrationLimits limits_of(double max_residual_mm) {
  if (!(max_residual_mm >= 1.0 && max_residual_mm <= 100.0))
    throw UsageError("--max-residual-mm must lie in [1, 100] millimetres");
  geometry::CalibrationLimits limits;
  limits.max_residual_m = max_residual_mm / 1000.0;
  return limits;
}

void write_out(const Json& doc, const std::string& path) {
  if (path.empty()) return;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << doc.dump(2) << '\n';
  out.close();
  if (!out) throw RuntimeFailure("cannot write the calibration to " + path);
}

geometry::PhysicalTableFit known_table(const CalibrateArgs& a);

void fit_recorded(const CalibrateArgs& a) {
  const auto touches = read_touches_csv(a.touches);
  auto limits = limits_of(a.max_residual_mm);
  limits.known_edge_m = known_table(a).edge_m;
  auto fitted = geometry::fit_square_table(touches, limits);
  if (auto* e = std::get_if<geometry::GeometryError>(&fitted)) throw UsageError(a.touches + ": " + e->message);
  const Json doc = calibration_document(std::get<geometry::PhysicalTableFit>(fitted), touches);
  write_out(doc, a.out);
  print_result(doc, a.json);
}

// The table as known before the calibration: --edge-m and --height-m, else
// --protocol's [table] edge_m and height_m, else the protocol defaults',
// centred at the origin. The fit keeps this edge (CalibrationLimits).
geometry::PhysicalTableFit known_table(const CalibrateArgs& a) {
  const harness::protocol::Settings settings =
      a.protocol.empty() ? harness::protocol::Settings{} : load_protocol_or_usage(a.protocol).session_settings();
  geometry::PhysicalTableFit t;
  t.edge_m = a.edge_m.value_or(settings.table.edge_m);
  t.height_m = a.height_m.value_or(settings.table.height_m);
  if (!(t.edge_m >= 0.2 && t.edge_m <= 5.0)) throw UsageError("--edge-m must lie in [0.2, 5] m");
  if (!(t.height_m >= 0.3 && t.height_m <= 1.5)) throw UsageError("--height-m must lie in [0.3, 1.5] m");
  return t;
}

void calibrate_now(const CalibrateArgs& a) {
  if (a.backend.backend != "desktop" && a.backend.backend != "xr")
    throw UsageError("--backend must be desktop or xr (the corners are touched with the desktop window's hand "
                     "or the headset's right controller), got '" + a.backend.backend + "'");
  if (a.out.empty()) throw UsageError("--out FILE is needed: the accepted calibration is written there");
  if (std::error_code ec; std::filesystem::is_directory(a.out, ec))
    throw UsageError("--out " + a.out + ": is a folder; expected the calibration file to write");
  rn::CalibrationOptions o;
  o.known = known_table(a);
  const auto tip = parse_number_list(a.tip_offset, "--tip-offset-m", 3);
  o.tip_offset_m = {tip[0], tip[1], tip[2]};
  if (glm::length(o.tip_offset_m) > 0.5) throw UsageError("--tip-offset-m must lie within 0.5 m of the grip");
  o.limits = limits_of(a.max_residual_mm);
  o.limits.known_edge_m = o.known.edge_m;
  if (!(a.ipd_m > 0.04 && a.ipd_m < 0.09)) throw UsageError("--ipd-m must lie in (0.04, 0.09) m");
  o.ipd_m = a.ipd_m;
  o.screenshot_dir = a.backend.screenshot;
  StationNeeds needs;
  needs.msaa = a.backend.msaa ? parse_msaa(*a.backend.msaa) : std::nullopt;
  needs.table = o.known;
  const Devices devices = open_station(a.backend, needs);
  o.stop_signal = &catch_stop_signals();
  const auto result = calibrate_on(devices, o);
  const Json doc = calibration_document(result.fit, result.touches_m);
  write_out(doc, a.out);
  print_result(doc, a.json);
}

void calibrate_command(const CalibrateArgs& a) {
  if (a.touches.empty() == !a.backend_given)
    throw UsageError(a.touches.empty()
                         ? "give --touches FILE.csv (fit recorded touches) or --backend desktop|xr (touch the "
                           "corners now)"
                         : "--touches and --backend exclude each other: recorded touches are fitted without devices");
  if (!a.touches.empty()) return fit_recorded(a);
  calibrate_now(a);
}

std::string vec_text(const geometry::Vec3& p) {
  char text[64];
  std::snprintf(text, sizeof text, "(%.3f, %.3f, %.3f) m", p.x, p.y, p.z);
  return text;
}

}  // namespace

rn::CalibrationResult calibrate_on(const Devices& devices, const rn::CalibrationOptions& options) {
  auto made = rn::run_calibration(devices.station, options);
  if (!made) raise(made.error());
  const rn::CalibrationResult& r = made.value();
  for (const auto& reason : r.refusals) std::cerr << "curvlab: calibration: fit refused: " << reason << '\n';
  if (!r.accepted) {
    const std::string message = "the table calibration ended before a fit was accepted; nothing was written";
    if (const int sig = stop_signal_received(); sig != 0)
      throw RuntimeFailure(message + " (signal " + std::to_string(sig) + ")", 128 + sig);
    throw RuntimeFailure(message);
  }
  std::cerr << "curvlab: calibration: table fitted to " << r.fit.corners_used << " corners";
  for (std::size_t j = 0; j < r.touches_m.size(); ++j)
    std::cerr << (j == 0 ? ": " : ", ") << vec_text(r.touches_m[j]);
  char largest[128];
  std::snprintf(largest, sizeof largest, "; edge %.1f mm as known, %.1f mm as touched; largest residual %.1f mm\n",
                r.fit.edge_m * 1000.0, r.fit.fitted_edge_m * 1000.0, r.fit.max_residual_m * 1000.0);
  std::cerr << largest;
  return r;
}

Json calibration_document(const geometry::PhysicalTableFit& fit, const std::vector<geometry::Vec3>& touches_m) {
  Json doc = Json::parse(rn::calibration_json(fit));
  // The edge the touches span beside the known one the fit kept.
  doc["fitted_edge_m"] = fit.fitted_edge_m;
  Json touches = Json::array();
  for (const auto& p : touches_m) touches.push_back(Json::array({p.x, p.y, p.z}));
  doc["touches_m"] = touches;
  return doc;
}

void add_calibrate_commands(CLI::App& app) {
  auto args = std::make_shared<CalibrateArgs>();
  auto* c = app.add_subcommand("calibrate", "calibrate the physical table from corner touches (recorded, or made now "
                                            "with --backend desktop|xr)");
  c->add_option("--touches", args->touches, "fit recorded touches: a CSV of x_m,y_m,z_m rows in touch order");
  c->add_option("--out", args->out, "write the calibration JSON (what run --calibration reads) here");
  c->add_flag("--json", args->json, "print the calibration as JSON");
  c->add_option("--max-residual-mm", args->max_residual_mm,
                "refuse a touch farther than this from its fitted corner (default 15)");
  c->add_option("--backend", args->backend.backend, "touch the corners now: desktop or xr");
  c->add_option_function<double>("--edge-m", [args](double v) { args->edge_m = v; },
                                  "the table's edge as known, which the fit keeps; touches spanning an edge more "
                                  "than 10 mm different are refused (default: --protocol's, else 1.0 m)");
  c->add_option("--protocol", args->protocol, "take the table as known (edge, height) from this protocol's [table]");
  c->add_option_function<double>("--height-m", [args](double v) { args->height_m = v; },
                                  "the table as known before: its height (default: the protocol default)");
  c->add_option("--tip-offset-m", args->tip_offset,
                "X,Y,Z: the touching tip in the right controller's grip frame (default 0,0,0)");
  c->add_option("--ipd-m", args->ipd_m, "interpupillary distance in metres (default 0.063)");
  c->add_option_function<std::string>("--msaa", [args](const std::string& n) { args->backend.msaa = n; },
                              "samples per pixel, 1, 2, 4 (default) or 8");
  c->add_flag("--software", args->backend.software, "use a CPU Vulkan device (lavapipe) even with a GPU");
  c->add_option("--window-size", args->backend.window_size, "desktop: per-eye size WxH (default 960x960)");
  c->add_option("--preview", args->backend.preview, "desktop: side-by-side (default), left or right");
  c->add_option("--screenshot", args->backend.screenshot, "desktop: save the view at every step here");
  c->add_option("--key-script", args->backend.key_script,
                "desktop: scripted key presses and hand placements (docs/devices.md)");
  c->callback([args, c] {
    args->backend_given = c->count("--backend") > 0;
    calibrate_command(*args);
  });
}

}  // namespace curvlab::harness::cli
