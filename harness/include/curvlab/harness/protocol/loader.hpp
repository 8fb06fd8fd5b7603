// Reading a protocol file: TOML text → Protocol, or an Error listing every
// problem found. Never throws for bad input, never writes anything.
// Thread-safe (no shared state).
#pragma once

#include "curvlab/harness/protocol/diagnostic.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/result.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::protocol {

// The protocol, its `text` the text given; or an Error (bad_input) whose
// diagnostics hold every problem of the text, each placed in `file`, and
// whose message names the first.
Result<Protocol> load_protocol_text(std::string_view text, const std::string& file);
// As load_protocol_text, for the file at `path`; a file that cannot be read
// fails with one diagnostic and kind not_found (no such file) or io.
Result<Protocol> load_protocol_file(const std::string& path);

// The names the loader accepts in `keys` and `buttons` arrays (the JSON
// Schema lists the same).
const std::vector<std::string>& response_key_names();
const std::vector<std::string>& response_button_names();

}  // namespace curvlab::harness::protocol
