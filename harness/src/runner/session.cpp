#include "curvlab/harness/runner/session.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/sample_writer.hpp"
#include "curvlab/harness/data/session_store.hpp"
#include "curvlab/harness/data/sqlite.hpp"
#include "curvlab/harness/protocol/adjustment.hpp"
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/staircase.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/harness/runner/view_record.hpp"
#include "curvlab/harness/version.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <unistd.h>

namespace curvlab::harness::runner {

using Json = nlohmann::ordered_json;
using geometry::Isometry;
using protocol::Design;
using protocol::JudgementType;
using protocol::PlannedTrial;
using protocol::Protocol;
using protocol::Settings;
using SteadyTime = std::chrono::steady_clock;

std::optional<FrameDrawing> parse_frame_drawing(std::string_view text) {
  if (text == "all") return FrameDrawing::all;
  if (text == "onset") return FrameDrawing::onset;
  if (text == "none") return FrameDrawing::none;
  return std::nullopt;
}

namespace {

const protocol::Block& block_of(const Protocol& p, const std::string& name) {
  for (const auto& b : p.blocks)
    if (b.name == name) return b;
  return p.blocks.front();  // unreachable for a design of p
}

// Staircases are named uniquely within a session: the block, the cell when
// the block has several, and the staircase's own name.
std::string staircase_key(const Protocol& p, const PlannedTrial& t) {
  const auto& b = block_of(p, t.block);
  std::string key = t.block + ":";
  if (protocol::block_cells(p, b).size() > 1) key += "cell" + std::to_string(t.cell) + ":";
  return key + b.judgement.staircases.at(static_cast<std::size_t>(t.staircase)).name;
}

Json matrix_json(const Isometry& iso) {
  Json a = Json::array();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) a.push_back(iso.m[c][r]);
  return a;
}

data::Backend backend_kind(const std::string& name) {
  if (name == "desktop") return data::Backend::desktop;
  if (name == "xr") return data::Backend::xr;
  return data::Backend::headless;
}

bool is_continue(const std::string& name) {
  return name == "space" || name == "enter" || name == "return" || name == "continue";
}

// A progress line on stderr, redrawn in place.
class Progress {
 public:
  explicit Progress(bool on) : on_(on && isatty(STDERR_FILENO) != 0) {}
  void update(std::int64_t done, std::int64_t total, const std::string& block) {
    if (!on_ || total <= 0) return;
    const int width = 30;
    const auto filled = static_cast<int>(width * done / total);
    const double s = std::chrono::duration<double>(SteadyTime::now() - start_).count();
    std::fprintf(stderr, "\r[%s%s] %lld/%lld trials  %-16.16s %5.0f s", std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(width - filled), '.').c_str(),
                 static_cast<long long>(done), static_cast<long long>(total), block.c_str(), s);
    std::fflush(stderr);
    drawn_ = true;
  }
  ~Progress() {
    if (drawn_) std::fputc('\n', stderr);
  }

 private:
  bool on_;
  bool drawn_ = false;
  SteadyTime::time_point start_ = SteadyTime::now();
};

struct ScheduledKey {
  std::int64_t t_ns = 0;
  std::string name;
};

enum class Outcome { done, quit };

// Everything one run of the frame loop needs; lives for one run/resume.
class Session {
 public:
  Session(const Protocol& p, Design design, data::SessionStore& store, data::SampleWriter& writer,
          Backend& backend, const devices::Clock& clock, const RunOptions& options,
          std::int64_t session_id, std::vector<std::int64_t> trial_ids, std::int64_t frame_offset)
      : p_(p),
        design_(std::move(design)),
        store_(store),
        writer_(writer),
        backend_(backend),
        clock_(clock),
        options_(options),
        session_id_(session_id),
        trial_ids_(std::move(trial_ids)),
        frame_index_(frame_offset),
        progress_(options.progress) {
    if (options.observer) observer_.emplace(*options.observer);
    dominant_ = options.dominant_eye == data::DominantEye::left ? renderer::Eye::left : renderer::Eye::right;
    eye_size_ = eye_image_size(backend.info(), static_cast<std::uint32_t>(p.resolution_width),
                               static_cast<std::uint32_t>(p.resolution_height));
  }

  // Staircase state from the steps already committed (resume).
  std::optional<std::string> restore_staircases() {
    try {
      data::Statement s(store_.database().connection(),
                        "SELECT trial_id, response_correct FROM staircase_steps "
                        "WHERE session_id = ?1 ORDER BY step_id");
      s.bind(1, session_id_);
      std::map<std::int64_t, std::size_t> index_of;
      for (std::size_t i = 0; i < trial_ids_.size(); ++i) index_of[trial_ids_[i]] = i;
      while (s.step()) {
        const auto it = index_of.find(s.column_int(0));
        if (it == index_of.end() || s.is_null(1)) continue;
        const auto& t = design_.trials[it->second];
        if (t.staircase < 0) continue;
        staircases_for(t).at(static_cast<std::size_t>(t.staircase)).respond(s.column_int(1) != 0);
      }
    } catch (const data::SqliteFailure& f) {
      return std::string("cannot read the staircase steps: ") + f.what();
    }
    return std::nullopt;
  }

