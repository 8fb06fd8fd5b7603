// `curvlab render …`: one stereo frame of a stimulus scene, offscreen, written
// as DIR/left.png, DIR/right.png and DIR/plan.json (what the render plan
// drew and skipped, and how long it took; for the stick scene also the eye
// geometry and stick that `curvlab measure stick` reads). The scene is a
// trial's, built by the session runner's builder (runner/stimulus.hpp,
// viewed_scene) from protocol settings filled from the options, so what is
// rendered here is what participants see.
#include "common.hpp"

#include "curvlab/harness/render_result.hpp"
#include "curvlab/geometry/enum_names.hpp"
#include "curvlab/harness/measure/stick.hpp"
#include "curvlab/harness/protocol/settings.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/renderer.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>

namespace curvlab::harness::cli {
namespace {

using namespace curvlab::renderer;
using harness::runner::SceneKind;
using harness::runner::ViewedScene;

// The prompt a choice about the stick asks, shown with the stimulus as in a
// trial's response window.
constexpr const char* kPrompt = "Is the cue stick bent toward you,\nstraight, or bent away?";

struct RenderArgs {
  std::string space = "E3";
  std::optional<double> radius_m;
  std::string view = "native";
  std::string scene = "billiards";
  double eye_height_m = 1.55;
  std::string size = "1024x1024";
  double fov_deg = 90.0;
  double yaw_deg = 0.0;
  std::string back_hemisphere = "on";
  std::string eyes;
  double ipd_m = 0.063;
  double bend_m = 0.0;
  int msaa = 4;
  std::string stick_marks = "none";
  bool software = false;
  std::string out;
  bool json = false;
};

// What `curvlab measure stick` needs besides the images: the eyes and the
// stick as placed at onset.
Json stick_record(const ViewedScene& stimulus, const FrameDescription& frame, const harness::protocol::Settings& s) {
  harness::measure::StickScene m;
  m.space = stimulus.space;
  m.preset = perceived_preset(frame.settings.projection, frame.settings.eyes);
  m.head = stimulus.head;
  m.rig = frame.rig;
  m.width_px = frame.width_px;
  m.height_px = frame.height_px;
  m.stick = stimulus.placement.stick;
  m.stick_pose = stimulus.placement.stick_pose;
  m.marks = s.stimulus.stick_marks;
  return harness::measure::scene_json(m);
}

// The arguments parsed and range-checked, before anything is made.
struct RenderRequest {
  geometry::SpaceKind kind;
  geometry::ViewPreset preset;
  SceneKind scene;
  std::uint32_t width_px;
  std::uint32_t height_px;
  std::uint32_t msaa;
};

RenderRequest check_render_args(const RenderArgs& a) {
  const auto kind = geometry::parse_space_kind(a.space);
  if (!kind) throw UsageError("--space must be S3, E3 or H3, got '" + a.space + "'");
  const auto preset = geometry::parse_view_preset(a.view);
  if (!preset)
    throw UsageError("--view must be " + geometry::alternatives_text(geometry::kViewPresets) + ", got '" + a.view + "'");
  const auto scene_kind = harness::runner::parse_scene_kind(a.scene);
  if (!scene_kind)
    throw UsageError("--scene must be stick, table, billiards or tiling, got '" + a.scene + "'");
  if (a.radius_m && !(*a.radius_m > 0.0 && std::isfinite(*a.radius_m)))
    throw UsageError("--radius-m must be a positive number of metres");
  if (!(a.eye_height_m > 0.85 && a.eye_height_m < 3.0))
    throw UsageError("--eye-height-m must lie between 0.85 and 3 m (the cloth is at the table height, 0.76 m)");
  if (!(a.fov_deg >= 10.0 && a.fov_deg <= 170.0))
    throw UsageError("--fov-deg must lie between 10 and 170 degrees");
  if (a.back_hemisphere != "on" && a.back_hemisphere != "off")
    throw UsageError("--back-hemisphere must be on or off, got '" + a.back_hemisphere + "'");
  if (!(std::abs(a.yaw_deg) <= 360.0)) throw UsageError("--yaw-deg must lie in [-360, 360]");
  if (!(a.ipd_m >= 0.0 && a.ipd_m < 0.1)) throw UsageError("--ipd-m must lie in [0, 0.1) m");
  const auto [w, h] = parse_size(a.size, "--size");
  const std::uint32_t msaa = check_msaa(a.msaa);
  if (a.out.empty()) throw UsageError("--out DIR is required");
  return {*kind, *preset, *scene_kind, w, h, msaa};
}

ViewSettings view_settings(const RenderArgs& a, geometry::ViewPreset preset) {
  ViewSettings settings = ViewSettings::preset(preset);
  settings.back_hemisphere = a.back_hemisphere == "on";
  if (!a.eyes.empty()) {
    const auto eyes = parse_eye_selection(a.eyes);
    if (!eyes)
      throw UsageError("--eyes must be " + geometry::alternatives_text(kEyeSelections) + ", got '" + a.eyes + "'");
    settings.eyes = *eyes;
  }
  return settings;
}

// The protocol's settings (and so its dimensions: table, stick, balls) with
// what the options set; the scene kind adds what it shows (scene_settings).
harness::protocol::Settings scene_settings(const RenderArgs& a, const RenderRequest& rq) {
  harness::protocol::Settings s;
  s.space.kind = rq.kind;
  s.space.radius_m = a.radius_m;
  s.stimulus.stick_sagitta_m = a.bend_m;
  const auto marks = parse_stick_marks(a.stick_marks);
  if (!marks)
    throw UsageError("--stick-marks must be " + geometry::alternatives_text(kStickMarks) + ", got '" + a.stick_marks +
                     "'");
  s.stimulus.stick_marks = *marks;
  return s;
}

FrameDescription frame_description(const RenderArgs& a, const RenderRequest& rq, const ViewedScene& stimulus,
                                   const ViewSettings& settings) {
  FrameDescription frame;
  frame.space = stimulus.space;
  frame.settings = settings;
  frame.head = stimulus.head;
  frame.rig = StereoRig::from_ipd(
      a.ipd_m, Fov::symmetric(a.fov_deg * std::numbers::pi / 180.0, double(rq.width_px) / double(rq.height_px)));
  frame.width_px = rq.width_px;
  frame.height_px = rq.height_px;
  return frame;
}

void write_eye_images(const std::string& dir, const OffscreenTarget& target) {
  for (Eye eye : {Eye::left, Eye::right}) {
    const std::string path = (std::filesystem::path(dir) / (eye == Eye::left ? "left.png" : "right.png")).string();
    if (auto written = harness::from_renderer(write_png(path, target.image(eye))); !written)
      raise(written.error());
  }
}

// plan.json: what was asked for, and what the render plan drew and skipped.
Json plan_record(const RenderArgs& a, const RenderRequest& rq, const ViewedScene& stimulus,
                 const ViewSettings& settings, const Context& ctx, const Renderer& renderer, const FrameStats& stats) {
  Json plan;
  plan["space"] = std::string(geometry::to_string(rq.kind));
  plan["radius_m"] = stimulus.space.radius_m;
  plan["view"] = a.view;
  plan["projection"] = std::string(to_string(settings.projection));
  plan["scene"] = a.scene;
  plan["width_px"] = rq.width_px;
  plan["height_px"] = rq.height_px;
  plan["device"] = ctx.device_name();
  plan["msaa"] = renderer.msaa();
  plan["views"] = stats.views;
  plan["passes"] = stats.passes;
  plan["draws"] = stats.draws;
  plan["culled"] = stats.culled;
  plan["triangles"] = stats.triangles;
  plan["lines"] = stats.lines;
  plan["back_hemisphere"] = stats.back_hemisphere;
  plan["subdivision_level"] = stats.max_level;
  plan["edge_error_px"] = stats.error_px;
  plan["cpu_ms"] = stats.cpu_ms;
  plan["gpu_ms"] = stats.gpu_ms;
  plan["frame_ms"] = stats.frame_ms;
  return plan;
}

void run_render(const RenderArgs& a) {
  const RenderRequest rq = check_render_args(a);
  const ViewSettings settings = view_settings(a, rq.preset);
  const harness::protocol::Settings s = scene_settings(a, rq);
  // Options that give no table are bad input (exit 2); an unreadable prompt font is io (exit 1).
  auto made = harness::runner::viewed_scene(
      rq.scene, s,
      {.eye_height_m = a.eye_height_m,
       .yaw_rad = a.yaw_deg * std::numbers::pi / 180.0,
       .panel_px_per_deg = static_cast<double>(rq.width_px) / a.fov_deg},
      kPrompt, CURVLAB_DEFAULT_FONT);
  if (!made) raise(made.error());
  auto& stimulus = made.value();

  std::error_code ec;
  std::filesystem::create_directories(a.out, ec);
  if (ec) throw RuntimeFailure("cannot create --out directory " + a.out + ": " + ec.message());

  auto created = Context::create({.device = a.software ? DeviceChoice::software : DeviceChoice::automatic,
                                  .validation = false});
  auto context = harness::from_renderer(std::move(created));
  if (!context) raise(context.error());
  const Context& ctx = context.value();
  Renderer renderer(ctx, RendererOptions{.msaa = rq.msaa});
  warn_if_msaa_clamped(rq.msaa, renderer.msaa());
  OffscreenTarget target(ctx, rq.width_px, rq.height_px);
  const FrameDescription frame = frame_description(a, rq, stimulus, settings);
  const FrameStats stats = renderer.render(stimulus.scene, frame, target);

  write_eye_images(a.out, target);
  Json plan = plan_record(a, rq, stimulus, settings, ctx, renderer, stats);
  if (rq.scene == SceneKind::stick) plan["measure"] = stick_record(stimulus, frame, s);
  const std::string plan_path = (std::filesystem::path(a.out) / "plan.json").string();
  std::ofstream out(plan_path);
  out << plan.dump(2) << '\n';
  if (!out) throw RuntimeFailure("cannot write " + plan_path);
  print_result(plan, a.json);
}

}  // namespace

void add_render_commands(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  auto* cmd = app.add_subcommand(
      "render", "draw one stereo frame of a stimulus scene offscreen (left.png, right.png, plan.json)");
  cmd->add_option("--space", args->space, "S3, E3 or H3")->required();
  cmd->add_option_function<double>("--radius-m", [args](double r) { args->radius_m = r; },
                                   "radius ρ in metres (default: from the protocol's table edge, 1 m)");
  cmd->add_option("--view", args->view, geometry::alternatives_text(geometry::kViewPresets))->required();
  cmd->add_option("--scene", args->scene, "stick, table, billiards or tiling")->required();
  cmd->add_option("--eye-height-m", args->eye_height_m, "eye height above the floor (default 1.55)");
  cmd->add_option("--size", args->size, "per-eye image size WxH (default 1024x1024)");
  cmd->add_option("--fov-deg", args->fov_deg, "horizontal field of view (default 90)");
  cmd->add_option("--back-hemisphere", args->back_hemisphere, "S3 back hemisphere: on or off");
  cmd->add_option("--eyes", args->eyes, "override the preset's eyes: both, left, right, dominant");
  cmd->add_option("--yaw-deg", args->yaw_deg, "turn the head left (+) from facing the stimulus");
  cmd->add_option("--ipd-m", args->ipd_m, "interpupillary distance (default 0.063)");
  cmd->add_option("--bend-m", args->bend_m, "cue-stick sagitta in metres (+ toward the viewer)");
  cmd->add_option("--msaa", args->msaa, "samples per pixel: 1, 2, 4 (default) or 8");
  cmd->add_option("--stick-marks", args->stick_marks,
                  "cue-stick marks: " + geometry::alternatives_text(kStickMarks) + " (for curvlab measure)");
  cmd->add_flag("--software", args->software, "use a CPU Vulkan device (lavapipe) even with a GPU");
  cmd->add_option("--out", args->out, "output directory")->required();
  cmd->add_flag("--json", args->json, "print the plan as JSON");
  cmd->callback([args] { run_render(*args); });
}

}  // namespace curvlab::harness::cli
