// What two stations must share before they play one game
// (docs/shared_play.md, "Same protocol"): the same curvlab version, the same
// protocol file (its SHA-256), the same parameters that decide the game (the
// space, the table, the balls' physics, the rack) and opposite roles. Each
// station sends its Hello and compares the partner's with its own; a
// difference ends the link, with a message naming it, before either station
// writes a session.
//
// Pure; safe from any thread.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <curvlab/harness/net/messages.hpp>

namespace curvlab::harness::net {

using Parameters = std::vector<std::pair<std::string, std::string>>;

// "name=value\n" per parameter, sorted by name: the text parameters_sha256 is of.
std::string canonical_parameters(Parameters params);

// A Hello with the parameters sorted and their digest filled in.
Hello make_hello(Role role, std::string software_version, std::string protocol_sha256, Parameters params,
                 std::string initials);

// Empty when `theirs` may play with `mine`; otherwise one sentence per
// difference, naming it and both sides' values ("this station" first).
std::optional<std::string> incompatibility(const Hello& mine, const Hello& theirs);

}  // namespace curvlab::harness::net