  RunResult run(std::size_t first, bool start_pages) {
    const auto wall0 = SteadyTime::now();
    session_start_ns_ = clock_.now_ns();
    summary_.session_id = session_id_;
    summary_.trials_planned = static_cast<std::int64_t>(design_.trials.size());
    // One entry per frame: reserved up front so the frame loop does not grow it.
    cpu_ns_.reserve(static_cast<std::size_t>(design_.estimated_duration_ms() * p_.refresh_hz / 1000) + 1024);
    Outcome outcome = Outcome::done;
    try {
      // Pages are shown in the scene of the trial that follows them (the
      // first here, the previous one later): each trial prepares its own.
      prepare(design_.trials[std::min(first, design_.trials.size() - 1)].settings);
      if (start_pages) outcome = pages(p_.instructions_start, "instructions", 0, std::nullopt);
      std::optional<std::size_t> block_position;
      for (std::size_t i = first; outcome == Outcome::done && i < design_.trials.size(); ++i) {
        const PlannedTrial& t = design_.trials[i];
        if (block_position != t.block_position) {
          block_position = t.block_position;
          const auto& pb = design_.blocks.at(t.block_position);
          event(std::nullopt, "block_start", Json{{"block", pb.name}, {"block_index", t.block_position}});
          if (t.trial_in_block == 0 || i == first) {
            outcome = pages(pb.instructions, "instructions", 0, std::nullopt);
            if (outcome == Outcome::quit) break;
          }
        }
        if (t.break_before && i != first) {
          const auto& b = block_of(p_, t.block);
          outcome = pages({b.break_text.empty() ? std::string("Break") : b.break_text}, "break",
                          b.break_min_ms * 1'000'000, trial_ids_[i]);
          if (outcome == Outcome::quit) break;
        }
        if (t.staircase >= 0 &&
            staircases_for(t).at(static_cast<std::size_t>(t.staircase)).finished()) {
          check(store_.skip_trial(trial_ids_[i]));
          ++summary_.trials_skipped;
          continue;
        }
        outcome = run_trial(i);
        progress_.update(static_cast<std::int64_t>(i + 1), summary_.trials_planned, t.block);
      }
      if (outcome == Outcome::done) outcome = pages(p_.instructions_end, "done", 0, std::nullopt);
      check(writer_.flush());
      const auto status = outcome == Outcome::done ? data::SessionStatus::completed
                                                   : data::SessionStatus::interrupted;
      event(std::nullopt, "session_end", Json{{"status", data::to_string(status)}});
      check(store_.close_session(session_id_, status));
      summary_.status = data::to_string(status);
    } catch (const RunError& e) {
      // Leave the session resumable: completed trials are committed.
      (void)store_.set_session_status(session_id_, data::SessionStatus::interrupted);
      return e;
    }
    summary_.wall_s = std::chrono::duration<double>(SteadyTime::now() - wall0).count();
    summary_.session_s = static_cast<double>(clock_.now_ns() - session_start_ns_) * 1e-9;
    summary_.samples_dropped = writer_.stats().dropped_tracking + writer_.stats().dropped_frames;
    if (!cpu_ns_.empty()) {
      std::sort(cpu_ns_.begin(), cpu_ns_.end());
      summary_.frame_cpu_median_ms = static_cast<double>(cpu_ns_[cpu_ns_.size() / 2]) * 1e-6;
      summary_.frame_cpu_p95_ms = static_cast<double>(cpu_ns_[cpu_ns_.size() * 95 / 100]) * 1e-6;
    }
    auto completed = store_.count_trials(session_id_, "completed");
    if (completed) summary_.trials_completed = completed.value();
    return summary_;
  }

 private:
  template <class T>
  T check(data::Expected<T> r) {
    if (!r) throw RunError{false, r.error().message};
    return std::move(r).value();
  }

  void event(std::optional<std::int64_t> trial_id, const std::string& kind, const Json& detail) {
    data::EventRecord e;
    e.session_id = session_id_;
    e.trial_id = trial_id;
    e.t_ns = clock_.now_ns();
    e.kind = kind;
    e.detail_json = detail.dump();
    check(store_.record_event(e));
  }

  protocol::InterleavedStaircases& staircases_for(const PlannedTrial& t) {
    const auto key = std::pair{t.block_position, t.cell};
    auto it = staircases_.find(key);
    if (it == staircases_.end())
      it = staircases_.emplace(key, protocol::InterleavedStaircases(block_of(p_, t.block).judgement.staircases)).first;
    return it->second;
  }

  // World, tracker and scene for these settings (the tracker is kept while
  // the world stays the same, so the edge correspondence carries over).
  void prepare(const Settings& s) {
    auto made = make_world(s);
    if (auto* e = std::get_if<std::string>(&made)) throw RunError{true, "impossible table: " + *e};
    World world = std::get<World>(made);
    const auto algorithm = tracking_algorithm(s);
    if (!tracker_ || !world_ || !world_->same_as(world) || tracker_->algorithm() != algorithm) {
      tracker_ = geometry::make_tracker(algorithm, world.space, world.table,
                                        physical_table(s, options_.calibration));
      if (tracker_ && last_lab_) tracker_->update(*last_lab_);
    }
    world_ = world;
    settings_ = s;
    rebuild_scene();
  }

  void rebuild_scene() {
    std::string prompt;
    if (current_trial_) prompt = block_of(p_, design_.trials[*current_trial_].block).judgement.prompt;
    auto built = TrialScene::build(*world_, settings_, prompt, font());
    if (auto* e = std::get_if<std::string>(&built)) throw RunError{false, *e};
    scene_.emplace(std::move(std::get<TrialScene>(built)));
  }

  std::string font() const {
    return options_.font_path.empty() ? std::string(CURVLAB_DEFAULT_FONT) : options_.font_path;
  }

  double ipd() const { return options_.ipd_m.value_or(settings_.viewing.ipd_m); }

  // ---- one frame ---------------------------------------------------------

  struct Frame {
    FrameTiming timing;
    std::vector<InputEvent> inputs;
    BackendSignal signal = BackendSignal::none;
    bool head_tracked = false;
    SteadyTime::time_point started;
  };

