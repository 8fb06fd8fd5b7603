#include "session_frames.hpp"

#include "session_records.hpp"

#include "curvlab/harness/lab_volume.hpp"
#include "curvlab/harness/runner/trial_state.hpp"
#include "curvlab/harness/runner/view_record.hpp"

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>

namespace curvlab::harness::runner {

namespace {

using SteadyTime = std::chrono::steady_clock;

// The signal event stored when stdout's reader has gone: SIGPIPE's number
// (13 on Linux; Windows has no SIGPIPE, so its number is used there too).
#ifdef SIGPIPE
constexpr int kBrokenPipe = SIGPIPE;
#else
constexpr int kBrokenPipe = 13;
#endif

// The gaze a pose source located with the frame's poses, as gaze_samples
// stores it (data_schema/codebook.md).
data::GazeRayRecord gaze_record(const io::GazeRay& r) {
  return {r.valid, r.confidence.value_or(-1.0), {r.origin_m.x, r.origin_m.y, r.origin_m.z},
          {r.direction.x, r.direction.y, r.direction.z}};
}
data::GazeSample gaze_record(const io::Gaze& g) {
  data::GazeSample s;
  if (g.combined) {
    s.has_combined = true;
    s.combined = gaze_record(*g.combined);
  }
  if (g.eyes) {
    s.has_eyes = true;
    s.eyes = {gaze_record((*g.eyes)[0]), gaze_record((*g.eyes)[1])};
  }
  if (g.vergence) {
    s.has_vergence = true;
    s.vergence_rad = g.vergence->angle_rad;
    s.vergence_distance_m = g.vergence->distance_m.value_or(-1.0);
  }
  return s;
}

}  // namespace

SessionFrames::SessionFrames(SessionSetup& s)
    : protocol(*s.protocol),
      design(std::move(s.design)),
      store(*s.store),
      writer(*s.writer),
      lock(s.lock),
      station(s.station),
      clock(*s.clock),
      session_id(s.session_id),
      trial_ids(std::move(s.trial_ids)),
      watchers(s.watchers),
      room(s.options.console),
      options_(std::move(s.options)),
      frame_index_(s.frame_offset),
      progress_(options_.progress, options_.progress_json, options_.progress_every),
      continues_(page_continues(protocol)) {
  dominant_ = options_.dominant_eye == data::DominantEye::left ? renderer::Eye::left : renderer::Eye::right;
  eye_size_ = eye_image_size(station.display->info(), static_cast<std::uint32_t>(protocol.resolution_width),
                             static_cast<std::uint32_t>(protocol.resolution_height));
  restore_adaptive(s.staircase_history);
  resumed_trial.attempts = s.first_trial_attempts;
  resumed_trial.aborts = s.first_trial_aborts;
  for (const io::ResponseSource* source : station.responses) reach_.push_back(source->reach());
  continue_line_ = continue_line(reach_, protocol);
  room.status.participant = options_.participant;
  room.status.session_id = session_id;
  room.status.protocol = protocol.meta.name;
  room.status.trials = static_cast<std::int64_t>(design.trials.size());
  summary.session_id = session_id;
  summary.trials_planned = static_cast<std::int64_t>(design.trials.size());
  // One entry per frame: reserved up front so the frame loop does not grow it.
  cpu_ns.reserve(static_cast<std::size_t>(design.estimated_duration_ms() * protocol.refresh_hz / 1000) + 1024);
}

// ---- the world ------------------------------------------------------------

void SessionFrames::prepare(const protocol::Settings& s, const std::string& prompt) {
  auto made = make_world(s);
  if (!made) throw Stop{{made.error().kind, "impossible table: " + made.error().message}};
  World world = std::move(made).value();
  if (!tracker_ || !world_ || !world_->same_as(world) || tracker_->algorithm() != s.tracking) {
    tracker_ = geometry::make_tracker(s.tracking, world.space, world.table, runner::physical_table(s, options_.calibration));
    if (tracker_ && last_lab_) tracker_->update(*last_lab_);
  }
  world_ = world;
  settings_ = s;
  // The panels' texels match the display's pixels (a 90° field of view
  // where the display does not say).
  const auto eye_now = eye_image_size(station.display->info(), eye_size_.first, eye_size_.second);
  const double px_per_deg = std::clamp(static_cast<double>(eye_now.first) / 90.0, 5.0, 40.0);
  auto built = TrialScene::build(*world_, settings_, prompt, font(), px_per_deg);
  if (!built) throw Stop{built.error()};
  scene_.emplace(std::move(built).value());
}

std::string SessionFrames::font() const {
  return options_.font_path.empty() ? std::string(CURVLAB_DEFAULT_FONT) : options_.font_path;
}

geometry::Isometry SessionFrames::head() const {
  return tracker_ ? tracker_->output().pose[0] : geometry::Isometry::identity();
}

// ---- one frame --------------------------------------------------------------

geometry::PhysicalTable SessionFrames::physical_table() const {
  return runner::physical_table(settings_, options_.calibration);
}

bool SessionFrames::begin(Frame& f) {
  auto timing = station.display->begin_frame();
  if (!timing) return false;
  f.started = SteadyTime::now();
  f.timing = *timing;
  lab_ = lab_override ? lab_override(f.timing) : station.poses->poses(f.timing);
  // A pose no lab can hold (NaN, inf, 1e308 m) is lost tracking, stored as
  // such, and never reaches the tracker (lab_volume.hpp).
  for (auto& pose : lab_.pose) pose = possible_pose(pose);
  last_lab_ = lab_;
  if (tracker_) tracker_->update(lab_);
  f.head_tracked = head_meets(settings_.tracking_loss.head_requires, tracker_ && tracker_->output().tracked[0],
                              station.poses->head_tracking());
  f.inputs.clear();
  f.signal = poll_devices(f.inputs);
  store_display_reports();
  if (room.open()) {
    for (const auto& action : room.take(f.timing.now_ns - session_start_ns, clock.now_ns(), f.signal))
      event(current_trial_id(), action);
    room.acted();
  }
  take_stop_signal(f);
  return true;
}

// This frame's inputs from every response source, and one signal: the
// display's and the sources' in that order, those after the first kept for
// the next frames; a quit outranks them all.
io::Signal SessionFrames::poll_devices(std::vector<io::InputEvent>& inputs) {
  auto keep = [this](io::Signal s) {
    if (s != io::Signal::none) device_signals_.push_back(s);
  };
  keep(station.display->poll_signal());
  for (io::ResponseSource* source : station.responses) keep(source->poll(inputs));
  if (device_signals_.empty()) return io::Signal::none;
  if (std::find(device_signals_.begin(), device_signals_.end(), io::Signal::quit) != device_signals_.end()) {
    device_signals_.clear();
    return io::Signal::quit;
  }
  const io::Signal s = device_signals_.front();
  device_signals_.pop_front();
  return s;
}

// What the headset's runtime reported since the last frame, as events of
// the trial running (if any).
void SessionFrames::store_display_reports() {
  reports_.clear();
  station.display->take_reports(reports_);
  if (reports_.empty()) return;  // nearly every frame
  const auto trial_id = current_trial_id();
  for (const io::DisplayReport& r : reports_) {
    switch (r.kind) {
      case io::DisplayReport::Kind::events_lost:
        event(trial_id, data::events::EventsLost{r.lost_events});
        break;
      case io::DisplayReport::Kind::stage_moved:
        event(trial_id, data::events::StageMoved{r.change_ns, r.pose_valid, r.origin, r.kept_lab_frame});
        break;
      case io::DisplayReport::Kind::refresh_rate:
        event(trial_id, data::events::RefreshRate{r.from_hz, r.to_hz, r.requested});
        break;
    }
  }
}

// A SIGINT, SIGTERM or SIGHUP ends the session as the operator's end does:
// interrupted, flushed, resumable. So does standard output closed under
// --progress json (its reader gone), stored as the signal a broken pipe
// would have sent.
void SessionFrames::take_stop_signal(Frame& f) {
  const int sig = output_lost_                       ? kBrokenPipe
                  : options_.stop_signal != nullptr ? options_.stop_signal->load(std::memory_order_relaxed)
                                                    : 0;
  if (sig == 0) return;
  summary.output_lost = output_lost_;
  if (!stop_logged_) {
    event(std::nullopt, data::events::Signal{sig});
    stop_logged_ = true;
  }
  f.signal = Signal::quit;
}

renderer::FrameStats SessionFrames::end(Frame& f, const io::Overlay& overlay, bool onset,
                                        std::optional<std::int64_t> trial_id) {
  renderer::FrameDescription desc;
  desc.space = world_->space;
  desc.settings = view_settings(settings_, dominant_);
  desc.head = head();
  desc.rig = station.display->rig(f.timing, ipd());
  desc.width_px = static_cast<std::uint32_t>(protocol.resolution_width);
  desc.height_px = static_cast<std::uint32_t>(protocol.resolution_height);
  const bool draw = options_.drawing == FrameDrawing::all || (options_.drawing == FrameDrawing::onset && onset);
  // What moves with time or with the body (stimulus_kind.hpp) moves to
  // where it is when this frame is shown.
  if (tracker_) scene_->update(f.timing.predicted_display_ns, tracker_->output());
  const auto before_submit = SteadyTime::now();
  const renderer::FrameStats stats = station.display->submit(scene_->scene(), desc, overlay, draw);
  const auto after_submit = SteadyTime::now();
  log_frame(f, stats, trial_id, desc.rig);
  const auto own = std::chrono::duration_cast<std::chrono::nanoseconds>((before_submit - f.started) +
                                                                        (SteadyTime::now() - after_submit));
  cpu_ns.push_back(own.count() + static_cast<std::int64_t>(stats.cpu_ms * 1e6));
  ++summary.frames;
  ++frame_index_;
  if (f.timing.late) room.count_late();
  if (room.open()) {
    const auto ws = writer.stats();
    StatusFacts facts;
    facts.now_ns = f.timing.now_ns;
    facts.elapsed_ns = f.timing.now_ns - session_start_ns;
    facts.trials_ended = trials_reported_;
    facts.trials_before = first_reported;
    facts.lab = &lab_;
    facts.cpu_ms = stats.cpu_ms + static_cast<double>(own.count()) * 1e-6;
    facts.gpu_ms = stats.gpu_ms > 0.0 ? stats.gpu_ms : -1.0;
    facts.logger_drops = ws.dropped_tracking + ws.dropped_frames + ws.dropped_gaze;
    facts.logger_lock_wait_s = writer.lock_wait_s();
    room.show(facts, overlay.phase);
  }
  progress_.tick(progress_point());
  return stats;
}

// ---- records ----------------------------------------------------------------

void SessionFrames::event(std::optional<std::int64_t> trial_id, const data::Event& e,
                          std::optional<std::int64_t> moment_ns) {
  data::EventRecord record = data::event_record(session_id, trial_id, clock.now_ns(), e);
  if (options_.streams != nullptr) mark_event(record, e, moment_ns);
  writer.journal(std::move(record));
}

void SessionFrames::set_current_trial(std::optional<std::size_t> i) { current_trial_ = i; }

std::optional<std::int64_t> SessionFrames::current_trial_id() const {
  return current_trial_ ? std::optional<std::int64_t>(trial_ids[*current_trial_]) : std::nullopt;
}

protocol::AdaptiveState* SessionFrames::adaptive_for(const protocol::PlannedTrial& t) {
  const auto key = std::pair{t.block_position, t.cell};
  auto it = adaptive_.find(key);
  if (it == adaptive_.end()) {
    const auto& j = block_of(protocol, t).judgement;
    it = adaptive_.emplace(key, j.type->adaptive_state(j)).first;
  }
  return it->second.get();
}

// A resumed run replays the committed answers of adaptive trials, in order.
void SessionFrames::restore_adaptive(const std::vector<std::pair<std::int64_t, bool>>& history) {
  std::map<std::int64_t, std::size_t> index_of;
  for (std::size_t i = 0; i < trial_ids.size(); ++i) index_of[trial_ids[i]] = i;
  for (const auto& [trial_id, positive] : history) {
    const auto it = index_of.find(trial_id);
    if (it == index_of.end()) continue;
    const auto& t = design.trials[it->second];
    if (auto* state = adaptive_for(t)) state->record(t, positive);
  }
}

// Where the session stands: the trial running (or the last one ended),
// the trials ended in this run and those left.
ProgressPoint SessionFrames::progress_point() const {
  const auto total = static_cast<std::int64_t>(design.trials.size());
  const std::int64_t ended_all = first_reported + trials_reported_;
  ProgressPoint p;
  p.trial = current_trial_ ? static_cast<std::int64_t>(*current_trial_) + 1 : std::max<std::int64_t>(1, ended_all);
  p.total = total;
  p.ended = trials_reported_;
  p.left = total - ended_all;
  p.block = room.status.block;
  return p;
}

void SessionFrames::report_trial(std::size_t i, data::TrialStatus status, const std::string& reason) {
  ++trials_reported_;
  const protocol::PlannedTrial& t = design.trials[i];
  mark_trial_end(i, status, reason);
  if (!progress_.json()) return;
  Json line{{"trial", i + 1},
            {"of", design.trials.size()},
            {"trial_id", trial_ids[i]},
            {"block", t.block},
            {"status", data::to_string(status)}};
  Json levels = Json::object();
  for (const auto& [f, l] : t.levels) levels[f] = l;
  line["conditions"] = levels;
  if (!reason.empty()) line["end_reason"] = reason;
  if (status == data::TrialStatus::completed) {
    line["response"] = room.status.last_response;
    line["rt_ms"] = room.status.last_rt_ms >= 0.0 ? Json(room.status.last_rt_ms) : Json(nullptr);
  }
  line["frames_late"] = room.status.late_trial;
  line["elapsed_s"] = static_cast<double>(clock.now_ns() - session_start_ns) * 1e-9;
  if (!progress_.line(line.dump())) output_lost_ = true;
}

// Hands a record to the logger. Fast runs wait for the writer rather than
// lose samples; real-time runs never wait (the writer counts the drop).
template <class Push>
void SessionFrames::push(Push&& try_push) {
  if (try_push() || !options_.lossless_logging) return;
  for (int i = 0; i < 100; ++i) {
    check(writer.flush());
    if (try_push()) return;
  }
}

data::TrackingSample SessionFrames::sample(const Frame& f, std::int64_t trial_id, int d) const {
  const auto& out = tracker_->output();
  const auto& pose = lab_.pose[static_cast<std::size_t>(d)];
  static constexpr data::TrackedDevice devices[] = {data::TrackedDevice::head, data::TrackedDevice::left_hand,
                                                    data::TrackedDevice::right_hand};
  data::TrackingSample s;
  stamp(s, f, trial_id);
  s.device = devices[d];
  s.position_valid = pose.valid;
  s.orientation_valid = pose.valid || pose.orientation_valid;
  s.lab_position_m = {pose.position_m.x, pose.position_m.y, pose.position_m.z};
  s.lab_orientation_xyzw = {pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w};
  store_pose(out.pose[static_cast<std::size_t>(d)].m, s.virtual_pose);
  const bool finite =
      std::all_of(s.virtual_pose.begin(), s.virtual_pose.end(), [](double v) { return std::isfinite(v); });
  s.has_virtual_pose = out.tracked[static_cast<std::size_t>(d)] && finite;
  if (!finite) s.position_valid = s.orientation_valid = false;  // placed nowhere: not tracked
  s.has_state = true;
  s.state.physical_edge = out.state.physical_edge;
  s.state.virtual_edge = out.state.virtual_edge;
  s.state.laps = out.state.physical_laps;
  s.state.anchor_fraction = out.state.anchor_fraction;
  if (d > 0) {
    // A hand not measured (it or the head not tracked) has no coherence
    // error (NULL), never an error of 0.
    const auto& c = out.coherence[static_cast<std::size_t>(d - 1)];
    s.state.coherence_measured = c.measured && finite && std::isfinite(c.error_m) && std::isfinite(c.error_rad);
    s.state.coherence_error_m = c.error_m;
    s.state.coherence_error_rad = c.error_rad;
  }
  return s;
}

void SessionFrames::stamp(data::TrackingSample& s, const Frame& f, std::int64_t trial_id) const {
  s.session_id = session_id;
  s.trial_id = trial_id;
  s.frame_index = frame_index_;
  s.t_ns = f.timing.predicted_display_ns;
}

void SessionFrames::log_sample(const Frame& f, std::int64_t trial_id, data::TrackingSample s) {
  stamp(s, f, trial_id);
  push([&] { return writer.push_tracking(s); });
}

// The frame record carries the eye geometry it was drawn with, so that
// replay draws from what was recorded (the writer stores only changes).
void SessionFrames::log_frame(const Frame& f, const renderer::FrameStats& stats,
                              std::optional<std::int64_t> trial_id, const renderer::StereoRig& rig) {
  const std::int64_t tid = trial_id.value_or(-1);
  if (tracker_)
    for (int d = 0; d < geometry::kDeviceCount; ++d) {
      const auto s = sample(f, tid, d);
      push([&] { return writer.push_tracking(s); });
    }
  data::FrameRecord fr;
  fr.session_id = session_id;
  fr.trial_id = tid;
  fr.frame_index = frame_index_;
  fr.t_ns = f.timing.now_ns;
  fr.predicted_display_ns = f.timing.predicted_display_ns;
  fr.display_period_ns = f.timing.period_ns > 0 ? f.timing.period_ns : -1;
  fr.late = f.timing.late;
  fr.dropped_frames = f.timing.skipped_periods;
  fr.cpu_time_ns = static_cast<std::int64_t>(stats.cpu_ms * 1e6);
  fr.gpu_time_ns = stats.gpu_ms > 0.0 ? static_cast<std::int64_t>(stats.gpu_ms * 1e6) : -1;
  fr.views = stats.views;
  fr.passes = stats.reused ? 0 : stats.passes;
  fr.draws = stats.draws;
  fr.triangles = static_cast<std::int64_t>(stats.triangles);
  fr.has_view_geometry = true;
  fr.view_geometry = record_view_geometry(rig, eye_size_.first, eye_size_.second);
  push([&] { return writer.push_frame(fr); });
  if (options_.streams != nullptr) options_.streams->frame(f.timing.predicted_display_ns, lab_, station.poses->gaze());
  if (const auto gaze = station.poses->gaze()) {
    data::GazeSample g = gaze_record(*gaze);
    g.session_id = session_id;
    g.trial_id = tid;
    g.frame_index = frame_index_;
    g.t_ns = f.timing.predicted_display_ns;
    push([&] { return writer.push_gaze(g); });
  }
}

}  // namespace curvlab::harness::runner
