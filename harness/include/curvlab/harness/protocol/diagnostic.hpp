// Where a protocol is wrong and what was expected. Loading never throws for
// bad input: every problem becomes one Diagnostic (harness/result.hpp), all
// of a file's in one Error, and the caller decides what to print (the CLI
// prints `file:line:column: error: field: message`).
#pragma once

#include "curvlab/harness/result.hpp"

#include <string>
#include <vector>

namespace curvlab::harness::protocol {

using harness::Diagnostic;
using harness::format_diagnostic;
using harness::SourcePos;

// Levenshtein distance, used for "did you mean" suggestions.
std::size_t edit_distance(const std::string& a, const std::string& b);

// The closest candidate within a distance that still reads as a typo, or "".
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace curvlab::harness::protocol