  // Begins a frame: timing, poses, tracking, input (with the observer's key
  // presses that are due). false: the backend has ended the session.
  bool begin(Frame& f) {
    auto timing = backend_.begin_frame();
    if (!timing) return false;
    f.started = SteadyTime::now();
    f.timing = *timing;
    lab_ = backend_.poses(f.timing);
    last_lab_ = lab_;
    if (tracker_) tracker_->update(lab_);
    f.head_tracked = tracker_ && tracker_->output().tracked[0];
    f.inputs.clear();
    f.signal = backend_.poll_input(f.inputs);
    while (!scheduled_.empty() && scheduled_.front().t_ns <= f.timing.now_ns) {
      f.inputs.push_back({scheduled_.front().t_ns, scheduled_.front().name, "observer", true});
      scheduled_.pop_front();
    }
    return true;
  }

  Isometry head() const { return tracker_ ? tracker_->output().pose[0] : Isometry::identity(); }

  // Ends a frame: draw (or plan), then log the frame and its samples.
  renderer::FrameStats end(Frame& f, const Overlay& overlay, bool draw,
                           std::optional<std::int64_t> trial_id) {
    renderer::FrameDescription desc;
    desc.space = world_->space;
    desc.settings = view_settings(settings_, dominant_);
    desc.head = head();
    desc.rig = backend_.rig(f.timing, ipd());
    desc.width_px = static_cast<std::uint32_t>(p_.resolution_width);
    desc.height_px = static_cast<std::uint32_t>(p_.resolution_height);
    const bool really_draw = options_.drawing == FrameDrawing::all ||
                             (options_.drawing == FrameDrawing::onset && draw);
    const auto before_submit = SteadyTime::now();
    const renderer::FrameStats stats = backend_.submit(scene_->scene(), desc, overlay, really_draw);
    const auto after_submit = SteadyTime::now();
    log_frame(f, stats, trial_id, desc.rig);
    const auto done = SteadyTime::now();
    const auto own = std::chrono::duration_cast<std::chrono::nanoseconds>((before_submit - f.started) +
                                                                          (done - after_submit))
                         .count();
    const auto cpu = own + static_cast<std::int64_t>(stats.cpu_ms * 1e6);
    cpu_ns_.push_back(cpu);
    ++summary_.frames;
    ++frame_index_;
    return stats;
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

  void log_frame(const Frame& f, const renderer::FrameStats& stats, std::optional<std::int64_t> trial_id,
                 const renderer::StereoRig& rig) {
    const std::int64_t tid = trial_id.value_or(-1);
    if (tracker_) {
      const auto& out = tracker_->output();
      const data::TrackedDevice devices[] = {data::TrackedDevice::head, data::TrackedDevice::left_hand,
                                             data::TrackedDevice::right_hand};
      for (int d = 0; d < geometry::kDeviceCount; ++d) {
        const auto& pose = lab_.pose[static_cast<std::size_t>(d)];
        data::TrackingSample s;
        s.session_id = session_id_;
        s.trial_id = tid;
        s.frame_index = frame_index_;
        s.t_ns = f.timing.predicted_display_ns;
        s.device = devices[d];
        s.position_valid = pose.valid;
        s.orientation_valid = pose.valid;
        s.lab_position_m = {pose.position_m.x, pose.position_m.y, pose.position_m.z};
        s.lab_orientation_xyzw = {pose.orientation.x, pose.orientation.y, pose.orientation.z,
                                  pose.orientation.w};
        s.has_virtual_pose = out.tracked[static_cast<std::size_t>(d)];
        const auto& m = out.pose[static_cast<std::size_t>(d)].m;
        for (int c = 0; c < 4; ++c)
          for (int r = 0; r < 4; ++r) s.virtual_pose[static_cast<std::size_t>(c * 4 + r)] = m[c][r];
        s.has_state = true;
        s.state.physical_edge = out.state.physical_edge;
        s.state.virtual_edge = out.state.virtual_edge;
        s.state.laps = out.state.physical_laps;
        s.state.anchor_fraction = out.state.anchor_fraction;
        if (d > 0) {
          const auto& c = out.coherence[static_cast<std::size_t>(d - 1)];
          s.state.coherence_error_m = c.error_m;
          s.state.coherence_error_rad = c.error_rad;
        }
        push([&] { return writer_.push_tracking(s); });
      }
    }
    data::FrameRecord fr;
    fr.session_id = session_id_;
    fr.trial_id = tid;
    fr.frame_index = frame_index_;
    fr.t_ns = f.timing.now_ns;
    fr.predicted_display_ns = f.timing.predicted_display_ns;
    fr.cpu_time_ns = static_cast<std::int64_t>(stats.cpu_ms * 1e6);
    fr.gpu_time_ns = stats.gpu_ms > 0.0 ? static_cast<std::int64_t>(stats.gpu_ms * 1e6) : -1;
    fr.views = stats.views;
    fr.passes = stats.reused ? 0 : stats.passes;
    fr.draws = stats.draws;
    fr.triangles = static_cast<std::int64_t>(stats.triangles);
    fr.has_view_geometry = true;
    fr.view_geometry = record_view_geometry(rig, eye_size_.first, eye_size_.second);
    push([&] { return writer_.push_frame(fr); });
  }

  // ---- pages: instructions, breaks, the end ------------------------------

  Outcome pages(const std::vector<std::string>& texts, const std::string& phase,
                std::int64_t min_ns, std::optional<std::int64_t> trial_id) {
    for (std::size_t k = 0; k < texts.size(); ++k) {
      Frame f;
      if (!begin(f)) return Outcome::quit;
      if (auto err = scene_->set_page(texts[k], head())) throw RunError{false, *err};
      scene_->show(phase, false);
      const std::int64_t shown_ns = f.timing.now_ns;
      if (observer_) scheduled_.push_back({shown_ns + min_ns + 300'000'000, "space"});
      event(trial_id, phase, Json{{"page", k}, {"text", texts[k]}});
      Overlay overlay{phase, texts[k], true};
      bool advance = false;
      bool first_frame = true;  // a key held from before the page does not count
      for (;;) {
        for (const auto& in : f.inputs)
          if (!first_frame && in.pressed && is_continue(in.name) && f.timing.now_ns - shown_ns >= min_ns)
            advance = true;
        first_frame = false;
        if (f.signal == BackendSignal::quit) return Outcome::quit;
        if (f.signal == BackendSignal::pause) {
          // The page stays; keys pressed while paused or held from then do not count.
          if (hold(phase, trial_id) == Outcome::quit) return Outcome::quit;
          advance = false;
          first_frame = true;
          if (!begin(f)) return Outcome::quit;
          continue;
        }
        end(f, overlay, false, trial_id);
        if (advance) break;
        if (!begin(f)) return Outcome::quit;
      }
    }
    scene_->show("", false);
    return Outcome::done;
  }

  // ---- one trial -----------------------------------------------------------

  std::string trial_line(std::size_t i) const {
    const auto& t = design_.trials[i];
    std::string line = t.block + "  trial " + std::to_string(t.trial_in_block + 1);
    for (const auto& [f, l] : t.levels) line += "  " + f + "=" + l;
    return line;
  }

  // Which option an input selects (choice and staircase), if any.
  static std::optional<std::size_t> option_for(const protocol::Judgement& j, const InputEvent& in) {
    for (std::size_t k = 0; k < j.options.size(); ++k) {
      const auto& o = j.options[k];
      if (std::find(o.keys.begin(), o.keys.end(), in.name) != o.keys.end() ||
          std::find(o.buttons.begin(), o.buttons.end(), in.name) != o.buttons.end())
        return k;
    }
    return std::nullopt;
  }

  static std::string key_for(const protocol::ResponseOption& o) {
    if (!o.keys.empty()) return o.keys.front();
    if (!o.buttons.empty()) return o.buttons.front();
    return o.value;
  }

  static std::string first_of(const std::vector<std::string>& keys, const std::vector<std::string>& buttons) {
    if (!keys.empty()) return keys.front();
    if (!buttons.empty()) return buttons.front();
    return {};
  }

  static bool listed(const std::vector<std::string>& a, const std::vector<std::string>& b,
                     const std::string& name) {
    return std::find(a.begin(), a.end(), name) != a.end() || std::find(b.begin(), b.end(), name) != b.end();
  }

  double judged_quantity(const Settings& s, const Placement& placement, const Isometry& head_pose) const {
    if (observer_->params().model == ObserverModel::physical) return physical_sagitta_m(s);
    return perceived_sagitta_m(*world_, s, placement, head_pose);
  }

  // Schedules the observer's answer for this trial.
  void observe(const protocol::Judgement& j, const Settings& s, const Placement& placement,
               const Isometry& head_at_onset, std::int64_t onset_ns,
               const std::optional<protocol::Adjustment>& adjustment) {
    if (!observer_) return;
    scheduled_.clear();
    const std::int64_t rt = observer_->response_time_ns();
    if (j.type != JudgementType::adjustment) {
      const double q = judged_quantity(s, placement, head_at_onset);
      const std::size_t k = observer_->choose(q, j.options.size());
      scheduled_.push_back({onset_ns + rt, key_for(j.options.at(k))});
      last_perceived_ = q;
      return;
    }
    const auto& a = *j.adjustment;
    auto perceived = [&](double x) {
      Settings s2 = s;
      protocol::set_numeric_setting(s2, a.parameter, x);
      const Placement p2 = place_stimulus(*world_, s2, head_at_onset);
      return judged_quantity(s2, p2, head_at_onset);
    };
    const double target = observer_->adjust(perceived, a.min, a.max);
    last_perceived_ = perceived(adjustment->value());
    // Coarse steps toward the target, then fine ones, then confirm.
    double v = adjustment->value();
    std::int64_t t = onset_ns + rt;
    const std::string up = first_of(a.keys_increase, a.buttons_increase);
    const std::string down = first_of(a.keys_decrease, a.buttons_decrease);
    int presses = 0;
    while (std::abs(target - v) > a.step / 2.0 && presses < 400) {
      const bool inc = target > v;
      scheduled_.push_back({t, inc ? up : down});
      v = std::clamp(v + (inc ? a.step : -a.step), a.min, a.max);
      t += 80'000'000;
      ++presses;
    }
    scheduled_.push_back({t + 200'000'000, first_of(a.keys_confirm, a.buttons_confirm)});
  }

  Outcome run_trial(std::size_t i) {
    const PlannedTrial& t = design_.trials[i];
    const std::int64_t trial_id = trial_ids_[i];
    const auto& block = block_of(p_, t.block);
    const auto& j = block.judgement;
    current_trial_ = i;
    Settings s = t.settings;
    std::optional<double> staircase_value;
    if (t.staircase >= 0) {
      staircase_value = staircases_for(t).at(static_cast<std::size_t>(t.staircase)).value();
      protocol::set_numeric_setting(s, j.parameter, *staircase_value);
    }
    const auto& tl = s.timeline;
    for (;;) {  // attempts
      std::optional<protocol::Adjustment> adjustment;
      if (j.type == JudgementType::adjustment && j.adjustment) {
        adjustment.emplace(*j.adjustment, t.adjustment_start.value_or(j.adjustment->start_min));
        protocol::set_numeric_setting(s, j.adjustment->parameter, adjustment->value());
      }
      prepare(s);
      const std::int64_t attempt = check(store_.begin_trial(trial_id));
      if (attempt > 1) ++summary_.attempts_repeated;
      if (observer_) {
        ObserverParams op = observer_->params();
        op.seed = protocol::mix_seed(op.seed ^ protocol::mix_seed((i << 8) + static_cast<std::uint64_t>(attempt)));
        observer_.emplace(op);
      }
      scheduled_.clear();
      const std::string line = trial_line(i);

      Frame f;
      if (!begin(f)) return Outcome::quit;
      const std::int64_t start_ns = f.timing.now_ns;
      scene_->place(place_stimulus(*world_, s, head()), head());
      // Tracking loss: how long the head has been untracked, and for
      // "flag", the spells past the threshold and their total length.
      const auto& loss = s.tracking_loss;
      std::int64_t untracked_since = -1;
      bool lost_spell = false;
      std::int64_t lost_ns = 0;
      int lost_spells = 0;
      std::optional<std::int64_t> onset_ns;
      std::int64_t onset_frame_time = 0;
      Isometry head_at_onset;
      Placement placement;
      std::optional<std::pair<std::string, InputEvent>> answer;
      bool aborted = false;
      std::string abort_reason;
      for (;;) {
        if (f.signal == BackendSignal::quit) {
          event(trial_id, "trial_aborted", Json{{"reason", "quit"}});
          return Outcome::quit;
        }
        if (f.signal == BackendSignal::pause || f.signal == BackendSignal::recenter) {
          aborted = true;
          abort_reason = f.signal == BackendSignal::pause ? "pause" : "recenter";
        }
        if (!f.head_tracked) {
          if (untracked_since < 0) untracked_since = f.timing.now_ns;
          if (f.timing.now_ns - untracked_since >= loss.loss_ms * 1'000'000) {
            if (loss.on_loss == protocol::OnTrackingLoss::flag) {
              lost_spell = true;
            } else {
              aborted = true;
              abort_reason = "tracking_lost";
            }
          }
        } else {
          if (lost_spell) {
            lost_ns += f.timing.now_ns - untracked_since;
            ++lost_spells;
            lost_spell = false;
          }
          untracked_since = -1;
        }
        if (aborted) break;

        const std::int64_t now = f.timing.now_ns;
        std::string phase;
        bool draw = false;
        if (!onset_ns && now - start_ns >= tl.fixation_ms * 1'000'000) {
          // Onset: the stimulus is placed once, from the head at this frame.
          head_at_onset = head();
          placement = place_stimulus(*world_, s, head_at_onset);
          scene_->place(placement, head_at_onset);
          onset_ns = f.timing.predicted_display_ns;
          onset_frame_time = now;
          draw = true;
          observe(j, s, placement, head_at_onset, now, adjustment);
        }
        if (!onset_ns) {
          phase = "fixation";
        } else if (now - onset_frame_time < tl.stimulus_ms * 1'000'000) {
          phase = "stimulus";
        } else {
          phase = "response";
        }
        // Responses count from onset to the end of the response window.
        for (const auto& in : f.inputs) {
          if (!in.pressed || answer) continue;
          if (!onset_ns || in.t_ns < *onset_ns) {
            // Pressed before the stimulus was on the display (during the
            // fixation, or in the onset frame before its display time):
            // an anticipation, logged but not an answer.
            event(trial_id, "early_input", Json{{"name", in.name}, {"device", in.device}, {"t_ns", in.t_ns}});
            continue;
          }
          if (j.type == JudgementType::adjustment) {
            const auto& a = *j.adjustment;
            if (listed(a.keys_increase, a.buttons_increase, in.name)) adjustment->increase();
            else if (listed(a.keys_decrease, a.buttons_decrease, in.name)) adjustment->decrease();
            else if (listed(a.keys_confirm, a.buttons_confirm, in.name)) {
              adjustment->confirm();
              char buf[64];
              std::snprintf(buf, sizeof buf, "%.9g", adjustment->value());
              answer = std::pair{std::string(buf), in};
              continue;
            } else {
              continue;
            }
            protocol::set_numeric_setting(s, a.parameter, adjustment->value());
            event(trial_id, "adjustment", Json{{"value", adjustment->value()}, {"frame_index", frame_index_}});
            placement = place_stimulus(*world_, s, head_at_onset);
            scene_->set_stimulus(s, placement);
          } else if (auto k = option_for(j, in)) {
            answer = std::pair{j.options[*k].value, in};
          }
        }
        scene_->show(phase, tl.stimulus_during_response);
        const Overlay overlay{phase, line, phase == "response" || phase == "stimulus"};
        const auto stats = end(f, overlay, draw, trial_id);
        if (draw) {
          Json detail{{"frame_index", frame_index_ - 1},
                      {"predicted_display_ns", *onset_ns},
                      {"attempt", attempt},
                      {"head_pose", matrix_json(head_at_onset)},
                      {"stick_pose", matrix_json(placement.stick_pose)},
                      {"views", stats.views},
                      {"draws", stats.draws}};
          if (observer_) detail["perceived_sagitta_m"] = last_perceived_;
          if (!options_.images_dir.empty() && options_.drawing != FrameDrawing::none) {
            char stem[32];
            std::snprintf(stem, sizeof stem, "trial_%04zu", i);
            const auto files = backend_.save_frame(
                (std::filesystem::path(options_.images_dir) / stem).string());
            detail["images"] = files;
            summary_.images.insert(summary_.images.end(), files.begin(), files.end());
          }
          event(trial_id, "onset", detail);
        }
        if (answer) break;
        if (onset_ns && now - onset_frame_time >= (tl.stimulus_ms + tl.response_ms) * 1'000'000) break;
        if (!begin(f)) return Outcome::quit;
      }

      if (aborted) {
        event(trial_id, "trial_aborted", Json{{"reason", abort_reason}, {"attempt", attempt}});
        // Wait for the head (or the resume) whatever comes next, so that one
        // loss does not abort the trials after it as well.
        if (auto o = wait_until_ready(abort_reason, trial_id); o == Outcome::quit) return o;
        const bool give_up =
            (abort_reason == "tracking_lost" && loss.on_loss == protocol::OnTrackingLoss::abort) ||
            (loss.max_attempts > 0 && attempt >= loss.max_attempts);
        if (!give_up) {
          event(trial_id, "trial_repeated", Json{{"reason", abort_reason}});
          continue;  // the same trial again, as a new attempt
        }
        check(store_.abort_trial(trial_id));
        event(trial_id, "trial_abandoned", Json{{"reason", abort_reason}, {"attempts", attempt}});
        ++summary_.trials_aborted;
        check(writer_.flush());
        current_trial_.reset();
        return Outcome::done;
      }
      if (lost_spell) {
        lost_ns += clock_.now_ns() - untracked_since;
        ++lost_spells;
      }
      if (lost_spells > 0) {
        event(trial_id, "tracking_flagged",
              Json{{"lost_ms", static_cast<double>(lost_ns) * 1e-6}, {"spells", lost_spells}, {"attempt", attempt}});
        ++summary_.trials_flagged;
      }

      data::TrialResult r;
      r.trial_id = trial_id;
      r.onset_ns = *onset_ns;
      if (answer) {
        r.response = answer->first;
        r.response_ns = answer->second.t_ns;
        r.response_device = answer->second.device;
      } else {
        r.response = "timeout";
        r.response_ns = clock_.now_ns();
        r.response_device = "none";
      }
      if (staircase_value && answer) {
        auto& stair = staircases_for(t).at(static_cast<std::size_t>(t.staircase));
        const int reversals = stair.reversals();
        const int step = stair.trials();
        const bool positive = answer->first == j.positive;
        stair.respond(positive);
        r.staircase_step = data::StaircaseStep{staircase_key(p_, t), step, *staircase_value, positive,
                                               stair.reversals() > reversals, stair.value()};
      }
      check(store_.complete_trial(r));

      // Inter-trial interval: nothing on screen. A pause here holds the
      // session; the interval starts again after it.
      std::int64_t iti_end = clock_.now_ns() + tl.iti_ms * 1'000'000;
      scene_->show("iti", false);
      for (;;) {
        Frame g;
        if (!begin(g)) return Outcome::quit;
        if (g.signal == BackendSignal::pause) {
          if (hold("iti", trial_id) == Outcome::quit) return Outcome::quit;
          scene_->show("iti", false);
          iti_end = clock_.now_ns() + tl.iti_ms * 1'000'000;
          continue;
        }
        end(g, Overlay{"iti", line, false}, false, std::nullopt);
        if (g.signal == BackendSignal::quit) return Outcome::quit;
        if (g.timing.now_ns >= iti_end) break;
      }
      check(writer_.flush());
      current_trial_.reset();
      return Outcome::done;
    }
  }

  // After an aborted attempt: wait for tracking (or the resume signal).
  // A pause outside a trial's attempt (instruction pages, breaks, the
  // inter-trial interval): nothing to repeat, the session waits for resume.
  Outcome hold(const std::string& phase, std::optional<std::int64_t> trial_id) {
    const std::int64_t from = clock_.now_ns();
    event(trial_id, "paused", Json{{"phase", phase}});
    if (wait_until_ready("pause", trial_id) == Outcome::quit) return Outcome::quit;
    event(trial_id, "unpaused", Json{{"phase", phase}, {"paused_ms", static_cast<double>(clock_.now_ns() - from) * 1e-6}});
    return Outcome::done;
  }

  Outcome wait_until_ready(const std::string& reason, std::optional<std::int64_t> trial_id) {
    if (reason == "pause") check(store_.set_session_status(session_id_, data::SessionStatus::paused));
    scene_->show("", false);
    for (;;) {
      Frame f;
      if (!begin(f)) return Outcome::quit;
      end(f, Overlay{reason, "waiting", false}, false, trial_id);
      if (f.signal == BackendSignal::quit) return Outcome::quit;
      const bool ready = reason == "pause" ? f.signal == BackendSignal::resume : f.head_tracked;
      if (ready) break;
    }
    if (reason == "pause") check(store_.set_session_status(session_id_, data::SessionStatus::running));
    return Outcome::done;
  }

  const Protocol& p_;
  Design design_;
  data::SessionStore& store_;
  data::SampleWriter& writer_;
  Backend& backend_;
  const devices::Clock& clock_;
  RunOptions options_;
  std::int64_t session_id_;
  std::vector<std::int64_t> trial_ids_;
  std::int64_t frame_index_;
  Progress progress_;
  std::optional<SimulatedObserver> observer_;
  renderer::Eye dominant_ = renderer::Eye::right;
  std::pair<std::uint32_t, std::uint32_t> eye_size_;  // each eye's image as the backend draws it
  std::map<std::pair<std::size_t, std::size_t>, protocol::InterleavedStaircases> staircases_;
  std::optional<World> world_;
  Settings settings_;
  std::unique_ptr<geometry::Tracker> tracker_;
  std::optional<TrialScene> scene_;
  std::optional<std::size_t> current_trial_;
  geometry::LabFrame lab_;
  std::optional<geometry::LabFrame> last_lab_;
  std::deque<ScheduledKey> scheduled_;
  double last_perceived_ = 0.0;
  std::int64_t session_start_ns_ = 0;
  std::vector<std::int64_t> cpu_ns_;
  SessionSummary summary_;
};

std::vector<data::BlockPlan> block_plans(const Protocol& p, const Design& d) {
  std::vector<data::BlockPlan> out;
  for (const auto& b : d.blocks) {
    data::BlockPlan bp;
    bp.name = b.name;
    bp.is_practice = b.practice;
    Json settings{{"instructions", b.instructions}, {"break_min_ms", b.break_min_ms}};
    bp.settings_json = settings.dump();
    for (std::size_t k = 0; k < b.trial_count; ++k) {
      const auto& t = d.trials.at(b.first_trial + k);
      bp.trials.push_back({conditions_json(p, t), stimulus_json(t)});
    }
    out.push_back(std::move(bp));
  }
  return out;
}

struct OpenedDb {
  std::optional<data::SessionStore> store;
  std::unique_ptr<data::SampleWriter> writer;
};

}  // namespace

