#include "session_loop.hpp"

#include "observer_keys.hpp"
#include "progress.hpp"
#include "session_records.hpp"

#include "curvlab/harness/lab_volume.hpp"
#include "curvlab/harness/numbered_files.hpp"
#include "curvlab/harness/protocol/adjustment.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/runner/image_observer.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/harness/runner/trial_state.hpp"
#include "curvlab/harness/runner/view_record.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <deque>
#include <exception>
#include <filesystem>
#include <map>

namespace curvlab::harness::runner {

namespace {

using geometry::Isometry;
using protocol::PlannedTrial;
using protocol::Settings;
using SteadyTime = std::chrono::steady_clock;

// The gaze a pose source located with the frame's poses, as gaze_samples
// stores it (data_schema/codebook.md).
data::GazeRay gaze_record(const io::GazeRay& r) {
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

enum class Outcome { done, quit };

// Ends the run with an error; caught at the top of SessionLoop::run.
struct Stop {
  Error error;
};

std::string trial_line(const PlannedTrial& t) {
  std::string line = t.block + "  trial " + std::to_string(t.trial_in_block + 1);
  for (const auto& [f, l] : t.levels) line += "  " + f + "=" + l;
  return line;
}

constexpr std::int64_t ms_to_ns(std::int64_t v) { return v * 1'000'000; }

// The signal event stored when stdout's reader has gone: SIGPIPE's number
// (13 on Linux; Windows has no SIGPIPE, so its number is used there too).
#ifdef SIGPIPE
constexpr int kBrokenPipe = SIGPIPE;
#else
constexpr int kBrokenPipe = 13;
#endif

// The event a page is logged as; pages are shown only in these three phases.
data::EventKind page_event(Phase phase) {
  switch (phase) {
    case Phase::instructions: return data::EventKind::instructions;
    case Phase::break_page: return data::EventKind::break_page;
    case Phase::done: return data::EventKind::done;
    case Phase::fixation:
    case Phase::stimulus:
    case Phase::response:
    case Phase::iti:
    case Phase::paused:
    case Phase::tracking_lost:
    case Phase::calibration: break;
  }
  std::fprintf(stderr, "curvlab: a page shown in phase %s\n", std::string(to_string(phase)).c_str());
  std::abort();
}

// How long the attempt's current phase lasts after `now_ns`.
std::int64_t phase_left(const Attempt& a, Phase phase, const protocol::Timeline& tl, std::int64_t now_ns) {
  const auto onset = a.onset_frame_ns();
  switch (phase) {
    case Phase::fixation: return std::max<std::int64_t>(0, a.start_ns() + ms_to_ns(tl.fixation_ms) - now_ns);
    case Phase::stimulus:
      return onset ? std::max<std::int64_t>(0, *onset + ms_to_ns(tl.stimulus_ms) - now_ns) : -1;
    case Phase::response:
      return onset ? std::max<std::int64_t>(0, *onset + ms_to_ns(tl.stimulus_ms + tl.response_ms) - now_ns) : -1;
    default: return -1;
  }
}

}  // namespace

class SessionLoop::Impl {
 public:
  explicit Impl(SessionSetup s)
      : p_(*s.protocol),
        design_(std::move(s.design)),
        store_(*s.store),
        writer_(*s.writer),
        lock_(s.lock),
        station_(s.station),
        clock_(*s.clock),
        options_(std::move(s.options)),
        session_id_(s.session_id),
        trial_ids_(std::move(s.trial_ids)),
        frame_index_(s.frame_offset),
        first_trial_attempts_(s.first_trial_attempts),
        first_trial_aborts_(s.first_trial_aborts),
        progress_(options_.progress, options_.progress_json, options_.progress_every),
        console_(options_.console) {
    dominant_ = options_.dominant_eye == data::DominantEye::left ? renderer::Eye::left : renderer::Eye::right;
    eye_size_ = eye_image_size(station_.display->info(), static_cast<std::uint32_t>(p_.resolution_width),
                               static_cast<std::uint32_t>(p_.resolution_height));
    restore_adaptive(s.staircase_history);
    std::vector<io::Reach> reach;
    for (const io::ResponseSource* source : station_.responses) reach.push_back(source->reach());
    if (observer_params()) reach.push_back(observer_keys_.reach());
    continue_line_ = continue_line(reach, p_);
    status_.participant = options_.participant;
    status_.session_id = session_id_;
    status_.protocol = p_.meta.name;
    status_.trials = static_cast<std::int64_t>(design_.trials.size());
  }

  RunResult run(std::size_t first, bool start_pages) {
    const auto wall0 = SteadyTime::now();
    session_start_ns_ = clock_.now_ns();
    summary_.session_id = session_id_;
    summary_.trials_planned = static_cast<std::int64_t>(design_.trials.size());
    // One entry per frame: reserved up front so the frame loop does not grow it.
    cpu_ns_.reserve(static_cast<std::size_t>(design_.estimated_duration_ms() * p_.refresh_hz / 1000) + 1024);
    try {
      const Outcome outcome = run_trials(first, start_pages);
      end_session(outcome == Outcome::done ? data::SessionStatus::completed : data::SessionStatus::interrupted);
    } catch (const Stop& stop) {
      return interrupted(stop.error);
    } catch (const std::exception& e) {
      // Device failures (DeviceFailure: a Vulkan or OpenXR call, named
      // with its result) and anything else thrown from the frame loop.
      return interrupted(Error{Error::Kind::api, e.what()});
    }
    summarize(wall0);
    return summary_;
  }

 private:
  // ---- the session: pages, blocks, breaks, trials ------------------------

