// Pooling the files of a study (DESIGN.md §7, "A study spans machines"):
// sessions from several curvlab files are copied into one study database,
// with every id remapped and every provenance row kept. docs/data.md,
// "Pooling a study", gives the rules a user sees.
#pragma once

#include "curvlab/harness/data/error.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace curvlab::harness::data {

struct MergeOptions {
  std::string out_path;              // the study database; created when missing
  std::vector<std::string> inputs;   // files, in the order they are merged
  bool allow_protocol_versions = false;  // pool different texts under one protocol name
};

// What one input contributed. Row counts are those of the added sessions.
struct MergeInputReport {
  std::string path;
  std::int64_t sessions_added = 0;
  std::int64_t sessions_skipped = 0;      // already in the study with identical content
  std::int64_t sessions_conflicting = 0;  // same UUID, different content
  std::int64_t sessions_renumbered = 0;   // session_number taken by another session
  std::int64_t trials = 0;
  std::int64_t samples = 0;
  std::int64_t frames = 0;
};

// A session found twice with different content: the merge is refused.
struct MergeConflict {
  std::string session_uuid;
  std::string first;   // where the study's copy came from
  std::string second;  // the input that disagrees
  std::string detail;  // how the two copies differ, and what to do
};

struct MergeReport {
  std::vector<MergeInputReport> inputs;
  std::vector<MergeConflict> conflicts;  // non-empty: the output was left unchanged
  bool output_changed = false;
};

// Merges opts.inputs into opts.out_path. Inputs are opened read-only and
// never modified; they must have the current schema version (an older file
// is refused, naming the command that upgrades it). The work happens in a
// temporary file beside the output that replaces it only when every input
// merged cleanly: on any error, and when conflicts are reported, the output
// is left as it was. An error is returned for unreadable or foreign inputs
// and for protocol versions refused without allow_protocol_versions.
Expected<MergeReport> merge_databases(const MergeOptions& opts);

// The .sqlite files directly inside `dir`, sorted by name.
Expected<std::vector<std::string>> database_files_in(const std::string& dir);

// SHA-256 over the rows of one session that a merge compares: the session's
// provenance, blocks, trials, staircase steps, tracking samples, frames and
// events (without the events merge itself adds), with ids replaced by the
// indices they stand for. Equal for a file and its merged copy.
Expected<std::string> session_content_digest(const std::string& db_path, const std::string& session_uuid);

}  // namespace curvlab::harness::data