std::string conditions_json(const Protocol& p, const PlannedTrial& t) {
  Json j;
  for (const auto& [factor, label] : t.levels) j[factor] = label;
  const auto& s = t.settings;
  auto add = [&](const char* key, const std::string& v) {
    if (!j.contains(key)) j[key] = v;
  };
  add("space", std::string(geometry::to_string(s.space.kind)));
  add("view", view_name(s));
  add("projection", std::string(protocol::to_string(s.viewing.projection)));
  add("eyes", std::string(protocol::to_string(s.viewing.eyes)));
  add("judged", judged(s) == Judged::stick ? "stick" : "table");
  if (t.staircase >= 0)
    add("staircase", block_of(p, t.block).judgement.staircases.at(static_cast<std::size_t>(t.staircase)).name);
  return j.dump();
}

std::string stimulus_json(const PlannedTrial& t) {
  const auto& s = t.settings;
  Json j;
  j["stick_sagitta_m"] = s.stimulus.stick_sagitta_m;
  j["table_sagitta_m"] = s.stimulus.table_sagitta_m;
  j["stick_length_m"] = s.stimulus.stick_length_m;
  j["stick_distance_m"] = s.stimulus.stick_distance_m;
  j["stick_height_m"] = s.stimulus.stick_height_m;
  j["stick_anchor"] = std::string(protocol::to_string(s.stimulus.stick_anchor));
  j["show_stick"] = s.stimulus.show_stick;
  j["show_table"] = s.stimulus.show_table;
  j["radius_m"] = t.derived.radius_m;
  j["table_sides"] = t.derived.table_sides;
  j["tracking"] = std::string(protocol::to_string(s.tracking));
  j["ipd_m"] = s.viewing.ipd_m;
  if (t.adjustment_start) j["adjustment_start"] = *t.adjustment_start;
  return j.dump();
}

