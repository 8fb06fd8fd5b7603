// What a session stores about its plan and its frames, as JSON and records
// (data_schema/codebook.md): shared by the session loop, run and resume.
#pragma once

#include "curvlab/geometry/isometry.hpp"
#include "curvlab/harness/data/events.hpp"
#include "curvlab/harness/data/records.hpp"
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/protocol.hpp"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::runner {

using Json = nlohmann::ordered_json;

// The block a planned trial belongs to, by its stored index. The index comes from the design of
// the same protocol, so a miss is a broken contract: it aborts.
const protocol::Block& block_of(const protocol::Protocol& p, const protocol::PlannedTrial& t);
// Adaptive tracks (staircases) are named uniquely within a session: the
// block, the cell when the block has several, and the track's own name.
std::string staircase_key(const protocol::Protocol& p, const protocol::PlannedTrial& t, const std::string& track);
// A Bayesian adaptive method's posterior as the store keeps it.
std::optional<data::StepPosterior> step_posterior(const std::optional<protocol::PosteriorSummary>& p);
// A 4×4 isometry as 16 numbers, column-major.
data::Pose16 pose16(const geometry::Isometry& iso);
// Every block and trial of a design, as the store keeps them.
std::vector<data::BlockPlan> block_plans(const protocol::Protocol& p, const protocol::Design& d);

}  // namespace curvlab::harness::runner
