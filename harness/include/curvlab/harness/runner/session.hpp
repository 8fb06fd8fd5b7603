// The session runner (DESIGN.md §6): Session → Block → Trial, driven frame by
// frame by its devices (io/station.hpp): a display, a pose source and
// response sources. At start the whole expanded design is stored, so a
// crash resumes exactly: every trial runs to completion exactly once, in the
// stored order (a trial interrupted mid-way is run again as a new attempt).
// Each completed trial commits in its own transaction before the next one
// starts; tracking samples and frame records go through the SampleWriter.
//
// Per frame: poses → tracking → input → trial state → scene → submit → log.
// Phases of a trial (trial_state.hpp): fixation → stimulus → response window
// → inter-trial interval; responses count from stimulus onset to the
// window's end. A lost head (or a recenter) during a trial aborts the
// attempt and repeats the trial once tracking is back; a pause does the same
// after resuming. The protocol's [tracking] section may flag losses instead,
// give such trials up, or cap the attempts (protocol::TrackingLoss).
//
// The frame loop never waits on the disk: events and trial state go through
// the SampleWriter's journal like samples, and a completed trial is on disk
// before the next one starts. Random streams derive from (session seed,
// trial index, attempt), so a resumed simulated session answers as the
// uninterrupted one would. A backend failure (a Vulkan or OpenXR error) ends
// the run `interrupted`, resumable, with every completed trial kept.
#pragma once

#include "curvlab/geometry/calibration.hpp"
#include "curvlab/harness/data/events.hpp"
#include "curvlab/harness/data/records.hpp"
#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/harness/io/station.hpp"
#include "curvlab/harness/io/streams.hpp"
#include "curvlab/harness/runner/observer.hpp"
#include "curvlab/harness/runner/operator.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::runner {
struct SharedPlay;
}