  Outcome run_trials(std::size_t first, bool start_pages) {
    first_reported_ = static_cast<std::int64_t>(first);
    // Pages are shown in the scene of the trial that follows them (the
    // first here, the previous one later): each trial prepares its own.
    prepare(design_.trials[std::min(first, design_.trials.size() - 1)].settings);
    if (start_pages && pages(p_.instructions_start, Phase::instructions, 0, std::nullopt) == Outcome::quit)
      return Outcome::quit;
    for (std::size_t i = first; i < design_.trials.size(); ++i) {
      const PlannedTrial& t = design_.trials[i];
      if (enter_block(i, first) == Outcome::quit || take_break(i, first) == Outcome::quit) return Outcome::quit;
      if (const auto reason = skip_reason(t)) {
        writer_.journal(data::EndUnanswered{trial_ids_[i], false, *reason});
        ++summary_.trials_skipped;
        report_trial(i, data::TrialStatus::skipped, *reason);
        continue;
      }
      if (run_trial(i) == Outcome::quit) return Outcome::quit;
      progress_.update(progress_point());
    }
    return pages(p_.instructions_end, Phase::done, 0, std::nullopt);
  }

  Outcome enter_block(std::size_t i, std::size_t first) {
    const PlannedTrial& t = design_.trials[i];
    if (block_position_ == t.block_position) return Outcome::done;
    block_position_ = t.block_position;
    const auto& pb = design_.blocks.at(t.block_position);
    event(std::nullopt, data::events::BlockStart{pb.name, static_cast<std::int64_t>(t.block_position)});
    if (t.trial_in_block != 0 && i != first) return Outcome::done;
    return pages(pb.instructions, Phase::instructions, 0, std::nullopt);
  }

  Outcome take_break(std::size_t i, std::size_t first) {
    const PlannedTrial& t = design_.trials[i];
    if (!t.break_before || i == first) return Outcome::done;
    const auto& b = block_of(p_, t);
    return pages({b.break_text.empty() ? std::string("Break") : b.break_text}, Phase::break_page,
                 b.break_min_ms * 1'000'000, trial_ids_[i]);
  }

  // A slot an adaptive method no longer needs (a stopped staircase's).
  std::optional<std::string> skip_reason(const PlannedTrial& t) {
    const protocol::AdaptiveState* state = adaptive_for(t);
    return state ? state->skip_reason(t) : std::nullopt;
  }

  void end_session(data::SessionStatus status) {
    event(std::nullopt, data::events::SessionEnd{status});
    show_ended();
    // The writer applies an entry after the samples pushed before it: once
    // the closing status is durable, so is everything the session logged.
    const auto ticket = writer_.journal(data::StatusChange{session_id_, status, true});
    check(writer_.wait_durable(ticket));
    summary_.status = status;
  }

  // Leaves the session resumable: completed trials are on disk already.
  RunResult interrupted(const Error& error) {
    show_ended();
    // The writer retries what failed; the reserve's space lets it finish.
    if (error.kind == Error::Kind::disk_full && lock_ != nullptr) lock_->free_reserve();
    const auto ticket = writer_.journal(data::StatusChange{session_id_, data::SessionStatus::interrupted, false});
    if (!writer_.wait_durable(ticket, std::chrono::seconds(5)))
      (void)store_.set_session_status(session_id_, data::SessionStatus::interrupted);
    const std::string id = std::to_string(session_id_);
    return Error{error.kind, error.message + " (session " + id + " stopped before the end; continue it with: " +
                                 "curvlab resume --db " + store_.path() + " --session " + id + ")"};
  }

  void summarize(SteadyTime::time_point wall0) {
    summary_.wall_s = std::chrono::duration<double>(SteadyTime::now() - wall0).count();
    summary_.session_s = static_cast<double>(clock_.now_ns() - session_start_ns_) * 1e-9;
    summary_.samples_dropped = writer_.stats().dropped_tracking + writer_.stats().dropped_frames;
    if (!cpu_ns_.empty()) {
      std::sort(cpu_ns_.begin(), cpu_ns_.end());
      summary_.frame_cpu_median_ms = static_cast<double>(cpu_ns_[cpu_ns_.size() / 2]) * 1e-6;
      summary_.frame_cpu_p95_ms = static_cast<double>(cpu_ns_[cpu_ns_.size() * 95 / 100]) * 1e-6;
    }
    if (auto completed = store_.count_trials(session_id_, data::TrialStatus::completed))
      summary_.trials_completed = completed.value();
  }

  template <class T>
  T check(Result<T> r) {
    if (!r) throw Stop{r.error()};
    return std::move(r).value();
  }

  void event(std::optional<std::int64_t> trial_id, const data::Event& e) {
    writer_.journal(data::event_record(session_id_, trial_id, clock_.now_ns(), e));
  }

  // The adaptive state of the trial's condition (block and cell); null when
  // its judgement type is not adaptive.
  protocol::AdaptiveState* adaptive_for(const PlannedTrial& t) {
    const auto key = std::pair{t.block_position, t.cell};
    auto it = adaptive_.find(key);
    if (it == adaptive_.end()) {
      const auto& j = block_of(p_, t).judgement;
      it = adaptive_.emplace(key, j.type->adaptive_state(j)).first;
    }
    return it->second.get();
  }

  // A resumed run replays the committed answers of adaptive trials, in order.
  void restore_adaptive(const std::vector<std::pair<std::int64_t, bool>>& history) {
    std::map<std::int64_t, std::size_t> index_of;
    for (std::size_t i = 0; i < trial_ids_.size(); ++i) index_of[trial_ids_[i]] = i;
    for (const auto& [trial_id, positive] : history) {
      const auto it = index_of.find(trial_id);
      if (it == index_of.end()) continue;
      const auto& t = design_.trials[it->second];
      if (auto* state = adaptive_for(t)) state->record(t, positive);
    }
  }

  // World, tracker and scene for these settings (the tracker is kept while
  // the world stays the same, so the edge correspondence carries over).
  void prepare(const Settings& s) {
    auto made = make_world(s);
    if (!made) throw Stop{{made.error().kind, "impossible table: " + made.error().message}};
    World world = std::move(made).value();
    if (!tracker_ || !world_ || !world_->same_as(world) || tracker_->algorithm() != s.tracking) {
      tracker_ = geometry::make_tracker(s.tracking, world.space, world.table, physical_table(s, options_.calibration));
      if (tracker_ && last_lab_) tracker_->update(*last_lab_);
    }
    world_ = world;
    settings_ = s;
    std::string prompt;
    if (current_trial_) prompt = block_of(p_, design_.trials[*current_trial_]).judgement.prompt;
    auto built = TrialScene::build(*world_, settings_, prompt, font());
    if (!built) throw Stop{built.error()};
    scene_.emplace(std::move(built).value());
  }

