// `curvlab preview`: a self-contained HTML sheet of a protocol for one
// participant — every distinct condition's onset stereo pair rendered with the
// runner's own pieces (make_world, place_stimulus, TrialScene, view_settings,
// the offscreen renderer), a red/cyan anaglyph of it, the settings it was
// rendered with, the simulated observer's predicted response proportions
// (predict.hpp) and its trial count per block; the block order, timelines,
// each judgement's answers with their keys and buttons and its own settings
// (staircases, adjustment), instruction and break texts, the estimated
// duration, the protocol's SHA-256 and the software version.
// Something to look at before spending participant hours, and to attach to a
// preregistration. Writes only under the output folder.
#pragma once

#include "curvlab/harness/result.hpp"

#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/protocol.hpp"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace curvlab::harness::runner {

// One distinct condition of a design: the trials that share their factor
// levels, every resolved setting, what the judgement's type tells apart (a
// staircase) and whether they are practice (the judgement and the block may
// differ; practice trials are never merged with the others).
struct PreviewCondition {
  std::vector<std::pair<std::string, std::string>> levels;  // factor → level
  // What the judgement's type adds to the trial's conditions (a staircase's
  // name; JudgementType::conditions).
  std::vector<std::pair<std::string, std::string>> tracks;
  bool practice = false;
  // name → value, as shown: the settings the first trial's onset is rendered
  // with, including the value the judgement sets then (a staircase's start,
  // an adjustment trial's drawn start).
  std::vector<std::pair<std::string, std::string>> settings;
  std::string onset_note;  // how the judgement chose that value; "" when it sets none
  std::size_t first_trial = 0;  // index in the design of its first trial
  std::vector<std::pair<std::string, std::size_t>> trials_per_block;  // run order
};

// The distinct conditions of a design, block by block in run order (the
// block where each first appears) and in factorial order within it, a
// staircase block's staircases in the order the protocol lists them. Pure.
std::vector<PreviewCondition> preview_conditions(const protocol::Protocol& p, const protocol::Design& design);

struct PreviewRequest {
  std::string protocol_path;  // its file name is shown on the sheet (never a folder: one can name a person)
  std::string protocol_text;  // fingerprinted (SHA-256)
  std::uint64_t participant = 1;
  std::string out_dir;
  // Per-eye image size; default: the protocol's resolution scaled to at most
  // 480 px wide (the aspect ratio, and so the field of view, is kept).
  std::optional<std::pair<std::uint32_t, std::uint32_t>> size;
  bool software = false;  // lavapipe even with a GPU
  // Called before the first and after every rendered condition.
  std::function<void(std::size_t done, std::size_t total, const std::string& what)> progress;
};

struct PreviewResult {
  std::string index_html;
  std::size_t conditions = 0;
  std::size_t images = 0;
  std::string device;
};

// The protocol must have passed the loader.
Result<PreviewResult> write_preview(const protocol::Protocol& p, const PreviewRequest& request);

}  // namespace curvlab::harness::runner