RunResult run_session(const Protocol& p, const std::string& protocol_text, const std::string& db_path,
                      const RunOptions& options, Backend& backend, const devices::Clock& clock) {
  if (!data::valid_pseudonym(options.participant))
    return RunError{true, "--participant must be a pseudonym of 1-32 letters, digits, '_' or '-' (no names), got '" +
                              options.participant + "'"};
  if (options.participant_number < 1) return RunError{true, "the participant number must be at least 1"};
  if (options.observer)
    if (auto e = check_observer(*options.observer)) return RunError{true, "observer: " + *e};
  Design design = protocol::expand_design(p, options.participant_number);
  if (design.trials.empty()) return RunError{true, p.file + ": the design has no trials"};

  auto db = data::Database::open(db_path, data::OpenMode::create_or_open);
  if (!db) return RunError{false, db.error().message};
  data::SessionStore store(std::move(db).value());
  auto fail = [](const data::DataError& e) { return RunError{false, e.message}; };
  auto protocol_id = store.add_protocol(p.meta.name, protocol_text, p.file);
  if (!protocol_id) return fail(protocol_id.error());
  data::ParticipantRecord participant{options.participant, options.ipd_m, options.dominant_eye};
  auto participant_id = store.add_participant(participant);
  if (!participant_id) return fail(participant_id.error());
  const BackendInfo info = backend.info();
  data::SessionRecord rec;
  rec.protocol_id = protocol_id.value();
  rec.participant_id = participant_id.value();
  rec.software_version = std::string(software_version());
  rec.software_commit = std::string(git_commit());
  rec.backend = backend_kind(info.name);
  rec.renderer_device = info.renderer_device;
  rec.renderer_driver = info.renderer_driver;
  rec.display_refresh_hz = info.refresh_hz;
  rec.seed = static_cast<std::int64_t>(design.seed);
  const auto calibration = options.calibration.value_or(nominal_calibration(p.session_settings()));
  rec.table_calibration_json = calibration_json(calibration);
  auto session_id = store.create_session(rec);
  if (!session_id) return fail(session_id.error());
  auto ids = store.store_plan(session_id.value(), block_plans(p, design));
  if (!ids) return fail(ids.error());

  Json start{{"participant_number", options.participant_number},
             {"seed", design.seed},
             {"protocol_seed", design.protocol_seed},
             {"backend", info.name},
             {"trials", design.trials.size()}};
  if (design.counterbalance_row) start["counterbalance_row"] = *design.counterbalance_row;
  data::EventRecord e{session_id.value(), std::nullopt, clock.now_ns(), "session_start", start.dump()};
  if (auto r = store.record_event(e); !r) return fail(r.error());
  if (options.observer) {
    data::EventRecord o{session_id.value(), std::nullopt, clock.now_ns(), "observer",
                        observer_json(*options.observer)};
    if (auto r = store.record_event(o); !r) return fail(r.error());
  }
  auto writer = data::SampleWriter::open(db_path);
  if (!writer) return fail(writer.error());

  RunOptions o = options;
  o.calibration = calibration;
  Session session(p, std::move(design), store, *writer.value(), backend, clock, o, session_id.value(),
                  std::move(ids).value(), 0);
  auto result = session.run(0, true);
  if (auto* s = std::get_if<SessionSummary>(&result)) s->db_path = db_path;
  return result;
}

