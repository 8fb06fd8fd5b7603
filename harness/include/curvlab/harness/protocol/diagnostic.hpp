// Where a protocol is wrong and what was expected. Loading never throws for
// bad input: every problem becomes one Diagnostic, and the caller decides
// what to print (the CLI prints `file:line:column: error: field: message`).
#pragma once

#include <string>
#include <vector>

namespace curvlab::harness::protocol {

// A 1-based position in the protocol text; line 0 means "no position known"
// (for example a problem with the file as a whole).
struct SourcePos {
  int line = 0;
  int column = 0;
};

struct Diagnostic {
  std::string file;
  SourcePos pos;
  std::string field;    // dotted path, e.g. "blocks[2].timeline.iti_ms"
  std::string message;  // what was found and what was expected
};

// "file:line:column: error: field: message" (the field part is left out
// when the problem is not tied to one field).
std::string format_diagnostic(const Diagnostic& d);

// Levenshtein distance, used for "did you mean" suggestions.
std::size_t edit_distance(const std::string& a, const std::string& b);

// The closest candidate within a distance that still reads as a typo, or "".
std::string closest_match(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace curvlab::harness::protocol
