// Design expansion: protocol + participant number → the exact list of trials
// the runner stores at session start. Pure and deterministic: the only input
// besides the protocol is the participant number, which selects the
// counterbalancing row and (by default) the seed.
#pragma once

#include "curvlab/harness/protocol/protocol.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace curvlab::harness::protocol {

// A slot of a staircase block: which staircase of its cell's interleaved set
// it belongs to (the runner skips a slot whose staircase has stopped).
struct StaircaseSlot {
  std::size_t index = 0;  // into the judgement's staircases
};

// One slot of a block before its trials are numbered: the judgement type
// lays them out (judgement.hpp, JudgementType::slots).
struct DesignSlot {
  std::size_t cell = 0;
  int repetition = 0;
  std::optional<StaircaseSlot> staircase;
};

struct PlannedTrial {
  std::size_t index = 0;           // 0-based in the session
  std::size_t block_position = 0;  // 0-based position of the block in the run order
  std::size_t protocol_block = 0;  // its block's index in Protocol::blocks (the file's order)
  std::string block;               // its block's name, for people and exports; never looked up
  bool practice = false;
  std::size_t trial_in_block = 0;
  int repetition = 0;  // 0-based
  std::vector<std::pair<std::string, std::string>> levels;  // factor → level label
  std::size_t cell = 0;  // index of the factor-level combination within the block
  Settings settings;     // resolved: session → block → levels
  Derived derived;
  const JudgementType* judgement = nullptr;  // the block's judgement type
  std::optional<StaircaseSlot> staircase;    // staircase blocks
  std::optional<double> adjustment_start;    // adjustment blocks: the drawn start value
  bool break_before = false;
};

struct PlannedBlock {
  std::string name;
  std::string kind = "trials";     // Block::kind
  std::size_t protocol_block = 0;  // index in Protocol::blocks
  bool practice = false;
  std::size_t first_trial = 0;
  std::size_t trial_count = 0;  // the maximum where the judgement stops early
  std::vector<std::string> instructions;
  std::int64_t break_min_ms = 0;
};

struct Design {
  std::uint64_t protocol_seed = 0;
  std::uint64_t seed = 0;  // the seed actually used (logged with the session)
  std::uint64_t participant = 0;
  std::optional<std::size_t> counterbalance_row;
  std::vector<PlannedBlock> blocks;  // in run order
  std::vector<PlannedTrial> trials;
  // Upper bound from the timelines and minimum break lengths (reading time of
  // instruction pages excluded).
  [[nodiscard]] std::int64_t estimated_duration_ms() const;
};

// participant ≥ 1. The protocol must have passed the loader.
Design expand_design(const Protocol& p, std::uint64_t participant);

// Combinations of the block's factor levels, in factorial order (last factor
// fastest): each entry is one level index per factor of p.factors.
std::vector<std::vector<std::size_t>> block_cells(const Protocol& p, const Block& b);

}  // namespace curvlab::harness::protocol