  std::string font() const {
    return options_.font_path.empty() ? std::string(CURVLAB_DEFAULT_FONT) : options_.font_path;
  }
  double ipd() const { return options_.ipd_m.value_or(settings_.viewing.ipd_m); }
  Isometry head() const { return tracker_ ? tracker_->output().pose[0] : Isometry::identity(); }

  // ---- one frame ---------------------------------------------------------

  struct Frame {
    io::FrameTiming timing;
    std::vector<io::InputEvent> inputs;
    Signal signal = Signal::none;
    bool head_tracked = false;
    SteadyTime::time_point started;

    [[nodiscard]] FrameFacts facts() const {
      return {timing.now_ns, timing.predicted_display_ns, head_tracked, signal};
    }
  };

  // Begins a frame: timing, poses, tracking, input (with the observer's key
  // presses that are due). false: the display has ended the session.
  bool begin(Frame& f) {
    auto timing = station_.display->begin_frame();
    if (!timing) return false;
    f.started = SteadyTime::now();
    f.timing = *timing;
    lab_ = station_.poses->poses(f.timing);
    // A pose no lab can hold (NaN, inf, 1e308 m) is lost tracking, stored as
    // such, and never reaches the tracker (lab_volume.hpp).
    for (auto& pose : lab_.pose) pose = possible_pose(pose);
    last_lab_ = lab_;
    if (tracker_) tracker_->update(lab_);
    f.head_tracked = head_meets(settings_.tracking_loss.head_requires, tracker_ && tracker_->output().tracked[0],
                                station_.poses->head_tracking());
    f.inputs.clear();
    f.signal = poll_devices(f.inputs);
    store_display_reports();
    take_operator_actions(f);
    take_stop_signal(f);
    return true;
  }

