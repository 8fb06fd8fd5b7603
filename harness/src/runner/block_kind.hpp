// Block kinds (DESIGN.md §1, "block kind"): a session is a run of blocks, and
// what a block's frames show is its kind's — a list of judged trials today.
// Each kind is one file in blocks/ and one line of blocks/registry.cpp, as
// judgement types are; the session level (session_loop.cpp) enters each
// block, runs it and leaves it, and knows no kind.
#pragma once

#include "session_frames.hpp"

#include <cstddef>
#include <string_view>

namespace curvlab::harness::runner {

// One block as this run meets it.
struct BlockRun {
  SessionFrames& frames;
  std::size_t position = 0;  // the block's place in the design's run order
  const protocol::PlannedBlock& block;
  std::size_t from = 0;       // where this run enters it (ResumePoint::position)
  bool first_of_run = false;  // the block this run starts in
};

class BlockKind {
 public:
  virtual ~BlockKind() = default;
  BlockKind() = default;
  BlockKind(const BlockKind&) = delete;
  BlockKind& operator=(const BlockKind&) = delete;

  [[nodiscard]] virtual std::string_view name() const = 0;
  // Where a stored session continues in the block, from the design's first
  // trial not yet ended (a trial within it for trials blocks).
  [[nodiscard]] virtual std::size_t resume_position(const protocol::PlannedBlock& block,
                                                    std::size_t first_trial) const = 0;
  // The block's start: its BlockStart event and instruction pages (shown
  // again when a resumed run starts inside the block).
  virtual Outcome enter(BlockRun& run) const;
  // Its frames, from run.from to its end.
  virtual Outcome run(BlockRun& run) const = 0;
  // What it leaves behind when done; nothing by default.
  virtual Outcome leave(BlockRun& run) const {
    (void)run;
    return Outcome::done;
  }
};

// The kind named `name` (a protocol's [[blocks]] kind); null when unknown.
const BlockKind* find_block_kind(std::string_view name);

}  // namespace curvlab::harness::runner
