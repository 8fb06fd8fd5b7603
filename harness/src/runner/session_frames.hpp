// The room every block kind runs its frames in (DESIGN.md §6): the session's
// devices, its world, tracker and scene, its logger, and the frame itself —
//   poses → tracking → input (begin) … scene → submit → log (end)
// — with the pages and holds every kind shows between its own frames
// (session_pages.cpp). What the operator sees and does lives in its own room
// (operator_room.hpp); the session level (session_loop.cpp) walks the blocks;
// each block kind (block_kind.hpp) decides what its frames show.
//
// Owned and used by the frame thread. Not copyable.
#pragma once

#include "operator_room.hpp"
#include "progress.hpp"
#include "session_loop.hpp"
#include "trial_watcher.hpp"

#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/harness/runner/trial_state.hpp"

#include <glm/mat4x4.hpp>

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace curvlab::harness::runner {

enum class Outcome { done, quit };

constexpr std::int64_t ms_to_ns(std::int64_t v) { return v * 1'000'000; }

// One frame between begin() and end().
struct Frame {
  io::FrameTiming timing;
  std::vector<io::InputEvent> inputs;
  Signal signal = Signal::none;
  bool head_tracked = false;
  std::chrono::steady_clock::time_point started;

  [[nodiscard]] FrameFacts facts() const {
    return {timing.now_ns, timing.predicted_display_ns, head_tracked, signal};
  }
};

// An isometry's 4×4 matrix as a stored virtual pose: column-major, as
// tracking_samples.virtual_pose and partner_samples.virtual_pose hold it.
inline void store_pose(const glm::dmat4& m, std::array<double, 16>& out) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) out[static_cast<std::size_t>(c * 4 + r)] = m[c][r];
}

class SessionFrames {
 public:
  explicit SessionFrames(SessionSetup& s);
  SessionFrames(const SessionFrames&) = delete;
  SessionFrames& operator=(const SessionFrames&) = delete;

  // ---- frames ----
  // Begins a frame: timing, poses, tracking, input, the operator's actions
  // and stop signals. false: the display has ended the session.
  bool begin(Frame& f);
  // Ends a frame: draw (or plan), then log the frame and its samples.
  renderer::FrameStats end(Frame& f, const io::Overlay& overlay, bool onset, std::optional<std::int64_t> trial_id);

  // ---- pages and holds (session_pages.cpp) ----
  // Pages of text, each shown until continued (after min_ns).
  Outcome pages(const std::vector<std::string>& texts, Phase phase, std::int64_t min_ns,
                std::optional<std::int64_t> trial_id);
  // A pause outside a trial's attempt: the session waits for the resume.
  Outcome hold(Phase phase, std::optional<std::int64_t> trial_id);
  // After an abort: wait for the resume (pause) or for the head (otherwise).
  Outcome wait_until_ready(AbortReason reason, std::optional<std::int64_t> trial_id);

  // ---- the world and what is drawn ----
  // World, tracker and scene for these settings (the tracker is kept while
  // the world stays the same, so the edge correspondence carries over);
  // `prompt`: what the response panel shows (response_panel()).
  void prepare(const protocol::Settings& s, const std::string& prompt);
  // The response panel's text for a judgement: its question and its answers
  // with the inputs that give them at this station.
  [[nodiscard]] std::string response_panel(const protocol::Judgement& j) const {
    return response_panel_text(j, reach_);
  }
  [[nodiscard]] const World& world() const { return *world_; }
  [[nodiscard]] TrialScene& scene() { return *scene_; }
  [[nodiscard]] geometry::Isometry head() const;
  // This frame's lab poses and the tracker's curved-space poses (null
  // before the first frame of a world).
  [[nodiscard]] const geometry::LabFrame& lab() const { return lab_; }
  [[nodiscard]] const geometry::TrackingOutput* tracking() const { return tracker_ ? &tracker_->output() : nullptr; }
  // The physical table the tracker anchors to (the calibration's, or the
  // protocol's table where there is none).
  [[nodiscard]] geometry::PhysicalTable physical_table() const;
  // Where set, the frames take the lab's poses from it instead of the
  // station's pose source (the simulated player walking round the table).
  std::function<geometry::LabFrame(const io::FrameTiming&)> lab_override;
  [[nodiscard]] double ipd() const { return options_.ipd_m.value_or(settings_.viewing.ipd_m); }
  [[nodiscard]] renderer::Eye dominant() const { return dominant_; }
  [[nodiscard]] std::int64_t frame_index() const { return frame_index_; }

