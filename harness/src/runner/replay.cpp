#include "curvlab/harness/render_result.hpp"
#include "curvlab/harness/runner/replay.hpp"
#include "curvlab/harness/runner/trial_state.hpp"

#include "play_scene.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/session_reader.hpp"
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/harness/runner/view_record.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/renderer.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

namespace curvlab::harness::runner {

using Json = nlohmann::ordered_json;
using Kind = Error::Kind;

namespace {

geometry::Isometry isometry(const std::array<double, 16>& m) {
  geometry::Isometry iso;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) iso.m[c][r] = m[static_cast<std::size_t>(c * 4 + r)];
  return iso;
}

// Everything the replayed frame depends on, read from the database.
struct StoredFrame {
  protocol::Protocol protocol;
  protocol::Settings settings;  // the trial's, with the value shown at that frame
  std::optional<protocol::Block> block;
  std::int64_t trial_id = 0;
  std::int64_t frame_index = 0;
  std::int64_t display_ns = 0;  // the frame's predicted display time
  data::OnsetRecord onset;
  geometry::Isometry head;
  data::DominantEye dominant_eye = data::DominantEye::unknown;
  std::uint32_t msaa = 1;  // the samples per pixel the session drew with
  std::optional<data::ViewGeometry> views;  // nullopt: not recorded (schema version 2)
  bool adjusted = false;                   // an adjustment after onset changed the stimulus
  std::optional<double> adjustment_value;  // an adjustment trial's value shown at the frame
  std::vector<data::ShotRecord> shots;     // a play block's (its trial has no onset)
  bool play = false;
};

// The session's protocol, re-expanded for its participant: the trial's
// settings and block.
Result<Done> read_trial_settings(const data::SessionProvenance& prov, const ReplayRequest& rq, StoredFrame& out) {
  auto loaded = protocol::load_protocol_text(prov.protocol_text,
                                             prov.protocol_source_path.value_or("stored protocol"));
  if (!loaded)
    return Error{Kind::bad_input, "the stored protocol no longer loads: " +
                                      protocol::format_diagnostic(loaded.error().diagnostics.front())};
  out.protocol = std::move(loaded).value();
  const protocol::Design design = protocol::expand_design(out.protocol, prov.participant_number.value_or(1));
  if (rq.trial_index < 0 || rq.trial_index >= static_cast<std::int64_t>(design.trials.size()))
    return Error{Kind::usage, "--trial must lie in [0, " + std::to_string(design.trials.size() - 1) +
                                  "] for session " + std::to_string(rq.session_id)};
  const auto& planned = design.trials[static_cast<std::size_t>(rq.trial_index)];
  out.settings = planned.settings;
  out.block = out.protocol.blocks.at(planned.protocol_block);
  if (planned.adjustment_start && out.block) {
    protocol::set_numeric_setting(out.settings, out.block->judgement.parameter, *planned.adjustment_start);
    out.adjustment_value = *planned.adjustment_start;
  }
  return Done{};
}

// The value the trial showed: an adaptive method's intensity, and in an
// adjustment trial (one planned with a start value) the value as last
// changed at or before the frame.
Result<Done> read_shown_value(data::Database& db, StoredFrame& out) {
  if (!out.block) return Done{};
  const auto& j = out.block->judgement;
  auto intensity = data::read_staircase_intensity(db, out.trial_id);
  if (!intensity) return intensity.error();
  if (*intensity) protocol::set_numeric_setting(out.settings, j.parameter, **intensity);
  if (!out.adjustment_value) return Done{};
  auto adjusted = data::read_adjustment_at(db, out.trial_id, out.onset.event_id, out.frame_index);
  if (!adjusted) return adjusted.error();
  if (*adjusted) {
    protocol::set_numeric_setting(out.settings, j.parameter, **adjusted);
    out.adjusted = true;
    out.adjustment_value = **adjusted;
  }
  return Done{};
}

// The head's virtual pose and display time of the replayed frame, which must
// belong to the trial.
Result<Done> read_head(data::Database& db, const ReplayRequest& rq, StoredFrame& out) {
  auto head = data::read_head_at_frame(db, rq.session_id, out.frame_index);
  if (!head) return head.error();
  const bool in_trial = *head && (*head)->trial_id == out.trial_id;
  // A head pose that is not finite (stored by curvlab before such poses were
  // stored as lost) would draw a black frame: refused like a lost one.
  const bool drawable = in_trial && std::all_of((*head)->virtual_pose.begin(), (*head)->virtual_pose.end(),
                                                [](double v) { return std::isfinite(v); });
  if (!drawable) {
    auto span = data::read_trial_frame_span(db, out.trial_id);
    if (!span) return span.error();
    const std::string frames = *span ? std::to_string((*span)->first) + ".." + std::to_string((*span)->last)
                                     : std::string("none logged");
    const bool within = *span && out.frame_index >= (*span)->first && out.frame_index <= (*span)->last;
    if (in_trial || within)
      return Error{Kind::bad_input, "frame " + std::to_string(out.frame_index) + " of trial " +
                                        std::to_string(rq.trial_index) +
                                        " has no valid head pose (tracking was lost or the pose source gave a pose "
                                        "that is not finite), so there is no view to draw; replay another of its "
                                        "frames (" + frames + ")"};
    return Error{Kind::not_found, "frame " + std::to_string(out.frame_index) + " has no logged head pose of trial " +
                                      std::to_string(rq.trial_index) + " (its frames: " + frames + ")"};
  }
  out.head = isometry((*head)->virtual_pose);
  out.display_ns = (*head)->t_ns;
  return Done{};
}

Result<StoredFrame> read_stored_frame(const ReplayRequest& rq) {
  if (!std::filesystem::exists(rq.db_path)) return Error{Kind::not_found, rq.db_path + ": no such database"};
  // Like export and resume, an older file is migrated first (its frames then
  // have no eye geometry, and replay assumes the headless one).
  auto opened = data::Database::open(rq.db_path, data::OpenMode::read_only);
  if (!opened) return opened.error();
  auto& db = opened.value();
  auto prov = data::read_session_provenance(db, rq.session_id);
  if (!prov) return prov.error();
  StoredFrame out;
  out.dominant_eye = prov->dominant_eye;
  // Drawn as the session drew it: sessions from before multisampling (no
  // msaa recorded) with one sample, a session that drew nothing as its
  // protocol asks.
  out.msaa = prov->msaa.value_or(1);
  if (auto r = read_trial_settings(*prov, rq, out); !r) return r.error();
  auto trial_id = data::read_trial_id(db, rq.session_id, rq.trial_index);
  if (!trial_id) return trial_id.error();
  out.trial_id = *trial_id;
  out.play = out.block && out.block->kind == "play";
  if (out.play) {
    // A play block's frames: its shots say where the balls were.
    auto shots = data::read_shots(db, out.trial_id);
    if (!shots) return shots.error();
    out.shots = std::move(*shots);
    if (!rq.frame_index)
      return Error{Kind::usage, "trial " + std::to_string(rq.trial_index) +
                                    " is a play block, which has no onset: give the frame to draw with --frame"};
    out.frame_index = *rq.frame_index;
    if (auto r = read_head(db, rq, out); !r) return r.error();
    auto views = data::read_view_geometry(db, rq.session_id, out.frame_index);
    if (!views) return views.error();
    out.views = *views;
    return out;
  }
  auto onset = data::read_onset(db, out.trial_id);
  if (!onset) return onset.error();
  if (!*onset)
    return Error{Kind::not_found, "trial " + std::to_string(rq.trial_index) +
                                      " never reached its stimulus onset (not run yet, or skipped)"};
  out.onset = **onset;
  out.frame_index = rq.frame_index.value_or(out.onset.frame_index);
  if (auto r = read_shown_value(db, out); !r) return r.error();
  if (auto r = read_head(db, rq, out); !r) return r.error();
  auto views = data::read_view_geometry(db, rq.session_id, out.frame_index);
  if (!views) return views.error();
  out.views = *views;
  return out;
}

// fixation, stimulus or response at the frame, from the onset and the timeline.
Phase phase_at(const StoredFrame& f) {
  if (f.play) return Phase::stimulus;
  const std::int64_t onset_ns = f.onset.predicted_display_ns;
  if (f.display_ns < onset_ns) return Phase::fixation;
  if (f.display_ns < onset_ns + f.settings.timeline.stimulus_ms * 1'000'000) return Phase::stimulus;
  return Phase::response;
}

Result<ReplayResult> write_outputs(const ReplayRequest& rq, const StoredFrame& f, const World& world,
                                   Phase phase, const renderer::OffscreenTarget& target,
                                   const renderer::FrameStats& stats, const std::string& device) {
  std::error_code ec;
  std::filesystem::create_directories(rq.out_dir, ec);
  if (ec) return Error{Kind::io, "cannot create " + rq.out_dir + ": " + ec.message()};
  ReplayResult out;
  out.frame_index = f.frame_index;
  out.phase = std::string(to_string(phase));
  out.device = device;
  for (auto [eye, name] : {std::pair{renderer::Eye::left, "left.png"}, std::pair{renderer::Eye::right, "right.png"}}) {
    const auto path = (std::filesystem::path(rq.out_dir) / name).string();
    if (auto written = from_renderer(renderer::write_png(path, target.image(eye))); !written)
      return written.error();
    out.files.push_back(path);
  }
  Json j;
  j["session_id"] = rq.session_id;
  j["trial_index"] = rq.trial_index;
  j["trial_id"] = f.trial_id;
  j["frame_index"] = f.frame_index;
  j["phase"] = std::string(to_string(phase));
  j["space"] = std::string(geometry::to_string(world.space.kind));
  j["radius_m"] = world.space.radius_m;
  j["view"] = view_name(f.settings);
  j["eye_geometry"] = f.views ? "recorded" : "assumed";
  if (f.adjustment_value) j["adjustment_value"] = *f.adjustment_value;
  j["views"] = stats.views;
  j["draws"] = stats.draws;
  j["device"] = device;
  const auto json_path = (std::filesystem::path(rq.out_dir) / "replay.json").string();
  std::ofstream file(json_path);
  file << j.dump(2) << '\n';
  if (!file) return Error{Kind::io, "cannot write " + json_path};
  out.files.push_back(json_path);
  return out;
}

}  // namespace

