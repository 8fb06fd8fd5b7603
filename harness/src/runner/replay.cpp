#include "curvlab/harness/runner/replay.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/sqlite.hpp"
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/renderer.hpp"

#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>

namespace curvlab::harness::runner {

using Json = nlohmann::ordered_json;

namespace {

geometry::Isometry from_json(const Json& a) {
  geometry::Isometry iso;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) iso.m[c][r] = a.at(static_cast<std::size_t>(c * 4 + r)).get<double>();
  return iso;
}

}  // namespace

std::variant<ReplayResult, ReplayError> replay_frame(const ReplayRequest& rq) {
  auto stored_v = read_stored_session(rq.db_path, rq.session_id);
  if (!stored_v) return ReplayError{exit_code(stored_v.error()) == 2, stored_v.error().message};
  const auto& stored = stored_v.value();
  auto loaded = protocol::load_protocol_text(stored.protocol_text, stored.protocol_source);
  if (!loaded.ok())
    return ReplayError{false, "the stored protocol no longer loads: " +
                                  protocol::format_diagnostic(loaded.diagnostics.front())};
  const protocol::Protocol& p = *loaded.protocol;
  const protocol::Design design = protocol::expand_design(p, stored.participant_number);
  if (rq.trial_index < 0 || rq.trial_index >= static_cast<std::int64_t>(design.trials.size()))
    return ReplayError{true, "--trial must lie in [0, " + std::to_string(design.trials.size() - 1) +
                                 "] for session " + std::to_string(rq.session_id)};
  const auto& planned = design.trials[static_cast<std::size_t>(rq.trial_index)];
  protocol::Settings s = planned.settings;
  const protocol::Block* block = nullptr;
  for (const auto& b : p.blocks)
    if (b.name == planned.block) block = &b;

  auto db = data::Database::open(rq.db_path, data::OpenMode::read_only);
  if (!db) return ReplayError{false, db.error().message};
  auto& conn = db.value().connection();
  std::int64_t trial_id = 0;
  Json onset;
  geometry::Isometry head;
  std::int64_t frame = 0;
  std::int64_t frame_display_ns = 0;
  std::string dominant = "unknown";
  try {
    data::Statement t(conn, "SELECT trial_id FROM trials WHERE session_id = ?1 AND trial_index = ?2");
    t.bind(1, rq.session_id).bind(2, rq.trial_index);
    if (!t.step()) return ReplayError{true, "no trial " + std::to_string(rq.trial_index) + " in session " +
                                                std::to_string(rq.session_id)};
    trial_id = t.column_int(0);
    data::Statement e(conn, "SELECT detail FROM events WHERE trial_id = ?1 AND kind = 'onset' "
                            "ORDER BY event_id DESC LIMIT 1");
    e.bind(1, trial_id);
    if (!e.step())
      return ReplayError{true, "trial " + std::to_string(rq.trial_index) +
                                   " never reached its stimulus onset (not run yet, or skipped)"};
    onset = Json::parse(e.column_text(0));
    data::Statement st(conn, "SELECT intensity FROM staircase_steps WHERE trial_id = ?1");
    st.bind(1, trial_id);
    if (st.step() && block) protocol::set_numeric_setting(s, block->judgement.parameter, st.column_double(0));
    if (planned.adjustment_start && block && block->judgement.adjustment)
      protocol::set_numeric_setting(s, block->judgement.adjustment->parameter, *planned.adjustment_start);
    frame = rq.frame_index.value_or(onset.at("frame_index").get<std::int64_t>());
    data::Statement h(conn, "SELECT virtual_pose, t_ns, trial_id FROM tracking_samples WHERE session_id = ?1 "
                            "AND frame_index = ?2 AND device = 'head' ORDER BY sample_id DESC LIMIT 1");
    h.bind(1, rq.session_id).bind(2, frame);
    bool ok = h.step() && !h.is_null(0) && h.column_opt_int(2) == trial_id;
    if (!ok) {
      data::Statement range(conn, "SELECT MIN(frame_index), MAX(frame_index) FROM tracking_samples "
                                  "WHERE trial_id = ?1 AND device = 'head'");
      range.bind(1, trial_id);
      std::string span = "none logged";
      if (range.step() && !range.is_null(0))
        span = std::to_string(range.column_int(0)) + ".." + std::to_string(range.column_int(1));
      return ReplayError{true, "frame " + std::to_string(frame) + " has no logged head pose of trial " +
                                   std::to_string(rq.trial_index) + " (its frames: " + span + ")"};
    }
    const auto blob = h.column_blob(0);
    double m[16];
    std::memcpy(m, blob.data(), sizeof m);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) head.m[c][r] = m[c * 4 + r];
    frame_display_ns = h.column_int(1);
    data::Statement d(conn, "SELECT p.dominant_eye FROM sessions se JOIN participants p "
                            "ON p.participant_id = se.participant_id WHERE se.session_id = ?1");
    d.bind(1, rq.session_id);
    if (d.step()) dominant = d.column_text(0);
  } catch (const std::exception& f) {
    return ReplayError{false, rq.db_path + ": " + f.what()};
  }

  const std::int64_t onset_ns = onset.value("predicted_display_ns", std::int64_t{0});
  const auto& tl = s.timeline;
  Phase phase = Phase::fixation;
  if (frame_display_ns >= onset_ns) phase = Phase::stimulus;
  if (frame_display_ns >= onset_ns + tl.stimulus_ms * 1'000'000) phase = Phase::response;

  auto made = make_world(s);
  if (auto* e = std::get_if<std::string>(&made)) return ReplayError{false, *e};
  const World world = std::get<World>(made);
  auto built = TrialScene::build(world, s, block ? block->judgement.prompt : std::string(),
                                 CURVLAB_DEFAULT_FONT);
  if (auto* e = std::get_if<std::string>(&built)) return ReplayError{false, *e};
  auto& scene = std::get<TrialScene>(built);
  Placement placement = place_stimulus(world, s, from_json(onset.at("head_pose")));
  placement.stick_pose = from_json(onset.at("stick_pose"));
  scene.place(placement, from_json(onset.at("head_pose")));
  scene.show(phase, tl.stimulus_during_response);

  auto created = renderer::Context::create(
      {.device = rq.software ? renderer::DeviceChoice::software : renderer::DeviceChoice::automatic,
       .validation = false});
  if (auto* e = std::get_if<renderer::RenderError>(&created)) return ReplayError{false, e->message};
  const auto& ctx = std::get<renderer::Context>(created);
  renderer::Renderer r(ctx);
  const auto w = static_cast<std::uint32_t>(p.resolution_width);
  const auto hgt = static_cast<std::uint32_t>(p.resolution_height);
  renderer::OffscreenTarget target(ctx, w, hgt);
  renderer::FrameDescription desc;
  desc.space = world.space;
  desc.settings = view_settings(s, dominant == "left" ? renderer::Eye::left : renderer::Eye::right);
  desc.head = head;
  desc.rig = renderer::StereoRig::from_ipd(
      s.viewing.ipd_m, renderer::Fov::symmetric(std::numbers::pi / 2.0, double(w) / double(hgt)));
  desc.width_px = w;
  desc.height_px = hgt;
  const auto stats = r.render(scene.scene(), desc, target);

  std::error_code ec;
  std::filesystem::create_directories(rq.out_dir, ec);
  if (ec) return ReplayError{false, "cannot create " + rq.out_dir + ": " + ec.message()};
  ReplayResult out;
  out.frame_index = frame;
  out.phase = std::string(to_string(phase));
  out.device = ctx.device_name();
  for (auto [eye, name] : {std::pair{renderer::Eye::left, "left.png"}, std::pair{renderer::Eye::right, "right.png"}}) {
    const auto path = (std::filesystem::path(rq.out_dir) / name).string();
    if (auto err = renderer::write_png(path, target.image(eye)); !err.empty()) return ReplayError{false, err};
    out.files.push_back(path);
  }
  Json j;
  j["session_id"] = rq.session_id;
  j["trial_index"] = rq.trial_index;
  j["trial_id"] = trial_id;
  j["frame_index"] = frame;
  j["phase"] = std::string(to_string(phase));
  j["space"] = std::string(geometry::to_string(world.space.kind));
  j["radius_m"] = world.space.radius_m;
  j["view"] = view_name(s);
  j["views"] = stats.views;
  j["draws"] = stats.draws;
  j["device"] = ctx.device_name();
  const auto json_path = (std::filesystem::path(rq.out_dir) / "replay.json").string();
  std::ofstream f(json_path);
  f << j.dump(2) << '\n';
  if (!f) return ReplayError{false, "cannot write " + json_path};
  out.files.push_back(json_path);
  return out;
}

}  // namespace curvlab::harness::runner
