// Numbered output files that never replace older ones: stimulus images of a
// resumed session, screenshots of a second pilot run into the same folder.
#pragma once

#include <filesystem>
#include <string>

namespace curvlab::harness {

// The first of `stem`, `stem_2`, `stem_3`, … that no entry of `dir` uses
// (an entry named the stem itself, or starting with it and '_' or '.').
std::string unused_stem(const std::filesystem::path& dir, const std::string& stem);

// The largest N among entries of `dir` named `prefix` + N + anything, where
// N is a run of digits (0 when there is none, or no such folder).
int highest_number(const std::filesystem::path& dir, const std::string& prefix);

}  // namespace curvlab::harness