Result<ReplayResult> replay_frame(const ReplayRequest& rq) {
  auto stored = read_stored_frame(rq);
  if (!stored) return stored.error();
  const StoredFrame& f = *stored;
  const Phase phase = phase_at(f);

  auto made = make_world(f.settings);
  if (!made) return made.error();
  const World world = std::move(made).value();
  auto built = TrialScene::build(world, f.settings, f.block ? response_panel_text(f.block->judgement, {}) : std::string(),
                                 CURVLAB_DEFAULT_FONT);
  if (!built) return built.error();
  auto& scene = built.value();
  std::optional<PlayScene> play;
  if (f.play) {
    // The table and balls where the stored shots put them at the frame.
    auto state = play_state_at(world, f.shots, f.display_ns);
    if (!state) return state.error();
    scene.show(Phase::iti, false);
    if (state->system) {
      play.emplace(scene.scene(), world, state->params, state->balls.size());
      play->show(scene.scene(), *state->system, state->t_s);
    }
  } else {
    // The stimulus stays where onset placed it; an adjustment re-places it
    // from the head at onset, as the session did.
    const geometry::Isometry head_at_onset = isometry(f.onset.head_pose);
    Placement placement = place_stimulus(world, f.settings, head_at_onset);
    if (!f.adjusted) placement.stick_pose = isometry(f.onset.stick_pose);
    scene.place(placement, head_at_onset);
    scene.show(phase, f.settings.timeline.stimulus_during_response);
    // What moves (stimulus_kind.hpp) is where it was when the frame was
    // shown, for the head the frame recorded.
    FramePoses poses;
    poses.pose[0] = f.head;
    poses.tracked[0] = true;
    scene.update(f.display_ns, poses);
  }

  auto created = renderer::Context::create(
      {.device = rq.software ? renderer::DeviceChoice::software : renderer::DeviceChoice::automatic,
       .validation = false});
  auto context = from_renderer(std::move(created));
  if (!context) return context.error();
  const auto& ctx = context.value();
  const std::optional<std::uint32_t> msaa = f.msaa > 0 ? std::optional(f.msaa) : f.settings.viewing.msaa;
  renderer::Renderer r(ctx, renderer::RendererOptions{.msaa = msaa});
  renderer::FrameDescription desc;
  desc.space = world.space;
  desc.settings =
      view_settings(f.settings, f.dominant_eye == data::DominantEye::left ? renderer::Eye::left : renderer::Eye::right);
  desc.head = f.head;
  if (f.views) {
    desc.rig = rig_from_record(*f.views);
    desc.width_px = f.views->width_px;
    desc.height_px = f.views->height_px;
  } else {
    // Recorded before frames stored their eye geometry: what the headless
    // backend uses (the protocol's IPD and resolution, 90° across).
    desc.width_px = static_cast<std::uint32_t>(f.protocol.resolution_width);
    desc.height_px = static_cast<std::uint32_t>(f.protocol.resolution_height);
    desc.rig = renderer::StereoRig::from_ipd(
        f.settings.viewing.ipd_m,
        renderer::Fov::symmetric(std::numbers::pi / 2.0, double(desc.width_px) / double(desc.height_px)));
  }
  renderer::OffscreenTarget target(ctx, desc.width_px, desc.height_px);
  const auto stats = r.render(scene.scene(), desc, target);
  return write_outputs(rq, f, world, phase, target, stats, ctx.device_name());
}

}  // namespace curvlab::harness::runner
