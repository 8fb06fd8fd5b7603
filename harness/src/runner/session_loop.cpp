// The session level of the loop: Session → Block → Trial. It opens with the
// session's pages, enters, runs and leaves each block through its kind
// (block_kind.hpp), closes with the closing pages, and ends the session
// completed, or interrupted and resumable.
#include "session_loop.hpp"

#include "block_kind.hpp"
#include "session_frames.hpp"

#include <algorithm>
#include <chrono>
#include <exception>

namespace curvlab::harness::runner {

namespace {

using SteadyTime = std::chrono::steady_clock;

}  // namespace

ResumePoint resume_point(const protocol::Design& d, std::size_t first_trial) {
  for (std::size_t b = 0; b < d.blocks.size(); ++b) {
    const auto& block = d.blocks[b];
    if (first_trial < block.first_trial + block.trial_count) {
      const BlockKind* kind = find_block_kind(block.kind);
      return {b, kind != nullptr ? kind->resume_position(block, first_trial) : 0};
    }
  }
  return {d.blocks.size(), 0};
}

class SessionLoop::Impl {
 public:
  explicit Impl(SessionSetup s) : frames_(s) {}

  RunResult run(ResumePoint from, bool start_pages) {
    const auto wall0 = SteadyTime::now();
    frames_.session_start_ns = frames_.clock.now_ns();
    try {
      frames_.start_streams(!start_pages);
      const Outcome outcome = run_blocks(from, start_pages);
      end_session(outcome == Outcome::done ? data::SessionStatus::completed : data::SessionStatus::interrupted);
    } catch (const Stop& stop) {
      return interrupted(stop.error);
    } catch (const std::exception& e) {
      // Device failures (DeviceFailure: a Vulkan or OpenXR call, named
      // with its result) and anything else thrown from the frame loop.
      return interrupted(Error{Error::Kind::api, e.what()});
    }
    summarize(wall0);
    return frames_.summary;
  }

 private:
  Outcome run_blocks(ResumePoint from, bool start_pages) {
    const auto& design = frames_.design;
    const std::size_t first = first_trial(from);
    frames_.first_reported = static_cast<std::int64_t>(first);
    // Pages are shown in the scene of the trial that follows them (the
    // first here, the previous one later): each trial prepares its own.
    if (!design.trials.empty())
      frames_.prepare(design.trials[std::min(first, design.trials.size() - 1)].settings, "");
    else
      frames_.prepare(frames_.protocol.session_settings(), "");
    if (start_pages && frames_.pages(frames_.protocol.instructions_start, Phase::instructions, 0, std::nullopt) ==
                           Outcome::quit)
      return Outcome::quit;
    for (std::size_t b = from.block; b < design.blocks.size(); ++b) {
      const auto& block = design.blocks[b];
      const BlockKind* kind = find_block_kind(block.kind);
      if (kind == nullptr)
        throw Stop{{Error::Kind::bad_input, "block '" + block.name + "': no block kind '" + block.kind + "'"}};
      BlockRun run{frames_, b, block, b == from.block ? from.position : 0, b == from.block};
      if (kind->enter(run) == Outcome::quit || kind->run(run) == Outcome::quit || kind->leave(run) == Outcome::quit)
        return Outcome::quit;
      frames_.mark_block_end(b);
    }
    return frames_.pages(frames_.protocol.instructions_end, Phase::done, 0, std::nullopt);
  }

  // The design's index of the first trial the run starts at (its count when
  // the run starts after the last block).
  std::size_t first_trial(ResumePoint from) const {
    const auto& design = frames_.design;
    if (from.block >= design.blocks.size()) return design.trials.size();
    return design.blocks[from.block].first_trial + from.position;
  }

  void end_session(data::SessionStatus status) {
    frames_.event(std::nullopt, data::events::SessionEnd{status});
    frames_.room.show_ended();
    // The writer applies an entry after the samples pushed before it: once
    // the closing status is durable, so is everything the session logged.
    const auto ticket = frames_.writer.journal(data::StatusChange{frames_.session_id, status, true});
    frames_.check(frames_.writer.wait_durable(ticket));
    frames_.summary.status = status;
  }

  // Leaves the session resumable: completed trials are on disk already.
  RunResult interrupted(const Error& error) {
    frames_.room.show_ended();
    // The writer retries what failed; the reserve's space lets it finish.
    if (error.kind == Error::Kind::disk_full && frames_.lock != nullptr) frames_.lock->free_reserve();
    const auto id = frames_.session_id;
    const auto ticket = frames_.writer.journal(data::StatusChange{id, data::SessionStatus::interrupted, false});
    if (!frames_.writer.wait_durable(ticket, std::chrono::seconds(5)))
      (void)frames_.store.set_session_status(id, data::SessionStatus::interrupted);
    const std::string sid = std::to_string(id);
    return Error{error.kind, error.message + " (session " + sid + " stopped before the end; continue it with: " +
                                 "curvlab resume --db " + frames_.store.path() + " --session " + sid + ")"};
  }

  void summarize(SteadyTime::time_point wall0) {
    auto& summary = frames_.summary;
    summary.wall_s = std::chrono::duration<double>(SteadyTime::now() - wall0).count();
    summary.session_s = static_cast<double>(frames_.clock.now_ns() - frames_.session_start_ns) * 1e-9;
    summary.samples_dropped = frames_.writer.stats().dropped_tracking + frames_.writer.stats().dropped_frames;
    auto& cpu = frames_.cpu_ns;
    if (!cpu.empty()) {
      std::sort(cpu.begin(), cpu.end());
      summary.frame_cpu_median_ms = static_cast<double>(cpu[cpu.size() / 2]) * 1e-6;
      summary.frame_cpu_p95_ms = static_cast<double>(cpu[cpu.size() * 95 / 100]) * 1e-6;
    }
    if (auto completed = frames_.store.count_trials(frames_.session_id, data::TrialStatus::completed))
      summary.trials_completed = completed.value();
  }

  SessionFrames frames_;
};

SessionLoop::SessionLoop(SessionSetup setup) : impl_(std::make_unique<Impl>(std::move(setup))) {}
SessionLoop::~SessionLoop() = default;
RunResult SessionLoop::run(ResumePoint from, bool start_pages) { return impl_->run(from, start_pages); }

}  // namespace curvlab::harness::runner