  // This frame's inputs from every response source, the simulated observer's
  // last, and one signal: the display's and the sources' in that order,
  // those after the first kept for the next frames; a quit outranks them all.
  io::Signal poll_devices(std::vector<io::InputEvent>& inputs) {
    auto keep = [this](io::Signal s) {
      if (s != io::Signal::none) device_signals_.push_back(s);
    };
    keep(station_.display->poll_signal());
    for (io::ResponseSource* source : station_.responses) keep(source->poll(inputs));
    keep(observer_keys_.poll(inputs));
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
  void store_display_reports() {
    reports_.clear();
    station_.display->take_reports(reports_);
    if (reports_.empty()) return;  // nearly every frame
    const std::optional<std::int64_t> trial_id =
        current_trial_ ? std::optional<std::int64_t>(trial_ids_[*current_trial_]) : std::nullopt;
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

  // Ends a frame: draw (or plan), then log the frame and its samples.
  renderer::FrameStats end(Frame& f, const io::Overlay& overlay, bool onset, std::optional<std::int64_t> trial_id) {
    renderer::FrameDescription desc;
    desc.space = world_->space;
    desc.settings = view_settings(settings_, dominant_);
    desc.head = head();
    desc.rig = station_.display->rig(f.timing, ipd());
    desc.width_px = static_cast<std::uint32_t>(p_.resolution_width);
    desc.height_px = static_cast<std::uint32_t>(p_.resolution_height);
    const bool draw = options_.drawing == FrameDrawing::all || (options_.drawing == FrameDrawing::onset && onset);
    if (tracker_) scene_->update(f.timing.predicted_display_ns, tracker_->output());
    const auto before_submit = SteadyTime::now();
    const renderer::FrameStats stats = station_.display->submit(scene_->scene(), desc, overlay, draw);
    const auto after_submit = SteadyTime::now();
    log_frame(f, stats, trial_id, desc.rig);
    const auto own = std::chrono::duration_cast<std::chrono::nanoseconds>((before_submit - f.started) +
                                                                          (SteadyTime::now() - after_submit));
    cpu_ns_.push_back(own.count() + static_cast<std::int64_t>(stats.cpu_ms * 1e6));
    ++summary_.frames;
    ++frame_index_;
    if (f.timing.late) {
      ++late_trial_;
      ++late_session_;
    }
    if (console_) show_status(f, stats, overlay.phase, own.count());
    progress_.tick(progress_point());
    return stats;
  }

  // Where the session stands: the trial running (or the last one ended),
  // the trials ended in this run and those left.
  ProgressPoint progress_point() const {
    const auto total = static_cast<std::int64_t>(design_.trials.size());
    const std::int64_t ended_all = first_reported_ + trials_reported_;
    ProgressPoint p;
    p.trial = current_trial_ ? static_cast<std::int64_t>(*current_trial_) + 1
                             : std::max<std::int64_t>(1, ended_all);
    p.total = total;
    p.ended = trials_reported_;
    p.left = total - ended_all;
    p.block = status_.block;
    return p;
  }

  // A SIGINT, SIGTERM or SIGHUP ends the session as the operator's end does:
  // interrupted, flushed, resumable.
  // So does standard output closed under --progress json (its reader
  // gone), stored as the signal a broken pipe would have sent.
  void take_stop_signal(Frame& f) {
    const int sig = output_lost_ ? kBrokenPipe
                    : options_.stop_signal != nullptr ? options_.stop_signal->load(std::memory_order_relaxed)
                                                      : 0;
    if (sig == 0) return;
    summary_.output_lost = output_lost_;
    if (!stop_logged_) {
      event(std::nullopt, data::events::Signal{sig});
      stop_logged_ = true;
    }
    f.signal = Signal::quit;
  }

  // ---- the operator's console ---------------------------------------------

  // Actions due now: each logged with its time stamp, notes stored verbatim;
  // the others become this frame's signal (or a later frame's, when the
  // backend already gave one), handled as a backend's signal would be.
  void take_operator_actions(Frame& f) {
    if (console_ == nullptr) return;
    actions_.clear();
    console_->take(f.timing.now_ns - session_start_ns_, actions_);
    for (const auto& a : actions_) carry_out(a);
    if (f.signal == Signal::none && !operator_signals_.empty()) {
      f.signal = operator_signals_.front();
      operator_signals_.pop_front();
    }
  }

  void carry_out(const OperatorAction& a) {
    const std::optional<std::int64_t> trial_id =
        current_trial_ ? std::optional<std::int64_t>(trial_ids_[*current_trial_]) : std::nullopt;
    data::events::OperatorAction action{std::string(to_string(a.kind)), a.source, clock_.now_ns(), std::nullopt};
    if (a.kind == OperatorActionKind::note) action.text = a.text;
    event(trial_id, action);
    if (const auto signal = operator_signal(a.kind)) operator_signals_.push_back(*signal);
    console_->acted(a);
  }

  static std::optional<Signal> operator_signal(OperatorActionKind kind) {
    switch (kind) {
      case OperatorActionKind::pause: return Signal::pause;
      case OperatorActionKind::resume: return Signal::resume;
      case OperatorActionKind::recenter: return Signal::recenter;
      case OperatorActionKind::repeat: return Signal::repeat;
      case OperatorActionKind::skip: return Signal::skip;
      case OperatorActionKind::end: return Signal::quit;
      case OperatorActionKind::note: return std::nullopt;
    }
    return std::nullopt;
  }

  void show_status(const Frame& f, const renderer::FrameStats& stats, Phase phase, std::int64_t own_ns) {
    status_.phase = phase;
    status_.phase_left_ns = phase_left_ns_;
    phase_left_ns_ = -1;
    status_.paused = phase == Phase::paused;
    status_.elapsed_ns = f.timing.now_ns - session_start_ns_;
    // The time per trial so far, for the trials still to run.
    if (trials_reported_ > 0)
      status_.remaining_ns = (f.timing.now_ns - session_start_ns_) / trials_reported_ *
                             (status_.trials - trials_reported_ - first_reported_);
    for (std::size_t d = 0; d < 3; ++d) {
      const bool tracked = lab_.pose[d].valid;
      if (!tracked && lost_since_[d] < 0) lost_since_[d] = f.timing.now_ns;
      if (tracked) lost_since_[d] = -1;
      status_.tracked[d] = tracked;
      status_.lost_ns[d] = tracked ? -1 : f.timing.now_ns - lost_since_[d];
    }
    status_.late_trial = late_trial_;
    status_.late_session = late_session_;
    status_.cpu_ms = stats.cpu_ms + static_cast<double>(own_ns) * 1e-6;
    status_.gpu_ms = stats.gpu_ms > 0.0 ? stats.gpu_ms : -1.0;
    const auto ws = writer_.stats();
    status_.logger_drops = ws.dropped_tracking + ws.dropped_frames + ws.dropped_gaze;
    status_.logger_lock_wait_s = writer_.lock_wait_s();
    console_->show(status_);
  }

  void show_ended() {
    if (console_ == nullptr) return;
    status_.ended = true;
    status_.phase = Phase::done;
    status_.phase_left_ns = -1;
    console_->show(status_);
  }

  // One line of --progress json per trial, however it ended.
  void report_trial(std::size_t i, data::TrialStatus status, const std::string& reason) {
    ++trials_reported_;
    const PlannedTrial& t = design_.trials[i];
    if (!progress_.json()) return;
    Json line{{"trial", i + 1},
              {"of", design_.trials.size()},
              {"trial_id", trial_ids_[i]},
              {"block", t.block},
              {"status", data::to_string(status)}};
    Json levels = Json::object();
    for (const auto& [f, l] : t.levels) levels[f] = l;
    line["conditions"] = levels;
    if (!reason.empty()) line["end_reason"] = reason;
    if (status == data::TrialStatus::completed) {
      line["response"] = status_.last_response;
      line["rt_ms"] = status_.last_rt_ms >= 0.0 ? Json(status_.last_rt_ms) : Json(nullptr);
    }
    line["frames_late"] = late_trial_;
    line["elapsed_s"] = static_cast<double>(clock_.now_ns() - session_start_ns_) * 1e-9;
    if (!progress_.line(line.dump())) output_lost_ = true;
  }

  // Hands a record to the logger. Fast runs wait for the writer rather than
  // lose samples; real-time runs never wait (the writer counts the drop).
  template <class Push>
  void push(Push&& try_push) {
    if (try_push() || !options_.lossless_logging) return;
    for (int i = 0; i < 100; ++i) {
      check(writer_.flush());
      if (try_push()) return;
    }
  }

  data::TrackingSample sample(const Frame& f, std::int64_t trial_id, int d) const {
    const auto& out = tracker_->output();
    const auto& pose = lab_.pose[static_cast<std::size_t>(d)];
    static constexpr data::TrackedDevice devices[] = {data::TrackedDevice::head, data::TrackedDevice::left_hand,
                                                      data::TrackedDevice::right_hand};
    data::TrackingSample s;
    s.session_id = session_id_;
    s.trial_id = trial_id;
    s.frame_index = frame_index_;
    s.t_ns = f.timing.predicted_display_ns;
    s.device = devices[d];
    s.position_valid = pose.valid;
    s.orientation_valid = pose.valid || pose.orientation_valid;
    s.lab_position_m = {pose.position_m.x, pose.position_m.y, pose.position_m.z};
    s.lab_orientation_xyzw = {pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w};
    const auto& m = out.pose[static_cast<std::size_t>(d)].m;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) s.virtual_pose[static_cast<std::size_t>(c * 4 + r)] = m[c][r];
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

  // The frame record carries the eye geometry it was drawn with, so that
  // replay draws from what was recorded (the writer stores only changes).
  void log_frame(const Frame& f, const renderer::FrameStats& stats, std::optional<std::int64_t> trial_id,
                 const renderer::StereoRig& rig) {
    const std::int64_t tid = trial_id.value_or(-1);
    if (tracker_)
      for (int d = 0; d < geometry::kDeviceCount; ++d) {
        const auto s = sample(f, tid, d);
        push([&] { return writer_.push_tracking(s); });
      }
    data::FrameRecord fr;
    fr.session_id = session_id_;
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
    push([&] { return writer_.push_frame(fr); });
    if (const auto gaze = station_.poses->gaze()) {
      data::GazeSample g = gaze_record(*gaze);
      g.session_id = session_id_;
      g.trial_id = tid;
      g.frame_index = frame_index_;
      g.t_ns = f.timing.predicted_display_ns;
      push([&] { return writer_.push_gaze(g); });
    }
  }

  // ---- pages and holds: instructions, breaks, the end, pauses ------------

  Outcome pages(const std::vector<std::string>& texts, Phase phase, std::int64_t min_ns,
                std::optional<std::int64_t> trial_id) {
    for (std::size_t k = 0; k < texts.size(); ++k)
      if (page(texts[k], k, phase, min_ns, trial_id) == Outcome::quit) return Outcome::quit;
    scene_->show(Phase::iti, false);
    return Outcome::done;
  }

  Outcome page(const std::string& text, std::size_t k, Phase phase, std::int64_t min_ns,
               std::optional<std::int64_t> trial_id) {
    Frame f;
    if (!begin(f)) return Outcome::quit;
    // The protocol's text, then how to go on with the devices at hand.
    const std::string shown_text = continue_line_.empty() ? text : text + "\n\n" + continue_line_;
    if (auto shown = scene_->set_page(shown_text, head()); !shown) throw Stop{shown.error()};
    scene_->show(phase, false);
    Page state(f.timing.now_ns, min_ns, continues_);
    if (observer_params()) observer_keys_.press({f.timing.now_ns + min_ns + 300'000'000, "space"});
    event(trial_id, data::events::Page{page_event(phase), k, shown_text});
    const io::Overlay overlay{phase, shown_text, true};
    for (;;) {
      const bool advance = state.frame(f.timing.now_ns, f.inputs);
      if (f.signal == Signal::quit) return Outcome::quit;
      if (f.signal == Signal::pause) {
        // The page stays; keys pressed while paused or held from then do not count.
        if (hold(phase, trial_id) == Outcome::quit) return Outcome::quit;
        state.restart();
      } else {
        end(f, overlay, false, trial_id);
        if (advance) return Outcome::done;
      }
      if (!begin(f)) return Outcome::quit;
    }
  }

  // A pause outside a trial's attempt (pages, the inter-trial interval):
  // nothing to repeat; the session waits for the resume.
  Outcome hold(Phase phase, std::optional<std::int64_t> trial_id) {
    const std::int64_t from = clock_.now_ns();
    event(trial_id, data::events::Paused{std::string(to_string(phase))});
    if (wait_until_ready(AbortReason::pause, trial_id) == Outcome::quit) return Outcome::quit;
    event(trial_id, data::events::Unpaused{std::string(to_string(phase)),
                                           static_cast<double>(clock_.now_ns() - from) * 1e-6});
    return Outcome::done;
  }

  // After an abort: wait for the resume (pause) or for the head (otherwise),
  // so that one loss does not abort the trials after it as well. The head
  // is waited for at most [tracking] head_wait_ms: a headset that never
  // tracks what head_requires asks for stops the session, resumable.
  Outcome wait_until_ready(AbortReason reason, std::optional<std::int64_t> trial_id) {
    const bool paused = reason == AbortReason::pause;
    if (paused) writer_.journal(data::StatusChange{session_id_, data::SessionStatus::paused, false});
    scene_->show(Phase::iti, false);
    const io::Overlay overlay{paused ? Phase::paused : Phase::tracking_lost, "waiting", false};
    const std::int64_t since_ns = clock_.now_ns();
    for (;;) {
      Frame f;
      if (!begin(f)) return Outcome::quit;
      end(f, overlay, false, trial_id);
      if (f.signal == Signal::quit) return Outcome::quit;
      if (paused ? f.signal == Signal::resume : f.head_tracked) break;
      if (!paused && f.timing.now_ns - since_ns >= ms_to_ns(settings_.tracking_loss.head_wait_ms))
        throw Stop{head_never_came(reason)};
    }
    if (paused) writer_.journal(data::StatusChange{session_id_, data::SessionStatus::running, false});
    return Outcome::done;
  }

  Error head_never_came(AbortReason reason) const {
    const auto& policy = settings_.tracking_loss;
    std::string reported = station_.poses->describe_head_tracking();
    if (reported.empty()) reported = tracker_ && tracker_->output().tracked[0] ? "tracked" : "not tracked";
    char waited[32];
    std::snprintf(waited, sizeof waited, "%.3g s", static_cast<double>(policy.head_wait_ms) * 1e-3);
    return Error{Error::Kind::device,
                 "the head was not tracked as [tracking] head_requires = \"" +
                     std::string(to_string(policy.head_requires)) + "\" asks for " + waited +
                     " after the attempt ended (" + std::string(to_string(reason)) +
                     "); the headset reports the head " + reported +
                     ". Check the headset's tracking, or for a headset that tracks no position set "
                     "head_requires = \"orientation\""};
  }

  // ---- one trial -----------------------------------------------------------

  struct TrialRun {
    std::size_t index = 0;
    std::int64_t id = 0;
    const PlannedTrial* planned = nullptr;
    const protocol::Judgement* judgement = nullptr;
    Settings settings;
    std::optional<double> adaptive_value;  // the value an adaptive method shows
    std::string line;
    std::int64_t attempts = 0;  // attempts made so far, stored ones included
    std::int64_t aborts = 0;    // of which ended in a logged abort
  };

  struct AttemptRun {
    std::int64_t number = 1;
    std::optional<protocol::Adjustment> adjustment;
    Isometry head_at_onset;
    Placement placement;
    OnsetView onset_view;  // the eyes at onset (the image observer, the images' record)
    std::optional<std::pair<std::string, io::InputEvent>> answer;
    std::optional<AbortReason> abort;
    bool display_ended = false;  // begin_frame gave no frame: no abort event
    std::optional<std::int64_t> onset_ns;
    int lost_spells = 0;
    std::int64_t lost_ns = 0;
  };

  TrialRun start_trial(std::size_t i) {
    TrialRun t;
    t.index = i;
    t.id = trial_ids_[i];
    t.planned = &design_.trials[i];
    t.judgement = &block_of(p_, *t.planned).judgement;
    t.settings = t.planned->settings;
    t.line = trial_line(*t.planned);
    if (const auto* state = adaptive_for(*t.planned)) {
      t.adaptive_value = state->value(*t.planned);
      protocol::set_numeric_setting(t.settings, t.judgement->parameter, *t.adaptive_value);
    }
    if (!resumed_trial_started_) {
      // The first trial of a resumed run may have attempts stored already.
      t.attempts = first_trial_attempts_;
      t.aborts = first_trial_aborts_;
      resumed_trial_started_ = true;
    }
    current_trial_ = i;
    late_trial_ = 0;
    status_.block = t.planned->block;
    status_.trial = static_cast<std::int64_t>(i + 1);
    status_.condition.clear();
    for (const auto& [f, l] : t.planned->levels) status_.condition += f + "=" + l + "  ";
    return t;
  }

  Outcome run_trial(std::size_t i) {
    TrialRun t = start_trial(i);
    for (;;) {
      AttemptRun a = run_attempt(t);
      if (!a.abort) {
        complete(t, a);
        const Outcome o = inter_trial_interval(t);
        current_trial_.reset();
        if (o == Outcome::done) report_trial(t.index, data::TrialStatus::completed, "");
        return o;
      }
      if (a.display_ended) return Outcome::quit;
      event(t.id, data::events::TrialAborted{std::string(to_string(*a.abort)), a.number});
      if (*a.abort == AbortReason::quit) return Outcome::quit;
      ++t.aborts;
      if (*a.abort == AbortReason::skip) {
        skip(t);
        return Outcome::done;
      }
      // The operator's repeat starts again at once; the others wait for the
      // resume or for the head.
      if (*a.abort != AbortReason::repeat && wait_until_ready(*a.abort, t.id) == Outcome::quit) return Outcome::quit;
      if (after_abort(*a.abort, a.number, t.settings.tracking_loss) == AfterAbort::give_up) {
        give_up(t, *a.abort, a.number);
        return Outcome::done;
      }
      event(t.id, data::events::TrialRepeated{std::string(to_string(*a.abort))});
    }
  }

  void give_up(const TrialRun& t, AbortReason reason, std::int64_t attempts) {
    writer_.journal(data::EndUnanswered{t.id, true, std::string(to_string(reason))});
    event(t.id, data::events::TrialAbandoned{std::string(to_string(reason)), attempts});
    ++summary_.trials_aborted;
    current_trial_.reset();
    report_trial(t.index, data::TrialStatus::aborted, std::string(to_string(reason)));
  }

  // The operator's skip: stored `skipped` (end_reason "operator"), so a
  // resumed session never runs it again.
  void skip(const TrialRun& t) {
    writer_.journal(data::EndUnanswered{t.id, false, "operator"});
    event(t.id, data::events::TrialSkipped{"operator", t.attempts});
    ++summary_.trials_skipped;
    current_trial_.reset();
    report_trial(t.index, data::TrialStatus::skipped, "operator");
  }

  // A new attempt: the stimulus from its start values, the observer's
  // stream for (session, trial, attempt), the attempt counted in the store.
  AttemptRun begin_attempt(TrialRun& t) {
    AttemptRun a;
    a.number = ++t.attempts;
    status_.attempt = a.number;
    if (a.number > 1) ++summary_.attempts_repeated;
    const auto& j = *t.judgement;
    a.adjustment = j.type->adjustment(j, *t.planned);
    if (a.adjustment) protocol::set_numeric_setting(t.settings, j.parameter, a.adjustment->value());
    prepare(t.settings);
    writer_.journal(data::BeginTrial{t.id});
    if (const auto& base = observer_params()) {
      ObserverParams op = *base;
      op.seed = attempt_seed(base->seed, design_.seed, t.index, t.aborts + 1);
      observer_.emplace(op);
    }
    observer_keys_.clear();
    return a;
  }

  // What the pilot window shows beside the scene during an attempt: the
  // trial's line, the question and its answers (shown while the runner waits
  // for one). Made once per attempt; each frame sets only the phase and the
  // value (set_overlay_value).
  static io::Overlay attempt_overlay(const TrialRun& t) {
    io::Overlay o{Phase::fixation, t.line, false};
    const auto& j = *t.judgement;
    o.prompt = j.prompt;
    for (const auto& b : j.type->answer_bindings(j)) o.answers.push_back({b.answer, b.keys, b.buttons});
    return o;
  }

  // The value a method varies, as the overlay shows it: written again only
  // when it changed (an adjustment step), not every frame.
  static void set_overlay_value(io::Overlay& o, const TrialRun& t, const AttemptRun& a,
                                std::optional<double>& written) {
    std::optional<double> shown = t.adaptive_value;
    if (a.adjustment) shown = a.adjustment->value();
    if (!shown || shown == written) return;
    written = shown;
    char buf[64];
    std::snprintf(buf, sizeof buf, " = %.6g", *shown);
    o.value = t.judgement->parameter + buf;
  }

  AttemptRun run_attempt(TrialRun& t) {
    AttemptRun a = begin_attempt(t);
    Frame f;
    if (!begin(f)) {
      a.abort = AbortReason::quit;
      a.display_ended = true;
      return a;
    }
    Attempt state(t.settings.timeline, t.settings.tracking_loss, f.timing.now_ns);
    io::Overlay overlay = attempt_overlay(t);
    std::optional<double> value_written;
    scene_->place(place_stimulus(*world_, t.settings, head()), head());
    for (;;) {
      const AttemptStep step = state.advance(f.facts());
      if (step.abort) {
        a.abort = step.abort;
        break;
      }
      if (step.onset) present_onset(t, a, f);
      take_inputs(t, a, state, f);
      scene_->show(step.phase, t.settings.timeline.stimulus_during_response);
      overlay.phase = step.phase;
      overlay.waiting_for_input = step.phase == Phase::response || step.phase == Phase::stimulus;
      set_overlay_value(overlay, t, a, value_written);
      phase_left_ns_ = phase_left(state, step.phase, t.settings.timeline, f.timing.now_ns);
      const auto stats = end(f, overlay, step.onset, t.id);
      if (step.onset) log_onset(t, a, stats, f.timing.predicted_display_ns);
      if (state.over(f.timing.now_ns)) break;
      if (!begin(f)) {
        a.abort = AbortReason::quit;
        a.display_ended = true;
        break;
      }
    }
    state.finish(clock_.now_ns());
    a.onset_ns = state.onset_display_ns();
    a.lost_spells = state.loss().spells();
    a.lost_ns = state.loss().lost_ns();
    return a;
  }

  // Onset: the stimulus is placed once, from the head at this frame.
  void present_onset(const TrialRun& t, AttemptRun& a, const Frame& f) {
    a.head_at_onset = head();
    a.placement = place_stimulus(*world_, t.settings, a.head_at_onset);
    scene_->place(a.placement, a.head_at_onset);
    a.onset_view = {view_settings(t.settings, dominant_), a.head_at_onset, station_.display->rig(f.timing, ipd()),
                    static_cast<std::uint32_t>(p_.resolution_width), static_cast<std::uint32_t>(p_.resolution_height)};
    if (!observer_) {
      // Where the eyes are tracked, the human model's account of the
      // stimulus is stored with the onset all the same: its vergence demand
      // is what the measured vergence is compared with (docs/xr.md, "Eye
      // tracking").
      last_account_.reset();
      if (station_.poses->gaze())
        last_account_ = perceive(*world_, t.settings, a.placement, a.head_at_onset, ObserverParams{}).human;
      return;
    }
    auto answer = plan_answer(*observer_, *world_, *t.judgement, t.settings, a.placement, a.head_at_onset,
                              f.timing.now_ns, a.adjustment, read_onset(t, a));
    observer_keys_.replace(answer.plan.keys);
    last_perceived_ = answer.plan.perceived_m;
    last_account_ = answer.percept.human;
  }

  // The image observer's reading of the onset pair (nullopt for the others).
  std::optional<Percept> read_onset(const TrialRun& t, const AttemptRun& a) {
    if (observer_->params().model != ObserverModel::image) return std::nullopt;
    if (!onset_reader_) onset_reader_ = check(OnsetReader::create());
    return check(onset_reader_->read(*world_, t.settings, a.placement, a.onset_view, observer_->params()));
  }

  // Responses count from the onset's display to the end of the window; a
  // press before the stimulus was on the display is an anticipation.
  void take_inputs(TrialRun& t, AttemptRun& a, Attempt& state, const Frame& f) {
    for (const auto& in : f.inputs) {
      if (!in.pressed || a.answer) continue;
      const auto verdict = classify_input(*t.judgement, in.name, state.answerable(in.t_ns));
      switch (verdict.use) {
        case InputUse::ignored: break;
        case InputUse::early:
          event(t.id, data::events::EarlyInput{in.name, in.device, in.t_ns});
          break;
        case InputUse::choose:
          a.answer = std::pair{t.judgement->options[verdict.option].value, in};
          state.answered();
          break;
        case InputUse::increase:
        case InputUse::decrease:
          verdict.use == InputUse::increase ? a.adjustment->increase() : a.adjustment->decrease();
          protocol::set_numeric_setting(t.settings, t.judgement->parameter, a.adjustment->value());
          a.placement = place_stimulus(*world_, t.settings, a.head_at_onset);
          scene_->set_stimulus(t.settings, a.placement);
          event(t.id, data::events::Adjustment{a.adjustment->value(), frame_index_});
          break;
        case InputUse::confirm: {
          a.adjustment->confirm();
          char buf[64];
          std::snprintf(buf, sizeof buf, "%.9g", a.adjustment->value());
          a.answer = std::pair{std::string(buf), in};
          state.answered();
          break;
        }
      }
    }
  }

  void log_onset(const TrialRun& t, const AttemptRun& a, const renderer::FrameStats& stats,
                 std::int64_t display_ns) {
    data::events::Onset onset;
    onset.frame_index = frame_index_ - 1;
    onset.predicted_display_ns = display_ns;
    onset.attempt = a.number;
    onset.head_pose = pose16(a.head_at_onset);
    onset.stick_pose = pose16(a.placement.stick_pose);
    onset.views = stats.views;
    onset.draws = stats.draws;
    onset.stimulus_ms = t.settings.timeline.stimulus_ms;
    if (observer_) onset.perceived_sagitta_m = last_perceived_;
    if (last_account_) onset.percept_json = human_account_json(*last_account_);
    if (!options_.images_dir.empty() && options_.drawing != FrameDrawing::none) {
      // A trial run again (a later attempt, a resumed session, another
      // session into the same folder) gets trial_NNNN_2, …: none is replaced.
      char stem[32];
      std::snprintf(stem, sizeof stem, "trial_%04zu", t.index);
      const auto path = std::filesystem::path(options_.images_dir) / unused_stem(options_.images_dir, stem);
      const auto files = station_.display->save_frame(path.string());
      if (!files.empty()) check(write_onset_record(path.string() + ".json", *world_, t.settings, a.placement, a.onset_view));
      // The files' names, not the folder: a folder can name a person.
      std::vector<std::string> names;
      for (const auto& f : files) names.push_back(std::filesystem::path(f).filename().string());
      onset.images = std::move(names);
      summary_.images.insert(summary_.images.end(), files.begin(), files.end());
    }
    event(t.id, onset);
  }

  // The answer (or the timeout), the adaptive method's step and the lost tracking,
  // journalled; durable before the next trial starts.
  void complete(TrialRun& t, const AttemptRun& a) {
    if (a.lost_spells > 0) {
      event(t.id, data::events::TrackingFlagged{static_cast<double>(a.lost_ns) * 1e-6, a.lost_spells, a.number});
      ++summary_.trials_flagged;
    }
    data::TrialResult r;
    r.trial_id = t.id;
    r.onset_ns = *a.onset_ns;
    if (a.answer) {
      r.response = a.answer->first;
      r.response_ns = a.answer->second.t_ns;
      r.response_device = a.answer->second.device;
    } else {
      r.response = "timeout";
      r.response_ns = clock_.now_ns();
      r.response_device = "none";
    }
    if (t.adaptive_value && a.answer) {
      auto& state = *adaptive_for(*t.planned);
      const auto step = state.record(*t.planned, state.positive(a.answer->first));
      r.staircase_step = data::StaircaseStep{staircase_key(p_, *t.planned, step.track), step.step, step.value,
                                             step.positive, step.reversal, step.next_value,
                                             step_posterior(step.posterior)};
    }
    // A staircase's or an adjustment's value is stored with the trial.
    if (!t.judgement->parameter.empty()) r.stimulus_json = shown_stimulus_json(p_, *t.planned, t.settings);
    status_.last_response = r.response;
    status_.last_rt_ms = a.answer ? static_cast<double>(r.response_ns - r.onset_ns) * 1e-6 : -1.0;
    completed_ticket_ = writer_.journal(std::move(r));
  }

  // Nothing on screen. A pause here holds the session; the interval starts
  // again after it. The trial just completed is on disk before this returns.
  Outcome inter_trial_interval(const TrialRun& t) {
    std::int64_t iti_end = clock_.now_ns() + t.settings.timeline.iti_ms * 1'000'000;
    scene_->show(Phase::iti, false);
    for (;;) {
      Frame g;
      if (!begin(g)) return Outcome::quit;
      if (g.signal == Signal::pause) {
        if (hold(Phase::iti, t.id) == Outcome::quit) return Outcome::quit;
        scene_->show(Phase::iti, false);
        iti_end = clock_.now_ns() + t.settings.timeline.iti_ms * 1'000'000;
        continue;
      }
      phase_left_ns_ = std::max<std::int64_t>(0, iti_end - g.timing.now_ns);
      end(g, io::Overlay{Phase::iti, t.line, false}, false, std::nullopt);
      if (g.signal == Signal::quit) return Outcome::quit;
      // While another program holds the file's lock the inter-trial
      // interval lasts until the trial is on disk: frames go on, nothing
      // waits on the disk (data/sample_writer.hpp).
      if (g.timing.now_ns >= iti_end && (writer_.durable(completed_ticket_) || writer_.lock_wait_s() == 0.0)) break;
    }
    check(writer_.wait_durable(completed_ticket_));
    return Outcome::done;
  }

  const std::optional<ObserverParams>& observer_params() const { return options_.observer; }

  const protocol::Protocol& p_;
  protocol::Design design_;
  data::SessionStore& store_;
  data::SampleWriter& writer_;
  data::WriterLock* lock_;
  io::Station station_;
  const devices::Clock& clock_;
  ObserverKeys observer_keys_{clock_};
  std::vector<std::string> continues_ = page_continues(p_);  // inputs that turn pages
  std::string continue_line_;  // under every page
  RunOptions options_;
  std::int64_t session_id_;
  std::vector<std::int64_t> trial_ids_;
  std::int64_t frame_index_;
  std::int64_t first_trial_attempts_ = 0;
  std::int64_t first_trial_aborts_ = 0;
  bool resumed_trial_started_ = false;
  Progress progress_;
  std::optional<SimulatedObserver> observer_;
  std::unique_ptr<OnsetReader> onset_reader_;  // --observer image only
  renderer::Eye dominant_ = renderer::Eye::right;
  std::pair<std::uint32_t, std::uint32_t> eye_size_;  // each eye's image as the display draws it
  // Adaptive types' state per (block position, cell); null for the others.
  std::map<std::pair<std::size_t, std::size_t>, std::unique_ptr<protocol::AdaptiveState>> adaptive_;
  std::optional<World> world_;
  Settings settings_;
  std::unique_ptr<geometry::Tracker> tracker_;
  std::optional<TrialScene> scene_;
  std::optional<std::size_t> current_trial_;
  std::vector<io::DisplayReport> reports_;  // this frame's, reused
  std::optional<std::size_t> block_position_;
  geometry::LabFrame lab_;
  std::optional<geometry::LabFrame> last_lab_;
  double last_perceived_ = 0.0;
  std::optional<HumanAccount> last_account_;  // the human model's, at the last onset
  std::uint64_t completed_ticket_ = 0;
  std::int64_t session_start_ns_ = 0;
  std::vector<std::int64_t> cpu_ns_;
  SessionSummary summary_;
  OperatorConsole* console_ = nullptr;
  std::vector<OperatorAction> actions_;          // this frame's, reused
  std::deque<Signal> operator_signals_;  // not yet handed to the loop
  std::deque<io::Signal> device_signals_;  // raised, not yet handed to the loop
  bool stop_logged_ = false;
  bool output_lost_ = false;  // a --progress json line could not be written
  OperatorStatus status_;
  std::int64_t phase_left_ns_ = -1;  // for the next status; set before end()
  std::array<std::int64_t, 3> lost_since_{-1, -1, -1};
  std::int64_t late_trial_ = 0;
  std::int64_t late_session_ = 0;
  std::int64_t trials_reported_ = 0;  // ended in this run
  std::int64_t first_reported_ = 0;   // ended before it (a resumed run)
};

SessionLoop::SessionLoop(SessionSetup setup) : impl_(std::make_unique<Impl>(std::move(setup))) {}
SessionLoop::~SessionLoop() = default;
RunResult SessionLoop::run(std::size_t first, bool start_pages) { return impl_->run(first, start_pages); }

}  // namespace curvlab::harness::runner