namespace curvlab::harness::runner {

// Which frames the backend must draw. Fast headless runs need pixels only
// for the stimulus images; every other frame is planned (counts logged) but
// not drawn.
enum class FrameDrawing { all, onset, none };
std::optional<FrameDrawing> parse_frame_drawing(std::string_view text);

struct RunOptions {
  std::string participant;  // pseudonym, [A-Za-z0-9_-]{1,32}
  std::uint64_t participant_number = 1;  // counterbalancing row and seed (≥ 1)
  data::DominantEye dominant_eye = data::DominantEye::unknown;
  std::optional<double> ipd_m;  // overrides the protocol's viewing.ipd_m
  std::optional<ObserverParams> observer;  // answers for the participant
  FrameDrawing drawing = FrameDrawing::all;
  std::string images_dir;  // stimulus images of every onset ("" none)
  bool progress = false;   // progress on stderr: a bar on a terminal, else a line every progress_every
  std::chrono::milliseconds progress_every{10'000};
  bool progress_json = false;  // one JSON object per trial on stdout (docs/xr.md, "The operator window")
  // The experimenter's console (operator.hpp): status shown, actions taken.
  // Not owned; outlives the run. nullptr: none.
  OperatorConsole* console = nullptr;
  std::optional<geometry::PhysicalTableFit> calibration;
  std::string font_path;   // text panels; empty: the renderer's default
  // Fast runs may wait for the logger instead of dropping samples.
  bool lossless_logging = true;
  // Set (to the signal's number) by the caller's signal handler: the session
  // ends interrupted at the next frame. nullptr: not watched.
  const std::atomic<int>* stop_signal = nullptr;
  // What the lab's other instruments are told (io/streams.hpp: the Lab
  // Streaming Layer's outlets). Not owned; outlives the run. nullptr: none.
  io::SessionStreams* streams = nullptr;
  // The command line's run options as a JSON object (render, pace, images,
  // export, observer), stored with the session_start or resume event: they
  // are what `resume` continues with by default. Empty: not stored.
  std::string run_options_json;
  // Warnings about the protocol stored with the session's start (the human
  // model's range of validity), which the report repeats.
  std::vector<std::string> warnings;
  // The experimenter's note at the start (run --note, the start form),
  // stored as an operator_note event with the session's start; "" none.
  std::string note;
  // Shared play's partner (shared_play.hpp): connected and compared before
  // the session was written. Not owned; outlives the run. nullptr: play
  // blocks are played alone.
  SharedPlay* shared = nullptr;
};

struct SessionSummary {
  std::string db_path;
  std::int64_t session_id = 0;
  data::SessionStatus status = data::SessionStatus::running;  // completed, interrupted or aborted at the end
  std::int64_t trials_planned = 0;
  std::int64_t trials_completed = 0;
  std::int64_t trials_skipped = 0;   // stopped staircases' slots
  std::int64_t trials_aborted = 0;   // given up after tracking loss (tracking.on_loss, max_attempts)
  std::int64_t trials_flagged = 0;   // completed with tracking lost (tracking.on_loss = "flag")
  std::int64_t attempts_repeated = 0;
  std::int64_t shots = 0;           // play blocks' shots in this run
  std::int64_t balls_pocketed = 0;  // by those shots
  std::int64_t items_answered = 0;  // questionnaire blocks' items answered in this run
  std::vector<data::events::PlaySummary> play;  // each play block ended in this run
  std::int64_t frames = 0;
  std::uint64_t samples_dropped = 0;
  double session_s = 0.0;  // on the session clock
  double wall_s = 0.0;
  double frame_cpu_median_ms = 0.0;  // runner work per frame, GPU excluded
  double frame_cpu_p95_ms = 0.0;
  std::vector<std::string> images;
  // Ended because a --progress json line could not be written to stdout (its
  // reader gone): interrupted, resumable, like a stop signal.
  bool output_lost = false;
};

// Where a run starts: a block (its place in the design's run order) and a
// position within it, as its kind counts (a trial, for trials blocks).
// {design.blocks.size(), 0}: after the last block (the closing pages).
struct ResumePoint {
  std::size_t block = 0;
  std::size_t position = 0;
};
// The point of the design's trial `first_trial` (the first not yet ended).
ResumePoint resume_point(const protocol::Design& d, std::size_t first_trial);

// A failure's kind decides the exit code (result.hpp: bad input 2, run-time 1).
using RunResult = Result<SessionSummary>;

// Starts a new session of `protocol` (loaded from `protocol_text`).
RunResult run_session(const protocol::Protocol& protocol, const std::string& protocol_text,
                      const std::string& db_path, const RunOptions& options, const io::Station& station,
                      const io::Clock& clock);

// What a session needs from the database before a backend is opened: its
// protocol (text and parsed), participant number and state.
struct StoredSession {
  std::string protocol_text;
  std::string protocol_source;
  std::string participant;
  std::uint64_t participant_number = 1;
  std::int64_t seed = 0;
  data::SessionStatus status = data::SessionStatus::running;
  std::string backend;
  std::optional<geometry::PhysicalTableFit> calibration;
  std::optional<ObserverParams> observer;
  std::int64_t last_t_ns = 0;  // latest time stamp logged (a resumed clock starts after it)
  std::optional<std::string> run_options_json;  // the run options it last ran with (RunOptions)
};
Result<StoredSession> read_stored_session(const std::string& db_path, std::int64_t session_id);

// Continues a session from its first incomplete trial. `stored` is what
// read_stored_session returned and `protocol` its protocol text, loaded; the
// participant, seed, calibration and (unless options give one) observer come
// from it; options supply the drawing and progress settings.
RunResult resume_session(const std::string& db_path, std::int64_t session_id,
                         const StoredSession& stored, const protocol::Protocol& protocol,
                         const RunOptions& options, const io::Station& station,
                         const io::Clock& clock);

// The stored conditions and stimulus of a planned trial (trials.conditions
// and trials.stimulus; data_schema/codebook.md). The parameter of a
// judgement that sets it on each trial (staircase, adjustment) is null in
// the plan and filled in when the trial ends with its answer or a timeout:
// shown_stimulus_json, with `shown` the trial's settings then (a
// staircase's value as shown from its onset, an adjustment's as confirmed
// or, on a timeout, as last shown).
std::string conditions_json(const protocol::Protocol& p, const protocol::PlannedTrial& t);
std::string stimulus_json(const protocol::Protocol& p, const protocol::PlannedTrial& t);
std::string shown_stimulus_json(const protocol::Protocol& p, const protocol::PlannedTrial& t,
                                const protocol::Settings& shown);

}  // namespace curvlab::harness::runner