std::variant<StoredSession, RunError> read_stored_session(const std::string& db_path,
                                                          std::int64_t session_id) {
  if (!std::filesystem::exists(db_path)) return RunError{true, db_path + ": no such database"};
  auto db = data::Database::open(db_path, data::OpenMode::open_existing);
  if (!db) return RunError{false, db.error().message};
  StoredSession out;
  try {
    data::Statement s(db.value().connection(),
                      "SELECT pr.text, pr.source_path, p.pseudonym, se.seed, se.status, se.backend, "
                      "se.table_calibration FROM sessions se JOIN protocols pr ON pr.protocol_id = se.protocol_id "
                      "JOIN participants p ON p.participant_id = se.participant_id WHERE se.session_id = ?1");
    s.bind(1, session_id);
    if (!s.step())
      return RunError{true, db_path + ": no session with id " + std::to_string(session_id)};
    out.protocol_text = s.column_text(0);
    out.protocol_source = s.column_opt_text(1).value_or("stored protocol");
    out.participant = s.column_text(2);
    out.seed = s.column_int(3);
    out.status = s.column_text(4);
    out.backend = s.column_text(5);
    if (const auto text = s.column_opt_text(6)) {
      auto fit = parse_calibration_json(*text);
      if (auto* f = std::get_if<geometry::PhysicalTableFit>(&fit)) out.calibration = *f;
    }
    data::Statement last(db.value().connection(),
                         "SELECT MAX(COALESCE((SELECT MAX(t_ns) FROM frames WHERE session_id = ?1), 0), "
                         "COALESCE((SELECT MAX(t_ns) FROM events WHERE session_id = ?1), 0))");
    last.bind(1, session_id);
    if (last.step()) out.last_t_ns = last.column_int(0);
    data::Statement ev(db.value().connection(),
                       "SELECT kind, detail FROM events WHERE session_id = ?1 AND kind IN "
                       "('session_start', 'observer') ORDER BY event_id");
    ev.bind(1, session_id);
    bool found = false;
    while (ev.step()) {
      const Json d = Json::parse(ev.column_text(1), nullptr, false);
      if (d.is_discarded()) continue;
      if (ev.column_text(0) == "session_start") {
        out.participant_number = d.value("participant_number", std::uint64_t{1});
        found = true;
      } else {
        ObserverParams o;
        o.model = parse_observer_model(d.value("model", std::string("perception"))).value_or(ObserverModel::perception);
        o.bias_m = d.value("bias_m", 0.0);
        o.slope_per_m = d.value("slope_per_m", 300.0);
        o.lapse = d.value("lapse", 0.02);
        o.criterion_m = d.value("criterion_m", 0.006);
        o.rt_base_ms = d.value("rt_base_ms", 450.0);
        o.rt_mean_extra_ms = d.value("rt_mean_extra_ms", 250.0);
        o.seed = d.value("seed", std::uint64_t{1});
        out.observer = o;
      }
    }
    if (!found) return RunError{false, db_path + ": session " + std::to_string(session_id) +
                                          " has no session_start event; it cannot be resumed"};
  } catch (const data::SqliteFailure& f) {
    return RunError{false, db_path + ": " + f.what()};
  }
  return out;
}