  // A sample of this frame (partner_samples when `s.partner`): stamped with
  // the session, the frame's index and display time, and stored by the
  // sample writer with the frame's own.
  void log_sample(const Frame& f, std::int64_t trial_id, data::TrackingSample s);
  // ---- records ----
  // Stored, and streamed as a marker (session_markers.cpp) stamped with the
  // moment it describes: `moment_ns`, else the event's own time, else now.
  void event(std::optional<std::int64_t> trial_id, const data::Event& e,
             std::optional<std::int64_t> moment_ns = std::nullopt);
  // ---- markers for the lab's other instruments (session_markers.cpp) ----
  // The streams open and the session's start (or a resumed run's) is marked.
  void start_streams(bool resumed);
  // A marker of `kind` at `t_ns` (session clock) with a JSON object's text.
  void marker(std::int64_t t_ns, std::string_view kind, std::optional<std::int64_t> trial_id,
              const std::string& detail_json);
  // The participant's answer, at its input's time.
  void mark_response(const data::TrialResult& r);
  // The design's trial `i` ended so (report_trial), and block `b` is over.
  void mark_trial_end(std::size_t i, data::TrialStatus status, const std::string& reason);
  void mark_block_end(std::size_t b);
  template <class T>
  T check(Result<T> r) {
    if (!r) throw Stop{r.error()};
    return std::move(r).value();
  }
  // The adaptive state of the trial's condition (block and cell); null when
  // its judgement type is not adaptive.
  protocol::AdaptiveState* adaptive_for(const protocol::PlannedTrial& t);
  // A trial ended (completed, skipped, aborted): the progress report, the
  // --progress json line.
  void report_trial(std::size_t i, data::TrialStatus status, const std::string& reason);
  void update_progress() { progress_.update(progress_point()); }
  // The trial running, for the events the frame stores and the status.
  void set_current_trial(std::optional<std::size_t> i);
  [[nodiscard]] std::optional<std::int64_t> current_trial_id() const;

  // What the whole loop shares, read and written by the block kinds.
  const protocol::Protocol& protocol;
  const protocol::Design design;
  data::SessionStore& store;
  data::SampleWriter& writer;
  data::WriterLock* const lock;
  const io::Station station;
  const io::Clock& clock;
  const RunOptions& options() const { return options_; }
  const std::int64_t session_id;
  const std::vector<std::int64_t> trial_ids;
  const std::vector<TrialWatcher*> watchers;
  SessionSummary summary;
  OperatorRoom room;
  std::int64_t session_start_ns = 0;
  // The trial a resumed run starts with may have attempts stored already,
  // some of them ended in a logged abort (the observer's streams count
  // those); taken by the first trial the run starts.
  struct {
    std::int64_t attempts = 0;
    std::int64_t aborts = 0;
    bool taken = false;
  } resumed_trial;
  std::vector<std::int64_t> cpu_ns;  // the runner's own time per frame

  // The panels' font: --font, or the built-in DejaVu Sans.
  std::string font() const;

 private:
  struct ProgressPoint progress_point() const;
  Signal poll_devices(std::vector<io::InputEvent>& inputs);
  void store_display_reports();
  void take_stop_signal(Frame& f);
  data::TrackingSample sample(const Frame& f, std::int64_t trial_id, int d) const;
  // The session, trial, frame index and display time of this frame's sample.
  void stamp(data::TrackingSample& s, const Frame& f, std::int64_t trial_id) const;
  void log_frame(const Frame& f, const renderer::FrameStats& stats, std::optional<std::int64_t> trial_id,
                 const renderer::StereoRig& rig);
  template <class Push>
  void push(Push&& try_push);
  void restore_adaptive(const std::vector<std::pair<std::int64_t, bool>>& history);
  void mark_event(const data::EventRecord& record, const data::Event& e, std::optional<std::int64_t> moment_ns);
  Outcome page(const std::string& text, std::size_t k, Phase phase, std::int64_t min_ns,
               std::optional<std::int64_t> trial_id);
  Error head_never_came(AbortReason reason) const;

  RunOptions options_;
  std::int64_t frame_index_;
  Progress progress_;
  std::vector<io::Reach> reach_;        // what the station's sources can press
  std::vector<std::string> continues_;  // inputs that turn pages
  std::string continue_line_;           // under every page
  renderer::Eye dominant_ = renderer::Eye::right;
  std::pair<std::uint32_t, std::uint32_t> eye_size_;  // each eye's image as the display draws it
  // Adaptive types' state per (block position, cell); null for the others.
  std::map<std::pair<std::size_t, std::size_t>, std::unique_ptr<protocol::AdaptiveState>> adaptive_;
  std::optional<World> world_;
  protocol::Settings settings_;
  std::unique_ptr<geometry::Tracker> tracker_;
  std::optional<TrialScene> scene_;
  std::optional<std::size_t> current_trial_;
  std::vector<io::DisplayReport> reports_;  // this frame's, reused
  geometry::LabFrame lab_;
  std::optional<geometry::LabFrame> last_lab_;
  std::deque<io::Signal> device_signals_;  // raised, not yet handed to the loop
  bool stop_logged_ = false;
  bool output_lost_ = false;  // a --progress json line could not be written
  std::int64_t trials_reported_ = 0;  // ended in this run
 public:
  std::int64_t first_reported = 0;  // ended before it (a resumed run)
};

}  // namespace curvlab::harness::runner
