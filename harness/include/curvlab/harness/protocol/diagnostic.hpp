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

// "; did you mean \"guess\"?" when closest_match finds one, else "".
std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates);

// What follows a name that is not one of `allowed`: `; did you mean
// "native"? Expected one of "tourist", "native", "monocular"`, or without a
// close candidate `: expected one of …`.
std::string expected_one_of(const std::string& word, const std::vector<std::string>& allowed);

// `unknown value "natve"` + expected_one_of: how every value check words a
// name it does not know.
std::string unknown_value(const std::string& word, const std::vector<std::string>& allowed);

}  // namespace curvlab::harness::protocol