RunResult resume_session(const std::string& db_path, std::int64_t session_id,
                         const StoredSession& stored, const Protocol& p, const RunOptions& options,
                         Backend& backend, const devices::Clock& clock) {
  if (stored.status == "completed")
    return RunError{true, db_path + ": session " + std::to_string(session_id) + " is already completed"};
  Design design = protocol::expand_design(p, stored.participant_number);
  if (static_cast<std::int64_t>(design.seed) != stored.seed)
    return RunError{false, "the stored seed does not match the re-expanded design"};

  auto db = data::Database::open(db_path, data::OpenMode::create_or_open);
  if (!db) return RunError{false, db.error().message};
  data::SessionStore store(std::move(db).value());
  std::vector<std::int64_t> ids;
  std::int64_t frame_offset = 0;
  try {
    data::Statement s(store.database().connection(),
                      "SELECT trial_id, conditions FROM trials WHERE session_id = ?1 ORDER BY trial_index");
    s.bind(1, session_id);
    std::size_t k = 0;
    while (s.step()) {
      if (k >= design.trials.size() || s.column_text(1) != conditions_json(p, design.trials[k]))
        return RunError{false, db_path + ": the stored trial list of session " + std::to_string(session_id) +
                                   " differs from its protocol's design at trial " + std::to_string(k)};
      ids.push_back(s.column_int(0));
      ++k;
    }
    if (ids.size() != design.trials.size())
      return RunError{false, db_path + ": session " + std::to_string(session_id) + " stores " +
                                 std::to_string(ids.size()) + " trials, its design has " +
                                 std::to_string(design.trials.size())};
    data::Statement fr(store.database().connection(),
                       "SELECT COALESCE(MAX(frame_index), -1) FROM frames WHERE session_id = ?1");
    fr.bind(1, session_id);
    if (fr.step()) frame_offset = fr.column_int(0) + 1;
  } catch (const data::SqliteFailure& f) {
    return RunError{false, db_path + ": " + f.what()};
  }
  auto next = store.next_incomplete_trial(session_id);
  if (!next) return RunError{false, next.error().message};
  std::size_t first = ids.size();
  if (next.value()) first = static_cast<std::size_t>(next.value()->trial_index);

  if (auto r = store.set_session_status(session_id, data::SessionStatus::running); !r)
    return RunError{false, r.error().message};
  Json detail{{"from_trial", first}, {"backend", backend.info().name}};
  data::EventRecord e{session_id, std::nullopt, clock.now_ns(), "resume", detail.dump()};
  if (auto r = store.record_event(e); !r) return RunError{false, r.error().message};
  auto writer = data::SampleWriter::open(db_path);
  if (!writer) return RunError{false, writer.error().message};

  RunOptions o = options;
  o.participant = stored.participant;
  o.participant_number = stored.participant_number;
  if (!o.observer) o.observer = stored.observer;
  if (!o.calibration) o.calibration = stored.calibration;
  Session session(p, std::move(design), store, *writer.value(), backend, clock, o, session_id,
                  std::move(ids), frame_offset);
  if (auto err = session.restore_staircases()) return RunError{false, *err};
  auto result = session.run(first, false);
  if (auto* s = std::get_if<SessionSummary>(&result)) s->db_path = db_path;
  return result;
}

}  // namespace curvlab::harness::runner
